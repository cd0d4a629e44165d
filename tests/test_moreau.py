"""Moreau time stepping (Sect. 4): kernels vs kinematics, impacts, convergence, drift, statuses."""

import dataclasses
import math

import numpy as np
import pytest
import xarray as xr

from tippedisk_analysis import kinematics as kin
from tippedisk_analysis import results, simulate
from tippedisk_analysis.errors import ParameterError
from tippedisk_analysis import defaults
from tippedisk_analysis.models import moreau_geometry as geo
from tippedisk_analysis.models import prox
from tippedisk_analysis.parameters import Friction, InitialState, Setup
from tippedisk_analysis.solvers import resolve
from tippedisk_analysis.solvers.moreau import dataset, driver, layout
from tippedisk_analysis.solvers.moreau.models import EULER, MODELS

RNG = np.random.default_rng(7)


# ------------------------------------------------------------ kernels vs kinematics.py


def test_kernels_match_kinematics():
    R = np.empty((3, 3))
    w = np.empty(3)
    back = np.empty(3)
    pd = np.empty(4)
    off = np.empty((3, 3))
    exg = np.zeros(3)
    for _ in range(20):
        alpha, gamma = RNG.uniform(-np.pi, np.pi, 2)
        beta = RNG.uniform(0.2, np.pi - 0.2)
        rates = RNG.normal(size=3) * 10
        geo.rotation_euler(alpha, beta, gamma, R)
        np.testing.assert_allclose(R, kin.rotation_from_euler(alpha, beta, gamma), atol=1e-15)
        p = kin.quaternion_from_rotation(R)
        Rq = np.empty((3, 3))
        geo.rotation_quaternion(*p, Rq)
        np.testing.assert_allclose(Rq, R, atol=1e-14)
        geo.omega_from_rates(beta, gamma, *rates, w)
        np.testing.assert_allclose(w, kin.omega_from_euler_rates(beta, gamma, rates), atol=1e-13)
        geo.rates_from_omega(beta, gamma, w, back)
        np.testing.assert_allclose(back, rates, atol=1e-11)
        geo.quaternion_rates(*p, *w, pd)
        np.testing.assert_allclose(pd, kin.quaternion_rate_entries(*p, *w), atol=1e-14)
        geo.floating_frame(R, exg)
        geo.contact_offsets(R, exg, 0.045, off)
        np.testing.assert_allclose(off, kin.contact_point_offsets(R, 0.045), atol=1e-15)


def test_contour_direction_is_regularised_only_near_a_flat_disk():
    """1/s^2 -> 1/(s^2 + s_reg^2) in (3.64): |c| stays below ~1/(2 s_reg) + 2 near flat, unchanged when upright."""
    s_reg = defaults.CONTOUR_REGULARISATION
    exact, regular, R = np.empty(3), np.empty(3), np.empty((3, 3))
    for beta in (1e-8, 1e-5, 1e-3, 1e-2, 0.1):
        geo.rotation_euler(0.3, beta, 0.7, R)
        geo.contour_direction(R, math.sin(beta), 0.0, exact)
        geo.contour_direction(R, math.sin(beta), s_reg, regular)
        assert np.linalg.norm(regular) <= 0.5 / s_reg + 2.0
        assert np.linalg.norm(exact) >= 0.5 / math.sin(beta) - 2.0  # the exact law grows like 1 / sin(beta)
    geo.rotation_euler(0.3, 1.2, 0.7, R)
    geo.contour_direction(R, math.sin(1.2), 0.0, exact)
    geo.contour_direction(R, math.sin(1.2), s_reg, regular)
    np.testing.assert_allclose(regular, exact, rtol=0, atol=2 * s_reg**2 * np.linalg.norm(exact))


def test_jdot_and_contour_direction_from_finite_differences():
    """J_R_dot phi_dot by central differences of (3.3); phi_dot = c . Omega equals gamma_dot (3.34)."""
    a = np.empty(3)
    c = np.empty(3)
    R = np.empty((3, 3))
    for _ in range(10):
        beta, gamma = RNG.uniform(0.3, 2.8), RNG.uniform(-3, 3)
        ad, bd, gd = RNG.normal(size=3) * 5
        h = 1e-6
        hi = kin.omega_from_euler_rates(beta + h * bd, gamma + h * gd, [ad, bd, gd])
        lo = kin.omega_from_euler_rates(beta - h * bd, gamma - h * gd, [ad, bd, gd])
        geo.jdot_rates(beta, gamma, ad, bd, gd, a)
        np.testing.assert_allclose(a, (hi - lo) / (2 * h), rtol=1e-6, atol=1e-6)
        alpha = RNG.uniform(-3, 3)
        geo.rotation_euler(alpha, beta, gamma, R)
        geo.contour_direction(R, math.sin(beta), 0.0, c)  # the exact law
        omega = kin.omega_from_euler_rates(beta, gamma, [ad, bd, gd])
        assert math.isclose(c @ omega, gd, rel_tol=1e-10, abs_tol=1e-10)


