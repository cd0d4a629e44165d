"""Every analysis of :mod:`tippedisk_analysis.dynamics` on systems a user declares (``tests/zoo.py``), none of
them in the catalogue, with the settings a user would pick: each answer is checked against an exact result or
scipy's DOP853 at 1e-12, and a wrong answer must not pass as ``completed``."""

from __future__ import annotations

import copy
import math

import heyoka as hy
import numpy as np
import pytest
from scipy.optimize import brentq

import tippedisk_analysis as td
import zoo
from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.errors import ParameterError

EQUILIBRIUM, PERIODIC, IRREGULAR = 0, 1, 2


def labels(ds) -> dict[str, int]:
    """The negative labels of a basins dataset by name."""
    meanings = ds.outcome.attrs["flag_meanings"].split()
    return {m: int(v) for m, v in zip(meanings, ds.outcome.attrs["flag_values"]) if v < 0}


def starts(axes: dict) -> np.ndarray:
    """The initial conditions of ``axes`` as dy.basins lays them out: (len(axes), n1, n2)."""
    return np.array(np.meshgrid(*(np.linspace(*a) for a in axes.values()), indexing="ij"))


# ------------------------------------------------------------------------------- integer powers
def test_integer_powers_integrate_from_an_exact_zero():
    """heyoka's recursion of x**3 divides by x: a run from x = 0 exactly gave NaN. The System's integrator
    runs, and the right-hand side is unchanged (the rewrite is the same polynomial)."""
    s = dy.System("cubic", [zoo.x, zoo.y], [zoo.y, -zoo.x**3 - (zoo.x + zoo.y) ** 5])
    ta = copy.copy(s.taylor(1e-14))
    ta.state[:] = [0.0, 1e-3]
    outcome = ta.propagate_until(1.0)[0]
    assert str(outcome) == "taylor_outcome.time_limit" and np.all(np.isfinite(ta.state))
    run = zoo.reference_run(lambda t, u: [u[1], -u[0] ** 3 - (u[0] + u[1]) ** 5], [0.0, 1e-3], 1.0)
    np.testing.assert_allclose(ta.state, run.y[:, -1], rtol=1e-10, atol=1e-16)
    X = np.random.default_rng(1).normal(size=(2, 50))
    np.testing.assert_allclose(s.f(X), [X[1], -X[0] ** 3 - (X[0] + X[1]) ** 5], rtol=1e-14)
    assert s.equations()[1].count("**") == 2  # the declaration is shown as written


def test_duffing_vdp_basins_from_41x41_starts_have_no_failed_column():
    """The issue's grid of 41 x 41 starts holds the column x = 0 exactly: every run is decided (the one start at
    the unstable origin is undecided, with its reason)."""
    s = zoo.duffing_vdp(1.0)
    axes = {"x": (-3.0, 3.0, 41), "y": (-3.0, 3.0, 41)}
    ds = dy.basins(s, dy.Grid(("x", "y"), (-4, -6), (4, 6), (80, 120)), axes, horizon=200.0, progress=False)
    lab = labels(ds)
    out = ds.outcome.values
    assert not np.any(out == lab["failed"])
    assert ds.sizes["attractor"] == 1 and int(ds.attractor_kind[0]) == PERIODIC
    origin = (starts(axes)[0] == 0) & (starts(axes)[1] == 0)
    assert np.all(out[~origin] == 0) and out[origin] == lab["undecided"]
    assert ds.rejection.values[origin][0] == 1 + dy.attractors.system_problem.SystemProblem.rejection_reasons.index(
        "unstable_equilibrium")


