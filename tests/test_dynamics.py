"""The generic dynamics layer (tippedisk_analysis.dynamics): one System declaration, checked, and the
analyses on it, proven on AUTO-07p's demo 'ab' (B = 14, beta = 2) against exact algebra."""

from __future__ import annotations

import copy
import math
import re

import heyoka as hy
import numpy as np
import pytest
from scipy.optimize import brentq

import tippedisk_analysis as td
from tippedisk_analysis import dynamics as dy

B, BETA = 14.0, 2.0


def ab_system(name: str = "ab") -> dy.System:
    u1, u2 = hy.make_vars("u1", "u2")
    D, Bp, beta = hy.par[0], hy.par[1], hy.par[2]
    return dy.System(name, [u1, u2], [-u1 + D * (1 - u1) * hy.exp(u2),
                                      -u2 + D * Bp * (1 - u1) * hy.exp(u2) - beta * u2],
                     parameters={"D": 0.0, "B": B, "beta": BETA})


# ---------------------------------------------------------------- exact algebra of 'ab'
# equilibria: u2 = B u1 / (1 + beta), D = u1 exp(-u2) / (1 - u1); folds where dD/du1 = 0; Hopf points where
# the trace of the Jacobian vanishes with a positive determinant (a negative one: a neutral saddle)


def _D(u1, beta=BETA):
    return u1 * math.exp(-B * u1 / (1 + beta)) / (1 - u1)


def _jacobian(u1, beta=BETA):
    D, E = _D(u1, beta), math.exp(B * u1 / (1 + beta))
    return np.array([[-1 - D * E, D * (1 - u1) * E], [-D * B * E, -1 + D * B * (1 - u1) * E - beta]])


def _exact_points(beta=BETA):
    k = B / (1 + beta)
    folds = [brentq(lambda u: 1 / u - k + 1 / (1 - u), a, b) for a, b in ((0.05, 0.5), (0.5, 0.95))]
    grid = np.linspace(0.01, 0.99, 999)
    tr = [np.trace(_jacobian(u, beta)) for u in grid]
    zeros = [brentq(lambda u: np.trace(_jacobian(u, beta)), grid[i], grid[i + 1])
             for i in range(len(grid) - 1) if tr[i] * tr[i + 1] < 0]
    hopf = [u for u in zeros if np.linalg.det(_jacobian(u, beta)) > 0]
    saddles = [u for u in zeros if np.linalg.det(_jacobian(u, beta)) < 0]
    return folds, hopf, saddles


@pytest.fixture(scope="module")
def ab():
    return ab_system()


@pytest.fixture(scope="module")
def ab_branch(ab):
    return dy.equilibrium_branch(ab, [0.0, 0.0], "D", bounds=(0.0, 0.2))


def test_ab_branch_has_its_two_folds_and_one_hopf_point_and_no_neutral_saddle(ab_branch):
    folds, hopf, saddles = _exact_points()
    assert len(folds) == 2 and len(hopf) == 1 and len(saddles) == 1  # the algebra: one neutral saddle too
    ds = ab_branch
    assert ds.attrs["labels"] == "LP1 LP2 HOPF1" and ds.attrs["status"] == "completed"
    points = {str(label): int(i) for label, i in zip(ds.special_label.values, ds.special_index.values)}
    for label, u1 in (("LP1", folds[0]), ("LP2", folds[1]), ("HOPF1", hopf[0])):
        i = points[label]
        assert float(ds.u1[i]) == pytest.approx(u1, abs=1e-10), label
        assert float(ds.D[i]) == pytest.approx(_D(u1), abs=1e-10), label
        assert float(ds.u2[i]) == pytest.approx(B * u1 / (1 + BETA), abs=1e-10), label
    omega = math.sqrt(np.linalg.det(_jacobian(hopf[0])))
    k = list(ds.special_label.values).index("HOPF1")
    assert float(ds.special_frequency[k]) == pytest.approx(omega, rel=1e-10)
    assert 2 * math.pi / omega == pytest.approx(1.56775, abs=1e-5)  # AUTO-07p's period at the Hopf point
    # the neutral saddle (D = 0.10571, just past LP1) is no special point: no point of the branch sits there
    assert not any(abs(float(ds.D[i]) - _D(saddles[0])) < 1e-6 for i in ds.special_index.values)
    np.testing.assert_array_equal(ds.B.values, B)  # fixed parameters are stored along the branch
    assert float(ds.residual.max()) < 1e-12


