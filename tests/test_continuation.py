"""Numerical continuation (dynamics/continuation.py, equilibria.py, normal_forms.py; analysis/spin_continuation.py).

First on textbook systems with known answers (a fold, a pitchfork and a transcritical branch point,
Hopf points with known first Lyapunov coefficients, a C^1 Hopf point, a line of equilibria in
normal form), then on the tippedisk, where the special points are checked against the stability
map and the normal-form coefficients against simulations of ODE Model 1.
"""

from __future__ import annotations

import math
from pathlib import Path

import heyoka as hy
import numpy as np
import pytest
import xarray as xr
from scipy.integrate import solve_ivp
from scipy.stats import ortho_group

import tippedisk_analysis as td
from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.analysis import maps, reduced
from tippedisk_analysis.analysis import spin_continuation as sc
from tippedisk_analysis.analysis import stationary as st
from tippedisk_analysis.dynamics import continuation as co
from tippedisk_analysis.dynamics import normal_forms
from tippedisk_analysis.dynamics.equilibria import EquilibriumProblem, Parameter
from tippedisk_analysis.dynamics.switching import branch_directions, switch_branch
from tippedisk_analysis.dynamics.tensors import Field
from tippedisk_analysis.models import ode
from tippedisk_analysis.solvers import taylor

DATA = Path(__file__).resolve().parents[1] / "data"


def _problem(name, variables, rhs, parameters, **kw):
    system = dy.System(name, variables, rhs, parameters)
    return EquilibriumProblem(system, [Parameter.of(system, p) for p in parameters], **kw)


def _planar_problem(fx, fy, bounds=(0.0, 2.0)):
    x, y = hy.make_vars("x", "y")
    return _problem("planar", [x, y], [fx(x, y, hy.par[0]), fy(x, y, hy.par[0])], {"p": 0.0}, bounds={0: bounds})


# ------------------------------------------------------------------------------------------- textbook


def test_palc_passes_a_fold_that_natural_continuation_cannot():
    """x' = p - 1 - x^2 + 0.1 x y, y' = x^2 - y: two equilibria for p > 1 meet in a fold at p = 1."""
    prob = _planar_problem(lambda x, y, p: p - 1 - x * x + 0.1 * x * y, lambda x, y, p: x * x - y, (0.5, 3.0))
    u0 = np.array([1.0, 1.0, 1.9])  # (x, y, p) = (1, 1, 1.9) is an equilibrium
    branch = co.continue_branch(prob, u0, co.Options(ds=0.05, ds_max=0.1), direction=-1)
    u = branch.array("u")
    assert branch.status == "completed" and u[-1, 2] == 3.0 and u[-1, 0] < 0  # round the fold, up the lower half
    folds = [sp for sp in branch.special_points if sp.kind == "fold"]
    assert len(folds) == 1 and [sp.kind for sp in branch.special_points] == ["fold"]
    fold = folds[0]
    assert abs(fold.u[2] - 1.0) < 1e-10 and abs(fold.u[0]) < 1e-8  # p = 1, x = 0
    assert abs(fold.value) < 1e-10 and abs(fold.data["a"]) == pytest.approx(1.0, rel=1e-9)
    np.testing.assert_allclose(prob.residual(fold.u), 0, atol=1e-12)
    # natural-parameter continuation (Newton at fixed p, from the previous solution) follows the upper half
    # down to the fold and stops there: it never reaches the lower half that PALC continued on
    u, p_natural = u0.copy(), 1.9
    while True:
        nxt = co.solve_at(prob, np.array([u[0], u[1], p_natural - 0.05]), 2, p_natural - 0.05)
        if nxt is None:
            break
        u, p_natural = nxt, p_natural - 0.05
    assert 1.0 <= p_natural < 1.05 and u[0] > 0


