"""The notebook runs top to bottom on the stored datasets and reports what the datasets hold.

Every number the notebook prints is recomputed here from the netCDF files with plain xarray
(not through the notebook's code path), and checked against the paper where the paper gives
a value. A notebook that runs but prints wrong, stale or mislabelled numbers fails.
"""

import math
import re
from pathlib import Path

import nbformat
import numpy as np
import pytest
from nbclient import NotebookClient

import tippedisk_analysis as td

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "data"
NOTEBOOK = ROOT / "notebooks" / "explore_datasets.ipynb"
NUMBER = r"([-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?)"


@pytest.fixture(scope="module")
def executed():
    nb = nbformat.read(NOTEBOOK, as_version=4)
    NotebookClient(nb, timeout=300, kernel_name="python3",
                   resources={"metadata": {"path": str(NOTEBOOK.parent)}}).execute()
    return nb


@pytest.fixture(scope="module")
def printed(executed):
    """Everything the notebook printed to stdout, in cell order."""
    return "".join(o.get("text", "") for cell in executed.cells if cell.cell_type == "code"
                   for o in cell.get("outputs", []) if o.get("output_type") == "stream" and o.get("name") == "stdout")


def _grab(pattern, text, n=1):
    match = re.search(pattern, text)
    assert match, f"the notebook no longer prints {pattern!r}; output was:\n{text}"
    values = [float(v) for v in match.groups()]
    return values[0] if n == 1 else values


def _open(name):
    return td.load(DATA / name)  # as the notebook reads them (text labels back as the index)


def test_every_notebook_is_covered():
    assert sorted(p.name for p in (ROOT / "notebooks").glob("*.ipynb")) == [NOTEBOOK.name]


def test_notebook_runs_without_errors_and_draws_every_figure(executed):
    code = [cell for cell in executed.cells if cell.cell_type == "code"]
    errors = [o for cell in code for o in cell.get("outputs", []) if o.get("output_type") == "error"]
    assert not errors, errors
    plotting = [cell for cell in code if re.search(r"\.plot\(|\.scatter\(|plt\.subplots\(", cell.source)]
    for cell in plotting:  # one rendered image per figure cell, not just a Figure repr
        images = [o for o in cell.outputs if "image/png" in o.get("data", {})]
        assert len(images) == 1, cell.source
    assert len(plotting) == 5
    listing = code[0].outputs[-1]["data"]["text/plain"]
    assert sorted(re.findall(r"'([^']+\.nc)'", listing)) == sorted(p.name for p in DATA.glob("*.nc"))


def test_fig13_numbers(printed):
    run = _open("fig13_ode_inversion.nc")
    assert re.search(r"status: completed;", printed) and run.attrs["status"] == "completed"
    t_inv = _grab(rf"gamma crosses 0 at t = {NUMBER} s", printed)
    first = int(np.argmax(run.gamma.values > 0))
    assert t_inv == pytest.approx(float(run.time[first]), abs=5e-4)
    assert 0.2 < t_inv < 0.5  # Fig. 13: the inversion takes a few tenths of a second
    balance = _grab(rf"W_friction\| = {NUMBER} J", printed)
    recomputed = float(np.abs(run.E_tot - run.E_tot[0] - run.W_friction).max())
    assert balance == pytest.approx(recomputed, rel=6e-3) and recomputed < 1e-9
    z0, z1, r_minus_e, r_plus_e = _grab(rf"z_S: {NUMBER} mm -> {NUMBER} mm \(r - e = {NUMBER}, r \+ e = {NUMBER}\)",
                                        printed, n=4)
    assert z0 == pytest.approx(1e3 * float(run.z_S[0]), abs=0.006)
    assert z1 == pytest.approx(1e3 * float(run.z_S[-1]), abs=0.006)
    r, e = 0.045, 2.5e-3  # Table 1/2
    assert (r_minus_e, r_plus_e) == (pytest.approx(1e3 * (r - e)), pytest.approx(1e3 * (r + e)))
    assert z0 == pytest.approx(1e3 * (r - e * math.cos(0.1)), abs=0.01)  # Table 3 start, gamma = -pi/2 + 0.1
    assert z1 == pytest.approx(1e3 * (r + e), abs=0.1)  # ends inverted


def test_fig14_numbers(printed):
    moreau, ode2 = _open("moreau-smooth-quaternion_5s_normalized.nc"), _open("ode-quaternion_5s.nc")
    delta = _grab(rf"gamma\(ODE Model 2\)\| = {NUMBER} rad", printed)
    recomputed = float(np.abs(moreau.gamma.values - np.interp(moreau.time, ode2.time, ode2.gamma)).max())
    assert delta == pytest.approx(recomputed, rel=6e-3)
    assert 3e-4 < delta < 3e-3  # Sect. 6.5: the difference fluctuates between about +-1e-3 rad
    status, failures, iterations = re.search(
        rf"Moreau: (\w+), convergence failures: (\d+), mean prox iterations {NUMBER}", printed).groups()
    assert status == moreau.attrs["status"] == "completed"
    assert int(failures) == int(moreau.attrs["convergence_failures"]) == 0
    assert float(iterations) == pytest.approx(float(moreau.prox_iterations_mean.mean()), abs=0.006)


def test_stability_numbers(printed):
    smap = _open("stability_map.nc")
    counts = dict(re.findall(r"'(\w+)': (\d+)", re.search(r"points per branch: (\{.*\})", printed).group(1)))
    for branch in smap.branch.values:  # stable = every nontrivial eigenvalue in the left half plane
        expected = int((smap.eig_real.sel(branch=branch).max("eig") < 0).sum())
        assert int(counts[str(branch)]) == expected
    assert int(counts["noninverted"]) == 0  # the noninverted spin is never stable (a real eigenvalue > 0)
    assert int(counts["inverted"]) > 0  # the inverted spin has a stable window

    crit = _open("critical_speeds.nc").sel(branch="inverted")
    lo, hi = _grab(rf"eps is in \[{NUMBER}, {NUMBER}\] m/s", printed, n=2)
    with_window = crit.eps.values[crit.n_critical.values > 0]
    assert (lo, hi) == (pytest.approx(with_window.min(), abs=5e-4), pytest.approx(with_window.max(), abs=5e-4))
    lines = re.findall(rf"eps = {NUMBER} m/s: Omega_c = \[([^\]]*)\] rad/s", printed)
    assert len(lines) == len(with_window[::8])
    for eps, listed in lines:
        row = crit.sel(eps=float(eps), method="nearest")
        assert float(row.eps) == pytest.approx(float(eps), abs=5e-4)
        expected = row.omega_critical.values[: int(row.n_critical)]
        np.testing.assert_allclose([float(v) for v in listed.split()], expected, atol=6e-4)
        assert np.all((expected > 28) & (expected < 36))  # the window lies near 30 rad/s


def test_poincare_numbers(printed):
    sec = _open("poincare_section.nc")
    section, n = re.search(r"Poincaré section (\S+): (\d+) crossings", printed).groups()
    assert section == sec.attrs["section"] and int(n) == sec.sizes["crossing"] > 10
