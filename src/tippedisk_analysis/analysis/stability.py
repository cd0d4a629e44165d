"""Exact Jacobian of the reduced system and eigenvalue stability of the spinning solutions.

The Jacobian of the reduced right-hand side (:func:`.reduced.jacobian`) is exact (heyoka's
symbolic differentiation, compiled once) and evaluated in batches: states (7, N), parameters
(11, N) or (11,).

Zero slip. At the stationary solutions the slip gamma_T1 vanishes. The naive chain rule of
|gamma_T| = sqrt(gx^2 + gy^2) divides by zero there; the model evaluates |gamma_T| as
sqrt(|gamma_T|^2 + delta^2) - delta (:func:`tippedisk_analysis.models.ode.slip_magnitude`),
whose derivative is 0 at zero slip, so d/d gamma_T [mu gamma_T / (|gamma_T| + eps)] = mu I/eps,
the derivative of the regularised law (2.29). The compiled Jacobian is finite there.

Structural zero eigenvalues. The full ODE Model 1 (11 states) has five: x, y, alpha and
W_friction are cyclic (four zeros), and the spin family is a line of relative equilibria
(d/dOmega, a fifth). The reduction removes the first four. The fifth remains in the 7x7 reduced
Jacobian J: the family direction d x*/dOmega = sign e_{omega_x} is an exact null vector, i.e.
the omega_x *column* of J vanishes at every stationary solution. Expanding det(J - s I) along
that column gives det(J - s I) = -s det(J' - s I) with J' the 6x6 matrix without the omega_x
row and column, so the six *nontrivial* eigenvalues are those of J' (an exact deflation, no
tolerance needed).
Perturbations along the family (changing the spin rate) neither grow nor decay.

Classification (``classify``) of the six nontrivial eigenvalues s_k with
tol = atol + rtol max_k |s_k| (defaults.EIG_ATOL = 1e-9 1/s, EIG_RTOL = 1e-9, far above the
round-off of the Jacobian entries, far below physically relevant rates):

* unstable (2): some Re s_k > tol -- linearly unstable, perturbations grow like exp(Re s t);
* stable (0): every Re s_k < -tol -- asymptotically stable (modulo the spin family);
* marginal (1): otherwise, the linearisation does not decide.

``n_unstable`` counts Re s_k > tol; ``max_real_eig`` = max_k Re s_k [1/s].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..dynamics.spectra import STABILITY_FLAGS, classify  # noqa: F401 (stability.classify, .STABILITY_FLAGS)
from . import stationary as st
from .reduced import N_STATE, OMEGA_X_INDEX, jacobian

__all__ = ["Spectrum", "spectrum", "max_real_eig", "nontrivial_eigenvalues", "modal_coordinates"]

N_EIG = N_STATE - 1  # nontrivial eigenvalues (structural zero of the spin family removed)
KEEP = [i for i in range(N_STATE) if i != OMEGA_X_INDEX]

@dataclass(frozen=True)
class Spectrum:
    """Nontrivial eigenvalues at N stationary solutions (sorted by real part, descending)."""

    eigenvalues: np.ndarray  # (N, 6) complex [1/s]
    max_real_eig: np.ndarray  # (N,) [1/s]
    n_unstable: np.ndarray  # (N,) int
    stability: np.ndarray  # (N,) int8, STABILITY_FLAGS
    jacobian: np.ndarray  # (N, 7, 7)


def nontrivial_eigenvalues(J: np.ndarray) -> np.ndarray:
    """Eigenvalues of J without the spin-family zero (module docstring), sorted by real part desc."""
    J = np.asarray(J, dtype=float)
    reduced = J[..., KEEP, :][..., :, KEEP]
    ev = np.linalg.eigvals(reduced)
    order = np.argsort(-ev.real, axis=-1, kind="stable")
    return np.take_along_axis(ev, order, axis=-1)


def eigen(J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Nontrivial eigenvalues (6,) and eigenvectors (7, 6) (columns, unit norm) of one Jacobian.

    The eigenvectors of J' are lifted to J: with J = [[J', 0], [b^T, 0]] after moving the
    omega_x row/column last, J [w; c] = s [w; c] holds for c = b^T w / s (s != 0).
    """
    J = np.asarray(J, dtype=float)
    reduced = J[np.ix_(KEEP, KEEP)]
    vals, vecs = np.linalg.eig(reduced)
    order = np.argsort(-vals.real, kind="stable")
    vals, vecs = vals[order], vecs[:, order]
    b = J[OMEGA_X_INDEX, KEEP]
    full = np.zeros((N_STATE, N_EIG), dtype=complex)
    full[KEEP] = vecs
    with np.errstate(divide="ignore", invalid="ignore"):
        c = (b @ vecs) / vals
    full[OMEGA_X_INDEX] = np.where(np.isfinite(c), c, 0.0)
    full /= np.linalg.norm(full, axis=0)
    return vals, full


def spectrum(branch: str, omega, pars) -> Spectrum:
    """Stability of the stationary solutions of ``branch`` at spin rates ``omega`` (N,).

    pars: (11,) for all points or (11, N) per point (ode.PARAMETER_NAMES order).
    """
    x = st.stationary_state(branch, omega)
    J = jacobian(x, pars)
    ev = nontrivial_eigenvalues(J)
    stability, n_unstable, max_re = classify(ev)
    return Spectrum(ev, max_re, n_unstable, stability, J)


def max_real_eig(branch: str, omega: float, pars) -> float:
    """Largest real part of the nontrivial eigenvalues at one spin rate [1/s]."""
    return float(spectrum(branch, [omega], pars).max_real_eig[0])


def modal_coordinates(states, branch: str, omega: float, pars) -> tuple[np.ndarray, np.ndarray]:
    """Modal amplitudes of deviations from the stationary solution: (eigenvalues (6,), c (6, N)).

    The deviation y = x - x*(Omega) without its omega_x component (the spin family) obeys
    y_dot = J' y to first order, so c = V^-1 y (V: eigenvectors of J') evolves as
    c_k(t) = c_k(0) exp(s_k t): log|c_k| grows at the rate Re s_k. Used to compare the
    linearisation with simulations (tests/test_stability.py).
    """
    x_star = st.stationary_state(branch, [omega])
    J = jacobian(x_star, pars)[0]
    vals, vecs = np.linalg.eig(J[np.ix_(KEEP, KEEP)])
    order = np.argsort(-vals.real, kind="stable")
    vals, vecs = vals[order], vecs[:, order]
    y = np.asarray(states, dtype=float).reshape(N_STATE, -1) - x_star
    return vals, np.linalg.solve(vecs, y[KEEP])