@pytest.mark.parametrize("name, fx, exact", [
    ("transcritical", lambda x, y, p: (p - 1) * x - x * x, lambda p: p - 1),
    ("pitchfork", lambda x, y, p: (p - 1) * x - x * x * x, lambda p: math.sqrt(p - 1)),
])
def test_branch_point_and_switching(name, fx, exact):
    prob = _planar_problem(fx, lambda x, y, p: x * x - y)
    trivial = co.continue_branch(prob, np.array([0.0, 0.0, 0.2]), co.Options(ds=0.05, ds_max=0.1))
    (bp,) = trivial.special_points
    assert bp.kind == "branch_point" and abs(bp.u[2] - 1.0) < 1e-10
    new = switch_branch(prob, trivial, 0)
    assert len(new) == 2  # both directions of the emanating branch
    for branch in new:
        u = branch.array("u")
        above = u[u[:, 2] > 1.2]
        if len(above):
            np.testing.assert_allclose(np.abs(above[:, 0]), [abs(exact(p)) for p in above[:, 2]], rtol=1e-8)
            np.testing.assert_allclose(above[:, 1], above[:, 0] ** 2, rtol=1e-8)  # on y = x^2
    assert any(len(b.array("u")[b.array("u")[:, 2] > 1.2]) for b in new)


def _gh_coefficient(f, g, omega):
    """Guckenheimer & Holmes (3.4.11): r' = a r^3 for x' = -omega y + f, y' = omega x + g (f, g: dicts of
    partial derivatives at 0)."""
    return (f["xxx"] + f["xyy"] + g["xxy"] + g["yyy"]) / 16 + (
        f["xy"] * (f["xx"] + f["yy"]) - g["xy"] * (g["xx"] + g["yy"]) - f["xx"] * g["xx"] + f["yy"] * g["yy"]) / (
        16 * omega)


def test_first_lyapunov_coefficient_equals_the_planar_formula_in_any_orthonormal_frame():
    """Kuznetsov's n-dimensional l1 of a planar system embedded in 3-D and rotated, against the planar
    formula: l1 = 2 a / omega (with <q, q> = 1 the radius is sqrt(2)|z|)."""
    omega = 1.7
    cf = {"xx": 0.8, "xy": -0.3, "yy": 0.5, "xxx": -1.1, "xyy": 0.4}
    cg = {"xx": -0.6, "xy": 0.9, "yy": 0.2, "xxy": 0.3, "yyy": -0.7}
    a = _gh_coefficient(cf, cg, omega)
    Q = ortho_group.rvs(3, random_state=3)
    x = hy.make_vars("x0", "x1", "x2")
    X, Y, Z = (sum(Q[k, i] * x[k] for k in range(3)) for i in range(3))  # planar coordinates of the rotated state
    f = (-omega * Y + cf["xx"] / 2 * X * X + cf["xy"] * X * Y + cf["yy"] / 2 * Y * Y + cf["xxx"] / 6 * X ** 3
         + cf["xyy"] / 2 * X * Y * Y)
    g = (omega * X + cg["xx"] / 2 * X * X + cg["xy"] * X * Y + cg["yy"] / 2 * Y * Y + cg["xxy"] / 2 * X * X * Y
         + cg["yyy"] / 6 * Y ** 3)
    h = -2.0 * Z + X * X  # a stable third direction; f and g do not depend on Z, so l1 is the planar one
    field = Field([sum(Q[k, i] * v for i, v in enumerate((f, g, h))) for k in range(3)], list(x))
    origin = np.zeros(3)
    nf = normal_forms.first_lyapunov_coefficient(field.tensor(origin, [], 1), field.tensor(origin, [], 2),
                                                 field.tensor(origin, [], 3))
    assert nf["frequency"] == pytest.approx(omega, rel=1e-12)
    assert nf["l1"] == pytest.approx(2 * a / omega, rel=1e-9)


def test_first_lyapunov_coefficient_predicts_the_limit_cycle_by_simulation():
    """Supercritical Hopf: the cycle radius sqrt(2) sqrt(-alpha / (omega l1)) near alpha = 0."""
    omega, alpha = 1.3, 0.004
    x, y = hy.make_vars("x", "y")
    fx = alpha * x - omega * y + 0.5 * x * y - x * x * x - 0.2 * x * y * y
    fy = omega * x + alpha * y - 0.3 * x * x + 0.4 * y * y - 0.8 * y * y * y
    field = Field([fx - alpha * x, fy - alpha * y], [x, y])  # the Hopf point itself (alpha = 0)
    nf = normal_forms.first_lyapunov_coefficient(*(field.tensor(np.zeros(2), [], k) for k in (1, 2, 3)))
    assert nf["l1"] < 0
    ta = hy.taylor_adaptive([(x, fx), (y, fy)], [0.05, 0.0], tol=1e-12)
    ta.propagate_until(3000.0)
    grid = np.linspace(3000.0, 3000.0 + 20 * math.pi / omega, 2000)
    r = np.hypot(*ta.propagate_grid(grid)[5].T)
    predicted = math.sqrt(2) * math.sqrt(-alpha / (omega * nf["l1"]))
    assert r.mean() == pytest.approx(predicted, rel=0.05)  # O(alpha) corrections
    assert r.max() - r.min() < 0.2 * r.mean()