# ------------------------------------------------------------------------------- attractors
@pytest.mark.parametrize("mu, grid", [
    (1.0, ((-4, -6), (4, 6), (80, 120))),  # the grid
    (1.0, ((-3, -3), (3, 3), (30, 30))),  # coarse
    (2.0, ((-4, -6), (4, 6), (80, 120))),
    (2.0, ((-5, -8), (5, 8), (200, 160))),  # fine
])
def test_duffing_vdp_has_one_periodic_attractor_for_any_grid(mu, grid):
    """The slow part of the cycle is no equilibrium: the only attractor is the cycle, its period equal to scipy's
    return time, its state on the cycle (the right-hand side there is far from zero)."""
    s = zoo.duffing_vdp(mu)
    ds = dy.basins(s, dy.Grid(("x", "y"), *grid), {"x": (-3.0, 3.0, 40), "y": (-3.0, 3.0, 40)}, horizon=200.0,
                   progress=False)
    assert ds.attrs["status"] == "completed"
    assert ds.sizes["attractor"] == 1 and int(ds.attractor_kind[0]) == PERIODIC
    reference = zoo.reference_period(zoo.duffing_vdp_rhs(mu), [2.0, 0.0], 100.0)
    assert float(ds.attractor_period[0]) == pytest.approx(reference, rel=1e-9)
    assert np.all(ds.outcome.values == 0)  # no start of this grid is the origin
    state = ds.attractor_state.values[0]
    run = zoo.reference_run(zoo.duffing_vdp_rhs(mu), state, reference)
    np.testing.assert_allclose(run.y[:, -1], state, atol=1e-7)  # it closes after one period


def test_duffing_vdp_escapes_are_diverged_not_failed():
    """mu = -0.5: the origin attracts inside an unstable cycle; outside it runs blow up in finite time and are
    labelled diverged (a label of starts, not an attractor)."""
    s = zoo.duffing_vdp(-0.5)
    ds = dy.basins(s, dy.Grid(("x", "y"), (-4, -6), (4, 6), (80, 120)), {"x": (-3.0, 3.0, 40), "y": (-3.0, 3.0, 40)},
                   horizon=200.0, progress=False)
    lab = labels(ds)
    out = ds.outcome.values
    assert ds.sizes["attractor"] == 1 and int(ds.attractor_kind[0]) == EQUILIBRIUM
    np.testing.assert_allclose(ds.attractor_state.values[0], [0.0, 0.0], atol=1e-12)
    assert np.sum(out == lab["diverged"]) > 0 and not np.any(out == lab["failed"])
    assert not np.any(out == lab["undecided"])
    # every start that stays is inside the unstable cycle: scipy from the same starts stays bounded
    grid = starts({"x": (-3.0, 3.0, 40), "y": (-3.0, 3.0, 40)})
    for i, j in np.argwhere(out == 0)[::37]:
        run = zoo.reference_run(zoo.duffing_vdp_rhs(-0.5), grid[:, i, j], 60.0)
        assert run.success and np.max(np.abs(run.y[:, -1])) < 1e-3


@pytest.mark.parametrize("mu", [1.0, 5.0, 10.0])
def test_van_der_pol_relaxation_cycles_at_three_stiffness_levels(mu):
    """The recurrence window (5 time units) is shorter than the cycles (6.7, 11.6, 19.1): the cycle is still the
    one attractor of every start but the unstable origin, with scipy's period."""
    s = zoo.van_der_pol(mu)
    grid = dy.Grid(("x", "y"), (-3, -3 * mu - 3), (3, 3 * mu + 3), (60, 60))
    axes = {"x": (-2.5, 2.5, 21), "y": (-2.5, 2.5, 21)}
    ds = dy.basins(s, grid, axes, horizon=300.0, progress=False)
    assert ds.sizes["attractor"] == 1 and int(ds.attractor_kind[0]) == PERIODIC
    origin = (starts(axes)[0] == 0) & (starts(axes)[1] == 0)
    assert np.all(ds.outcome.values[~origin] == 0) and ds.outcome.values[origin] == labels(ds)["undecided"]
    reference = zoo.reference_period(zoo.vdp_rhs(mu), [2.0, 0.0], 100.0)
    assert float(ds.attractor_period[0]) == pytest.approx(reference, rel=1e-9)


