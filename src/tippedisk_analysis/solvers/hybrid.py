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
VARIABLE_ATTRS = {  # the variables of the hybrid model that the other models lack
    "lambda_Tx": {"units": "N", "long_name": "tangential contact force at C1, x-component (I-frame)"},
    "lambda_Ty": {"units": "N", "long_name": "tangential contact force at C1, y-component (I-frame)"},
    "cone_margin": {"units": "N", "long_name": "mu lambda_N - |lambda_T| (>= 0: rolling is consistent; 0 while "
                                               "sliding)"},
}
ENDINGS = {-1: "fell", -2: "lift_off"}  # terminal events 0 and 1 of both modes
LEVEL_INDEX = len(ode.PARAMETER_NAMES)  # hy.par index of a section's level


@dataclass(frozen=True)
class Compiled:
    rolling: object  # taylor_adaptive templates (copied per run)
    sliding: object
    rolling_outputs: object  # cfuncs: rolling.OUTPUT_NAMES; ode.OUTPUT_NAMES + (x_dot, y_dot)
    sliding_outputs: object


SLIDING_OUTPUTS = (*ode.OUTPUT_NAMES, "x_dot", "y_dot")
SECTION_QUANTITIES = tuple(dict.fromkeys((*rolling.STATE_NAMES, *rolling.OUTPUT_NAMES)))
"""What a section of the hybrid model may cut: the quantities both modes have (a state or an output)."""


def _mode_quantity(variables, names, outputs, output_names, quantity: str):
    return variables[names.index(quantity)] if quantity in names else outputs[output_names.index(quantity)]


@functools.lru_cache(maxsize=None)
def compiled(tol: float, section: tuple | None = None) -> Compiled:
    """The two modes' integrators; with ``section`` = (quantity, modulo, direction) both also record the
    crossings of quantity = hy.par[LEVEL_INDEX] (:class:`tippedisk_analysis.dynamics.poincare.Recorder`)."""
    from ..dynamics.poincare import Recorder

    neg = hy.event_direction.negative
    rv, rsys, rfall, rout, cone = rolling.system()
    sv, ssys, sfall, sout = sliding.system()
    pars = ode.parameter_vector()
    nt = {"rolling": [], "sliding": []}
    if section is not None:
        quantity, modulo, direction = section
        if quantity not in SECTION_QUANTITIES:
            raise ParameterError(f"section quantity {quantity!r} is not one of the hybrid model's; choose one of "
                                 f"{', '.join(SECTION_QUANTITIES)}")
        level = hy.par[LEVEL_INDEX]
        hy_dir = {"positive": hy.event_direction.positive, "negative": neg, "any": hy.event_direction.any}[direction]
        for mode, (v, names, out, out_names) in {"rolling": (rv, rolling.STATE_NAMES, rout, rolling.OUTPUT_NAMES),
                                                 "sliding": (sv, sliding.STATE_NAMES, sout, SLIDING_OUTPUTS)}.items():
            q = _mode_quantity(v, names, out, out_names, quantity)
            nt[mode] = [hy.nt_event(hy.sin(q - level) if modulo else q - level, Recorder(), direction=hy_dir)]
        pars = np.append(pars, 0.0)
    with compiling(f"the hybrid model's integrators (rolling and sliding, tol {tol:g}"
                   + (f", section {section[0]})" if section else ")")):
        roll = hy.taylor_adaptive(rsys, np.zeros(N_ROLL), pars=pars, tol=tol, compact_mode=False, t_events=[
            hy.t_event(rfall, direction=neg), hy.t_event(rout[rolling.OUTPUT_NAMES.index("lambda_N")], direction=neg),
            hy.t_event(cone, direction=neg)], nt_events=nt["rolling"])
        slide = hy.taylor_adaptive(ssys, np.zeros(N_SLIDE), pars=pars, tol=tol, compact_mode=False, t_events=[
            hy.t_event(sfall, direction=neg), hy.t_event(sout[ode.OUTPUT_NAMES.index("lambda_N")], direction=neg),
            hy.t_event(sv[sliding.STATE_NAMES.index("slip_speed")], direction=neg)], nt_events=nt["sliding"])
        return Compiled(roll, slide, hy.cfunc(rout, rv), hy.cfunc(sout, sv))


