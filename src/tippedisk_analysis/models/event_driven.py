"""The event-driven model of set-valued Coulomb friction (``hybrid-euler``, ``h1``) declared as a
:class:`~tippedisk_analysis.dynamics.hybrid.HybridSystem`: rolling while the contact force lies inside the
friction cone, sliding on its boundary otherwise.

Two smooth modes share the orientation, the angular velocity, the position of G and the work of friction:

* ``rolling`` (:mod:`.rolling`): the contact point at rest; valid while |lambda_T| <= mu lambda_N. The guard
  ``slip_onset``, (mu lambda_N)^2 - |lambda_T|^2 falling through 0, starts sliding;
* ``sliding`` (:mod:`.sliding`): friction -mu lambda_N t against the slip s t, the slip integrated as speed s and
  angle phi. The guard ``stick``, s falling through 0, ends it.

The jumps (the transition problem of Pfeiffer and Glocker's event-driven scheme, for a point contact):

* slip onset: the slip starts in the direction t = -lambda_T / |lambda_T| of the rolling contact's tangential
  force, so that the contact force is continuous (sliding friction -mu lambda_N t equals the force rolling
  needed). It starts at the speed ``ONSET_SLIP`` = 1e-9 m/s, not 0: at s = 0 both the slip acceleration and
  t_perp . a_C vanish and the slip angle is not analytic there (it turns like log t as the slip aligns), so
  Taylor steps would shrink with s. Measured on the Table 3 run: gamma moves by 1.4e-8 rad over 8 s per 1e-9 m/s
  of ONSET_SLIP, linearly (1e-10 m/s: 1.4e-9 rad and 8x the steps), the energy by 1e-12 J;
* stick: rolling continues if its contact force lies inside the cone at the stick state, cone_margin =
  mu lambda_N - |lambda_T| >= 0; otherwise the slip restarts at once by the onset rule (a reversal).

Both modes keep the bilateral contact at C1 (g_N1 = 0 by construction); their terminal events ``fell`` (the
tilt reaches fall_angle) and ``lift_off`` (lambda_N falls through 0) end a run, as in ODE Models 1/2.
"""

from __future__ import annotations

import functools

import heyoka as hy

from . import ode, rolling, sliding
from .variables import OUTPUT_NAMES, PARAMETER_NAMES, PARAMETER_UNITS

ONSET_SLIP = 1e-9  # [m/s] the slip speed a slip starts with (module docstring)
MODES = {"rolling": 0, "sliding": 1}  # the flag values of a dataset's mode
COMMON_OBSERVABLES = ("z", "z_dot", "x_dot", "y_dot", "alpha_dot", "beta_dot", "gamma_dot", "z_S", "g_N1", "gamma_N1",
                      "lambda_N", "lambda_Tx", "lambda_Ty", "cone_margin", "slip_x", "slip_y", "E_kin", "E_pot",
                      "P_friction")
"""The observables both modes declare (zero where a mode has none: no slip while rolling, the cone margin 0 while
sliding)."""


def _system(name, variables, rhs, observables, events, description):
    from ..dynamics import System

    return System(name, variables, rhs, dict(zip(PARAMETER_NAMES, ode.parameter_vector())),
                  observables=observables, events=events, units=PARAMETER_UNITS, time_units="s",
                  description=description, strict_parameters=False)


@functools.lru_cache(maxsize=None)
def modes() -> dict:
    """{"rolling": System, "sliding": System} over the parameters of the ODE models (:data:`PARAMETER_NAMES`)."""
    from ..dynamics import Event

    rv, rsys, rfall, rout, _cone = rolling.system()
    work = hy.make_vars("W_friction")
    zero = 0.0 * rv[3]
    o = dict(zip(rolling.OUTPUT_NAMES, rout))
    roll_obs = {**{k: o[k] for k in COMMON_OBSERVABLES if k in o},
                **{k: zero for k in ("gamma_N1", "slip_x", "slip_y", "P_friction")}}
    roll = _system("hybrid-euler.rolling", [*rv, work], [f for _v, f in rsys] + [zero],
                   {k: roll_obs[k] for k in COMMON_OBSERVABLES},
                   (Event("fell", rfall), Event("lift_off", o["lambda_N"])),
                   "the tippedisk rolling without slip at C1 (the work of friction held)")
    sv, ssys, sfall, sout = sliding.system()
    s = dict(zip((*OUTPUT_NAMES, "x_dot", "y_dot"), sout))
    mu, phi = ode.P["mu"], sv[sliding.STATE_NAMES.index("slip_angle")]
    s.update(lambda_Tx=-mu * s["lambda_N"] * hy.cos(phi), lambda_Ty=-mu * s["lambda_N"] * hy.sin(phi),
             cone_margin=0.0 * s["lambda_N"])
    slide = _system("hybrid-euler.sliding", sv, [f for _v, f in ssys], {k: s[k] for k in COMMON_OBSERVABLES},
                    (Event("fell", sfall), Event("lift_off", s["lambda_N"])),
                    "the tippedisk sliding with set-valued Coulomb friction at C1 (2.24)")
    return {"rolling": roll, "sliding": slide}


def onset_reset() -> dict:
    """The sliding states a slip starts with, as expressions of the states both modes share (from rolling, or
    from sliding at a reversal): speed ONSET_SLIP along -lambda_T of the rolling contact force there."""
    o = dict(zip(rolling.OUTPUT_NAMES, rolling.system()[3]))
    return {"slip_speed": ONSET_SLIP, "slip_angle": hy.atan2(-o["lambda_Ty"], -o["lambda_Tx"])}


@functools.lru_cache(maxsize=None)
def hybrid_system():
    """hybrid-euler as a HybridSystem: the modes of :func:`modes`, the guards slip_onset and stick."""
    from ..dynamics import Guard, HybridSystem, Jump

    m = modes()
    _rv, _rsys, _rfall, rout, cone = rolling.system()
    margin = dict(zip(rolling.OUTPUT_NAMES, rout))["cone_margin"]
    slip_speed = m["sliding"].variables[sliding.STATE_NAMES.index("slip_speed")]
    onset = onset_reset()
    guards = [Guard("slip_onset", "rolling", cone, Jump("sliding", onset)),
              Guard("stick", "sliding", slip_speed, (Jump("rolling", when=margin), Jump("sliding", onset)))]
    return HybridSystem("hybrid-euler", m, guards,
                        description="event-driven Models 1/2: rolling and sliding with set-valued Coulomb friction")
