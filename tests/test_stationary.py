"""Stationary spinning solutions of the reduced system (Sect. 6, Fig. 6)."""

import dataclasses
import math

import heyoka as hy
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as hs

from tippedisk_analysis import Disk, Friction, ParameterError, Setup
from tippedisk_analysis.analysis import reduced
from tippedisk_analysis.analysis import stationary as st
from tippedisk_analysis.models import ode

PARS = ode.parameter_vector()


@pytest.mark.parametrize("branch", list(st.BRANCHES))
@settings(max_examples=25, deadline=None)
@given(omega=hs.floats(-300, 300), eps=hs.floats(1e-3, 2.0), mu=hs.floats(0.0, 1.5), e=hs.floats(0.0, 4e-3))
def test_stationary_solutions_are_equilibria(branch, omega, eps, mu, e):
    setup = Setup(disk=dataclasses.replace(Disk(), e=e), friction=Friction(mu=mu, eps=eps))
    pars = ode.parameter_vector(setup)
    x = st.stationary_state(branch, omega)
    ev = reduced.evaluate(x, pars)
    # round-off level: pi/2 is not a double (cos(pi/2) = 6e-17), so the residual is J delta with
    # |delta| ~ 1e-16 |x|; bound it by 1e-14 |J| (1 + |x|) with the exact Jacobian of stability.py
    tol = 1e-14 * np.abs(reduced.jacobian(x, pars)).max() * (1.0 + np.abs(x).max())
    assert np.max(np.abs(ev["rhs"])) <= tol
    assert ev["alpha_dot"][0] == pytest.approx(omega, abs=1e-12 * (1 + abs(omega)))
    assert np.max(np.abs(ev["slip"])) <= 1e-14 * (1 + abs(omega))  # no slip
    # spinning about the vertical through C1, G, S: no vertical acceleration of S, lambda_N = m g
    assert ev["lambda_N"][0] == pytest.approx(setup.disk.m * setup.gravity, rel=1e-12)


def test_branches_match_fig6():
    for branch, sign in (("noninverted", -1), ("inverted", 1)):
        x = st.stationary_state(branch, [25.0])[:, 0]
        assert x[0] == pytest.approx(math.pi / 2) and x[1] == pytest.approx(sign * math.pi / 2)
    with pytest.raises(ParameterError, match="choose one of"):
        st.stationary_state("upside-down", 1.0)


def test_reduced_rhs_is_the_rotated_full_model():
    """Symmetry reduction: the full ODE Model 1 at alpha != 0 gives the reduced rhs after rotating v_G."""
    variables, sys, _fall, _out = ode.system(ode.EULER)
    full = hy.cfunc([rhs for _v, rhs in sys], variables)
    rng = np.random.default_rng(1)
    for _ in range(5):
        alpha = rng.uniform(-3, 3)
        beta, gamma = rng.uniform(0.6, 2.5), rng.uniform(-3, 3)
        u = rng.normal(size=2) * 0.2
        w = rng.normal(size=3) * 20
        ca, sa = math.cos(alpha), math.sin(alpha)
        v_xy = [ca * u[0] - sa * u[1], sa * u[0] + ca * u[1]]
        state = np.array([0.3, -0.2, alpha, beta, gamma, *v_xy, *w, 0.0])
        f = dict(zip(ode.EULER.state_names, full(state, pars=PARS[: full.nparams])))
        alpha_dot = f["alpha"]
        red = reduced.evaluate(np.array([beta, gamma, *u, *w]), PARS)["rhs"][:, 0]
        a_R = [ca * f["x_dot"] + sa * f["y_dot"], -sa * f["x_dot"] + ca * f["y_dot"]]
        expected = [f["beta"], f["gamma"], a_R[0] + alpha_dot * u[1], a_R[1] - alpha_dot * u[0],
                    f["omega_x"], f["omega_y"], f["omega_z"]]
        np.testing.assert_allclose(red, expected, rtol=1e-12, atol=1e-12 * np.max(np.abs(expected)))