def test_floating_frame_continuity_when_horizontal():
    """Sect. 2.1: for R33 = 1 the previous e_x^G is kept (made orthogonal to e_z^B), never NaN."""
    exg = np.array([0.6, 0.8, 0.0])
    R = np.eye(3)
    assert geo.floating_frame(R, exg) == 0.0
    np.testing.assert_allclose(exg, [0.6, 0.8, 0.0])
    off = np.empty((3, 3))
    geo.contact_offsets(R, exg, 0.045, off)
    assert np.all(np.isfinite(off)) and np.allclose(off[:, 2], 0.0)
    np.testing.assert_allclose(np.linalg.norm(off, axis=1), 0.045)


# ------------------------------------------------------------ physics


def _drop_state(model, beta, height, v0):
    """Tilted disk, no rotation, C1 a distance ``height`` above the table, falling with v0 < 0."""
    r = Setup().disk.r
    q = np.zeros(7)
    q[2] = r * math.sin(beta) + height
    if model.parameterization == EULER:
        q[3:6] = 0.0, beta, 0.0
    else:
        q[3:7] = kin.quaternion_from_rotation(kin.rotation_from_euler(0.0, beta, 0.0))
    u = np.zeros(6)
    u[2] = v0
    return q, u


@pytest.mark.parametrize("name", ["moreau-coulomb-euler", "moreau-smooth-quaternion"])
@pytest.mark.parametrize("e_N", [0.0, 0.5])
def test_drop_and_impact_newton_restitution(name, e_N):
    """Newton's impact law (2.21) on velocity level: gamma_N1^+ = -e_N gamma_N1^- at the impact step."""
    model = MODELS[name]
    setup = Setup(friction=Friction(e_N=e_N))
    dt = 1e-5
    state = _drop_state(model, beta=1.2, height=2e-5, v0=-0.3)
    rows, status, failures, steps, _, _ = driver.integrate(model, setup, InitialState(), 3e-4, dt=dt,
                                                           store_every=1, state=state)
    data = dataset.outputs(model, setup, rows, dt)
    assert status == 0 and failures == 0
    k = int(np.argmax(data["P_N"][:, 0] > 0))  # the impact step
    assert k > 0 and data["P_N"][k, 0] > 0
    assert np.all(data["P_N"][:k, 0] == 0)  # free flight before
    pre, post = data["gamma_N1"][k - 1], data["gamma_N1"][k]
    assert pre < -0.29
    # post-impact normal velocity; the impact step itself adds gravity dt (1e-4 m/s)
    assert abs(post - (-e_N * pre)) < 2e-3 * abs(pre)
    # only C1 touches the table; C2, C3 stay far above
    assert np.all(data["g_N2"] > 1e-3) and np.all(data["g_N3"] > 1e-3)


def _max_error(a, b, names=("alpha", "beta", "gamma")):
    return max(float(np.max(np.abs(a[v].values - b[v].values))) for v in names)


