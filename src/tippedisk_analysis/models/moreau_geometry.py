"""Scalar numba kernels of the Moreau models' geometry (Sect. 2, 3): kinematics and force directions.

numba cannot call the list-building formulas of :mod:`tippedisk_analysis.kinematics`,
so the few formulas the step loop needs are restated here as scalar kernels
(rotation (3.2)/(3.40), omega (3.3) and its inverse, quaternion rates (3.44), floating
frame (2.8)-(2.11)). ``tests/test_moreau.py`` cross-checks every one of them against
:mod:`kinematics`, which stays the reference home of these laws.

Velocity space of the contact problem
-------------------------------------
Both parameterizations solve the contact problem in the velocities
``v = (v_S [m/s, I-frame], Omega [rad/s, B-frame])``, in which the mass matrix is the
constant diagonal ``M_hat = diag(m, m, m, A_S, B_S, C_S)`` (Newton-Euler about S). With
``v = A(q) u`` (``u`` = Euler rates (3.1) or ``(v_G, Omega)`` (3.43)) the paper's
generalized quantities are ``M = A^T M_hat A`` (3.12), ``W = A^T W_hat`` and
``h(q, u) = A^T (h_hat(q, A u) - M_hat A_dot u)``. Hence, exactly,

    u_E = u_A + M^-1 (h dt + W P)  <=>  A u_E = A u_A + M_hat^-1 (h_hat' dt + W_hat P),
    gamma = W^T u = W_hat^T (A u),

all evaluated at the midpoint q_M as in (4.1)-(4.2): no 6x6 solve, no transcription of the
damaged (3.13)-(3.20). ``A_dot u`` holds the centripetal term of S and, for Euler angles,
``J_R_dot phi_dot``.
"""

from __future__ import annotations

import math

from numba import njit

HORIZONTAL_SIN_BETA = 1e-12  # below this |e_z^I x e_z^B| the floating frame keeps its previous e_x^G


@njit(cache=True)
def rotation_euler(alpha, beta, gamma, R):
    """R = A_IB of (3.2) into R (3x3)."""
    sa, ca = math.sin(alpha), math.cos(alpha)
    sb, cb = math.sin(beta), math.cos(beta)
    sg, cg = math.sin(gamma), math.cos(gamma)
    R[0, 0] = ca * cg - sa * cb * sg
    R[0, 1] = -ca * sg - sa * cb * cg
    R[0, 2] = sa * sb
    R[1, 0] = sa * cg + ca * cb * sg
    R[1, 1] = -sa * sg + ca * cb * cg
    R[1, 2] = -ca * sb
    R[2, 0] = sb * sg
    R[2, 1] = sb * cg
    R[2, 2] = cb


@njit(cache=True)
def rotation_quaternion(p0, p1, p2, p3, R):
    """R(p) of (3.40) into R (3x3)."""
    R[0, 0] = 2 * (p0 * p0 + p1 * p1) - 1
    R[0, 1] = 2 * (p1 * p2 - p0 * p3)
    R[0, 2] = 2 * (p1 * p3 + p0 * p2)
    R[1, 0] = 2 * (p1 * p2 + p0 * p3)
    R[1, 1] = 2 * (p0 * p0 + p2 * p2) - 1
    R[1, 2] = 2 * (p2 * p3 - p0 * p1)
    R[2, 0] = 2 * (p1 * p3 - p0 * p2)
    R[2, 1] = 2 * (p2 * p3 + p0 * p1)
    R[2, 2] = 2 * (p0 * p0 + p3 * p3) - 1


@njit(cache=True)
def omega_from_rates(beta, gamma, ad, bd, gd, w):
    """Body angular velocity from Euler rates, (3.3): w = J_R phi_dot."""
    sb, cb = math.sin(beta), math.cos(beta)
    sg, cg = math.sin(gamma), math.cos(gamma)
    w[0] = ad * sb * sg + bd * cg
    w[1] = ad * sb * cg - bd * sg
    w[2] = ad * cb + gd


@njit(cache=True)
def rates_from_omega(beta, gamma, w, rates):
    """Inverse of (3.3); singular at sin(beta) = 0."""
    sb, cb = math.sin(beta), math.cos(beta)
    sg, cg = math.sin(gamma), math.cos(gamma)
    ad = (w[0] * sg + w[1] * cg) / sb
    rates[0] = ad
    rates[1] = w[0] * cg - w[1] * sg
    rates[2] = w[2] - cb * ad


@njit(cache=True)
def jdot_rates(beta, gamma, ad, bd, gd, a):
    """J_R_dot(beta, gamma) phi_dot: time derivative of (3.3) at constant Euler rates."""
    sb, cb = math.sin(beta), math.cos(beta)
    sg, cg = math.sin(gamma), math.cos(gamma)
    a[0] = ad * (cb * bd * sg + sb * cg * gd) - bd * sg * gd
    a[1] = ad * (cb * bd * cg - sb * sg * gd) - bd * cg * gd
    a[2] = -ad * sb * bd


