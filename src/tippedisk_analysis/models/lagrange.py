"""ODE Model 1 in the paper's Lagrangian form, evaluated with numpy.

M(q) q_dd - h(q, q_d) = f_g + W_NT lambda_N with the bilateral constraint on
acceleration level, solved as the linear system (4.10). M and h follow from the
virtual work (2.36)-(2.39) and the Jacobians (3.6) as M = A^T M_hat A (3.12) and
h = A^T (h_hat - M_hat A_dot q_d) (3.14); f_g (3.24), w_N1 (3.28), W_T1 (3.29).

This is deliberately a second, independent derivation of the physics in
:mod:`tippedisk_analysis.models.ode` (which uses Newton-Euler equations about S in
minimal velocities): the tests compare the two, and the benchmark integrates this
right-hand side with scipy. It uses the exact |gamma_T| of (2.29).
"""

from __future__ import annotations

import numpy as np

from .. import kinematics as kin
from ..parameters import Setup


def _skew(a):
    """j(a) of (2.2)."""
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


class LagrangeModel:
    """Right-hand side of ODE Model 1 for the state y = (q, q_d), q = (x, y, z, alpha, beta, gamma)."""

    def __init__(self, setup: Setup):
        d, f = setup.disk, setup.friction
        self.m, self.e, self.r = d.m, d.e, d.r
        self.theta_G = np.diag([d.A, d.B, d.C])
        self.g, self.mu, self.eps = setup.gravity, f.mu, f.eps

    def accelerations(self, q, qd):
        """(q_dd, lambda_N) from (4.10)."""
        m, e, r = self.m, self.e, self.r
        _, _, _, alpha, beta, gamma = q
        ad, bd, gd = qd[3:]
        sa, ca, sb, cb, sg, cg = np.sin(alpha), np.cos(alpha), np.sin(beta), np.cos(beta), np.sin(gamma), np.cos(gamma)
        R = kin.rotation_from_euler(alpha, beta, gamma)

        J_R = np.array([[sb * sg, cg, 0.0], [sb * cg, -sg, 0.0], [cb, 0.0, 1.0]])  # (3.6)
        A = np.zeros((6, 6))
        A[:3, :3] = np.eye(3)
        A[3:, 3:] = J_R
        J_R_dot_phid = np.array(kin.omega_derivative_entries_at_fixed_rates(beta, gamma, ad, bd, gd))  # d/dt(J_R) phi_d

        r_GS_B = np.array([e, 0.0, 0.0])
        r_GS_I = R @ r_GS_B
        M_hat = np.zeros((6, 6))  # (2.38)
        M_hat[:3, :3] = m * np.eye(3)
        M_hat[:3, 3:] = m * _skew(r_GS_I).T @ R
        M_hat[3:, :3] = m * _skew(r_GS_B) @ R.T
        M_hat[3:, 3:] = self.theta_G

        omega_B = J_R @ qd[3:]
        omega_I = R @ omega_B
        h_hat = np.concatenate([  # (2.39)
            -m * np.cross(omega_I, np.cross(omega_I, r_GS_I)),
            -np.cross(omega_B, self.theta_G @ omega_B),
        ])
        A_dot_qd = np.concatenate([np.zeros(3), J_R_dot_phid])
        M = A.T @ M_hat @ A  # (3.12)
        h = A.T @ (h_hat - M_hat @ A_dot_qd)  # (3.14)

        f_g = -m * self.g * np.array([0.0, 0.0, 1.0, 0.0, e * cb * sg, e * sb * cg])  # (3.24)
        w_N1 = np.array([0.0, 0.0, 1.0, 0.0, -r * cb, 0.0])  # (3.28)
        W_T1 = np.array([  # (3.29), columns
            [1.0, 0.0, 0.0, r * ca * cb, -r * sa * sb, r * ca],
            [0.0, 1.0, 0.0, r * sa * cb, r * ca * sb, r * sa],
        ]).T
        gamma_T = W_T1.T @ qd  # (3.27)
        W_NT = w_N1 - self.mu * W_T1 @ gamma_T / (np.hypot(*gamma_T) + self.eps)  # (4.10), (2.29)
        w_N1_dot_qd = r * sb * bd * bd  # d/dt(w_N1)^T q_d

        system = np.zeros((7, 7))  # (4.10) without the trivial kinematic block
        system[:6, :6] = M
        system[:6, 6] = -W_NT
        system[6, :6] = w_N1
        rhs = np.concatenate([h + f_g, [-w_N1_dot_qd]])
        solution = np.linalg.solve(system, rhs)
        return solution[:6], solution[6]

    def rhs(self, t, y):
        """d/dt (q, q_d) for scipy.integrate.solve_ivp."""
        q, qd = y[:6], y[6:]
        qdd, _ = self.accelerations(q, qd)
        return np.concatenate([qd, qdd])
