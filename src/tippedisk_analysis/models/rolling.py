"""The rolling tippedisk: the contact point C1 at rest (no slip, free pivoting about the normal), a smooth
nonholonomic ODE derived from the kinematics of Sect. 2 as ODE Models 1/2 are.

In the floating frame G of Sect. 2.1 (e_x^G horizontal, e_z^G = e_z^B; r_GC1 = -r e_y^G (2.10),
e_z^I = (0, sin beta, cos beta)), with Omega the angular velocity and w_G = Omega - gamma_dot e_z^B the
angular velocity of the frame G (so d/dt e_y^G = w_G x e_y^G):

* rolling: the material point at C1 is at rest, v_G + Omega x r_GC1 = 0 (2.13), so
  v_G = -Omega x r_GC1 = r (-Omega_z, 0, Omega_x); its e_z^I component r cos(beta) beta_dot keeps the gap
  g_N1 = z - r sin(beta) = 0 (2.12): the bilateral contact holds by construction;
* on acceleration level a_G = -Psi x r_GC1 - Omega x (w_G x r_GC1), hence a_S = Psi x d + b with
  d = r_C1S and b = Omega x (Omega x r_GS) - Omega x (w_G x r_GC1);
* Newton m a_S = F - m g e_z^I gives the contact force F = m (Psi x d + b + g e_z^I), and Euler's equation
  about S, Theta_S Psi + Omega x Theta_S Omega = r_SC1 x F, becomes Euler's equation about the contact point:
  [Theta_S + m (|d|^2 I - d d^T)] Psi = -Omega x Theta_S Omega - m d x (b + g e_z^I).
  d has no e_z^G component, so the matrix is block diagonal (2 x 2 and 1 x 1): one division each.

The contact force splits into lambda_N = F . e_z^I and the tangential (friction) force
lambda_T = F - lambda_N e_z^I that rolling needs; rolling is consistent with Coulomb's law while
|lambda_T| <= mu lambda_N (``cone_margin`` = mu lambda_N - |lambda_T| >= 0) and lambda_N > 0. The contact
force does no work (its point is at rest), so the energy is conserved.

State: horizontal position of G, Euler angles (3.1), body angular velocity (3.43); everything else follows.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import heyoka as hy
import numpy as np

from .. import kinematics as kin
from ..defaults import FALL_ANGLE
from ..dynamics import Event, System
from ..parameters import InitialState
from . import ode
from .ode import P, Trig, cross, dot
from .variables import PARAMETER_UNITS

STATE_NAMES = ("x", "y", "alpha", "beta", "gamma", "omega_x", "omega_y", "omega_z")
OUTPUT_NAMES = ("z", "z_dot", "x_dot", "y_dot", "alpha_dot", "beta_dot", "gamma_dot", "z_S", "g_N1", "lambda_N",
                "lambda_Tx", "lambda_Ty", "cone_margin", "E_kin", "E_pot")
"""Evaluated from the state: height of G and its rate, horizontal velocity of G, Euler rates (3.8), z_S, the
gap at C1, the contact force (normal, tangential x/y in the I-frame), mu lambda_N - |lambda_T|, energies."""


@dataclass(frozen=True)
class RollingDynamics:
    v_G: list  # velocity of G, I-frame [m/s]
    psi: list  # angular acceleration, B-frame [rad/s^2]
    euler_rates: list  # alpha_dot, beta_dot, gamma_dot [rad/s]
    lambda_N: object  # normal contact force [N]
    lambda_T: list  # tangential contact force, I-frame x, y [N]
    lambda_T_G: list  # the same, G-frame components [N]
    cone_margin: object  # mu lambda_N - |lambda_T| [N]
    friction_power: object  # lambda_T . s, the power of the contact force [W] (0 when rolling)
    holding_torque: object  # the torque about the vertical that holds alpha_dot (hold_spin) [N m], else 0
    energies: dict  # E_kin, E_pot [J]
    z_S: object
    g_N1: object


def rolling_dynamics(trig: Trig, omega, slip=None, *, hold_spin=False, pars=P, sqrt=hy.sqrt) -> RollingDynamics:
    """The rolling disk's accelerations and contact force at orientation ``trig``, body angular velocity
    ``omega`` (module docstring). Vectors in G-components unless named _B/_I.

    slip: (s, s_dot), a prescribed horizontal velocity s of the material point at C1 and its time derivative
    (both G-components; s_dot the derivative of the vector s in the inertial frame), for the slow flow of
    :mod:`.slow_flow`: then v_G = s - Omega x r_GC1 and a_S = Psi x d + b + s_dot. Default: rolling, s = 0.
    hold_spin: a torque tau e_z^I about the vertical joins Euler's equation, the one that keeps the spin
    alpha_dot constant (alpha_ddot = 0; the reduced model of :mod:`.held_spin`); its power is tau e_z^I . Omega.
    pars, sqrt: the parameters by name and the square root, heyoka's by default; sympy symbols and sympy.sqrt
    give the same expressions in sympy (:mod:`tippedisk_analysis.analysis.critical_spin`)."""
    m, e, r, g = pars["m"], pars["e"], pars["r"], pars["gravity"]
    A, B, C = pars["A"], pars["B"] - m * e * e, pars["C"] - m * e * e  # Theta_S in the body frame
    sb, cb, sg, cg = trig.sb, trig.cb, trig.sg, trig.cg
    ez_I = [0.0, sb, cb]
    W = trig.G_from_B(omega)
    alpha_d = W[1] / sb
    gamma_d = omega[2] - cb * alpha_d
    w_G = [W[0], W[1], cb * alpha_d]  # the frame G: Omega - gamma_dot e_z^B
    r_GC = [0.0, -r, 0.0]
    r_GS = [e * cg, e * sg, 0.0]
    d = [e * cg, e * sg + r, 0.0]  # r_C1S = r_GS - r_GC1
    v_G = [-r * W[2], 0.0, r * W[0]]  # -Omega x r_GC1
    if slip is not None:
        v_G = [u + v for u, v in zip(v_G, slip[0])]

    # Theta_S in G-components: the body frame turned by gamma about e_z^G
    t00, t01, t11 = A * cg * cg + B * sg * sg, (A - B) * cg * sg, A * sg * sg + B * cg * cg
    L = [t00 * W[0] + t01 * W[1], t01 * W[0] + t11 * W[1], C * W[2]]
    b = [u - v for u, v in zip(cross(W, cross(W, r_GS)), cross(W, cross(w_G, r_GC)))]
    if slip is not None:
        b = [u + v for u, v in zip(b, slip[1])]
    load = [b[i] + g * ez_I[i] for i in range(3)]
    rhs = [-u - m * v for u, v in zip(cross(W, L), cross(d, load))]
    # M = Theta_S + m (|d|^2 I - d d^T): block diagonal
    m00, m01, m11 = t00 + m * d[1] * d[1], t01 - m * d[0] * d[1], t11 + m * d[0] * d[0]
    det = m00 * m11 - m01 * m01
    m22 = C + m * (d[0] * d[0] + d[1] * d[1])
    psi_G = [(m11 * rhs[0] - m01 * rhs[1]) / det, (m00 * rhs[1] - m01 * rhs[0]) / det, rhs[2] / m22]
    torque = 0.0 * sb
    if hold_spin:
        # alpha_ddot sb = Psi_G,y + (gamma_dot - alpha_dot cos beta) beta_dot (d/dt of W_y = alpha_dot sb, with
        # dW/dt = Psi_G + gamma_dot e_z x W); the torque adds tau M^-1 e_z^I to Psi_G: choose tau for alpha_ddot = 0
        response = [-m01 * sb / det, m00 * sb / det, cb / m22]
        torque = -(psi_G[1] + (gamma_d - alpha_d * cb) * W[0]) / response[1]
        psi_G = [p + torque * u for p, u in zip(psi_G, response)]
    F = [m * (u + v) for u, v in zip(cross(psi_G, d), load)]
    lambda_N = dot(F, ez_I)
    lambda_T_G = [F[i] - lambda_N * ez_I[i] for i in range(3)]
    lambda_T = trig.I_from_G(lambda_T_G)[:2]
    v_S = [v_G[i] + c for i, c in enumerate(cross(W, r_GS))]
    z_S = r * sb + e * sb * sg
    L_B = [A * omega[0], B * omega[1], C * omega[2]]
    return RollingDynamics(
        v_G=trig.I_from_G(v_G),
        psi=trig.B_from_G(psi_G),
        euler_rates=[alpha_d, W[0], gamma_d],
        lambda_N=lambda_N,
        lambda_T=lambda_T,
        lambda_T_G=lambda_T_G,
        cone_margin=pars["mu"] * lambda_N - sqrt(dot(lambda_T_G, lambda_T_G)),
        friction_power=0.0 * sb if slip is None else dot(lambda_T_G, slip[0]),
        holding_torque=torque,
        energies={"E_kin": 0.5 * m * dot(v_S, v_S) + 0.5 * dot(omega, L_B), "E_pot": m * g * z_S},
        z_S=z_S,
        g_N1=0.0 * sb,  # r sin(beta) - r sin(beta): closed by construction
    )


def system(fall_angle=P["fall_angle"]):
    """(variables, sys, fall, outputs, cone) of the rolling model: the heyoka state variables, the system
    [(variable, rhs)], the fall event expression (the tilt reaching ``fall_angle``), the outputs of
    OUTPUT_NAMES and the squared cone condition (mu lambda_N)^2 - |lambda_T|^2 (analytic where |lambda_T| = 0:
    the event of slip onset)."""
    variables = hy.make_vars(*STATE_NAMES)
    _x, _y, alpha, beta, gamma, *omega = variables
    trig = Trig(hy.sin(alpha), hy.cos(alpha), hy.sin(beta), hy.cos(beta), hy.sin(gamma), hy.cos(gamma))
    dyn = rolling_dynamics(trig, omega)
    rhs = [*dyn.v_G[:2], *dyn.euler_rates, *dyn.psi]
    fall = trig.sb - hy.sin(fall_angle)
    r = P["r"]
    outputs = [r * trig.sb, dyn.v_G[2], *dyn.v_G[:2], *dyn.euler_rates, dyn.z_S, dyn.g_N1, dyn.lambda_N,
               *dyn.lambda_T, dyn.cone_margin, dyn.energies["E_kin"], dyn.energies["E_pot"]]
    cone = (P["mu"] * dyn.lambda_N) ** 2 - dyn.lambda_T[0] ** 2 - dyn.lambda_T[1] ** 2
    return list(variables), list(zip(variables, rhs)), fall, outputs, cone


PARAMETER_NAMES = ("m", "e", "r", "A", "B", "C", "gravity", "mu", "fall_angle")
REDUCED_STATE_NAMES = ("beta", "gamma", "omega_x", "omega_y", "omega_z")
REDUCED_STATE_UNITS = {"beta": "rad", "gamma": "rad", "omega_x": "rad s-1", "omega_y": "rad s-1", "omega_z": "rad s-1"}
"""Runtime parameters of the rolling System: those of the ODE models it uses (no eps, no slip smoothing)."""


def parameter_vector(setup=None, fall_angle: float = FALL_ANGLE) -> np.ndarray:
    """hy.par[i] of the rolling System in the order of PARAMETER_NAMES (default: Tables 1-2, Sect. 6)."""
    full = dict(zip(ode.PARAMETER_NAMES, ode.parameter_vector(setup, fall_angle)))
    return np.array([full[name] for name in PARAMETER_NAMES])


@functools.lru_cache(maxsize=None)
def as_system():
    """The rolling model as a :class:`~tippedisk_analysis.dynamics.System` (parameters PARAMETER_NAMES;
    observables: the outputs; terminal events: fell, lift_off, and slip (the cone is reached))."""
    variables, sys, fall, outputs, cone = system(fall_angle=hy.par[PARAMETER_NAMES.index("fall_angle")])
    observables = {name: out for name, out in zip(OUTPUT_NAMES, outputs) if name != "g_N1"}
    events = (Event("fell", fall), Event("lift_off", observables["lambda_N"]), Event("slip", cone))
    return System("rolling-euler", variables, [f for _v, f in sys], dict(zip(PARAMETER_NAMES, parameter_vector())),
                  state_names=STATE_NAMES, observables=observables, events=events,
                  units={k: PARAMETER_UNITS[k] for k in PARAMETER_NAMES}, time_units="s",
                  description="the tippedisk rolling without slip at C1 (nonholonomic)")


@functools.lru_cache(maxsize=None)
def reduced_system():
    """The rolling disk without its position and precession angle (symmetry about the vertical): (beta, gamma,
    omega) as a :class:`~tippedisk_analysis.dynamics.System` with the energy
    E_tot as a first integral (two trivial Floquet multipliers: the flow and the energy family), observables
    E_tot, lambda_N, cone_margin (``mu lambda_N - |lambda_T|``), alpha_dot, z_S, and the events of the rolling model
    (fell, lift_off, slip: the cone reached)."""
    beta, gamma, wx, wy, wz = hy.make_vars(*REDUCED_STATE_NAMES)
    fall_angle = hy.par[PARAMETER_NAMES.index("fall_angle")]
    # alpha does not enter: the frame at alpha = 0 (only the I-frame components of v_G and lambda_T need it)
    trig = Trig(0.0 * beta, 1.0 + 0.0 * beta, hy.sin(beta), hy.cos(beta), hy.sin(gamma), hy.cos(gamma))
    dyn = rolling_dynamics(trig, [wx, wy, wz])
    energy = dyn.energies["E_kin"] + dyn.energies["E_pot"]
    observables = {"E_tot": (energy, "J"), "lambda_N": (dyn.lambda_N, "N"), "cone_margin": (dyn.cone_margin, "N"),
                   "alpha_dot": (dyn.euler_rates[0], "rad s-1"), "z_S": (dyn.z_S, "m")}
    cone = (P["mu"] * dyn.lambda_N) ** 2 - dyn.lambda_T[0] ** 2 - dyn.lambda_T[1] ** 2
    events = (Event("fell", hy.sin(beta) - hy.sin(fall_angle)), Event("lift_off", dyn.lambda_N), Event("slip", cone))
    rhs = [dyn.euler_rates[1], dyn.euler_rates[2], *dyn.psi]
    return System("tippedisk_rolling_reduced", [beta, gamma, wx, wy, wz], rhs,
                  dict(zip(PARAMETER_NAMES, parameter_vector())), state_names=REDUCED_STATE_NAMES,
                  state_scale=(1.0, 1.0, 40.0, 40.0, 40.0), observables=observables, integrals={"E_tot": energy},
                  events=events, n_trivial=3, units={**{k: REDUCED_STATE_UNITS[k] for k in REDUCED_STATE_NAMES},
                                                     **{k: PARAMETER_UNITS[k] for k in PARAMETER_NAMES}},
                  time_units="s", compact_mode=True,
                  description="the rolling tippedisk without its position and precession angle")


def initial_state_vector(initial: InitialState) -> np.ndarray:
    """The state of an initial orientation and Euler rates (the contact at rest: rolling from the start)."""
    omega = kin.omega_from_euler_rates(initial.euler[1], initial.euler[2], initial.euler_rates)
    return np.array([initial.x, initial.y, *initial.euler, *omega])
