"""The symmetry-reduced system of ODE Model 1: its right-hand side and exact derivatives.

The ODE Model 1 state (Sect. 4.1, :mod:`tippedisk_analysis.models.ode`) is
(x, y, alpha, beta, gamma, x_dot, y_dot, omega_x, omega_y, omega_z, W_friction); the height of G
and its rate follow from the contact, z = r sin(beta) and z_dot = r cos(beta) beta_dot.
Its right-hand side does not depend on x, y (horizontal translation), alpha (rotation of
the whole motion about e_z^I, (3.1)) nor W_friction (an integral of the friction power),
so a spinning disk with alpha_dot = Omega is a *relative* equilibrium: alpha grows and
v_G turns with the disk. The reduction used here:

* drop x, y, alpha (cyclic) and W_friction (a quadrature);
* express the horizontal velocity of G in the R-frame, I turned by alpha about e_z^I (3.1):
  u = (e_x^R . v_G, e_y^R . v_G), i.e. u_x = cos(alpha) x_dot + sin(alpha) y_dot,
  u_y = -sin(alpha) x_dot + cos(alpha) y_dot. Differentiating in the turning frame,
  u_x_dot = a_x^R + alpha_dot u_y and u_y_dot = a_y^R - alpha_dot u_x.

Reduced state (STATE_NAMES): (beta, gamma, u_x, u_y, omega_x, omega_y, omega_z), seven
first-order equations. The right-hand side is *not* a second copy of the physics: it is
:func:`tippedisk_analysis.models.ode.system` for ODE Model 1 with alpha = 0 substituted
(where the R-frame and the I-frame coincide, so a_G in I equals a_G in R), x_dot -> u_x,
y_dot -> u_y, plus the turning-frame terms above; beta_dot, gamma_dot and alpha_dot are the
inverse of (3.3) from the same module.

Its derivatives, batch evaluations and the maps between full and reduced states are
:mod:`tippedisk_analysis.analysis.reduced`.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import heyoka as hy

from ..dynamics import Event, System
from . import ode

STATE_NAMES = ("beta", "gamma", "u_x", "u_y", "omega_x", "omega_y", "omega_z")
STATE_UNITS = {"beta": "rad", "gamma": "rad", "u_x": "m s-1", "u_y": "m s-1", "omega_x": "rad s-1",
               "omega_y": "rad s-1", "omega_z": "rad s-1"}
STATE_SCALE = (1.0, 1.0, 0.1, 0.1, 10.0, 10.0, 10.0)  # typical magnitudes: Newton steps, continuation metric
N_STATE = len(STATE_NAMES)
SLIP_NORM_INDEX = len(ode.PARAMETER_NAMES)  # hy.par index of |gamma_T| in the split system (nonsmooth_split)


@dataclass(frozen=True)
class ReducedSystem:
    """Heyoka expressions of the reduced dynamics (module docstring)."""

    variables: list  # heyoka variables, STATE_NAMES order
    rhs: list  # d/dt of the variables
    alpha_dot: object  # spin rate about e_z^I (inverse of (3.3)) [rad/s]
    lambda_N: object  # normal force at C1 [N]
    slip: list  # gamma_T1 in the R-frame [m/s]
    z_S: object  # height of S [m]
    E_tot: object  # total energy E_kin + E_pot [J]


@functools.lru_cache(maxsize=None)
def reduced_system(split_slip_norm: bool = False) -> ReducedSystem:
    """Build the reduced right-hand side from ODE Model 1's expressions (alpha = 0 substituted).

    split_slip_norm: |gamma_T| in (2.29) replaced by the runtime parameter hy.par[SLIP_NORM_INDEX]
    (for :func:`nonsmooth_split`).
    """
    slip_norm = hy.par[SLIP_NORM_INDEX] if split_slip_norm else None
    full_vars, sys, _fall, outputs = ode.system(ode.EULER, slip_norm)
    names = ode.EULER.state_names
    rhs_full = dict(zip(names, (rhs for _var, rhs in sys)))
    out = dict(zip(ode.OUTPUT_NAMES, outputs))
    beta, gamma, u_x, u_y, w_x, w_y, w_z = variables = hy.make_vars(*STATE_NAMES)
    subs = {
        "x": hy.expression(0.0), "y": hy.expression(0.0), "alpha": hy.expression(0.0),  # cyclic
        "x_dot": u_x, "y_dot": u_y,  # alpha = 0: R-frame = I-frame
        "W_friction": hy.expression(0.0),
    }

    def reduce(expr):
        return hy.subs(expr, subs)

    alpha_dot = reduce(rhs_full["alpha"])
    rhs = [
        reduce(rhs_full["beta"]),
        reduce(rhs_full["gamma"]),
        reduce(rhs_full["x_dot"]) + alpha_dot * u_y,  # d/dt (e_x^R . v_G)
        reduce(rhs_full["y_dot"]) - alpha_dot * u_x,  # d/dt (e_y^R . v_G)
        reduce(rhs_full["omega_x"]),
        reduce(rhs_full["omega_y"]),
        reduce(rhs_full["omega_z"]),
    ]
    return ReducedSystem(list(variables), rhs, alpha_dot, reduce(out["lambda_N"]),
                         [reduce(out["slip_x"]), reduce(out["slip_y"])], reduce(out["z_S"]),
                         reduce(out["E_kin"] + out["E_pot"]))


@functools.lru_cache(maxsize=None)
def system(frictionless: bool = False) -> System:
    """The reduced tippedisk as a :class:`~tippedisk_analysis.dynamics.System`: 7 states, the 11 runtime
    parameters of ode.PARAMETER_NAMES (default: Tables 1-2, Sect. 6), observables z_S, E_tot, lambda_N,
    alpha_dot (the spin rate the families are parametrised by) and the slip magnitude, terminal events
    ``fell`` (tilt down to fall_angle) and ``lift_off`` (lambda_N through 0).

    With friction: two trivial Floquet multipliers, the flow direction and the spin family. ``frictionless``
    (for mu = 0): the disk is conservative; the first integrals E_tot and L_z (the vertical angular momentum
    about S: the contact force is vertical, so it has no moment about the vertical through S) are declared
    and the trivial multipliers are three (flow, energy, angular momentum)."""
    red = reduced_system()
    beta = red.variables[0]
    observables = {"z_S": (red.z_S, "m"), "E_tot": (red.E_tot, "J"), "lambda_N": (red.lambda_N, "N"),
                   "alpha_dot": (red.alpha_dot, "rad s-1"),
                   "slip": (hy.sqrt(red.slip[0] ** 2 + red.slip[1] ** 2), "m s-1")}
    events = (Event("fell", hy.sin(beta) - hy.sin(ode.P["fall_angle"])), Event("lift_off", red.lambda_N))
    integrals = {"E_tot": red.E_tot, "L_z": _vertical_angular_momentum(red.variables)} if frictionless else {}
    defaults = ode.parameter_vector()
    return System("tippedisk_reduced" + ("_frictionless" if frictionless else ""), red.variables, red.rhs,
                  dict(zip(ode.PARAMETER_NAMES, defaults)), state_names=STATE_NAMES, state_scale=STATE_SCALE,
                  observables=observables, integrals=integrals, events=events, n_trivial=3 if frictionless else 2,
                  units={**STATE_UNITS, **ode.PARAMETER_UNITS}, time_units="s", compact_mode=True,
                  description="reduced tippedisk, ODE Model 1 (" + ("frictionless: conservative" if frictionless
                              else "smooth Coulomb friction") + ", bilateral contact)")


def _vertical_angular_momentum(variables):
    """e_z^I . Theta_S omega: e_z^I in body components (sin g sin b, cos g sin b, cos b) ((3.1): G_from_I then
    B_from_G), Theta_S = diag(A, B - m e^2, C - m e^2) (about S)."""
    beta, gamma, _ux, _uy, w_x, w_y, w_z = variables
    m, e = ode.P["m"], ode.P["e"]
    sb = hy.sin(beta)
    return (ode.P["A"] * w_x * hy.sin(gamma) * sb + (ode.P["B"] - m * e * e) * w_y * hy.cos(gamma) * sb
            + (ode.P["C"] - m * e * e) * w_z * hy.cos(beta))
