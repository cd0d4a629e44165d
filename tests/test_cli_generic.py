"""The command line on the datasets of any System and on the hybrid model's numerical endings (issue 30)."""

from __future__ import annotations

import matplotlib
import pytest

import tippedisk_analysis as td
import zoo
from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.cli import main
from tippedisk_analysis.cli.periodic_orbits import ORBIT_SYSTEMS
from tippedisk_analysis.plotting import FIGURES

matplotlib.use("Agg")


def test_the_system_help_lists_every_catalogue_system_with_a_start(capsys):
    assert set(ORBIT_SYSTEMS) == {name for name, tb in dy.TEXTBOOK.items() if tb.start}
    assert main(["periodic-orbits", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert all(name in text for name in ORBIT_SYSTEMS)


def test_from_hopf_of_a_user_system_is_one_line_and_of_a_catalogue_system_a_branch(tmp_path, capsys):
    s = zoo.bautin()
    td.save(dy.equilibrium_branch(s, [0.0, 0.0], "mu", bounds=(-1.5, 0.5), pars=s.with_pars(mu=-1.5)),
            tmp_path / "user.nc")
    assert main(["periodic-orbits", "--from-hopf", f"{tmp_path / 'user.nc'}:HOPF1", "-o", str(tmp_path / "o.nc")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "bautin_user" in err and "dy.orbit_branch(" in err
    assert not (tmp_path / "o.nc").exists()
    ab = dy.textbook_system("ab")
    td.save(dy.equilibrium_branch(ab, [0.0, 0.0], "D", bounds=(0.0, 0.2)), tmp_path / "ab.nc")
    assert main(["periodic-orbits", "--from-hopf", f"{tmp_path / 'ab.nc'}:HOPF1", "--to", "0.12",
                 "-o", str(tmp_path / "ab_po.nc")]) == 0
    po = td.load(tmp_path / "ab_po.nc")
    assert po.attrs["status"] == "completed" and float(po.D.min()) == pytest.approx(0.12, abs=1e-12)


def test_generic_figures_use_the_declared_names_and_time_units():
    """A user's parameter mu is no friction coefficient, and a dimensionless time has no seconds."""
    s = zoo.duffing_vdp()
    eq = dy.equilibrium_branch(s, [0.0, 0.0], "mu", bounds=(-1.0, 1.0), pars=s.with_pars(mu=-0.5))
    ba = dy.basins(s.with_defaults(mu=-0.5), dy.Grid(("x", "y"), (-4, -6), (4, 6), (80, 120)),
                   {"x": (-3.0, 3.0, 6), "y": (-3.0, 3.0, 6)}, horizon=60.0, progress=False)
    texts = []
    for ds in (eq, ba):
        fig = FIGURES[ds.attrs["kind"]](ds)
        texts += [t for ax in fig.axes for t in (ax.get_xlabel(), ax.get_ylabel())]
    assert "mu" in texts and not any("friction" in t or "[s]" in t for t in texts)
    assert "time to assignment [-]" in texts


@pytest.mark.parametrize("argv, status, code", [
    (["--t-end", "1", "--tol", "0.99", "--alpha-dot", "400"], "zeno", 1),  # switches accumulate: numerics
    (["--t-end", "0.3", "--mu", "0"], "completed", 0),  # slides all run long
])
def test_hybrid_endings_and_their_exit_status(tmp_path, capsys, argv, status, code):
    out = tmp_path / "h1.nc"
    assert main(["simulate", "--model", "h1", *argv, "-o", str(out)]) == code
    text = capsys.readouterr().out
    assert td.load(out).attrs["status"] == status
    if "--mu" in argv:
        assert "started sliding, then 0 mode switch(es)" in text


@pytest.mark.parametrize("option", [["--gravity", "1e300"], ["--alpha-dot", "1e150"], ["--mass", "1e-300"],
                                    ["--mu", "1e300"], ["--beta-dot", "1e10"]])
def test_hybrid_runs_with_extreme_finite_inputs_end_nonfinite(tmp_path, capsys, option):
    """Outputs that overflow at once: a dataset that ends at the last finite sample, status nonfinite, exit 1,
    one line (as the ODE and Moreau models)."""
    out = tmp_path / "h1.nc"
    assert main(["simulate", "--model", "h1", "--t-end", "0.1", *option, "-o", str(out)]) == 1
    ds = td.load(out)
    assert ds.attrs["status"] == "nonfinite" and "non-finite" in ds.attrs["message"]
    assert len(capsys.readouterr().err.strip().splitlines()) <= 1


def test_hybrid_section_of_an_overflowing_run_is_empty_and_nonfinite(tmp_path):
    out = tmp_path / "p.nc"
    assert main(["poincare", "--model", "h1", "--omega", "1e150", "-o", str(out)]) == 1
    ds = td.load(out)
    assert ds.attrs["status"] == "nonfinite" and ds.sizes["crossing"] == 0


def test_a_hybrid_run_starts_with_its_initial_state(tmp_path):
    ds = td.simulate("h1", 0.01)
    assert float(ds.time[0]) == 0.0 and float(ds.gamma[0]) == pytest.approx(-1.4707963267948965, abs=1e-15)


@pytest.mark.parametrize("argv", [
    ["periodic-orbits", "--frictionless", "inverted:nan"],
    ["periodic-orbits", "--frictionless", "inverted:inf"],
    ["periodic-orbits", "--frictionless", "inverted:1e300"],
    ["simulate", "--tol", "1e-300"],
    ["simulate", "--model", "m1", "--tol", "0"],
    ["poincare", "--tol", "1"],
])
def test_absurd_inputs_are_one_line_and_exit_2(tmp_path, capsys, argv):
    out = tmp_path / "out.nc"
    assert main([*argv, "-o", str(out)]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1 and not out.exists()


def test_a_dataset_whose_config_is_not_json_is_refused_in_one_line(tmp_path, capsys):
    ds = td.simulate("ode1", 0.01)
    ds.attrs["config"] = "not json {"
    ds.to_netcdf(tmp_path / "bad.nc")
    assert main(["periodic-orbits", "--from-run", str(tmp_path / "bad.nc"), "-o", str(tmp_path / "o.nc")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not JSON" in err[0]


def test_a_moreau_run_takes_every_whole_step_to_t_end():
    """600 s / 1e-5 s is 59999999.99999999 in floating point: the run took one step too few and ended at
    599.99999 s. The step count is the integer ratio to round-off."""
    from tippedisk_analysis.solvers.moreau.driver import whole_steps

    assert whole_steps(600.0, 1e-5) == 60_000_000 and whole_steps(0.35, 0.1) == 3
    ds = td.simulate("m1", 0.003, dt=1e-5)
    assert float(ds.time[-1]) == pytest.approx(0.003, abs=1e-15)


def test_a_dataset_too_large_for_memory_is_named_as_such(tmp_path):
    """A file of ours whose variable has 4e9 values (32 GB, stored sparse): refused as too large to load, not
    as 'not a netCDF dataset (MemoryError)'."""
    import netCDF4

    path = tmp_path / "huge.nc"
    with netCDF4.Dataset(path, "w") as nc:
        nc.setncatts({"producer": "tippedisk_analysis", "kind": "simulation"})
        nc.createDimension("time", 4_000_000_000)
        nc.createVariable("gamma", "f8", ("time",), chunksizes=(1_000_000,))
    with pytest.raises(td.TippediskError, match="needs about .* of memory"):
        td.load(path)


def test_messages_name_the_real_cause(tmp_path, capsys):
    """An eccentricity the inertia cannot take is named as such (not 'B_S not positive'); --from-run on a run
    that lifted off says it lifted off (not 'give a longer run')."""
    assert main(["simulate", "--e", "0.04", "-o", str(tmp_path / "e.nc")]) == 2
    assert "eccentricity e = 0.04 m is too large" in capsys.readouterr().err
    run = tmp_path / "lo.nc"
    assert main(["simulate", "--model", "h1", "--t-end", "1", "--alpha-dot", "400", "-o", str(run)]) == 0
    assert td.load(run).attrs["status"] == "lift_off"
    capsys.readouterr()
    assert main(["periodic-orbits", "--from-run", str(run), "-o", str(tmp_path / "o.nc")]) == 2
    err = capsys.readouterr().err
    assert "ended 'lift_off'" in err and "longer run" not in err


def test_after_its_result_the_command_ignores_ctrl_c():
    """Ctrl-C in the last moments, after the result line, hit the interpreter's shutdown (dask's atexit) with a
    traceback: the finished command ignores SIGINT from then on (observed on the process, not timed)."""
    import subprocess
    import sys

    code = ("import signal, sys; sys.argv = ['tippedisk', 'study', '--list']; from tippedisk_analysis.cli import main; "
            "status = main(); print(status, signal.getsignal(signal.SIGINT) == signal.SIG_IGN)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.stdout.strip().splitlines()[-1] == "0 True"
