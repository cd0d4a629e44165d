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


@pytest.fixture(scope="module")
def lagrangian_run():
    """The independent Lagrangian model (4.10) integrated by scipy's DOP853 over 1 s of the Table 3 run
    (rtol = atol = 1e-12), with z integrated as a coordinate: its state (x, y, z, alpha, beta, gamma) and rates."""
    from scipy.integrate import solve_ivp

    init = td.InitialState()
    rest = kin.rest_contact_state(DISK.r, init.euler, init.euler_rates)
    y0 = np.concatenate([[init.x, init.y, rest["z"]], init.euler, rest["v_G"], init.euler_rates])
    grid = np.linspace(0.0, 1.0, 101)
    sol = solve_ivp(LagrangeModel(SETUP).rhs, (0.0, 1.0), y0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=grid)
    assert sol.success
    return dict(zip(("x", "y", "z", "alpha", "beta", "gamma"), sol.y[:6]))


@pytest.mark.parametrize("model", ["ode-euler", "ode-quaternion"])
def test_trajectory_matches_the_independent_lagrangian_model(lagrangian_run, model):
    """Both ODE models (z = r sin(beta) built in) follow the Lagrangian model (z a coordinate, the contact
    kept on acceleration level) along the first second of Table 3 to the integrators' accuracy."""
    ds = td.simulate(model, 1.0, dt_output=0.01)
    for name in ("alpha", "beta", "gamma"):
        assert np.max(np.abs(ds[name].values - lagrangian_run[name])) < 3e-11, name
    for name in ("x", "y", "z"):
        assert np.max(np.abs(ds[name].values - lagrangian_run[name])) < 1e-12, name


@pytest.mark.slow
@pytest.mark.parametrize("model", ["ode-euler", "ode-quaternion"])
def test_contact_and_energy_balance_hold_for_2000_s(model):
    """The contact is built into the coordinates, so it cannot drift: over 2000 s of the Table 3 run (about
    370,000 Taylor steps of ODE Model 1) the stored height of G stays r sin(beta) of the stored angle and the
    normal velocity at C1 zero to round-off, while friction dissipates most of the energy."""
    ds = td.simulate(model, 2000.0, dt_output=1.0)
    assert ds.attrs["status"] == "completed"
    assert float(np.max(np.abs(ds.z - DISK.r * np.sin(ds.beta)))) <= 1e-12  # g_N1 (2.12) from the stored values
    assert float(np.max(np.abs(ds.gamma_N1))) <= 1e-12
    # heyoka controls the error relative to the largest state, here alpha (80,000 rad after 2000 s of ODE Model
    # 1): the balance holds to 5e-9 J there (7e-13 J for the quaternion model, whose state stays of order 1)
    assert float(np.max(np.abs(ds.E_tot - ds.E_tot[0] - ds.W_friction))) <= 2e-8
    assert float(ds.W_friction[-1]) < -0.3  # 0.38 J -> 0.04 J: a long run that really moves
    if "quaternion_norm_error" in ds:
        assert float(np.max(np.abs(ds.quaternion_norm_error))) <= 1e-12


def test_quaternion_norm_is_kept(table3_quaternion):
    assert float(abs(table3_quaternion.quaternion_norm_error).max()) < 1e-12


def test_euler_and_quaternion_models_agree(table3_euler, table3_quaternion):
    """Both models share ``contact_dynamics``: this checks the orientation kinematics (3.8) vs (3.44)
    along a run; the dynamics of each is checked against the Lagrangian model below."""
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


def _manifold_states(n, seed=3):
    """States (r_OG, euler, v_G, omega) on the constraint manifold (g_N1 = gamma_N1 = 0), and their slips.

    n random states (beta in [0.3, pi - 0.3], slip of order 0.3 m/s), then states the random
    draw misses: large tilt (beta = 0.12 and pi - 0.12, just above the fall angle 0.1) and
    near-zero slip (1e-9 and 1e-6 m/s, far below eps = 0.1 m/s, where (2.29) is linear and
    heyoka's |gamma_T| carries the slip_smoothing delta = 1e-12), and the Table 3 start (zero slip).
    """
    rng = np.random.default_rng(seed)
    cases = [(rng.uniform(0.3, math.pi - 0.3), rng.normal(scale=0.3, size=2)) for _ in range(n)]
    cases += [(0.12, rng.normal(scale=0.3, size=2)), (math.pi - 0.12, rng.normal(scale=0.3, size=2))]
    cases += [(rng.uniform(0.3, math.pi - 0.3), s * np.array([0.6, -0.8])) for s in (1e-9, 1e-6)]
    cases += [(0.12, 1e-9 * np.array([-0.6, 0.8]))]
    states, slips = [], []
    for beta, slip in cases:
        alpha, gamma = rng.uniform(-math.pi, math.pi, 2)
        omega = rng.normal(scale=20.0, size=3)
        R = kin.rotation_from_euler(alpha, beta, gamma)
        r_GC1 = kin.contact_point_offsets(R, DISK.r)[0]
        v_G = -np.cross(R @ omega, r_GC1) + [*slip, 0.0]  # v_C1 = (slip, 0): closed, gamma_N1 = 0
        r_OG = np.array([*rng.normal(scale=0.01, size=2), DISK.r * math.sin(beta)])
        states.append((r_OG, np.array([alpha, beta, gamma]), v_G, omega))
        slips.append(slip)
    init = td.InitialState()
    rest = kin.rest_contact_state(DISK.r, init.euler, init.euler_rates)
    states.append((np.array([0.0, 0.0, rest["z"]]), init.euler, rest["v_G"], rest["omega"]))
    slips.append(np.zeros(2))
    return states, np.array(slips)