def test_bautin_equilibrium_inside_a_cycle_basin_fractions_are_exact():
    """A stable origin inside the unstable cycle r_u, the stable cycle r_s outside: a start belongs to the origin
    exactly when its radius is below r_u."""
    s = zoo.bautin(-0.5)
    axes = {"x": (-1.5, 1.5, 31), "y": (-1.5, 1.5, 31)}
    ds = dy.basins(s, dy.Grid(("x", "y"), (-2, -2), (2, 2), (50, 50)), axes, horizon=200.0, progress=False)
    r_u, r_s = zoo.bautin_radii(-0.5)
    kinds = ds.attractor_kind.values
    assert sorted(kinds) == [EQUILIBRIUM, PERIODIC]
    eq, cyc = int(np.flatnonzero(kinds == EQUILIBRIUM)[0]), int(np.flatnonzero(kinds == PERIODIC)[0])
    radius = np.hypot(*starts(axes))
    np.testing.assert_array_equal(ds.outcome.values == eq, radius < r_u)
    np.testing.assert_array_equal(ds.outcome.values == cyc, radius > r_u)
    assert float(ds.attractor_period[cyc]) == pytest.approx(2 * math.pi, rel=1e-10)
    assert np.hypot(*ds.attractor_state.values[cyc]) == pytest.approx(r_s, rel=1e-9)


def test_escape_to_infinity_and_starts_on_the_saddle_line():
    """x' = -x + x^3: |x| < 1 to the origin, |x| > 1 diverged, |x| = 1 exactly stays on the saddle (undecided,
    an unstable equilibrium), never an attractor of its own."""
    axes = {"x": (-1.5, 1.5, 31), "y": (-1.0, 1.0, 5)}
    ds = dy.basins(zoo.escape(), dy.Grid(("x", "y"), (-2, -2), (2, 2), (40, 40)), axes, horizon=100.0,
                   progress=False)
    lab = labels(ds)
    x0 = starts(axes)[0]
    out = ds.outcome.values
    assert ds.sizes["attractor"] == 1 and int(ds.attractor_kind[0]) == EQUILIBRIUM
    np.testing.assert_array_equal(out == 0, np.abs(x0) < 1 - 1e-12)
    np.testing.assert_array_equal(out == lab["diverged"], np.abs(x0) > 1 + 1e-12)
    np.testing.assert_array_equal(out == lab["undecided"], np.abs(np.abs(x0) - 1) <= 1e-12)


@pytest.mark.slow
@pytest.mark.parametrize("system, axes, grid, reference", [
    (zoo.pendulum(0.1), {"x": (-3.0, 3.0, 9), "y": (-2.5, 2.5, 9)}, ((-10, -4), (10, 4), (80, 40)),
     lambda t, u: [u[1], -0.1 * u[1] - math.sin(u[0])]),
    (zoo.double_well(0.15), {"x": (-1.5, 1.5, 9), "y": (-1.5, 1.5, 9)}, ((-2, -2), (2, 2), (40, 40)),
     lambda t, u: [u[1], -0.15 * u[1] + u[0] - u[0] ** 3]),
])
def test_slow_spirals_end_in_the_equilibrium_scipy_finds(system, axes, grid, reference):
    """Slowly damped spirals (decay rates 0.05 and 0.075 against a 5-unit window): every start is assigned the
    equilibrium that scipy's run from it ends at (or left_grid where scipy's run leaves the grid), and each
    attractor is an exact equilibrium."""
    ds = dy.basins(system, dy.Grid(("x", "y"), *grid), axes, horizon=400.0, progress=False)
    assert np.all(ds.attractor_kind.values == EQUILIBRIUM)
    for state in ds.attractor_state.values:
        assert np.max(np.abs(system.f(state))) < 1e-12
    x0 = starts(axes)
    (x_low, y_low), (x_high, y_high), _cells = grid
    for i, j in np.ndindex(ds.outcome.shape):
        run = zoo.reference_run(reference, x0[:, i, j], 250.0, max_step=0.1)
        k = int(ds.outcome.values[i, j])
        if k == labels(ds)["left_grid"]:
            assert run.y[0].min() < x_low or run.y[0].max() > x_high or run.y[1].min() < y_low \
                or run.y[1].max() > y_high
            continue
        if k == labels(ds)["undecided"]:  # a start exactly on the saddle stays there
            assert np.all(system.f(x0[:, i, j]) == 0) and np.all(run.y[:, -1] == x0[:, i, j])
            continue
        assert k >= 0, (x0[:, i, j], k)
        np.testing.assert_allclose(ds.attractor_state.values[k], run.y[:, -1], atol=1e-3)


