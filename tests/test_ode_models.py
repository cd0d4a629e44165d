"""ODE Models 1 and 2 (Sect. 4.1): invariants, cross-checks, and the paper's Fig. 13."""

import math

import heyoka as hy
import numpy as np
import pytest

import tippedisk_analysis as td
from tippedisk_analysis import kinematics as kin
from tippedisk_analysis.models import ode
from tippedisk_analysis.models.lagrange import LagrangeModel
from tippedisk_analysis.defaults import TAYLOR_TOL
from tippedisk_analysis.solvers import taylor

SETUP = td.Setup()
DISK = SETUP.disk


def test_energy_balance(table3_euler, table3_quaternion):
    """E_tot(t) - E_tot(0) equals the work done by friction."""
    for ds in (table3_euler, table3_quaternion):
        balance = ds.E_tot - ds.E_tot[0] - ds.W_friction
        assert float(abs(balance).max()) < 1e-9
        assert float(ds.W_friction[-1]) < -0.02  # friction really dissipates (about 0.03 J in 5 s)
        assert float(ds.P_friction.max()) <= 0.0


def test_contact_constraint_holds(table3_euler, table3_quaternion):
    for ds in (table3_euler, table3_quaternion):
        assert float(abs(ds.g_N1).max()) <= 1e-12
        assert float(abs(ds.gamma_N1).max()) <= 1e-12
        assert float(ds.lambda_N.min()) > 0  # the contact stays closed: bilateral model valid


def test_quaternion_norm_is_kept(table3_quaternion):
    assert float(abs(table3_quaternion.quaternion_norm_error).max()) < 1e-12


def test_euler_and_quaternion_models_agree(table3_euler, table3_quaternion):
    np.testing.assert_array_equal(table3_euler.time, table3_quaternion.time)
    assert float(abs(table3_euler.gamma - table3_quaternion.gamma).max()) < 1e-8
    assert float(abs(table3_euler.beta - table3_quaternion.beta).max()) < 1e-8
    assert float(abs(table3_euler.z_S - table3_quaternion.z_S).max()) < 1e-10


def test_fig13_inversion(table3_euler):
    """Sect. 6.4 / Fig. 13: gamma rises from -pi/2 + 0.1 to oscillate about +pi/2, z_S from r - e to r + e."""
    ds = table3_euler
    r, e = DISK.r, DISK.e
    gamma = ds.gamma
    t_inverted = float(ds.time[np.argmax(gamma.values > 0)])  # first crossing of gamma = 0
    assert 0.2 < t_inverted < 0.5
    assert float(gamma.sel(time=slice(2, 5)).mean()) == pytest.approx(math.pi / 2, abs=0.05)
    assert float(abs(gamma.sel(time=slice(3, 5)) - math.pi / 2).max()) < 0.2
    assert float(abs(ds.beta - math.pi / 2).max()) < 0.35  # beta "does only change slightly"
    assert float(ds.z_S[0]) == pytest.approx(r - e * math.cos(0.1), abs=1e-12)
    assert float(ds.z_S.sel(time=slice(4, 5)).mean()) == pytest.approx(r + e, abs=1e-4)
    # energy: 0.380 J at the start (spin about the vertical through C1), about 0.36 J after inversion
    init = td.InitialState()
    omega = kin.omega_from_euler_rates(init.beta, init.gamma, init.euler_rates)
    E0 = 0.5 * omega @ np.diag([DISK.A, DISK.B, DISK.C]) @ omega + DISK.m * SETUP.gravity * float(ds.z_S[0])
    assert float(ds.E_tot[0]) == pytest.approx(E0, rel=1e-12)
    assert E0 == pytest.approx(0.380, abs=0.001)
    assert float(ds.E_tot.sel(time=0.6, method="nearest")) == pytest.approx(0.36, abs=0.005)
    assert float(ds.E_tot.diff("time").max()) <= 1e-12  # never gains energy


def _random_manifold_states(n, seed=3):
    """States on the constraint manifold (g_N1 = gamma_N1 = 0), Euler-model layout."""
    rng = np.random.default_rng(seed)
    states = []
    for _ in range(n):
        alpha, gamma = rng.uniform(-math.pi, math.pi, 2)
        beta = rng.uniform(0.3, math.pi - 0.3)
        omega = rng.normal(scale=20.0, size=3)
        beta_dot = omega[0] * math.cos(gamma) - omega[1] * math.sin(gamma)
        v_G = [*rng.normal(scale=0.3, size=2), DISK.r * math.cos(beta) * beta_dot]
        states.append([*rng.normal(scale=0.01, size=2), DISK.r * math.sin(beta), alpha, beta, gamma, *v_G, *omega, 0.0])
    return np.array(states)


