"""Cycle bifurcations continued in two parameters (dynamics/cycle_curves.py, cycle_bordered.py) against closed forms
and independent one-parameter branches."""

import math

import heyoka as hy
import numpy as np
import pytest

from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.errors import ParameterError


@pytest.fixture(scope="module")
def bautin_branch():
    system = dy.textbook_system("bautin")
    return system, dy.hopf_branch(system, [0.0, 0.0], {"beta": 0.0, "l": 1.0}, "beta", bounds=(-0.5, 0.1))


def test_bautin_fold_of_cycles_curve_is_beta1_equals_minus_beta2_squared_over_4(bautin_branch):
    """r' = r (beta + l r^2 - r^4), theta' = 1: folds of cycles exactly on beta = -l^2/4 with r^2 = l/2, T = 2 pi."""
    system, branch = bautin_branch
    curve = dy.special_point_curve(system, branch, "LP1", ("beta", "l"), bounds={"l": (0.5, 2.0)})
    assert curve.attrs["kind"] == "cycle_curve" and curve.attrs["status"] == "completed"
    beta, ell = curve["beta"].values, curve["l"].values
    assert ell.min() == pytest.approx(0.5, abs=1e-12) and ell.max() == pytest.approx(2.0, abs=1e-12)
    assert np.max(np.abs(beta + ell ** 2 / 4)) < 1e-8
    assert np.max(np.abs(curve["period"].values - 2 * math.pi)) < 1e-8
    r2 = (curve["initial_state"].values ** 2).sum(axis=1)
    assert np.max(np.abs(r2 - ell / 2)) < 1e-8
    mu = curve["multiplier_real"].values + 1j * curve["multiplier_imag"].values
    assert np.max(np.abs(mu - 1.0)) < 1e-6  # the trivial multiplier and the fold's
    assert curve.attrs["labels"] == ""  # no cusp on this curve


def test_cusp_of_cycles_is_located_where_the_curve_reverses_in_the_parameter_plane():
    """r' = r g(r^2), g = b1 + b2 s - s^3, s = r^2 - 1: folds of cycles on (b1, b2) = (-2 s^3, 3 s^2), a cusp of
    cycles at b1 = b2 = 0 with r = 1 (where the fold's coefficient g'' vanishes)."""
    x, y = hy.make_vars("x", "y")
    s = x * x + y * y - 1.0
    g = hy.par[0] + hy.par[1] * s - s * s * s
    system = dy.System("cusp_of_cycles", (x, y), (g * x - y, x + g * y), {"b1": 0.0, "b2": 0.75})
    branch = dy.hopf_branch(system, [0.0, 0.0], {"b1": -0.25, "b2": 0.75}, "b1", bounds=(-1.0, 1.0))
    assert branch.attrs["labels"] == "LP1 LP2"  # at s = -1/2 (b1 = 1/4) and s = 1/2 (b1 = -1/4)
    curve = dy.special_point_curve(system, branch, "LP1", ("b1", "b2"), bounds={"b2": (-0.1, 1.2)})
    assert curve.attrs["status"] == "completed"
    shift = (curve["initial_state"].values ** 2).sum(axis=1) - 1.0
    assert np.max(np.abs(curve["b1"].values + 2 * shift ** 3)) < 1e-8
    assert np.max(np.abs(curve["b2"].values - 3 * shift ** 2)) < 1e-8
    assert curve.attrs["labels"] == "CP1"
    cusp = int(curve["special_index"].values[0])
    assert abs(curve["b1"].values[cusp]) < 1e-9 and abs(curve["b2"].values[cusp]) < 1e-9
    assert abs(shift[cusp]) < 1e-8
    assert curve["b2"].values.max() == pytest.approx(1.2, abs=1e-12)  # through the cusp to the other fold


def test_a_curve_of_cycles_starts_at_a_fold_in_one_of_its_parameters(bautin_branch):
    system, branch = bautin_branch
    with pytest.raises(ParameterError, match="continued in 'beta'"):
        dy.special_point_curve(system, branch, "LP1", ("l", "other"), bounds={})
    with pytest.raises(ParameterError, match="no special point 'PD1'"):
        dy.special_point_curve(system, branch, "PD1", ("beta", "l"), bounds={})


