"""The slow flow of the smooth model: rolling corrected to first order in the friction smoothing eps.

With smooth Coulomb friction (2.29) the contact force is lambda_T = -mu lambda_N gamma_T / (|gamma_T| + eps);
for the force a motion needs, the slip that produces it is (solving (2.29) for gamma_T)

    gamma_T = -eps lambda_T / (mu lambda_N - |lambda_T|),                                      (S1)

which exists only inside the friction cone, |lambda_T| < mu lambda_N. eps is the singular parameter: at
eps = 0 the slip vanishes and the motion is rolling (:mod:`.rolling`), the critical manifold; the slip
relaxes to (S1) at the rates -9.15/eps and -15.8/eps (docs/rolling.md), the fast modes. The slow manifold is
the graph gamma_T = eps h(x) + O(eps^2) over the rolling state x = (beta, gamma, omega), with h (S1) evaluated
at the rolling forces:

    h = -lambda_T^roll / (mu lambda_N^roll - |lambda_T^roll|).                                 (S2)

The slow flow is the rolling disk with that slip prescribed (``rolling_dynamics(..., slip=(s, s_dot))``):
v_G = s - Omega x r_GC1, and a_S gains s_dot, the inertial derivative of s = eps h,

    s_dot = eps dh/dx . f_roll(x) + w_G x s                                                     (S3)

(dh/dx . f_roll the rate of h's G-components along the rolling flow, w_G x s the turning of the frame G).
Everything is consistent to first order: the slip that the slow flow's own contact force would produce
by (2.29) differs from s by O(eps^2). The contact force then does work at the rate lambda_T . s (the material
point at C1 moves at s), so the slow flow loses energy at

    dE/dt = lambda_T . s = -eps |lambda_T|^2 / (mu lambda_N - |lambda_T|) + O(eps^2),       (S4)

the friction power of the smooth model on its slow manifold.

|lambda_T| is evaluated as sqrt(|lambda_T|^2 + delta^2) - delta (delta = FORCE_SMOOTHING, 1e-12 N), analytic
at the spins where lambda_T = 0 (as the smooth model's |gamma_T|, :mod:`.ode`); it changes h by a relative
1e-12 / (mu lambda_N) at most.

State: (beta, gamma, omega_x, omega_y, omega_z), the reduced rolling state (no position, no precession
angle: both cyclic). The velocity of G is an output (u_x, u_y: horizontal, in the frame turned by alpha, as
in :mod:`.reduced`), so that a state of the smooth reduced model can be measured against the manifold.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import heyoka as hy
import numpy as np

from ..dynamics import Event, System
from . import ode, rolling
from .ode import P, Trig, dot
from .variables import PARAMETER_UNITS

PARAMETER_NAMES = ("m", "e", "r", "A", "B", "C", "gravity", "mu", "eps", "fall_angle")
"""Runtime parameters: the rolling model's, with eps at the index it has in the ODE models (hy.par[8])."""
STATE_NAMES = rolling.REDUCED_STATE_NAMES
EULER_STATE_NAMES = ("beta", "gamma", "alpha_dot", "beta_dot", "gamma_dot")
EULER_STATE_UNITS = {"beta": "rad", "gamma": "rad", "alpha_dot": "rad s-1", "beta_dot": "rad s-1",
                     "gamma_dot": "rad s-1"}
FORCE_SMOOTHING = 1e-12  # N: |lambda_T| = sqrt(|lambda_T|^2 + delta^2) - delta
CONE_RESERVE = 0.05  # the flow ends where |lambda_T| reaches (1 - CONE_RESERVE) mu lambda_N: |h| = 19 there
OBSERVABLE_UNITS = {"E_tot": "J", "friction_power": "W", "slip": "m s-1", "lambda_N": "N", "cone_margin": "N",
                    "alpha_dot": "rad s-1", "z_S": "m", "u_x": "m s-1", "u_y": "m s-1"}


def manifold_slip(dyn: rolling.RollingDynamics, eps, *, mu=P["mu"], sqrt=hy.sqrt,
                  smoothing=FORCE_SMOOTHING) -> list:
    """s = eps h (S1, S2): the slip on the slow manifold (G-components) from the rolling forces ``dyn``."""
    lt = dyn.lambda_T_G
    norm = sqrt(dot(lt, lt) + smoothing**2) - smoothing
    margin = mu * dyn.lambda_N - norm
    return [-eps * lt[i] / margin for i in range(3)]


