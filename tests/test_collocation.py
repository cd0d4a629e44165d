"""Periodic orbits by orthogonal collocation (dynamics/collocation*.py), each check against an independent answer:
the Hopf normal form's circle (convergence at order 2 ncol, the error estimate against the true error), the block
solver against a dense solve and the Jacobian against finite differences, the multipliers against shooting's
integrated monodromy, a canard explosion and stiff van der Pol cycles against scipy's DOP853 / Radau, and the
tippedisk's orbit families against shooting."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
import zoo
from scipy.integrate import solve_ivp

import tippedisk_analysis as td
from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.dynamics.collocation import CollocationProblem
from tippedisk_analysis.dynamics.collocation_mesh import Mesh, basis
from tippedisk_analysis.dynamics.orbit_base import newton
from tippedisk_analysis.dynamics.systems import HOPF_ROTATION
from tippedisk_analysis.errors import ParameterError


def assert_same_multipliers(actual, desired, atol: float) -> None:
    """Each multiplier of ``actual`` has one of ``desired`` within ``atol`` and the other way round (conjugate
    pairs whose real parts differ in the last digits sort differently)."""
    actual, desired = np.asarray(actual), np.asarray(desired)
    gap = np.abs(actual[:, None] - desired[None, :])
    assert gap.min(axis=1).max() <= atol and gap.min(axis=0).max() <= atol, (actual, desired)


# ------------------------------------------------------------------------------------- the basis and the mesh
@pytest.mark.parametrize("m", range(2, 8))
def test_the_basis_reproduces_polynomials_and_its_gauss_rule_is_exact(m):
    b = basis(m)
    rng = np.random.default_rng(m)
    c = rng.normal(size=m + 1)  # a polynomial of degree m: the basis reproduces it and its derivative
    p = np.polynomial.Polynomial(c)
    nodes = np.arange(m + 1) / m
    np.testing.assert_allclose(b.at_gauss @ p(nodes), p(b.gauss), atol=1e-12)
    np.testing.assert_allclose(b.slope_at_gauss @ p(nodes), p.deriv()(b.gauss), atol=1e-10)
    np.testing.assert_allclose(b.top @ p(nodes), math.factorial(m) * c[m], rtol=1e-8)
    q = np.polynomial.Polynomial(rng.normal(size=2 * m))  # degree 2m - 1: the Gauss rule integrates it exactly
    assert b.weights @ q(b.gauss) == pytest.approx(q.integ()(1.0) - q.integ()(0.0), abs=1e-13)


def test_a_mesh_evaluates_its_piecewise_polynomial_and_adapts_where_it_is_steep():
    mesh = Mesh.uniform(8, 4)
    X = np.column_stack([np.cos(2 * np.pi * mesh.times), np.sin(2 * np.pi * mesh.times)])
    t = np.linspace(0.0, 1.0, 1001)
    assert np.max(np.abs(mesh.evaluate(X, t)[:, 0] - np.cos(2 * np.pi * t))) < 1e-4
    fine = Mesh.uniform(64, 4)
    pulse = np.exp(-((fine.times - 0.3) / 0.02) ** 2)[:, None]  # steep near tau = 0.3
    adapted = fine.adapted(pulse, [1.0])
    middle = 0.5 * (adapted.tau[1:] + adapted.tau[:-1])
    assert abs(middle[np.argmin(adapted.h)] - 0.3) < 0.05
    assert adapted.h[np.abs(middle - 0.3) < 0.05].mean() < 0.1 * adapted.h[np.abs(middle - 0.3) > 0.2].mean()
    ratio = adapted.h / np.roll(adapted.h, 1)
    assert np.max(np.maximum(ratio, 1 / ratio)) < 4  # a graded mesh


# ------------------------------------------------------------------------------------- the Hopf normal form
def _hopf_orbit(ntst: int, ncol: int, beta: float = 0.1):
    """The circle r^2 = beta of the rotated Hopf normal form (l1 = -1, omega = 1, c = 0.5) on a uniform mesh."""
    system = dy.textbook_system("hopf")
    pars = system.with_pars(beta=beta)
    r, period = math.sqrt(beta), 2 * math.pi / (1 + 0.5 * beta)
    prob = CollocationProblem(system, pars, ntst=ntst, ncol=ncol, adapt=0, error_tol=math.inf, period_scale=period)
    u = prob.unknowns(HOPF_ROTATION @ np.array([1.1 * r, 0.0, 0.0]), 1.02 * period)
    status, u, _it, _F = newton(prob, u, 1e-13, 25)
    assert status == "converged"
    return prob, u, r, period


def _exact_circle(states, r: float, omega: float) -> np.ndarray:
    """The exact orbit at the phases of ``states`` (rotated frame): (r cos, r sin, w), w' = -w + u v."""
    xi = states @ HOPF_ROTATION
    theta = np.unwrap(np.arctan2(xi[:, 1], xi[:, 0]))
    theta = theta[0] + (np.arange(len(theta)) / len(theta)) * 2 * math.pi  # uniform in time, from the first phase
    w = 0.5 * r * r * np.imag(np.exp(2j * theta) / (1 + 2j * omega))
    return np.column_stack([r * np.cos(theta), r * np.sin(theta), w])


