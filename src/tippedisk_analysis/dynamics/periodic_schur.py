"""Eigenvalues of a product of pencils without forming it: the Floquet multipliers of a collocation orbit from its
condensed blocks, accurate when they spread over hundreds of orders of magnitude.

The blocks are N pencils (A_j, B_j) of size n x n: A_j x_j + B_j x_j+1 = 0, so x_N = M x_0 with the monodromy
M = (-B_N-1^-1 A_N-1) ... (-B_0^-1 A_0). Neither M nor any B_j^-1 is formed. A periodic QR sweep (orthogonal
iteration on the formal product: the unshifted form of Bojanczyk, Golub & Van Dooren's periodic QR algorithm)
carries an orthonormal basis Z_0 of R^n once around the product:

    A_j Z_j = Q_j S_j (QR),    Q_j^T B_j = T_j Z_j+1^T (RQ),

S_j and T_j upper triangular, so M Z_0 = Z_N P with P = prod_j (-T_j^-1 S_j) upper triangular and
Z_0^T M Z_0 = W P, W = Z_0^T Z_N. Sweeps repeat with Z_0 <- Z_N until W is block upper triangular to SPLIT_TOL; each
block's multipliers then are those of W_bb P_bb, and a block of one multiplier is the product of the diagonal
ratios, summed as logarithms: mu_k = W_kk prod_j (-S_j,kk / T_j,kk), each factor from one backward-stable QR, so
its relative error stays near round-off whatever the spread (a dense M loses every multiplier below
eps |M|). Multipliers of nearly equal modulus (complex pairs, the trivial one with its neighbours at a
bifurcation) do not separate by sweeps (the rate is their modulus ratio): they stay in one block whose product,
normalised interval by interval, has a modest spread.

A factor with a zero diagonal entry of T_j (a singular B_j) makes a multiplier infinite or undefined: the status
is ``singular`` with the interval named, never an exception.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

SPLIT_TOL = 1e-11  # W's block below the diagonal at which two groups of multipliers separate (their relative error;
# the sweeps' round-off floor is about N n eps)
MAX_SWEEPS = 60  # sweeps at most; a split that cannot reach SPLIT_TOL within them keeps its multipliers together
RATE_WINDOW = 3  # sweeps over which a split's convergence rate is measured
NEAR_ONE = 1e-3  # multipliers this far from 1 (plus the same share of the nearest's distance) may be the trivial one
STATUSES = ("completed", "singular", "nonfinite")


@dataclass
class ProductSpectrum:
    """The multipliers of a product of pencils (module docstring), block by block (by modulus descending where the
    sweeps separated them)."""

    values: np.ndarray  # complex (n,); +-inf where the modulus exceeds the float range
    log_moduli: np.ndarray  # log |mu| (n,), finite also where |mu| overflows; -inf for mu = 0
    blocks: tuple  # (start, stop) of the diagonal blocks of W P, in the order of ``values``
    basis: np.ndarray  # Z_0 (n, n): the orthonormal basis the periodic Schur form refers to at x_0
    block_vectors: tuple  # eigenvectors of each block's W_bb P_bb (columns), in the coordinates Z_0^T x
    sweeps: int
    status: str  # one of STATUSES
    message: str

    @property
    def completed(self) -> bool:
        return self.status == "completed"

    def flow_index(self, direction: np.ndarray) -> int:
        """The position of the multiplier near 1 whose eigenvector is ``direction`` (the flow f(x_0)): the block
        where direction's coordinates end (nothing after it) and whose eigenvector it lies along."""
        y = self.basis.T @ (direction / (np.linalg.norm(direction) or 1.0))
        distance = np.abs(self.values - 1.0)
        near = np.flatnonzero(distance <= NEAR_ONE + NEAR_ONE * distance.min())
        candidates = near if near.size else np.arange(len(self.values))
        scores = []
        for k in candidates:
            b = next(i for i, (start, stop) in enumerate(self.blocks) if start <= k < stop)
            start, stop = self.blocks[b]
            vectors = self.block_vectors[b]
            column = int(np.argmin(np.abs(self._block_values(b) - self.values[k])))
            v = vectors[:, column]
            along = abs(np.vdot(v, y[start:stop])) / (np.linalg.norm(v) or 1.0)
            tail = float(np.linalg.norm(y[stop:]))
            scores.append(along / (along + tail + 1e-300) - distance[k])
        return int(candidates[int(np.argmax(scores))])

    def _block_values(self, b: int) -> np.ndarray:
        start, stop = self.blocks[b]
        return self.values[start:stop]


@njit(cache=True)
def _sweep(A, B, Z0, S, T):
    """One periodic QR sweep (module docstring): S_j, T_j into S, T (N, n, n); returns Z_N."""
    N, n, _ = A.shape
    Z = Z0.copy()
    for j in range(N):
        Q, R = np.linalg.qr(np.ascontiguousarray(A[j] @ Z))
        S[j] = R
        C = np.ascontiguousarray(Q.T) @ B[j]
        # RQ of C from the QR of C^T J (J reverses the order): C = (J R1^T J) (J Q1^T)
        Q1, R1 = np.linalg.qr(np.ascontiguousarray(C.T[:, ::-1]))
        T[j] = R1.T[::-1, ::-1]
        Z = np.ascontiguousarray(Q1[:, ::-1])
    return Z


