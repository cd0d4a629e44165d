"""The event-driven model of set-valued Coulomb friction (``hybrid-euler``, ``h1``): rolling while the
contact force lies inside the friction cone, sliding on its boundary otherwise, switched by heyoka events.

Two smooth modes share the orientation, the angular velocity and the position of G:

* rolling (:mod:`tippedisk_analysis.models.rolling`): the contact point at rest; valid while
  |lambda_T| <= mu lambda_N. The event (mu lambda_N)^2 - |lambda_T|^2 = 0 (falling) starts sliding;
* sliding (:mod:`tippedisk_analysis.models.sliding`): friction -mu lambda_N t against the slip s t, the
  slip integrated as speed s and angle phi. The event s = 0 (falling) is a stick.

Switching rules (the transition problem of Pfeiffer and Glocker's event-driven scheme, for a point contact):

* slip onset: the slip starts in the direction t = -lambda_T / |lambda_T| of the rolling contact's
  tangential force when it reaches the cone, so that the contact force is continuous (sliding friction
  -mu lambda_N t equals the force rolling needed). It starts at the speed ``ONSET_SLIP`` = 1e-9 m/s, not 0:
  at s = 0 both the slip acceleration and t_perp . a_C vanish and the slip angle is not analytic there
  (it turns like log t as the slip aligns), so Taylor steps would shrink with s. Measured on the Table 3
  run: gamma moves by 1.4e-8 rad over 8 s per 1e-9 m/s of ONSET_SLIP, linearly (1e-10 m/s: 1.4e-9 rad and
  8x the steps), the energy by 1e-12 J;
* stick: rolling continues if its contact force lies inside the cone at the stick state, |lambda_T| <=
  mu lambda_N; otherwise the slip restarts at once by the onset rule (a reversal).

Both modes keep the bilateral contact at C1 (g_N1 = 0 by construction). lambda_N falling through 0 ends a run
with status ``lift_off`` (outside the model, as in ODE Models 1/2; a Moreau model follows it); the tilt
reaching ``fall_angle`` with ``fell``. More than ``max_switches`` mode changes end it with ``zeno`` (switches
accumulating: the model cannot continue).
"""

from __future__ import annotations

import copy
import functools
import math
from dataclasses import dataclass

import heyoka as hy
import numpy as np
import xarray as xr

from ..compilation import compiling
from ..defaults import FALL_ANGLE, SLIP_SMOOTHING, TAYLOR_TOL
from ..errors import ParameterError
from ..models import ode, rolling, sliding
from ..parameters import InitialState, Setup, to_dict
from ..results import describe, flat_parameters, make_attrs
from .taylor import output_grid

MODES = {"rolling": 0, "sliding": 1}
MAX_SWITCHES = 10_000
ONSET_SLIP = 1e-9  # [m/s] the slip speed a slip starts with (module docstring)
ROUND_OFF_TIME = 1e-12  # [s] (relative to t) a mode held no longer than this is no switch (round-off at s = 0)
N_ROLL, N_SLIDE = len(rolling.STATE_NAMES), len(sliding.STATE_NAMES)
ENDINGS = {-1: "fell", -2: "lift_off"}  # terminal events 0 and 1 of both modes


@dataclass(frozen=True)
class Compiled:
    rolling: object  # taylor_adaptive templates (copied per run)
    sliding: object
    rolling_outputs: object  # cfuncs: rolling.OUTPUT_NAMES; ode.OUTPUT_NAMES + (x_dot, y_dot)
    sliding_outputs: object


@functools.lru_cache(maxsize=None)
def compiled(tol: float) -> Compiled:
    neg = hy.event_direction.negative
    rv, rsys, rfall, rout, cone = rolling.system()
    sv, ssys, sfall, sout = sliding.system()
    pars = ode.parameter_vector()
    with compiling(f"the hybrid model's integrators (rolling and sliding, tol {tol:g})"):
        roll = hy.taylor_adaptive(rsys, np.zeros(N_ROLL), pars=pars, tol=tol, compact_mode=False, t_events=[
            hy.t_event(rfall, direction=neg), hy.t_event(rout[rolling.OUTPUT_NAMES.index("lambda_N")], direction=neg),
            hy.t_event(cone, direction=neg)])
        slide = hy.taylor_adaptive(ssys, np.zeros(N_SLIDE), pars=pars, tol=tol, compact_mode=False, t_events=[
            hy.t_event(sfall, direction=neg), hy.t_event(sout[ode.OUTPUT_NAMES.index("lambda_N")], direction=neg),
            hy.t_event(sv[sliding.STATE_NAMES.index("slip_speed")], direction=neg)])
        return Compiled(roll, slide, hy.cfunc(rout, rv), hy.cfunc(sout, sv))


def _outputs(cfunc, states: np.ndarray, pars: np.ndarray) -> np.ndarray:
    states = np.atleast_2d(states)
    return cfunc(np.ascontiguousarray(states.T), pars=np.repeat(pars[: cfunc.nparams, None], len(states), axis=1))


