"""ODE Models 1 and 2: bilateral contact at C1 with smooth Coulomb friction (Sect. 4.1).

The equations are derived from the kinematics (Sect. 2) as Newton-Euler equations
about the centre of gravity S, written in the floating frame G of Sect. 2.1
(e_x^G horizontal, e_z^G = e_z^B), where the contact geometry is simplest:
r_GC1 = -r e_y^G (2.10), e_z^I = (0, sin beta, cos beta), r_GS = e (cos gamma, sin gamma, 0).

* contact force at C1: F = lambda_N n with n = e_z^I - mu gamma_T / (|gamma_T| + eps)
  (normal force (2.19) and smooth Coulomb friction (2.29), linear in lambda_N);
* m a_S = F - m g e_z^I and Theta_S Psi + Omega x Theta_S Omega = r_SC x F
  (equivalent to (2.41) about G), Theta_S = diag(A, B - m e^2, C - m e^2);
* a_G = a_S - Psi x r_GS - Omega x (Omega x r_GS), rigid body formula (2.7);
* the bilateral constraint g_N1 = z - r sin(beta) = 0 (2.12) on acceleration level,
  z_dd = r (cos beta beta_dd - sin beta beta_d^2), (4.9), with beta_d = Omega . e_x^G;
  every acceleration is affine in lambda_N, so lambda_N is one division: no matrix inverse.

Both formulations only enter through sin and cos of the Euler angles (3.1): the
Euler model has them directly, the quaternion model reads them off R(p) (3.40).

The bilateral contact is built into the coordinates: the height of G and its rate follow
from the orientation, z = r sin(beta) (2.12) and z_dot = r cos(beta) beta_dot, so they are
outputs, not states. The gap g_N1 and the normal velocity gamma_N1 then vanish to round-off
for any horizon (integrating z beside the angles let the acceleration-level constraint (4.9)
drift like t^2: 8.7e-7 m after 2000 s of the Table 3 run), at no cost per step.
State: horizontal position of G, orientation (Euler angles or quaternion), horizontal
velocity of G (I-frame), body angular velocity (3.43) -- the minimal velocities of (3.9) --
and the work done by friction, integrated alongside for the energy balance.

|gamma_T| is evaluated as sqrt(|gamma_T|^2 + delta^2) - delta (delta = ``slip_smoothing``,
default 1e-12 m/s): this makes (2.29) analytic at zero slip, where the exact law is
only C^1 and the Taylor recursion of sqrt(gx^2 + gy^2) divides by zero. The force
changes by at most mu lambda_N delta / eps (relative 1e-11 for the defaults) and its
slope at zero slip stays exactly I/eps.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import heyoka as hy
import numpy as np

from .. import kinematics as kin
from ..defaults import FALL_ANGLE, SLIP_SMOOTHING
from ..dynamics import Event, System
from ..parameters import InitialState, Setup
from .variables import (ORIENTATIONS, OUTPUT_NAMES, PARAMETER_NAMES, PARAMETER_UNITS,  # noqa: F401
                        state_names)

P = {name: hy.par[i] for i, name in enumerate(PARAMETER_NAMES)}


def cross(a, b):
    """a x b of two 3-vectors (lists of expressions or numbers), in the frame both are given in."""
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def dot(a, b):
    """a . b of two 3-vectors."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def slip_magnitude(gamma_T_squared, delta):
    """|gamma_T| made analytic at zero slip: sqrt(|gamma_T|^2 + delta^2) - delta."""
    return hy.sqrt(gamma_T_squared + delta * delta) - delta


@dataclass(frozen=True)
class Trig:
    """sin and cos of the Euler angles (3.1): all the orientation the dynamics needs."""

    sa: object
    ca: object
    sb: object
    cb: object
    sg: object
    cg: object

    def G_from_I(self, v):
        """I-components -> G-components (rows e_x^G, e_y^G, e_z^G of A_IR A_RG)."""
        sa, ca, sb, cb = self.sa, self.ca, self.sb, self.cb
        return [ca * v[0] + sa * v[1],
                -sa * cb * v[0] + ca * cb * v[1] + sb * v[2],
                sa * sb * v[0] - ca * sb * v[1] + cb * v[2]]

    def I_from_G(self, v):
        sa, ca, sb, cb = self.sa, self.ca, self.sb, self.cb
        return [ca * v[0] - sa * cb * v[1] + sa * sb * v[2],
                sa * v[0] + ca * cb * v[1] - ca * sb * v[2],
                sb * v[1] + cb * v[2]]

    def G_from_B(self, v):
        """A_GB of (3.1)."""
        return [self.cg * v[0] - self.sg * v[1], self.sg * v[0] + self.cg * v[1], v[2]]

    def B_from_G(self, v):
        return [self.cg * v[0] + self.sg * v[1], -self.sg * v[0] + self.cg * v[1], v[2]]