@pytest.mark.parametrize("ncol", [3, 4])
def test_hopf_normal_form_errors_fall_at_order_2_ncol_and_the_estimate_is_the_true_error(ncol):
    """At the mesh points the orbit and the period converge at order 2 ncol (superconvergence): doubling ntst
    divides their errors by 2^(2 ncol); between them the error is order ncol + 1, and the estimate
    (collocation_mesh) is that error to a factor 2 once the mesh resolves the orbit."""
    beta = 0.1
    omega = 1 + 0.5 * beta
    period_errors, point_errors = [], []
    for ntst in (4, 8, 16):
        prob, u, r, period = _hopf_orbit(ntst, ncol, beta)
        X, T, _p = prob.split(u)
        period_errors.append(abs(T - period))
        radius = np.linalg.norm((X[::ncol] @ HOPF_ROTATION)[:, :2], axis=1)
        point_errors.append(np.max(np.abs(radius - r)))
    order = 2 ** (2 * ncol)
    for errors in (period_errors, point_errors):
        ratios = np.array(errors[:-1]) / np.array(errors[1:])
        assert np.all((0.6 * order < ratios) & (ratios < 1.5 * order)), (errors, ratios, order)
    orbit = prob.orbit(u, n_samples=4000)
    true_error = np.max(np.linalg.norm(orbit.samples @ HOPF_ROTATION - _exact_circle(orbit.samples, r, omega), axis=1))
    assert 0.5 < orbit.discretisation_error / true_error < 2.0
    mu = np.sort(np.abs(orbit.multipliers))  # 1, the radial exp(-2 beta T) and the slave exp(-T)
    np.testing.assert_allclose(mu, [math.exp(-T), math.exp(-2 * beta * T), 1.0], rtol=1e-6)


# ------------------------------------------------------------------------------------- the linear algebra
def test_the_block_elimination_solves_the_dense_system_and_the_jacobian_is_exact():
    ab = dy.textbook_system("ab")
    pars = ab.with_pars(D=0.12)
    state, period = dy.simulation_guess(ab, [0.3, 1.0], pars, transient=200.0)
    prob = CollocationProblem(ab, pars, ntst=12, parameter="D")
    u = prob.unknowns(state, period, 0.12)
    prob.set_reference(u)
    A = prob.jacobian(u).toarray()
    h = 1e-7 * np.maximum(1.0, np.abs(u))
    fd = np.column_stack([(prob.residual(u + h[j] * e) - prob.residual(u - h[j] * e)) / (2 * h[j])
                          for j, e in enumerate(np.eye(len(u)))])
    assert np.max(np.abs(A - fd)) < 1e-6 * np.max(np.abs(A))
    rng = np.random.default_rng(1)
    row = rng.normal(size=len(u))
    lin = prob.linearise(u, prob.scale, row)
    b = rng.normal(size=lin.rows)
    dense = np.vstack([A * prob.scale[None, :], row])
    np.testing.assert_allclose(lin.solve(b), np.linalg.solve(dense, b), rtol=1e-9, atol=1e-11)
    np.testing.assert_allclose(lin.magnitude(u / prob.scale), np.abs(dense) @ np.abs(u / prob.scale), rtol=1e-12)