def test_damped_oscillator_slow_spiral_is_its_equilibrium():
    """x'' + 0.04 x' + x = 0 decays by 10 % per window: every start ends at the origin, exactly."""
    ds = dy.basins(zoo.damped_oscillator(), dy.Grid(("x", "y"), (-3, -3), (3, 3), (60, 60)),
                   {"x": (-2.0, 2.0, 9), "y": (-2.0, 2.0, 9)}, horizon=600.0, progress=False)
    assert ds.sizes["attractor"] == 1 and int(ds.attractor_kind[0]) == EQUILIBRIUM
    assert np.all(ds.outcome.values == 0)
    np.testing.assert_allclose(ds.attractor_state.values[0], 0.0, atol=1e-12)


def test_lorenz_symmetric_pair_and_starts_on_the_symmetry_axis():
    """rho = 15: the stable pair C+- swapped by (x, y) -> -(x, y); starts on the z-axis (x = y = 0 exactly) stay
    on it and end at the saddle origin: undecided, not an attractor."""
    s = zoo.lorenz(15.0)
    axes = {"x": (-10.0, 10.0, 5), "y": (-10.0, 10.0, 5)}
    ds = dy.basins(s, dy.Grid(("x", "y", "z"), (-25, -25, 0), (25, 25, 40), (25, 25, 20)), axes, state=[0, 0, 10],
                   horizon=300.0, progress=False)
    c = math.sqrt(8 / 3 * 14)
    assert ds.sizes["attractor"] == 2 and np.all(ds.attractor_kind.values == EQUILIBRIUM)
    np.testing.assert_allclose(sorted(ds.attractor_state.values.tolist()), [[-c, -c, 14.0], [c, c, 14.0]],
                               atol=1e-10)
    out = ds.outcome.values
    assert out[2, 2] == labels(ds)["undecided"]
    x_end = ds.attractor_state.values[:, 0]
    for i, j in np.ndindex(5, 5):  # the symmetric start ends on the symmetric equilibrium
        if (i, j) != (2, 2):
            assert x_end[out[4 - i, 4 - j]] == pytest.approx(-x_end[out[i, j]], rel=1e-12)


def test_a_period_four_orbit_is_periodic_not_irregular():
    """Roessler at c = 4 winds four times before it closes: the latest near return is a neighbouring strand.
    The attractor is the period-4 orbit, its period the sum of scipy's four return times."""
    s = zoo.roessler(4.0)
    ds = dy.basins(s, dy.Grid(("x", "y", "z"), (-10, -10, 0), (10, 10, 20), (40, 40, 40)),
                   {"x": (-3.0, 3.0, 4), "y": (-3.0, 3.0, 4)}, horizon=400.0, progress=False)
    assert ds.sizes["attractor"] == 1 and int(ds.attractor_kind[0]) == PERIODIC and np.all(ds.outcome.values == 0)
    section = lambda t, u: u[1]  # noqa: E731
    section.direction = -1
    rhs = lambda t, u: [-u[1] - u[2], u[0] + 0.2 * u[1], 0.2 + u[2] * (u[0] - 4.0)]  # noqa: E731
    run = zoo.reference_run(rhs, [1.0, 1.0, 0.0], 1000.0, events=section)
    returns = np.diff(run.t_events[0][-9:])
    np.testing.assert_allclose(returns[:4], returns[4:], rtol=1e-7)  # period 4
    assert float(ds.attractor_period[0]) == pytest.approx(returns[:4].sum(), rel=1e-8)