@dataclass(frozen=True)
class ContactDynamics:
    """Expressions of the constrained dynamics at one state."""

    r_OG: list  # position of G, I-frame [m] (z = r sin(beta))
    v_G: list  # velocity of G, I-frame [m/s] (z_dot = r cos(beta) beta_dot)
    a_G: list  # acceleration of G, I-frame [m/s^2]
    psi: list  # angular acceleration, B-frame [rad/s^2]
    lambda_N: object  # normal force at C1 [N]
    slip: list  # sliding velocity gamma_T1 (3.27), I-frame x, y [m/s]
    gamma_N: object  # normal velocity gamma_N1 (3.26) [m/s]
    friction_power: object  # lambda_T . gamma_T [W], <= 0
    euler_rates: list  # alpha_dot, beta_dot, gamma_dot (3.8) [rad/s]
    energies: dict  # E_kin, E_pot [J]
    z_S: object  # height of S [m]
    g_N1: object  # gap at C1 (2.12) [m]


def contact_dynamics(trig: Trig, r_xy, v_xy, omega, slip_norm=None, slip_direction=None) -> ContactDynamics:
    """Newton-Euler equations with the bilateral contact at C1 and smooth Coulomb friction.

    trig: sin/cos of the Euler angles; r_xy, v_xy: horizontal position and velocity of G (I-frame);
    omega: angular velocity (B-frame). The height of G and its rate follow from the contact at C1,
    z = r sin(beta) (2.12) and z_dot = r cos(beta) beta_dot. Vectors below are in G-components unless
    named _B/_I.
    slip_norm: an expression to use for |gamma_T| in (2.29) instead of the slip's own norm (the
    normal forms of analysis/ need the law's dependence on |gamma_T| separately, since |gamma_T|
    is not differentiable at zero slip); default the model's analytic |gamma_T|.
    slip_direction: (t_x, t_y), the unit slip direction in the I-frame, for set-valued Coulomb friction
    while sliding, F = lambda_N (e_z^I - mu t) (2.24) (the hybrid model: the slip is integrated as speed
    and angle); replaces the smooth law.
    """
    m, e, r, g = P["m"], P["e"], P["r"], P["gravity"]
    theta_S = [P["A"], P["B"] - m * e * e, P["C"] - m * e * e]
    sb, cb = trig.sb, trig.cb
    ez_I = [0.0, sb, cb]
    Omega_G = trig.G_from_B(omega)  # angular velocity in G-components
    beta_d = Omega_G[0]  # (3.8): e_x^G is the nodal axis of beta
    r_OG = [r_xy[0], r_xy[1], r * sb]  # g_N1 = 0 (2.12)
    v_G = [v_xy[0], v_xy[1], r * cb * beta_d]  # its rate: gamma_N1 = 0
    v = trig.G_from_I(v_G)
    r_GS = [e * trig.cg, e * trig.sg, 0.0]
    r_SC = [-r_GS[0], -r - r_GS[1], 0.0]  # r_GC1 = -r e_y^G (2.10)

    # contact velocity (2.13): v_C = v_G + Omega x r_GC1; slip = its horizontal part (2.15)
    v_C = [v[0] + r * Omega_G[2], v[1], v[2] - r * Omega_G[0]]
    gamma_N = dot(v_C, ez_I)  # (2.14)
    slip = [v_C[i] - gamma_N * ez_I[i] for i in range(3)]
    slip_squared = dot(v_C, v_C) - gamma_N * gamma_N
    if slip_direction is None:
        norm = slip_magnitude(slip_squared, P["slip_smoothing"]) if slip_norm is None else slip_norm
        k = P["mu"] / (norm + P["eps"])  # (2.29)
        n = [ez_I[i] - k * slip[i] for i in range(3)]  # F = lambda_N n
        friction_power = -k * slip_squared  # per unit lambda_N
    else:  # set-valued Coulomb while sliding: -mu lambda_N along the slip direction
        t_G = trig.G_from_I([slip_direction[0], slip_direction[1], 0.0])
        n = [ez_I[i] - P["mu"] * t_G[i] for i in range(3)]
        friction_power = -P["mu"] * dot(t_G, slip)

    # Psi = psi0 + lambda_N psi1: Euler's equation about S, B-frame
    L = [theta_S[i] * omega[i] for i in range(3)]
    gyro = cross(omega, L)
    psi0 = [-gyro[i] / theta_S[i] for i in range(3)]
    moment = trig.B_from_G(cross(r_SC, n))
    psi1 = [moment[i] / theta_S[i] for i in range(3)]
    psi0_G, psi1_G = trig.G_from_B(psi0), trig.G_from_B(psi1)

    # a_G = aG0 + lambda_N aG1: Newton about S and the rigid body formula
    centripetal = cross(Omega_G, cross(Omega_G, r_GS))
    turn0, turn1 = cross(psi0_G, r_GS), cross(psi1_G, r_GS)
    aG0 = [-g * ez_I[i] - turn0[i] - centripetal[i] for i in range(3)]
    aG1 = [n[i] / m - turn1[i] for i in range(3)]

    # Euler rates (3.8) in G: beta_d = W_x, alpha_d sin(beta) = W_y, gamma_d = omega_z - cos(beta) alpha_d
    alpha_d = Omega_G[1] / sb
    gamma_d = omega[2] - cb * alpha_d
    # beta_dd = d/dt(cos(gamma) omega_x - sin(gamma) omega_y) = (A_GB Psi)_x - gamma_d W_y
    beta_dd0, beta_dd1 = psi0_G[0] - gamma_d * Omega_G[1], psi1_G[0]
    # constraint (4.9): e_z^I . a_G = r (cos(beta) beta_dd - sin(beta) beta_d^2)
    lambda_N = (r * (cb * beta_dd0 - sb * beta_d * beta_d) - dot(aG0, ez_I)) / (dot(aG1, ez_I) - r * cb * beta_dd1)

    a_G = trig.I_from_G([aG0[i] + lambda_N * aG1[i] for i in range(3)])
    psi = [psi0[i] + lambda_N * psi1[i] for i in range(3)]
    slip_I = trig.I_from_G(slip)[:2]

    v_S = [v[i] + c for i, c in enumerate(cross(Omega_G, r_GS))]
    z_S = r_OG[2] + e * sb * trig.sg
    return ContactDynamics(
        r_OG=r_OG,
        v_G=v_G,
        a_G=a_G,
        psi=psi,
        lambda_N=lambda_N,
        slip=slip_I,
        gamma_N=gamma_N,
        friction_power=lambda_N * friction_power,
        euler_rates=[alpha_d, beta_d, gamma_d],
        energies={"E_kin": 0.5 * m * dot(v_S, v_S) + 0.5 * dot(omega, L), "E_pot": m * g * z_S},
        z_S=z_S,
        g_N1=r_OG[2] - r * sb,
    )


