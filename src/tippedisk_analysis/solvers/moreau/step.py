"""The numba step loop of Moreau's midpoint scheme (Sect. 4, (4.1)-(4.7)) for Models 1-10.

Per step:

1. q_M = q_A + dt/2 F(q_A) u_A;
2. at q_M: rotation, floating frame (2.8) with continuity when horizontal, candidate points
   C1-C3 (2.10)-(2.11), gaps (2.12), closed set I = {i | g_Ni(q_M) <= 0}, force directions of
   N (normal), T (tangential x, y), tau (pivoting (3.61)), R (contour (3.63)), gyroscopic and
   gravity terms with u_A, in the velocities v = (v_S, Omega) of
   :mod:`tippedisk_analysis.models.moreau_geometry` (algebraically identical to (4.1));
3. the fixed-point iteration (4.1)-(4.7) written with the Delassus matrix G = W^T M^-1 W:
   gamma_E^k = gamma_free + G P^k, xi = gamma_E + e gamma_A (4.3); a Jacobi sweep over the
   closed contacts (:mod:`.force_laws`), the friction reservoirs use the new P_N^{k+1}; stop
   when the summed impulse change is below ``tol``, or count a convergence failure after ``max_iter``;
4. u_E from the impulses, q_E = q_M + dt/2 F(q_M) u_E (optionally normalise the quaternion).

Impulses are warm-started from the previous step's values for contacts that stay closed.

Coulomb-Contensou torque share (diagnostic variant, Models 3/4): each column j carries a share s_j of
its impulse that acts on the disk, 1 except for the Contensou tau column, which gets
``par[CONTENSOU_TORQUE_SHARE]``. The contact velocities use W_j unscaled (gamma_tau = eps_i omega_IB,
so the ball still couples spin and sliding), the Delassus matrix and the end velocity use s_k W_k:
G_jk = W_j^T M^-1 W_k s_k, v_E = v_free + M^-1 sum_k s_k W_k P_k. s = 1 is the law (2.24)-(2.27).
Every array index is named in :mod:`.layout`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...defaults import CONTOUR_REGULARISATION
from ...models import moreau_geometry as geo
from . import force_laws as law
from .layout import (A_S, B_S, C_S, COL_GAP, COL_IMPULSE, COL_ITER_MAX, COL_ITER_MEAN, COL_N_CLOSED, COL_Q,
                     COL_TIME, COL_U, CONTACT_RADIUS, CONTENSOU_TORQUE_SHARE, DT, E, E_N, E_R, E_T, E_TAU, EPS, GRAVITY,
                     IMPULSE_N,
                     IMPULSE_R, IMPULSE_TAU, IMPULSE_TX, IMPULSE_TY, LAW, M, MAX_COLUMNS, MAX_ITER, MU, MU_R,
                     MU_TAU, N_CONTACTS, N_IMPULSES, NORMALIZE_QUATERNION, PARAMETERIZATION, PIVOT_CONTOUR, R_N,
                     R_R, R_T, R_TAU, RADIUS, SIN_FALL_ANGLE, STAT_FAILURES, STAT_ITER_MAX, STAT_ITER_SUM,
                     STAT_N_CLOSED, STAT_STEPS, STATUS_FELL, STATUS_NONFINITE, STATUS_OK, STORE_EVERY, TOL)
from .models import CONTENSOU, COULOMB, EULER, QUATERNION, SMOOTH

GAIN_CAP = 1.5  # largest r_j G_jj of a prox gain (convergence needs < 2 for one column)
CONTOUR_SIN_BETA_REG = CONTOUR_REGULARISATION  # numba reads module globals as constants


@njit(cache=True)
def orientation(q, parameterization, R):
    """R = A_IB of (3.2) (Euler angles q[3:6]) or (3.40) (quaternion q[3:7])."""
    if parameterization == EULER:
        geo.rotation_euler(q[3], q[4], q[5], R)
    else:
        geo.rotation_quaternion(q[3], q[4], q[5], q[6], R)


@njit(cache=True)
def advance_position(q, u, h, parameterization, out, p_dot):
    """out = q + h F(q) u: (3.8) for Euler angles (q_dot = u), (3.44) for quaternions."""
    out[0] = q[0] + h * u[0]
    out[1] = q[1] + h * u[1]
    out[2] = q[2] + h * u[2]
    if parameterization == EULER:
        out[3] = q[3] + h * u[3]
        out[4] = q[4] + h * u[4]
        out[5] = q[5] + h * u[5]
        out[6] = 0.0
    else:
        geo.quaternion_rates(q[3], q[4], q[5], q[6], u[3], u[4], u[5], p_dot)
        for k in range(4):
            out[3 + k] = q[3 + k] + h * p_dot[k]


@njit(cache=True)
def contact_gaps(q, R, ex_G, r, offsets, gaps):
    """Floating frame (2.8), offsets r_GC1..3 (2.10)-(2.11) and gaps g_Ni (2.12)."""
    geo.floating_frame(R, ex_G)
    geo.contact_offsets(R, ex_G, r, offsets)
    for i in range(N_CONTACTS):
        gaps[i] = q[2] + offsets[i, 2]


@njit(cache=True)
def run_steps(q, u, ex_G, P_last, par, flags, ball, n_steps, step0, out, row0, stats):
    """Advance ``n_steps`` Moreau steps in place; store every ``flags[STORE_EVERY]``-th step into ``out``.

    q (7), u (6): state (Euler: q[6] unused); ex_G (3): floating-frame e_x^G; P_last (3, 5):
    impulses of the last step per contact and kind (warm start); stats: statistics of the
    current storage interval (STAT_FAILURES is the run's total). Returns
    (steps_done, rows_written, status) with the status codes of :mod:`.layout`.
    """
    parameterization, friction_law = flags[PARAMETERIZATION], flags[LAW]
    pivot_contour, max_iter = flags[PIVOT_CONTOUR], flags[MAX_ITER]
    normalize, store_every = flags[NORMALIZE_QUATERNION], flags[STORE_EVERY]
    m, e, r = par[M], par[E], par[RADIUS]
    theta = np.array([par[A_S], par[B_S], par[C_S]])
    g, mu, eps, mu_tau, mu_R, contact_radius = par[GRAVITY], par[MU], par[EPS], par[MU_TAU], par[MU_R], \
        par[CONTACT_RADIUS]
    dt, tol = par[DT], par[TOL]
    gain = np.array([par[R_N], par[R_T], par[R_T], par[R_TAU], par[R_R]])  # per impulse kind
    restitution = np.array([par[E_N], par[E_T], par[E_T], par[E_TAU], par[E_R]])
    m_inv = np.array([1.0 / m, 1.0 / m, 1.0 / m, 1.0 / theta[0], 1.0 / theta[1], 1.0 / theta[2]])

    R = np.empty((3, 3))
    q_M = np.empty(7)
    q_E = np.empty(7)
    p_dot = np.empty(4)
    omega = np.empty(3)
    omega_dot_rates = np.empty(3)  # J_R_dot phi_dot (Euler angles), 0 for quaternions
    rates = np.empty(3)
    offsets = np.empty((3, 3))
    gaps = np.empty(3)
    contour = np.empty(3)
    v_A = np.empty(6)  # (v_S, Omega) at the start of the step
    v_free = np.empty(6)  # ... after the smooth forces of the step
    W = np.zeros((MAX_COLUMNS, 6))  # force directions in the velocities v, one row per column
    delassus = np.zeros((MAX_COLUMNS, MAX_COLUMNS))
    gamma_free = np.zeros(MAX_COLUMNS)
    gamma_A = np.zeros(MAX_COLUMNS)
    P = np.zeros(MAX_COLUMNS)
    P_new = np.zeros(MAX_COLUMNS)
    r_col = np.zeros(MAX_COLUMNS)  # prox gain of each column, capped by the Delassus diagonal
    column_contact = np.zeros(MAX_COLUMNS, np.int64)
    column_kind = np.zeros(MAX_COLUMNS, np.int64)
    column_share = np.ones(MAX_COLUMNS)  # share of the column's impulse acting on the disk (module docstring)
    tau_share = par[CONTENSOU_TORQUE_SHARE] if friction_law == CONTENSOU else 1.0
    column = np.zeros((N_CONTACTS, N_IMPULSES), np.int64)  # column of (contact, kind), -1 if absent
    xi = np.zeros(N_IMPULSES)
    gamma_E = np.zeros(N_IMPULSES)
    has_tau = friction_law == CONTENSOU or pivot_contour == 1
    rows = 0
    for n in range(n_steps):
        # 1) midpoint (Sect. 4, step 2)
        advance_position(q, u, 0.5 * dt, parameterization, q_M, p_dot)
        orientation(q_M, parameterization, R)
        # 2) velocities v = A(q_M) u_A = (v_S, Omega) and A_dot u_A
        if parameterization == EULER:
            if abs(math.sin(q_M[4])) < par[SIN_FALL_ANGLE]:
                return n, rows, STATUS_FELL
            geo.omega_from_rates(q_M[4], q_M[5], u[3], u[4], u[5], omega)
            geo.jdot_rates(q_M[4], q_M[5], u[3], u[4], u[5], omega_dot_rates)
        else:
            omega[0], omega[1], omega[2] = u[3], u[4], u[5]
            omega_dot_rates[0], omega_dot_rates[1], omega_dot_rates[2] = 0.0, 0.0, 0.0
        # Omega x r_GS (B, r_GS = e e_x^B) and Omega x (Omega x r_GS) + (J_R_dot phi_dot) x r_GS
        oxr0, oxr1, oxr2 = 0.0, omega[2] * e, -omega[1] * e
        cen0 = omega[1] * oxr2 - omega[2] * oxr1 + 0.0
        cen1 = omega[2] * oxr0 - omega[0] * oxr2 + omega_dot_rates[2] * e
        cen2 = omega[0] * oxr1 - omega[1] * oxr0 - omega_dot_rates[1] * e
        for k in range(3):
            v_A[k] = u[k] + R[k, 0] * oxr0 + R[k, 1] * oxr1 + R[k, 2] * oxr2  # v_S = v_G + Omega x r_GS
            v_A[3 + k] = omega[k]
        # free velocity: v_A + M_hat^-1 h_hat' dt (gravity, centripetal of S, gyroscopic, -Theta a)
        L0, L1, L2 = theta[0] * omega[0], theta[1] * omega[1], theta[2] * omega[2]
        gyr0 = omega[1] * L2 - omega[2] * L1
        gyr1 = omega[2] * L0 - omega[0] * L2
        gyr2 = omega[0] * L1 - omega[1] * L0
        for k in range(3):
            v_free[k] = v_A[k] - dt * (R[k, 0] * cen0 + R[k, 1] * cen1 + R[k, 2] * cen2)
        v_free[2] -= dt * g
        v_free[3] = v_A[3] - dt * (gyr0 / theta[0] + omega_dot_rates[0])
        v_free[4] = v_A[4] - dt * (gyr1 / theta[1] + omega_dot_rates[1])
        v_free[5] = v_A[5] - dt * (gyr2 / theta[2] + omega_dot_rates[2])

        # 3) contacts at q_M: one column per (closed contact, impulse kind)
        contact_gaps(q_M, R, ex_G, r, offsets, gaps)
        sin_beta = math.sqrt(R[0, 2] * R[0, 2] + R[1, 2] * R[1, 2])
        if pivot_contour == 1:
            geo.contour_direction(R, sin_beta, CONTOUR_SIN_BETA_REG, contour)
        nc = 0
        n_closed = 0
        for i in range(N_CONTACTS):
            for kind in range(N_IMPULSES):
                column[i, kind] = -1
            if gaps[i] > 0.0:
                P_last[i, :] = 0.0
                continue
            n_closed += 1
            # r_SC = r_GC - r_GS (I)
            sx = offsets[i, 0] - e * R[0, 0]
            sy = offsets[i, 1] - e * R[1, 0]
            sz = offsets[i, 2] - e * R[2, 0]
            for kind in (IMPULSE_N, IMPULSE_TX, IMPULSE_TY):  # directions e_z, e_x, e_y (I)
                dx = 1.0 if kind == IMPULSE_TX else 0.0
                dy = 1.0 if kind == IMPULSE_TY else 0.0
                dz = 1.0 if kind == IMPULSE_N else 0.0
                m0 = sy * dz - sz * dy  # r_SC x d (I)
                m1 = sz * dx - sx * dz
                m2 = sx * dy - sy * dx
                W[nc, 0], W[nc, 1], W[nc, 2] = dx, dy, dz
                for j in range(3):
                    W[nc, 3 + j] = R[0, j] * m0 + R[1, j] * m1 + R[2, j] * m2
                column[i, kind] = nc
                column_contact[nc] = i
                column_kind[nc] = kind
                column_share[nc] = 1.0
                nc += 1
            if has_tau:  # (3.61): w_tau = eps_i [0, R^T e_z]
                W[nc, 0:3] = 0.0
                for j in range(3):
                    W[nc, 3 + j] = contact_radius * R[2, j]
                column[i, IMPULSE_TAU] = nc
                column_contact[nc] = i
                column_kind[nc] = IMPULSE_TAU
                column_share[nc] = tau_share
                nc += 1
            if pivot_contour == 1:  # (3.63): gamma_R = -r phi_dot
                W[nc, 0:3] = 0.0
                for j in range(3):
                    W[nc, 3 + j] = -r * contour[j]
                column[i, IMPULSE_R] = nc
                column_contact[nc] = i
                column_kind[nc] = IMPULSE_R
                column_share[nc] = 1.0
                nc += 1
        # Delassus matrix and free / start-of-step contact velocities
        for j in range(nc):
            sf = 0.0
            sa = 0.0
            for l in range(6):
                sf += W[j, l] * v_free[l]
                sa += W[j, l] * v_A[l]
            gamma_free[j] = sf
            gamma_A[j] = sa
            P[j] = P_last[column_contact[j], column_kind[j]]
            for k in range(j, nc):
                gs = 0.0
                for l in range(6):
                    gs += W[j, l] * W[k, l] * m_inv[l]
                delassus[j, k] = gs * column_share[k]  # gamma_j += W_j^T M^-1 (s_k W_k) P_k
                delassus[k, j] = gs * column_share[j]
        # gains: r_j G_jj < 2 makes the sweep of one column contract; GAIN_CAP / G_jj keeps a margin. Inactive in
        # ordinary steps (r_N G_NN ~ 1); it matters where a force direction grows without bound, e.g. the
        # contour direction (3.64) ~ 1 / sin(beta) of a nearly flat disk. The solution does not depend on r.
        for j in range(nc):
            r_col[j] = min(gain[column_kind[j]], GAIN_CAP / delassus[j, j]) if delassus[j, j] > 0.0 \
                else gain[column_kind[j]]

        # 4) fixed-point iteration (4.1)-(4.7)
        it = 0
        if nc > 0:
            converged = False
            while it < max_iter:
                it += 1
                err = 0.0
                for i in range(N_CONTACTS):
                    jN = column[i, IMPULSE_N]
                    if jN < 0:
                        continue
                    # gamma_E = gamma_free + G P (4.1)-(4.2), xi = gamma_E + e gamma_A (4.3)
                    for kind in range(N_IMPULSES):
                        j = column[i, kind]
                        if j < 0:
                            gamma_E[kind] = 0.0
                            xi[kind] = 0.0
                            continue
                        sgm = gamma_free[j]
                        for k in range(nc):
                            sgm += delassus[j, k] * P[k]
                        gamma_E[kind] = sgm
                        xi[kind] = sgm + restitution[kind] * gamma_A[j]
                    P_N = law.normal(P[jN], xi[IMPULSE_N], r_col[jN])
                    P_new[jN] = P_N
                    err += abs(P_N - P[jN])
                    jx, jy, jtau = column[i, IMPULSE_TX], column[i, IMPULSE_TY], column[i, IMPULSE_TAU]
                    r_T = min(r_col[jx], r_col[jy])
                    if friction_law == COULOMB:
                        px, py = law.coulomb(P[jx], P[jy], xi[IMPULSE_TX], xi[IMPULSE_TY], r_T, mu * P_N)
                    elif friction_law == SMOOTH:
                        G_TT = max(delassus[jx, jx], delassus[jy, jy])
                        px, py = law.smooth_coulomb(P[jx], P[jy], gamma_E[IMPULSE_TX], gamma_E[IMPULSE_TY], mu * P_N,
                                                    eps, G_TT)
                    else:
                        px, py, ptau = law.contensou(P[jx], P[jy], P[jtau], xi[IMPULSE_TX], xi[IMPULSE_TY],
                                                     xi[IMPULSE_TAU], min(r_T, r_col[jtau]), mu * P_N, ball)
                        P_new[jtau] = ptau
                        err += abs(ptau - P[jtau])
                    P_new[jx] = px
                    P_new[jy] = py
                    err += math.sqrt((px - P[jx]) ** 2 + (py - P[jy]) ** 2)
                    if pivot_contour == 1:
                        if friction_law != CONTENSOU:  # separate dry pivoting (2.30)
                            ptau = law.interval(P[jtau], xi[IMPULSE_TAU], r_col[jtau], mu_tau * P_N)
                            P_new[jtau] = ptau
                            err += abs(ptau - P[jtau])
                        jR = column[i, IMPULSE_R]
                        pR = law.interval(P[jR], xi[IMPULSE_R], r_col[jR], mu_R * P_N)  # (2.31)
                        P_new[jR] = pR
                        err += abs(pR - P[jR])
                for j in range(nc):
                    P[j] = P_new[j]
                if err < tol:
                    converged = True
                    break
            if not converged:
                stats[STAT_FAILURES] += 1.0
        # 5) end velocity and position
        for l in range(6):
            v_end = v_free[l]
            for j in range(nc):
                v_end += W[j, l] * P[j] * column_share[j] * m_inv[l]
            v_A[l] = v_end  # v_E
        for i in range(N_CONTACTS):
            P_last[i, :] = 0.0
        for j in range(nc):
            P_last[column_contact[j], column_kind[j]] = P[j]
        for k in range(3):
            omega[k] = v_A[3 + k]
        oxr0, oxr1, oxr2 = 0.0, omega[2] * e, -omega[1] * e
        for k in range(3):
            u[k] = v_A[k] - (R[k, 0] * oxr0 + R[k, 1] * oxr1 + R[k, 2] * oxr2)  # v_G = v_S - Omega x r_GS
        if parameterization == EULER:
            geo.rates_from_omega(q_M[4], q_M[5], omega, rates)
            u[3], u[4], u[5] = rates[0], rates[1], rates[2]
        else:
            u[3], u[4], u[5] = omega[0], omega[1], omega[2]
        advance_position(q_M, u, 0.5 * dt, parameterization, q_E, p_dot)
        if parameterization == QUATERNION and normalize == 1:
            norm = math.sqrt(q_E[3] ** 2 + q_E[4] ** 2 + q_E[5] ** 2 + q_E[6] ** 2)
            for k in range(4):
                q_E[3 + k] /= norm
        finite = True
        for k in range(7):
            if not math.isfinite(q_E[k]):
                finite = False
        for k in range(6):
            if not math.isfinite(u[k]):
                finite = False
        if not finite:
            return n, rows, STATUS_NONFINITE
        for k in range(7):
            q[k] = q_E[k]
        if it > stats[STAT_ITER_MAX]:
            stats[STAT_ITER_MAX] = it
        stats[STAT_ITER_SUM] += it
        stats[STAT_STEPS] += 1.0
        stats[STAT_N_CLOSED] = n_closed
        if (step0 + n + 1) % store_every == 0:
            row = row0 + rows
            out[row, COL_TIME] = (step0 + n + 1) * dt
            for k in range(7):
                out[row, COL_Q + k] = q[k]
            for k in range(6):
                out[row, COL_U + k] = u[k]
            orientation(q, parameterization, R)
            contact_gaps(q, R, ex_G, r, offsets, gaps)
            for i in range(N_CONTACTS):
                out[row, COL_GAP + i] = gaps[i]
                for kind in range(N_IMPULSES):
                    out[row, COL_IMPULSE + kind * N_CONTACTS + i] = P_last[i, kind]
            out[row, COL_N_CLOSED] = n_closed
            out[row, COL_ITER_MAX] = stats[STAT_ITER_MAX]
            out[row, COL_ITER_MEAN] = stats[STAT_ITER_SUM] / stats[STAT_STEPS]
            stats[STAT_ITER_MAX] = 0.0
            stats[STAT_ITER_SUM] = 0.0
            stats[STAT_STEPS] = 0.0
            rows += 1
    return n_steps, rows, STATUS_OK