def _onset_angle(cm: Compiled, x_roll: np.ndarray, pars: np.ndarray) -> tuple[float, float]:
    """(cone margin, slip angle of the onset rule) of the rolling contact at ``x_roll``."""
    o = dict(zip(rolling.OUTPUT_NAMES, _outputs(cm.rolling_outputs, x_roll, pars)[:, 0]))
    return o["cone_margin"], math.atan2(-o["lambda_Ty"], -o["lambda_Tx"])


@dataclass
class Segment:
    mode: str
    time: np.ndarray
    states: np.ndarray  # in the mode's coordinates
    work: float  # W_friction at the segment's start (rolling holds it)


def integrate(setup: Setup, initial: InitialState, t_end: float, dt_output: float, tol: float, fall_angle: float,
              slip_smoothing: float, max_switches: int = MAX_SWITCHES):
    """The run on the output grid: (segments, switches [(time, new mode)], status, message, t_final)."""
    cm = compiled(tol)
    pars = ode.parameter_vector(setup, fall_angle, slip_smoothing)
    roll, slide = copy.copy(cm.rolling), copy.copy(cm.sliding)
    for ta in (roll, slide):
        ta.pars[:] = pars
    grid = output_grid(t_end, dt_output)
    x = rolling.initial_state_vector(initial)
    margin, phi = _onset_angle(cm, x, pars)
    mode, t, work = ("rolling", 0.0, 0.0) if margin >= 0 else ("sliding", 0.0, 0.0)
    state = x if mode == "rolling" else np.concatenate([x, [ONSET_SLIP, phi, 0.0]])
    segments, spans = [], [(0.0, mode)]  # the modes entered
    status, message = "completed", f"reached t_end = {t_end:g} s"
    n_events = 0
    while True:
        ta = roll if mode == "rolling" else slide
        ta.time, ta.state[:] = t, state
        ta.reset_cooldowns()
        ahead = grid[grid > t]
        res = ta.propagate_grid(np.concatenate([[t], ahead]))

        out = np.asarray(res[-1])[1:]
        seg_time = ahead[: len(out)]
        outcome = res[0]
        if outcome == hy.taylor_outcome.time_limit:
            segments.append(Segment(mode, seg_time, out, work))
            break
        event = int(outcome)
        t, state = float(ta.time), np.array(ta.state)
        if not np.all(np.isfinite(state)):
            status, message = "nonfinite", f"the state became non-finite at t = {t:.6g} s; try a smaller --tol"
            segments.append(Segment(mode, seg_time, out, work))
            break
        segments.append(Segment(mode, np.append(seg_time, t), np.vstack([out, state]), work))
        if event in ENDINGS:
            status = ENDINGS[event]
            message = (f"the disk fell (tilt down to {fall_angle:g} rad above the table) at t = {t:.6g} s"
                       if status == "fell" else f"lambda_N fell through 0 at t = {t:.6g} s: the disk lifts off, "
                       "outside the bilateral model (a Moreau model follows it)")
            break
        if event != -3:  # pragma: no cover - no other outcome is configured
            status, message = "failed", f"heyoka stopped with {outcome!r} at t = {t:.6g} s"
            break
        if n_events >= max_switches:
            status, message = "zeno", (f"more than {max_switches} mode switches by t = {t:.6g} s (switches "
                                       "accumulate); the event-driven model cannot continue")
            break
        if mode == "rolling":  # slip onset
            _margin, phi = _onset_angle(cm, state, pars)
            mode, state = "sliding", np.concatenate([state, [ONSET_SLIP, phi, work]])
        else:  # stick
            work = float(state[-1])
            x = state[:N_ROLL]
            margin, phi = _onset_angle(cm, x, pars)
            if margin >= 0:
                mode, state = "rolling", x
            else:
                state = np.concatenate([x, [ONSET_SLIP, phi, work]])
        spans.append((t, mode))
        n_events += 1
    return segments, _switches(spans), status, message, t


def _switches(spans: list) -> list:
    """[(time, mode)] from the modes entered [(time, mode)]: a mode held for no longer than ROUND_OFF_TIME
    (s = 0 at a slip onset crossed by round-off, then the onset again) is no switch."""
    kept = []
    for k, (t, mode) in enumerate(spans):
        t_next = spans[k + 1][0] if k + 1 < len(spans) else math.inf
        if t_next - t > ROUND_OFF_TIME * max(1.0, t) and (not kept or kept[-1][1] != mode):
            kept.append((t, mode))
    return kept