@pytest.mark.slow
def test_chen_chaos_is_irregular_with_a_positive_exponent():
    """Chen's attractor: the one attractor is irregular, its largest Lyapunov exponent positive and the sum of
    the spectrum the constant divergence -a - b + c = -10."""
    s = zoo.chen()
    ds = dy.basins(s, dy.Grid(("x", "y", "z"), (-40, -40, 0), (40, 40, 60), (40, 40, 30)),
                   {"x": (-5.0, 5.0, 4), "y": (-5.0, 5.0, 4)}, state=[0, 0, 20], horizon=200.0, progress=False)
    assert ds.sizes["attractor"] == 1 and int(ds.attractor_kind[0]) == IRREGULAR and np.all(ds.outcome.values == 0)
    ly = dy.lyapunov_spectrum(s, ds.attractor_state.values[0], t_end=400.0, dt=1.0, transient=20.0)
    exponents = ly.exponents.values
    assert exponents[0] > 1.0 and abs(exponents[1]) < 0.05
    assert exponents.sum() == pytest.approx(-10.0, abs=0.02)


def test_thomas_weak_chaos_sums_to_its_divergence_and_a_short_run_says_it_has_not_converged():
    """Thomas' system: the divergence is -3b everywhere, so the spectrum's sum is -3b along any run; its largest
    exponent (about 0.005) is too small to settle in 3000 time units, and the run says so instead of `completed`."""
    b = 0.208186
    ly = dy.lyapunov_spectrum(zoo.thomas(b), [0.1, 0.0, -0.1], t_end=3000.0, dt=1.0, transient=200.0)
    assert float(ly.divergence_mean) == pytest.approx(-3 * b, rel=1e-12)
    assert ly.exponents.values.sum() == pytest.approx(-3 * b, rel=1e-9)
    assert ly.attrs["status"] == "not_converged" and "t_end" in ly.attrs["message"]
    assert np.all(ly.exponent_error.values > 0)


# ------------------------------------------------------------------------- continuation and orbits
def test_conservative_hopf_point_is_degenerate_and_its_family_vertical():
    """Duffing-van der Pol at mu = 0 is conservative: its Hopf point has l1 = 0 (flagged degenerate), and the
    orbit branch from it ends with status degenerate after a few orbits, all at mu = 0, with a short message."""
    s = zoo.duffing_vdp()
    eq = dy.equilibrium_branch(s, [0.0, 0.0], "mu", bounds=(-1.0, 1.0), pars=s.with_pars(mu=-0.5))
    assert eq.attrs["status"] == "completed" and list(eq.special_label.values) == ["HOPF1"]
    assert float(eq.mu[int(eq.special_index[0])]) == pytest.approx(0.0, abs=1e-14)
    assert int(eq.special_degenerate[0]) == 1
    for method in ("collocation", "shooting"):
        po = dy.orbit_branch(s, eq, "HOPF1", bounds=(-1.0, 1.0), method=method)
        assert po.attrs["status"] == "degenerate" and "vertical family" in po.attrs["message"], method
        # the family's mu: the round-off of the orbit equations (collocation: of its discretised ones)
        drift = {"collocation": 1e-10, "shooting": 1e-12}[method]
        assert po.sizes["point"] < 100 and np.max(np.abs(po.mu.values)) < drift
    assert len(po.attrs["message"]) < 600


