"""Kinematics of the tippedisk (Sect. 2.1, 3.1, 3.2).

Rotation matrices R = A_IB from z-x-z Euler angles (3.2) and unit quaternions
(3.40), the body angular velocity (3.3), the floating frame G (2.8) and the
candidate contact points C1-C3 (2.10)-(2.11).

The entry-level functions take an ``xp`` namespace with ``sin``, ``cos`` and
``sqrt`` and return nested lists, so the same formula builds numpy arrays
(``xp=numpy``) and heyoka expressions (``xp=heyoka``): every law has one home.
"""

from __future__ import annotations

import numpy as np

from .errors import ParameterError

# ---------------------------------------------------------------- generic entries


def rotation_entries_euler(alpha, beta, gamma, xp=np):
    """R(alpha, beta, gamma) = A_IR A_RG A_GB, (3.1)-(3.2), as nested rows."""
    sa, ca = xp.sin(alpha), xp.cos(alpha)
    sb, cb = xp.sin(beta), xp.cos(beta)
    sg, cg = xp.sin(gamma), xp.cos(gamma)
    return [
        [ca * cg - sa * cb * sg, -ca * sg - sa * cb * cg, sa * sb],
        [sa * cg + ca * cb * sg, -sa * sg + ca * cb * cg, -ca * sb],
        [sb * sg, sb * cg, cb],
    ]


def rotation_entries_quaternion(p0, p1, p2, p3):
    """R(p) of (3.40) as nested rows (orthogonal for |p| = 1)."""
    return [
        [2 * (p0 * p0 + p1 * p1) - 1, 2 * (p1 * p2 - p0 * p3), 2 * (p1 * p3 + p0 * p2)],
        [2 * (p1 * p2 + p0 * p3), 2 * (p0 * p0 + p2 * p2) - 1, 2 * (p2 * p3 - p0 * p1)],
        [2 * (p1 * p3 - p0 * p2), 2 * (p2 * p3 + p0 * p1), 2 * (p0 * p0 + p3 * p3) - 1],
    ]


def omega_entries_from_euler_rates(beta, gamma, alpha_dot, beta_dot, gamma_dot, xp=np):
    """Body angular velocity [omega_x, omega_y, omega_z] from Euler rates, (3.3)."""
    sb, cb = xp.sin(beta), xp.cos(beta)
    sg, cg = xp.sin(gamma), xp.cos(gamma)
    return [
        alpha_dot * sb * sg + beta_dot * cg,
        alpha_dot * sb * cg - beta_dot * sg,
        alpha_dot * cb + gamma_dot,
    ]


def euler_rate_entries_from_omega(beta, gamma, omega_x, omega_y, omega_z, xp=np):
    """Inverse of (3.3): [alpha_dot, beta_dot, gamma_dot]; singular at sin(beta) = 0."""
    sb, cb = xp.sin(beta), xp.cos(beta)
    sg, cg = xp.sin(gamma), xp.cos(gamma)
    alpha_dot = (omega_x * sg + omega_y * cg) / sb
    return [alpha_dot, omega_x * cg - omega_y * sg, omega_z - cb * alpha_dot]


def omega_derivative_entries_at_fixed_rates(beta, gamma, alpha_dot, beta_dot, gamma_dot, xp=np):
    """J_R_dot phi_dot: the time derivative of (3.3) with the Euler rates held fixed (the
    velocity-dependent part of the angular acceleration, Psi = J_R phi_dd + J_R_dot phi_dot)."""
    sb, cb = xp.sin(beta), xp.cos(beta)
    sg, cg = xp.sin(gamma), xp.cos(gamma)
    return [
        alpha_dot * (cb * beta_dot * sg + sb * cg * gamma_dot) - beta_dot * sg * gamma_dot,
        alpha_dot * (cb * beta_dot * cg - sb * sg * gamma_dot) - beta_dot * cg * gamma_dot,
        -alpha_dot * sb * beta_dot,
    ]


def quaternion_rate_entries(p0, p1, p2, p3, omega_x, omega_y, omega_z):
    """p_dot = 1/2 H_bar^T omega, (3.44)-(3.45)."""
    return [
        0.5 * (-p1 * omega_x - p2 * omega_y - p3 * omega_z),
        0.5 * (p0 * omega_x - p3 * omega_y + p2 * omega_z),
        0.5 * (p3 * omega_x + p0 * omega_y - p1 * omega_z),
        0.5 * (-p2 * omega_x + p1 * omega_y + p0 * omega_z),
    ]


def floating_frame_ey_entries(R, sin_beta):
    """e_y^G in I-coordinates from R and sin(beta) = |e_z^I x e_z^B|, (2.8)-(2.9).

    e_x^G = (e_z^I x e_z^B)/sin(beta) and e_y^G = e_z^B x e_x^G give
    e_y^G = (-R33 R13/sin(beta), -R33 R23/sin(beta), sin(beta)).
    Undefined for a horizontal disk (sin(beta) = 0).
    """
    return [-R[2][2] * R[0][2] / sin_beta, -R[2][2] * R[1][2] / sin_beta, sin_beta]


def euler_floating_frame_ey_entries(alpha, beta, xp=np):
    """e_y^G = A_IR A_RG e_y in I-coordinates for Euler angles (no division)."""
    return [-xp.sin(alpha) * xp.cos(beta), xp.cos(alpha) * xp.cos(beta), xp.sin(beta)]


# ---------------------------------------------------------------- numpy front