@pytest.mark.slow
def test_nonsmooth_hopf_coefficient_predicts_a_c1_limit_cycle():
    """A C^1 Hopf point, w' = A w + (G w)|Gamma w|: the cycle radius grows linearly, |z| = -alpha / k."""
    omega, alpha = 1.0, 0.01
    G = np.array([[-0.4, 0.3], [0.2, -0.5]])
    Gamma = np.array([[1.0, 0.5]])
    A0 = np.array([[0.0, -omega], [omega, 0.0]])
    q = np.array([1.0, -1j]) / math.sqrt(2)
    p = q.copy()  # <p, q> = 1 for the rotation matrix
    kappa = normal_forms.nonsmooth_hopf_coefficient(q, p, lambda w: (G @ w) * np.linalg.norm(Gamma @ w))
    assert kappa.real < 0

    def rhs(_t, w):
        return (A0 + alpha * np.eye(2)) @ w + (G @ w) * np.linalg.norm(Gamma @ w)

    sol = solve_ivp(rhs, (0, 2000), [0.01, 0.0], rtol=1e-10, atol=1e-12, dense_output=True)
    late = sol.sol(np.linspace(1800, 2000, 4000))
    radius = np.hypot(*late)
    predicted = math.sqrt(2) * (-alpha / kappa.real)  # |x| = sqrt(2) |z| on a circle for this q
    assert radius.mean() == pytest.approx(predicted, rel=0.05)


def _line_normal_form_system(a, b, k, omega, rotation):
    """s' = b |y|^2, y' = [[a s, -omega], [omega, a s]] y + k |y| y, in an orthonormal frame of R^3."""

    def rhs(_t, xx):
        s, y1, y2 = rotation.T @ xx
        ny = math.hypot(y1, y2)
        ds = b * (y1 * y1 + y2 * y2)
        dy1 = a * s * y1 - omega * y2 + k * ny * y1
        dy2 = omega * y1 + a * s * y2 + k * ny * y2
        return rotation @ np.array([ds, dy1, dy2])

    return rhs


def test_line_of_equilibria_normal_form_and_the_elliptic_return():
    """Coefficients of a constructed line Hopf point (up to the normalisation |z|^2 = |y|^2 / 2), and an
    orbit leaving the line at s0 returns at s1 = -s0 exp(pi k / (2 nu)) (elliptic)."""
    a, b, k, omega = -0.8, 0.5, 0.15, 2.0
    R = ortho_group.rvs(3, random_state=5)
    x = hy.make_vars("x0", "x1", "x2")
    s_, y1, y2 = (sum(R[m, i] * x[m] for m in range(3)) for i in range(3))
    smooth = [b * (y1 * y1 + y2 * y2), a * s_ * y1 - omega * y2, omega * y1 + a * s_ * y2]
    field = Field([sum(R[m, i] * v for i, v in enumerate(smooth)) for m in range(3)], list(x))
    J, B = field.tensor(np.zeros(3), [], 1), field.tensor(np.zeros(3), [], 2)
    phi0 = R[:, 0]

    def N(w):
        y = R[:, 1:].T @ w
        return k * np.linalg.norm(y) * (R[:, 1:] @ y)

    nf = normal_forms.line_hopf(J, B, phi0, N)
    assert nf["a"] == pytest.approx(a, rel=1e-12) and nf["b"] == pytest.approx(2 * b, rel=1e-12)
    assert nf["k"] == pytest.approx(math.sqrt(2) * k, rel=1e-9) and nf["frequency"] == pytest.approx(omega)
    assert nf["class"] == "elliptic"
    s0 = -0.05  # a < 0: the unstable side is s < 0
    start = R @ np.array([s0, 1e-6, 0.0])
    sol = solve_ivp(_line_normal_form_system(a, b, k, omega, R), (0, 2000), start, method="DOP853", rtol=1e-10,
                    atol=1e-14)
    s_end = (R.T @ sol.y[:, -1])[0]
    predicted = s0 * normal_forms.elliptic_return(nf["a"], nf["b"], nf["k"])
    assert s_end == pytest.approx(predicted, rel=0.05)
    assert np.linalg.norm((R.T @ sol.y[:, -1])[1:]) < 1e-4  # back on the line


