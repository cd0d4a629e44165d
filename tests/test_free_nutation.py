"""The free disk's averaged nutation flow (N1) (analysis.free_nutation): its model in Euler rates against the
slow flow in body rates, its small-amplitude limit against the closed form (C3), and its paths against runs of
the slow flow started on the family (the first-order averaging it claims)."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from tippedisk_analysis.analysis import critical_spin as cs
from tippedisk_analysis.analysis import free_nutation as fn
from tippedisk_analysis.analysis import inversion
from tippedisk_analysis.errors import ParameterError
from tippedisk_analysis.dynamics.melnikov import period_map
from tippedisk_analysis.dynamics.symmetric_families import Shooter
from tippedisk_analysis.models import reduced, slow_flow


def _run(system, state, pars, times):
    ta = copy.deepcopy(system.taylor(1e-13))
    ta.time, ta.state[:], ta.pars[:] = 0.0, state, pars[: len(ta.pars)]
    return ta.propagate_grid(np.asarray(times))[5]


def test_the_slow_flow_in_euler_rates_is_the_one_in_body_rates():
    euler, body = slow_flow.euler_system(), slow_flow.system()
    pars = euler.with_pars(None, eps=0.005)
    beta, gamma, spin, beta_d, gamma_d = state = np.array([1.5, 1.0, 31.0, 0.5, 0.8])
    W = [beta_d, spin * math.sin(beta), spin * math.cos(beta) + gamma_d]  # G-components of Omega
    omega = [math.cos(gamma) * W[0] + math.sin(gamma) * W[1], -math.sin(gamma) * W[0] + math.cos(gamma) * W[1], W[2]]
    times = np.linspace(0.0, 2.0, 5)
    x = _run(euler, state, pars, times)
    y = _run(body, np.array([beta, gamma, *omega]), pars, times)
    assert np.allclose(x[:, :2], y[:, :2], atol=1e-10)
    assert np.allclose(x[:, 2], body.observe(y.T, pars)["alpha_dot"], atol=1e-9)
    assert abs(x[-1, 2] - spin) > 0.5  # the spin is free: it moved
    energy = euler.observe(x.T, pars)["E_tot"] - body.observe(y.T, pars)["E_tot"]
    assert np.abs(energy).max() < 1e-12


@pytest.mark.parametrize("spin", [29.5, 31.0])
def test_small_nutations_drift_at_the_closed_form_rate_and_the_spin_only_at_second_order(spin):
    small, double = fn.rates(0.01, spin), fn.rates(0.02, spin)
    assert small["valid"] and double["valid"]
    assert small["amplitude_rate"] / 0.01 == pytest.approx(cs.rates(spin)["rate_nutation"], rel=5e-3)
    assert double["spin_rate"] / small["spin_rate"] == pytest.approx(4.0, rel=2e-2)  # G = O(a^2): spins rest


@pytest.mark.slow
def test_the_averaged_path_follows_the_slow_flow_started_on_the_family():
    """From the member a = 1.2 rad, Omega0 = 32 rad/s: runs of the free slow flow at eps 0.004 and 0.002 m/s
    pass their turning points where (N1) puts them at the same slow time, with errors of first order in eps
    (measured: 1.7e-4 and 8.1e-5 rad, 3.6e-4 and 1.5e-4 rad/s; 4.0e-5 rad at eps 0.001)."""
    path = fn.averaged_path(1.2, 32.0, 0.1, samples=401)
    assert path.attrs["status"] == "completed"
    start = fn.rates(1.2, 32.0)
    errors = []
    for eps in (0.004, 0.002):
        system = slow_flow.euler_system()
        times = np.arange(0.0, 0.1 / eps, 0.001)
        x = _run(system, [0.5 * math.pi, 0.5 * math.pi - 1.2, 32.0, start["beta_dot"], 0.0],
                 system.with_pars(None, eps=eps), times)
        turns = fn.turning_points(times, x[:, 1], x[:, 2])
        a = np.interp(turns["time"] * eps, path.slow_time, path.amplitude)
        spin = np.interp(turns["time"] * eps, path.slow_time, path.spin)
        errors.append((np.abs(turns["amplitude"] - a).max(), np.abs(turns["spin"] - spin).max()))
    assert path.amplitude.values[-1] < 1.05  # it moved: 1.2 -> 1.00 rad
    assert errors[0][0] < 5e-4 and errors[0][1] < 1e-3
    for first, second in zip(*errors):  # halving eps halves the error: (N1) is the first-order average
        assert 0.3 < second / first < 0.7


@pytest.mark.slow
def test_members_come_from_the_first_branch_and_none_past_its_fold():
    """At 32.2 rad/s the family's first branch folds at a = 2.1053 rad (traced at 32.25 rad/s); at a = 2.2 rad
    another branch has members (beta_dot 2.24 and 2.95 rad/s), which a guess alone could land on. Members are
    resolved up to FOLD_MARGIN below the fold; on the amplitude's nullcline F = 0 (30.7 rad/s, a = 1.05 and
    1.15 rad) the drift is checked against the rates' typical size, not F itself."""
    a, _beta_dot = fn.first_branch(32.25)
    assert a[-1] == pytest.approx(2.105, abs=2e-3)
    with pytest.raises(fn.NoMember, match="folds"):
        fn.rates(2.2, 32.2)
    with pytest.raises(fn.NoMember, match="folds"):
        fn.rates(2.104, 32.13)
    assert fn.rates(2.0, 32.2)["valid"]
    assert fn.rates(1.05, 30.7)["valid"] and fn.rates(1.15, 30.7)["valid"]


