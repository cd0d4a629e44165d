"""Hybrid (event-driven) systems: smooth modes, guards that end them, and jumps between them.

A :class:`HybridSystem` has modes, each a :class:`~.system.System` over its own states (all modes share the
runtime parameters, by name and order). A :class:`Guard` of a mode is an expression of the mode's states: the
mode ends where it crosses zero in the guard's direction (heyoka locates the crossing to round-off on the step's
Taylor polynomials). The guard then takes the first of its :class:`Jump` s whose condition holds (``when`` >= 0,
or no condition) into the jump's target mode. The target's states are set by ``reset`` {target state name:
expression of the source states}; a target state that ``reset`` does not name keeps the source state of the
same name, so an empty reset is the identity.

:func:`simulate_hybrid` integrates event to event, entering each mode past its guards' zeros without skipping a
crossing (:mod:`.zeno`); the modes' own terminal events (a System's ``events``) end a run with their name as
status, switch times that accumulate (or more than ``max_switches`` jumps) with ``zeno``, a guard none of whose
jumps applies with ``no_jump``, Taylor coefficients that overflow with ``nonfinite``. Sections across modes (:func:`simulate_hybrid` with ``section``) are recorded by every mode's
integrator. Periodic orbits by multi-segment shooting with saltation matrices: :mod:`.hybrid_orbits`;
Filippov sliding from the two sides of a switching surface: :mod:`.filippov`.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field

import heyoka as hy
import numpy as np

from ..errors import ParameterError
from .poincare import Recorder
from .system import DIRECTIONS, Event, System
from .zeno import ZENO_TAIL, Departures, accumulation

MAX_SWITCHES = 10_000


@dataclass(frozen=True)
class Jump:
    """Into mode ``target`` with its states ``reset`` {name: expression of the source states} (unnamed states
    keep the source state of their name); taken if ``when`` (an expression of the source states) is >= 0 at
    the guard, or always without ``when``."""

    target: str
    reset: dict = field(default_factory=dict)
    when: object = None


@dataclass(frozen=True)
class Guard:
    """Mode ``mode`` ends where ``expression`` (of its states) crosses zero in ``direction``; the first of
    ``jumps`` whose condition holds is taken."""

    name: str
    mode: str
    expression: object
    jumps: tuple
    direction: str = "negative"

    def __post_init__(self):
        jumps = (self.jumps,) if isinstance(self.jumps, Jump) else tuple(self.jumps)
        object.__setattr__(self, "jumps", jumps)
        if not jumps or not all(isinstance(j, Jump) for j in jumps):
            raise ParameterError(f"guard {self.name!r}: give one Jump or a sequence of Jumps")
        if self.direction not in DIRECTIONS:
            raise ParameterError(f"guard {self.name!r}: direction {self.direction!r}; give one of "
                                 f"{', '.join(DIRECTIONS)}")


class HybridSystem:
    """Modes {name: System} and guards (:class:`Guard`); checked once, compiled on demand."""

    def __init__(self, name: str, modes: dict, guards, description: str = ""):
        self.name, self.description = name, description
        self.modes = dict(modes)
        self.guards = tuple(guards)
        if not self.modes:
            raise ParameterError(f"hybrid system {name!r} needs at least one mode")
        first = next(iter(self.modes.values()))
        self.parameter_names, self.pars = first.parameter_names, first.pars.copy()
        for mode, system in self.modes.items():
            if system.parameter_names != self.parameter_names:
                raise ParameterError(f"hybrid system {name!r}: mode {mode!r} has the parameters "
                                     f"{', '.join(system.parameter_names) or 'none'}, not "
                                     f"{', '.join(self.parameter_names) or 'none'}; every mode takes the same ones")
        seen = set()
        for g in self.guards:
            if g.mode not in self.modes:
                raise ParameterError(f"guard {g.name!r}: no mode {g.mode!r}; the modes are {', '.join(self.modes)}")
            if (g.mode, g.name) in seen or g.name in {e.name for e in self.modes[g.mode].events}:
                raise ParameterError(f"guard {g.name!r} of mode {g.mode!r}: the name is taken; give each guard of a "
                                     "mode its own name")
            seen.add((g.mode, g.name))
            for j in g.jumps:
                self._check_jump(g, j)
        self._systems: dict = {}
        self._jumps: dict = {}

    def _check_jump(self, g: Guard, j: Jump) -> None:
        if j.target not in self.modes:
            raise ParameterError(f"guard {g.name!r}: no target mode {j.target!r}; the modes are "
                                 f"{', '.join(self.modes)}")
        source, target = self.modes[g.mode], self.modes[j.target]
        unknown = [k for k in j.reset if k not in target.state_names]
        if unknown:
            raise ParameterError(f"guard {g.name!r}: mode {j.target!r} has no state {unknown[0]!r} to reset")
        missing = [k for k in target.state_names if k not in j.reset and k not in source.state_names]
        if missing:
            raise ParameterError(f"guard {g.name!r} into {j.target!r}: give the state {missing[0]!r} in reset (mode "
                                 f"{g.mode!r} has no state of that name)")

    # -- compiled pieces
    def mode_guards(self, mode: str) -> tuple:
        return tuple(g for g in self.guards if g.mode == mode)

    def system(self, mode: str) -> System:
        """The mode's System with its guards appended to its terminal events (after its own)."""
        if mode not in self.modes:
            raise ParameterError(f"{self.name} has no mode {mode!r}; choose one of {', '.join(self.modes)}")
        if mode not in self._systems:
            base = self.modes[mode]
            self._systems[mode] = base.with_events(f"{self.name}.{mode}", [
                Event(g.name, g.expression, g.direction) for g in self.mode_guards(mode)])
        return self._systems[mode]

    def reset_expressions(self, g: Guard, j: Jump) -> list:
        """The target's states as expressions of the source's states."""
        source, target = self.modes[g.mode], self.modes[j.target]
        return [j.reset[k] if k in j.reset else source.variables[source.state_index(k)] for k in target.state_names]

    def _jump_function(self, g: Guard, k: int):
        if (g.mode, g.name, k) not in self._jumps:  # looked up once: a run may take thousands of jumps
            j = g.jumps[k]
            exprs = [j.when if j.when is not None else 1.0, *self.reset_expressions(g, j)]
            self._jumps[g.mode, g.name, k] = self.modes[g.mode].function(f"jump {g.name} {k}", exprs,
                                                                         f"the jump {g.name} -> {j.target}")
        return self._jumps[g.mode, g.name, k]

    def jump(self, mode: str, guard: str, state, pars=None) -> tuple[int, str, np.ndarray]:
        """(jump index, target mode, target state) of ``guard`` of ``mode`` at ``state``; index -1 (and the
        state unchanged) when none of its jumps applies."""
        g = self.guard(mode, guard)
        pars = self.with_pars(pars)
        source = self.modes[mode]
        for k, j in enumerate(g.jumps):
            out = source.evaluate(self._jump_function(g, k), np.asarray(state, dtype=float), pars)
            if out[0] >= 0.0:
                return k, j.target, np.array(out[1:])
        return -1, mode, np.asarray(state, dtype=float)

    def guard(self, mode: str, name: str) -> Guard:
        for g in self.mode_guards(mode):
            if g.name == name:
                return g
        raise ParameterError(f"mode {mode!r} of {self.name} has no guard {name!r}")

    def with_pars(self, pars=None, **values) -> np.ndarray:
        return next(iter(self.modes.values())).with_pars(self.pars if pars is None else pars, **values)

    def __repr__(self) -> str:
        return f"HybridSystem({self.name!r}: modes {', '.join(self.modes)}; {len(self.guards)} guard(s))"


