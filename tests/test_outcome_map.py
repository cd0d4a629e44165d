"""Outcome maps: ranges, batch = scalar, classification, chunked resume after a kill, dask, CLI."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from tippedisk_analysis import ParameterError, load
from tippedisk_analysis.analysis import outcome_config
from tippedisk_analysis.analysis import outcome_map as om
from tippedisk_analysis.dynamics import sweeps
from tippedisk_analysis.cli import main
from tippedisk_analysis.models import ode
from tippedisk_analysis.parameters import Disk
from tippedisk_analysis.testing import outcome_chunk_scalar

SRC = str(Path(__file__).resolve().parents[1] / "src")
SMALL = {"omega": (5.0, 70.0, 6), "eps": (0.05, 0.2, 4)}  # 24 points: 3 batches of 8 lanes
OPTS = {"t_end": 1.0, "chunk_size": 8}


def test_linspace_semantics():
    cfg = om.MapConfig(ranges={"omega": (10, 80, 8), "eps": (0.1, 0.1, 1)})
    np.testing.assert_array_equal(cfg.axes()["omega"], np.linspace(10, 80, 8))
    assert cfg.shape == (8, 1) and cfg.window == pytest.approx(0.2 * cfg.t_end)


def test_fast_point_preparation_matches_the_parameter_dataclasses():
    """_prepare edits the base parameter vector; the validated dataclasses must give the same runs."""
    cfg = om.MapConfig(ranges={"omega": (-50, 80, 5), "eps": (0.01, 0.3, 3), "mu": (0.1, 0.5, 2),
                               "e": (1e-3, 4e-3, 2), "dgamma0": (0.05, 0.2, 2)}, t_end=0.1)
    x0, pars = outcome_config.prepare(cfg, 0, cfg.n_points)
    for i in range(0, cfg.n_points, 7):
        point = {k: v[0] for k, v in cfg.points(i, i + 1).items()}
        setup, initial = outcome_config.point_setup(cfg.base_setup(), point)
        np.testing.assert_array_equal(pars[:, i], ode.parameter_vector(setup, cfg.fall_angle, cfg.slip_smoothing))
        np.testing.assert_array_equal(x0[:-2, i], ode.initial_state_vector(ode.EULER, setup, initial))
        assert initial.alpha_dot == point["omega"] and initial.gamma == pytest.approx(-np.pi / 2 + point["dgamma0"])


@pytest.mark.slow
def test_batch_equals_scalar():
    """SIMD batch lanes (with lanes that fall and are shadowed) = one run at a time."""
    cfg = om.MapConfig(ranges=SMALL, **OPTS)
    batch = om.run_chunk(cfg, 0, cfg.n_points)
    scalar = outcome_chunk_scalar(cfg, 0, cfg.n_points)
    assert np.any(batch["outcome"] == om.OUTCOMES["fell"])  # the shadowing path is exercised
    for name in om.RESULT_VARIABLES:
        np.testing.assert_allclose(batch[name], scalar[name], rtol=1e-9, atol=1e-9, err_msg=name)


def test_classification_follows_the_paper():
    """Table 3 (Omega = 40 rad/s, eps = 0.1 m/s) inverts within 0.5 s (Fig. 13); a slow spin falls."""
    ds = om.outcome_map({"omega": (2.0, 40.0, 2), "eps": (0.1, 0.1, 1)}, t_end=2.0, progress=False)
    slow, paper = ds.isel(omega=0, eps=0), ds.isel(omega=1, eps=0)
    assert int(paper["outcome"]) == om.OUTCOMES["inverted"]
    assert 0 < float(paper["inversion_time"]) < 0.5
    assert float(paper["fall_time"]) == om.FILL_TIME
    disk = Disk()
    assert float(paper["z_S_mean"]) > disk.r  # S above G on average in the window
    assert int(slow["outcome"]) == om.OUTCOMES["fell"]
    assert 0 < float(slow["fall_time"]) == float(slow["t_final"]) < 2.0
    assert np.sin(float(slow["beta_final"])) == pytest.approx(np.sin(0.1), abs=1e-9)
    flags = ds["outcome"].attrs
    assert list(flags["flag_values"]) == list(om.OUTCOMES.values())
    assert flags["flag_meanings"].split() == list(om.OUTCOMES)


def test_outcome_follows_the_documented_rules():
    """Re-derive every outcome from the stored variables with the rules of the module docstring."""
    cfg = om.MapConfig(ranges={"omega": (5.0, 80.0, 8), "eps": (0.02, 0.3, 4)}, t_end=1.5, chunk_size=16)
    r = om.run_chunk(cfg, 0, cfg.n_points)
    assert len(set(r["outcome"])) >= 3  # several classes occur on this grid
    for i in range(cfg.n_points):
        if r["fall_time"][i] != om.FILL_TIME:
            expected = "fell"
        elif abs(r["gamma_turns"][i]) >= 1:
            expected = "rolling"
        elif r["sin_gamma_mean"][i] >= cfg.threshold:
            expected = "inverted"
        elif r["sin_gamma_mean"][i] <= -cfg.threshold:
            expected = "not_inverted"
        else:
            expected = "undecided"
        assert r["outcome"][i] == om.OUTCOMES[expected], i
        assert (r["fall_time"][i] == om.FILL_TIME) == (r["t_final"][i] == cfg.t_end)
        # every run started with S below G: an inversion time exists iff gamma ever reached 0 from below
        if r["inversion_time"][i] == om.FILL_TIME:
            assert expected in ("fell", "not_inverted", "undecided")
        else:
            assert 0 < r["inversion_time"][i] <= r["t_final"][i]


def test_round_trip_and_dims(tmp_path):
    ds = om.outcome_map({"omega": (30, 50, 3), "eps": (0.05, 0.1, 2), "mu": (0.2, 0.3, 2)}, t_end=0.3,
                        progress=False, output=tmp_path / "m.nc")
    assert ds["outcome"].dims == ("omega", "eps", "mu") and ds["outcome"].dtype == np.int8
    xr.testing.assert_identical(load(tmp_path / "m.nc"), ds)
    assert not sweeps.chunk_dir(tmp_path / "m.nc").exists()  # merged and cleaned up
    for name in ds.data_vars:
        assert np.all(np.isfinite(ds[name])), name


KILL_SCRIPT = textwrap.dedent("""
    import os, signal, sys
    from tippedisk_analysis.analysis import outcome_map as om
    from tippedisk_analysis.dynamics import sweeps
    cfg = om.MapConfig(ranges={ranges!r}, **{opts!r})
    stored = []
    def on_chunk(i):
        stored.append(i)
        if len(stored) == 3:
            os.kill(os.getpid(), signal.SIGKILL)  # a hard kill, as from the OOM killer or kill -9
    sweeps.run_sweep(om.sweep(cfg), output=sys.argv[1], threads=1, progress=False, on_chunk=on_chunk)
