"""Lyapunov spectra that check themselves (dynamics/lyapunov.py): the sum of the exponents equals the mean
divergence integrated on the same steps (Liouville), standard errors from blocks of the run, and a status that is
``completed`` only when every exponent is settled. References: exact divergences (Lorenz-63: -(sigma + 1 + beta)),
scipy's solve_ivp at rtol 1e-12, published exponents and the literature van der Pol multiplier."""

from __future__ import annotations

import math

import heyoka as hy
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import tippedisk_analysis as td
from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.dynamics import lyapunov
from tippedisk_analysis.errors import ParameterError

L84 = {"a": 0.25, "b": 4.0, "F": 8.0, "G": 1.0}
L63_SUM = -(10.0 + 1.0 + 8.0 / 3.0)


def lorenz84() -> dy.System:
    """Lorenz-84: x' = -y^2 - z^2 - a x + a F, y' = x y - b x z - y + G, z' = b x y + x z - z; div = 2 x - 2 - a."""
    x, y, z = hy.make_vars("x", "y", "z")
    a, b, F, G = (hy.par[i] for i in range(4))
    return dy.System("lorenz84", (x, y, z), (-y * y - z * z - a * x + a * F, x * y - b * x * z - y + G,
                                             b * x * y + x * z - z), dict(L84))


def lorenz84_rhs(_t, u):
    x, y, z = u[:3]
    a, b, F, G = L84.values()
    return [-y * y - z * z - a * x + a * F, x * y - b * x * z - y + G, b * x * y + x * z - z, 2 * x - 2 - a]