# ------------------------------------------------------------------------------------------- tippedisk

SETUP = td.Setup(friction=td.Friction(eps=0.25))


@pytest.fixture(scope="module")
def branch():
    return sc.continue_branch("inverted", "omega", 0.0, 100.0, setup=SETUP)


def _special(ds, label):
    k = [str(v) for v in ds["special_label"].values].index(label)
    return {name[len("special_"):]: ds[name].values[k] for name in ds.data_vars if name.startswith("special_")}


def test_branch_points_are_the_stationary_solutions(branch):
    """The corrector alone (no projection onto the closed form) finds the stationary solutions, and the
    stored branch's states are them."""
    prob = sc.problem(["omega"], SETUP, bounds={"omega": (20.0, 40.0)})
    prob._project = None  # Gauss-Newton on [rhs, alpha_dot - Omega] only
    free = co.continue_branch(prob, np.append(st.stationary_state("inverted", [20.0])[:, 0], 20.0))
    u = free.array("u")
    np.testing.assert_allclose(u[:, :7], st.stationary_state("inverted", u[:, 7]).T, atol=1e-10)
    assert float(u[-1, 7]) == 40.0
    assert branch.attrs["status"] == "completed" and float(branch.omega[-1]) == 100.0
    assert float(branch.residual.max()) < 1e-10
    pars = ode.parameter_vector(SETUP)
    for i in range(0, branch.sizes["point"], 9):
        omega = float(branch.omega[i])
        state = np.array([float(branch[n][i]) for n in reduced.STATE_NAMES])
        solved = st.solve(state + 1e-6, omega, pars)
        assert solved.converged
        np.testing.assert_allclose(state, solved.state, atol=1e-10)
    assert np.all(branch.lambda_N > 0)


def test_special_points_equal_the_stability_maps_critical_speeds(branch):
    """HOPF1 enters and BP1 leaves the stable window (docs/stability.md): equal to the map's brentq zeros."""
    assert [str(v) for v in branch.special_label.values] == ["HOPF1", "BP1", "HOPF2"]
    crit = maps.find_critical_speeds("inverted", np.linspace(0, 100, 201), setup=SETUP)
    hopf, bp = _special(branch, "HOPF1"), _special(branch, "BP1")
    for sp, (omega_c, direction, frequency) in zip((hopf, bp), crit[:2]):
        omega = float(branch.omega[int(sp["index"])])
        assert abs(omega - omega_c) < 1e-6
        assert abs(float(sp["value"])) < 1e-10  # the critical eigenvalue(s) on the axis
        assert float(sp["frequency"]) == pytest.approx(frequency, rel=1e-6)
    i = int(hopf["index"])
    assert abs(float(branch.eig_real[i, 0])) < 1e-8 and float(branch.eig_imag[i, 0]) == pytest.approx(3.884, abs=1e-3)
    assert int(branch.stability[int(hopf["index"]) + 1]) == 0 and int(branch.stability[int(hopf["index"]) - 1]) == 2


def _point_state(ds, label):
    sp = _special(ds, label)
    i = int(sp["index"])
    return float(ds.omega[i]), np.array([float(ds[n][i]) for n in reduced.STATE_NAMES]), sp


def _reduced_run(x0, t_end, dt):
    tr = taylor.integrate("ode-euler", SETUP, reduced.full_from_reduced(x0), t_end, dt, 1e-14, 0.1, 1e-12)
    S = tr.states
    names = ode.EULER.state_names
    idx = [names.index(n) for n in ("alpha", "beta", "gamma", "x_dot", "y_dot", "omega_x", "omega_y", "omega_z")]
    return tr, reduced.reduced_from_full(*(S[:, i] for i in idx))


def _hopf_normal_form(branch):
    omega, x, sp = _point_state(branch, "HOPF1")
    pars = ode.parameter_vector(SETUP)
    f = reduced.field()
    J, B = f.tensor(x, pars, 1)[:7, :7], f.tensor(x, pars, 2)[:7, :7, :7]
    G, Gamma = reduced.nonsmooth_split(x, pars)
    phi0 = np.eye(7)[reduced.OMEGA_X_INDEX]
    nf = normal_forms.line_hopf(J, B, phi0, lambda w: (G @ w) * np.linalg.norm(Gamma @ w))
    return omega, x, sp, nf, phi0