OUTPUTS = ("lambda_N", "slip_x", "slip_y", "z", "z_dot")


def _ode_rhs(model):
    """Compiled right-hand side and the OUTPUTS of ``model`` at a batch of states: a dict of columns."""
    variables, sys, _fall, outputs = ode.system(model)
    names = [f for _, f in sys] + [outputs[ode.OUTPUT_NAMES.index(k)] for k in OUTPUTS]
    cf = hy.cfunc(names, variables)
    pars = ode.parameter_vector(SETUP)
    keys = [f"d_{name}" for name in model.state_names] + list(OUTPUTS)

    def evaluate(states):
        values = cf(np.ascontiguousarray(np.array(states).T), pars=np.repeat(pars[: cf.nparams, None], len(states), 1))
        return [dict(zip(keys, column)) for column in values.T]

    return evaluate


def _lagrange_reference(r_OG, euler, v_G, omega):
    """(q_dd, lambda_N, phi_dot) of the independent Lagrangian model (4.10) at one state."""
    phi_dot = kin.euler_rates_from_omega(euler[1], euler[2], omega)
    q_dd, lambda_N = LagrangeModel(SETUP).accelerations(np.concatenate([r_OG, euler]),
                                                          np.concatenate([v_G, phi_dot]))
    return q_dd, lambda_N, phi_dot


def _column(values, *names):
    return np.array([values[name] for name in names])


def _check_position_and_translation(value, r_OG, v_G, q_dd, scale=1.0):
    """The contact fixes z and z_dot (outputs); x, y move with v_G and accelerate as the Lagrangian model."""
    assert value["z"] == pytest.approx(r_OG[2], rel=1e-14)  # z = r sin(beta) (2.12)
    assert value["z_dot"] == pytest.approx(v_G[2], rel=1e-12, abs=1e-15)  # gamma_N1 = 0
    np.testing.assert_allclose(_column(value, "d_x", "d_y"), v_G[:2], rtol=1e-14)
    np.testing.assert_allclose(_column(value, "d_x_dot", "d_y_dot"), q_dd[:2], rtol=1e-8, atol=1e-9 * scale)


def test_rhs_matches_independent_lagrangian_model():
    """ODE Model 1: Newton-Euler about S (heyoka) against M q_dd - h = f_g + W_NT lambda_N, (3.11)/(4.10), in numpy."""
    states, slips = _manifold_states(12)
    rows = [[*r[:2], *phi, *v[:2], *w, 0.0] for r, phi, v, w in states]
    values = _ode_rhs(ode.EULER)(rows)
    assert all(np.all(np.isfinite(list(v.values()))) for v in values)
    np.testing.assert_allclose([_column(v, "slip_x", "slip_y") for v in values], slips, rtol=1e-6, atol=1e-15)
    for (r_OG, phi, v_G, omega), value in zip(states, values):
        q_dd, lambda_N, phi_dot = _lagrange_reference(r_OG, phi, v_G, omega)
        _check_position_and_translation(value, r_OG, v_G, q_dd)
        np.testing.assert_allclose(_column(value, "d_alpha", "d_beta", "d_gamma"), phi_dot, rtol=1e-12,
                                   atol=1e-12)  # (3.8)
        h = 1e-6  # omega_dot = d/dt omega(beta, gamma, phi_dot) along (phi_dot, phi_dd)
        plus = kin.omega_from_euler_rates(phi[1] + h * phi_dot[1], phi[2] + h * phi_dot[2], phi_dot + h * q_dd[3:])
        minus = kin.omega_from_euler_rates(phi[1] - h * phi_dot[1], phi[2] - h * phi_dot[2], phi_dot - h * q_dd[3:])
        np.testing.assert_allclose(_column(value, "d_omega_x", "d_omega_y", "d_omega_z"), (plus - minus) / (2 * h),
                                   rtol=1e-6, atol=1e-5)
        assert value["lambda_N"] == pytest.approx(lambda_N, rel=1e-9)


