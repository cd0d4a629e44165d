"""The linear algebra of collocation (:mod:`.collocation`): the block-bordered Newton system solved by condensation of
parameters and a sequential elimination of the mesh points (AUTO-07p's method), compiled with numba; and the
condensed blocks of the first stage, whose product is the monodromy.

The system: per mesh interval j the collocation rows (m n) touch the interval's nodes (the mesh point x_j, m - 1
interior nodes, the mesh point x_j+1; x_ntst = x_0) and the q extra unknowns (T, p); b border rows (the phase
condition, the arclength, levels) touch everything. Three stages, each Gaussian elimination with partial pivoting
on small dense blocks, every row operation recorded so that a factorisation solves any number of right-hand
sides (chord steps, tangents):

1. in each interval the interior nodes are eliminated: n condensed rows A_j x_j + B_j x_j+1 + E_j e = r_j remain;
2. the mesh points x_1 .. x_ntst-1 are eliminated one after the other from F x_0 + G x_j + H e = s, leaving
   F x_0 + G x_ntst + H e = s (the Floquet multipliers come from the condensed blocks of stage 1 instead, by
   :mod:`.periodic_schur`: this elimination forms the product they span);
3. (F + G) x_0 + H e = s with the condensed border rows: a dense (n + b) x (n + q) system (least squares if b != q).

The border rows are condensed alongside (their coefficients on each eliminated unknown removed with the pivot rows).
Nothing of size (n ntst m)^2 is formed: memory and work grow like ntst.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from scipy import sparse

RANK_TOL = 1e-10  # singular values of the last stage below this share of the largest count as zero: the level rows of
# a family make it rank deficient, the discretisation only nearly so


@njit(cache=True)
def assemble(J, h, T, at_gauss, slope_at_gauss):
    """The collocation blocks d/dx (dx/dtau - T f(x)) at the Gauss points: (ntst, m n, (m+1) n), rows (point k,
    state a), columns (node i, state b): slope_i(z_k) / h_j delta_ab - T L_i(z_k) f_x[a, b] (J: (ntst, m, n, n))."""
    ntst, m, n, _n = J.shape
    out = np.zeros((ntst, m * n, (m + 1) * n))
    for j in range(ntst):
        for k in range(m):
            for i in range(m + 1):
                d = slope_at_gauss[k, i] / h[j]
                w = T * at_gauss[k, i]
                for a in range(n):
                    row = k * n + a
                    for b in range(n):
                        out[j, row, i * n + b] = -w * J[j, k, a, b]
                    out[j, row, i * n + a] += d
    return out


@njit(cache=True)
def _eliminate(rows, first, count, border, factors, pivots, multipliers):
    """Gaussian elimination with partial pivoting of columns first .. first + count - 1 of ``rows`` (r x c) in place:
    the first ``count`` rows become the pivot rows (upper triangular there), the others have zeros there; the row
    swaps go to ``pivots`` (count), the multipliers to ``multipliers`` (r x count). The border rows (k x c) lose
    those columns too, ``factors`` (k x count) record how."""
    r = rows.shape[0]
    multipliers[:] = 0.0
    for k in range(count):
        col = first + k
        best, p = -1.0, k
        for i in range(k, r):
            a = abs(rows[i, col])
            if a > best:
                best, p = a, i
        pivots[k] = p
        if p != k:
            for c in range(rows.shape[1]):
                rows[k, c], rows[p, c] = rows[p, c], rows[k, c]
        d = rows[k, col]
        if d == 0.0:
            continue
        for i in range(k + 1, r):
            f = rows[i, col] / d
            multipliers[i, k] = f
            if f != 0.0:
                for c in range(rows.shape[1]):
                    rows[i, c] -= f * rows[k, c]
    for k in range(count):  # the border rows, with the finished pivot rows
        col = first + k
        d = rows[k, col]
        for i in range(border.shape[0]):
            f = border[i, col] / d if d != 0.0 else 0.0
            factors[i, k] = f
            if f != 0.0:
                for c in range(rows.shape[1]):
                    border[i, c] -= f * rows[k, c]


@njit(cache=True)
def _replay(vector, pivots, multipliers):
    """The row operations of :func:`_eliminate` on a right-hand side (in place)."""
    for k in range(pivots.shape[0]):
        p = pivots[k]
        if p != k:
            vector[k], vector[p] = vector[p], vector[k]
        for i in range(k + 1, vector.shape[0]):
            vector[i] -= multipliers[i, k] * vector[k]


@njit(cache=True)
def factorise(blocks, extras, border_nodes, border_extras, m):
    """The factorisation of the system (module docstring). blocks (ntst, m n, (m+1) n) on the interval's nodes,
    extras (ntst, m n, q), border_nodes (b, ntst m, n), border_extras (b, q). Returns the tuple of arrays
    :func:`solve` takes and the pencil (F, G)."""
    ntst, mn, width = blocks.shape
    n = width // (m + 1)
    q = extras.shape[2]
    b = border_nodes.shape[0]
    inner = (m - 1) * n
    # stage 1: per interval, columns [x_j | interior | x_j+1 | e]
    top1 = np.empty((ntst, inner, width + q))
    cond = np.empty((ntst, n, 3 * n + q))  # the condensed rows, columns [x_0 | x_j | x_j+1 | e] (x_0 filled later)
    piv1 = np.empty((ntst, inner), np.int64)
    mul1 = np.empty((ntst, mn, inner))
    fac1 = np.empty((ntst, b, inner))
    # border rows in the reduced unknowns: [x_0 .. x_ntst-1 (mesh points) | e]
    bord = np.zeros((b, ntst * n + q))
    for i in range(b):
        for j in range(ntst):
            for a in range(n):
                bord[i, j * n + a] = border_nodes[i, j * m, a]
        for k in range(q):
            bord[i, ntst * n + k] = border_extras[i, k]
    rows = np.empty((mn, width + q))
    local = np.zeros((b, width + q))  # the border rows on one interval's columns
    for j in range(ntst):
        rows[:, :width] = blocks[j]
        rows[:, width:] = extras[j]
        local[:] = 0.0
        for i in range(b):
            for s in range(1, m):
                for a in range(n):
                    local[i, s * n + a] = border_nodes[i, j * m + s, a]
        _eliminate(rows, n, inner, local, fac1[j], piv1[j], mul1[j])
        top1[j] = rows[:inner]
        cond[j, :, :n] = 0.0
        cond[j, :, n:2 * n] = rows[inner:, :n]
        cond[j, :, 2 * n:3 * n] = rows[inner:, width - n:width]
        cond[j, :, 3 * n:] = rows[inner:, width:]
        nxt = (j + 1) % ntst
        for i in range(b):  # what the elimination moved onto the mesh points and the extras
            for a in range(n):
                bord[i, j * n + a] += local[i, a]
                bord[i, nxt * n + a] += local[i, width - n + a]
            for k in range(q):
                bord[i, ntst * n + k] += local[i, width + k]
    # stage 2: eliminate x_1 .. x_ntst-1; the relation [F | G | H] on [x_0 | x_j | e]
    rel = np.zeros((n, 3 * n + q))  # columns [x_0 | x_cur | (unused) | e]
    rel[:, :n] = cond[0, :, n:2 * n]
    rel[:, n:2 * n] = cond[0, :, 2 * n:3 * n]
    rel[:, 3 * n:] = cond[0, :, 3 * n:]
    piv2 = np.zeros((ntst, n), np.int64)
    mul2 = np.zeros((ntst, 2 * n, n))
    top2 = np.zeros((ntst, n, 3 * n + q))
    fac2 = np.zeros((ntst, b, n))
    stack = np.zeros((2 * n, 3 * n + q))
    local = np.zeros((b, 3 * n + q))  # border columns [x_0 | x_j | x_j+1 | e]
    for j in range(1, ntst):
        stack[:] = 0.0
        stack[:n, :n] = rel[:, :n]
        stack[:n, n:2 * n] = rel[:, n:2 * n]
        stack[:n, 3 * n:] = rel[:, 3 * n:]
        stack[n:, n:] = cond[j, :, n:]
        nxt = (j + 1) % ntst
        for i in range(b):
            for a in range(n):
                local[i, a] = bord[i, a]
                local[i, n + a] = bord[i, j * n + a]
                local[i, 2 * n + a] = bord[i, nxt * n + a] if nxt != 0 else 0.0
            for k in range(q):
                local[i, 3 * n + k] = bord[i, ntst * n + k]
        _eliminate(stack, n, n, local, fac2[j], piv2[j], mul2[j])
        top2[j] = stack[:n]
        rel[:, :n] = stack[n:, :n]
        rel[:, n:2 * n] = stack[n:, 2 * n:3 * n]
        rel[:, 3 * n:] = stack[n:, 3 * n:]
        for i in range(b):
            for a in range(n):
                bord[i, a] = local[i, a]
                bord[i, j * n + a] = 0.0
                if nxt != 0:
                    bord[i, nxt * n + a] = local[i, 2 * n + a]
                else:  # x_ntst is x_0
                    bord[i, a] += local[i, 2 * n + a]
            for k in range(q):
                bord[i, ntst * n + k] = local[i, 3 * n + k]
    pencil_F = rel[:, :n].copy()
    pencil_G = rel[:, n:2 * n].copy()
    # stage 3: (F + G) x_0 + H e = s and the border rows
    final = np.zeros((n + b, n + q))
    final[:n, :n] = pencil_F + pencil_G
    final[:n, n:] = rel[:, 3 * n:]
    for i in range(b):
        final[n + i, :n] = bord[i, :n]
        final[n + i, n:] = bord[i, ntst * n:]
    return (top1, piv1, mul1, fac1, cond, top2, piv2, mul2, fac2, final), (pencil_F, pencil_G)


@njit(cache=True)
def _reduce(factors, rhs_coll, rhs_border):
    """Stages 1 and 2 on a right-hand side: (the stage-1 pivot rows' rhs, the stage-2 pivot rows' rhs, the final
    rhs)."""
    top1, piv1, mul1, fac1, cond, top2, piv2, mul2, fac2, final = factors
    ntst, inner = piv1.shape
    n = cond.shape[1]
    b = fac1.shape[1]
    r1 = np.empty((ntst, inner))
    rc = np.empty((ntst, n))
    rb = rhs_border.copy()
    for j in range(ntst):
        v = rhs_coll[j].copy()
        _replay(v, piv1[j], mul1[j])
        r1[j] = v[:inner]
        rc[j] = v[inner:]
        for i in range(b):
            for k in range(inner):
                rb[i] -= fac1[j, i, k] * v[k]
    s = rc[0].copy()
    r2 = np.zeros((ntst, n))
    for j in range(1, ntst):
        v = np.empty(2 * n)
        v[:n] = s
        v[n:] = rc[j]
        _replay(v, piv2[j], mul2[j])
        r2[j] = v[:n]
        s = v[n:].copy()
        for i in range(b):
            for k in range(n):
                rb[i] -= fac2[j, i, k] * v[k]
    out = np.empty(n + b)
    out[:n] = s
    out[n:] = rb
    return r1, r2, out


@njit(cache=True)
def _back(factors, r1, r2, x0, e, m):
    """The mesh points and interior nodes from x_0 and the extras e: (ntst m, n) node states."""
    top1, piv1, mul1, fac1, cond, top2, piv2, mul2, fac2, final = factors
    ntst, inner = piv1.shape
    n = cond.shape[1]
    q = e.shape[0]
    width = (m + 1) * n
    mesh = np.empty((ntst + 1, n))
    mesh[0] = x0
    mesh[ntst] = x0
    for j in range(ntst - 1, 0, -1):  # U x_j = r - F x_0 - G x_j+1 - H e
        row = top2[j]
        v = r2[j].copy()
        for k in range(n):
            for a in range(n):
                v[k] -= row[k, a] * x0[a] + row[k, 2 * n + a] * mesh[j + 1, a]
            for a in range(q):
                v[k] -= row[k, 3 * n + a] * e[a]
        for k in range(n - 1, -1, -1):
            for a in range(k + 1, n):
                v[k] -= row[k, n + a] * mesh[j, a]
            mesh[j, k] = v[k] / row[k, n + k]
            # (mesh[j, a] for a > k is set before it is used: back substitution)
    nodes = np.empty((ntst * m, n))
    for j in range(ntst):
        row = top1[j]
        v = r1[j].copy()
        for k in range(inner):
            for a in range(n):
                v[k] -= row[k, a] * mesh[j, a] + row[k, width - n + a] * mesh[j + 1, a]
            for a in range(q):
                v[k] -= row[k, width + a] * e[a]
        c = np.empty(inner)
        for k in range(inner - 1, -1, -1):
            acc = v[k]
            for a in range(k + 1, inner):
                acc -= row[k, n + a] * c[a]
            c[k] = acc / row[k, n + k]
        nodes[j * m] = mesh[j]
        for s in range(1, m):
            nodes[j * m + s] = c[(s - 1) * n:s * n]
    return nodes


class Factorisation:
    """The collocation system at one u, factorised: solves for any right-hand side."""

    def __init__(self, blocks, extras, border_nodes, border_extras, m: int):
        self.m = m
        self.factors, self.pencil = factorise(blocks, extras, border_nodes, border_extras, m)

    @property
    def condensed(self) -> tuple[np.ndarray, np.ndarray]:
        """The condensed blocks (A_j, B_j) (ntst, n, n): A_j x_j + B_j x_j+1 = 0 on each mesh interval once its
        interior nodes are eliminated (the homogeneous part of stage 1; the Floquet multipliers are those of
        prod_j (-B_j^-1 A_j), :mod:`.periodic_schur`)."""
        cond = self.factors[4]
        n = cond.shape[1]
        return cond[:, :, n:2 * n], cond[:, :, 2 * n:3 * n]

    def solve(self, rhs_coll: np.ndarray, rhs_border: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(node corrections (ntst m, n), extras' corrections (q,)); least squares / least norm in the last stage
        where the border rows are more or fewer than the extras; non-finite where the system is singular."""
        r1, r2, rhs = _reduce(self.factors, rhs_coll, rhs_border)
        final = self.factors[-1]
        try:
            z = (np.linalg.solve(final, rhs) if final.shape[0] == final.shape[1]
                 else np.linalg.lstsq(final, rhs, rcond=RANK_TOL)[0])
        except np.linalg.LinAlgError:
            z = np.full(final.shape[1], np.nan)
        n = self.pencil[0].shape[0]
        return _back(self.factors, r1, r2, z[:n].copy(), z[n:].copy(), self.m), z[n:]