def test_hopf_point_drift_b_matches_the_spin_rate_drift_of_ODE_model_1(branch):
    """At the Hopf point a wobble of size |z| changes the spin rate at d Omega / dt = b |z|^2 (second order)."""
    omega, x, sp, nf, _ = _hopf_normal_form(branch)
    assert nf["b"] == pytest.approx(float(sp["b"]), rel=1e-9) and sp["class"] == sc.CLASSES["hyperbolic"]
    z0 = 0.01
    tr, _ = _reduced_run(x + 2 * (z0 * nf["q"]).real, 8.0, 1e-3)
    alpha_dot = tr.outputs[ode.OUTPUT_NAMES.index("alpha_dot")]
    period = 2 * math.pi / nf["frequency"]
    means = [alpha_dot[(tr.time >= k * period) & (tr.time < (k + 1) * period)].mean() for k in range(4)]
    slope = np.polyfit((np.arange(4) + 0.5) * period, means, 1)[0]
    assert slope == pytest.approx(nf["b"] * z0 ** 2, rel=2e-3)


def test_hopf_point_c1_coefficient_k_matches_the_amplitude_decay_of_ODE_model_1(branch):
    """r' = k r^2 at the Hopf point (the C^1 term of |gamma_T|; a smooth l1 would give r' ~ r^3)."""
    omega, x, sp, nf, phi0 = _hopf_normal_form(branch)
    assert nf["k"] == pytest.approx(float(sp["k"]), rel=1e-9) and nf["k"] < 0
    rates = []
    for z0 in (0.005, 0.01):
        tr, xr = _reduced_run(x + 2 * (z0 * nf["q"]).real, 6.0, 2e-3)
        d = xr - x[:, None]
        z = np.conj(nf["p"]) @ (d - np.outer(phi0, nf["psi0"] @ d))
        rates.append(np.polyfit(tr.time, np.log(np.abs(z)), 1)[0] / z0)
    assert rates[0] == pytest.approx(nf["k"], rel=0.01)
    assert abs(rates[0] - nf["k"]) < abs(rates[1] - nf["k"])  # converging as the amplitude -> 0


def test_zero_eigenvalue_point_is_a_repelling_node_and_orbits_leave_it(branch):
    """BP1 (a real eigenvalue through 0, Omega_c2): k^2 + 4ab > 0, k > 0: a disk spun slightly above Omega_c2
    does not return to the neighbouring stable spin but makes a large excursion (here it lands deep in the
    stable window)."""
    omega, x, sp = _point_state(branch, "BP1")
    assert sp["class"] == sc.CLASSES["repelling_node"] and float(sp["k"]) > 0 and float(sp["a"] * sp["b"]) < 0
    pars = ode.parameter_vector(SETUP)
    f = reduced.field()
    nf = normal_forms.line_transcritical(f.tensor(x, pars, 1)[:7, :7], f.tensor(x, pars, 2)[:7, :7, :7],
                                         np.eye(7)[reduced.OMEGA_X_INDEX])
    delta = 0.004
    x0 = st.stationary_state("inverted", [omega + delta])[:, 0] + 1e-4 * nf["q"]
    tr = taylor.integrate("ode-euler", SETUP, reduced.full_from_reduced(x0), 8000.0, 1.0, 1e-12, 0.1,
                          1e-12)
    alpha_dot = tr.outputs[ode.OUTPUT_NAMES.index("alpha_dot")]
    elliptic_landing = omega - delta  # where an elliptic point would return the orbit
    assert tr.status == "completed" and alpha_dot[-1] < elliptic_landing - 1.0
    assert float(branch.stability.where(np.abs(branch.omega - alpha_dot[-1]) < 0.5, drop=True).max()) == 0


