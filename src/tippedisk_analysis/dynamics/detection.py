"""Test functions of equilibrium branches (on the eigenvalues of the state Jacobian) and the labels of special
points, for the continuation core (:mod:`.continuation`)."""

from __future__ import annotations

import math

import numpy as np


def zero_test(ev: np.ndarray) -> float:
    """det = prod s_i (real): changes sign when a real eigenvalue crosses 0."""
    return float(np.prod(ev).real)


def hopf_test(ev: np.ndarray) -> float:
    """prod_{i<j} (s_i + s_j) (real): the determinant of the bialternate product."""
    i, j = np.triu_indices(len(ev), 1)
    return float(np.prod(ev[i] + ev[j]).real)


def nearest_real(ev: np.ndarray) -> float:
    real = ev[np.abs(ev.imag) <= 1e-12 * max(1.0, np.abs(ev).max())].real
    return float(real[np.argmin(np.abs(real))]) if real.size else math.nan


def nearest_pair(ev: np.ndarray) -> complex:
    pairs = ev[ev.imag > 1e-12 * max(1.0, np.abs(ev).max())]
    return complex(pairs[np.argmin(np.abs(pairs.real))]) if pairs.size else complex(math.nan)


LABELS = {"fold": "LP", "branch_point": "BP", "hopf": "HOPF", "bogdanov_takens": "BT", "zero_hopf": "ZH",
          "double_hopf": "HH", "bautin": "GH", "cusp": "CP", "line_saddle_change": "LS",
          "line_focus_node": "LF", "period_doubling": "PD", "neimark_sacker": "NS", "homoclinic": "HC", "user": "UZ",
          "heteroclinic": "HET", "snic": "SNIC", "period_bound": "PB"}


def label_points(special: list) -> None:
    counts: dict[str, int] = {}
    for sp in special:
        counts[sp.kind] = counts.get(sp.kind, 0) + 1
        sp.label = LABELS.get(sp.kind, sp.kind.upper()) + str(counts[sp.kind])
