"""Folds of cycles continued in two parameters (dynamics/cycle_curves.py) against closed forms."""

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
