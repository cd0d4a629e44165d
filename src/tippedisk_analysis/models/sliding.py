"""The sliding tippedisk with set-valued Coulomb friction, the slip integrated as speed and angle: the
sliding mode of the event-driven model (:mod:`tippedisk_analysis.solvers.hybrid`).

The bilateral contact at C1 and the Newton-Euler equations are those of ODE Model 1
(:func:`.ode.contact_dynamics`), with the friction force of the set-valued law while sliding,
F = lambda_N (e_z^I - mu t) (2.24), t = (cos phi, sin phi) the direction of the slip gamma_T = s t (3.27).
The slip speed s and angle phi are states in place of the velocity of G, which follows from them and the
angular velocity: v_G = s t - Omega x r_GC1 (its vertical component r cos(beta) beta_dot keeps g_N1 = 0).
With a_C the acceleration of the material point at C1, d/dt gamma_T = a_G + Psi x r_GC1 + Omega x (w_G x
r_GC1) (w_G: the angular velocity of the frame G, as in :mod:`.rolling`),

    s' = t . a_C,        phi' = (t_perp . a_C) s / (s^2 + delta^2),

delta = ``slip_smoothing`` (1e-12 m/s): phi' = (t_perp . a_C) / s to relative 1e-24 wherever s > 1e-12 m/s,
and analytic at s = 0, where a stick makes s cross zero transversally (s' = t . a_C < 0) and heyoka's event
locates it to round-off. The work of friction W' = -mu lambda_N s is integrated alongside.
"""

from __future__ import annotations

import heyoka as hy

from .ode import P, Trig, contact_dynamics, cross

STATE_NAMES = ("x", "y", "alpha", "beta", "gamma", "omega_x", "omega_y", "omega_z", "slip_speed", "slip_angle",
               "W_friction")


def system():
    """(variables, sys, fall, outputs) of the sliding mode: outputs as :data:`.ode.OUTPUT_NAMES` (the slip
    from its speed and angle) followed by the velocity of G (x_dot, y_dot)."""
    variables = hy.make_vars(*STATE_NAMES)
    x, y, alpha, beta, gamma, wx, wy, wz, s, phi, _work = variables
    omega = [wx, wy, wz]
    trig = Trig(hy.sin(alpha), hy.cos(alpha), hy.sin(beta), hy.cos(beta), hy.sin(gamma), hy.cos(gamma))
    t_I = [hy.cos(phi), hy.sin(phi)]
    r = P["r"]
    W = trig.G_from_B(omega)
    t_G = trig.G_from_I([t_I[0], t_I[1], 0.0])
    v_G = trig.I_from_G([s * t_G[0] - r * W[2], s * t_G[1], s * t_G[2] + r * W[0]])
    dyn = contact_dynamics(trig, [x, y], v_G[:2], omega, slip_direction=t_I)

    # the acceleration of the material point at C1 (I-frame): a_G + Psi x r_GC1 + Omega x (w_G x r_GC1)
    psi_G = trig.G_from_B(dyn.psi)
    alpha_d = W[1] / trig.sb
    w_G = [W[0], W[1], trig.cb * alpha_d]
    r_GC = [0.0, -r, 0.0]
    turn = [u + v for u, v in zip(cross(psi_G, r_GC), cross(W, cross(w_G, r_GC)))]
    a_C = [dyn.a_G[i] + c for i, c in enumerate(trig.I_from_G(turn))]
    along = t_I[0] * a_C[0] + t_I[1] * a_C[1]
    across = -t_I[1] * a_C[0] + t_I[0] * a_C[1]
    delta = P["slip_smoothing"]
    rhs = [*v_G[:2], *dyn.euler_rates, *dyn.psi, along, across * s / (s * s + delta * delta), dyn.friction_power]
    fall = trig.sb - hy.sin(P["fall_angle"])
    outputs = [dyn.r_OG[2], dyn.v_G[2], alpha, beta, gamma, *dyn.euler_rates, dyn.z_S, dyn.g_N1, dyn.gamma_N,
               dyn.lambda_N, s * t_I[0], s * t_I[1], dyn.energies["E_kin"], dyn.energies["E_pot"],
               dyn.friction_power, *v_G[:2]]
    return list(variables), list(zip(variables, rhs)), fall, outputs