@dataclass(frozen=True)
class OdeModel:
    """One ODE formulation: its state variables and how to build its equations."""

    name: str
    paper_name: str
    orientation: tuple[str, ...]
    build: Callable[..., tuple[Trig, list, ContactDynamics, list]]  # (variables, slip_norm)

    @property
    def state_names(self) -> tuple[str, ...]:
        return state_names(self.orientation)

    def equations(self, slip_norm=None):
        """(variables, (trig, orientation rates, ContactDynamics, Euler angles))."""
        variables = hy.make_vars(*self.state_names)
        return variables, self.build(variables, slip_norm)


def _split(variables, n_orient):
    r_xy = variables[0:2]
    orient = variables[2:2 + n_orient]
    v_xy = variables[2 + n_orient:4 + n_orient]
    omega = variables[4 + n_orient:7 + n_orient]
    return r_xy, orient, v_xy, omega


def _build_euler(variables, slip_norm=None):
    r_xy, (alpha, beta, gamma), v_xy, omega = _split(variables, 3)
    trig = Trig(hy.sin(alpha), hy.cos(alpha), hy.sin(beta), hy.cos(beta), hy.sin(gamma), hy.cos(gamma))
    dyn = contact_dynamics(trig, r_xy, v_xy, omega, slip_norm)
    return trig, dyn.euler_rates, dyn, [alpha, beta, gamma]  # (3.8)