@pytest.mark.slow
def test_hopf_and_zero_curves_bound_the_stable_window_as_the_stored_map_says():
    """Every critical spin speed of data/critical_speeds.nc (eps 0.14-0.36) lies on one of the curves to 1e-6."""
    stored = td.load(DATA / "critical_speeds.nc")
    curves = []
    for eps0, labels in ((0.25, ("HOPF1", "BP1", "HOPF2")),):
        ds = sc.continue_branch("inverted", "omega", 10.0, 60.0, setup=td.Setup(friction=td.Friction(eps=eps0)))
        for label in labels:
            curves.append(sc.continue_curve(ds, label, ("omega", "eps"), bounds={"eps": (0.1, 0.4),
                                                                                  "omega": (0, 100)}))
    bt = [c for c in curves if "BT1" in c.attrs["labels"]]
    assert len(bt) == 2  # the Hopf and the zero-eigenvalue curve meet in one Bogdanov-Takens point
    bts = [_special(c, "BT1") for c in bt]
    np.testing.assert_allclose(*[[float(c.omega[int(s["index"])]), float(c.eps[int(s["index"])])]
                                 for c, s in zip(bt, bts)], rtol=1e-8)
    checked = 0
    for b, branch_name in enumerate(stored.branch.values):
        if branch_name != "inverted":
            continue
        for j, eps in enumerate(stored.eps.values):
            for c in range(int(stored.n_critical[b, j])):
                omega_c = float(stored.omega_critical[b, j, c])
                assert min(_curve_omega_at(curve, eps, omega_c) for curve in curves) < 1e-6, (eps, omega_c)
                checked += 1
    assert checked >= 2 * 30


def _curve_omega_at(curve, eps, omega_c):
    """|Omega - omega_c| of the curve point at ``eps`` nearest omega_c (inf if the curve has none)."""
    e, om = curve.eps.values, curve.omega.values
    best = math.inf
    config = td.results.config_of(curve)
    prob = sc.problem(["omega", "eps"], td.Setup(friction=td.Friction(eps=0.25)), branch=config["branch"],
                      critical=config["critical"])
    for i in np.flatnonzero((e[:-1] - eps) * (e[1:] - eps) <= 0):
        w = 0.0 if e[i + 1] == e[i] else (eps - e[i]) / (e[i + 1] - e[i])  # the chord at eps (a special point such
        ends = [np.array([*(float(curve[n][j]) for n in reduced.STATE_NAMES), om[j], e[j]]) for j in (i, i + 1)]
        u = co.solve_at(prob, (1 - w) * ends[0] + w * ends[1], 8, eps)  # as HH1 at an end lies on two curves)
        if u is not None:
            best = min(best, abs(u[7] - omega_c))
    return best


def test_continuation_in_other_parameters_finds_the_same_window():
    """The Jacobian depends on mu and eps through mu/eps only: the Hopf point in mu at eps = 0.25 lies at
    mu/eps of the Hopf point in eps at mu = 0.3."""
    in_eps = sc.continue_branch("inverted", "eps", 0.25, 0.05, omega=31.0)
    in_mu = sc.continue_branch("inverted", "mu", 0.3, 1.0, setup=SETUP, omega=31.0)
    eps_h = float(in_eps.eps[int(_special(in_eps, "HOPF1")["index"])])
    mu_h = float(in_mu.mu[int(_special(in_mu, "HOPF1")["index"])])
    assert mu_h / 0.25 == pytest.approx(0.3 / eps_h, rel=1e-8)


def test_dataset_round_trip_and_labels(branch, tmp_path):
    path = td.save(branch, tmp_path / "c.nc")
    again = td.load(path)
    xr.testing.assert_identical(again, branch)
    assert again.attrs["kind"] == "continuation" and again.attrs["labels"] == "HOPF1 BP1 HOPF2"
    assert td.results.config_of(again)["options"]["ds_max"] > 0


@pytest.mark.parametrize("call, match", [
    (lambda: sc.continue_branch("inverted", "zeta", 0.1, 0.2, omega=30.0), "unknown continuation parameter"),
    (lambda: sc.continue_branch("sideways", "omega", 0.0, 10.0), "unknown branch"),
    (lambda: sc.continue_branch("inverted", "omega", 5.0, 5.0), "two different values"),
    (lambda: sc.continue_branch("inverted", "eps", 0.25, -0.1, omega=30.0), "eps"),
    (lambda: sc.continue_branch("inverted", "omega", 0.0, math.inf), "finite"),
    (lambda: sc.continue_branch("inverted", "eps", 0.25, 0.3), "give the spin rate"),
])
def test_bad_input_raises_one_clear_error(call, match):
    with pytest.raises(td.ParameterError, match=match):
        call()