# ------------------------------------------------------------------------------------- multipliers
@pytest.mark.parametrize("name, state, period, pars", [
    ("vanderpol", [2.0, 0.0], 6.66, {"mu": 1.0}),
    ("roessler", [4.58086947, 0.0, 1.52654668], 5.749, {"c": 2.5}),
])
def test_collocation_multipliers_are_the_integrated_monodromys(name, state, period, pars):
    system = dy.textbook_system(name)
    p = system.with_pars(**pars)
    shot = dy.find_orbit(system, state, period, p)
    coll = dy.find_orbit(system, state, period, p, method="collocation")
    assert shot.converged and coll.converged and coll.multiplier_source == "collocation"
    assert coll.period == pytest.approx(shot.period, rel=1e-9)
    assert_same_multipliers(coll.multipliers, shot.multipliers, 1e-7)
    assert coll.discretisation_error < 1e-6 and coll.flow_multiplier_error < 1e-6


# ------------------------------------------------------------------------------------- errors
@pytest.mark.parametrize("options, fragment", [
    ({"method": "collocation", "ncol": 8}, "ncol = 8"),
    ({"method": "collocation", "ntst": 1}, "ntst = 1"),
    ({"method": "collocation", "segments": 4}, "segments is an option of shooting"),
    ({"method": "collocation", "phase": "poincare"}, "integral phase condition"),
    ({"method": "shooting", "ntst": 60}, "ntst is an option of collocation"),
    ({"method": "collocation", "error_tol": 0.0}, "error_tol = 0.0"),
    ({"method": "spline"}, "unknown method 'spline'"),
])
def test_bad_collocation_options_are_one_line_errors(options, fragment):
    system = dy.textbook_system("vanderpol")
    with pytest.raises(ParameterError, match=re.escape(fragment)) as info:
        dy.find_orbit(system, [2.0, 0.0], 6.66, **options)
    assert "\n" not in str(info.value)


# ------------------------------------------------------------------------------------- relaxation and canards
CANARD_MARKS = (0.9935, 0.9934, 0.95)  # inside the explosion (a canard without head), just after it, relaxation


def _simulated_cycle(a: float, eps: float = 0.05):
    """(period, x max, x min) of the attractor of eps x' = y - x^3/3 + x, y' = a - x by DOP853 at 1e-12 (returns
    to x = a upwards after a transient of 400)."""
    def rhs(t, u):
        return [(u[1] - u[0] ** 3 / 3 + u[0]) / eps, a - u[0]]

    run = solve_ivp(rhs, (0.0, 400.0), [0.5, 0.0], method="DOP853", rtol=1e-12, atol=1e-12)
    section = lambda t, u: u[0] - a  # noqa: E731
    section.direction = 1
    run = solve_ivp(rhs, (0.0, 40.0), run.y[:, -1], method="DOP853", rtol=1e-12, atol=1e-12, events=section,
                    dense_output=True)
    times = run.t_events[0]
    x = run.sol(np.linspace(times[-2], times[-1], 400001))[0]
    return times[-1] - times[-2], x.max(), x.min()