@dataclass(frozen=True)
class SlowFlow:
    rhs: list  # d/dt of the state (S1-S3): (beta, gamma, omega_x, omega_y, omega_z), or held_spin's
    rolling: rolling.RollingDynamics  # the rolling forces at the state (eps = 0)
    slow: rolling.RollingDynamics  # the slow flow's kinematics and forces, with the slip s
    slip: list  # s = eps h, G-components [m/s]


def slow_dynamics(variables, trig: Trig, *, pars=P, sqrt=hy.sqrt, diff=hy.diff,
                  smoothing=FORCE_SMOOTHING, hold_spin=False, euler_rates=False) -> SlowFlow:
    """The slow flow (S1-S3) at the reduced state ``variables`` with orientation ``trig``. heyoka's
    expressions by default; sympy symbols with sympy.sqrt and sympy.diff give the same in sympy.
    hold_spin: the held-spin model of :mod:`.held_spin`: ``variables`` are (beta, gamma, beta_dot, gamma_dot)
    and the spin alpha_dot = pars["spin"] is held by a torque about the vertical (rhs: their rates).
    euler_rates: the same free flow in the state EULER_STATE_NAMES (beta, gamma, alpha_dot, beta_dot, gamma_dot)
    instead of the body angular velocity (:func:`euler_system`)."""
    if hold_spin or euler_rates:
        spin, beta_d, gamma_d = (pars["spin"], *variables[2:]) if hold_spin else variables[2:]
        omega = trig.B_from_G([beta_d, spin * trig.sb, spin * trig.cb + gamma_d])
    else:
        _beta, _gamma, *omega = variables

    def rates(dyn: rolling.RollingDynamics) -> list:
        if not (hold_spin or euler_rates):
            return [dyn.euler_rates[1], dyn.euler_rates[2], *dyn.psi]
        # dW/dt = Psi_G + gamma_dot e_z x W with W = (beta_dot, alpha_dot sb, alpha_dot cb + gamma_dot)
        psi_G = trig.G_from_B(dyn.psi)
        spin_dd = 0.0 if hold_spin else (psi_G[1] + (gamma_d - spin * trig.cb) * beta_d) / trig.sb
        angles = [beta_d, gamma_d, psi_G[0] - gamma_d * spin * trig.sb,
                  psi_G[2] + spin * trig.sb * beta_d - spin_dd * trig.cb]
        return angles if hold_spin else [beta_d, gamma_d, spin_dd, *angles[2:]]

    roll = rolling.rolling_dynamics(trig, omega, hold_spin=hold_spin, pars=pars, sqrt=sqrt)
    f_roll = rates(roll)
    s = manifold_slip(roll, pars["eps"], mu=pars["mu"], sqrt=sqrt, smoothing=smoothing)
    W = trig.G_from_B(omega)
    w_G = [W[0], W[1], trig.cb * W[1] / trig.sb]  # the frame G (rolling.rolling_dynamics)
    turn = [w_G[1] * s[2] - w_G[2] * s[1], w_G[2] * s[0] - w_G[0] * s[2], w_G[0] * s[1] - w_G[1] * s[0]]
    s_dot = [sum(diff(s_i, x) * f for x, f in zip(variables, f_roll)) + turn[i] for i, s_i in enumerate(s)]
    slow = rolling.rolling_dynamics(trig, omega, slip=(s, s_dot), hold_spin=hold_spin, pars=pars, sqrt=sqrt)
    return SlowFlow(rates(slow), roll, slow, s)