def _skew(a):
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def test_quaternion_rhs_matches_independent_lagrangian_model():
    """ODE Model 2 against the Lagrangian Model 1 mapped through the kinematics (no shared contact code).

    The two ODE models share ``contact_dynamics``, so their agreement along a run only tests the
    orientation kinematics; here Model 2's accelerations meet the independent derivation
    (models/lagrange.py): a_G = q_dd[:3], Psi = J_R phi_dd + J_R_dot phi_dot (3.3) differentiated,
    lambda_N equal, and p_dot (3.44) moves R(p) as R Omega~ (Poisson's equation).
    """
    states, slips = _manifold_states(12, seed=5)
    rows = [[*r[:2], *kin.quaternion_from_rotation(kin.rotation_from_euler(*phi)), *v[:2], *w, 0.0]
            for r, phi, v, w in states]
    values = _ode_rhs(ode.QUATERNION)(rows)
    assert all(np.all(np.isfinite(list(v.values()))) for v in values)
    np.testing.assert_allclose([_column(v, "slip_x", "slip_y") for v in values], slips, rtol=1e-6, atol=1e-15)
    for (r_OG, phi, v_G, omega), row, value in zip(states, rows, values):
        q_dd, lambda_N, phi_dot = _lagrange_reference(r_OG, phi, v_G, omega)
        scale = 1.0 + np.abs(q_dd).max()
        _check_position_and_translation(value, r_OG, v_G, q_dd, scale)
        J_R = np.array(kin.omega_entries_from_euler_rates(phi[1], phi[2], *np.eye(3)))  # (3.3) columns
        psi = J_R @ q_dd[3:] + np.array(kin.omega_derivative_entries_at_fixed_rates(phi[1], phi[2], *phi_dot))
        np.testing.assert_allclose(_column(value, "d_omega_x", "d_omega_y", "d_omega_z"), psi, rtol=1e-8,
                                   atol=1e-9 * scale)  # omega_dot
        assert value["lambda_N"] == pytest.approx(lambda_N, rel=1e-9)
        p, p_dot, h = np.array(row[2:6]), _column(value, "d_p0", "d_p1", "d_p2", "d_p3"), 1e-6
        R_dot = (kin.rotation_from_quaternion(p + h * p_dot) - kin.rotation_from_quaternion(p - h * p_dot)) / (2 * h)
        np.testing.assert_allclose(R_dot, kin.rotation_from_euler(*phi) @ _skew(omega), atol=1e-7 * (1 + abs(omega).max()))


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


@pytest.mark.parametrize("beta_dot, starts_negative", [(30.0, True), (14.0, False)])
def test_negative_normal_force_is_reported(beta_dot, starts_negative):
    """A fast tilting start (r beta_dot^2 comparable to g) needs lambda_N < 0 to keep the bilateral
    contact closed: the disk would lift off. The run keeps going (the ODE is defined) but says so:
    the message names the first time of lambda_N < 0, the attribute lambda_N_min is negative, and
    lambda_N agrees with the independent Lagrangian model at the start."""
    init = td.InitialState(beta_dot=beta_dot)
    ds = td.simulate("ode-euler", 0.2, initial=init, dt_output=1e-3)
    lam = ds.lambda_N.values
    first = int(np.argmax(lam < 0))
    assert lam[first] < 0 and np.all(lam[:first] >= 0)
    assert (first == 0) == starts_negative
    t_neg = float(ds.time[first])
    assert ds.attrs["status"] == "completed"
    assert ds.attrs["message"] == (f"reached t_end = 0.2 s; lambda_N < 0 from t = {t_neg:.6g} s: the disk would lift "
                                   "off, outside the bilateral model's validity (use a Moreau model)")
    assert ds.attrs["lambda_N_min"] == float(lam.min()) < 0
    rest = kin.rest_contact_state(DISK.r, init.euler, init.euler_rates)
    _q_dd, lambda_0, _ = _lagrange_reference(np.array([0.0, 0.0, rest["z"]]), init.euler, rest["v_G"], rest["omega"])
    assert float(ds.lambda_N[0]) == pytest.approx(lambda_0, rel=1e-9)
    assert (lambda_0 < 0) == starts_negative


def test_valid_run_reports_no_negative_normal_force(table3_euler):
    assert "lambda_N < 0" not in table3_euler.attrs["message"]
    assert table3_euler.attrs["lambda_N_min"] == float(table3_euler.lambda_N.min()) > 0
