"""Scalar numba kernels of the Moreau models (Sect. 2, 3, 4): kinematics, force directions, prox.

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

import numpy as np
from numba import njit

XI_STAR = 9.0 * math.pi / 32.0  # (2.26)
ETA_STAR = 9.0 * math.pi / 128.0  # (2.26)
HORIZONTAL_SIN_BETA = 1e-12  # below this |e_z^I x e_z^B| the floating frame keeps its previous e_x^G


# ----------------------------------------------------------------- kinematics


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
def contour_direction(R, s, c):
    """c (B-frame) with phi_dot = c . Omega: spin of the body relative to the floating frame.

    phi_dot = (Omega - omega_G) . e_z^B with omega_G . e_z^B = e_x^G_dot . e_y^G
            = R33 w_Iz - R33^2 (w_Ix R13 + w_Iy R23) / s^2   (w_I = R Omega, s = sin beta),
    derived from (2.8); for Euler angles phi_dot = gamma_dot, so gamma_R = -r phi_dot is
    (3.34) and (3.63). Zero for a horizontal disk (W_R = 0, Sect. 3.2).
    """
    if s <= HORIZONTAL_SIN_BETA:
        c[0] = 0.0
        c[1] = 0.0
        c[2] = 0.0
        return
    k = R[2, 2] * R[2, 2] / (s * s)
    # I-frame row vector multiplying w_I
    i0 = k * R[0, 2]
    i1 = k * R[1, 2]
    i2 = -R[2, 2]
    for j in range(3):
        c[j] = R[0, j] * i0 + R[1, j] * i1 + R[2, j] * i2
    c[2] += 1.0


# ----------------------------------------------------------------- prox operators


@njit(cache=True)
def prox_nonneg(x):
    """Projection onto R_0^+ (Signorini / Newton impact law (2.19)-(2.21))."""
    return x if x > 0.0 else 0.0


@njit(cache=True)
def prox_interval(x, radius):
    """Projection onto [-radius, radius] (dry pivoting (2.30), contour friction (2.31))."""
    if x > radius:
        return radius
    if x < -radius:
        return -radius
    return x


@njit(cache=True)
def prox_disk(x, y, radius):
    """Projection of (x, y) onto the disk of the given radius (spatial Coulomb (2.22), (2.28))."""
    n = math.hypot(x, y)  # no underflow of x * x for tiny x
    if n <= radius:
        return x, y
    if n == 0.0:
        return 0.0, 0.0
    f = radius / n
    return x * f, y * f


def contensou_polygon(n: int = 129) -> np.ndarray:
    """Vertices (xi_bar, eta_bar) of the first-quadrant boundary of B_F (2.25)-(2.27), scaled by mu P_N.

    The boundary eta_bar(xi_bar) of (2.27) (truncated series as printed; branch 1 for
    xi_bar <= xi*, branch 2 above) is sampled at ``n`` values of xi_bar in [0, 1], and its
    least concave majorant (upper convex hull) is taken: the two truncated branches do not
    meet at xi* (eta_bar 0.197 vs 0.221), and the hull makes the set convex, as a friction
    ball must be. Runs from (0, 3 pi/16) (pure pivoting) to (1, 0) (pure sliding).
    """
    xi = np.linspace(0.0, 1.0, n)
    eta = np.empty_like(xi)
    x = xi / XI_STAR
    first = xi <= XI_STAR
    eta[first] = ETA_STAR * np.sqrt(64.0 / 9.0 * (1.0 - 9.0 / 8.0 * x[first] ** 2 + 243.0 / 1024.0 * x[first] ** 4))
    k = 75.0 / 7.0
    disc = np.maximum(25.0 - 4.0 * k * (1.0 - xi[~first] ** 2), 0.0)
    eta[~first] = np.sqrt(np.maximum((5.0 - np.sqrt(disc)) / (2.0 * k), 0.0))
    hull: list[tuple[float, float]] = []  # monotone chain, upper hull
    for point in zip(xi, eta):
        while len(hull) >= 2:
            (x1, y1), (x2, y2) = hull[-2], hull[-1]
            if (x2 - x1) * (point[1] - y1) - (y2 - y1) * (point[0] - x1) >= 0:  # not a right turn
                hull.pop()
            else:
                break
        hull.append(point)
    return np.ascontiguousarray(hull, dtype=float)


@njit(cache=True)
def prox_contensou(tx, ty, tau, radius, poly):
    """Euclidean projection of (lambda_T, lambda_tau) onto the friction ball B_F of radius mu P_N.

    B_F is rotationally symmetric about the lambda_tau axis and symmetric in lambda_tau, so
    the projection works in the meridian half-plane (|lambda_T|, |lambda_tau|) / radius:
    inside the convex polygon ``poly`` (:func:`contensou_polygon`) the point is kept, else
    it moves to the nearest point of the boundary polyline; direction and signs are restored.
    Exact for the polygonal ball (129 vertices: boundary error below 1e-4 of mu P_N).
    """
    if radius <= 1e-290:  # the ball is the origin (and rho / radius would overflow)
        return 0.0, 0.0, 0.0
    rho = math.hypot(tx, ty)
    a = rho / radius
    b = abs(tau) / radius
    nv = poly.shape[0]
    if a <= 1.0:  # inside test against the concave boundary eta_bar(xi_bar)
        k = 0
        while k < nv - 2 and poly[k + 1, 0] < a:
            k += 1
        x0, y0, x1, y1 = poly[k, 0], poly[k, 1], poly[k + 1, 0], poly[k + 1, 1]
        t = (a - x0) / (x1 - x0) if x1 > x0 else 0.0
        if b <= y0 + t * (y1 - y0):
            return tx, ty, tau
    best = 1e300
    ba, bb = 0.0, 0.0
    for k in range(nv - 1):
        x0, y0 = poly[k, 0], poly[k, 1]
        dx, dy = poly[k + 1, 0] - x0, poly[k + 1, 1] - y0
        t = ((a - x0) * dx + (b - y0) * dy) / (dx * dx + dy * dy)
        if t < 0.0:
            t = 0.0
        elif t > 1.0:
            t = 1.0
        px, py = x0 + t * dx, y0 + t * dy
        d = (px - a) * (px - a) + (py - b) * (py - b)
        if d < best:
            best, ba, bb = d, px, py
    if rho > 0.0:
        f = ba * radius / rho
        ox, oy = tx * f, ty * f
    else:
        ox, oy = 0.0, 0.0
    ot = bb * radius if tau >= 0.0 else -bb * radius
    return ox, oy, ot
