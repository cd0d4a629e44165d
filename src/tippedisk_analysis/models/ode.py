"""ODE Models 1 and 2: bilateral contact at C1 with smooth Coulomb friction (Sect. 4.1).

The equations are derived from the kinematics (Sect. 2) as Newton-Euler equations
about the centre of gravity S, which keeps the right-hand side explicit:

* contact force at C1: F = lambda_N n with n = e_z^I - mu gamma_T / (|gamma_T| + eps)
  (normal force (2.19) and smooth Coulomb friction (2.29), linear in lambda_N);
* m a_S = F - m g e_z^I and Theta_S Psi + Omega x Theta_S Omega = r_SC x F
  (equivalent to (2.41) about G), Theta_S = diag(A, B - m e^2, C - m e^2);
* a_G = a_S - Psi x r_GS - Omega x (Omega x r_GS), rigid body formula (2.7);
* the bilateral constraint g_N1 = z - r sin(beta) = 0 (2.12) on acceleration level,
  z_dd = r (sin beta)_dd, (4.9); every acceleration is affine in lambda_N, so lambda_N
  is one division: no matrix inverse.

State: position of G, orientation (z-x-z Euler angles (3.1) or a quaternion (3.40)),
velocity of G (I-frame), body angular velocity (3.43) -- the minimal velocities of
(3.9) -- and the work done by friction, integrated alongside for the energy balance.

|gamma_T| is evaluated as sqrt(|gamma_T|^2 + delta^2) - delta (delta = ``slip_smoothing``,
default 1e-12 m/s): this makes (2.29) analytic at zero slip, where the exact law is
only C^1 and the Taylor recursion of sqrt(gx^2 + gy^2) divides by zero. The force
changes by at most mu lambda_N delta / eps (relative 1e-11 for the defaults) and its
slope at zero slip stays exactly I/eps.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import heyoka as hy

from .. import kinematics as kin

# Runtime parameters hy.par[i]: one compiled integrator serves every value.
PARAMETER_NAMES = ("m", "e", "r", "A", "B", "C", "gravity", "mu", "eps", "slip_smoothing", "fall_angle")
P = {name: hy.par[i] for i, name in enumerate(PARAMETER_NAMES)}


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _matvec(R, v):
    return [_dot(row, v) for row in R]


def _matTvec(R, v):
    return [R[0][i] * v[0] + R[1][i] * v[1] + R[2][i] * v[2] for i in range(3)]


def _add(a, b, scale=1.0):
    return [ai + scale * bi for ai, bi in zip(a, b)]


def slip_magnitude(gx, gy, delta):
    """|gamma_T| made analytic at zero slip: sqrt(gx^2 + gy^2 + delta^2) - delta."""
    return hy.sqrt(gx * gx + gy * gy + delta * delta) - delta


@dataclass(frozen=True)
class ContactDynamics:
    """Expressions of the constrained dynamics at one state."""

    a_G: list  # acceleration of G, I-frame [m/s^2]
    psi: list  # angular acceleration, B-frame [rad/s^2]
    lambda_N: object  # normal force at C1 [N]
    slip: list  # sliding velocity gamma_T1 (3.27) [m/s]
    gamma_N: object  # normal velocity gamma_N1 (3.26) [m/s]
    friction_power: object  # lambda_T . gamma_T [W], <= 0
    energies: dict  # E_kin, E_pot [J]
    z_S: object  # height of S [m]
    g_N1: object  # gap at C1 (2.12) [m]


def contact_dynamics(R, sin_beta, ey_G, r_OG, v_G, omega) -> ContactDynamics:
    """Newton-Euler equations with the bilateral contact at C1 and smooth Coulomb friction.

    R: rotation matrix (nested rows) (3.2)/(3.40); sin_beta = |e_z^I x e_z^B| (2.9);
    ey_G: e_y^G in I (2.8); r_OG, v_G: position and velocity of G in I; omega: B-frame.
    """
    m, e, r, g = P["m"], P["e"], P["r"], P["gravity"]
    theta_S = [P["A"], P["B"] - m * e * e, P["C"] - m * e * e]
    ez = [0.0, 0.0, 1.0]
    ez_B = [R[0][2], R[1][2], R[2][2]]
    cos_beta = R[2][2]

    r_GS = [e * R[i][0] for i in range(3)]  # e e_x^B
    r_GC = [-r * c for c in ey_G]  # (2.10)
    r_SC = _add(r_GC, r_GS, -1.0)
    omega_I = _matvec(R, omega)

    # contact velocity (2.13)-(2.15), smooth Coulomb (2.29): F = lambda_N * n
    v_C = _add(v_G, _cross(omega_I, r_GC))
    slip = v_C[:2]
    k = P["mu"] / (slip_magnitude(slip[0], slip[1], P["slip_smoothing"]) + P["eps"])
    n = [-k * slip[0], -k * slip[1], 1.0]

    # Psi = psi0 + lambda_N psi1 (Euler's equation about S, B-frame)
    L = [theta_S[i] * omega[i] for i in range(3)]
    gyro = _cross(omega, L)
    psi0 = [-gyro[i] / theta_S[i] for i in range(3)]
    moment = _matTvec(R, _cross(r_SC, n))
    psi1 = [moment[i] / theta_S[i] for i in range(3)]

    # a_G = aG0 + lambda_N aG1 (Newton about S, rigid body formula)
    centripetal = _cross(omega_I, _cross(omega_I, r_GS))
    aG0 = _add(_add([0.0, 0.0, -g], _cross(_matvec(R, psi0), r_GS), -1.0), centripetal, -1.0)
    aG1 = _add([n[i] / m for i in range(3)], _cross(_matvec(R, psi1), r_GS), -1.0)

    # constraint z_dd = r (sin beta)_dd with cos beta = e_z . e_z^B:
    # c_d = e_z.(Omega x e_z^B), c_dd = e_z.(Psi x e_z^B + Omega x (Omega x e_z^B)),
    # s_dd = -(c_d^2 + c c_dd)/s - c^2 c_d^2 / s^3
    c, s = cos_beta, sin_beta
    c_d = _dot(ez, _cross(omega_I, ez_B))
    c_dd0 = _dot(ez, _add(_cross(_matvec(R, psi0), ez_B), _cross(omega_I, _cross(omega_I, ez_B))))
    c_dd1 = _dot(ez, _cross(_matvec(R, psi1), ez_B))
    s_dd0 = -(c_d * c_d + c * c_dd0) / s - c * c * c_d * c_d / (s * s * s)
    s_dd1 = -c * c_dd1 / s
    lambda_N = (r * s_dd0 - aG0[2]) / (aG1[2] - r * s_dd1)

    a_G = _add(aG0, aG1, lambda_N)
    psi = _add(psi0, psi1, lambda_N)

    v_S = _add(v_G, _cross(omega_I, r_GS))
    z_S = r_OG[2] + r_GS[2]
    energies = {
        "E_kin": 0.5 * m * _dot(v_S, v_S) + 0.5 * _dot(omega, L),
        "E_pot": m * g * z_S,
    }
    return ContactDynamics(
        a_G=a_G,
        psi=psi,
        lambda_N=lambda_N,
        slip=slip,
        gamma_N=v_C[2],
        friction_power=lambda_N * (n[0] * slip[0] + n[1] * slip[1]),
        energies=energies,
        z_S=z_S,
        g_N1=r_OG[2] - r * s,
    )


@dataclass(frozen=True)
class OdeModel:
    """One ODE formulation: its state variables and how to build its equations."""

    name: str
    paper_name: str
    orientation: tuple[str, ...]
    build: Callable[[list], tuple[list, list, object, ContactDynamics, list]]

    @property
    def state_names(self) -> tuple[str, ...]:
        return ("x", "y", "z", *self.orientation, "x_dot", "y_dot", "z_dot", "omega_x", "omega_y", "omega_z",
                "W_friction")

    def equations(self):
        """(sys, events-ready pieces): list of (var, rhs), output expressions, helpers."""
        variables = hy.make_vars(*self.state_names)
        return variables, self.build(variables)


def _split(variables, n_orient):
    r_OG = variables[0:3]
    orient = variables[3:3 + n_orient]
    v_G = variables[3 + n_orient:6 + n_orient]
    omega = variables[6 + n_orient:9 + n_orient]
    return r_OG, orient, v_G, omega


def _build_euler(variables):
    r_OG, (alpha, beta, gamma), v_G, omega = _split(variables, 3)
    R = kin.rotation_entries_euler(alpha, beta, gamma, xp=hy)
    sin_beta = hy.sin(beta)
    ey_G = kin.euler_floating_frame_ey_entries(alpha, beta, xp=hy)
    dyn = contact_dynamics(R, sin_beta, ey_G, r_OG, v_G, omega)
    orient_rates = kin.euler_rate_entries_from_omega(beta, gamma, *omega, xp=hy)  # (3.8)
    angles = [alpha, beta, gamma]
    return R, orient_rates, sin_beta, dyn, angles


def _build_quaternion(variables):
    r_OG, p, v_G, omega = _split(variables, 4)
    R = kin.rotation_entries_quaternion(*p)
    sin_beta = hy.sqrt(R[0][2] * R[0][2] + R[1][2] * R[1][2])  # (2.9)
    ey_G = kin.floating_frame_ey_entries(R, sin_beta)
    dyn = contact_dynamics(R, sin_beta, ey_G, r_OG, v_G, omega)
    orient_rates = kin.quaternion_rate_entries(*p, *omega)  # (3.44)
    angles = [hy.atan2(R[0][2], -R[1][2]), hy.acos(R[2][2]), hy.atan2(R[2][0], R[2][1])]  # inverse of (3.2)
    return R, orient_rates, sin_beta, dyn, angles


EULER = OdeModel("ode-euler", "ODE Model 1", ("alpha", "beta", "gamma"), _build_euler)
QUATERNION = OdeModel("ode-quaternion", "ODE Model 2", ("p0", "p1", "p2", "p3"), _build_quaternion)


def system(model: OdeModel):
    """The heyoka system, the fall event expression and the output expressions of ``model``.

    Outputs (in this order, see OUTPUT_NAMES): Euler angles, Euler rates (3.8), z_S,
    g_N1, gamma_N1, lambda_N, slip_x, slip_y, E_kin, E_pot, friction power.
    """
    variables, (R, orient_rates, sin_beta, dyn, angles) = model.equations()
    n_o = len(model.orientation)
    v_G = variables[3 + n_o:6 + n_o]
    omega = variables[6 + n_o:9 + n_o]
    rhs = [*v_G, *orient_rates, *dyn.a_G, *dyn.psi, dyn.friction_power]
    sys = list(zip(variables, rhs))
    # the disk has fallen when its tilt above the table, asin(sin beta), drops to fall_angle
    fall = sin_beta - hy.sin(P["fall_angle"])
    euler_rates = kin.euler_rate_entries_from_omega(angles[1], angles[2], *omega, xp=hy)
    outputs = [*angles, *euler_rates, dyn.z_S, dyn.g_N1, dyn.gamma_N, dyn.lambda_N, *dyn.slip,
               dyn.energies["E_kin"], dyn.energies["E_pot"], dyn.friction_power]
    return variables, sys, fall, outputs


OUTPUT_NAMES = ("alpha", "beta", "gamma", "alpha_dot", "beta_dot", "gamma_dot", "z_S", "g_N1", "gamma_N1",
                "lambda_N", "slip_x", "slip_y", "E_kin", "E_pot", "P_friction")

MODELS = {m.name: m for m in (EULER, QUATERNION)}
