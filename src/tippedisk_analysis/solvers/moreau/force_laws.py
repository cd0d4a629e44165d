"""One prox sweep of the contact laws of one closed contact (numba), Sect. 2.2 and (4.4)-(4.7).

Each function takes the contact's velocities ``xi`` (xi = gamma_E + e gamma_A, (4.3), per
impulse kind of :mod:`.layout`) and its impulses of the previous sweep, and returns the new
impulses. The normal impulse of the same sweep enters the friction reservoirs (mu P_N).
"""

from __future__ import annotations

import math

from numba import njit

from ...models import prox


@njit(cache=True)
def normal(P_N, xi_N, r_N):
    """Signorini / Newton (2.19)-(2.21): P_N = prox_{R0+}(P_N - r_N xi_N), (4.4)."""
    return prox.prox_nonneg(P_N - r_N * xi_N)


@njit(cache=True)
def coulomb(P_x, P_y, xi_x, xi_y, r_T, radius):
    """Set-valued spatial Coulomb (2.22), (2.28): projection onto the disk of radius mu P_N, (4.5)."""
    return prox.prox_disk(P_x - r_T * xi_x, P_y - r_T * xi_y, radius)


@njit(cache=True)
def smooth_coulomb(P_x, P_y, gamma_x, gamma_y, mu_P_N, eps, G_TT):
    """Regularised Coulomb (2.29) at the end-of-step slip (gamma_x, gamma_y): P_T = -mu P_N gamma / (|gamma| + eps).

    A relaxed fixed point, theta = 1 / (1 + mu P_N G_TT / eps), makes the linear part
    (|gamma_T| << eps) converge in one sweep even for impact-sized P_N; theta ~ 1 in
    ordinary steps (mu P_N G_TT / eps ~ 1e-4).
    """
    slope = -mu_P_N / (math.sqrt(gamma_x * gamma_x + gamma_y * gamma_y) + eps)
    theta = 1.0 / (1.0 + mu_P_N * G_TT / eps)
    return P_x + theta * (slope * gamma_x - P_x), P_y + theta * (slope * gamma_y - P_y)


@njit(cache=True)
def contensou(P_x, P_y, P_tau, xi_x, xi_y, xi_tau, r_T, radius, ball):
    """Coulomb-Contensou (2.24)-(2.27): (P_T, P_tau) = prox_{B_F(mu P_N)}(P - r_T xi), one Euclidean projection."""
    return prox.prox_contensou(P_x - r_T * xi_x, P_y - r_T * xi_y, P_tau - r_T * xi_tau, radius, ball)


@njit(cache=True)
def interval(P, xi, r, radius):
    """Dry pivoting (2.30), (4.6) and contour friction (2.31), (4.7): projection onto [-radius, radius]."""
    return prox.prox_interval(P - r * xi, radius)