@functools.lru_cache(maxsize=None)
def system() -> System:
    """The slow flow (S1-S3) as a :class:`~tippedisk_analysis.dynamics.System` (parameters PARAMETER_NAMES,
    default Tables 1-2 and eps = 0.1 m/s); observables E_tot (with the slip's kinetic energy),
    friction_power (S4), slip |s|, lambda_N, cone_margin, alpha_dot, z_S and the velocity of G (u_x, u_y);
    events fell, lift_off and cone (the rolling force within CONE_RESERVE of the cone: h (S2) grows without
    bound towards the cone, where the manifold ends)."""
    variables = hy.make_vars(*STATE_NAMES)
    beta, gamma, *omega = variables
    trig = Trig(0.0 * beta, 1.0 + 0.0 * beta, hy.sin(beta), hy.cos(beta), hy.sin(gamma), hy.cos(gamma))
    flow = slow_dynamics(variables, trig)
    roll, slow, s = flow.rolling, flow.slow, flow.slip
    energy = slow.energies["E_kin"] + slow.energies["E_pot"]
    observables = {"E_tot": energy, "friction_power": slow.friction_power, "slip": hy.sqrt(dot(s, s)),
                   "lambda_N": slow.lambda_N, "cone_margin": roll.cone_margin, "alpha_dot": slow.euler_rates[0],
                   "z_S": slow.z_S, "u_x": slow.v_G[0], "u_y": slow.v_G[1]}
    fall_angle = hy.par[PARAMETER_NAMES.index("fall_angle")]
    reach = (1.0 - CONE_RESERVE) * P["mu"] * roll.lambda_N
    cone = reach * reach - dot(roll.lambda_T_G, roll.lambda_T_G)  # squared: analytic at lambda_T = 0
    events = (Event("fell", trig.sb - hy.sin(fall_angle)), Event("lift_off", slow.lambda_N), Event("cone", cone))
    defaults = dict(zip(ode.PARAMETER_NAMES, ode.parameter_vector()))
    return System("tippedisk_slow_flow", variables, flow.rhs,
                  {name: defaults[name] for name in PARAMETER_NAMES}, state_names=STATE_NAMES,
                  state_scale=(1.0, 1.0, 40.0, 40.0, 40.0),
                  observables={k: (v, OBSERVABLE_UNITS[k]) for k, v in observables.items()}, events=events,
                  n_trivial=2,
                  units={**rolling.REDUCED_STATE_UNITS, **{k: PARAMETER_UNITS[k] for k in PARAMETER_NAMES}},
                  time_units="s", compact_mode=True,
                  description="the slow flow of the smooth tippedisk: rolling with the first-order slip eps h")


@functools.lru_cache(maxsize=None)
def euler_system(rolling_only: bool = False) -> System:
    """The slow flow (S1-S3) in the state EULER_STATE_NAMES (beta, gamma, alpha_dot, beta_dot, gamma_dot), the
    spin a state, so that a start can fix it (:mod:`tippedisk_analysis.analysis.free_nutation`); observables
    E_tot, friction_power (S4), z_S. rolling_only: the rolling disk (eps = 0 written into the expressions, as
    :func:`.held_spin.rolling_system`), reversible under (beta, gamma, alpha_dot, beta_dot, gamma_dot) ->
    (pi - beta, gamma, alpha_dot, beta_dot, -gamma_dot) and -> (beta, pi - gamma, alpha_dot, -beta_dot,
    gamma_dot)."""
    variables = hy.make_vars(*EULER_STATE_NAMES)
    beta, gamma = variables[:2]
    trig = Trig(0.0 * beta, 1.0 + 0.0 * beta, hy.sin(beta), hy.cos(beta), hy.sin(gamma), hy.cos(gamma))
    flow = slow_dynamics(variables, trig, pars={**P, "eps": 0.0} if rolling_only else P, euler_rates=True)
    slow = flow.slow
    observables = {"E_tot": slow.energies["E_kin"] + slow.energies["E_pot"], "friction_power": slow.friction_power,
                   "z_S": slow.z_S}
    defaults = dict(zip(ode.PARAMETER_NAMES, ode.parameter_vector()))
    name = "tippedisk_rolling_euler" if rolling_only else "tippedisk_slow_flow_euler"
    return System(name, variables, flow.rhs, {n: defaults[n] for n in PARAMETER_NAMES}, state_names=EULER_STATE_NAMES,
                  state_scale=(1.0, 1.0, 40.0, 10.0, 10.0),
                  observables={k: (v, OBSERVABLE_UNITS[k]) for k, v in observables.items()}, n_trivial=2,
                  units={**EULER_STATE_UNITS, **{k: PARAMETER_UNITS[k] for k in PARAMETER_NAMES}}, time_units="s",
                  compact_mode=True, strict_parameters=False,
                  description="the rolling tippedisk (eps = 0) in Euler rates" if rolling_only else
                  "the slow flow of the smooth tippedisk in Euler rates")


def smooth_state(states, pars=None) -> np.ndarray:
    """The points of the slow manifold over slow states (5,) or (5, N): states of the smooth reduced model
    (:mod:`.reduced`, (beta, gamma, u_x, u_y, omega)) with the velocity of G that the slip eps h gives."""
    x = np.asarray(states, dtype=float)
    o = system().observe(x, pars)
    return np.concatenate([x[:2], [o["u_x"], o["u_y"]], x[2:]])


def manifold_distance(smooth_states, pars=None) -> np.ndarray:
    """|u - U(x)| [m/s]: how far states of the smooth reduced model (7,) or (7, N) lie from the slow manifold
    (u the velocity of G, U(x) the manifold's at the same beta, gamma, omega)."""
    y = np.asarray(smooth_states, dtype=float)
    on = smooth_state(np.concatenate([y[:2], y[4:]]), pars)
    return np.hypot(y[2] - on[2], y[3] - on[3])