@pytest.mark.parametrize("moreau_name, ode_name, options", [("m5", "ode-euler", {}), ("m6", "ode-quaternion", {})])
def test_smooth_coulomb_converges_first_order_to_ode(moreau_name, ode_name, options):
    """Models 5/6 -> heyoka ODE Models 1/2 on [0, 1] s with first order in dt (error ratio ~2 per halving)."""
    t_end = 1.0  # the interval of issue 3
    ref = simulate(ode_name, t_end, dt_output=1e-3)
    errors = []
    for dt in (4e-5, 2e-5, 1e-5):
        ds = simulate(moreau_name, t_end, dt=dt, store_every=int(round(1e-3 / dt)), **options)
        np.testing.assert_allclose(ds.time.values, ref.time.values, atol=1e-12)
        errors.append(_max_error(ds, ref))
    ratios = errors[0] / errors[1], errors[1] / errors[2]
    assert all(1.8 < ratio < 2.2 for ratio in ratios), (errors, ratios)
    assert errors[-1] < 2e-3  # rad at dt = 1e-5 s; the paper reports about 1e-3 rad (Sect. 6.5)
    if moreau_name == "m6":  # Sect. 6.5: gamma of Model 6 and ODE Model 2 differ by about +-1e-3 rad
        assert float(np.max(np.abs(ds.gamma.values - ref.gamma.values))) <= 1.2e-3  # 1.03e-3 (normalised)
        raw = simulate("m6", t_end, normalize_quaternion=False)  # 1.6e-2 rad: the paper's runs were normalised
        assert float(np.max(np.abs(raw.gamma.values - ref.gamma.values))) > 1e-2


def test_euler_and_quaternion_models_agree():
    """Models 1 and 2 (set-valued Coulomb) describe the same motion; normalisation (the default) removes the drift."""
    e = simulate("m1", 0.2)
    q = simulate("m2", 0.2)
    assert _max_error(e, q) < 2e-4
    assert float(np.max(np.abs(q.quaternion_norm_error))) < 1e-12
    np.testing.assert_allclose(e.E_tot, q.E_tot, rtol=1e-4)


@pytest.mark.parametrize("name", ["m2", "m4", "m6", "m8", "m10"])
def test_quaternion_models_normalise_by_default(name):
    """Sect. 3.2 after (3.67): the quaternion is normalised after each step. By default |p| - 1 stays
    below 1e-12 over a run; ``normalize_quaternion=False`` (the drift study) lets |p| grow."""
    ds = simulate(name, 1.0, store_every=10)
    assert ds.attrs["status"] == "completed" and ds.attrs["convergence_failures"] == 0
    assert results.config_of(ds)["integrator"]["normalize_quaternion"] == 1
    assert float(np.max(np.abs(ds.quaternion_norm_error))) < 1e-12
    raw = simulate(name, 1.0, store_every=10, normalize_quaternion=False)
    assert results.config_of(raw)["integrator"]["normalize_quaternion"] == 0
    assert float(raw.quaternion_norm_error[-1]) > 1e-4  # dt^2 |Omega|^2 / 8 per step: ~1e-3 after 1 s


@pytest.mark.parametrize("value", ["yes", 2, None])
def test_normalize_quaternion_option_is_validated(value):
    with pytest.raises(ParameterError, match="normalize_quaternion"):
        simulate("m2", 0.01, normalize_quaternion=value)


def test_constraint_drift_euler_vs_quaternion():
    """Fig. 8: Euler gap chatters at the 1e-9 m level; unnormalised quaternions drift downwards."""
    e = simulate("m1", 0.3)
    q = simulate("m2", 0.3, normalize_quaternion=False)
    assert float(np.max(np.abs(e.g_N1))) < 5e-9
    assert float(q.g_N1[-1]) < -1e-6  # drift (paper: -1.36e-5 m saturation for Model 4)
    assert float(q.quaternion_norm_error[-1]) > 0  # |p| grows: rotation no longer orthogonal
    assert e.attrs["status"] == "completed" and e.attrs["convergence_failures"] == 0


@pytest.mark.parametrize("name", [f"m{i}" for i in range(1, 11)])
def test_every_model_runs_and_stores_a_valid_dataset(name, tmp_path):
    """A smoke test of every model: 0.05 s is too short to prove anything about energy; the energy
    balance over 5 s and the per-step laws of the dissipative impulses are tested below."""
    ds = simulate(name, 0.05, store_every=100)
    assert ds.attrs["status"] == "completed"
    assert ds.sizes["time"] == 51 and ds.sizes["contact"] == 3
    assert float(ds.lambda_N[-1]) > 0 and int(ds.n_closed[-1]) == 1
    info = resolve(name)
    assert info.paper_name == f"Model {name[1:]}"
    results.check_finite(ds)
    path = results.save(ds, tmp_path / "run.nc")
    xr.testing.assert_identical(results.load(path), ds)


