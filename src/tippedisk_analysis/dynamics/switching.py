"""Branch switching at branch points of a continuation (:mod:`.continuation`): the tangents of the
emanating branches from the algebraic bifurcation equations, and their continuation."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from .continuation import Branch, Options, Point, Problem, continue_branch, correct


@dataclass(frozen=True)
class Switch:
    """Result of :func:`branch_directions` at a branch point."""

    kernel: np.ndarray  # (n, 2) orthonormal basis of ker F_u (scaled unknowns), first column the old tangent
    cokernel: np.ndarray  # (m, c) left null vectors
    coefficients: np.ndarray  # (c, 2, 2) algebraic bifurcation equations psi_k^T F_vv[phi_i, phi_j]
    directions: list  # unit tangents (scaled) of the emanating branches (the old one excluded)


def branch_directions(problem: Problem, sp_point: Point, old_tangent: np.ndarray, rank_tol: float = 1e-7) -> Switch:
    """Tangents of the branches through a branch point from the algebraic bifurcation equations.

    At a simple branch point ker F_u is 2-dimensional (span of the old tangent phi_1 and phi_2).
    The tangent alpha phi_1 + beta phi_2 of any branch through the point solves
    sum_ij c_kij alpha_i alpha_j = 0 for every left null vector psi_k, c_kij = psi_k^T F_vv[phi_i, phi_j].
    The old branch is one root; the others are returned (none if the equations share only it).
    ``old_tangent``: the tangent of a regular point next to the branch point (at the point itself
    the null vector of F_u is an arbitrary vector of the 2-dimensional kernel).
    """
    u = sp_point.u
    scale = problem.scale
    A = problem.jacobian(u) * scale[None, :]
    U, sv, Vt = np.linalg.svd(A)
    tol = rank_tol * sv[0]
    null = Vt[np.sum(sv > tol):].T if len(sv) == A.shape[1] else Vt[len(sv):].T
    if null.shape[1] < 2:  # numerically rank n - 1 at the located point: take the two smallest directions
        null = Vt[-2:].T
    t_old = null[:, -2:] @ (null[:, -2:].T @ old_tangent)  # the old branch's direction within the kernel
    t_old /= np.linalg.norm(t_old)
    phi2 = null[:, 0] - (null[:, 0] @ t_old) * t_old
    if np.linalg.norm(phi2) < 1e-6:
        phi2 = null[:, 1] - (null[:, 1] @ t_old) * t_old
    phi2 /= np.linalg.norm(phi2)
    kernel = np.column_stack([t_old, phi2])
    n_left = int(np.sum(sv <= tol)) + (A.shape[0] - len(sv))
    cokernel = U[:, A.shape[0] - max(n_left, 1):]
    basis = [kernel[:, i] * scale for i in range(2)]  # in unscaled unknowns
    coefficients = np.empty((cokernel.shape[1], 2, 2))
    for i in range(2):
        for j in range(2):
            second = problem.second_derivative(u, basis[i], basis[j])
            coefficients[:, i, j] = cokernel.T @ second
    directions = []
    for theta in _common_roots(coefficients):
        d = math.cos(theta) * kernel[:, 0] + math.sin(theta) * kernel[:, 1]
        if abs(d @ t_old) < 1 - 1e-6:  # not the old branch
            directions.append(d)
    return Switch(kernel, cokernel, coefficients, directions)


def _common_roots(c: np.ndarray) -> list[float]:
    """Angles theta in [0, pi) with sum_ij c_kij a_i a_j = 0 for all k, a = (cos theta, sin theta)."""
    norm = np.abs(c).max() or 1.0
    roots = []
    for k in range(c.shape[0]):  # candidate roots of each quadratic form
        a, b, d = c[k, 0, 0], c[k, 0, 1] + c[k, 1, 0], c[k, 1, 1]
        if abs(d) > 1e-12 * norm:  # d tan^2 + b tan + a = 0
            disc = b * b - 4 * a * d
            if disc >= 0:
                roots += [math.atan((-b + sgn * math.sqrt(disc)) / (2 * d)) % math.pi for sgn in (1, -1)]
        elif abs(b) > 1e-12 * norm:  # a cos^2 + b cos sin = 0: theta = pi/2 or tan = -a/b
            roots += [math.pi / 2, math.atan(-a / b) % math.pi]
        else:
            roots += [math.pi / 2] if abs(a) > 1e-12 * norm else list(np.linspace(0, math.pi, 7)[:-1])
    common = []
    for theta in roots:
        a_vec = np.array([math.cos(theta), math.sin(theta)])
        residual = np.abs(np.einsum("kij,i,j->k", c, a_vec, a_vec)).max()
        if residual <= 1e-8 * norm and all(abs(math.sin(theta - t)) > 1e-9 for t in common):
            common.append(theta)
    return common


def switch_branch(problem: Problem, branch: Branch, special_index: int, options: Options | None = None,
                  ds: float | None = None) -> list[Branch]:
    """The branches emanating from branch point ``special_index`` of ``branch`` (both directions of
    each new tangent). An empty list means the bifurcation equations admit no other branch."""
    options = options or branch.options
    sp = branch.special_points[special_index]
    if sp.kind != "branch_point":
        raise ParameterError(f"{sp.label} is a {sp.kind}, not a branch point; branch switching needs a BP")
    point = branch.points[sp.index]
    switch = branch_directions(problem, point, branch.points[sp.index - 1].tangent)
    step = min(abs(options.ds), 1e-3) if ds is None else ds
    new = []
    for d in switch.directions:
        for sign in (1, -1):
            v0 = point.u / problem.scale
            u, _ = correct(problem, (v0 + sign * step * d) * problem.scale, (sign * d, v0, step), options)
            if u is None:
                continue
            offset = (u / problem.scale - v0)
            t_old = switch.kernel[:, 0]
            if np.linalg.norm(offset - (offset @ t_old) * t_old) < 0.1 * step:
                continue  # fell back onto the old branch
            new.append(continue_branch(problem, u, options, tangent=sign * d))
    return new