@njit(cache=True)
def quaternion_rates(p0, p1, p2, p3, wx, wy, wz, pd):
    """p_dot = 1/2 H_bar^T omega, (3.44)-(3.45)."""
    pd[0] = 0.5 * (-p1 * wx - p2 * wy - p3 * wz)
    pd[1] = 0.5 * (p0 * wx - p3 * wy + p2 * wz)
    pd[2] = 0.5 * (p3 * wx + p0 * wy - p1 * wz)
    pd[3] = 0.5 * (-p2 * wx + p1 * wy + p0 * wz)


@njit(cache=True)
def floating_frame(R, exg):
    """Update e_x^G (2.8) in place; returns sin(beta) = |e_z^I x e_z^B| (2.9).

    For a (numerically) horizontal disk the previous e_x^G is kept, made orthogonal to
    e_z^B and normalised: the continuity condition of Sect. 2.1.
    """
    s = math.sqrt(R[0, 2] * R[0, 2] + R[1, 2] * R[1, 2])
    if s > HORIZONTAL_SIN_BETA:
        exg[0] = -R[1, 2] / s
        exg[1] = R[0, 2] / s
        exg[2] = 0.0
    else:
        d = exg[0] * R[0, 2] + exg[1] * R[1, 2] + exg[2] * R[2, 2]
        x0 = exg[0] - d * R[0, 2]
        x1 = exg[1] - d * R[1, 2]
        x2 = exg[2] - d * R[2, 2]
        n = math.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
        exg[0], exg[1], exg[2] = x0 / n, x1 / n, x2 / n
    return s


@njit(cache=True)
def contact_offsets(R, exg, r, off):
    """r_GC1..3 (rows of off, I-frame) from e_y^G = e_z^B x e_x^G, (2.10)-(2.11)."""
    ez0, ez1, ez2 = R[0, 2], R[1, 2], R[2, 2]
    ey0 = ez1 * exg[2] - ez2 * exg[1]
    ey1 = ez2 * exg[0] - ez0 * exg[2]
    ey2 = ez0 * exg[1] - ez1 * exg[0]
    c0, c1, c2 = -r * ey0, -r * ey1, -r * ey2  # (2.10)
    t0 = ez1 * c2 - ez2 * c1  # e_z^G x r_GC1
    t1 = ez2 * c0 - ez0 * c2
    t2 = ez0 * c1 - ez1 * c0
    s3 = 0.5 * math.sqrt(3.0)
    off[0, 0], off[0, 1], off[0, 2] = c0, c1, c2
    off[1, 0], off[1, 1], off[1, 2] = -0.5 * c0 + s3 * t0, -0.5 * c1 + s3 * t1, -0.5 * c2 + s3 * t2  # (2.11)
    off[2, 0], off[2, 1], off[2, 2] = -0.5 * c0 - s3 * t0, -0.5 * c1 - s3 * t1, -0.5 * c2 - s3 * t2


@njit(cache=True)
def contour_direction(R, s, s_reg, c):
    """c (B-frame) with phi_dot = c . Omega: spin of the body relative to the floating frame.

    phi_dot = (Omega - omega_G) . e_z^B with omega_G . e_z^B = e_x^G_dot . e_y^G
            = R33 w_Iz - R33^2 (w_Ix R13 + w_Iy R23) / s^2   (w_I = R Omega, s = sin beta),
    derived from (2.8); for Euler angles phi_dot = gamma_dot, so gamma_R = -r phi_dot is
    (3.34) and (3.63). The paper's (3.64) prints the first two entries of the row vector with
    the wrong sign: in Euler angles it gives omega_z + cos(beta) alpha_dot, not gamma_dot
    = omega_z - cos(beta) alpha_dot (3.8).

    Regularised near a flat disk: 1/s^2 is replaced by 1/(s^2 + s_reg^2). The exact term grows
    like 1/sin(beta) (the contact point runs round the rim ever faster), so the contour torque
    r mu_R lambda_N |c| of (2.31) would be unbounded; with s_reg it is at most about
    r mu_R lambda_N / (2 s_reg), and for s >> s_reg the law is unchanged (relative change
    (s_reg / s)^2). s_reg = 0 gives the exact law. Zero for a horizontal disk (W_R = 0, Sect. 3.2).
    """
    if s <= HORIZONTAL_SIN_BETA:
        c[0] = 0.0
        c[1] = 0.0
        c[2] = 0.0
        return
    k = R[2, 2] * R[2, 2] / (s * s + s_reg * s_reg)
    # I-frame row vector multiplying w_I
    i0 = k * R[0, 2]
    i1 = k * R[1, 2]
    i2 = -R[2, 2]
    for j in range(3):
        c[j] = R[0, j] * i0 + R[1, j] * i1 + R[2, j] * i2
    c[2] += 1.0