def _outputs(cfunc, states: np.ndarray, pars: np.ndarray) -> np.ndarray:
    states = np.atleast_2d(states)
    return cfunc(np.ascontiguousarray(states.T), pars=np.repeat(pars[: cfunc.nparams, None], len(states), axis=1))


def _onset_angle(cm: Compiled, x_roll: np.ndarray, pars: np.ndarray) -> tuple[float, float]:
    """(cone margin, slip angle of the onset rule) of the rolling contact at ``x_roll``."""
    o = dict(zip(rolling.OUTPUT_NAMES, _outputs(cm.rolling_outputs, x_roll, pars)[:, 0]))
    return o["cone_margin"], math.atan2(-o["lambda_Ty"], -o["lambda_Tx"])


@dataclass(frozen=True)
class SectionEvent:
    """A Poincaré section recorded by both modes' integrators: quantity (mod 2 pi if modulo) = level, crossed
    in direction, after t_transient [s]."""

    quantity: str
    level: float
    modulo: bool = False
    direction: str = "positive"
    t_transient: float = 0.0

    @property
    def compiled_key(self) -> tuple:
        return (self.quantity, self.modulo, self.direction)  # the level is a runtime parameter


@dataclass
class Segment:
    mode: str
    time: np.ndarray
    states: np.ndarray  # in the mode's coordinates
    work: float  # W_friction at the segment's start (rolling holds it)


def integrate(setup: Setup, initial: InitialState, t_end: float, dt_output: float, tol: float, fall_angle: float,
              slip_smoothing: float, max_switches: int = MAX_SWITCHES, section: SectionEvent | None = None):
    """The run on the output grid: (segments, switches [(time, new mode)], status, message, t_final,
    {mode: integrator}); with a ``section`` the integrators' recorders hold its crossings."""
    cm = compiled(tol, None if section is None else section.compiled_key)
    pars = ode.parameter_vector(setup, fall_angle, slip_smoothing)
    roll, slide = copy.copy(cm.rolling), copy.copy(cm.sliding)
    for ta in (roll, slide):
        if section is None:
            ta.pars[:] = pars
        else:
            ta.pars[:] = np.append(pars, section.level)
            rec = ta.nt_events[0].callback
            rec.t_transient, rec.level, rec.modulo = section.t_transient, section.level, section.modulo
            rec.times, rec.states = [], []
            if section.modulo:  # an angle: the same index in both modes
                rec.q_index = rolling.STATE_NAMES.index(section.quantity)
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
        times = np.concatenate([[t], grid[grid > t]])
        res = ta.propagate_grid(times)
        first = 0 if not segments else 1  # the initial state is the run's first sample; later ones end a segment
        out = np.asarray(res[-1])[first:]
        seg_time = times[first:first + len(out)]
        outcome = res[0]
        if outcome == hy.taylor_outcome.time_limit:
            segments.append(Segment(mode, seg_time, out, work))
            break
        event = int(outcome)
        start, t, state = state, float(ta.time), np.array(ta.state)
        if not (np.all(np.isfinite(state)) and math.isfinite(t)):
            last = seg_time[-1] if len(seg_time) else times[0]
            status, message = "nonfinite", (f"the state became non-finite after t = {last:.6g} s (extreme inputs, "
                                            "or try a smaller --tol)")
            if not segments and not len(out):  # at the first step: the initial state is the run's one sample
                seg_time, out = times[:1], np.asarray(start)[None, :]
            segments.append(Segment(mode, seg_time, out, work))
            t = last
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
    return segments, _switches(spans), status, message, t, {"rolling": roll, "sliding": slide}


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
    segments, switches, status, message, t_final, _ = integrate(setup, initial, t_end, dt_output, tol, fall_angle,
                                                             slip_smoothing, max_switches)
    pars = ode.parameter_vector(setup, fall_angle, slip_smoothing)
    cm = compiled(tol)
    columns: dict[str, list] = {}
    for seg in segments:
        for name, values in _segment_data(cm, seg, pars).items():
            columns.setdefault(name, []).append(values)
    data = {name: np.concatenate(parts) for name, parts in columns.items()}
    finite = np.all([np.isfinite(v) for v in data.values()], axis=0)
    if not finite.all():  # outputs that overflow (extreme inputs): the dataset ends at the last finite sample
        keep = int(np.argmin(finite))
        data = {name: values[:keep] for name, values in data.items()}
        t_final = float(data["time"][-1]) if keep else 0.0
        status, message = "nonfinite", (f"the outputs became non-finite after t = {t_final:.6g} s (extreme inputs, "
                                        "or try a smaller --tol); the dataset ends there")
    time = data.pop("time")
    for angle in ("alpha", "gamma"):
        data[angle] = np.unwrap(data[angle])
    data["E_tot"] = data["E_kin"] + data["E_pot"]
    mode = data.pop("mode").astype(np.int8)
    n_slide = sum(1 for _t, m in switches[1:] if m == "sliding")
    message += (f"; started {switches[0][1]}, then {len(switches) - 1} mode switch(es) that held longer than "
                f"round-off, {n_slide} to sliding")
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
    for name, attrs in VARIABLE_ATTRS.items():
        ds[name].attrs.update(attrs)
    return describe(ds)