def _euler_midpoint_velocities(ds, dt):
    """Per step of an Euler-angle run stored every step: the midpoint q_M and, at q_M, Omega (B) and
    R for the start (u_A = previous row) and end (u_E) velocities, as the step computes them.

    Euler models advance q_E = q_M + dt/2 u_E (q_dot = u), so q_M = q_E - dt/2 u_E exactly, and
    Omega = J_R(beta_M, gamma_M) phi_dot (3.3) with the rates of u.
    """
    q = np.stack([ds[v].values for v in ("x", "y", "z", "alpha", "beta", "gamma")], axis=1)
    u = np.stack([ds[v].values for v in ("x_dot", "y_dot", "z_dot", "alpha_dot", "beta_dot", "gamma_dot")], axis=1)
    q_M = q[1:] - 0.5 * dt * u[1:]
    R = kin.rotation_from_euler(q_M[:, 3], q_M[:, 4], q_M[:, 5])
    omega_E = kin.omega_from_euler_rates(q_M[:, 4], q_M[:, 5], u[1:, 3:])
    omega_A = kin.omega_from_euler_rates(q_M[:, 4], q_M[:, 5], u[:-1, 3:])
    return q_M, R, u[:-1], u[1:], omega_A, omega_E


@pytest.mark.parametrize("name", ["m7", "m9"])
def test_pivoting_and_contour_friction_obey_their_laws(name):
    """Dry pivoting (2.30) and contour friction (2.31) step by step, with the end-of-step velocities
    recomputed from the stored state at the step's midpoint (not from the kernel's force directions):

    gamma_tau = contact_radius e_z^I . Omega (2.16), gamma_R = -r gamma_dot (3.34);
    |P_tau| <= mu_tau P_N and |P_R| <= mu_R P_N (the reservoirs); on the boundary the impulse opposes
    the velocity, so its dissipation -P gamma >= 0; inside, the contact sticks: |gamma| below the
    fixed-point resolution tol / r_gain. Table 3 exercises both: pivoting slides throughout
    (spin 40 rad/s about the vertical), contour friction sticks where gamma_dot changes sign.
    """
    dt, f, r = 1e-5, Friction(), Setup().disk.r
    ds = simulate(name, 0.3, dt=dt, store_every=1)
    assert ds.attrs["status"] == "completed" and ds.attrs["convergence_failures"] == 0
    _q_M, R, _u_A, u_E, _omega_A, omega_E = _euler_midpoint_velocities(ds, dt)
    P_N = ds.P_N.isel(contact=0).values[1:]
    closed = P_N > 0
    assert closed.mean() > 0.99  # C1 is closed in (nearly) every step
    velocity = {"tau": f.contact_radius * np.einsum("nj,nj->n", R[:, 2, :], omega_E), "R": -r * u_E[:, 5]}
    laws = {"tau": ("P_tau", f.mu_tau, defaults.MOREAU_GAINS["r_tau"]), "R": ("P_R", f.mu_R, defaults.MOREAU_GAINS["r_R"])}
    dissipated = {}
    for kind, (variable, mu, gain) in laws.items():
        P = ds[variable].isel(contact=0).values[1:]
        gamma = velocity[kind]
        assert np.all(np.abs(P) <= mu * P_N * (1 + 1e-12))  # the reservoir [-mu P_N, mu P_N]
        assert np.all(P[~closed] == 0.0)
        boundary = closed & (np.abs(P) >= mu * P_N * (1 - 1e-12))
        inside = closed & ~boundary
        assert np.all(P[boundary] * gamma[boundary] < 0)  # sliding: the impulse opposes the velocity
        assert np.all(np.abs(gamma[inside]) <= defaults.MOREAU_TOL / gain)  # sticking
        dissipation = -P[closed] * gamma[closed]
        assert np.all(dissipation >= -np.abs(P[closed]) * defaults.MOREAU_TOL / gain)
        dissipated[kind] = (dissipation.sum(), boundary.sum(), inside.sum())
    assert dissipated["tau"][2] == 0 and dissipated["tau"][1] == closed.sum()  # pivoting slides throughout
    assert dissipated["R"][2] > 0 and dissipated["R"][1] > 0  # contour friction both sticks and slides
    # sliding pivoting dissipates mu_tau lambda_N |gamma_tau| (2.30): about 0.15 mJ in 0.3 s (40 rad/s, 1 mm)
    assert dissipated["tau"][0] == pytest.approx(np.sum(f.mu_tau * P_N * np.abs(velocity["tau"])), rel=1e-12)
    assert 1e-4 < dissipated["tau"][0] < 2e-4 and dissipated["R"][0] > 1e-4