@njit(cache=True)
def _block_product(S, T, start, stop):
    """(P / scale, log scale): P = prod_j (-T_j^-1 S_j) on the diagonal block [start, stop) (upper triangular
    factors: their diagonal blocks multiply), normalised factor by factor."""
    N = S.shape[0]
    c = stop - start
    P = np.eye(c)
    log_scale = 0.0
    for j in range(N):
        Sb = S[j, start:stop, start:stop]
        Tb = T[j, start:stop, start:stop]
        R = Sb @ P
        for col in range(c):  # back substitution: T_b X = -R
            for row in range(c - 1, -1, -1):
                acc = -R[row, col]
                for k in range(row + 1, c):
                    acc -= Tb[row, k] * R[k, col]
                R[row, col] = acc / Tb[row, row]
        size = np.abs(R).max()
        if not size > 0:
            return R, log_scale
        P = R / size
        log_scale += math.log(size)
    return P, log_scale


def _lower_norms(W: np.ndarray) -> np.ndarray:
    """max |W[k:, :k]| for k = 1 .. n-1: how far the first k basis vectors are from an invariant subspace."""
    n = len(W)
    return np.array([np.abs(W[k:, :k]).max() for k in range(1, n)])


def _blocks(splits: np.ndarray, n: int) -> list:
    edges = [0] + [int(k) + 1 for k in np.flatnonzero(splits)] + [n]
    return list(zip(edges[:-1], edges[1:]))


def product_eigenvalues(A: np.ndarray, B: np.ndarray, basis: np.ndarray | None = None, *,
                        max_sweeps: int = MAX_SWEEPS, tol: float = SPLIT_TOL) -> ProductSpectrum:
    """The eigenvalues of M = prod_j (-B_j^-1 A_j) (j = N-1 first) from the pencils A, B (N, n, n) by periodic QR
    sweeps (module docstring); ``basis``: a start for Z_0 (e.g. the last orbit's, so that a branch needs one or two
    sweeps)."""
    A = np.ascontiguousarray(A, dtype=float)
    B = np.ascontiguousarray(B, dtype=float)
    N, n, _ = A.shape
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(B))):
        return _failed(n, "nonfinite", "the collocation blocks are not finite: the orbit cannot be evaluated")
    Z0 = np.eye(n) if basis is None or basis.shape != (n, n) else np.ascontiguousarray(basis, dtype=float)
    S, T = np.empty_like(A), np.empty_like(B)
    history = []
    splits = np.zeros(n - 1, bool)
    sweeps = 0
    for sweeps in range(1, max_sweeps + 1):
        ZN = _sweep(A, B, Z0, S, T)
        W = Z0.T @ ZN
        lower = _lower_norms(W)
        history.append(lower)
        splits = lower <= tol
        if splits.all() or sweeps == max_sweeps:
            break
        if sweeps > RATE_WINDOW:  # stop where every open split is too slow to close within the sweeps left
            rate = (lower / np.maximum(history[-1 - RATE_WINDOW], 1e-300)) ** (1.0 / RATE_WINDOW)
            reachable = lower * np.minimum(rate, 1.0) ** (max_sweeps - sweeps) <= tol
            if not np.any(reachable & ~splits):
                break
        Z0 = ZN
    return _spectrum(S, T, W, Z0, _blocks(splits, n), sweeps)


def _failed(n: int, status: str, message: str) -> ProductSpectrum:
    nan = np.full(n, complex(math.nan))
    return ProductSpectrum(nan, np.full(n, math.nan), ((0, n),), np.eye(n), (np.eye(n, dtype=complex),), 0, status,
                           message)


def _spectrum(S, T, W, Z0, blocks, sweeps) -> ProductSpectrum:
    """The multipliers block by block (module docstring)."""
    N, n, _ = S.shape
    values, logs, vectors, status, message = [], [], [], "completed", ""
    for start, stop in blocks:
        diagonal_T = np.abs(np.diagonal(T[:, start:stop, start:stop], axis1=1, axis2=2))
        singular = np.flatnonzero(~(diagonal_T > 0).all(axis=1))
        if singular.size:
            status = "singular"
            message = (f"the collocation block of mesh interval {singular[0]} is singular (its pencil has a zero "
                       f"pivot): raise ntst or ncol, or check the field's smoothness on the orbit")
            values += [complex(math.nan)] * (stop - start)
            logs += [math.nan] * (stop - start)
            vectors.append(np.eye(stop - start, dtype=complex))
            continue
        if stop - start == 1:
            s, t = S[:, start, start], T[:, start, start]
            with np.errstate(divide="ignore"):
                log_mod = float(np.log(abs(W[start, start])) + np.sum(np.log(np.abs(s))) - np.sum(np.log(np.abs(t))))
            sign = np.sign(W[start, start]) * np.prod(-np.sign(s) * np.sign(t))
            values.append(complex(sign * math.exp(min(log_mod, 709.0))) if log_mod <= 709 else complex(sign * math.inf))
            logs.append(log_mod)
            vectors.append(np.ones((1, 1), complex))
            continue
        P, log_scale = _block_product(S, T, start, stop)
        vals, vecs = np.linalg.eig(W[start:stop, start:stop] @ P)
        with np.errstate(divide="ignore"):
            block_logs = np.log(np.abs(vals)) + log_scale
        values += [v * math.exp(min(lg - math.log(abs(v)), 709.0)) if v != 0 and lg <= 709 else
                   (complex(math.inf) if v != 0 else 0j) for v, lg in zip(vals, block_logs)]
        logs += list(block_logs)
        vectors.append(vecs)
    values, logs = np.array(values, complex), np.array(logs)
    if status == "completed" and not np.all(np.isfinite(logs) | (logs == -np.inf)):
        status, message = "nonfinite", "a multiplier is not a number: the collocation blocks are not finite"
    return ProductSpectrum(values, logs, tuple(blocks), Z0, tuple(vectors), sweeps, status, message)
