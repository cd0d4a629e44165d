"""Lyapunov exponents (analysis/lyapunov.py): Lorenz to two decimals, Liouville (sum = mean divergence),
the spectrum at a stable spinning equilibrium, and the map over (Omega, eps) on the sweep machinery."""

from __future__ import annotations

import numpy as np
import pytest

import tippedisk_analysis as td
from tippedisk_analysis.analysis import lyapunov as ly
from tippedisk_analysis.analysis import reduced, stationary
from tippedisk_analysis.errors import ParameterError
from tippedisk_analysis.models import ode


def test_lorenz_spectrum_to_two_decimals():
    ds = ly.textbook_spectrum("lorenz", [1.0, 1.0, 1.0], t_end=5000.0, dt=1.0, transient=20.0)
    assert ds.attrs["kind"] == "lyapunov" and ds.attrs["status"] == "completed"
    np.testing.assert_allclose(ds.exponents.values, [0.9056, 0.0, -14.5723], atol=5e-3)
    assert float(ds.exponent_sum) == pytest.approx(-(10 + 1 + 8 / 3), abs=1e-6)  # constant divergence
    assert float(ds.divergence_mean) == pytest.approx(-(10 + 1 + 8 / 3), rel=1e-12)
    h = ds.running_exponents.values[:, 0]
    assert abs(h[-1] - 0.9056) < abs(h[len(h) // 20] - 0.9056) + 1e-3  # the history converges


def test_tippedisk_spectrum_sum_equals_the_mean_divergence():
    """3 s of the Table 3 run: the sum equals the divergence of the same run; the error bars are wider than the
    exponents' distances from zero, so the run is not_converged and says how long a run would be."""
    ds = ly.tippedisk_spectrum(td.Setup(friction=td.Friction(eps=0.25)), t_end=3.0)
    assert ds.sizes["exponent"] == 7 and ds.attrs["status"] == "not_converged"
    assert "give t_end >=" in ds.attrs["message"] and np.all(ds.exponent_error.values > 0)
    assert float(ds.exponent_sum) == pytest.approx(float(ds.divergence_mean), rel=1e-10)


def test_at_a_stable_equilibrium_the_spectrum_is_the_real_parts_including_the_spin_family_zero():
    setup = td.Setup(friction=td.Friction(eps=0.25))
    x = stationary.stationary_state("inverted", [31.63])[:, 0]  # inside the stable window (docs/continuation.md)
    real = np.sort(np.linalg.eigvals(reduced.jacobian(x, ode.parameter_vector(setup))[0]).real)[::-1]
    assert real[1] < -0.3  # the largest nontrivial real part: not what the largest exponent converges to
    ds = ly.tippedisk_spectrum(setup, state=x, t_end=200.0, transient=20.0)
    lam = ds.exponents.values
    assert abs(lam[0] - real[0]) < 1e-4 and abs(real[0]) < 1e-12  # the structural zero
    np.testing.assert_allclose(lam, real, atol=5e-3)  # complex pairs: finite-time oscillation ~1/t


def test_bad_requests_are_one_line_errors():
    system = ly.textbook_system("lorenz")
    with pytest.raises(ParameterError, match="n_exponents"):
        ly.spectrum(system, [1.0, 1.0, 1.0], n_exponents=4)
    with pytest.raises(ParameterError, match="transient"):
        ly.spectrum(system, [1.0, 1.0, 1.0], t_end=1.0, transient=2.0)
    with pytest.raises(ParameterError, match="eps must be positive"):
        ly.MapConfig(omega=[10, 20, 2], eps=[0.0, 0.1, 2])


@pytest.mark.slow
def test_map_flags_falls_and_matches_single_runs(tmp_path):
    out = tmp_path / "map.nc"
    seen = []
    kw = dict(t_end=20.0, dt=0.5, chunk_size=2, batch_size=4)
    ds = ly.lyapunov_map((10.0, 40.0, 2), (0.05, 0.25, 2), output=out, progress=False, threads=2, **kw)
    assert out.is_file() and not (tmp_path / "map.nc.chunks").exists()
    assert ds.attrs["mode"] == "map" and ds.max_exponent.dims == ("omega", "eps")
    outcome = ds.outcome.values
    assert outcome[0, 0] == ly.OUTCOMES["fell"] and float(ds.t_final[0, 0]) < 20.0  # slow spin, small eps
    assert (outcome[1] == ly.OUTCOMES["completed"]).all()
    # a completed point equals the scalar integrator's largest exponent (same start vector and dt)
    setup = td.Setup(friction=td.Friction(eps=0.25))
    single = ly.spectrum(ly.tippedisk_system(setup), ly.tippedisk_start(setup, td.InitialState(alpha_dot=40.0)),
                         ode.parameter_vector(setup), n_exponents=1, t_end=20.0, dt=0.5, divergence=False)
    assert float(ds.max_exponent[1, 1]) == pytest.approx(single.exponents[0], rel=1e-3, abs=1e-4)
    # resumable: interrupted after the first chunk, a rerun computes only the missing one
    config = ly.MapConfig(omega=[10.0, 40.0, 2], eps=[0.05, 0.25, 2], **kw)
    from tippedisk_analysis.dynamics import sweeps

    def stop_after_first(_index):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sweeps.run_sweep(ly.sweep(config), output=tmp_path / "again.nc", progress=False, threads=1,
                         on_chunk=stop_after_first)
    assert len(list(sweeps.chunk_dir(tmp_path / "again.nc").glob("chunk_*.nc"))) == 1
    again = sweeps.run_sweep(ly.sweep(config), output=tmp_path / "again.nc", progress=False,
                             on_chunk=seen.append)
    assert len(seen) == 1
    np.testing.assert_array_equal(again.max_exponent.values, ds.max_exponent.values)


def test_cli_map_spectrum_and_bad_input(tmp_path, capsys):
    from tippedisk_analysis.cli import main

    out = tmp_path / "map.nc"
    assert main(["lyapunov", "--omega", "20:40:2", "--eps", "0.1:0.25:2", "--t-end", "4", "-o", str(out)]) == 0
    assert td.load(out).attrs["mode"] == "map" and main(["plot", str(out)]) == 0
    out = tmp_path / "lorenz.nc"
    assert main(["lyapunov", "--system", "lorenz", "--t-end", "50", "-o", str(out)]) == 0
    assert td.load(out).sizes["exponent"] == 3 and main(["plot", str(out)]) == 0
    capsys.readouterr()
    bad = tmp_path / "bad.nc"
    for args, fragment in ((["--omega", "10:40:3", "--eps", "0:0.2:3"], "eps must be positive"),
                           (["--system", "duffing"], "knows lorenz"),
                           (["--omega", "40", "--n-exponents", "8"], "n_exponents")):
        assert main(["lyapunov", *args, "-o", str(bad)]) == 2
        err = capsys.readouterr().err.strip()
        assert fragment in err and len(err.splitlines()) == 1 and not bad.exists()