@pytest.mark.slow
def test_the_branch_goes_through_the_canard_explosion_to_the_relaxation_cycles():
    """From the Hopf point a = 1 the orbits of the canard system (eps = 0.05) grow within 1e-7 of a = 0.99349 (the
    explosion, where shooting stalls: test_zoo.py) into relaxation cycles; collocation follows them to a = 0
    within the point budget, and at a canard inside the explosion, just after it and on a relaxation cycle the
    period and the extremes of x equal DOP853's attractor. A canard's period is sensitive to the orbit: at the
    default error_tol (1e-6) the one at a = 0.9935 is off by 5.5e-6 (relative), at 1e-8 by about 4e-9."""
    s = zoo.canard()
    eq = dy.equilibrium_branch(s, [1.2, 1.2**3 / 3 - 1.2], "a", bounds=(0.0, 1.2), direction=-1)
    po = dy.orbit_branch(s, eq, "HOPF1", bounds=(0.0, 1.2), marks=CANARD_MARKS, n_samples=20000, error_tol=1e-8)
    assert po.attrs["status"] == "completed" and po.sizes["point"] < 100
    assert float(po.amplitude.max()) > 2.0 and float(po.a[-1]) == 0.0  # the relaxation cycles, to the bound
    error = po.discretisation_error.values  # the branch's orbits within error_tol; user points and the bound solved
    located = np.isin(np.arange(po.sizes["point"]), [*po.special_index.values, po.sizes["point"] - 1])  # on the
    # mesh of the step that brackets them
    assert np.all(error[~located] <= 1e-8) and np.all(error <= 2e-7)
    explosion = (po.a.values > 0.99349) & (po.a.values < 0.99350)
    assert np.ptp(po.period.values[explosion]) > 1.0  # the period rises by over 1 within 1e-5 of a
    for value in CANARD_MARKS:
        i = [int(k) for k, label in zip(po.special_index.values, po.special_label.values)
             if label.startswith("UZ") and float(po.a.values[k]) == value]
        assert len(i) == 1, value
        period, x_max, x_min = _simulated_cycle(value)
        assert float(po.period[i[0]]) == pytest.approx(period, rel=1e-6), value
        assert float(po.state_max[i[0], 0]) == pytest.approx(x_max, abs=2e-6), value
        assert float(po.state_min[i[0], 0]) == pytest.approx(x_min, abs=2e-6), value
        assert int(po.stability[i[0]]) == dy.STABILITY["stable"]


ALPHA = 2.338107410459767  # -(the first zero of the Airy function Ai)


@pytest.mark.slow
@pytest.mark.parametrize("mu", [10.0, 30.0])
def test_stiff_van_der_pol_cycles_against_radau_and_the_asymptotic_period(mu):
    """x'' - mu (1 - x^2) x' + x = 0: T = (3 - 2 ln 2) mu + 3 alpha mu^(-1/3) - (2/3) ln(mu) / mu + O(1/mu)
    (Dorodnitsyn); the collocation orbit's period equals scipy's Radau return time at 1e-12, its mesh puts the
    intervals where the cycle jumps, and its nontrivial multiplier is exp(int div f dt) < 1e-15."""
    system = dy.textbook_system("vanderpol")
    pars = system.with_pars(mu=mu)
    state, period = dy.simulation_guess(system, [2.0, 0.0], pars, transient=5 * mu, dt=1e-3 * mu)
    orbit = dy.find_orbit(system, state, period, pars, method="collocation")
    assert orbit.converged and orbit.discretisation_error < 1e-6

    def rhs(t, u):
        return [u[1], mu * (1 - u[0] ** 2) * u[1] - u[0]]

    section = lambda t, u: u[1]  # noqa: E731
    section.direction = -1
    run = solve_ivp(rhs, (0.0, 20 * mu), [2.0, 0.0], method="Radau", rtol=1e-12, atol=1e-12, events=section)
    assert orbit.period == pytest.approx(np.diff(run.t_events[0])[-1], rel=1e-8)
    asymptotic = (3 - 2 * math.log(2)) * mu + 3 * ALPHA * mu ** (-1 / 3) - (2 / 3) * math.log(mu) / mu
    assert abs(orbit.period - asymptotic) < 2.0 / mu
    h = np.diff(orbit.mesh)
    assert h.max() / h.min() > 10  # adapted: short intervals where x jumps
    assert np.sort(np.abs(orbit.multipliers))[0] < 1e-15


