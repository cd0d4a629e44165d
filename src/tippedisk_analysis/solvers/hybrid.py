"""Runs of the event-driven model of set-valued Coulomb friction (``hybrid-euler``, ``h1``): its declaration
(modes, guards, the onset and stick rules) is :mod:`tippedisk_analysis.models.event_driven`; the integration
from event to event and the sections across modes are the generic ones (:mod:`tippedisk_analysis.dynamics.hybrid`).
This module turns a run into the package's simulation dataset.

lambda_N falling through 0 ends a run with status ``lift_off`` (outside the model, as in ODE Models 1/2; a
Moreau model follows it); the tilt reaching ``fall_angle`` with ``fell``. Mode switches that accumulate (their
intervals shrinking geometrically, or many within round-off of one instant) end it with ``zeno`` at the last
switch, the message giving the accumulation time; so do more than ``max_switches`` mode changes. A mode is
entered on a guard's zero (rolling entered on the cone) without skipping a crossing: :mod:`tippedisk_analysis.dynamics.zeno`.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from ..defaults import FALL_ANGLE, SLIP_SMOOTHING, TAYLOR_TOL
from ..dynamics.hybrid import HybridRun, simulate_hybrid
from ..errors import ParameterError
from ..models import event_driven, ode, rolling
from ..parameters import InitialState, Setup
from .taylor import output_grid, simulation_dataset

MODES = event_driven.MODES
MAX_SWITCHES = 10_000
ROUND_OFF_TIME = 1e-12  # [s] (relative to t) a mode held no longer than this is no switch (round-off at s = 0)
VARIABLE_ATTRS = {  # the variables of the hybrid model that the other models lack
    "lambda_Tx": {"units": "N", "long_name": "tangential contact force at C1, x-component (I-frame)"},
    "lambda_Ty": {"units": "N", "long_name": "tangential contact force at C1, y-component (I-frame)"},
    "cone_margin": {"units": "N", "long_name": "mu lambda_N - |lambda_T| (>= 0: rolling is consistent; 0 while "
                                               "sliding)"},
}
SECTION_QUANTITIES = tuple(dict.fromkeys((*rolling.STATE_NAMES, *event_driven.COMMON_OBSERVABLES)))
"""What a section of the hybrid model may cut: the quantities both modes have (a state or an observable)."""


def start(initial: InitialState, pars: np.ndarray) -> tuple[str, np.ndarray]:
    """(mode, state) a run starts in: rolling from rest at C1 if its contact force lies in the cone, else
    sliding by the onset rule."""
    hybrid = event_driven.hybrid_system()
    x = np.append(rolling.initial_state_vector(initial), 0.0)  # W_friction = 0
    if hybrid.modes["rolling"].observe(x, pars)["cone_margin"] >= 0:
        return "rolling", x
    _k, mode, state = hybrid.jump("rolling", "slip_onset", x, pars)
    return mode, state


def integrate(setup: Setup, initial: InitialState, t_end: float, dt_output: float | None, tol: float,
              fall_angle: float, slip_smoothing: float, max_switches: int = MAX_SWITCHES,
              section: dict | None = None) -> HybridRun:
    """The generic event-driven run of hybrid-euler (on the output grid, or with a section's crossings), its
    status and message in the model's words."""
    pars = ode.parameter_vector(setup, fall_angle, slip_smoothing)
    mode, x = start(initial, pars)
    grid = output_grid(t_end, dt_output) if dt_output else np.array([0.0, t_end])
    run = simulate_hybrid(event_driven.hybrid_system(), mode, x, t_end, pars=pars, grid=grid, tol=tol,
                          max_switches=max_switches, section=section)
    t = run.t_final
    if run.status == "completed":
        run.message = f"reached t_end = {t_end:g} s"
    elif run.status == "fell":
        run.message = f"the disk fell (tilt down to {fall_angle:g} rad above the table) at t = {t:.6g} s"
    elif run.status == "lift_off":
        run.message = (f"lambda_N fell through 0 at t = {t:.6g} s: the disk lifts off, outside the bilateral model "
                       "(a Moreau model follows it)")
    elif run.status == "zeno" and run.accumulation is None:
        run.message = (f"more than {max_switches} mode switches by t = {t:.6g} s (switches accumulate); the "
                       "event-driven model cannot continue")
    elif run.status == "nonfinite":
        run.message = (f"the state became non-finite after t = {t:.6g} s (extreme inputs, or try a smaller --tol)")
    return run


def mode_switches(run: HybridRun) -> list:
    """[(time, mode)] from the modes entered: a mode held for no longer than ROUND_OFF_TIME (s = 0 at a slip
    onset crossed by round-off, then the onset again) is no switch."""
    spans, kept = run.modes_entered, []
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
    run = integrate(setup, initial, t_end, dt_output, tol, fall_angle, slip_smoothing, max_switches)
    status, message, t_final = run.status, run.message, run.t_final
    pars = ode.parameter_vector(setup, fall_angle, slip_smoothing)
    columns: dict[str, list] = {}
    for seg in run.segments:
        for name, values in _segment_data(seg.mode, seg.time, seg.states, pars).items():
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
    mode = data.pop("mode").astype(np.int8)
    switches = mode_switches(run)
    n_slide = sum(1 for _t, m in switches[1:] if m == "sliding")
    message += (f"; started {switches[0][1]}, then {len(switches) - 1} mode switch(es) that held longer than "
                f"round-off, {n_slide} to sliding")
    flags = {"flag_values": np.array(list(MODES.values()), np.int8), "flag_meanings": " ".join(MODES)}
    variables = {
        "mode": ("time", mode, {"units": "1", "long_name": "contact mode", **flags}),
        "switch_time": ("switch", np.array([s for s, _m in switches]),
                        {"units": "s", "long_name": "time of the mode switch (the first: the initial mode)"}),
        "switch_mode": ("switch", np.array([MODES[m] for _s, m in switches], np.int8),
                        {"units": "1", "long_name": "mode from that time", **flags})}
    options = {"tol": tol, "fall_angle": fall_angle, "slip_smoothing": slip_smoothing, "max_switches": max_switches}
    ds = simulation_dataset("hybrid-euler", "event-driven Models 1/2", setup, initial, t_end, dt_output, options, time,
                            data, status, message, {"t_final": t_final, "n_switches": len(switches) - 1}, variables)
    for name, attrs in VARIABLE_ATTRS.items():
        ds[name].attrs.update(attrs)
    return ds


def section_crossings(setup: Setup, initial: InitialState, quantity: str, level: float, *, modulo: bool = False,
                      direction: str = "positive", t_transient: float = 0.0, t_end: float = 10.0,
                      tol: float = TAYLOR_TOL, fall_angle: float = FALL_ANGLE,
                      slip_smoothing: float = SLIP_SMOOTHING, max_switches: int = MAX_SWITCHES) -> dict:
    """The crossings of ``quantity`` = ``level`` by the hybrid run, located by events in whichever mode holds
    them: {"time", "mode", "data" (the common variables at each crossing), "status", "message", "t_final",
    "switches"}."""
    if quantity not in SECTION_QUANTITIES:
        raise ParameterError(f"section quantity {quantity!r} is not one of the hybrid model's; choose one of "
                             f"{', '.join(SECTION_QUANTITIES)}")
    if modulo and quantity not in rolling.STATE_NAMES[2:5]:
        raise ParameterError(f"a 'mod 2pi' section needs an angle (alpha, beta, gamma), not {quantity!r}")
    section = {"quantity": quantity, "level": float(level), "modulo": bool(modulo), "direction": direction,
               "transient": float(t_transient)}
    run = integrate(setup, initial, t_end, None, tol, fall_angle, slip_smoothing, max_switches, section=section)
    pars = ode.parameter_vector(setup, fall_angle, slip_smoothing)
    parts = [_segment_data(mode, times, states, pars) for mode, (times, states) in run.crossings.items()
             if len(times)]
    if not parts:  # no crossing: the columns, empty (their names from the initial state's)
        mode, x = start(initial, pars)
        with np.errstate(all="ignore"):
            parts = [{name: values[:0] for name, values in _segment_data(mode, np.zeros(1), x[None, :], pars).items()}]
    data = {name: np.concatenate([p[name] for p in parts]) for name in parts[0]}
    order = np.argsort(data["time"])
    data = {name: values[order] for name, values in data.items()}
    time, mode = data.pop("time"), data.pop("mode")
    return {"time": time, "mode": mode.astype(np.int8), "data": data, "status": run.status, "message": run.message,
            "t_final": run.t_final, "switches": mode_switches(run)}


def _segment_data(mode: str, time: np.ndarray, states: np.ndarray, pars: np.ndarray) -> dict:
    """The common variables of a mode's samples: the shared states and the common observables."""
    system = event_driven.hybrid_system().modes[mode]
    d = {name: states[:, i] for i, name in enumerate(system.state_names) if name not in ("slip_speed", "slip_angle")}
    d.update(system.observe(states.T, pars))
    d["time"] = time
    d["mode"] = np.full(len(time), MODES[mode])
    return d