def test_the_hopf_curve_keeps_the_trace_zero(ab, ab_branch):
    curve = dy.special_point_curve(ab, ab_branch, "HOPF1", ("D", "beta"), bounds={"beta": (1.0, 3.0)})
    assert curve.attrs["critical"] == "hopf" and curve.sizes["point"] > 10
    beta = curve.beta.values
    assert beta.min() == pytest.approx(1.0) and beta.max() == pytest.approx(3.0)
    for i in range(0, curve.sizes["point"], 7):  # on every point: an equilibrium with a zero trace
        u1, b = float(curve.u1[i]), float(curve.beta[i])
        assert float(curve.D[i]) == pytest.approx(_D(u1, b), rel=1e-9)
        assert np.trace(_jacobian(u1, b)) == pytest.approx(0.0, abs=1e-8)
        assert np.linalg.det(_jacobian(u1, b)) > 0


def test_a_stored_branch_is_continued_with_the_same_system_only(ab, ab_branch, tmp_path):
    td.save(ab_branch, tmp_path / "ab.nc")
    stored = td.load(tmp_path / "ab.nc")
    assert stored.attrs["system"] == "ab" and "u1' = " in stored.attrs["system_equations"]
    state, pars = dy.point_of(stored, ab, int(stored.special_index.values[2]))
    assert pars[0] == pytest.approx(float(ab_branch.D[int(ab_branch.special_index[2])]))
    other = dy.System("ab2", ab.variables, ab.rhs, ab.parameters)
    with pytest.raises(td.DatasetError, match="pass the System the dataset was computed with"):
        dy.point_of(stored, other, 0)
    from tippedisk_analysis.plotting import plot_dataset

    plot_dataset(stored, tmp_path / "ab.png")  # generic datasets take the generic figure
    assert (tmp_path / "ab.png").stat().st_size > 10_000


def test_an_observables_rate_and_its_maxima_on_a_damped_oscillator():
    """rate_of is grad . f (the energy of x'' + 2 zeta x' + x = 0 falls at 2 zeta v^2); sectioning at its downward
    zeros finds the maxima of x(t) = exp(-zeta t) (cos wd t + zeta / wd sin wd t) from (1, 0): t = 2 pi k / wd,
    the start (k = 0) included."""
    from tippedisk_analysis.dynamics.poincare import crossings

    x, v = hy.make_vars("x", "v")
    zeta = 0.1
    damped = dy.System("damped", [x, v], [v, -x - 2 * hy.par[0] * v], {"zeta": zeta})
    energy = 0.5 * (x * x + v * v)
    rated = damped.with_observables("damped_rates", {"E_rate": damped.rate_of(energy), "x_rate": damped.rate_of(x)})
    assert damped.observables == {} and set(rated.observables) == {"E_rate", "x_rate"}
    states = np.random.default_rng(1).normal(size=(2, 5))
    np.testing.assert_allclose(rated.observe(states)["E_rate"], -2 * zeta * states[1] ** 2, rtol=1e-13)
    run = crossings(rated, [1.0, 0.0], "x_rate", direction="negative", t_end=20.0)
    wd = math.sqrt(1 - zeta**2)
    k = np.arange(4)
    assert len(run.times) == 4 and run.status == "completed"
    np.testing.assert_allclose(run.times, 2 * math.pi * k / wd, rtol=1e-10)
    np.testing.assert_allclose(run.states[:, 0], np.exp(-zeta * run.times), rtol=1e-9)
    with pytest.raises(td.ParameterError, match="'x' is a str; give a heyoka expression of damped's variables"):
        damped.rate_of("x")
    with pytest.raises(td.ParameterError, match="observable 'bad'"):
        damped.with_observables("bad", {"bad": [x]})
    t = run.t_final
    assert t == pytest.approx(20.0)
    assert run.final[0] == pytest.approx(math.exp(-zeta * t) * (math.cos(wd * t) + zeta / wd * math.sin(wd * t)),
                                         abs=1e-10)


def test_a_second_analysis_of_the_same_system_compiles_nothing():
    system = ab_system("ab_reuse")
    dy.equilibrium_branch(system, [0.0, 0.0], "D", bounds=(0.0, 0.2))
    compiled = system.compiled_count()
    field = system.field((), ("D",))
    dy.equilibrium_branch(system, [0.0, 0.0], "D", bounds=(0.0, 0.15))
    assert system.compiled_count() == compiled and system.field((), ("D",)) is field