def run(setup: Setup, initial: InitialState, t_end: float, *, dt_output: float = 1e-3, tol: float = TAYLOR_TOL,
        fall_angle: float = FALL_ANGLE, slip_smoothing: float = SLIP_SMOOTHING,
        max_switches: int = MAX_SWITCHES) -> xr.Dataset:
    """Integrate the hybrid model and return the labelled dataset (schema of results.py, plus ``mode``,
    ``lambda_Tx``, ``lambda_Ty``, ``cone_margin`` along time and the switches along ``switch``)."""
    if not (isinstance(fall_angle, int | float) and 0 < fall_angle < math.pi / 2):
        raise ParameterError(f"fall_angle = {fall_angle!r} rad must lie in (0, pi/2) (sin beta = 0 is the "
                             f"Euler-angle singularity); give e.g. {FALL_ANGLE:g}")
    if not (isinstance(max_switches, int) and max_switches > 0):
        raise ParameterError(f"max_switches = {max_switches!r} must be a positive integer")
    segments, switches, status, message, t_final = integrate(setup, initial, t_end, dt_output, tol, fall_angle,
                                                             slip_smoothing, max_switches)
    pars = ode.parameter_vector(setup, fall_angle, slip_smoothing)
    cm = compiled(tol)
    columns: dict[str, list] = {}
    for seg in segments:
        for name, values in _segment_data(cm, seg, pars).items():
            columns.setdefault(name, []).append(values)
    data = {name: np.concatenate(parts) for name, parts in columns.items()}
    time = data.pop("time")
    for angle in ("alpha", "gamma"):
        data[angle] = np.unwrap(data[angle])
    data["E_tot"] = data["E_kin"] + data["E_pot"]
    mode = data.pop("mode").astype(np.int8)
    n_slide = sum(1 for _t, m in switches[1:] if m == "sliding")
    message += f"; {len(switches) - 1} mode switch(es), {n_slide} to sliding"
    config = {"model": "hybrid-euler", "setup": to_dict(setup), "initial": to_dict(initial), "t_end": t_end,
              "dt_output": dt_output, "integrator": {"name": "heyoka.taylor_adaptive", "heyoka_version": hy.__version__,
                                                     "tol": tol, "fall_angle": fall_angle,
                                                     "slip_smoothing": slip_smoothing, "max_switches": max_switches}}
    flags = {"flag_values": np.array(list(MODES.values()), np.int8), "flag_meanings": " ".join(MODES)}
    variables = {name: ("time", np.asarray(v, dtype=float)) for name, v in data.items()}
    variables["mode"] = ("time", mode, {"units": "1", "long_name": "contact mode", **flags})
    variables["switch_time"] = ("switch", np.array([s for s, _m in switches]),
                                {"units": "s", "long_name": "time of the mode switch (the first: the initial mode)"})
    variables["switch_mode"] = ("switch", np.array([MODES[m] for _s, m in switches], np.int8),
                                {"units": "1", "long_name": "mode from that time", **flags})
    extra = {"t_final": t_final, "n_switches": len(switches) - 1, "integrator": "heyoka.taylor_adaptive", "tol": tol,
             **flat_parameters(setup)}
    ds = xr.Dataset(variables, coords={"time": time},
                    attrs=make_attrs("simulation", config, status, message, model="hybrid-euler",
                                     paper_model="event-driven Models 1/2", **extra))
    ds["lambda_Tx"].attrs.update(units="N", long_name="tangential contact force at C1, x-component (I-frame)")
    ds["lambda_Ty"].attrs.update(units="N", long_name="tangential contact force at C1, y-component (I-frame)")
    ds["cone_margin"].attrs.update(units="N", long_name="mu lambda_N - |lambda_T| (>= 0: rolling is consistent; 0 "
                                                        "while sliding)")
    return describe(ds)


def _segment_data(cm: Compiled, seg: Segment, pars: np.ndarray) -> dict:
    """The common variables of a segment, from its mode's states and outputs."""
    n = len(seg.time)
    mu = pars[ode.PARAMETER_NAMES.index("mu")]
    if seg.mode == "rolling":
        o = dict(zip(rolling.OUTPUT_NAMES, _outputs(cm.rolling_outputs, seg.states, pars))) if n else {}
        zero = np.zeros(n)
        d = {name: seg.states[:, i] for i, name in enumerate(rolling.STATE_NAMES)} if n else {}
        d.update({k: o[k] for k in ("z", "z_dot", "x_dot", "y_dot", "alpha_dot", "beta_dot", "gamma_dot", "z_S",
                                    "g_N1", "lambda_N", "lambda_Tx", "lambda_Ty", "cone_margin", "E_kin", "E_pot")}
                 if n else {})
        d.update({"gamma_N1": zero, "slip_x": zero, "slip_y": zero, "P_friction": zero,
                  "W_friction": np.full(n, seg.work)})
    else:
        names = (*ode.OUTPUT_NAMES, "x_dot", "y_dot")
        o = dict(zip(names, _outputs(cm.sliding_outputs, seg.states, pars))) if n else {}
        d = {name: seg.states[:, i] for i, name in enumerate(sliding.STATE_NAMES)
             if name not in ("slip_speed", "slip_angle")} if n else {}
        d.update({k: o[k] for k in names if k not in ("alpha", "beta", "gamma")} if n else {})
        if n:
            phi = seg.states[:, sliding.STATE_NAMES.index("slip_angle")]
            d.update({"lambda_Tx": -mu * o["lambda_N"] * np.cos(phi), "lambda_Ty": -mu * o["lambda_N"] * np.sin(phi),
                      "cone_margin": np.zeros(n)})
    if not n:
        return {}
    d["time"] = seg.time
    d["mode"] = np.full(n, MODES[seg.mode])
    return d