# ------------------------------------------------------------------------------------- the tippedisk
@pytest.mark.slow
def test_the_frictionless_centre_family_by_collocation_equals_shootings():
    """The family born at the inverted spin (Omega = 40 rad/s, mu = 0: two first integrals) in the energy, by
    both methods: the periods and multipliers at two energies agree."""
    from tippedisk_analysis.analysis import orbits

    setup = td.Setup(friction=td.Friction(mu=0.0))
    orbit = orbits.tippedisk_lyapunov_orbit(setup, "inverted", 40.0, 1e-3)
    e0 = dy.integral_levels(orbit.system, orbit.states[0], orbit.pars)["E_tot"]
    marks = (e0 + 0.02, e0 + 0.05)
    found = {}
    for method in ("shooting", "collocation"):
        br, prob = dy.continue_orbits(orbit, "E_tot", bounds={"E_tot": (e0 - 1e-3 * abs(e0), e0 + 0.06)},
                                      method=method, parameter_scale=0.01, marks=marks)
        ds = dy.branch_dataset(prob, br)
        assert ds.attrs["status"] == "completed" and ds.attrs["method"] == method
        users = [i for i, label in zip(ds.special_index.values, ds.special_label.values) if label.startswith("UZ")]
        found[method] = [(float(ds.period[i]), ds.multiplier_real.values[i] + 1j * ds.multiplier_imag.values[i])
                         for i in users]
    assert len(found["collocation"]) == len(found["shooting"]) == 2
    for (t_c, mu_c), (t_s, mu_s) in zip(found["collocation"], found["shooting"]):
        assert t_c == pytest.approx(t_s, rel=1e-8)
        assert_same_multipliers(mu_c, mu_s, 2e-4)  # the multipliers at 1 split by the discretisation


