"""Floquet multipliers of collocation orbits and the test functions built on them (:class:`CollocationFloquet`, a
part of :class:`.collocation.CollocationProblem`).

The multipliers come from the condensed collocation blocks: pencils (A_j, B_j) per mesh interval with
A_j x_j + B_j x_j+1 = 0, their product's eigenvalues by periodic QR sweeps (:mod:`.periodic_schur`), never the
monodromy formed, so each multiplier keeps its relative accuracy where they spread over many orders of magnitude.
The test functions count the multipliers outside the unit circle and measure their distances from +1, -1 and the
circle, bounded however large the multipliers are.
"""

from __future__ import annotations

import math

import numpy as np

from .flows import MULTIPLIER_TOL
from .periodic_schur import product_eigenvalues

ACCEPT_SHARE = 2.0  # a located crossing's multiplier may be this many flow-direction errors off the circle


class CollocationFloquet:
    """The multipliers of an evaluation ``ev`` (its ``condensed`` blocks, ``f0`` = f(x(0))) and what is decided from
    them; the problem keeps ``_basis``, the last periodic Schur basis, to start the next orbit's sweeps from it."""

    def _multipliers(self, ev: dict) -> tuple:
        """(multipliers by modulus descending, trivial mask, flow direction's mask, its |mu - 1|, status, message)
        from the condensed blocks (:mod:`.periodic_schur`); the trivial ones: the flow direction's and the
        n_trivial - 1 others nearest 1."""
        spectrum = product_eigenvalues(*ev["condensed"], basis=self._basis)
        n = self.n
        if not spectrum.completed:
            none = np.zeros(n, bool)
            return np.full(n, complex(np.nan)), none, none, math.nan, spectrum.status, spectrum.message
        self._basis = spectrum.basis
        flow = np.zeros(n, bool)
        flow[spectrum.flow_index(ev["f0"])] = True
        trivial = flow.copy()
        for _ in range(self.system.n_trivial - 1):
            rest = np.flatnonzero(~trivial)
            trivial[rest[np.argmin(np.abs(spectrum.values[rest] - 1.0))]] = True
        order = np.argsort(-spectrum.log_moduli, kind="stable")
        return (spectrum.values[order], trivial[order], flow[order], float(abs(spectrum.values[flow][0] - 1.0)),
                "completed", f"{spectrum.sweeps} periodic QR sweep(s)")

    def floquet(self, ev: dict, n_trivial: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(multipliers, trivial mask) of an evaluation from the condensed blocks; ``n_trivial`` = 1: the flow
        direction's alone."""
        mu, trivial, flow = ev["multipliers"][:3]
        return mu, (flow if n_trivial == 1 else trivial)

    def flow_multiplier_error(self, u) -> float:
        """|mu - 1| of the flow direction's multiplier (from the condensed blocks; NaN where they fail)."""
        ev = self._evaluate(u)
        return math.nan if "error" in ev else ev["multipliers"][3]

    def state_eigenvalues(self, u) -> np.ndarray:
        """The multipliers but the flow direction's, by real part descending (NaN where they cannot be
        computed)."""
        ev = self._evaluate(u)
        if "error" in ev:
            return np.full(self.n - 1, complex(math.nan))
        mu, flow = self.floquet(ev, n_trivial=1)
        if not flow.any():
            return np.full(self.n - 1, complex(math.nan))
        rest = mu[~flow]
        return rest[np.argsort(-rest.real, kind="stable")]

    def tests(self, point) -> dict:
        """The test functions of :meth:`.orbit_base.OrbitProblem.tests`, bounded for any size of multipliers: the
        sign of prod (mu_i - 1) (the parity of the real multipliers below 1) times the distance of the nearest one
        from 1; likewise prod (mu_i + 1) and prod_{i<j} (mu_i mu_j - 1); NaN where the multipliers fail their check
        (:func:`.orbit_base.multipliers_decide`)."""
        tests = super().tests(point)
        mu = self._nontrivial(point.eigenvalues)
        i, j = np.triu_indices(len(mu), 1)
        for kind, values in (("branch_point", mu - 1.0), ("period_doubling", mu + 1.0),
                             ("neimark_sacker", mu[i] * mu[j] - 1.0)):
            if kind in tests and not math.isnan(tests[kind]):
                tests[kind] = signed_distance(values)
        return tests

    def accept(self, kind: str, point, value: float, options):
        """As :meth:`.orbit_base.OrbitProblem.accept`, with a located branch point, period doubling or
        Neimark-Sacker point's critical multiplier allowed ACCEPT_SHARE times the flow direction's error off the
        unit circle: the discretisation unfolds a crossing through +1 into two multipliers that avoid each other
        by about that much."""
        if kind in ("branch_point", "period_doubling", "neimark_sacker"):
            allowed = max(MULTIPLIER_TOL, options.locate_tol, ACCEPT_SHARE * self.flow_multiplier_error(point.u))
            return math.isfinite(value) and abs(value) <= allowed
        return super().accept(kind, point, value, options)


def signed_distance(values: np.ndarray) -> float:
    """The sign of Re prod(values) (complex values come in conjugate pairs) times min |values|: zero where one
    of them is, and bounded whatever their size."""
    values = np.asarray(values, dtype=complex)
    if not values.size:
        return 1.0
    if np.any(np.isnan(values)):
        return math.nan
    real = values[np.abs(values.imag) <= 1e-12 * np.maximum(1.0, np.abs(values))].real
    return float((-1.0) ** int(np.sum(real < 0)) * np.abs(values).min())


def formed_monodromy(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """prod_j (-B_j^-1 A_j) formed densely (NaN where a B_j is singular)."""
    M = np.eye(A.shape[1])
    try:
        for A_j, B_j in zip(A, B):
            M = -np.linalg.solve(B_j, A_j @ M)
    except np.linalg.LinAlgError:
        return np.full_like(M, np.nan)
    return M
