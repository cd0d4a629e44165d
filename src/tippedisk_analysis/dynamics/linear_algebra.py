"""The linear algebra of the continuation core (:mod:`.continuation`): a problem's Jacobian in scaled unknowns,
linearised at a point (:meth:`.continuation_interface.Problem.linearise`), solves Newton steps and gives the tangent.

The default is a dense Jacobian: least-squares steps (a consistent overdetermined system, e.g. a family of
equilibria, is solved exactly) and the smallest right singular vector as the tangent. A problem with structure
gives its own linearisation (collocation: the block elimination of :mod:`.collocation_solver`, whose factorisation
serves several right-hand sides: chord steps) and its tangent comes from a bordered solve.
"""

from __future__ import annotations

import numpy as np


class DenseLinearisation:
    """A dense (scaled) Jacobian A: least-squares solves, a new one for every Newton step."""

    reusable = False  # Gauss-Newton: the Jacobian is evaluated at every step

    def __init__(self, A: np.ndarray):
        self.matrix = A
        self.rows = A.shape[0]

    def solve(self, b: np.ndarray) -> np.ndarray:
        return np.linalg.lstsq(self.matrix, b, rcond=None)[0]

    def magnitude(self, v: np.ndarray) -> np.ndarray:
        """|A| |v|: the size of the terms of each row of A v (the round-off yardstick of a residual)."""
        return np.abs(self.matrix) @ np.abs(v)


def null_vector(linearise, size: int, previous: np.ndarray | None, hints=()) -> np.ndarray:
    """A unit vector t with A t = 0 for A of rank (columns - 1), oriented along ``previous``; ``linearise(row)`` is
    the problem's linearisation with ``row`` appended (None: none).

    Dense: the smallest right singular vector. Otherwise: the solution of [A; c^T] t = [0; 1] with c the previous
    tangent, else the first of ``hints`` (column indices, e.g. the free parameter) that makes it regular, else a
    fixed generic vector."""
    plain = linearise(None)
    if getattr(plain, "matrix", None) is not None:
        t = np.linalg.svd(plain.matrix)[2][-1]
    else:
        borders = [previous] if previous is not None else []
        for k in hints:
            e = np.zeros(size)
            e[k] = 1.0
            borders.append(e)
        borders.append(np.random.default_rng(0).normal(size=size))  # generic: not orthogonal to the null vector
        for c in borders:
            lin = linearise(c)
            rhs = np.zeros(lin.rows)
            rhs[-1] = 1.0
            t = lin.solve(rhs)
            if np.all(np.isfinite(t)) and np.linalg.norm(t) > 0:
                break
        t = t / np.linalg.norm(t)
    if previous is not None and t @ previous < 0:
        t = -t
    return t
