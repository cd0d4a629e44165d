"""The datasets keep their CF-1.8 promise: the community's reference checker (cfchecker 4.1 with UDUNITS-2)
finds no error, no warning and no traceback in a dataset of every kind the package writes, nor in the stored
files of data/. `bash run.sh test-all` installs the checker (its own venv in .venv/cfchecker) and Debian's
libudunits2-0.

The standard-name, area-type and region tables cannot be downloaded here; the package uses no standard names,
area types or regions, so minimal local tables (a version and a date) stand in for them. INFO messages ("No
units attribute set") are allowed: they concern the variables whose values along a label dimension mix units
(the orbit's states, a representative state), which carry a ``comment`` and a ``<dim>_units`` coordinate
instead, CF having no units per element.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import tippedisk_analysis as td
from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.cli import main

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
CHECKER = Path(sys.prefix) / "cfchecker" / "bin" / "cfchecks"
STORED = sorted((ROOT / "data").rglob("*.nc"))
TABLES = {"s": ("cf-standard-name-table.xml", "standard_name_table", "last_modified"),
          "a": ("area-type-table.xml", "area_type_table", "date"),
          "r": ("standardized-region-list.xml", "standardized_region_list", "date")}

COMMANDS = {  # one run of every command that writes a dataset, small enough for seconds
    "simulate_euler": ["simulate", "--model", "ode-euler", "--t-end", "0.2"],
    "simulate_quaternion": ["simulate", "--model", "ode-quaternion", "--t-end", "0.2"],
    "simulate_moreau": ["simulate", "--model", "m1", "--t-end", "0.02"],
    "simulate_hybrid": ["simulate", "--model", "h1", "--t-end", "0.6"],
    "stability_map": ["stability-map", "--omega", "30:60:4", "--eps", "0.1:0.4:4"],
    "outcome_map_rules": ["outcome-map", "--omega", "30:40:2", "--eps", "0.1:0.2:2", "--t-end", "1",
                          "--classify", "rules"],
    "outcome_map_attractors": ["outcome-map", "--omega", "30:40:2", "--eps", "0.1:0.2:2", "--t-end", "60"],
    "poincare": ["poincare", "--t-end", "2"],
    "poincare_hybrid": ["poincare", "--model", "h1", "--section", "gamma mod 2pi=pi/2", "--t-end", "2"],
    "bifurcation": ["bifurcation", "--omega", "30:40:2", "--t-end", "2", "--t-transient", "1"],
    "continue": ["continue", "--from", "20", "--to", "120"],
    "periodic_orbits": ["periodic-orbits", "--system", "bautin", "--to", "-0.3"],
    "periodic_orbits_frictionless": ["periodic-orbits", "--frictionless", "inverted:40", "--max-points", "5"],
    "lyapunov_run": ["lyapunov", "--t-end", "1"],
    "lyapunov_lorenz": ["lyapunov", "--system", "lorenz", "--t-end", "50"],
    "lyapunov_map": ["lyapunov", "--omega", "30:40:2", "--eps", "0.1:0.2:2", "--t-end", "1"],
    "basins": ["basins", "--omega", "30:40:2", "--dgamma0", "0.05:0.1:2", "--t-end", "60"],
    "basin_fractions": ["basin-fractions", "--over", "omega=30:40:2", "--samples", "4", "--dgamma0", "0.05:0.15",
                        "--t-end", "60"],
}


@pytest.fixture(scope="module")
def tables(tmp_path_factory):
    if not CHECKER.exists():
        pytest.fail(f"the CF checker is not installed at {CHECKER}; run `bash run.sh test-all` (it installs it)")
    d = tmp_path_factory.mktemp("cf_tables")
    args = []
    for flag, (name, root, date) in TABLES.items():
        (d / name).write_text(f'<?xml version="1.0"?><{root}><version_number>0</version_number>'
                              f'<{date}>local</{date}></{root}>')
        args += [f"-{flag}", str(d / name)]
    return args


def cf_check(path: Path, tables: list[str]) -> tuple[int, int, str]:
    """(errors, warnings, report) of cfchecks -v 1.8 on ``path``; a traceback fails the test."""
    proc = subprocess.run([str(CHECKER), "-v", "1.8", *tables, str(path)], capture_output=True, text=True,
                          timeout=600)
    report = proc.stdout + proc.stderr
    assert "Traceback" not in report, report
    errors = re.search(r"ERRORS detected: (\d+)", report)
    warnings = re.search(r"WARNINGS given: (\d+)", report)
    assert errors and warnings, report
    return int(errors.group(1)), int(warnings.group(1)), _findings(report)


def _findings(report: str) -> str:
    """The ERROR and WARN lines with the variable each concerns."""
    out, variable = [], "(global)"
    for line in report.splitlines():
        if line.startswith("Checking variable:"):
            variable = line.split(":", 1)[1].strip()
        elif line.startswith(("ERROR", "WARN")):
            out.append(f"{variable}: {line}")
    return "\n".join(out)


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """A dataset of every kind, written by the package: every command, and the generic layer on 'ab'."""
    d = tmp_path_factory.mktemp("cf_written")
    for name, args in COMMANDS.items():
        assert main([*args, "-o", str(d / f"{name}.nc")]) in (0, 1), name
    assert main(["periodic-orbits", "--from-run", str(d / "simulate_hybrid.nc"), "--returns-time", "200", "-o",
                 str(d / "periodic_orbits_rolling.nc")]) == 0
    ab = dy.textbook_system("ab")
    eq = dy.equilibrium_branch(ab, [0.0, 0.0], "D", bounds=(0.0, 0.2))
    generic = {
        "generic_continuation": eq,
        "generic_curve": dy.special_point_curve(ab, eq, "HOPF1", ("D", "beta"), bounds={"beta": (1.5, 2.5)}),
        "generic_periodic_orbits": dy.orbit_branch(ab, eq, "HOPF1", bounds=(0.12, 0.2)),
        "generic_lyapunov": dy.lyapunov_spectrum(ab, [0.7, 2.7], ab.with_pars(D=0.12), t_end=50.0),
        "generic_basins": dy.basins(ab, dy.Grid(("u1", "u2"), (-0.2, -1.0), (1.2, 10.0), (70, 110)),
                                    {"u1": (0.0, 1.0, 3), "u2": (0.0, 8.0, 3)}, pars=ab.with_pars(D=0.12),
                                    horizon=400.0, progress=False),
        "generic_poincare": dy.poincare_section(ab, [0.7, 2.7], "u1", 0.8, pars=ab.with_pars(D=0.12), t_end=20.0),
    }
    generic["generic_fit"], generic["generic_fit_comparison"], generic["fit_moreau"] = _fits()
    for name, ds in generic.items():
        td.save(ds, d / f"{name}.nc")
    return d


def _fits():
    """A fit dataset (with a missing sample) of dy.fit, the table of dy.compare_fits, and td.fit of Model 1 (by
    finite differences on its simulation) to 0.2 s of its own beta."""
    import heyoka as hy

    x = hy.make_vars("x")
    decay = dy.System("decay", (x,), (-hy.par[0] * x,), {"k": 0.8}, units={"k": "s-1"})
    t = np.linspace(0.0, 2.0, 21)
    data = np.exp(-t) + 0.01 * np.random.default_rng(0).normal(size=t.size)
    data[5] = np.nan
    one = dy.fit(decay, t, {"x": data}, ["k"], state=[1.0])
    two = dy.fit(decay, t, {"x": data}, ["k", "x"], state=[1.0])
    t = np.arange(21) * 0.01
    run = td.simulate("m1", 0.2)
    moreau = td.fit(t, {"beta": np.interp(t, run.time.values, run.beta.values)}, ["mu"], model="m1",
                    setup=td.Setup(friction=td.Friction(mu=0.25)))
    return two, dy.compare_fits([one, two], names=["k", "k and x0"]), moreau


@pytest.mark.parametrize("name", [*COMMANDS, "periodic_orbits_rolling", "generic_continuation", "generic_curve",
                                  "generic_periodic_orbits", "generic_lyapunov", "generic_basins", "generic_poincare",
                                  "generic_fit", "generic_fit_comparison", "fit_moreau"])
def test_every_kind_the_package_writes_passes_the_cf_checker(written, tables, name):
    errors, warnings, findings = cf_check(written / f"{name}.nc", tables)
    assert (errors, warnings) == (0, 0), findings


@pytest.mark.parametrize("path", STORED, ids=lambda p: str(p.relative_to(ROOT / "data")))
def test_every_stored_dataset_passes_the_cf_checker(tables, path):
    errors, warnings, findings = cf_check(path, tables)
    assert (errors, warnings) == (0, 0), findings


def test_a_file_written_before_the_cf_encoding_loads_as_it_did(tmp_path):
    """An old-style file (text coordinates, variable-length strings, a 2-D ``history``) loads into the same
    objects as the new encoding gives back: labels as the index (``.sel(branch=...)``), text as str."""
    ds = xr.Dataset({"x": (("branch", "point"), np.arange(6.0).reshape(2, 3), {"units": "m", "long_name": "x"}),
                     "special_label": ("special_point", np.array(["HOPF1", "BP1"]), {"long_name": "label"})},
                    coords={"branch": ("branch", np.array(["noninverted", "inverted"]), {"long_name": "branch"}),
                            "point": td.results.index_coordinate("point", 3, "point")},
                    attrs=td.results.make_attrs("stability_map", {}, "completed", "test"))
    old = tmp_path / "old.nc"
    ds.to_netcdf(old, engine="netcdf4")  # as save() wrote it before
    new = td.save(ds, tmp_path / "new.nc")
    for path in (old, new):
        back = td.load(path)
        xr.testing.assert_identical(back, ds)
        assert float(back.x.sel(branch="inverted", point=2)) == 5.0 and back.special_label.dtype.kind == "U"
    ncdump = xr.open_dataset(new, decode_cf=False)  # on disk: no text coordinate variable, char arrays
    assert "branch" not in ncdump.variables and ncdump["branch_label"].dtype.kind == "S"
    assert ncdump.attrs["label_dimensions"] == "branch"