def test_generalised_hopf_point_is_flagged_but_its_branch_is_regular():
    """r' = r (mu - r^4): l1 = 0 at mu = 0 but no centre: flagged degenerate, and its orbit branch is the real
    one, radius mu^(1/4), period 2 pi, reaching the bound."""
    s = zoo.generalised_hopf()
    eq = dy.equilibrium_branch(s, [0.0, 0.0], "mu", bounds=(-0.1, 0.2))
    assert int(eq.special_degenerate[0]) == 1
    po = dy.orbit_branch(s, eq, "HOPF1", bounds=(-0.1, 0.2), marks=(0.1,))
    assert po.attrs["status"] == "completed"
    k = int(po.special_index.values[list(po.special_label.values).index("UZ1")])
    assert float(po.period[k]) == pytest.approx(2 * math.pi, rel=1e-9)
    assert np.hypot(*po.initial_state.values[k]) == pytest.approx(0.1**0.25, rel=1e-8)


def test_a_hopf_point_where_the_field_is_only_c1_says_so_and_its_cycles_grow_linearly():
    """r' = r (mu - r): the field has a kink at the origin, so l1 (which assumes C^2) does not apply. The Hopf
    point is flagged special_smooth = 0 with l1 stored 0 and a note in the message; the orbits from it are the
    exact ones, radius mu, period 2 pi, stable."""
    s = zoo.c1_hopf()
    eq = dy.equilibrium_branch(s, [0.0, 0.0], "mu", bounds=(-0.1, 0.2))
    assert list(eq.special_label.values) == ["HOPF1"] and abs(float(eq.mu[int(eq.special_index[0])])) < 1e-12
    assert int(eq.special_smooth[0]) == 0 and float(eq.special_l1[0]) == 0.0
    assert "the field has a kink there" in eq.attrs["message"]
    po = dy.orbit_branch(s, eq, "HOPF1", bounds=(-0.1, 0.2), marks=(0.1,))
    k = int(po.special_index.values[list(po.special_label.values).index("UZ1")])
    assert float(po.period[k]) == pytest.approx(2 * math.pi, rel=1e-9)
    assert np.hypot(*po.initial_state.values[k]) == pytest.approx(0.1, rel=1e-8)
    assert int(po.stability[k]) == dy.STABILITY["stable"]


def test_a_hopf_point_where_the_field_is_c2_but_not_c3_gets_no_l1():
    """l1 takes third derivatives; here they jump (3 relu(x)^3), and the one-sided value would give the wrong sign."""
    eq = dy.equilibrium_branch(zoo.c2_hopf(), [0.0, 0.0], "mu", bounds=(-0.5, 0.5))
    assert list(eq.special_label.values) == ["HOPF1"] and list(eq.special_smooth.values) == [0]


def test_smooth_hopf_points_are_not_flagged():
    for s, state in ((zoo.bautin(), [0.0, 0.0]), (zoo.generalised_hopf(), [0.0, 0.0])):
        eq = dy.equilibrium_branch(s, state, "mu", bounds=(-0.1, 0.2), pars=s.with_pars(mu=-0.1))
        assert list(eq.special_smooth.values) == [1], s.name


def test_a_smooth_model_with_tiny_states_keeps_its_l1():
    """Predator-prey densities of size 1e-5, no state scale given: smooth, and l1 = l1(size 1) / size^2 (l1 has
    units of a rate per state squared), supercritical as the paradox of enrichment is."""
    l1 = {}
    for size in (1.0, 1e-5):
        xs = 0.2 * size / 0.3  # X* = 2/3
        eq = dy.equilibrium_branch(zoo.predator_prey(size), [xs, (1 - xs / (2 * size)) * (size + xs)], "mu",
                                   bounds=(2.0, 5.0))
        assert list(eq.special_label.values) == ["HOPF1"] and list(eq.special_smooth.values) == [1]
        assert float(eq.mu[int(eq.special_index[0])]) == pytest.approx(7 / 3, rel=1e-10)
        l1[size] = float(eq.special_l1[0])
    assert l1[1.0] < 0 and l1[1e-5] == pytest.approx(l1[1.0] / 1e-10, rel=1e-6)