@dataclass
class Segment:
    """A mode's stretch of a run: its samples (the output grid inside it, its start and its end)."""

    mode: str
    time: np.ndarray
    states: np.ndarray  # (samples, mode's n)


@dataclass(frozen=True)
class Switch:
    time: float
    source: str
    guard: str
    jump: int
    target: str
    before: np.ndarray  # the source state at the guard
    after: np.ndarray  # the target state


@dataclass
class HybridRun:
    segments: list
    switches: list
    status: str
    message: str
    t_final: float
    start: tuple  # (mode, state)
    crossings: dict | None = None  # with a section: {mode: (times, states)}
    accumulation: float | None = None  # status zeno: the time the switches accumulate at (after t_final)

    @property
    def modes_entered(self) -> list:
        """[(time, mode)]: the initial mode, then each jump's target."""
        return [(self.segments[0].time[0] if self.segments else 0.0, self.start[0])] + \
            [(s.time, s.target) for s in self.switches]


def section_quantity(system: System, name: str):
    if name in system.state_names:
        return system.variables[system.state_index(name)]
    if name in system.observables:
        return system.observables[name][0]
    raise ParameterError(f"section quantity {name!r} is neither a state nor an observable of mode {system.name}")


def _integrators(hybrid: HybridSystem, tol: float, section) -> dict:
    out = {}
    for mode in hybrid.modes:
        system = hybrid.system(mode)
        nt = ()
        if section is not None:
            q = section_quantity(system, section["quantity"])
            level = hy.par[len(hybrid.parameter_names)]
            nt = ((hy.sin(q - level) if section.get("modulo") else q - level, Recorder(),
                   section.get("direction", "positive")),)
        out[mode] = copy.copy(system.taylor(tol, events=True, nt_events=nt))
    return out