@pytest.mark.slow
def test_the_rolling_family_with_a_pinned_spin_by_collocation_is_shootings():
    """The rolling orbits at fixed omega_x (pinned) continued in the energy end at the spin by both methods (the
    same energy and period); each collocation orbit is a shooting orbit: single shooting from its x(0) with the
    same levels returns its period and multipliers. (The pin holds omega_x at x(0), and each method's phase
    condition puts x(0) elsewhere on the orbit: the two pick neighbouring members of the family.)"""
    from tippedisk_analysis.analysis import rolling as ar

    guess = np.array([1.9457, 0.5 * math.pi, 38.297, 0.0, -1.1612])
    ends = {}
    for method in ("shooting", "collocation"):
        central = dy.find_orbit(ar.reduced_system(), guess, 0.888, pinned=("omega_x",), method=method)
        br, prob = dy.continue_orbits(central, "E_tot", bounds={"E_tot": (0.3, 0.5)}, pinned=("omega_x",))
        assert br.special_points[-1].kind == "hopf", br.message
        ends[method] = (float(prob.split(br.points[-1].u)[2]), float(prob.split(br.points[-1].u)[1]))
        if method == "collocation":
            ds = dy.branch_dataset(prob, br)
            for i in (1, ds.sizes["point"] // 2):
                x0, period = ds.initial_state.values[i], float(ds.period[i])
                shot = dy.find_orbit(ar.reduced_system(), x0, period, ds.runtime_parameters.values[i],
                                     pinned=("omega_x",))
                assert shot.converged and shot.period == pytest.approx(period, rel=1e-8)
                mu = ds.multiplier_real.values[i] + 1j * ds.multiplier_imag.values[i]
                assert_same_multipliers(mu, shot.multipliers, 1e-4)
    assert ends["collocation"] == pytest.approx(ends["shooting"], rel=1e-8)


# ------------------------------------------------------------------------------------- special points
def test_collocation_branches_locate_the_fold_the_period_doubling_and_the_neimark_sacker_point():
    """The special points of shooting's tests (test_periodic.py), by collocation: the Bautin fold of cycles at
    beta = -1/4 (r^2 = 1/2); Roessler's first period doubling at c = 2.8324 with the doubled branch (period twice
    the old one, the two halves apart), equal to shooting's; the torus system's Neimark-Sacker point at beta = 0
    with angle 2 pi sqrt(2) mod 2 pi."""
    bautin = dy.textbook_system("bautin")
    orbit, _g = dy.orbit_from_hopf(bautin, "beta", 0.0, [0.0, 0.0], radius=0.2, method="collocation")
    br, prob = dy.continue_orbits(orbit, "beta", bounds={"beta": (-0.5, 0.3)}, direction=-1)
    folds = [sp for sp in br.special_points if sp.kind == "fold"]
    assert [sp.label for sp in folds] == ["LP1"] and prob.split(folds[0].u)[2] == pytest.approx(-0.25, abs=1e-9)

    roessler = dy.textbook_system("roessler")
    x0, T0 = dy.simulation_guess(roessler, [1.0, 1.0, 0.0], index=1, level=0.0, transient=200.0)
    found = {}
    for method in ("shooting", "collocation"):
        orbit = dy.find_orbit(roessler, x0, T0, method=method)
        br, prob = dy.continue_orbits(orbit, "c", bounds={"c": (2.5, 3.2)})
        pd = [sp for sp in br.special_points if sp.kind == "period_doubling"]
        assert [sp.label for sp in pd] == ["PD1"], method
        doubled, dprob = dy.switch_period_doubling(prob, br, "PD1", options=dy.Options(ds=0.02, ds_max=0.2,
                                                                                         max_points=12))
        X, T2, c = dprob.split(doubled.points[-1].u)
        found[method] = (prob.split(pd[0].u)[2], c, T2, np.linalg.norm(X[0] - X[len(X) // 2]))
    (c_s, _c, _T, gap_s), (c_c, c2_c, T2_c, gap_c) = found["shooting"], found["collocation"]
    assert c_c == pytest.approx(c_s, abs=1e-8) and c_s == pytest.approx(2.8324, abs=1e-3)
    assert gap_c > 1e-2 and gap_s > 1e-2
    doubled_orbit = dy.find_orbit(roessler, dprob.split(doubled.points[-1].u)[0][0], T2_c,
                                  roessler.with_pars(c=c2_c))  # shooting from the collocation's doubled orbit
    assert doubled_orbit.converged and doubled_orbit.period == pytest.approx(T2_c, rel=1e-8)

    torus = dy.textbook_system("torus")
    orbit = dy.find_orbit(torus, [1.0, 0.0, 0.0, 0.0], 2 * math.pi, method="collocation")
    br, prob = dy.continue_orbits(orbit, "beta", bounds={"beta": (-0.1, 0.1)})
    ns = [sp for sp in br.special_points if sp.kind == "neimark_sacker"]
    assert [sp.label for sp in ns] == ["NS1"] and abs(prob.split(ns[0].u)[2]) < 1e-9
    assert ns[0].data["angle"] == pytest.approx((2 * math.pi * math.sqrt(2)) % (2 * math.pi), abs=1e-8)
    assert not [sp for sp in br.special_points if sp.kind in ("period_doubling", "fold", "branch_point")]


# ------------------------------------------------------------------------------------- the command line
def test_cli_method_options_reach_the_branch_and_misplaced_ones_are_one_line(tmp_path, capsys):
    from tippedisk_analysis.cli import main

    out = tmp_path / "ab.nc"
    assert main(["periodic-orbits", "--system", "ab", "--to", "0.1", "--period-max", "10", "--method", "collocation",
                 "--ntst", "30", "--ncol", "5", "-o", str(out)]) == 0
    ds = td.load(out)
    assert ds.attrs["method"] == "collocation" and int(ds.ntst[0]) == 30
    assert td.results.config_of(ds)["ncol"] == 5 and ds.attrs["labels"] == "PB1"  # T = 10 comes before the fold
    capsys.readouterr()
    for argv, fragment in ((["--method", "collocation", "--segments", "4"], "--segments and --phase poincare"),
                           (["--method", "shooting", "--ntst", "30"], "--ntst and --ncol are collocation options"),
                           (["--ncol", "9"], "ncol = 9")):
        bad = tmp_path / "bad.nc"
        assert main(["periodic-orbits", "--system", "ab", "--to", "0.1", *argv, "-o", str(bad)]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and fragment in err, err
        assert not bad.exists()