def _as_matrix(entries) -> np.ndarray:
    """Nested rows of broadcastable arrays -> array of shape (..., 3, 3)."""
    rows = [np.stack(np.broadcast_arrays(*row), axis=-1) for row in entries]
    return np.stack(rows, axis=-2)


def rotation_from_euler(alpha, beta, gamma) -> np.ndarray:
    """R = A_IB of (3.2), shape (..., 3, 3)."""
    return _as_matrix(rotation_entries_euler(*np.broadcast_arrays(alpha, beta, gamma)))


def rotation_from_quaternion(p) -> np.ndarray:
    """R(p) of (3.40) for p of shape (..., 4)."""
    p = np.asarray(p, dtype=float)
    return _as_matrix(rotation_entries_quaternion(p[..., 0], p[..., 1], p[..., 2], p[..., 3]))


def quaternion_from_rotation(R) -> np.ndarray:
    """Unit quaternion p (p0 >= 0) with R(p) = R, for a single rotation matrix (Shepperd's method)."""
    R = np.asarray(R, dtype=float)
    trace = np.trace(R)
    candidates = np.array([trace, R[0, 0], R[1, 1], R[2, 2]])
    k = int(np.argmax(candidates))
    if k == 0:
        p0 = 0.5 * np.sqrt(1.0 + trace)
        p = [p0, (R[2, 1] - R[1, 2]) / (4 * p0), (R[0, 2] - R[2, 0]) / (4 * p0), (R[1, 0] - R[0, 1]) / (4 * p0)]
    else:
        i = k - 1
        j, l = (i + 1) % 3, (i + 2) % 3
        pi = 0.5 * np.sqrt(1.0 + 2 * R[i, i] - trace)
        vec = np.empty(3)
        vec[i] = pi
        vec[j] = (R[j, i] + R[i, j]) / (4 * pi)
        vec[l] = (R[l, i] + R[i, l]) / (4 * pi)
        p = [(R[l, j] - R[j, l]) / (4 * pi), *vec]
    p = np.asarray(p)
    return p if p[0] >= 0 else -p


def euler_from_rotation(R) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(alpha, beta, gamma) of (3.2) from R, with beta in [0, pi] (Sect. 6), wrapped to (-pi, pi]."""
    R = np.asarray(R, dtype=float)
    beta = np.arccos(np.clip(R[..., 2, 2], -1.0, 1.0))
    alpha = np.arctan2(R[..., 0, 2], -R[..., 1, 2])
    gamma = np.arctan2(R[..., 2, 0], R[..., 2, 1])
    return alpha, beta, gamma


def omega_from_euler_rates(beta, gamma, rates) -> np.ndarray:
    """(3.3) for rates = [alpha_dot, beta_dot, gamma_dot] (last axis)."""
    rates = np.asarray(rates, dtype=float)
    return np.stack(omega_entries_from_euler_rates(beta, gamma, rates[..., 0], rates[..., 1], rates[..., 2]), axis=-1)


def euler_rates_from_omega(beta, gamma, omega) -> np.ndarray:
    """Inverse of (3.3); singular for sin(beta) = 0."""
    omega = np.asarray(omega, dtype=float)
    return np.stack(euler_rate_entries_from_omega(beta, gamma, omega[..., 0], omega[..., 1], omega[..., 2]), axis=-1)


def contact_point_offsets(R, r: float) -> np.ndarray:
    """r_GC1, r_GC2, r_GC3 [m] in I-coordinates, (2.10)-(2.11), shape (3, 3) (row i = C_{i+1}).

    C1 is the lowest rim point; C2, C3 follow by rotating r_GC1 by +-2 pi/3 about e_z^B.
    Raises for a horizontal disk, where the floating frame is not defined (Sect. 2.1).
    """
    R = np.asarray(R, dtype=float)
    sin_beta = np.hypot(R[0, 2], R[1, 2])
    if sin_beta == 0.0:
        raise ParameterError("contact points are undefined for a horizontal disk; tilt it (0 < beta < pi)")
    ey = np.array(floating_frame_ey_entries(R, sin_beta))
    ez_B = R[:, 2]
    return disk_radius_offsets(ey, ez_B, r)


def disk_radius_offsets(ey_G, ez_B, r: float) -> np.ndarray:
    """Offsets r_GC1..3 of the rim points from e_y^G and e_z^B, (2.10)-(2.11)."""
    r1 = -r * np.asarray(ey_G)
    turned = np.cross(ez_B, r1)
    s3 = np.sqrt(3.0) / 2
    return np.stack([r1, -0.5 * r1 + s3 * turned, -0.5 * r1 - s3 * turned])


def rest_contact_state(r: float, euler, euler_rates) -> dict[str, np.ndarray]:
    """Position and velocity of G for a closed contact at C1 without slip, (2.10), (6.2).

    z = r sin(beta) closes the gap g_N1 = z - r sin(beta) (2.12); the velocity of G is
    v_G = -Omega x r_GC1 so that the material point at C1 is at rest (2.13): both the
    normal velocity (3.26) and the slip (3.27) vanish.
    Returns ``z`` [m], ``v_G`` [m/s] (I-frame), ``omega`` [rad/s] (B-frame).
    """
    alpha, beta, gamma = euler
    R = rotation_from_euler(alpha, beta, gamma)
    omega = omega_from_euler_rates(beta, gamma, euler_rates)
    r_GC1 = -r * np.array(euler_floating_frame_ey_entries(alpha, beta))
    v_G = -np.cross(R @ omega, r_GC1)
    return {"z": r * np.sin(beta), "v_G": v_G, "omega": omega}
