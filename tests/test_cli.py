import dataclasses

import pytest

import tippedisk_analysis as td
from tippedisk_analysis.cli import main


def test_simulate_then_plot(tmp_path, capsys):
    out = tmp_path / "run.nc"
    assert main(["simulate", "--model", "ode1", "--t-end", "0.3", "--dt-output", "0.01", "--alpha-dot", "45",
                 "--gamma0", "-1.4", "--mu", "0.25", "--eps", "0.05", "--output", str(out)]) == 0
    ds = td.load(out)
    assert ds.attrs["model"] == "ode-euler"
    assert float(ds.alpha_dot[0]) == pytest.approx(45.0)
    assert float(ds.gamma[0]) == pytest.approx(-1.4)
    config = td.results.config_of(ds)
    assert (config["setup"]["friction"]["mu"], config["setup"]["friction"]["eps"]) == (0.25, 0.05)
    assert "completed" in capsys.readouterr().out
    png = tmp_path / "run.png"
    assert main(["plot", str(out), "--output", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize(
    "args, fragment",
    [
        (["--radius", "-0.045"], "radius"),
        (["--e", "0.05"], "not smaller than the radius"),
        (["--eps", "0"], "eps"),
        (["--model", "ode7"], "unknown model"),
        (["--t-end", "-1"], "t_end"),
        (["--dt-output", "0"], "dt_output"),
        (["--alpha-dot", "fast"], "not a number"),
    ],
)
def test_bad_input_exits_2_and_writes_nothing(tmp_path, capsys, args, fragment):
    out = tmp_path / "run.nc"
    assert _exit_code(["simulate", "--t-end", "0.1", "--output", str(out), *args]) == 2
    err = capsys.readouterr().err.strip()
    assert fragment in err and len(err.splitlines()) == 1
    assert not out.exists()


def test_plot_rejects_foreign_file(tmp_path, capsys):
    bogus = tmp_path / "bogus.nc"
    bogus.write_text("hello")
    assert main(["plot", str(bogus)]) == 2
    assert "not a netCDF" in capsys.readouterr().err
    assert not (tmp_path / "bogus.png").exists()


def _exit_code(argv):
    """main's return value, or the status of argparse's SystemExit."""
    try:
        return main(argv)
    except SystemExit as exc:
        return exc.code


def test_plot_rejects_damaged_dataset_and_unknown_format(tmp_path, capsys):
    import xarray as xr

    fake = tmp_path / "fake.nc"
    xr.Dataset({"a": ("x", [1.0])}, attrs={"producer": "tippedisk_analysis", "kind": "simulation"}).to_netcdf(fake)
    assert main(["plot", str(fake)]) == 2
    assert "damaged or not one of ours" in capsys.readouterr().err
    run = tmp_path / "run.nc"
    assert main(["simulate", "--t-end", "0.05", "--output", str(run)]) == 0
    assert main(["plot", str(run), "--output", str(tmp_path / "run.txt")]) == 2
    assert "cannot draw to '.txt'" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fake.nc", "run.nc"]


@pytest.mark.parametrize("args, fragment", [(["--fall-angle", "0"], "fall_angle"), (["--tol", "1"], "tol")])
def test_numerical_options_are_validated(tmp_path, capsys, args, fragment):
    out = tmp_path / "run.nc"
    assert main(["simulate", "--t-end", "0.1", "--output", str(out), *args]) == 2
    assert fragment in capsys.readouterr().err
    assert not out.exists()


def test_range_errors_name_the_option(tmp_path, capsys):
    out = tmp_path / "map.nc"
    assert _exit_code(["outcome-map", "--omega", "10:80", "--eps", "0.1:0.2:2", "--output", str(out)]) == 2
    assert "--omega '10:80' is not START:STOP:N" in capsys.readouterr().err
    assert not out.exists()


def test_existing_output_needs_overwrite(tmp_path, capsys):
    out = tmp_path / "run.nc"
    argv = ["simulate", "--t-end", "0.05", "--output", str(out)]
    assert main(argv) == 0
    capsys.readouterr()  # the first run's output (a compile notice on a cold heyoka cache)
    before = out.read_bytes()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "exists; give --overwrite to replace it, or another --output" in err and err.count("\n") == 1
    assert out.read_bytes() == before
    assert main([*argv, "--mu", "0.2", "--overwrite"]) == 0
    assert td.results.config_of(td.load(out))["setup"]["friction"]["mu"] == 0.2


def _disk(path):
    return td.results.config_of(td.load(path))["setup"]["disk"]


def test_disk_from_table2_geometry_or_values(tmp_path):
    run = ["simulate", "--t-end", "0.02"]
    assert main([*run, "-o", str(tmp_path / "t2.nc")]) == 0
    assert _disk(tmp_path / "t2.nc") == {"m": 0.435, "e": 2.5e-3, "r": 0.045, "A": 0.249e-3, "B": 0.227e-3,
                                         "C": 0.468e-3}  # Table 2, stored as before
    assert main([*run, "--disk", "geometry", "--hole-offset", "0.024", "-o", str(tmp_path / "g.nc")]) == 0
    geo = _disk(tmp_path / "g.nc")
    expected = td.Disk.from_geometry(b=0.024)
    assert geo["geometry"] == {"rho": 7700.0, "r": 0.045, "a": 0.015, "b": 0.024, "h": 0.01}
    assert (geo["m"], geo["e"], geo["B"]) == (expected.m, expected.e, expected.B)
    assert td.load(tmp_path / "g.nc").attrs["disk_source"] == "geometry"
    values = ["--mass", "0.4", "--e", "0.002", "--radius", "0.04", "--A", "2e-4", "--B", "1.8e-4", "--C", "3.7e-4"]
    assert main([*run, "--disk", "given", *values, "-o", str(tmp_path / "v.nc")]) == 0
    assert _disk(tmp_path / "v.nc") == {"m": 0.4, "e": 0.002, "r": 0.04, "A": 2e-4, "B": 1.8e-4, "C": 3.7e-4}
    assert main([*run, "--mass", "0.87", "-o", str(tmp_path / "m.nc")]) == 0  # same shape, twice the density
    heavy = _disk(tmp_path / "m.nc")
    assert heavy["m"] == 0.87 and heavy["A"] == pytest.approx(2 * 0.249e-3) and heavy["e"] == 2.5e-3


def test_disk_options_reach_every_command(tmp_path):
    geo = ["--disk", "geometry", "--hole-offset", "0.024"]
    drilled = dataclasses.asdict(td.Disk.from_geometry(b=0.024))
    commands = {
        "p.nc": ["poincare", "--t-end", "0.3", *geo],
        "b.nc": ["bifurcation", "--omega", "40:50:2", "--t-transient", "0.1", "--t-end", "0.3", *geo],
        "o.nc": ["outcome-map", "--omega", "40:50:2", "--eps", "0.1", "--t-end", "0.2", *geo],
        "s.nc": ["stability-map", "--omega", "30:40:3", "--eps", "0.1", *geo],
        "ba.nc": ["basins", "--omega", "40", "--dgamma0", "0.1:0.2:2", "--t-end", "0.5", *geo],
        "bf.nc": ["basin-fractions", "--over", "omega=30:40:2", "--dgamma0", "0.1:0.2", "--samples", "2",
                  "--t-end", "0.5", *geo],
        "c.nc": ["continue", "--from", "30", "--to", "31", "--eps", "0.25", "--max-points", "3", *geo],
        "l.nc": ["lyapunov", "--t-end", "0.5", *geo],
        "lm.nc": ["lyapunov", "--omega", "30:40:2", "--t-end", "0.5", *geo],
        "po.nc": ["periodic-orbits", "--frictionless", "inverted:40", "--max-points", "2", *geo],
    }
    for name, argv in commands.items():
        assert main([*argv, "-o", str(tmp_path / name)]) == 0, name
        assert _disk(tmp_path / name) == drilled, name


@pytest.mark.parametrize("argv, fragment", [
    (["continue", "--from-point", "c.nc:HOPF1", "--mass", "0.5"], "--mass with --from-point"),
    (["continue", "--parameter", "e", "--omega", "40", "--to", "0.003", "--disk", "geometry"],
     "a continuation in e holds A, B, C about G fixed"),
    (["periodic-orbits", "--system", "hopf", "--radius", "0.05"], "the orbit radius of a Hopf start is --hopf-radius"),
    (["lyapunov", "--system", "lorenz", "--disk", "given"], "--disk belong(s) to the tippedisk"),
])
def test_disk_options_are_refused_where_the_disk_is_fixed_or_absent(tmp_path, capsys, argv, fragment):
    assert main([*argv, "-o", str(tmp_path / "x.nc")]) == 2
    err = capsys.readouterr().err
    assert fragment in err and err.count("\n") == 1 and not (tmp_path / "x.nc").exists()


def test_eccentricity_sweeps_say_what_they_hold(tmp_path):
    assert main(["stability-map", "--omega", "30:40:2", "--eps", "0.1", "--e", "0.002:0.003:2", "--disk", "geometry",
                 "-o", str(tmp_path / "g.nc")]) == 0
    assert main(["outcome-map", "--omega", "30:40:2", "--eps", "0.1", "--e", "0.002:0.003:2", "--t-end", "0.2",
                 "-o", str(tmp_path / "t.nc")]) == 0
    g, t = td.load(tmp_path / "g.nc"), td.load(tmp_path / "t.nc")
    assert "hole offset b moved" in g["e"].attrs["comment"] and "hole offset" in td.results.config_of(g)["e_sweep"]
    assert "A, B, C about G held fixed" in t["e"].attrs["comment"] and "held fixed" in t.attrs["e_sweep"]


def test_interrupt_in_process_returns_130_with_one_line(tmp_path, capsys, monkeypatch):
    from tippedisk_analysis.solvers import taylor

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(taylor, "integrate", interrupted)
    assert main(["simulate", "--t-end", "0.05", "-o", str(tmp_path / "run.nc")]) == 130
    err = capsys.readouterr().err
    assert err == "tippedisk simulate: interrupted; nothing stored (ODE runs keep no checkpoint: rerun to start again)\n"
    assert list(tmp_path.iterdir()) == []


def test_help_texts_name_values_and_units(capsys):
    for argv in (["study", "--help"], ["bifurcation", "--help"], ["simulate", "--help"]):
        assert _exit_code(argv) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "fig13_ode_inversion" in out  # study --help lists the studies
    assert "which crossings of the section count" in out and "one of x, y, alpha, beta, gamma, x_dot" in out
    assert "W_friction, z, z_dot, alpha_dot" in out
    assert "rate alpha_dot(0) = spin Omega [rad/s]" in out and "Euler angle beta(0), inclination [rad]" in out


def test_help_and_version_import_no_heavy_library():
    """`tippedisk --version` and every `--help` build the parser without numpy, xarray, heyoka, numba or
    matplotlib (their imports cost most of a second; benchmarks/bench_startup.py times the processes)."""
    import subprocess
    import sys

    code = ("import sys; from tippedisk_analysis.cli import build_parser; build_parser(); "
            "print(' '.join(m for m in ('numpy', 'xarray', 'heyoka', 'numba', 'matplotlib', 'scipy') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == ""


def test_a_reader_that_goes_away_ends_the_command_quietly():
    """`tippedisk critical-spin | head -c 1`: the pipe closes before the output is written; no error line."""
    import subprocess
    import sys

    proc = subprocess.Popen([sys.executable, "-m", "tippedisk_analysis.cli", "critical-spin"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE)
    proc.stdout.close()
    _out, err = proc.communicate()
    assert proc.returncode == 0 and b"error" not in err and b"Traceback" not in err, err
