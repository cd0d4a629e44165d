"""Exact Jacobian, eigenvalues and their agreement with simulations of ODE Model 1."""

import math

import numpy as np
import pytest

import tippedisk_analysis as td
from tippedisk_analysis.analysis import reduced, stability
from tippedisk_analysis.analysis import stationary as st
from tippedisk_analysis.models import ode
from tippedisk_analysis.testing import finite_difference_jacobian

PARS = ode.parameter_vector()


def test_jacobian_matches_finite_differences_away_from_zero_slip():
    x = st.stationary_state("noninverted", [40.0])[:, 0] + np.array([0.01, 0.02, 0.003, -0.002, 0.5, 0.3, -0.2])
    assert np.hypot(*reduced.evaluate(x, PARS)["slip"][:, 0]) > 1e-3  # a smooth point of (2.29)
    J = reduced.jacobian(x, PARS)[0]
    np.testing.assert_allclose(J, finite_difference_jacobian(x, PARS, h=1e-6), rtol=0,
                               atol=1e-7 * np.abs(J).max())


@pytest.mark.parametrize("branch", list(st.BRANCHES))
def test_jacobian_is_finite_at_zero_slip_and_finite_differences_converge_to_it(branch):
    """At zero slip |gamma_T| has a kink, so central differences are first-order accurate there."""
    x = st.stationary_state(branch, [40.0])[:, 0]
    J = reduced.jacobian(x, PARS)[0]
    assert np.all(np.isfinite(J))
    errors = [np.abs(finite_difference_jacobian(x, PARS, h=h) - J).max() / np.abs(J).max() for h in (1e-6, 1e-7)]
    assert errors[1] < 2e-5
    assert errors[1] < 0.2 * errors[0]  # converging (first order: factor 10)


def test_zero_slip_linearisation_depends_on_mu_over_eps_only():
    """d/d gamma_T of mu gamma_T / (|gamma_T| + eps) at 0 is mu/eps I (regularised (2.29))."""
    x = st.stationary_state("inverted", [33.0])
    p2 = PARS.copy()
    p2[7] *= 2.0  # mu
    p2[8] *= 2.0  # eps
    np.testing.assert_allclose(reduced.jacobian(x, p2), reduced.jacobian(x, PARS), rtol=1e-12, atol=1e-12)
    p3 = PARS.copy()
    p3[8] *= 2.0
    assert not np.allclose(reduced.jacobian(x, p3), reduced.jacobian(x, PARS))


@pytest.mark.parametrize("branch", list(st.BRANCHES))
def test_structural_zero_and_eigenvectors(branch):
    x = st.stationary_state(branch, [40.0])
    J = reduced.jacobian(x, PARS)[0]
    scale = np.abs(J).max()
    assert np.abs(J[:, reduced.OMEGA_X_INDEX]).max() < 1e-12 * scale  # d x*/d Omega is a null vector
    full = np.linalg.eigvals(J)
    nontrivial = stability.nontrivial_eigenvalues(J)
    assert np.min(np.abs(full)) < 1e-10 * scale
    for s in nontrivial:  # every nontrivial eigenvalue is one of J's
        assert np.min(np.abs(full - s)) < 1e-8 * scale
    vals, vecs = stability.eigen(J)
    np.testing.assert_allclose(vals, nontrivial)
    np.testing.assert_allclose(J @ vecs, vecs * vals, atol=1e-9 * scale)
    assert np.all(np.diff(vals.real) <= 0)


def test_classification_tolerance():
    stable, marginal, unstable = stability.STABILITY_FLAGS.values()
    ev = np.array([[-1 + 2j, -1 - 2j, -3, -4, -5, -6],
                   [1e-13 + 5j, 1e-13 - 5j, -3, -4, -5, -6],
                   [0.5, -1, -3, -4, -5, -6]])
    flags, n_unstable, max_re = stability.classify(ev)
    assert list(flags) == [stable, marginal, unstable]
    assert list(n_unstable) == [0, 0, 1]
    np.testing.assert_allclose(max_re, [-1, 1e-13, 0.5])


def _measured_rates(branch, omega, eps, d_gamma, t_end, window, modes):
    """Growth rates of the modal amplitudes in a heyoka simulation started near the stationary solution."""
    sign = st.BRANCHES[branch]
    setup = td.Setup(friction=td.Friction(eps=eps))
    pars = ode.parameter_vector(setup)
    ds = td.simulate("ode-euler", t_end, setup=setup, dt_output=2e-3,
                     initial=td.InitialState(alpha_dot=omega, beta=math.pi / 2, gamma=sign * math.pi / 2 + d_gamma,
                                             gamma_dot=0.0))
    assert ds.attrs["status"] == "completed"
    x = reduced.reduced_from_full(*(ds[v].values for v in ("alpha", "beta", "gamma", "x_dot", "y_dot",
                                                          "omega_x", "omega_y", "omega_z")))
    vals, c = stability.modal_coordinates(x, branch, omega, pars)
    t = ds["time"].values
    m = (t >= window[0]) & (t <= window[1])
    measured = [np.polyfit(t[m], np.log(np.abs(c[k, m])), 1)[0] for k in modes]
    return vals[list(modes)].real, np.array(measured)


def test_linearisation_predicts_strong_instability_of_noninverted_spinning():
    predicted, measured = _measured_rates("noninverted", 40.0, 0.1, 1e-7, 0.8, (0.1, 0.8), modes=(0,))
    assert predicted[0] > 5  # strongly unstable: a real eigenvalue
    np.testing.assert_allclose(measured, predicted, rtol=1e-3)


def test_linearisation_predicts_weak_instability_of_inverted_spinning():
    predicted, measured = _measured_rates("inverted", 40.0, 0.1, 1e-4, 5.0, (0.5, 5.0), modes=(0,))
    assert 0 < predicted[0] < 1  # weakly unstable wobble (complex pair)
    np.testing.assert_allclose(measured, predicted, rtol=1e-3)


def test_linearisation_predicts_decay_in_the_stable_window():
    predicted, measured = _measured_rates("inverted", 31.0, 0.25, 1e-3, 5.0, (0.5, 5.0), modes=(0, 2))
    assert np.all(predicted < 0)
    np.testing.assert_allclose(measured, predicted, rtol=2e-3)


def test_batched_evaluation_matches_pointwise():
    rng = np.random.default_rng(3)
    omega = rng.uniform(-80, 80, 6)
    pars = np.repeat(PARS[:, None], 6, axis=1)
    pars[8] = rng.uniform(0.01, 1.0, 6)  # eps per point
    batch = stability.spectrum("inverted", omega, pars)
    for i in range(6):
        single = stability.spectrum("inverted", [omega[i]], pars[:, i])
        np.testing.assert_array_equal(batch.jacobian[i], single.jacobian[0])
        np.testing.assert_allclose(batch.eigenvalues[i], single.eigenvalues[0], rtol=1e-12, atol=1e-12)
