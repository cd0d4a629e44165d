"""Linear stability from eigenvalues (equilibria) and Floquet multipliers (periodic orbits): one set of flags
and tolerances for every dataset of the package."""

from __future__ import annotations

import numpy as np

from ..defaults import EIG_ATOL, EIG_RTOL

STABILITY_FLAGS = {"stable": 0, "marginal": 1, "unstable": 2}
"""int8 codes of the ``stability`` variables (flag_values / flag_meanings in every dataset)."""


def classify(eigenvalues: np.ndarray, atol: float = EIG_ATOL, rtol: float = EIG_RTOL):
    """(stability int8, n_unstable, max_real_eig) of eigenvalues (..., k): unstable if some real part exceeds
    tol = atol + rtol max |s|, stable if all lie below -tol, marginal otherwise (the linearisation does not
    decide)."""
    ev = np.asarray(eigenvalues)
    tol = atol + rtol * np.max(np.abs(ev), axis=-1)
    re = ev.real
    max_re = re.max(axis=-1)
    n_unstable = np.sum(re > tol[..., None], axis=-1)
    stability = np.where(n_unstable > 0, STABILITY_FLAGS["unstable"],
                         np.where(max_re < -tol, STABILITY_FLAGS["stable"], STABILITY_FLAGS["marginal"]))
    return stability.astype(np.int8), n_unstable.astype(np.int32), max_re


def sorted_eigenvalues(J: np.ndarray) -> np.ndarray:
    """Eigenvalues of J (..., k, k), sorted by real part, descending."""
    ev = np.linalg.eigvals(np.asarray(J, dtype=float))
    return np.take_along_axis(ev, np.argsort(-ev.real, axis=-1, kind="stable"), axis=-1)
