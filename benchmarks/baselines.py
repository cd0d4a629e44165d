"""What an expert would write instead of the package, for side-by-side timings (benchmarks only).

ODE Model 1 in the paper's Lagrangian form (4.10), as in :mod:`tippedisk_analysis.models.lagrange`, with the
right-hand side jitted by numba for scipy's ``solve_ivp``: q = (x, y, z, alpha, beta, gamma), state (q, q_d),
M q_dd - h = f_g + W_NT lambda_N with the contact on acceleration level, one 7 x 7 solve per evaluation.
``check`` compares it with the numpy model at random states, so the baseline computes the same physics.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _skew(a):
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


@njit(cache=True)
def _rhs(y, p):
    """d/dt (q, q_d); p = (m, e, r, A, B, C, g, mu, eps)."""
    m, e, r, A, B, C, g, mu, eps = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8]
    alpha, beta, gamma = y[3], y[4], y[5]
    qd = y[6:]
    ad, bd, gd = qd[3], qd[4], qd[5]
    sa, ca, sb, cb, sg, cg = np.sin(alpha), np.cos(alpha), np.sin(beta), np.cos(beta), np.sin(gamma), np.cos(gamma)
    R = np.array([[ca * cg - sa * cb * sg, -ca * sg - sa * cb * cg, sa * sb],  # (3.2)
                  [sa * cg + ca * cb * sg, -sa * sg + ca * cb * cg, -ca * sb],
                  [sb * sg, sb * cg, cb]])
    J_R = np.array([[sb * sg, cg, 0.0], [sb * cg, -sg, 0.0], [cb, 0.0, 1.0]])  # (3.6)
    A_ = np.zeros((6, 6))
    A_[:3, :3] = np.eye(3)
    A_[3:, 3:] = J_R
    J_R_dot_phid = np.array([ad * (cb * bd * sg + sb * cg * gd) - bd * sg * gd,
                             ad * (cb * bd * cg - sb * sg * gd) - bd * cg * gd,
                             -ad * sb * bd])
    theta = np.diag(np.array([A, B, C]))
    r_GS_B = np.array([e, 0.0, 0.0])
    r_GS_I = R @ r_GS_B
    M_hat = np.zeros((6, 6))  # (2.38)
    M_hat[:3, :3] = m * np.eye(3)
    M_hat[:3, 3:] = m * _skew(r_GS_I).T @ R
    M_hat[3:, :3] = m * _skew(r_GS_B) @ R.T
    M_hat[3:, 3:] = theta
    omega_B = J_R @ qd[3:]
    omega_I = R @ omega_B
    h_hat = np.zeros(6)  # (2.39)
    h_hat[:3] = -m * np.cross(omega_I, np.cross(omega_I, r_GS_I))
    h_hat[3:] = -np.cross(omega_B, theta @ omega_B)
    A_dot_qd = np.zeros(6)
    A_dot_qd[3:] = J_R_dot_phid
    M = A_.T @ M_hat @ A_  # (3.12)
    h = A_.T @ (h_hat - M_hat @ A_dot_qd)  # (3.14)
    f_g = -m * g * np.array([0.0, 0.0, 1.0, 0.0, e * cb * sg, e * sb * cg])  # (3.24)
    w_N1 = np.array([0.0, 0.0, 1.0, 0.0, -r * cb, 0.0])  # (3.28)
    W_T1 = np.array([[1.0, 0.0, 0.0, r * ca * cb, -r * sa * sb, r * ca],  # (3.29), transposed
                     [0.0, 1.0, 0.0, r * sa * cb, r * ca * sb, r * sa]]).T
    gamma_T = W_T1.T @ qd  # (3.27)
    W_NT = w_N1 - mu * W_T1 @ gamma_T / (np.sqrt(gamma_T[0] ** 2 + gamma_T[1] ** 2) + eps)  # (2.29), (4.10)
    system = np.zeros((7, 7))
    system[:6, :6] = M
    system[:6, 6] = -W_NT
    system[6, :6] = w_N1
    rhs = np.zeros(7)
    rhs[:6] = h + f_g
    rhs[6] = -r * sb * bd * bd  # -d/dt(w_N1)^T q_d
    qdd = np.linalg.solve(system, rhs)[:6]
    out = np.empty(12)
    out[:6] = qd
    out[6:] = qdd
    return out


def parameters(setup) -> np.ndarray:
    d, f = setup.disk, setup.friction
    return np.array([d.m, d.e, d.r, d.A, d.B, d.C, setup.gravity, f.mu, f.eps])


def lagrange_rhs(setup):
    """fun(t, y) for scipy.integrate.solve_ivp (compiled on the first call; numba caches it on disk)."""
    p = parameters(setup)
    return lambda t, y: _rhs(y, p)


def initial_state(setup, initial) -> np.ndarray:
    """(q, q_d) of the Table 3 start: closed contact at C1 without slip."""
    from tippedisk_analysis import kinematics as kin

    rest = kin.rest_contact_state(setup.disk.r, initial.euler, initial.euler_rates)
    return np.concatenate([[initial.x, initial.y, rest["z"]], initial.euler, rest["v_G"], initial.euler_rates])


def check(setup, n: int = 20, seed: int = 0) -> float:
    """Largest relative difference of the jitted and the numpy right-hand sides at random states."""
    from tippedisk_analysis.models.lagrange import LagrangeModel

    rng = np.random.default_rng(seed)
    fun, ref = lagrange_rhs(setup), LagrangeModel(setup)
    worst = 0.0
    for _ in range(n):
        y = np.concatenate([rng.normal(scale=0.01, size=3), [rng.uniform(-3, 3), rng.uniform(0.5, 2.6),
                                                             rng.uniform(-3, 3)], rng.normal(scale=5.0, size=6)])
        a, b = fun(0.0, y), ref.rhs(0.0, y)
        worst = max(worst, float(np.max(np.abs(a - b)) / (1.0 + np.max(np.abs(b)))))
    return worst