def test_a_start_that_is_not_an_equilibrium_is_refused():
    prob = sc.problem(["omega"], SETUP, bounds={"omega": (0.0, 50.0)})
    state = st.stationary_state("inverted", [30.0])[:, 0] + np.array([0.3, 0.2, 0.1, 0, 0, 5.0, 0])
    with pytest.raises(td.ParameterError, match="not a solution"):
        co.continue_branch(prob, np.append(state, 30.0), co.Options(max_newton=2))


def test_a_label_that_is_not_in_the_dataset_is_refused(branch):
    with pytest.raises(td.ParameterError, match="no special point 'HOPF7'"):
        sc.continue_curve(branch, "HOPF7")


def test_no_branch_of_other_equilibria_emanates_from_the_zero_eigenvalue_point():
    """At BP1 the kernel and the cokernel are two-dimensional (the family's structural zero and the crossing
    eigenvalue); the two algebraic bifurcation equations share only the family's own tangent, so branch
    switching finds nothing - as it must: every equilibrium has zero slip, hence S on the vertical through C1
    and e_x^B vertical (stationary.py), i.e. only the two families exist."""
    prob = sc.problem(["omega"], SETUP, bounds={"omega": (20.0, 40.0)})
    branch = co.continue_branch(prob, np.append(st.stationary_state("inverted", [20.0])[:, 0], 20.0))
    k = [sp.kind for sp in branch.special_points].index("branch_point")
    sp = branch.special_points[k]
    switch = branch_directions(prob, branch.points[sp.index], branch.points[sp.index - 1].tangent)
    assert switch.cokernel.shape[1] == 2
    c = switch.coefficients
    assert np.all(np.abs(c[:, 0, 0]) < 1e-12 * np.abs(c).max())  # the family's tangent solves both equations
    ratios = [c[m, 1, 1] / (2 * c[m, 0, 1]) for m in range(2)]  # each has one other root alpha/beta = -c22/(2 c12)
    assert abs(ratios[0] - ratios[1]) > 0.5 * max(map(abs, ratios))  # and they differ: no common second root
    assert switch.directions == [] and switch_branch(prob, branch, k) == []


def test_stored_continuation_datasets_are_reproduced(branch):
    """data/continuation/ (study continuation) holds what the package computes today."""
    stored = td.load(DATA / "continuation" / "continuation_inverted.nc")
    assert [str(v) for v in stored.special_label.values] == [str(v) for v in branch.special_label.values]
    for name in ("special_a", "special_b", "special_k", "special_frequency"):
        np.testing.assert_allclose(stored[name].values, branch[name].values, rtol=1e-7, atol=1e-12)
    stored_curve = td.load(DATA / "continuation" / "continuation_curve_HOPF1.nc")
    curve = sc.continue_curve(branch, "HOPF1", ("omega", "eps"), bounds={"eps": (0.1, 0.4), "omega": (0, 100)})
    assert curve.attrs["labels"] == stored_curve.attrs["labels"] == "BT1 HH1"
    for label in ("BT1", "HH1"):
        i, j = int(_special(curve, label)["index"]), int(_special(stored_curve, label)["index"])
        for name in ("omega", "eps"):
            assert float(curve[name][i]) == pytest.approx(float(stored_curve[name][j]), rel=1e-8)
    i = int(_special(curve, "BT1")["index"])
    assert (float(curve.omega[i]), float(curve.eps[i])) == pytest.approx((28.583595, 0.33645952), abs=1e-6)


def test_branch_through_a_point_of_a_dataset_equals_the_branch_from_the_stationary_solution(branch):
    """From HOPF1 of the Omega branch in eps (Omega fixed there) = a branch in eps at that Omega."""
    through = sc.continue_from_point(branch, "HOPF1", "eps", 0.1)
    omega = float(branch.omega[int(_special(branch, "HOPF1")["index"])])
    assert np.all(through.omega.values == omega) and float(through.eps[0]) == 0.25
    direct = sc.continue_branch("inverted", "eps", 0.25, 0.1, setup=SETUP, omega=omega)
    far = [sp for sp in ("HOPF2", "HOPF1") if sp in direct.attrs["labels"].split()]
    assert far, direct.attrs["message"]
    for label in direct.attrs["labels"].split():
        eps_direct = float(direct.eps[int(_special(direct, label)["index"])])
        if abs(eps_direct - 0.25) > 1e-6:  # (the start itself is a Hopf point)
            eps_through = [float(through.eps[int(i)]) for i in through.special_index.values]
            assert min(abs(e - eps_direct) for e in eps_through) < 1e-9