def _one_parameter_folds(system, beta: float) -> list[tuple[float, float]]:
    """(D, T) of the folds of cycles on the orbit branch from the Hopf point of 'ab' at fixed beta (ntst 80)."""
    eq = dy.equilibrium_branch(system, [0.0, 0.0], "D", bounds=(0.0, 0.25), pars={"beta": beta})
    hopf = next(label for label in eq.attrs["labels"].split() if label.startswith("HOPF"))
    orbits = dy.orbit_branch(system, eq, hopf, bounds=(0.0, 0.25), ntst=80, error_tol=1e-9)
    return [(float(orbits["D"].values[i]), float(orbits["period"].values[i]))
            for label, i in zip(orbits["special_label"].values, orbits["special_index"].values)
            if str(label).startswith("LP")]


def test_ab_fold_of_cycles_curve_agrees_with_one_parameter_branches_at_fixed_beta():
    """AUTO-07p's 'ab' (B = 14): the curve from the fold at beta = 3 in (beta, D), its points at beta = 2.7 and 3.3
    (marks) against the folds of one-parameter orbit branches in D at those beta (an independent continuation)."""
    system = dy.textbook_system("ab")
    eq = dy.equilibrium_branch(system, [0.0, 0.0], "D", bounds=(0.0, 0.25), pars={"beta": 3.0})
    branch = dy.orbit_branch(system, eq, "HOPF1", bounds=(0.0, 0.25))
    curve = dy.special_point_curve(system, branch, "LP1", ("beta", "D"), bounds={"beta": (2.6, 3.4)},
                                   marks=(2.7, 3.3))
    assert curve.attrs["status"] == "completed" and curve.attrs["labels"] == "UZ1 UZ2"
    for index in curve["special_index"].values:
        beta = float(curve["beta"].values[index])
        [(D, T)] = _one_parameter_folds(system, beta)
        assert curve["D"].values[index] == pytest.approx(D, abs=1e-9)
        assert curve["period"].values[index] == pytest.approx(T, rel=1e-6)


def _orbit_dataset(system, state, period, parameter, bounds, pars=None, method="collocation"):
    """The one-parameter orbit branch through the orbit found from (state, period) at pars."""
    orbit = dy.find_orbit(system, state, period, pars, method=method)
    br, prob = dy.continue_orbits(orbit, parameter, bounds={parameter: bounds})
    return br, prob


def test_roessler_period_doubling_curve_agrees_with_one_parameter_shooting_branches():
    """Roessler (b = 0.2): the first period doubling continued in (a, c) from c = 2.8324 at a = 0.2; at a = 0.17, 0.21
    and 0.24 (marks) against the period doublings that branches in c at those a locate by multiple shooting (the
    multipliers of heyoka's variational equations: an independent integrator and test)."""
    system = dy.textbook_system("roessler")
    br, prob = _orbit_dataset(system, [4.3, 0.0, 0.03], 6.0, "c", (2.5, 3.2))
    branch = dy.branch_dataset(prob, br)
    curve = dy.special_point_curve(system, branch, "PD1", ("a", "c"), bounds={"a": (0.15, 0.25)},
                                   marks=(0.17, 0.21, 0.24))
    assert curve.attrs["status"] == "completed" and curve.attrs["critical"] == "period_doubling"
    assert curve.attrs["labels"] == "UZ1 UZ2 UZ3"  # no codimension-two point in this box
    mu = curve["multiplier_real"].values + 1j * curve["multiplier_imag"].values
    assert np.max(np.min(np.abs(mu + 1.0), axis=1)) < 1e-7  # a multiplier -1 all along
    for index in curve["special_index"].values:
        a = float(curve["a"].values[index])
        ref, ref_prob = _orbit_dataset(system, [4.0, 0.0, 0.03], 5.8, "c", (2.3, 3.5), system.with_pars(a=a, c=2.3),
                                       method="shooting")
        [pd] = [sp for sp in ref.special_points if sp.kind == "period_doubling"]
        _X, T, c = ref_prob.split(pd.u)
        assert curve["c"].values[index] == pytest.approx(c, abs=1e-8)
        assert curve["period"].values[index] == pytest.approx(T, rel=1e-9)


