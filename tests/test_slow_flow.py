"""The slow flow of the smooth model (models/slow_flow.py) against the smooth model itself (ODE Model 1,
symmetry-reduced: models/reduced.py): every claim of the reduction is a convergence study in eps, the
error falling by 4 when eps halves (second order), not a single number."""

import copy

import numpy as np
import pytest

from tippedisk_analysis.analysis import rolling as rolling_analysis
from tippedisk_analysis.analysis import stationary
from tippedisk_analysis.models import reduced, rolling, slow_flow

EPS = (2e-3, 1e-3, 5e-4)  # m/s: small enough for the asymptotic ratio, the fast modes still cheap
WOBBLE = np.array([0.1, 0.0, 0.0, 2.0, 0.0])  # a tilt and a rate off the inverted spin, inside the cone


def assert_second_order(errors, low=3.6, high=4.4):
    errors = np.asarray(errors)
    ratios = errors[:-1] / errors[1:]
    assert np.all((ratios > low) & (ratios < high)), f"errors {errors} fall by {ratios}, not by 4 per halving"


def run(system, state, eps, times, extra=()):
    """States of ``system`` at ``times`` (rows) from ``state``, Taylor tolerance 1e-14."""
    pars = system.with_pars(eps=eps)
    ta = copy.deepcopy(system.taylor(1e-14, extra=extra))
    ta.state[:] = np.concatenate([state, np.zeros(len(extra))])
    ta.pars[:] = pars[: len(ta.pars)]
    return ta.propagate_grid(times)[-1]


def wobble_start():
    return rolling_analysis.spin_state("inverted", 40.0) + WOBBLE


def test_the_slow_flow_at_eps_zero_is_rolling_and_its_spins_are_rolling_spins():
    slow, roll = slow_flow.system(), rolling.reduced_system()
    rng = np.random.default_rng(3)
    states = wobble_start()[:, None] + rng.normal(scale=[0.05, 0.3, 1.0, 1.0, 1.0], size=(200, 5)).T
    p_roll = roll.pars
    p_slow = slow.with_pars(eps=0.0, **{k: v for k, v in zip(roll.parameter_names, p_roll) if k != "fall_angle"})
    np.testing.assert_allclose(slow.f(states, p_slow), roll.f(states, p_roll), rtol=1e-12, atol=1e-10)
    for branch in ("inverted", "noninverted"):  # lambda_T = 0 there: no slip, an equilibrium for every eps
        x = rolling_analysis.spin_state(branch, 40.0)
        assert np.abs(slow.f(x, slow.with_pars(eps=0.1))).max() < 1e-11
        assert slow.observe(x)["slip"] < 1e-12


@pytest.mark.parametrize(("branch", "omega"), [("inverted", 40.0), ("noninverted", 40.0), ("inverted", 20.0)])
def test_slow_eigenvalues_are_the_smooth_models_to_second_order(branch, omega):
    """The smooth model's five slow eigenvalues at a spin (docs/rolling.md) against the slow flow's: the
    difference falls as eps^2 (real parts are O(eps) themselves, so first order would not do)."""
    slow, smooth = slow_flow.system(), reduced.system()
    x_slow, x_smooth = rolling_analysis.spin_state(branch, omega), stationary.stationary_state(branch, omega)
    errors = []
    for eps in EPS:
        ev_slow = np.linalg.eigvals(slow.jacobian(x_slow, slow.with_pars(eps=eps)).reshape(5, 5))
        ev_smooth = np.linalg.eigvals(smooth.jacobian(x_smooth, smooth.with_pars(eps=eps)).reshape(7, 7))
        fast = np.sort(ev_smooth.real)[:2]
        assert np.all(fast * eps < -5.0), f"the slip modes {fast} are not fast (-9.15/eps, -15.8/eps inverted)"
        ev_smooth = ev_smooth[np.argsort(np.abs(ev_smooth))][:5]
        errors.append(max(np.abs(ev_smooth - z).min() for z in ev_slow))
        assert np.abs(ev_slow.real).max() > 2 * errors[-1], "the eps-dependent real parts are not resolved"
    assert_second_order(errors)