""")


def test_killed_run_resumes_without_recomputing(tmp_path):
    out = tmp_path / "map.nc"
    script = KILL_SCRIPT.format(ranges=SMALL, opts=OPTS)
    env = {**os.environ, "PYTHONPATH": SRC}
    proc = subprocess.run([sys.executable, "-c", script, str(out)], env=env, capture_output=True, timeout=120)
    assert proc.returncode == -9, proc.stderr.decode()
    d = sweeps.chunk_dir(out)
    finished = sorted(d.glob("chunk_*.nc"))
    assert len(finished) == 3 and not out.exists()
    before = {p.name: p.stat().st_mtime_ns for p in finished}

    cfg = om.MapConfig(ranges=SMALL, **OPTS)
    with pytest.raises(ParameterError, match="different outcome map configuration"):
        sweeps.run_sweep(om.sweep(om.MapConfig(ranges=SMALL, t_end=0.5, chunk_size=8)), output=out, progress=False)

    computed = []

    def on_chunk(i):
        computed.append(i)
        for name, mtime in before.items():  # finished chunks are neither rewritten nor removed
            assert (d / name).stat().st_mtime_ns == mtime

    resumed = sweeps.run_sweep(om.sweep(cfg), output=out, progress=False, on_chunk=on_chunk)
    done = {int(name[6:11]) for name in before}
    assert sorted(computed) == sorted(set(range(len(sweeps.chunk_bounds(om.sweep(cfg))))) - done)

    fresh = sweeps.run_sweep(om.sweep(cfg), output=tmp_path / "fresh.nc", progress=False)
    xr.testing.assert_identical(load(out), load(tmp_path / "fresh.nc"))
    xr.testing.assert_identical(resumed, fresh)


def test_dask_local_cluster_equals_threads():
    distributed = pytest.importorskip("distributed")
    cfg = om.MapConfig(ranges=SMALL, **OPTS)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        on_dask = sweeps.run_sweep(om.sweep(cfg), scheduler=client, progress=False)
    xr.testing.assert_identical(on_dask, sweeps.run_sweep(om.sweep(cfg), progress=False))


@pytest.mark.parametrize("args", [
    ["--omega", "10:80", "--eps", "0.1:0.2:3"],
    ["--omega", "10:80:x", "--eps", "0.1:0.2:3"],
    ["--omega", "10:80:4", "--eps", "0:0.2:3"],  # eps = 0 is not a smooth law
    ["--omega", "10:80:4", "--eps", "0.1:0.2:3", "--e", "0.05:0.06:2"],  # e >= r
    ["--omega", "10:80:4", "--eps", "0.1:0.2:3", "--t-end", "-1"],
    ["--omega", "10:80:4"],
])
def test_cli_bad_input_exits_2_without_file(tmp_path, capsys, args):
    out = tmp_path / "m.nc"
    assert _exit_code(["outcome-map", *args, "-o", str(out)]) == 2
    assert not out.exists() and not sweeps.chunk_dir(out).exists()
    assert capsys.readouterr().err.strip().count("\n") == 0  # one line


def _exit_code(argv) -> int:
    try:
        return main(argv)
    except SystemExit as exc:  # argparse errors
        return exc.code


def test_cli_writes_and_plots(tmp_path):
    out = tmp_path / "m.nc"
    assert main(["outcome-map", "--omega", "30:50:2", "--eps", "0.1:0.2:2", "--t-end", "0.3", "-o", str(out)]) == 0
    assert load(out).attrs["kind"] == "outcome_map"
    assert main(["plot", str(out)]) == 0 and out.with_suffix(".png").stat().st_size > 0


def test_cli_scheduler_address(tmp_path):
    distributed = pytest.importorskip("distributed")
    out = tmp_path / "m.nc"
    argv = ["outcome-map", "--omega", "30:50:2", "--eps", "0.1:0.2:2", "--t-end", "0.3", "-o", str(out)]
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        assert main([*argv, "--scheduler", cluster.scheduler_address]) == 0
    on_cluster = load(out)
    assert main([*argv, "--overwrite"]) == 0  # the output exists: replacing it needs --overwrite
    xr.testing.assert_identical(on_cluster, load(out))


@pytest.mark.slow
def test_cli_unreachable_scheduler_exits_2_without_file(tmp_path, capsys):
    out = tmp_path / "m.nc"
    argv = ["outcome-map", "--omega", "30:50:2", "--eps", "0.1:0.2:2", "-o", str(out),
            "--scheduler", "tcp://127.0.0.1:9"]
    assert _exit_code(argv) == 2
    assert not out.exists() and not sweeps.chunk_dir(out).exists()
    assert "dask scheduler" in capsys.readouterr().err


def test_error_in_a_chunk_keeps_the_stored_chunks(tmp_path):
    """An exception while storing (as Ctrl-C would raise) stops the sweep; finished chunks stay for a rerun."""
    cfg = om.MapConfig(ranges=SMALL, **OPTS)
    out = tmp_path / "m.nc"

    def stop_after_two(i, seen=[]):  # noqa: B006 - deliberate accumulator
        seen.append(i)
        if len(seen) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sweeps.run_sweep(om.sweep(cfg), output=out, threads=1, progress=False, on_chunk=stop_after_two)
    assert len(list(sweeps.chunk_dir(out).glob("chunk_*.nc"))) == 2 and not out.exists()
    computed = []
    sweeps.run_sweep(om.sweep(cfg), output=out, progress=False, on_chunk=computed.append)
    assert len(computed) == len(sweeps.chunk_bounds(om.sweep(cfg))) - 2 and out.exists()


def test_validity_flag_marks_runs_whose_normal_force_turns_negative():
    """lift_off_time is the first zero of lambda_N (an exact event); it agrees with a sampled simulation."""
    import tippedisk_analysis as td

    ds = om.outcome_map({"omega": (100.0, 300.0, 2), "eps": (0.1, 0.1, 1)}, t_end=1.0, progress=False)
    valid, lift_off = ds["valid"].values.ravel(), ds["lift_off_time"].values.ravel()
    assert list(valid) == [1, 0] and lift_off[0] == -1.0 and 0 < lift_off[1] < 1.0
    assert "1 run(s) with lambda_N < 0" in ds.attrs["message"]
    run = td.simulate("ode-euler", 1.0, initial=td.InitialState(alpha_dot=300.0), dt_output=1e-4)
    first_negative = float(run.time[np.argmax(run.lambda_N.values < 0)])
    assert first_negative - 1e-4 <= lift_off[1] <= first_negative
    assert float(td.simulate("ode-euler", 1.0, initial=td.InitialState(alpha_dot=100.0)).lambda_N.min()) > 0


def test_cli_says_why_runs_are_undecided_and_what_to_do(tmp_path, capsys):
    """A horizon shorter than the time to a decision leaves runs undecided: the line says so and names the fix."""
    out = tmp_path / "m.nc"
    assert main(["outcome-map", "--omega", "30:50:2", "--eps", "0.1:0.2:2", "--t-end", "2", "-o", str(out)]) == 0
    ds = load(out)
    flags = dict(zip(ds.outcome.attrs["flag_meanings"].split(), ds.outcome.attrs["flag_values"]))
    n = int((ds.outcome == flags["undecided"]).sum())
    line = capsys.readouterr().out
    assert n > 0 and f"{n} of 4 runs undecided: the horizon --t-end 2 s ended before they reached an attractor" in line
    assert "give a longer --t-end, e.g. 60, or --classify rules" in line
    assert main(["outcome-map", "--omega", "30:50:2", "--eps", "0.1:0.2:2", "--t-end", "2", "--classify", "rules",
                 "-o", str(tmp_path / "r.nc")]) == 0
    assert "undecided:" not in capsys.readouterr().out  # rules classify every run of fixed length