def test_lorenz84_sum_equals_the_divergence_of_the_same_run_and_scipy_agrees_on_it():
    """Over 20 time units scipy (rtol 1e-12) follows the same trajectory: the stored mean divergence is its
    quadrature of 2 x - 2 - a; the sum of the exponents equals it to QR and integration error (the old separately
    stepped divergence run missed it by 2e-2 at t_end 1000)."""
    system = lorenz84()
    short = dy.lyapunov_spectrum(system, [1.0, 1.0, 1.0], t_end=20.0, dt=0.5)
    ref = solve_ivp(lorenz84_rhs, (0.0, 20.0), [1.0, 1.0, 1.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-12)
    assert float(short.divergence_mean) == pytest.approx(ref.y[3, -1] / 20.0, rel=1e-8)
    assert float(short.exponent_sum) == pytest.approx(float(short.divergence_mean), rel=1e-8)
    long = dy.lyapunov_spectrum(system, [1.0, 1.0, 1.0], t_end=1000.0, dt=1.0, transient=10.0)
    assert float(long.exponent_sum) == pytest.approx(float(long.divergence_mean), rel=1e-8)
    assert abs(float(long.divergence_mean) + 0.22) < 0.05  # 2 <x> - 2.25 on the attractor, not a placeholder


def test_lorenz63_sum_is_the_constant_divergence_and_error_bars_cover_the_published_exponents():
    ds = dy.lyapunov_spectrum(dy.textbook_system("lorenz"), [1.0, 1.0, 1.0], t_end=1000.0, dt=0.5, transient=10.0)
    assert ds.attrs["status"] == "completed"
    assert float(ds.exponent_sum) == pytest.approx(L63_SUM, rel=1e-8)
    assert float(ds.divergence_mean) == pytest.approx(L63_SUM, rel=1e-12)
    error = ds.exponent_error.values
    assert np.all(error > 0) and np.all(error < 0.02) and ds.exponent_error.attrs["units"] == "1"
    assert "standard error" in ds.exponent_error.attrs["long_name"] and ds.attrs["n_blocks"] == 10
    assert np.all(np.abs(ds.exponents.values - [0.9056, 0.0, -14.5723]) <= 4 * error + 5e-5)  # published 4 digits
    blocks = ds.block_exponents.values  # 10 equal blocks of 99 time units: their mean is the estimate
    assert blocks.shape == (10, 3)
    np.testing.assert_allclose(blocks.mean(axis=0), ds.exponents.values, rtol=1e-10, atol=1e-12)
    assert error == pytest.approx(blocks.std(axis=0, ddof=1) / math.sqrt(10))


def test_a_run_too_short_for_its_blocks_or_its_error_bars_is_not_converged(tmp_path):
    system = dy.textbook_system("lorenz")
    few = dy.lyapunov_spectrum(system, [1.0, 1.0, 1.0], t_end=15.0, dt=1.0, transient=10.0)
    assert few.attrs["status"] == "not_converged" and few.sizes["block"] == 5
    assert "fewer than 10 blocks" in few.attrs["message"] and "give t_end >= 30" in few.attrs["message"]
    td.save(few, tmp_path / "few.nc")  # stored without a NaN
    wide = dy.lyapunov_spectrum(lorenz84(), [1.0, 1.0, 1.0], t_end=200.0, dt=1.0, transient=10.0)
    assert wide.attrs["status"] == "not_converged" and "lambda_1" in wide.attrs["message"]
    assert "give t_end >=" in wide.attrs["message"] and len(wide.attrs["message"].splitlines()) == 1
    one = dy.lyapunov_spectrum(system, [1.0, 1.0, 1.0], t_end=1.0, dt=1.0)
    assert one.attrs["status"] == "not_converged" and "exponent_error" not in one and one.attrs["n_blocks"] == 0
    td.save(one, tmp_path / "one.nc")


def test_long_lorenz84_run_converges_with_the_largest_exponent_settled():
    ds = dy.lyapunov_spectrum(lorenz84(), [1.0, 1.0, 1.0], t_end=10000.0, dt=1.0, transient=10.0)
    lam, error = ds.exponents.values, ds.exponent_error.values
    assert ds.attrs["status"] == "completed" and lam[0] > 10 * error[0] > 0
    assert abs(lam[1]) < 3 * error[1]  # the flow direction
    assert float(ds.exponent_sum) == pytest.approx(float(ds.divergence_mean), rel=1e-8)


def test_van_der_pol_cycle_has_a_largest_exponent_zero_within_its_error_bar():
    """The second exponent is the Floquet exponent log(8.59695e-4) / 6.6632868593231 (literature multiplier)."""
    ds = dy.lyapunov_spectrum(dy.textbook_system("vanderpol"), [2.0, 0.0], t_end=1000.0, dt=0.5, transient=50.0)
    lam, error = ds.exponents.values, ds.exponent_error.values
    assert ds.attrs["status"] == "completed" and np.all(error > 0)
    assert abs(lam[0]) <= error[0] < 0.01
    assert abs(lam[1] - math.log(8.59695e-4) / 6.6632868593231) <= error[1]
    assert float(ds.exponent_sum) == pytest.approx(float(ds.divergence_mean), rel=1e-8)


def test_the_liouville_check_catches_an_interval_too_long_for_the_contracting_vector():
    """Lorenz-63 contracts the third vector by exp(-14.57 dt): at dt = 2 its integration loses digits and the sum
    misses the divergence (not_verified); at dt = 3 R_33 underflows to 0 and the run says to shorten dt."""
    system = dy.textbook_system("lorenz")
    coarse = dy.lyapunov_spectrum(system, [1.0, 1.0, 1.0], t_end=1000.0, dt=2.0, transient=10.0)
    assert coarse.attrs["status"] == "not_verified" and "give a smaller dt" in coarse.attrs["message"]
    with pytest.raises(ParameterError, match="collapsed.*give a smaller dt"):
        dy.lyapunov_spectrum(system, [1.0, 1.0, 1.0], t_end=100.0, dt=3.0)
    collapsed = lyapunov.spectrum(system, [1.0, 1.0, 1.0], t_end=100.0, dt=1.5)
    assert collapsed.status in ("completed", "not_verified", "failed")  # whatever happens, no -inf is stored
    assert np.all(np.isfinite(collapsed.exponents))


def test_the_dataset_states_the_parameters_of_the_run():
    ab = dy.textbook_system("ab")
    ds = dy.lyapunov_spectrum(ab, [0.7, 2.7], ab.with_pars(D=0.12), t_end=50.0)
    assert "D = 0.12;" in ds.attrs["system_parameters"]


def test_bad_block_requests_are_one_line_errors():
    system = dy.textbook_system("lorenz")
    with pytest.raises(ParameterError, match="n_blocks"):
        dy.lyapunov_spectrum(system, [1.0, 1.0, 1.0], n_blocks=1)
    with pytest.raises(ParameterError, match="rtol"):
        dy.lyapunov_spectrum(system, [1.0, 1.0, 1.0], rtol=0.0)
    with pytest.raises(ParameterError, match="zeros"):
        dy.lyapunov_spectrum(system, [1.0, 1.0, 1.0], zeros=4)
