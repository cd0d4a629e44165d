"""Piecewise polynomials on a mesh of [0, 1] for orthogonal collocation (:mod:`.collocation`): the Gauss-Legendre
basis, evaluation and interpolation, the error estimate and the adapted mesh (as COLSYS and AUTO-07p).

On mesh interval j, [tau_j, tau_j+1] of length h_j, the orbit is the polynomial of degree m = ncol through its
values at the m + 1 equally spaced nodes s_i = i / m (s = (tau - tau_j) / h_j); neighbouring intervals share their
end node and the last node is the first (a periodic, continuous piecewise polynomial). It satisfies the
differential equation at the m Gauss-Legendre points z_k of each interval (collocation).

Error (Ascher, Mattheij & Russell, Numerical Solution of BVPs for ODEs, Sect. 9.3): the m-th derivative of each
piece is a constant d_j; its jumps estimate the (m+1)-th derivative x^(m+1) at the mesh points, and the error of
the polynomial inside interval j is about C_m h_j^(m+1) |x^(m+1)| with C_m = max_s |int_0^s prod_k (r - z_k) dr| / m!
(the local error of Gauss collocation; at the mesh points it is of order h^(2m), superconvergence). The adapted
mesh equidistributes |x^(m+1)|^(1/(m+1)), which equalises that estimate over the intervals.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..errors import ParameterError

NCOL_RANGE = (2, 7)
MONITOR_FLOOR = 0.05  # the adapted mesh's density is at least this share of its mean (no empty stretches)
GRADING = 1.5  # ... and neighbouring intervals of an adapted mesh differ in size by about this factor at most


@dataclass(frozen=True)
class Basis:
    """The Lagrange basis of degree m on s_i = i/m and the Gauss-Legendre points z_k of [0, 1]."""

    m: int
    coefficients: np.ndarray  # (m+1, m+1): L_i(s) = sum_p coefficients[i, p] s^p
    gauss: np.ndarray  # (m,) z_k
    weights: np.ndarray  # (m,) Gauss weights on [0, 1] (sum 1)
    at_gauss: np.ndarray  # (m, m+1) L_i(z_k)
    slope_at_gauss: np.ndarray  # (m, m+1) L_i'(z_k)
    top: np.ndarray  # (m+1,) d^m L_i / ds^m (constants)
    error_constant: float  # C_m
    both: np.ndarray  # (2m, m+1) at_gauss over slope_at_gauss (one product gives x and x')

    def values(self, s: np.ndarray) -> np.ndarray:
        """L_i(s) for points s (K,): (K, m+1)."""
        powers = np.asarray(s, dtype=float)[:, None] ** np.arange(self.m + 1)[None, :]
        return powers @ self.coefficients.T


@lru_cache(maxsize=None)
def basis(m: int) -> Basis:
    """The collocation basis for ncol = m (cached)."""
    if int(m) != m or not NCOL_RANGE[0] <= m <= NCOL_RANGE[1]:
        raise ParameterError(f"ncol = {m!r}; give an integer from {NCOL_RANGE[0]} to {NCOL_RANGE[1]} (4 is AUTO's "
                             "default)")
    nodes = np.arange(m + 1) / m
    coefficients = np.linalg.inv(np.vander(nodes, increasing=True)).T  # row i: the coefficients of L_i
    g, w = np.polynomial.legendre.leggauss(m)
    z, w = (g + 1) / 2, w / 2
    powers = z[:, None] ** np.arange(m + 1)[None, :]
    slopes = np.zeros_like(powers)
    slopes[:, 1:] = np.arange(1, m + 1)[None, :] * z[:, None] ** np.arange(m)[None, :]
    node_polynomial = np.polynomial.Polynomial.fromroots(z).integ()  # int_0^s prod_k (r - z_k) dr
    s = np.linspace(0.0, 1.0, 2001)
    constant = float(np.max(np.abs(node_polynomial(s) - node_polynomial(0.0)))) / math.factorial(m)
    at, slope = powers @ coefficients.T, slopes @ coefficients.T
    return Basis(m, coefficients, z, w, at, slope, math.factorial(m) * coefficients[:, m], constant,
                 np.vstack([at, slope]))


class Mesh:
    """A mesh 0 = tau_0 < ... < tau_ntst = 1 with the nodes of ncol = m (``basis(m)``)."""

    def __init__(self, tau, m: int):
        tau = np.asarray(tau, dtype=float)
        if tau.ndim != 1 or len(tau) < 3 or tau[0] != 0.0 or tau[-1] != 1.0 or np.any(np.diff(tau) <= 0):
            raise ParameterError("a collocation mesh needs at least 2 intervals, from 0 to 1, increasing")
        self.tau = tau
        self.basis = basis(m)
        self.m = m
        self.ntst = len(tau) - 1
        self.h = np.diff(tau)
        self.n_nodes = self.ntst * m
        self.times = (tau[:-1, None] + self.h[:, None] * np.arange(m)[None, :] / m).ravel()
        self.intervals = (np.arange(self.ntst)[:, None] * m + np.arange(m + 1)[None, :]) % self.n_nodes
        w = np.repeat(self.h / m, m)  # quadrature weights of the nodes (the arclength metric), sum 1
        w[::m] = (self.h + np.roll(self.h, 1)) / (2 * m)
        self.weights = w

    @classmethod
    def uniform(cls, ntst: int, m: int) -> Mesh:
        if int(ntst) != ntst or ntst < 2:
            raise ParameterError(f"ntst = {ntst!r}; give an integer >= 2 mesh intervals (AUTO's default 20)")
        return cls(np.linspace(0.0, 1.0, int(ntst) + 1), m)

    def pieces(self, X: np.ndarray) -> np.ndarray:
        """The node values of each interval, (ntst, m+1, n), from node values X (n_nodes, n): a strided view of X
        with its first node appended (neighbouring intervals share a node)."""
        closed = np.concatenate([X, X[:1]])
        rows, cols = closed.strides
        return np.lib.stride_tricks.as_strided(closed, (self.ntst, self.m + 1, X.shape[1]), (self.m * rows, rows, cols),
                                               writeable=False)

    def at_gauss(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """x and dx/dtau at the Gauss points, each (ntst, m, n)."""
        both = self.basis.both @ self.pieces(X)  # (ntst, 2m, n)
        return both[:, : self.m], both[:, self.m:] / self.h[:, None, None]

    def gauss_times(self) -> np.ndarray:
        """tau of the Gauss points, (ntst, m)."""
        return self.tau[:-1, None] + self.h[:, None] * self.basis.gauss[None, :]

    def evaluate(self, X: np.ndarray, tau) -> np.ndarray:
        """The piecewise polynomial at times ``tau`` (taken modulo 1): (len(tau), n)."""
        t = np.mod(np.asarray(tau, dtype=float), 1.0)
        j = np.clip(np.searchsorted(self.tau, t, side="right") - 1, 0, self.ntst - 1)
        s = (t - self.tau[j]) / self.h[j]
        return np.einsum("ki,kin->kn", self.basis.values(s), self.pieces(X)[j])

    def top_derivatives(self, X: np.ndarray) -> np.ndarray:
        """d^m x / dtau^m on each interval (constants), (ntst, n)."""
        return np.einsum("i,jin->jn", self.basis.top, self.pieces(X)) / self.h[:, None] ** self.m

    def error_indicator(self, X: np.ndarray, scale) -> np.ndarray:
        """|x^(m+1)| / scale on each interval (ntst,): the jumps of the m-th derivative at its two ends, per
        unit of the mean of the neighbouring intervals, averaged (periodic)."""
        d = self.top_derivatives(X) / np.asarray(scale, dtype=float)[None, :]
        jumps = np.abs(d - np.roll(d, 1, axis=0)).max(axis=1) / (0.5 * (self.h + np.roll(self.h, 1)))
        return 0.5 * (jumps + np.roll(jumps, -1))

    def error_estimate(self, X: np.ndarray, scale) -> float:
        """max_j C_m h_j^(m+1) |x^(m+1)| / scale: the estimated largest error of the orbit x(tau) (module
        docstring)."""
        return float(np.max(self.basis.error_constant * self.h ** (self.m + 1) * self.error_indicator(X, scale)))

    def _density(self, X: np.ndarray, scale, ntst: int | None = None) -> np.ndarray:
        """|x^(m+1)|^(1/(m+1)) / scale on each interval, at least MONITOR_FLOOR times its mean, and smoothed so that
        neighbouring intervals of the mesh of ``ntst`` intervals (default as many) that equidistributes it differ in
        size by at most GRADING (where they differ much, the jumps misjudge x^(m+1)): the spacing that mesh gives,
        Theta / (ntst density), may grow by at most GRADING - 1 per unit of tau (a Lipschitz envelope from below)."""
        density = self.error_indicator(X, scale) ** (1.0 / (self.m + 1))
        if not np.any(density > 0):
            return np.ones(self.ntst)
        density = np.maximum(density, MONITOR_FLOOR * np.mean(density))
        ntst = self.ntst if ntst is None else ntst
        centres = 0.5 * (self.tau[1:] + self.tau[:-1])
        c = np.concatenate([centres - 1.0, centres, centres + 1.0])  # periodic: the neighbours across tau = 0
        slope = GRADING - 1.0
        for _ in range(3):  # the total changes with the density: a few passes settle it
            spacing = np.tile(np.sum(density * self.h) / (ntst * density), 3)
            forward = slope * c + np.minimum.accumulate(spacing - slope * c)
            backward = -slope * c + np.minimum.accumulate((spacing + slope * c)[::-1])[::-1]
            graded = np.minimum(forward, backward)[self.ntst:2 * self.ntst]
            density = np.sum(density * self.h) / (ntst * graded)
        return density

    def needed_intervals(self, X: np.ndarray, scale, tol: float) -> int:
        """The intervals of an equidistributed mesh on which the error estimate is ``tol``: on it each interval
        holds C_m (int rho / ntst)^(m+1), rho the density of :meth:`adapted`."""
        integral = float(np.sum(self._density(X, scale) * self.h))  # graded for the present ntst
        return math.ceil(integral * (self.basis.error_constant / tol) ** (1.0 / (self.m + 1)))

    def adapted(self, X: np.ndarray, scale, ntst: int | None = None) -> Mesh:
        """The mesh of ``ntst`` intervals (default as many) that equidistributes |x^(m+1)|^(1/(m+1)), the error
        estimate."""
        ntst = self.ntst if ntst is None else int(ntst)
        density = self._density(X, scale, ntst)
        cumulative = np.concatenate([[0.0], np.cumsum(density * self.h)])
        tau = np.interp(np.linspace(0.0, cumulative[-1], ntst + 1), cumulative, self.tau)
        tau[0], tau[-1] = 0.0, 1.0
        return Mesh(tau, self.m)

    def __eq__(self, other) -> bool:
        return isinstance(other, Mesh) and self.m == other.m and np.array_equal(self.tau, other.tau)

    __hash__ = None