def test_smooth_coulomb_energy_balance_over_5s_is_first_order():
    """Model 6 (normalised), Table 3, 5 s: E_tot(t) - E_tot(0) = W_friction(t) up to the scheme's error.

    The friction work integrates the friction power P_T . gamma_T / dt at the stored samples (1 ms; the
    smooth-Coulomb force is continuous in the slip, so the trapezoidal rule resolves it). Moreau's
    midpoint scheme is first order, so the residual is an O(dt) error: it halves with dt. A wrong or
    missing dissipation term would leave a residual that does not scale with dt.
    """
    residual, work = [], []
    for dt in (2e-5, 1e-5):
        ds = simulate("m6", 5.0, dt=dt, store_every=int(round(1e-3 / dt)), normalize_quaternion=True)
        assert ds.attrs["status"] == "completed" and ds.attrs["convergence_failures"] == 0
        power = (ds.P_Tx.isel(contact=0) * ds.slip_x + ds.P_Ty.isel(contact=0) * ds.slip_y).values / dt
        assert np.all(power <= 0)  # (2.29) opposes the slip
        W = np.concatenate([[0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(ds.time.values))])
        residual.append(float(np.max(np.abs(ds.E_tot.values - ds.E_tot.values[0] - W))))
        work.append(W[-1])
    assert work[-1] < -0.025  # real dissipation: about 0.03 J of 0.38 J, mostly during the inversion
    assert abs(work[0] / work[1] - 1) < 0.01
    assert residual[-1] < 2e-3 * abs(work[-1])  # 2.7e-5 J at dt = 1e-5 s
    assert 1.7 < residual[0] / residual[1] < 2.3, residual  # first order in dt


def _contact_velocity(R, omega_B, v_G, r):
    """Velocity of the material point at C1 (2.13), I-frame: v_G + Omega x r_GC1, r_GC1 from (2.10)."""
    return v_G + np.cross(R @ omega_B, kin.contact_point_offsets(R, r)[0])


@pytest.mark.parametrize("mu, e_N, e_T, sticks", [(2.0, 0.5, 0.5, True), (2.0, 0.3, 1.0, True),
                                                  (0.1, 0.5, 0.5, False)])
def test_impact_with_slip_tangential_newton_law(mu, e_N, e_T, sticks):
    """Set-valued Coulomb with tangential restitution e_T > 0 (2.28), (4.3)-(4.5): at the impact step
    xi_T = gamma_T^E + e_T gamma_T^A. Sticking (|P_T| < mu P_N): xi_T = 0, the slip reverses,
    gamma_T^E = -e_T gamma_T^A; sliding: |P_T| = mu P_N and P_T opposes xi_T. Newton (2.21) normally."""
    model = MODELS["moreau-coulomb-euler"]
    setup = Setup(friction=Friction(mu=mu, e_N=e_N, e_T=e_T))
    dt, r, beta = 1e-5, setup.disk.r, 1.2
    q = np.array([0.0, 0.0, r * math.sin(beta) + 2e-5, 0.0, beta, 0.0, 0.0])  # C1 20 um above the table
    u = np.array([0.1, 0.05, -0.3, 0.0, 0.0, 0.0])  # falling and sliding, no rotation
    rows, status, failures, _, _, _ = driver.integrate(model, setup, InitialState(), 1e-4, dt=dt, store_every=1,
                                                       state=(q, u))
    assert status == 0 and failures == 0
    data = dataset.outputs(model, setup, rows, dt)
    k = int(np.argmax(data["P_N"][:, 0] > 0))  # the impact step
    assert k > 0 and np.all(data["P_N"][:k] == 0)
    q_E, u_A, u_E = rows[k, layout.COL_Q:layout.COL_Q + 6], rows[k - 1, layout.COL_U:layout.COL_U + 6], \
        rows[k, layout.COL_U:layout.COL_U + 6]
    q_M = q_E - 0.5 * dt * u_E
    R = kin.rotation_from_euler(*q_M[3:6])
    g_A = _contact_velocity(R, kin.omega_from_euler_rates(q_M[4], q_M[5], u_A[3:]), u_A[:3], r)
    g_E = _contact_velocity(R, kin.omega_from_euler_rates(q_M[4], q_M[5], u_E[3:]), u_E[:3], r)
    assert np.hypot(*g_A[:2]) > 0.1 and g_A[2] < -0.29  # an impact with slip
    P_N = data["P_N"][k, 0]
    P_T = np.array([data["P_Tx"][k, 0], data["P_Ty"][k, 0]])
    assert g_E[2] == pytest.approx(-e_N * g_A[2], abs=1e-6)  # (2.21)
    xi_T = g_E[:2] + e_T * g_A[:2]
    if sticks:
        assert np.hypot(*P_T) < mu * P_N
        np.testing.assert_allclose(g_E[:2], -e_T * g_A[:2], atol=1e-6)  # the slip reverses by e_T
    else:
        assert np.hypot(*P_T) == pytest.approx(mu * P_N, rel=1e-12)
        np.testing.assert_allclose(P_T / np.hypot(*P_T), -xi_T / np.hypot(*xi_T), atol=1e-6)
        assert np.hypot(*xi_T) > 0.1