def section_crossings(setup: Setup, initial: InitialState, quantity: str, level: float, *, modulo: bool = False,
                      direction: str = "positive", t_transient: float = 0.0, t_end: float = 10.0,
                      tol: float = TAYLOR_TOL, fall_angle: float = FALL_ANGLE,
                      slip_smoothing: float = SLIP_SMOOTHING, max_switches: int = MAX_SWITCHES) -> dict:
    """The crossings of ``quantity`` = ``level`` by the hybrid run, located by events in whichever mode holds
    them: {"time", "mode", "data" (the common variables at each crossing), "status", "message", "t_final",
    "switches"}."""
    if modulo and quantity not in rolling.STATE_NAMES[2:5]:
        raise ParameterError(f"a 'mod 2pi' section needs an angle (alpha, beta, gamma), not {quantity!r}")
    section = SectionEvent(quantity, float(level), bool(modulo), direction, float(t_transient))
    _seg, switches, status, message, t_final, integrators = integrate(
        setup, initial, t_end, t_end, tol, fall_angle, slip_smoothing, max_switches, section=section)
    cm = compiled(tol, section.compiled_key)
    pars = ode.parameter_vector(setup, fall_angle, slip_smoothing)
    parts = []
    for mode, ta in integrators.items():
        rec = ta.nt_events[0].callback
        if rec.times:
            seg = Segment(mode, np.array(rec.times), np.array(rec.states), math.nan)
            parts.append(_segment_data(cm, seg, pars))
    if not parts:  # no crossing: the columns, empty (their names from the initial state's)
        first = Segment("rolling", np.zeros(1), rolling.initial_state_vector(initial)[None, :], 0.0)
        with np.errstate(all="ignore"):
            parts = [{name: values[:0] for name, values in _segment_data(cm, first, pars).items()}]
    data = {name: np.concatenate([p[name] for p in parts]) for name in parts[0]}
    order = np.argsort(data["time"])
    data = {name: values[order] for name, values in data.items()}
    time, mode = data.pop("time"), data.pop("mode")
    data.pop("W_friction", None)  # the work is not integrated through the sliding recorder's states alone
    return {"time": time, "mode": mode.astype(np.int8), "data": data, "status": status, "message": message,
            "t_final": t_final, "switches": switches}


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
