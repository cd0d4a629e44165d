"""Poincaré sections of a :class:`~tippedisk_analysis.dynamics.System`'s trajectories with heyoka events.

A section is ``quantity = level`` (a state or an observable of the system), crossed in a direction; with
``modulo`` the event is sin(q - level) and only crossings with cos(q - level) > 0 count (angles). The level is
a runtime parameter appended after the system's (one compiled integrator per quantity, direction and
tolerance serves every level). Crossings are located by heyoka's root finding on the step's Taylor
polynomials and the state there is the dense output at the event time, so the section holds to about the
integrator tolerance. The system's terminal events end the run with their name as its status.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import heyoka as hy
import numpy as np
import xarray as xr

from ..errors import ParameterError
from ..results import index_coordinate, make_attrs
from .system import System

DIRECTIONS = ("positive", "negative", "any")


class Recorder:
    """nt_event callback: the dense state at each accepted crossing after ``t_transient``. heyoka calls it
    at the end of the step that holds the crossing; the state at the crossing comes from the step's
    Taylor polynomials."""

    def __init__(self):
        self.t_transient, self.level, self.modulo = 0.0, 0.0, False
        self.q_index, self.q_func, self.pars = None, None, None  # the quantity: a state index, or a cfunc
        self.times: list[float] = []
        self.states: list[np.ndarray] = []

    def __call__(self, ta, time, d_sign):
        if time < self.t_transient:
            return
        ta.update_d_output(time)
        state = np.array(ta.d_output, copy=True)
        if self.modulo:
            if self.q_index is not None:
                q = state[self.q_index]
            else:
                q = float((self.q_func(state, pars=self.pars) if self.q_func.nparams else self.q_func(state))[0])
            if math.cos(q - self.level) <= 0.0:
                return
        self.times.append(float(time))
        self.states.append(state)


class FirstCrossing:
    """nt_event callback: the time of the first crossing (None: none yet)."""

    def __init__(self):
        self.time = None

    def __call__(self, ta, time, d_sign):
        if self.time is None:
            self.time = float(time)


@dataclass
class Crossings:
    times: np.ndarray
    states: np.ndarray  # (n_crossings, n)
    status: str
    message: str
    t_final: float
    n_steps: int = 0
    first: dict | None = None  # {watched name: time of its first crossing, or None}
    final: np.ndarray | None = None  # (n,) the state at t_final


def _quantity(system: System, name: str):
    if name in system.state_names:
        return system.variables[system.state_index(name)]
    if name in system.observables:
        return system.observables[name][0]
    raise ParameterError(f"section quantity {name!r} is neither a state nor an observable of {system.name}; choose "
                         f"one of {', '.join((*system.state_names, *system.observables))}")


def section_template(system: System, quantity: str, *, direction: str = "positive", modulo: bool = False,
                     tol: float = 1e-12, events=True, watch: dict | None = None):
    """The compiled integrator template of a section (the level is the runtime parameter after the system's):
    terminal ``events`` (True: all of the system's, or their names), the section's recorder and a
    :class:`FirstCrossing` per ``watch`` {name: (quantity, direction)} (non-terminal)."""
    if direction not in DIRECTIONS:
        raise ParameterError(f"direction {direction!r} unknown; give one of {', '.join(DIRECTIONS)}")
    q = _quantity(system, quantity)
    level = hy.par[len(system.parameter_names)]
    nt = [(hy.sin(q - level) if modulo else q - level, Recorder(), direction)]
    nt += [(_quantity(system, what), FirstCrossing(), way) for what, way in (watch or {}).values()]
    return system.taylor(tol, events=events, nt_events=tuple(nt))


def crossings(system: System, state, quantity: str, level: float = 0.0, *, pars=None, direction: str = "positive",
              modulo: bool = False, t_end: float = 100.0, transient: float = 0.0, max_crossings: int | None = None,
              tol: float = 1e-12, events=True, watch: dict | None = None) -> Crossings:
    """Integrate from ``state`` and collect the crossings of ``quantity`` = ``level`` (raw arrays); the run ends at
    ``t_end``, after ``max_crossings``, or at one of the terminal ``events`` (True: all the system's, or their
    names; the status is its name). ``watch`` {name: (quantity, direction)}: the first crossing of each (in
    ``Crossings.first``), without ending the run."""
    if not (math.isfinite(t_end) and t_end > 0 and math.isfinite(transient) and 0 <= transient < t_end):
        raise ParameterError(f"give t_end > 0 and 0 <= transient < t_end (got {t_end!r}, {transient!r})")
    if max_crossings is not None and (int(max_crossings) != max_crossings or max_crossings < 1):
        raise ParameterError(f"max_crossings = {max_crossings!r} must be a positive integer")
    watch = dict(watch or {})
    ta = copy.copy(section_template(system, quantity, direction=direction, modulo=modulo, tol=tol, events=events,
                                    watch=watch))
    pars = np.append(system.with_pars(pars), float(level))
    ta.pars[:] = pars[: len(ta.pars)]
    ta.time = 0.0
    ta.state[:] = np.asarray(state, dtype=float)
    ta.reset_cooldowns()
    rec, *watchers = (event.callback for event in ta.nt_events)
    rec.t_transient, rec.level, rec.modulo, rec.times, rec.states = float(transient), float(level), modulo, [], []
    if modulo and quantity in system.state_names:
        rec.q_index = system.state_index(quantity)
    elif modulo:
        rec.q_func = system.function(f"section {quantity}", [_quantity(system, quantity)])
        rec.pars = pars[: rec.q_func.nparams]
    stop = None if max_crossings is None else (lambda _ta: len(rec.times) < max_crossings)
    outcome, _h_min, _h_max, n_steps, *_ = ta.propagate_until(float(t_end), callback=stop)
    times, states = np.array(rec.times), np.array(rec.states).reshape(-1, system.n)
    if max_crossings is not None:
        times, states = times[:max_crossings], states[:max_crossings]
    n = len(times)
    ended = system.terminal_events(events)
    if outcome == hy.taylor_outcome.time_limit:
        status, message = "completed", f"reached t_end = {t_end:g} with {n} crossing(s)"
    elif outcome == hy.taylor_outcome.cb_stop:
        status, message = "completed", f"collected {n} crossing(s) by t = {ta.time:.6g}"
    elif (index := System.stopping_event(outcome, ended)) is not None:
        status = ended[index].name
        message = f"ended at t = {ta.time:.6g} ({status}) after {n} crossing(s)"
    else:
        keep = np.all(np.isfinite(states), axis=1)
        times, states = times[keep], states[keep]
        status, message = "nonfinite", f"the integration stopped ({outcome!r}) at t = {ta.time:.6g}; try a smaller tol"
    first = {name: w.time for name, w in zip(watch, watchers)}
    return Crossings(times, states, status, message, float(ta.time), int(n_steps), first,
                     np.array(ta.state[: system.n], copy=True))


def poincare_section(system: System, state, quantity: str, level: float = 0.0, *, pars=None,
                     direction: str = "positive", modulo: bool = False, t_end: float = 100.0,
                     transient: float = 0.0, max_crossings: int | None = None, tol: float = 1e-12) -> xr.Dataset:
    """The crossings of ``quantity`` = ``level`` along the trajectory from ``state`` as a dataset of kind
    ``poincare`` (dim ``crossing``: the time, every state and every observable at each crossing)."""
    pars_vector = system.with_pars(pars)
    cr = crossings(system, state, quantity, level, pars=pars_vector, direction=direction, modulo=modulo,
                   t_end=t_end, transient=transient, max_crossings=max_crossings, tol=tol)
    data = {"time": ("crossing", cr.times, {"units": system.time_units, "long_name": "time of the crossing"})}
    for i, name in enumerate(system.state_names):
        data[name] = ("crossing", cr.states[:, i], {"units": system.units_of(name), "long_name": f"state {name}"})
    if system.observables and len(cr.times):
        for name, values in system.observe(cr.states.T, pars_vector).items():
            data[name] = ("crossing", np.atleast_1d(values), {"units": system.units_of(name),
                                                              "long_name": f"observable {name}"})
    label = f"{quantity}{' mod 2pi' if modulo else ''}={level:.17g}"
    config = {"system": system.name, "system_key": system.key, "state": list(map(float, state)),
              "section": {"quantity": quantity, "level": float(level), "modulo": int(modulo), "direction": direction},
              "t_end": t_end, "transient": transient, "max_crossings": max_crossings, "tol": tol,
              "pars": list(map(float, pars_vector))}
    attrs = make_attrs("poincare", config, cr.status, f"{system.name}: {cr.message}", **system.attrs(pars_vector),
                       section=label, direction=direction, n_crossings=len(cr.times), t_final=cr.t_final)
    return xr.Dataset(data, coords={"crossing": index_coordinate("crossing", len(cr.times), "crossing index")},
                      attrs=attrs)