def _skewed_torus():
    """A cycle of non-uniform speed times a Hopf normal form: on r = 1, theta' = 1 + a cos(theta), so
    T = 2 pi / s and the mean of x1 is (s - 1) / a, s = sqrt(1 - a^2); z = x3 + i x4 has
    z' = (beta + x1 + i omega2) z - z |z|^2, whose multipliers at z = 0 are exp(T (beta + mean x1) +- i omega2 T):
    Neimark-Sacker points on beta = (1 - s) / a with theta = omega2 T (mod 2 pi)."""
    x1, x2, x3, x4 = hy.make_vars("x1", "x2", "x3", "x4")
    beta, a, omega2 = hy.par[0], hy.par[1], hy.par[2]
    r2, speed = x1 * x1 + x2 * x2, 1.0 + a * x1
    g = beta + x1 - (x3 * x3 + x4 * x4)
    return dy.System("skewed_torus", (x1, x2, x3, x4), (x1 * (1 - r2) - x2 * speed, x2 * (1 - r2) + x1 * speed,
                                                          g * x3 - omega2 * x4, omega2 * x3 + g * x4),
                     {"beta": 0.1, "a": 0.5, "omega2": 1.0})


def test_neimark_sacker_curve_and_its_strong_resonances_in_closed_form():
    """The NS curve of the skewed torus in (beta, a) over 0.3 <= a <= 0.7 (omega2 = 1): beta = (1 - s)/a,
    T = 2 pi / s, theta = T - 2 pi; the 1:4 resonance at theta = pi/2 (s = 4/5, a = 3/5) and the 1:3 at
    theta = 2 pi/3 (s = 3/4, a = sqrt(7)/4)."""
    system = _skewed_torus()
    br, prob = _orbit_dataset(system, [1.0, 0.0, 0.0, 0.0], 2 * math.pi / math.sqrt(0.75), "beta", (0.1, 0.4))
    branch = dy.branch_dataset(prob, br)
    assert branch.attrs["labels"] == "NS1"
    curve = dy.special_point_curve(system, branch, "NS1", ("beta", "a"), bounds={"a": (0.3, 0.7)})
    assert curve.attrs["status"] == "completed" and curve.attrs["critical"] == "neimark_sacker"
    a, beta, theta, T = (curve[k].values for k in ("a", "beta", "theta", "period"))
    assert a.min() == pytest.approx(0.3, abs=1e-12) and a.max() == pytest.approx(0.7, abs=1e-12)
    s = np.sqrt(1 - a ** 2)
    assert np.max(np.abs(beta - (1 - s) / a)) < 1e-9
    assert np.max(np.abs(T - 2 * np.pi / s)) < 1e-8
    assert np.max(np.abs(theta - (T - 2 * np.pi))) < 1e-8
    assert curve.attrs["labels"] == "R4_1 R3_1"
    r4, r3 = curve["special_index"].values
    assert a[r4] == pytest.approx(0.6, abs=1e-9) and beta[r4] == pytest.approx(1 / 3, abs=1e-9)
    assert a[r3] == pytest.approx(math.sqrt(7) / 4, abs=1e-9)
    # on to theta = pi (s = 2/3): the 1:2 resonance, where the curve ends
    on = dy.special_point_curve(system, branch, "NS1", ("beta", "a"), bounds={"a": (0.5, 0.9)})
    assert on.attrs["labels"] == "R4_1 R3_1 R2_1" and "ended at a resonance_1_2 point" in on.attrs["message"]
    assert on["a"].values[-1] == pytest.approx(math.sqrt(5) / 3, abs=1e-9)
    assert on["theta"].values[-1] == pytest.approx(math.pi, abs=1e-9)


def test_fold_neimark_sacker_point_on_a_fold_of_cycles_curve():
    """The Bautin normal form times a Hopf normal form z' = (gamma + r^2 + i sqrt(2)) z - z |z|^2: on the folds of
    cycles (beta = -l^2/4, r^2 = l/2) the z multipliers are exp(2 pi (gamma + l/2) +- i 2 sqrt(2) pi); with
    gamma = -1/2 they cross the unit circle at l = 1, beta = -1/4 (LPNS)."""
    x, y, u, w = hy.make_vars("x", "y", "u", "w")
    beta, ell, gamma = hy.par[0], hy.par[1], hy.par[2]
    r2, omega = x * x + y * y, math.sqrt(2.0)
    a, g = beta + ell * r2 - r2 * r2, gamma + r2 - (u * u + w * w)
    pars = {"beta": 0.0, "l": 0.75, "gamma": -0.5}
    system = dy.System("bautin_hopf", (x, y, u, w), (a * x - y, x + a * y, g * u - omega * w, omega * u + g * w), pars)
    branch = dy.hopf_branch(system, [0.0] * 4, pars, "beta", bounds=(-1.0, 0.1))
    curve = dy.special_point_curve(system, branch, "LP1", ("beta", "l"), bounds={"l": (0.5, 2.0)})
    assert curve.attrs["status"] == "completed" and curve.attrs["labels"] == "LPNS1"
    [index] = curve["special_index"].values
    assert curve["l"].values[index] == pytest.approx(1.0, abs=1e-9)
    assert curve["beta"].values[index] == pytest.approx(-0.25, abs=1e-9)
    assert np.max(np.abs(curve["beta"].values + curve["l"].values ** 2 / 4)) < 1e-8


