"""The held-spin model: the slow flow (:mod:`.slow_flow`) with the spin about the vertical held constant.

A reduced model of the inversion with one assumption: the spin alpha_dot about the vertical is held at the
value ``spin`` (a parameter) by a torque tau e_z^I about the vertical (``rolling_dynamics(..., hold_spin=True)``,
tau chosen so that alpha_ddot = 0). Everything else is the slow flow's: rolling with the first-order slip
eps h (S1-S3). The free disk's spin is not constant: it falls from the initial spin to about omega_c while S
rises (33.7 -> 29.9 rad/s in the Table 3 run at the threshold); here the torque supplies or takes that energy.
What the assumption buys: the spin becomes a parameter, the spins of the disk become isolated equilibria
(rather than a family), and their Hopf points, periodic orbits and global bifurcations in the spin are those
of an ordinary four-dimensional ODE.

State (beta, gamma, beta_dot, gamma_dot): the tilt of the disk and the angle that turns it in its own plane,
and their rates (precession angle and position cyclic, alpha_dot = spin). The equilibria are the inverted
spin (beta = gamma = pi/2: S above G) and the lower spin (gamma = -pi/2: S below G), at every spin. At the
inverted spin the linearisation on (beta, gamma, beta_dot, gamma_dot) is the slow flow's K0 + eps K1 on
(beta, gamma, omega_y, omega_z) (:mod:`tippedisk_analysis.analysis.critical_spin`) in other coordinates: the
holding torque enters only the equation of omega_x at first order (M^-1 e_z^I is along e_x^B there), so the
closed form's omega_c and precession onset are this model's Hopf points to first order in eps.

Power balance: dE/dt = lambda_T . s + tau e_z^I . Omega (friction (S4) and the holding torque), the check
``tests/test_held_spin.py`` makes along runs.
"""

from __future__ import annotations

import functools
import math

import heyoka as hy
import numpy as np

from ..dynamics import Event, System
from ..errors import ParameterError
from . import ode, slow_flow
from .ode import P, Trig, dot
from .variables import PARAMETER_UNITS

PARAMETER_NAMES = (*slow_flow.PARAMETER_NAMES[:-1], "spin", "fall_angle")
"""The slow flow's parameters and the held spin alpha_dot [rad/s] (hy.par[9])."""
STATE_NAMES = ("beta", "gamma", "beta_dot", "gamma_dot")
STATE_UNITS = {"beta": "rad", "gamma": "rad", "beta_dot": "rad s-1", "gamma_dot": "rad s-1"}
OBSERVABLE_UNITS = {"E_tot": "J", "friction_power": "W", "holding_torque": "N m", "holding_power": "W",
                    "lambda_N": "N", "cone_margin": "N", "z_S": "m", "slip": "m s-1"}
DEFAULT_SPIN = 30.0  # rad/s
SPINS = {"inverted": 1.0, "lower": -1.0}  # sin(gamma) of the two spins: S above / below G


def spin_state(branch: str) -> np.ndarray:
    """The equilibrium ``branch`` ("inverted": S above G; "lower": S below G) in STATE_NAMES."""
    if branch not in SPINS:
        raise ParameterError(f"unknown spin {branch!r}; choose one of {', '.join(SPINS)}")
    return np.array([0.5 * math.pi, SPINS[branch] * 0.5 * math.pi, 0.0, 0.0])


def _pars() -> dict:
    """hy.par of this model by name: ode's P for the slow flow's (the same indices 0-8), spin at index 9."""
    return {**P, "spin": hy.par[PARAMETER_NAMES.index("spin")],
            "fall_angle": hy.par[PARAMETER_NAMES.index("fall_angle")]}


def _flow(eps=None):
    """(variables, trig, pars, the held slow flow) with eps the runtime parameter, or the number ``eps``."""
    pars = _pars() if eps is None else {**_pars(), "eps": eps}
    variables = hy.make_vars(*STATE_NAMES)
    beta, gamma, _beta_d, _gamma_d = variables
    trig = Trig(0.0 * beta, 1.0 + 0.0 * beta, hy.sin(beta), hy.cos(beta), hy.sin(gamma), hy.cos(gamma))
    return variables, trig, pars, slow_flow.slow_dynamics(variables, trig, pars=pars, hold_spin=True)