@pytest.mark.parametrize("make, fragment", [
    (lambda x, y: dy.System("s", [x, y], [hy.par[1] * x, y], {"a": 1.0}),
     "use hy.par[1] but only 1 parameter(s) are declared"),
    (lambda x, y: dy.System("s", [x, y], [hy.par[0] * x, y], {"a": 1.0, "b": 2.0}),
     "parameter 'b' (hy.par[1]) appears in no expression"),
    (lambda x, y: dy.System("s", [x, y], [x, y], {}, state_names=("point", "y")), "state name 'point' is reserved"),
    (lambda x, y: dy.System("s", [x, y], [hy.par[0] * x, y], {"x": 1.0}), "the name 'x' is both a state and a "
                                                                           "parameter"),
    (lambda x, y: dy.System("s", [x, y], [x], {}), "2 variables but 1 right-hand sides"),
    (lambda x, y: dy.System("s", [x, y], [x, y], {}, observables={"period": x}),
     "observable name 'period' is reserved"),
])
def test_a_bad_declaration_is_one_line_naming_the_clash(make, fragment):
    x, y = hy.make_vars("x", "y")
    with pytest.raises(td.ParameterError, match=re.escape(fragment)) as info:
        make(x, y)
    assert "\n" not in str(info.value)




def test_states_given_as_rows_are_refused_not_misread():
    """(N, n) rows, the layout of propagate_grid, would be read as n states of N entries: refused, with the fix."""
    system = ab_system("ab_rows")
    rows = np.tile([0.1, 0.2], (5, 1))
    with pytest.raises(td.ParameterError, match=r"states of shape \(5, 2\); give \(2,\) or \(2, N\)") as info:
        system.f(rows)
    assert "transpose" in str(info.value) and "\n" not in str(info.value)
    np.testing.assert_allclose(system.f(rows.T), np.tile(system.f(rows[0])[:, None], (1, 5)))
    with pytest.raises(td.ParameterError, match="states of shape"):
        system.f(np.zeros(4))
# ---------------------------------------------------------------- periodic orbits from the Hopf point
AUTO_PERIODS = {0.125: 1.8641832388, 0.12: 2.6727661404, 0.1168: 5.7046181435}
"""AUTO-07p (bifpy 0.3.0, NTST = 100-200, EPSS = 1e-10) on 'ab' with B = 14, beta = 2: the periods at user
points; the branch ends in a homoclinic orbit at D -> 0.10550707004 (an independent scipy integration of the
orbits and of the saddle's manifolds gives the same digits)."""


@pytest.fixture(scope="module", params=["collocation", "shooting"])
def ab_orbits(ab, ab_branch, request):
    return dy.orbit_branch(ab, ab_branch, "HOPF1", bounds=(0.0, 0.2), period_max=50.0, marks=tuple(AUTO_PERIODS),
                           method=request.param)


def test_ab_orbits_from_the_hopf_point_have_auto07p_periods_and_end_in_a_homoclinic_orbit(ab_orbits):
    """Both methods: the periods at AUTO-07p's user points to 1e-8, the homoclinic limit to 1e-8, every orbit
    stable (collocation: every orbit within its error tolerance, the mesh grown where the orbits lengthen)."""
    ds = ab_orbits
    assert ds.attrs["kind"] == "periodic_orbits" and ds.attrs["system"] == "ab"
    assert ds.attrs["labels"] == "UZ1 UZ2 UZ3 HC1"
    first = 0
    assert float(ds.period[first]) == pytest.approx(2 * math.pi / math.sqrt(np.linalg.det(_jacobian(
        _exact_points()[1][0]))), rel=1e-3)  # it starts at the Hopf point's period
    specials = {str(label): int(i) for label, i in zip(ds.special_label.values, ds.special_index.values)}
    for (value, period), label in zip(AUTO_PERIODS.items(), ("UZ1", "UZ2", "UZ3")):
        i = specials[label]
        assert float(ds.D[i]) == value and float(ds.period[i]) == pytest.approx(period, abs=1e-8), label
    i = specials["HC1"]
    k = list(ds.special_label.values).index("HC1")
    assert float(ds.period[i]) == pytest.approx(50.0) and float(ds.special_limit[k]) == pytest.approx(0.10550707004,
                                                                                                     abs=1e-8)
    assert "approach to a homoclinic orbit at D ~ 0.10550707" in ds.attrs["message"]
    assert np.all(ds.stability.values == 0)  # every orbit is stable, as AUTO-07p finds
    if ds.attrs["method"] == "collocation":
        assert np.all(ds.discretisation_error.values <= 1e-5) and ds.ntst.values[-1] > ds.ntst.values[0]
    assert np.all(np.diff(ds.period.values) > 0)  # the period grows monotonically towards the homoclinic orbit