def test_full_runs_reach_the_manifold_on_the_fast_time_scale_and_stay_within_eps_squared():
    """A smooth-model run started with no slip (the rolling velocity: O(eps) off the manifold) comes to the
    manifold on the fast time scale (its distance at t = k eps is the same fraction of the start's for every
    eps), then stays within O(eps^2) of it; so does a run started on it."""
    slow, smooth = slow_flow.system(), reduced.system()
    x0 = wobble_start()
    floors, decay = [], []
    for eps in EPS:
        times = np.linspace(0.0, 1.0, 20001)
        on = run(smooth, slow_flow.smooth_state(x0, slow.with_pars(eps=eps)), eps, times)
        off = run(smooth, slow_flow.smooth_state(x0, slow.with_pars(eps=0.0)), eps, times)
        pars = slow.with_pars(eps=eps)
        d_on = slow_flow.manifold_distance(on.T.copy(), pars)
        d_off = slow_flow.manifold_distance(off.T.copy(), pars)
        assert d_off[0] > 10 * d_on.max(), "the no-slip start is not O(eps) off the manifold"
        floors.append(d_on.max())
        arrived = np.nonzero(d_off <= 2 * d_on.max())[0]
        assert arrived.size, f"eps = {eps}: the run never came within 2 x {d_on.max():.3g} m/s of the manifold"
        assert np.all(d_off[arrived[0]:] <= 3 * d_on.max()), "the run left the manifold again"
        decay.append(np.interp([eps, 2 * eps, 4 * eps], times, d_off) / d_off[0])
    assert_second_order(floors)
    decay = np.array(decay)  # rows eps, columns t = eps, 2 eps, 4 eps
    assert np.all(decay[:, 1] < 0.5), f"not halved within 2 eps seconds: {decay}"
    assert np.ptp(decay[:, :2], axis=0).max() < 0.1, f"the decay does not scale with eps: {decay}"


def test_trajectories_and_energy_loss_agree_with_the_smooth_model_to_second_order():
    """From a point of the manifold, over 2 s (~13 turns of the wobble): the slow flow and the smooth model
    differ by O(eps^2) in the state and in the energy lost (itself O(eps); measured: O(eps^3), the
    O(eps^2) differences of the friction power average out over the wobble); the slow flow's own energy
    balance E + W_friction (W' = lambda_T . s, (S4)) holds to O(eps^2), as a first-order reduction does."""
    import heyoka as hy

    slow, smooth = slow_flow.system(), reduced.system()
    x0 = wobble_start()
    times = np.linspace(0.0, 2.0, 201)
    work = hy.make_vars("work")
    state_errors, loss_errors, balance_errors = [], [], []
    for eps in EPS:
        p_slow, p_smooth = slow.with_pars(eps=eps), smooth.with_pars(eps=eps)
        xs = run(slow, x0, eps, times, extra=[(work, slow.observables["friction_power"][0])])
        xf = run(smooth, slow_flow.smooth_state(x0, p_slow), eps, times)
        state_errors.append(np.abs((xf[:, [0, 1, 4, 5, 6]] - xs[:, :5]) / slow.state_scale).max())
        E_slow = slow.observe(xs[:, :5].T.copy(), p_slow)["E_tot"]
        E_smooth = smooth.observe(xf.T.copy(), p_smooth)["E_tot"]
        loss_slow, loss_smooth = E_slow[0] - E_slow[-1], E_smooth[0] - E_smooth[-1]
        assert loss_slow > 0 and loss_smooth > 0
        loss_errors.append(abs(loss_slow - loss_smooth))
        balance_errors.append(np.abs(E_slow - xs[:, 5] - E_slow[0]).max())
        assert loss_errors[-1] < 0.05 * loss_smooth and balance_errors[-1] < 0.05 * loss_smooth
        assert slow.observe(xs[:, :5].T.copy(), p_slow)["cone_margin"].min() > 0.3  # inside the cone throughout
    assert_second_order(state_errors, 3.4, 4.4)
    assert_second_order(loss_errors, 3.4, 9.0)
    assert_second_order(balance_errors, 3.4, 4.6)