@pytest.mark.slow
def test_the_held_disks_fold_of_cycles_in_spin_and_eps_and_in_spin_and_e_against_shooting():
    """The held-spin model's fold of cycles (Tables 1-2, 30.9533 rad/s at eps = 5 mm/s). Its collocation orbit
    branch from the shooting orbit at 30.9 rad/s is computed on a mesh that resolves the fold's double multiplier 1
    (a Jordan block: the multipliers near it err by the square root of the discretisation error): ntst 160,
    error_tol 1e-8. Continued in (eps, spin), its points at eps = 2.5 and
    10 mm/s are the folds nutation_cycles.held_fold_of_cycles finds by shooting; in (e, spin) the fold meets the
    branch's second fold in a cusp of cycles (at e = 2.4308 mm), and at e = 2.45 mm both folds are those of a
    branch in the spin by shooting."""
    from tippedisk_analysis.analysis import nutation_cycles as nc
    from tippedisk_analysis.models import held_spin

    system = held_spin.system()
    family = nc.drift(30.9, max_amplitude=3.1)
    k = int(np.argmin(np.abs(nc.amplitude_of(family) - nc.repelling_cycle(family)["amplitude"])))
    orbit = dy.find_orbit(system, family.start.values[k], float(family.period.values[k]),
                          system.with_pars(spin=30.9, eps=0.005))
    br, prob = dy.continue_orbits(orbit, "spin", bounds={"spin": (29.9, 31.9)}, method="collocation", ntst=160,
                                  error_tol=1e-8, options=dy.Options(ds=0.02, ds_max=0.3, max_points=8))
    branch = dy.branch_dataset(prob, br)
    assert branch.attrs["labels"].split()[0] == "LP1"
    in_eps = dy.special_point_curve(system, branch, "LP1", ("eps", "spin"), bounds={"eps": (0.002, 0.012)},
                                    marks=(0.0025, 0.01))
    assert in_eps.attrs["status"] == "completed" and in_eps.attrs["labels"] == "UZ1 UZ2"
    for index in in_eps["special_index"].values:
        held = nc.held_fold_of_cycles(30.9, float(in_eps["eps"].values[index]))
        assert held["status"] == "completed"
        assert in_eps["spin"].values[index] == pytest.approx(held["spin"], abs=2e-8)
        assert in_eps["period"].values[index] == pytest.approx(held["period"], rel=1e-8)

    in_e = dy.special_point_curve(system, branch, "LP1", ("e", "spin"), bounds={"e": (0.002, 0.003)},
                                  scales={"e": 1e-3}, marks=(0.00245,))
    assert in_e.attrs["status"] == "completed" and in_e.attrs["labels"] == "UZ1 CP1 UZ2"
    low, cusp, high = in_e["special_index"].values
    assert in_e["e"].values.min() == pytest.approx(in_e["e"].values[cusp], abs=1e-12)  # no fold below the cusp
    start = dict(spin=float(in_e["spin"].values[low]) + 2e-4, eps=0.005, e=0.00245)  # beside the fold
    beside = dy.find_orbit(system, in_e["initial_state"].values[low], float(in_e["period"].values[low]),
                           system.with_pars(**start))
    ref, ref_prob = dy.continue_orbits(beside, "spin", bounds={"spin": (30.84, 30.94)}, method="shooting",
                                       both_ways=True, options=dy.Options(ds=0.01, ds_max=0.1, max_points=60))
    folds = sorted(ref_prob.split(sp.u)[2] for sp in ref.special_points if sp.kind == "fold")
    assert len(folds) == 2
    assert in_e["spin"].values[low] == pytest.approx(folds[0], abs=2e-8)
    assert in_e["spin"].values[high] == pytest.approx(folds[1], abs=2e-8)
