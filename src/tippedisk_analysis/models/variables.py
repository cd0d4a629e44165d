"""Names of the ODE models' states, outputs and runtime parameters (Sect. 4.1), without heyoka.

The command line reads them to describe its options; :mod:`.ode` builds the equations in this order.
"""

from __future__ import annotations

PARAMETER_NAMES = ("m", "e", "r", "A", "B", "C", "gravity", "mu", "eps", "slip_smoothing", "fall_angle")
"""Runtime parameters hy.par[i] of the ODE models, in index order: one compiled integrator serves every value."""

PARAMETER_UNITS = {"m": "kg", "e": "m", "r": "m", "A": "kg m2", "B": "kg m2", "C": "kg m2", "gravity": "m s-2",
                   "mu": "1", "eps": "m s-1", "slip_smoothing": "m s-1", "fall_angle": "rad"}
"""UDUNITS units of the runtime parameters (Tables 1-2, Sect. 4.1)."""

ORIENTATIONS = {"ode-euler": ("alpha", "beta", "gamma"), "ode-quaternion": ("p0", "p1", "p2", "p3")}
"""Orientation coordinates of each ODE model: Euler angles (3.1) or the quaternion (3.40)."""

OUTPUT_NAMES = ("z", "z_dot", "alpha", "beta", "gamma", "alpha_dot", "beta_dot", "gamma_dot", "z_S", "g_N1",
                "gamma_N1", "lambda_N", "slip_x", "slip_y", "E_kin", "E_pot", "P_friction")
"""Quantities evaluated from the state: the height of G and its rate (the contact fixes them), Euler angles
and rates (3.8), z_S, the gap and normal velocity at C1, lambda_N, the slip (3.27), energies, friction power."""


def state_names(orientation: tuple[str, ...]) -> tuple[str, ...]:
    """The state: horizontal position of G, orientation, horizontal velocity of G (I-frame), body angular
    velocity (3.43) and the work done by friction."""
    return ("x", "y", *orientation, "x_dot", "y_dot", "omega_x", "omega_y", "omega_z", "W_friction")


def quantities(model_name: str = "ode-euler") -> tuple[str, ...]:
    """Every named quantity of a model's run: its states, then the outputs that are not states."""
    return tuple(dict.fromkeys((*state_names(ORIENTATIONS[model_name]), *OUTPUT_NAMES)))

FINAL_STATE_VARIABLES = {
    # name: (dtype, units, long_name): the state at the end of each run of an outcome or attractor map
    "E_tot_final": (float, "J", "total energy at t_final"),
    "E_kin_final": (float, "J", "kinetic energy at t_final"),
    "beta_final": (float, "rad", "Euler angle beta at t_final"),
    "gamma_final": (float, "rad", "Euler angle gamma at t_final (unwrapped)"),
    "alpha_dot_final": (float, "rad s-1", "alpha_dot at t_final"),
    "z_S_final": (float, "m", "height of S at t_final"),
}
"""Per-run columns of the outcome and attractor maps: the state where the run was decided."""
