"""Proximal point operators of the set-valued force laws (Sect. 2.2, 4): projections onto the
negative force reservoirs, as numba kernels for the Moreau step loop.

* prox_nonneg: Signorini / Newton (2.19)-(2.21), R_0^+;
* prox_interval: dry pivoting (2.30) and contour friction (2.31), [-radius, radius];
* prox_disk: spatial Coulomb friction (2.22), (2.28), the disk of radius mu P_N;
* prox_contensou: Coulomb-Contensou friction (2.24)-(2.27), the friction ball B_F.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

XI_STAR = 9.0 * math.pi / 32.0  # (2.26)
ETA_STAR = 9.0 * math.pi / 128.0  # (2.26)


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

    Axes: xi_bar = |lambda_T| / (mu lambda_N), eta_bar = lambda_tau / (mu lambda_N), where
    lambda_tau is dual to gamma_tau = eps_i omega_IB (2.16), i.e. the pivoting torque divided by
    the contact radius. (2.27) is the ball of a Hertzian (semi-ellipsoidal) pressure on a circular
    contact: pure pivoting 3 pi / 16, eta_bar ~ gamma_tau / (5 |gamma_T|) near pure sliding,
    and (xi*, eta*) of (2.26) is its exact point at |gamma_T| = gamma_tau (tests/test_prox.py
    evaluates that law by quadrature).

    The boundary of (2.27) (truncated series as printed) is sampled finely: branch 1
    (xi_bar <= xi*) in xi_bar; branch 2 (xi_bar > xi*), xi_bar = sqrt(1 - 5 eta_bar^2 +
    75/7 eta_bar^4), in eta_bar, because there the boundary turns vertical. Its least concave
    majorant (upper convex hull) is taken: the two truncated branches do not meet at xi*
    (eta_bar 0.197 vs 0.221), and the hull makes the set convex, as a friction ball must be.
    The (at most ``n``) vertices returned are the hull's support points for ``n - 2`` velocity
    directions (gamma_T, gamma_tau) = (s, 1), s log-spaced over [1e-3, 1e3], plus pure sliding
    and pure pivoting: the prox (the normal-cone law (2.24)) then resolves the friction law with
    the same relative accuracy (a few per cent) from pivot- to slide-dominated contact. (Sampling
    uniformly in xi_bar instead gives zero pivoting torque whenever |gamma_T| > 7.2 gamma_tau.)
    Runs from (0, 3 pi/16) (pure pivoting) to (1, 0) (pure sliding).
    """
    m = 4001
    xi1 = np.linspace(0.0, XI_STAR, m)
    x = xi1 / XI_STAR
    eta1 = ETA_STAR * np.sqrt(64.0 / 9.0 * (1.0 - 9.0 / 8.0 * x**2 + 243.0 / 1024.0 * x**4))
    k = 75.0 / 7.0
    eta_switch = math.sqrt((5.0 - math.sqrt(25.0 - 4.0 * k * (1.0 - XI_STAR**2))) / (2.0 * k))  # branch 2 at xi*
    eta2 = np.linspace(eta_switch, 0.0, m)[1:]  # xi_bar > xi*
    xi2 = np.sqrt(1.0 - 5.0 * eta2**2 + k * eta2**4)
    hull: list[tuple[float, float]] = []  # monotone chain, upper hull
    for point in zip(np.concatenate([xi1, xi2]), np.concatenate([eta1, eta2])):
        while len(hull) >= 2:
            (x1, y1), (x2, y2) = hull[-2], hull[-1]
            if (x2 - x1) * (point[1] - y1) - (y2 - y1) * (point[0] - x1) >= 0:  # not a right turn
                hull.pop()
            else:
                break
        hull.append(point)
    dense = np.array(hull)
    s = np.geomspace(1e-3, 1e3, max(n - 2, 1))
    directions = np.concatenate([[0.0], np.arctan2(1.0, s[::-1]), [0.5 * math.pi]])  # 0: sliding, pi/2: pivoting
    support = np.argmax(dense[:, 0] * np.cos(directions)[:, None] + dense[:, 1] * np.sin(directions)[:, None], axis=1)
    return np.ascontiguousarray(dense[np.unique(support)], dtype=float)


@njit(cache=True)
def prox_contensou(tx, ty, tau, radius, poly):
    """Euclidean projection of (lambda_T, lambda_tau) onto the friction ball B_F of radius mu P_N.

    B_F is rotationally symmetric about the lambda_tau axis and symmetric in lambda_tau, so
    the projection works in the meridian half-plane (|lambda_T|, |lambda_tau|) / radius:
    inside the convex polygon ``poly`` (:func:`contensou_polygon`) the point is kept, else
    it moves to the nearest point of the boundary polyline; direction and signs are restored.
    Exact for the polygonal ball; the law it gives matches the Hertz-contact law behind (2.27) within
    4 % for |gamma_T| / gamma_tau in [3e-3, 300] (tests/test_prox.py).
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
        d = px * px + py * py - 2.0 * (px * a + py * b)  # |p - (a, b)|^2 - |(a, b)|^2: no cancellation far out
        if d < best:
            best, ba, bb = d, px, py
    if rho > 0.0:
        f = ba * radius / rho
        ox, oy = tx * f, ty * f
    else:
        ox, oy = 0.0, 0.0
    ot = bb * radius if tau >= 0.0 else -bb * radius
    return ox, oy, ot