@pytest.mark.parametrize("branch", list(st.BRANCHES))
def test_newton_converges_from_a_perturbed_guess(branch):
    x_star = st.stationary_state(branch, [40.0])[:, 0]
    guess = x_star + np.array([0.05, -0.08, 0.01, -0.01, 1.0, 2.0, -1.0])
    eq = st.solve(guess, 40.0, PARS)
    assert eq.status == "converged", eq.message
    np.testing.assert_allclose(eq.state, x_star, atol=1e-10)
    assert eq.residual < 1e-10
    assert eq.lambda_N > 0


GUESS_FAR = np.array([1.2, 0.3, 0.0, 0.0, 5.0, 1.0, 2.0])  # no equilibrium of either family nearby


def test_newton_reports_max_iter_when_stopped_early():
    eq = st.solve(GUESS_FAR, 40.0, PARS, max_iter=8)
    assert eq.status == "max_iter" and not eq.converged
    assert eq.message == "no equilibrium within 8 Newton steps of the guess"
    assert eq.iterations == 8
    assert eq.residual > 1.0  # far from an equilibrium


def _newton_residual(x, omega, pars):
    ev = reduced.evaluate(x, pars)
    return max(np.abs(ev["rhs"]).max(), abs(ev["alpha_dot"][0] - omega))


def test_max_iter_residual_belongs_to_the_returned_state():
    eq = st.solve(GUESS_FAR, 40.0, PARS, max_iter=8)
    assert eq.residual == pytest.approx(_newton_residual(eq.state, 40.0, PARS), rel=1e-6)


def test_newton_reports_a_least_squares_minimum_that_is_no_equilibrium():
    """Gauss-Newton from the far guess stalls at a point where the gradient of |F|^2 / 2 vanishes
    but F does not: 'no_equilibrium', and the state really is such a point."""
    eq = st.solve(GUESS_FAR, 40.0, PARS, max_iter=100)
    assert eq.status == "no_equilibrium" and not eq.converged
    assert eq.message.startswith("Newton stalled at a least-squares minimum with residual")
    assert eq.iterations < 100
    ev = reduced.evaluate(eq.state, PARS)
    F = np.append(ev["rhs"][:, 0], ev["alpha_dot"][0] - 40.0)
    assert np.abs(F).max() == pytest.approx(eq.residual, rel=1e-6) and eq.residual > 0.1  # not an equilibrium
    J = np.vstack([reduced.jacobian(eq.state, PARS)[0], reduced.alpha_dot_gradient(eq.state, PARS)])
    assert np.abs(J.T @ F).max() < 1e-8 * np.abs(J).max() * np.abs(F).max()  # ... but stationary for |F|^2


def test_newton_reports_lift_off_with_the_normal_force():
    """With gravity pointing up (a parameter vector only, Setup refuses it) the spinning solution still
    solves rhs = 0, but lambda_N = -m |g| < 0: outside the bilateral model, status 'lift_off'."""
    pars = PARS.copy()
    pars[ode.PARAMETER_NAMES.index("gravity")] = -9.81
    x_star = st.stationary_state("inverted", [40.0])[:, 0]
    eq = st.solve(x_star + 1e-3, 40.0, pars)
    assert eq.status == "lift_off" and not eq.converged
    m = Disk().m
    assert eq.lambda_N == pytest.approx(-m * 9.81, rel=1e-9)
    assert eq.message == f"equilibrium has lambda_N = {-m * 9.81:.3g} N <= 0: the contact would open"
    np.testing.assert_allclose(eq.state, x_star, atol=1e-10)  # Newton itself converged


def test_newton_reports_nonfinite_equations_at_a_flat_disk():
    """beta = 0 (sin beta = 0) is the Euler-angle singularity: the equations divide by zero."""
    eq = st.solve(np.array([0.0, 0.3, 0.0, 0.0, 5.0, 1.0, 2.0]), 40.0, PARS)
    assert eq.status == "nonfinite" and eq.iterations == 1
    assert "not finite" in eq.message and "sin(beta)" in eq.message
    assert not np.all(np.isfinite(reduced.evaluate(eq.state, PARS)["rhs"]))


def test_newton_refuses_a_nonfinite_guess():
    with pytest.raises(ParameterError, match="finite"):
        st.solve(np.full(7, np.nan), 40.0, PARS)
    with pytest.raises(ParameterError, match="finite"):
        st.solve(st.stationary_state("inverted", [40.0])[:, 0], math.inf, PARS)