def _build_quaternion(variables, slip_norm=None):
    r_xy, p, v_xy, omega = _split(variables, 4)
    R = kin.rotation_entries_quaternion(*p)
    sb = hy.sqrt(R[0][2] * R[0][2] + R[1][2] * R[1][2])  # (2.9)
    # read off (3.2): R13 = sa sb, R23 = -ca sb, R31 = sb sg, R32 = sb cg, R33 = cb
    trig = Trig(R[0][2] / sb, -R[1][2] / sb, sb, R[2][2], R[2][0] / sb, R[2][1] / sb)
    dyn = contact_dynamics(trig, r_xy, v_xy, omega, slip_norm)
    angles = [hy.atan2(R[0][2], -R[1][2]), hy.acos(R[2][2]), hy.atan2(R[2][0], R[2][1])]  # inverse of (3.2)
    return trig, kin.quaternion_rate_entries(*p, *omega), dyn, angles  # (3.44)


EULER = OdeModel("ode-euler", "ODE Model 1", ORIENTATIONS["ode-euler"], _build_euler)
QUATERNION = OdeModel("ode-quaternion", "ODE Model 2", ORIENTATIONS["ode-quaternion"], _build_quaternion)


def system(model: OdeModel, slip_norm=None):
    """(variables, sys, fall, outputs) of ``model``: the heyoka state variables, the system
    [(variable, rhs)], the fall event expression and the outputs named in OUTPUT_NAMES
    (height of G and its rate, Euler angles and rates (3.8), z_S, g_N1, gamma_N1, lambda_N, slip,
    E_kin, E_pot, friction power).
    """
    variables, (trig, orient_rates, dyn, angles) = model.equations(slip_norm)
    rhs = [*dyn.v_G[:2], *orient_rates, *dyn.a_G[:2], *dyn.psi, dyn.friction_power]
    sys = list(zip(variables, rhs))
    # the disk has fallen when its tilt above the table, asin(sin beta), drops to fall_angle
    fall = trig.sb - hy.sin(P["fall_angle"])
    outputs = [dyn.r_OG[2], dyn.v_G[2], *angles, *dyn.euler_rates, dyn.z_S, dyn.g_N1, dyn.gamma_N, dyn.lambda_N,
               *dyn.slip, dyn.energies["E_kin"], dyn.energies["E_pot"], dyn.friction_power]
    return variables, sys, fall, outputs


MODELS = {m.name: m for m in (EULER, QUATERNION)}


@functools.lru_cache(maxsize=None)
def as_system(model: OdeModel) -> System:
    """``model`` as a :class:`~tippedisk_analysis.dynamics.System`: its state, the runtime parameters of
    PARAMETER_NAMES (default Tables 1-2, Sect. 6), the outputs that are not states as observables, and the
    terminal events ``fell`` (the tilt reaches fall_angle) and ``lift_off`` (lambda_N falls through 0)."""
    variables, sys, fall, outputs = system(model)
    observables = {name: out for name, out in zip(OUTPUT_NAMES, outputs) if name not in model.state_names}
    events = (Event("fell", fall), Event("lift_off", observables["lambda_N"]))
    return System(model.name, variables, [rhs for _v, rhs in sys], dict(zip(PARAMETER_NAMES, parameter_vector())),
                  state_names=model.state_names, observables=observables, events=events, units=PARAMETER_UNITS,
                  time_units="s",
                  description=f"{model.paper_name}: bilateral contact at C1, smooth Coulomb friction (2.29)")


def parameter_vector(setup: Setup | None = None, fall_angle: float = FALL_ANGLE,
                     slip_smoothing: float = SLIP_SMOOTHING) -> np.ndarray:
    """Runtime parameters hy.par[i] in the order of PARAMETER_NAMES (default: Tables 1-2, Sect. 6)."""
    setup = setup or Setup()
    d, f = setup.disk, setup.friction
    values = {"m": d.m, "e": d.e, "r": d.r, "A": d.A, "B": d.B, "C": d.C, "gravity": setup.gravity,
              "mu": f.mu, "eps": f.eps, "slip_smoothing": slip_smoothing, "fall_angle": fall_angle}
    return np.array([values[name] for name in PARAMETER_NAMES])


def initial_state_vector(model: OdeModel, setup: Setup, initial: InitialState) -> np.ndarray:
    """State vector of ``model``: closed contact at C1 without slip (6.2), W_friction = 0."""
    rest = kin.rest_contact_state(setup.disk.r, initial.euler, initial.euler_rates)
    if model is EULER:
        orientation = initial.euler
    else:
        orientation = kin.quaternion_from_rotation(kin.rotation_from_euler(*initial.euler))
    return np.array([initial.x, initial.y, *orientation, *rest["v_G"][:2], *rest["omega"], 0.0])