def test_an_averaged_path_that_settles_keeps_what_it_computed():
    """Above omega_c a small nutation decays onto the inverted spins (a = 0, a line of equilibria of (N1)), where
    the drift's checks end: the path says so and keeps its samples."""
    path = fn.averaged_path(0.05, 32.0, 4.0)
    assert path.attrs["status"] == "settled"
    assert path.sizes["slow_time"] > 2 and np.all(np.diff(path.amplitude.values) < 0)
    assert path.amplitude.values[-1] < 0.03 and abs(path.spin.values[-1] - 32.0) < 0.01


def test_bad_requests_are_refused_in_one_line():
    with pytest.raises(ParameterError, match="amplitude"):
        fn.rates(3.5, 30.0)
    with pytest.raises(ParameterError, match="spin"):
        fn.rates(1.0, -30.0)
    with pytest.raises(fn.NoMember, match="centre"):
        fn.rates(0.5, 5.0)
    with pytest.raises(ParameterError, match="spins"):
        fn.field([0.1, 0.2], [31.0])
    with pytest.raises(ParameterError, match="setup"):
        fn.field([0.1, 0.2], [31.0, 31.1], setup=3)
    with pytest.raises(ParameterError, match="slow_time"):
        fn.averaged_path(1.0, 31.0, 0.0)
    with pytest.raises(ParameterError, match="samples"):
        fn.averaged_path(1.0, 31.0, 0.01, samples=2.5)
    with pytest.raises(fn.NoMember):
        fn.averaged_path(3.0, 31.0, 0.01)
    with pytest.raises(ParameterError, match="state"):
        fn.precession_amplitude([1.0, 2.0, 3.0], 1.0, 31.0)


@pytest.mark.parametrize("amplitude, spin", [(1.2, 32.0), (0.6, 31.0)])
def test_the_precession_rate_is_the_growth_along_the_drifting_run(amplitude, spin):
    """sigma (N2) against brute force: the product of the perturbed period map's derivatives at the run's own
    crossings over 10 revolutions at eps = 1e-3 m/s (measured: 3.8692 against 3.8858 and 3.2724 against
    3.2774 /m)."""
    system = slow_flow.euler_system()
    pars = system.with_pars(None, eps=1e-3)
    shooter = Shooter(system, fn.shooting(spin))
    found = fn.rates(amplitude, spin)
    x = fn.member_orbit(amplitude, spin, None)[0]  # the member's state at the top, on the section
    product, elapsed = np.eye(5), 0.0
    for _ in range(10):
        (x, time), derivative = period_map(shooter, x, pars, 0.875 * found["period"])
        product, elapsed = derivative @ product, elapsed + time
    w = np.linalg.eigvals(product)
    pair = w[np.argsort(-np.abs(w.imag))][:2]
    assert found["precession_valid"]
    assert math.log(abs(pair[0])) / (elapsed * 1e-3) == pytest.approx(found["precession_rate"], rel=1e-2)


def test_a_small_precession_grows_at_the_precession_rate():
    """A start on the member a = 0.2 rad, Omega0 = 29.5 rad/s with a precession of rho = 0.005 rad (eps 1e-3 m/s,
    where the labels hardly move): ln rho grows as sigma eps t (measured 0.2332 against 0.2324 over 0.1 m)."""
    amplitude, spin, eps = 0.2, 29.5, 1e-3
    top, _period, right, _left = fn.member_orbit(amplitude, spin, None)
    system = slow_flow.euler_system()
    times = np.arange(0.0, 0.1 / eps, 0.0005)
    x = _run(system, top + 0.005 * right.real / abs(right[0]), system.with_pars(None, eps=eps), times)
    rows = fn.precession_along(times, x)
    crossed, rho = rows[:, 0], rows[:, 1]
    growth = math.log(np.median(rho[-7:]) / np.median(rho[:7]))
    sigma = np.mean([fn.rates(amplitude, spin)["precession_rate"], fn.rates(0.21, 29.48)["precession_rate"]])
    span = (crossed[-4] - crossed[3]) * eps
    assert rho[0] == pytest.approx(0.005, rel=0.05)
    assert growth == pytest.approx(sigma * span, rel=3e-2)


@pytest.mark.slow
def test_the_full_models_precession_grows_at_the_precession_rate():
    """ODE Model 1 from Table 3 at 33.7 rad/s, eps 0.01 m/s: from eps t = 0.05 to 0.3 m its precession about the
    family grows at sigma (N2) along its own labels, to 25 %: ln rho grows by 1.008 against 0.862 (1.105 against
    0.937 at eps 0.002; rho, the precession's extent in beta, also grows 10 % faster than sigma in the slow flow
    from a member, where the linearisation along the run grows at sigma to 0.6 %)."""
    eps = 0.01
    setup = inversion.with_eps(None, eps)
    model, pars = reduced.system(), inversion.parameters("smooth", setup)
    times = np.arange(0.0, 0.3 / eps, 0.0005)
    x = fn.euler_states(_run(model, inversion.start_state("smooth", 33.7, setup, -0.5 * math.pi + 0.1), pars,
                             times))
    rows = fn.precession_along(times, x)
    rows = rows[rows[:, 0] * eps > 0.05]  # one per revolution (about 1 s): time, rho, a, Omega0
    sigma = np.array([fn.rates(a, spin)["precession_rate"] for _t, _rho, a, spin in rows])
    predicted = np.trapezoid(sigma[1:-1], rows[1:-1, 0] * eps)
    measured = math.log(np.median(rows[-3:, 1]) / np.median(rows[:3, 1]))
    assert np.all(sigma > 3.0)
    assert measured == pytest.approx(predicted, rel=0.25)