def _bt_normal_form_problem(critical):
    """x' = y, y' = b1 + b2 x + x^2 - x y: fold curve b1 = b2^2/4, Hopf curve b1 = 0 (b2 < 0), BT at (0, 0)."""
    x, y = hy.make_vars("x", "y")
    b1, b2 = hy.par[0], hy.par[1]
    return _problem("bt_normal_form", [x, y], [y, b1 + b2 * x + x * x - x * y], {"b1": 0.0, "b2": 0.0},
                    bounds={0: (-1.0, 1.0), 1: (-1.5, 1.5)}, critical=critical)


@pytest.mark.parametrize("critical, start", [("zero", (0.5, 0.0, 0.25, -1.0)), ("hopf", (0.0, 0.0, 0.0, -1.0))])
def test_bogdanov_takens_point_of_the_normal_form_and_no_false_codim2_points(critical, start):
    """Both the fold and the Hopf curve of the BT normal form meet at (b1, b2) = (0, 0); nothing else is
    reported on them (a cusp test through a pole, a jumping eigenvalue order would give false points)."""
    branch = co.continue_both_ways(_bt_normal_form_problem(critical), np.array(start), co.Options(ds=0.02, ds_max=0.05))
    kinds = [sp.kind for sp in branch.special_points]
    assert kinds == ["bogdanov_takens"], (kinds, branch.message)
    np.testing.assert_allclose(branch.special_points[0].u[2:], [0.0, 0.0], atol=1e-8)
    u = branch.array("u")
    if critical == "zero":
        np.testing.assert_allclose(u[:, 2], u[:, 3] ** 2 / 4, atol=1e-10)  # on the fold curve b1 = b2^2/4


def test_a_neutral_saddle_is_not_a_double_hopf_point():
    """Along the Hopf curve mu = 0 of a 4-D system, the other block's real eigenvalues nu +- sqrt(2) sum to 0
    at nu = 0: the bialternate test vanishes there, but no second pair is on the axis."""
    x = hy.make_vars("x0", "x1", "x2", "x3")
    mu, nu = hy.par[0], hy.par[1]
    r2 = x[0] * x[0] + x[1] * x[1]
    prob = _problem("hopf_times_saddle", list(x), [mu * x[0] - x[1] - x[0] * r2, x[0] + mu * x[1] - x[1] * r2,
                                                   nu * x[2] + 2 * x[3], x[2] + nu * x[3]],
                    {"mu": 0.0, "nu": -0.5}, bounds={1: (-0.5, 0.5)}, critical="hopf")
    branch = co.continue_branch(prob, np.array([0, 0, 0, 0, 0.0, -0.5]), co.Options(ds=0.02, ds_max=0.05),
                                tangent=np.array([0, 0, 0, 0, 0, 1.0]))
    assert float(branch.array("u")[-1, 5]) == 0.5 and not branch.special_points, branch.message


def test_plot_options_observable_and_background(branch, tmp_path, capsys):
    from tippedisk_analysis.cli import main

    td.save(branch, tmp_path / "c.nc")
    assert main(["plot", str(tmp_path / "c.nc"), "--observable", "lambda_N", "-o", str(tmp_path / "c.png")]) == 0
    assert (tmp_path / "c.png").stat().st_size > 10_000
    assert main(["plot", str(tmp_path / "c.nc"), "--observable", "zeta", "-o", str(tmp_path / "x.png")]) == 2
    assert "no observable 'zeta'" in capsys.readouterr().err and not (tmp_path / "x.png").exists()
    curve = td.load(DATA / "continuation" / "continuation_curve_BP1.nc")
    td.save(curve, tmp_path / "z.nc")
    td.save(maps.stability_map(np.linspace(25, 40, 16), np.linspace(0.15, 0.35, 9), critical=False),
            tmp_path / "m.nc")
    assert main(["plot", str(tmp_path / "z.nc"), "--over", str(tmp_path / "m.nc"), "-o", str(tmp_path / "z.png")]) == 0
    assert main(["plot", str(tmp_path / "z.nc"), "--over", str(tmp_path / "c.nc"), "-o", str(tmp_path / "y.png")]) == 2
    assert "give a stability map" in capsys.readouterr().err