def test_integer_powers_beside_a_function_sympy_cannot_read_are_refused_by_name():
    with pytest.raises(ParameterError, match=r"write them as products, e.g. x\*x\*x"):
        dy.System("relu_cube", [zoo.x, zoo.y], [hy.relu(zoo.x) ** 3, zoo.x], parameters={"mu": 0.0})


def test_subcritical_hopf_point_and_its_unstable_orbits():
    """Bautin with mu free: the Hopf point at mu = 0 is subcritical (l1 > 0, not degenerate); its orbits exist for
    mu < 0 with radius r_u and are unstable, the branch turning at the fold of cycles mu = -1."""
    s = zoo.bautin()
    eq = dy.equilibrium_branch(s, [0.0, 0.0], "mu", bounds=(-1.5, 0.5), pars=s.with_pars(mu=-1.5))
    assert list(eq.special_label.values) == ["HOPF1"] and float(eq.special_l1[0]) > 0
    assert int(eq.special_degenerate[0]) == 0
    po = dy.orbit_branch(s, eq, "HOPF1", bounds=(-1.5, 0.5), marks=(-0.5,))
    assert "LP1" in po.special_label.values
    fold = int(po.special_index.values[list(po.special_label.values).index("LP1")])
    assert float(po.mu[fold]) == pytest.approx(-1.0, abs=1e-8)
    k = int(po.special_index.values[list(po.special_label.values).index("UZ1")])
    assert np.hypot(*po.initial_state.values[k]) == pytest.approx(zoo.bautin_radii(-0.5)[0], rel=1e-8)
    assert int(po.stability[k]) == 2  # unstable


def test_a_shooting_branch_into_a_canard_explosion_says_it_stalled():
    """eps = 0.05: from the Hopf point a = 1 the orbits grow within ~1e-9 of a = 0.9935 (the canard explosion);
    shooting creeps there (collocation goes through: tests/test_collocation.py). The branch says so (status
    stalled, not completed), and its last orbit is right: its period is scipy's return time from its own state."""
    s = zoo.canard()
    eq = dy.equilibrium_branch(s, [1.2, 1.2**3 / 3 - 1.2], "a", bounds=(0.0, 1.2), direction=-1)
    assert list(eq.special_label.values) == ["HOPF1"] and float(eq.special_l1[0]) < 0
    assert float(eq.a[int(eq.special_index[0])]) == pytest.approx(1.0, abs=1e-12)
    po = dy.orbit_branch(s, eq, "HOPF1", bounds=(0.0, 1.2), method="shooting")
    assert po.attrs["status"] == "stalled" and "canard" in po.attrs["message"]
    a, T, state = float(po.a[-1]), float(po.period[-1]), po.initial_state.values[-1]
    assert 0.99 < a < 1.0
    run = zoo.reference_run(lambda t, u: [(u[1] - u[0] ** 3 / 3 + u[0]) / 0.05, a - u[0]], state, T)
    np.testing.assert_allclose(run.y[:, -1], state, atol=1e-6)


def test_selkov_hopf_points_equal_the_trace_condition():
    """Sel'kov (a = 0.08): the equilibrium (b, b / (a + b^2)) loses stability where the trace of its Jacobian,
    -1 + 2 b^2 / (a + b^2) - (a + b^2), vanishes: two Hopf points, located to 1e-9."""
    a = 0.08
    trace = lambda b: -1 + 2 * b**2 / (a + b**2) - (a + b**2)  # noqa: E731
    roots = [brentq(trace, 0.2, 0.6), brentq(trace, 0.6, 1.2)]
    s = zoo.selkov(0.2)
    eq = dy.equilibrium_branch(s, [0.2, 0.2 / (a + 0.04)], "b", bounds=(0.2, 1.2))
    hopf = sorted(float(eq.b[int(i)]) for i, k in zip(eq.special_index.values, eq.special_label.values)
                  if k.startswith("HOPF"))
    np.testing.assert_allclose(hopf, roots, atol=1e-9)