class Linearisation:
    """The collocation Jacobian at one u in scaled unknowns (u / scale), bordered: factorised once, it serves chord
    steps and tangents (the interface of :meth:`.continuation_interface.Problem.linearise`). ``borders``: the
    border rows (b, len(u)) in the layout of u, (T[, p], nodes); None for an evaluation that failed."""

    reusable = True
    matrix = None

    def __init__(self, blocks, extras, borders, scale, x_start: int, mesh, n: int):
        self.blocks, self.extras, self.borders, self.scale = blocks, extras, borders, scale
        self.x_start, self.mesh, self.n = x_start, mesh, n
        self.collocation_rows = mesh.n_nodes * n
        self.failed = blocks is None
        self.rows = self.collocation_rows + (0 if self.failed else len(borders))
        if not self.failed:
            k = x_start
            self.factorisation = Factorisation(blocks, extras, borders[:, k:].reshape(len(borders), -1, n),
                                               borders[:, :k], mesh.m)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """The solution in scaled unknowns for the right-hand side b (rows: collocation, then the borders)."""
        if self.failed:
            return np.full(len(self.scale), np.nan)
        c = self.collocation_rows
        nodes, extras = self.factorisation.solve(b[:c].reshape(self.mesh.ntst, -1), b[c:])
        return np.concatenate([extras, nodes.ravel()]) / self.scale

    def magnitude(self, v: np.ndarray) -> np.ndarray:
        """|A| |v| per row (v scaled): the round-off yardstick of a residual."""
        if self.failed:
            return np.full(self.rows, np.inf)
        u = np.abs(v * self.scale)
        k = self.x_start
        pieces = u[k:].reshape(-1, self.n)[self.mesh.intervals].reshape(self.mesh.ntst, -1)
        coll = np.einsum("jrc,jc->jr", np.abs(self.blocks), pieces) + np.abs(self.extras) @ u[:k]
        return np.concatenate([coll.ravel(), np.abs(self.borders) @ u])


def sparse_jacobian(blocks, extras, borders, mesh, n: int, x_start: int):
    """The same system as a scipy sparse matrix (CSC; rows: collocation, then the borders), for inspection."""
    ntst, m = mesh.ntst, mesh.m
    n_coll = ntst * m * n
    j, k, a, i, b = np.ix_(range(ntst), range(m), range(n), range(m + 1), range(n))
    rows = np.broadcast_to((j * m + k) * n + a, (ntst, m, n, m + 1, n)).ravel()
    cols = np.broadcast_to(x_start + mesh.intervals[j, i] * n + b, (ntst, m, n, m + 1, n)).ravel()
    q = extras.shape[2]
    extra_rows = np.repeat(np.arange(n_coll), q)
    extra_cols = np.tile(np.arange(q), n_coll)
    border_rows, border_cols = np.nonzero(borders)
    A = sparse.coo_matrix((np.concatenate([blocks.ravel(), extras.reshape(n_coll, q).ravel(),
                                           borders[border_rows, border_cols]]),
                           (np.concatenate([rows, extra_rows, n_coll + border_rows]),
                            np.concatenate([cols, extra_cols, border_cols]))),
                          shape=(n_coll + len(borders), x_start + n_coll))
    return A.tocsc()