def _flat_spin_state(beta, spin=10.0):
    """Quaternion state: the disk tilted by beta (nearly flat), C1 on the table, spinning about its normal."""
    q = np.zeros(7)
    q[2] = Setup().disk.r * math.sin(beta)
    q[3:7] = kin.quaternion_from_rotation(kin.rotation_from_euler(0.0, beta, 0.0))
    return q, np.array([0.0, 0.0, 0.0, 0.0, 0.0, spin])


def _run_flat_spin(name, beta, setup, spin=10.0):
    model = MODELS[name]
    rows, status, failures, steps, _, _ = driver.integrate(model, setup, InitialState(), 0.01, store_every=10,
                                                           state=_flat_spin_state(beta, spin))
    return dataset.outputs(model, setup, rows, defaults.MOREAU_DT), status, failures, steps


def _assert_flat_spin_runs_cleanly(data, status, failures, steps):
    assert layout.STATUS_NAMES[status] == "completed", layout.STATUS_NAMES[status]
    assert failures == 0
    assert steps == 1000
    assert all(np.all(np.isfinite(v)) for v in data.values())
    assert data["E_tot"][-1] < data["E_tot"][0]  # friction on the table slows the spin


@pytest.mark.parametrize("spin", [10.0, 40.0])
@pytest.mark.parametrize("beta", [1e-3, 1e-5])
@pytest.mark.parametrize("name", ["moreau-coulomb-pivot-contour-quaternion", "moreau-smooth-pivot-contour-quaternion"])
def test_pivot_contour_models_run_through_a_nearly_flat_disk(name, beta, spin):
    """Acceptance test of issue 14 item 1: Models 8/10 started nearly flat (beta = 1e-3, 1e-5) spinning
    about the disk normal run 0.01 s without prox failures and without a non-finite state (today:
    'nonfinite' after 37-344 steps, or 'completed' with prox failures in 251 steps at 40 rad/s)."""
    _assert_flat_spin_runs_cleanly(*_run_flat_spin(name, beta, Setup(), spin))


@pytest.mark.parametrize("beta", [1e-3, 1e-5])
@pytest.mark.parametrize("name, friction", [("moreau-coulomb-quaternion", Friction()),
                                            ("moreau-smooth-quaternion", Friction()),
                                            ("moreau-coulomb-pivot-contour-quaternion", Friction(mu_R=0.0))])
def test_nearly_flat_spin_runs_without_contour_friction(name, friction, beta):
    """Control for the test above: the same start runs cleanly without contour friction (Models 2/6,
    or Model 8 with mu_R = 0), so the start itself is sound."""
    _assert_flat_spin_runs_cleanly(*_run_flat_spin(name, beta, Setup(friction=friction)))


def test_iteration_limit_is_reported_not_silent():
    ds = simulate("m3", 0.01, max_iter=1, tol=1e-15)
    assert ds.attrs["status"] == "not_converged"
    assert ds.attrs["convergence_failures"] > 0 and "max_iter" in ds.attrs["message"]


def test_euler_model_ends_with_status_near_horizontal():
    ds = simulate("m1", 0.01, initial=InitialState(beta=0.05, gamma=0.0, alpha_dot=0.0), fall_angle=0.1)
    assert ds.attrs["status"] == "fell" and ds.attrs["n_steps"] == 0
    results.check_finite(ds)