def test_continue_orbits_takes_a_bounds_pair_and_finds_the_least_period():
    """The issue's call: dy.continue_orbits(orbit, "mu", bounds=(0.01, 2.0)). A period guess near twice the
    period gives the orbit of its least period (scipy's), and the branch reaches the bound."""
    s = zoo.duffing_vdp(1.0)
    reference = zoo.reference_period(zoo.duffing_vdp_rhs(1.0), [2.0, 0.0], 100.0)
    orbit = dy.find_orbit(s, [1.6043, -1.3379], 6.6)  # van der Pol's period as a guess: near 1.6 T
    assert orbit.converged and orbit.period == pytest.approx(reference, rel=1e-10)
    br, _prob = dy.continue_orbits(orbit, "mu", bounds=(0.01, 2.0))
    assert br.status == "completed" and "bound mu = 2" in br.message
    assert not any(sp.kind == "hopf" for sp in br.special_points)


@pytest.mark.slow
def test_fitzhugh_nagumo_relaxation_cycle_by_every_analysis():
    """The slow-fast FitzHugh-Nagumo cycle: basins, shooting, the Poincaré section's return time and the
    Lyapunov spectrum (0 and the Floquet exponent) agree with scipy's period."""
    s = zoo.fitzhugh_nagumo()
    reference = zoo.reference_period(zoo.fhn_rhs(0.08), [1.0, 0.0], 300.0)
    ds = dy.basins(s, dy.Grid(("x", "y"), (-3, -1), (3, 3), (60, 40)), {"x": (-2.5, 2.5, 8), "y": (-0.5, 2.0, 8)},
                   horizon=500.0, progress=False)
    assert ds.sizes["attractor"] == 1 and int(ds.attractor_kind[0]) == PERIODIC and np.all(ds.outcome.values == 0)
    assert float(ds.attractor_period[0]) == pytest.approx(reference, rel=1e-9)
    orbit = dy.find_orbit(s, ds.attractor_state.values[0], float(ds.attractor_period[0]))
    assert orbit.converged and orbit.period == pytest.approx(reference, rel=1e-10) and orbit.stability == 0
    section = dy.poincare_section(s, ds.attractor_state.values[0], "y", 0.0, direction="negative",
                                  t_end=6 * reference)
    assert np.diff(section.time.values).mean() == pytest.approx(reference, rel=1e-9)
    ly = dy.lyapunov_spectrum(s, orbit.states[0], t_end=40 * reference, dt=reference / 4)
    one_period = zoo.reference_run(zoo.fhn_rhs(0.08), orbit.states[0], reference,
                                   t_eval=np.linspace(0.0, reference, 20001))
    divergence = np.trapezoid(1 - one_period.y[0] ** 2 - 0.8 * 0.08, one_period.t) / reference  # Floquet exponent
    assert abs(float(ly.exponents[0])) < 1e-2 and float(ly.exponents[1]) == pytest.approx(divergence, rel=1e-3)


def test_basins_of_a_user_system_plot_with_its_own_labels(tmp_path):
    """A basins dataset of a user's system saves, loads and plots from the command line."""
    s = zoo.double_well()
    ds = dy.basins(s, dy.Grid(("x", "y"), (-2, -2), (2, 2), (40, 40)), {"x": (-1.5, 1.5, 7), "y": (-1.5, 1.5, 7)},
                   horizon=300.0, progress=False)
    td.save(ds, tmp_path / "well.nc")
    back = td.load(tmp_path / "well.nc")
    np.testing.assert_array_equal(back.rejection.values, ds.rejection.values)
    from tippedisk_analysis.cli import main

    assert main(["plot", str(tmp_path / "well.nc"), "-o", str(tmp_path / "well.png")]) == 0
    assert (tmp_path / "well.png").stat().st_size > 0