def test_rhs_matches_independent_lagrangian_model():
    """Newton-Euler about S (heyoka) against M q_dd - h = f_g + W_NT lambda_N, (3.11)/(4.10), in numpy."""
    variables, sys, _fall, outputs = ode.system(ode.EULER)
    rhs = hy.cfunc([f for _, f in sys] + [outputs[ode.OUTPUT_NAMES.index("lambda_N")]], variables)
    pars = ode.parameter_vector(SETUP, fall_angle=0.1, slip_smoothing=1e-12)
    reference = LagrangeModel(SETUP)
    states = _random_manifold_states(12)
    # one zero-slip state (Table 3 start): the heyoka law must stay finite there
    states = np.vstack([states, ode.initial_state_vector(ode.EULER, SETUP, td.InitialState())])
    values = rhs(states.T.copy(), pars=np.repeat(pars[: rhs.nparams, None], len(states), axis=1)).T
    assert np.all(np.isfinite(values))
    for state, value in zip(states, values):
        phi, omega = state[3:6], state[9:12]
        phi_dot = kin.euler_rates_from_omega(phi[1], phi[2], omega)
        q, q_dot = np.concatenate([state[:3], phi]), np.concatenate([state[6:9], phi_dot])
        q_dd, lambda_N = reference.accelerations(q, q_dot)
        np.testing.assert_allclose(value[:3], state[6:9], rtol=1e-14)  # r_dot = v_G
        np.testing.assert_allclose(value[3:6], phi_dot, rtol=1e-12, atol=1e-12)  # (3.8)
        np.testing.assert_allclose(value[6:9], q_dd[:3], rtol=1e-8, atol=1e-9)  # a_G
        h = 1e-6  # omega_dot = d/dt omega(beta, gamma, phi_dot) along (phi_dot, phi_dd)
        plus = kin.omega_from_euler_rates(phi[1] + h * phi_dot[1], phi[2] + h * phi_dot[2], phi_dot + h * q_dd[3:])
        minus = kin.omega_from_euler_rates(phi[1] - h * phi_dot[1], phi[2] - h * phi_dot[2], phi_dot - h * q_dd[3:])
        np.testing.assert_allclose(value[9:12], (plus - minus) / (2 * h), rtol=1e-6, atol=1e-5)
        assert value[13] == pytest.approx(lambda_N, rel=1e-9)


def test_zero_slip_start_does_not_stall(table3_euler):
    """Table 3 starts at zero slip: no NaN, and the step count stays that of a smooth run."""
    assert float(abs(table3_euler.slip_x[0])) < 1e-15
    assert table3_euler.attrs["status"] == "completed"
    assert table3_euler.attrs["n_steps"] < 5000  # about 600 steps for 5 s


def test_stationary_spin_stays_stationary():
    """Upright spin with S straight below G and no slip is an exact (relative) equilibrium."""
    init = td.InitialState(gamma=-math.pi / 2, alpha_dot=30.0)
    ds = td.simulate("ode-euler", 0.5, initial=init, dt_output=0.05)
    assert float(abs(ds.gamma + math.pi / 2).max()) < 1e-12
    assert float(abs(ds.beta - math.pi / 2).max()) < 1e-12
    np.testing.assert_allclose(ds.alpha, 30.0 * ds.time, rtol=1e-13, atol=1e-13)


@pytest.mark.parametrize("model", ["ode-euler", "ode-quaternion"])
def test_slow_spin_falls_with_status(model):
    """A slowly spun disk falls over: the run ends at the fall angle with status 'fell', never with NaN."""
    init = td.InitialState(gamma=-math.pi / 2 + 0.1, alpha_dot=3.0, beta=math.pi / 2 - 0.2)
    ds = td.simulate(model, 10.0, initial=init, dt_output=0.01, fall_angle=0.15)
    assert ds.attrs["status"] == "fell"
    t_fell = ds.attrs["t_final"]
    assert 0 < t_fell < 10.0 and float(ds.time[-1]) == pytest.approx(t_fell)
    tilt = min(float(ds.beta[-1]), math.pi - float(ds.beta[-1]))
    assert tilt == pytest.approx(0.15, abs=1e-9)
    for name in ds.data_vars:
        assert np.all(np.isfinite(ds[name].values)), name


def test_compiled_integrator_is_reused():
    first = taylor.compiled("ode-euler", TAYLOR_TOL)
    assert taylor.compiled("ode-euler", TAYLOR_TOL) is first


def test_parameters_are_runtime_parameters():
    """Changing mu changes the run without recompiling; mu = 0 conserves energy."""
    setup = td.Setup(friction=td.Friction(mu=0.0))
    taylor.compiled("ode-euler", TAYLOR_TOL)
    before = taylor.compiled.cache_info().misses
    ds = td.simulate("ode-euler", 0.5, setup=setup, dt_output=0.01)
    assert taylor.compiled.cache_info().misses == before
    assert float(abs(ds.E_tot - ds.E_tot[0]).max()) < 1e-12


def test_nonfinite_state_ends_run_with_status(monkeypatch):
    """eps = 0 at zero slip makes 0/0 in (2.29): the run must end with a status, storing no NaN."""
    real = ode.parameter_vector

    def eps_zero(setup, fall_angle, slip_smoothing):
        values = real(setup, fall_angle, 0.0)
        values[ode.PARAMETER_NAMES.index("eps")] = 0.0
        return values

    monkeypatch.setattr(ode, "parameter_vector", eps_zero)
    ds = td.simulate("ode-euler", 1.0, dt_output=0.01)
    assert ds.attrs["status"] == "nonfinite"
    assert "non-finite" in ds.attrs["message"]
    for name in ds.data_vars:
        assert np.all(np.isfinite(ds[name].values)), name