def _configure_recorder(rec: Recorder, system: System, section: dict, pars: np.ndarray) -> None:
    rec.t_transient, rec.level = float(section.get("transient", 0.0)), float(section["level"])
    rec.modulo, rec.times, rec.states = bool(section.get("modulo")), [], []
    if rec.modulo and section["quantity"] in system.state_names:
        rec.q_index = system.state_index(section["quantity"])
    elif rec.modulo:
        rec.q_func = system.function("section", [section_quantity(system, section["quantity"])])
        rec.pars = pars[: rec.q_func.nparams]


def simulate_hybrid(hybrid: HybridSystem, mode: str, state, t_end: float, *, pars=None, grid=None, tol: float = 1e-13,
                    max_switches: int = MAX_SWITCHES, section: dict | None = None) -> HybridRun:
    """Integrate from ``state`` in ``mode`` to ``t_end``, jump to jump; each mode is entered past its guards'
    zeros without skipping a crossing (:mod:`.zeno`), and switch times that accumulate end the run ``zeno``
    at the last switch, ``run.accumulation`` holding the extrapolated time.

    grid: output times (the run's samples inside each segment; each segment also holds its end state); without
    one a segment holds its start and end. section: {"quantity", "level", "modulo", "direction", "transient"}
    records the crossings in every mode (``run.crossings``)."""
    if not (math.isfinite(t_end) and t_end > 0):
        raise ParameterError(f"t_end = {t_end!r}: give a positive finite time")
    if not (isinstance(max_switches, int) and max_switches > 0):
        raise ParameterError(f"max_switches = {max_switches!r} must be a positive integer")
    pars = hybrid.with_pars(pars)
    integrators = _integrators(hybrid, tol, section)
    for m, ta in integrators.items():
        ta.pars[:] = np.append(pars, section["level"])[: len(ta.pars)] if section else pars[: len(ta.pars)]
        if section is not None:
            _configure_recorder(ta.nt_events[0].callback, hybrid.system(m), section, pars)
    x = np.asarray(state, dtype=float)
    if x.shape != (hybrid.system(mode).n,):
        raise ParameterError(f"mode {mode!r} has {hybrid.modes[mode].n} states, not {x.size}")
    grid = None if grid is None else np.asarray(grid, dtype=float)
    departures = Departures(hybrid, tol, pars)
    run = HybridRun([], [], "completed", f"reached t_end = {t_end:g}", 0.0, (mode, x.copy()))
    t = 0.0
    while True:
        entry_t, entry_x = t, x
        head = [(t, x)] if grid is None or not run.segments else []  # a later segment's start: the last one's end
        dep = departures.depart(mode, t, x, t_end, grid)
        if dep.status == "nonfinite":
            run.status = "nonfinite"
            run.message = (f"the Taylor coefficients became non-finite at t = {t:.6g} in mode {mode}: the state or "
                           "the parameters overflow the equations; give smaller ones")
            run.segments.append(Segment(mode, np.array([t]), x[None, :].copy()))
            break
        head += dep.samples
        t, x = dep.time, dep.state
        if dep.fired is not None:
            index, outcome = dep.fired, None
            seg_time, out = [p[0] for p in head], [p[1] for p in head]
        else:
            ta = integrators[mode]
            ta.time, ta.state[:] = t, x
            if ta.with_events:
                ta.reset_cooldowns()
            if grid is None:
                res = ta.propagate_until(float(t_end))
                seg_time, out = [p[0] for p in head], [p[1] for p in head]
            else:
                times = np.concatenate([[t], grid[(grid > t) & (grid <= t_end)]])
                res = ta.propagate_grid(times)
                grid_out = list(np.asarray(res[-1])[1:])
                seg_time = [p[0] for p in head] + list(times[1:1 + len(grid_out)])
                out = [p[1] for p in head] + grid_out
            outcome = res[0]
            if outcome == hy.taylor_outcome.time_limit:
                if grid is None:
                    seg_time, out = seg_time + [ta.time], out + [np.array(ta.state)]
                run.segments.append(Segment(mode, np.array(seg_time), _rows(out, x)))
                t = float(ta.time)
                break
            t, x = float(ta.time), np.array(ta.state)
            if not (np.all(np.isfinite(x)) and math.isfinite(t)):
                last = seg_time[-1] if seg_time else run.segments[-1].time[-1] if run.segments else entry_t
                run.status = "nonfinite"
                run.message = f"the state became non-finite after t = {last:.6g}; try a smaller tol"
                if not run.segments and not out:
                    seg_time, out = [entry_t], [entry_x]
                run.segments.append(Segment(mode, np.array(seg_time, dtype=float), _rows(out, entry_x)))
                t = last
                break
            index = System.stopping_event(outcome, hybrid.system(mode).events)
        run.segments.append(Segment(mode, np.array(seg_time + [t]), _rows(out + [x], x)))
        events = hybrid.system(mode).events
        if index is None:
            run.status, run.message = "failed", f"heyoka stopped with {outcome!r} at t = {t:.6g}"
            break
        n_own = len(hybrid.modes[mode].events)
        if index < n_own:
            run.status, run.message = events[index].name, f"{events[index].name} at t = {t:.6g} in mode {mode}"
            break
        if len(run.switches) >= max_switches:
            run.status, run.message = "zeno", (f"more than {max_switches} jumps by t = {t:.6g} (switches accumulate); "
                                               "the event-driven integration cannot continue")
            break
        guard = events[index].name
        k, target, after = hybrid.jump(mode, guard, x, pars)
        if k < 0:
            run.status, run.message = "no_jump", (f"guard {guard!r} of mode {mode!r} at t = {t:.6g}: none of its jumps "
                                                  "applies; add a jump without condition")
            break
        run.switches.append(Switch(t, mode, guard, k, target, x, after))
        mode, x = target, after
        found = accumulation([s.time for s in run.switches[-ZENO_TAIL:]], run.segments[0].time[0])
        if found is not None:
            run.status, run.accumulation = "zeno", found[0]
            run.message = _zeno_message(found, t, guard)
            break
    run.t_final = t
    if section is not None:
        run.crossings = {m: (np.array(ta.nt_events[0].callback.times),
                             np.array(ta.nt_events[0].callback.states).reshape(-1, hybrid.modes[m].n))
                         for m, ta in integrators.items()}
    return run


def _rows(states: list, like: np.ndarray) -> np.ndarray:
    """(samples, n) from a list of states (an empty (0, n) for none)."""
    return np.array(states, dtype=float).reshape(-1, like.size)


def _zeno_message(found: tuple, t: float, guard: str) -> str:
    t_z, per_cycle, ratio = found
    if ratio == 0.0:
        return (f"switches accumulate at t = {t_z:.10g}: the last of them fall within round-off of that instant "
                f"(guard {guard!r}; the motion stays on it: declare a mode that holds it, sticking or sliding, as "
                "dy.filippov_system does)")
    cycle = "switch" if per_cycle == 1 else f"{per_cycle} switches"
    return (f"switches accumulate at t = {t_z:.10g} (intervals shrink by {ratio:.6g} per {cycle}); the run stops at "
            f"the last switch, t = {t:.10g}, before it (continue past it with a mode that holds the motion there)")