def _defaults() -> dict:
    defaults = {**dict(zip(ode.PARAMETER_NAMES, ode.parameter_vector())), "spin": DEFAULT_SPIN}
    return {name: defaults[name] for name in PARAMETER_NAMES}


@functools.lru_cache(maxsize=None)
def system() -> System:
    """The held-spin model as a :class:`~tippedisk_analysis.dynamics.System` (parameters PARAMETER_NAMES,
    default Tables 1-2, eps = 0.1 m/s, spin DEFAULT_SPIN); observables E_tot, friction_power (S4),
    holding_torque and holding_power (tau e_z^I . Omega), lambda_N, cone_margin, z_S, slip |s|; events fell,
    lift_off and cone (as :func:`.slow_flow.system`)."""
    variables, trig, pars, flow = _flow()
    _beta, _gamma, _beta_d, gamma_d = variables
    roll, slow, s = flow.rolling, flow.slow, flow.slip
    omega_vertical = pars["spin"] + gamma_d * trig.cb  # Omega . e_z^I
    observables = {"E_tot": slow.energies["E_kin"] + slow.energies["E_pot"], "friction_power": slow.friction_power,
                   "holding_torque": slow.holding_torque, "holding_power": slow.holding_torque * omega_vertical,
                   "lambda_N": slow.lambda_N, "cone_margin": roll.cone_margin, "z_S": slow.z_S,
                   "slip": hy.sqrt(dot(s, s))}
    reach = (1.0 - slow_flow.CONE_RESERVE) * P["mu"] * roll.lambda_N
    events = (Event("fell", trig.sb - hy.sin(pars["fall_angle"])), Event("lift_off", slow.lambda_N),
              Event("cone", reach * reach - dot(roll.lambda_T_G, roll.lambda_T_G)))
    return System("tippedisk_held_spin", variables, flow.rhs, _defaults(),
                  state_names=STATE_NAMES, state_scale=(1.0, 1.0, 10.0, 10.0),
                  observables={k: (v, OBSERVABLE_UNITS[k]) for k, v in observables.items()}, events=events,
                  units=_units(), time_units="s", compact_mode=True,
                  description="the slow flow of the smooth tippedisk with its spin about the vertical held fixed")


@functools.lru_cache(maxsize=None)
def rolling_system() -> System:
    """The held-spin model at eps = 0: the disk rolls (no slip) with its spin held, the unperturbed system of
    :mod:`tippedisk_analysis.analysis.nutation_cycles`. The same parameters as :func:`system` (eps and mu unused),
    so one vector serves both. Written with eps = 0 in the expressions, not as a parameter: heyoka's Taylor
    coefficients of eps * h overflow near lambda_T = 0 (h is only C^1 there) and 0 * inf is not 0. Reversible:
    (beta, gamma, beta_dot, gamma_dot) -> (pi - beta, gamma, beta_dot, -gamma_dot) and
    -> (beta, pi - gamma, -beta_dot, gamma_dot) reverse time (friction breaks both)."""
    variables, _trig, _pars_, flow = _flow(0.0)
    observables = {"E_tot": flow.slow.energies["E_kin"] + flow.slow.energies["E_pot"], "z_S": flow.slow.z_S}
    return System("tippedisk_held_rolling", variables, flow.rhs, _defaults(), state_names=STATE_NAMES,
                  state_scale=(1.0, 1.0, 10.0, 10.0), observables={k: (v, OBSERVABLE_UNITS[k])
                                                                   for k, v in observables.items()},
                  units=_units(), time_units="s", compact_mode=True, strict_parameters=False,
                  description="the rolling tippedisk with its spin about the vertical held fixed (eps = 0)")


def _units() -> dict:
    return {**STATE_UNITS, **{k: PARAMETER_UNITS[k] for k in PARAMETER_NAMES if k != "spin"}, "spin": "rad s-1"}