@pytest.mark.parametrize("options, word", [({"dt": -1e-5}, "dt"), ({"store_every": 0}, "store_every"),
                                           ({"max_iter": 2.5}, "max_iter"), ({"r_N": 0.0}, "r_N"),
                                           ({"dt": 0.1}, "dt"), ({"fall_angle": 2.0}, "fall_angle"),
                                           ({"dt_output": 1e-3}, "dt_output")])
def test_bad_options_raise_parameter_error(options, word):
    with pytest.raises(ParameterError, match=word):
        simulate("m1", 0.01, **options)


def test_setup_parameters_reach_the_kernel():
    """Gravity and friction of Setup are used: no friction -> no tangential impulse."""
    setup = Setup(friction=dataclasses.replace(Friction(), mu=0.0, mu_tau=0.0, mu_R=0.0))
    ds = simulate("m7", 0.02, setup=setup, store_every=100)
    assert float(np.max(np.abs(ds.P_Tx))) == 0.0 and float(np.max(np.abs(ds.P_R))) == 0.0
    assert float(ds.P_N[-1, 0]) > 0


def test_flat_drop_closes_three_contacts_and_keeps_the_frame():
    """A horizontal disk (quaternions; floating frame undefined, Sect. 2.1) lands on C1-C3 at once."""
    model = MODELS["moreau-coulomb-quaternion"]
    setup = Setup(friction=Friction(e_N=0.5))
    dt = 1e-5
    q = np.array([0.0, 0.0, 5e-6, 1.0, 0.0, 0.0, 0.0])  # flat, G 5 um above the table
    u = np.array([0.0, 0.0, -0.2, 0.0, 0.0, 0.0])
    rows, status, failures, steps, _, _ = driver.integrate(model, setup, InitialState(), 2e-3, dt=dt,
                                                           store_every=1, state=(q, u))
    data = dataset.outputs(model, setup, rows, dt)
    assert status == 0 and failures == 0 and steps == 200
    assert all(np.all(np.isfinite(v)) for v in data.values())
    k = int(np.argmax(data["n_closed"] == 3))  # impact: all three candidate points at once
    assert k > 0 and np.all(data["P_N"][k] > 0)
    # Newton's law (2.21) at every closed contact: the disk leaves with -e_N times its speed
    np.testing.assert_allclose(data["z_dot"][k], -0.5 * data["z_dot"][k - 1], rtol=2e-3)
    np.testing.assert_allclose(data["omega_x"][k:], 0.0, atol=1e-9)  # no tilting from a flat impact


def test_nonfinite_state_ends_the_run_with_a_status(monkeypatch):
    real = driver.run_steps

    def failing(*args):
        steps, rows, _ = real(*args)
        return steps, rows, layout.STATUS_NONFINITE  # as if the state became non-finite after the first chunk

    monkeypatch.setattr(driver, "run_steps", failing)
    ds = simulate("m5", 0.5)
    assert ds.attrs["status"] == "nonfinite" and "non-finite" in ds.attrs["message"]
    assert ds.attrs["t_final"] < 0.5
    results.check_finite(ds)


def test_step_loop_detects_a_nonfinite_state():
    model = MODELS["moreau-smooth-quaternion"]
    setup = Setup()
    q, u, exg = driver.initial_state(model, setup, InitialState())
    u[0] = np.inf
    par, ipar = driver.parameter_vectors(model, setup, dt=1e-5, tol=1e-8, max_iter=100, r_N=0.1, r_T=0.1,
                                         r_tau=0.1, r_R=1e-4, normalize_quaternion=False, fall_angle=0.0,
                                         store_every=1)
    out = np.zeros((5, layout.N_COLUMNS))
    steps, rows, status = driver.run_steps(q, u, exg, np.zeros((3, 5)), par, ipar, prox.contensou_polygon(), 3, 0,
                                           out, 0, np.zeros(5))
    assert (steps, rows, status) == (0, 0, 1)
    assert np.all(np.isfinite(q))  # the stored state is the last finite one


def test_force_law_limits_reduce_to_set_valued_coulomb():
    """Coulomb-Contensou -> set-valued Coulomb as the contact radius -> 0 (linearly); Models 7 = 1
    without pivoting and contour friction."""
    ref = simulate("m1", 0.2, store_every=1000)
    errors = [_max_error(ref, simulate("m3", 0.2, store_every=1000,
                                       setup=Setup(friction=Friction(contact_radius=rc)))) for rc in (1e-5, 1e-6)]
    assert errors[1] < 2e-4 and 5 < errors[0] / errors[1] < 20
    plain = simulate("m7", 0.2, store_every=1000, setup=Setup(friction=Friction(mu_tau=0.0, mu_R=0.0)))
    assert _max_error(ref, plain) < 1e-12