def test_one_system_through_equilibria_orbits_lyapunov_exponents_and_basins(ab, ab_orbits):
    """The stable orbit at D = 0.12 (from the Hopf point of the equilibrium branch): its largest Lyapunov exponent
    is 0 (the flow direction) and the other one is its Floquet exponent log|mu_2| / T (a measured growth rate
    against the monodromy); the basins of the same System find it as the one attractor, with the same period,
    and its state on the shooting orbit."""
    i = int(ab_orbits.special_index.values[list(ab_orbits.special_label.values).index("UZ2")])
    T = float(ab_orbits.period[i])
    mu = ab_orbits.multiplier_real.values[i] + 1j * ab_orbits.multiplier_imag.values[i]
    nontrivial = mu[ab_orbits.multiplier_trivial.values[i] == 0]
    floquet_exponent = math.log(abs(nontrivial[0])) / T
    x0 = ab_orbits.initial_state.values[i]
    ly = dy.lyapunov_spectrum(ab, x0, ab.with_pars(D=0.12), t_end=400 * T, dt=T / 4)
    assert abs(float(ly.exponents[0])) < 2e-3
    assert float(ly.exponents[1]) == pytest.approx(floquet_exponent, rel=2e-3)
    assert float(ly.exponents.sum()) == pytest.approx(float(ly.divergence_mean), rel=1e-3)
    grid = dy.Grid(("u1", "u2"), (-0.2, -1.0), (1.2, 10.0), (70, 110))
    at = dy.basins(ab, grid, {"u1": (0.0, 1.0, 4), "u2": (0.0, 8.0, 4)}, pars=ab.with_pars(D=0.12), horizon=400.0,
                   progress=False)
    assert at.sizes["attractor"] == 1 and np.all(at.outcome.values == 0) and int(at.attractor_kind[0]) == 1
    assert float(at.attractor_period[0]) == pytest.approx(T, rel=1e-7)
    ta = copy.copy(ab.taylor(1e-13))
    ta.state[:], ta.pars[:], ta.time = x0, ab.with_pars(D=0.12), 0.0
    path = ta.propagate_grid(np.linspace(0.0, T, 4001))[-1]  # the shooting orbit, sampled
    spacing = np.max(np.linalg.norm(np.diff(path, axis=0), axis=1))
    assert np.min(np.linalg.norm(path - at.attractor_state.values[0], axis=1)) < 0.5 * spacing


def test_roessler_lyapunov_spectrum_against_the_published_values():
    """a = b = 0.2, c = 5.7: 0.0714, 0, -5.3943 (J. C. Sprott, Chaos and Time-Series Analysis, Oxford 2003, the
    exponents of common chaotic flows); their sum, -5.3229, is the mean divergence a - c + <x> (<x> = 0.1773 from
    a separate 20,000-s scipy run)."""
    roessler = dy.textbook_system("roessler").with_defaults(c=5.7)
    ds = dy.lyapunov_spectrum(roessler, [1.0, 1.0, 1.0], t_end=10000.0, dt=1.0, transient=100.0)
    np.testing.assert_allclose(ds.exponents.values, [0.0714, 0.0, -5.3943], atol=2e-3)
    assert float(ds.exponents.sum()) == pytest.approx(float(ds.divergence_mean), rel=1e-3)  # Liouville


def test_a_start_inside_the_bounds_is_continued_both_ways_or_says_it_covered_one_side():
    """x' = p + x - x^3: the S-curve p = x^3 - x has folds at p = +-2/(3 sqrt 3). From its middle (0, 0) one way
    finds one fold and says it covered one side; both ways (direction=0) finds both and reaches both bounds."""
    x = hy.make_vars("x")
    s = dy.System("s_curve", [x], [hy.par[0] + x - x**3], parameters={"p": 0.0})
    fold = 2 / (3 * math.sqrt(3))
    one = dy.equilibrium_branch(s, [0.0], "p", bounds=(-1.0, 1.0))
    assert "one side of the start p = 0 only" in one.attrs["message"]
    both = dy.equilibrium_branch(s, [0.0], "p", bounds=(-1.0, 1.0), direction=0)
    assert "one side" not in both.attrs["message"] and both.attrs["status"] == "completed"
    p = both["p"].values
    assert p.min() == pytest.approx(-1.0, abs=1e-9) and p.max() == pytest.approx(1.0, abs=1e-9)
    folds = sorted(float(p[i]) for i, label in zip(both["special_index"].values, both["special_label"].values)
                   if str(label).startswith("LP"))
    assert folds == pytest.approx([-fold, fold], abs=1e-7)
    assert [str(label) for label in one["special_label"].values] == ["LP1"]
    with pytest.raises(td.TippediskError, match="direction"):
        dy.equilibrium_branch(s, [0.0], "p", bounds=(-1.0, 1.0), direction=2)