def test_cli_simulate_moreau_model(tmp_path, capsys):
    from tippedisk_analysis.cli import main

    path = tmp_path / "m5.nc"
    code = main(["simulate", "--model", "m5", "--t-end", "0.01", "--dt", "2e-5", "--tol", "1e-9",
                 "--store-every", "10", "-o", str(path)])
    assert code == 0 and "moreau-smooth-euler completed" in capsys.readouterr().out
    ds = results.load(path)
    config = results.config_of(ds)["integrator"]
    assert (config["dt"], config["tol"], config["store_every"]) == (2e-5, 1e-9, 10)
    assert ds.sizes["time"] == 51
    assert main(["simulate", "--model", "m5", "--store-every", "0", "-o", str(tmp_path / "x.nc")]) == 2
    assert "--store-every" in capsys.readouterr().err and not (tmp_path / "x.nc").exists()


def test_interrupted_run_resumes_from_its_checkpoint(tmp_path, monkeypatch):
    """A long run killed midway resumes from its checkpoint and ends as if never interrupted."""
    checkpoint = tmp_path / "run.checkpoint.npz"
    reference = simulate("m5", 1.2)  # 120,000 steps: 6 chunks of 20,000
    monkeypatch.setattr(defaults, "CHECKPOINT_SECONDS", 0.0)  # save after every chunk
    real_chunk, calls = driver.run_steps, []

    def dies_after_three_chunks(*args):
        calls.append(1)
        if len(calls) > 3:
            raise KeyboardInterrupt
        return real_chunk(*args)

    monkeypatch.setattr(driver, "run_steps", dies_after_three_chunks)
    with pytest.raises(KeyboardInterrupt):
        simulate("m5", 1.2, checkpoint=str(checkpoint))
    assert checkpoint.exists()
    monkeypatch.setattr(driver, "run_steps", real_chunk)
    with pytest.raises(ParameterError, match="different run"):
        simulate("m5", 1.2, checkpoint=str(checkpoint), dt=2e-5)
    calls.clear()
    monkeypatch.setattr(driver, "run_steps", dies_after_three_chunks)  # only 3 of 6 chunks are left
    resumed = simulate("m5", 1.2, checkpoint=str(checkpoint))
    assert not checkpoint.exists()
    for name in reference.data_vars:
        np.testing.assert_array_equal(resumed[name].values, reference[name].values, err_msg=name)
    assert resumed.attrs["n_steps"] == reference.attrs["n_steps"]


# ------------------------------------------------------------ Coulomb-Contensou torque share (diagnostic variant)


@pytest.mark.parametrize("model, value", [("m3", -0.1), ("m3", 1.5), ("m3", True), ("m3", "0"), ("m3", float("nan")),
                                          ("m1", 0.5), ("m8", 0.0)])
def test_contensou_torque_share_is_validated(model, value):
    with pytest.raises(ParameterError, match="contensou_torque_share"):
        simulate(model, 0.01, contensou_torque_share=value)


def test_contensou_torque_share_is_stored_and_removes_only_the_torque():
    """The share is stored with Models 3/4 (not with others); share 1 is the law bitwise; share 0 keeps the
    prox impulse P_tau (the ball still couples spin and slip) but the disk's spin no longer feels it."""
    law = simulate("m3", 0.05, store_every=100)
    one = simulate("m3", 0.05, store_every=100, contensou_torque_share=1.0)
    zero = simulate("m3", 0.05, store_every=100, contensou_torque_share=0.0)
    assert results.config_of(law)["integrator"]["contensou_torque_share"] == 1.0
    assert results.config_of(zero)["integrator"]["contensou_torque_share"] == 0.0
    assert "contensou_torque_share" not in results.config_of(simulate("m1", 0.01))["integrator"]
    for name in law.data_vars:
        np.testing.assert_array_equal(one[name].values, law[name].values, err_msg=name)
    assert float(np.max(np.abs(zero.P_tau.isel(contact=0)))) > 0  # the prox impulse is still there
    # the pivoting torque slows the spin: without it alpha_dot stays higher
    assert float(zero.alpha_dot[-1]) > float(law.alpha_dot[-1])
