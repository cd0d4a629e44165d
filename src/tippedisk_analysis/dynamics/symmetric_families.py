"""Families of symmetric periodic orbits of a reversible System.

A System x' = f(x; p) that is **reversible** at p = 0 (a reversor R with f(Rx) = -R f(x)) has families of
symmetric periodic orbits: an orbit that starts on the fixed plane of R and reaches the fixed plane again is
closed (an orbit through both fixed planes of two reversors R1, R2 closes after four times that time). Each
family member is found by shooting: the start lies on the first plane (``fixed`` state values), one start
coordinate ``vary`` is the family's amplitude, another ``free`` is solved for so that the state ``condition``
vanishes where the orbit first crosses ``section`` (the second plane). The family is continued in (free, vary)
by the generic pseudo-arclength core (:mod:`.continuation`), which locates its folds (the largest amplitude a
family reaches). Without a ``free`` coordinate (a planar system) every amplitude is an orbit. Every member must
close after its period and not after a fraction 1/k of it (k = 2 ... MAX_MULTIPLE): a section met at a multiple
of the period, or a wrong ``period_factor``, is refused.

How a perturbation drifts a start across a family: :mod:`.melnikov`.
"""

from __future__ import annotations

import copy
import math
import numbers
from dataclasses import dataclass

import numpy as np
import xarray as xr
from scipy.optimize import newton

from ..errors import ParameterError
from ..results import index_coordinate, make_attrs
from .continuation import continue_branch
from .continuation_interface import Options, Problem
from .datasets import flag_attrs, mixed_units, state_coordinates
from .system import Event, System

__all__ = ["Shooting", "Shooter", "symmetric_family"]

TOL = 1e-13  # Taylor tolerance of the shooting runs
FD_STEP = 1e-7  # relative finite-difference step of the shooting Jacobian and of DP0
TANGENT_STEP = 1e-6  # relative amplitude step of the re-shot members that give the family's tangent
MIN_TIME = 1e-9  # a section crossing this soon after the start is the start itself (heyoka sees a zero at t = 0)
CLOSURE_TOL = 1e-6  # a member must return to its start after its period to this (state scale, relative)
MAX_MULTIPLE = 7  # a member must not close after period / k, k = 2 ... MAX_MULTIPLE


def finite_real(value, what: str) -> float:
    """``value`` as a finite float, or a one-line ParameterError naming ``what``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise ParameterError(f"{what} = {value!r}: give a finite number")
    return float(value)


def _pair(value, what: str) -> tuple[float, float]:
    if isinstance(value, str) or not hasattr(value, "__len__") or len(value) != 2:
        raise ParameterError(f"{what} = {value!r}: give two numbers")
    return finite_real(value[0], what), finite_real(value[1], what)


@dataclass(frozen=True)
class Shooting:
    """How a family member is shot: from ``fixed`` (state name: value) with ``vary`` = the amplitude and ``free``
    solved for (None: planar, nothing to solve), to the first crossing of ``section`` (an :class:`Event`) after
    the start, where the state ``condition`` must vanish; the period is ``period_factor`` times the time to the
    section (4 for an orbit through the fixed planes of two reversors, 2 for one)."""

    fixed: dict
    vary: str
    section: Event
    free: str | None = None
    condition: str | None = None
    period_factor: float = 4.0
    t_max: float = 1e3

    def check(self, system: System) -> None:
        if not isinstance(self.fixed, dict) or not isinstance(self.section, Event):
            raise ParameterError("give fixed as {state: value} and section as a dynamics.Event")
        for name, value in self.fixed.items():
            finite_real(value, f"fixed[{name!r}]")
        names = [*self.fixed, self.vary, *([self.free, self.condition] if self.free else [])]
        unknown = [n for n in names if n not in system.state_names]
        if unknown:
            raise ParameterError(f"{system.name} has no state {unknown[0]!r}; choose among "
                                 f"{', '.join(system.state_names)}")
        starts = [*self.fixed, self.vary, *([self.free] if self.free else [])]
        if sorted(starts) != sorted(system.state_names):
            raise ParameterError(f"the start of a {system.n}-state orbit needs every state once: fixed ones, the "
                                 "amplitude (vary) and the free one")
        if bool(self.free) != bool(self.condition):
            raise ParameterError("give both free and condition (one unknown, one equation), or neither")
        if not (finite_real(self.period_factor, "period_factor") > 0 and finite_real(self.t_max, "t_max") > 0):
            raise ParameterError("period_factor and t_max must be positive")

    def config(self) -> dict:
        return {"fixed": self.fixed, "vary": self.vary, "free": self.free, "condition": self.condition,
                "section": self.section.name, "section_direction": self.section.direction,
                "period_factor": self.period_factor}


class Shooter:
    """Runs to the section (and round the period, for the period map) with the System's compiled integrators."""

    def __init__(self, system: System, shooting: Shooting, tol: float = TOL):
        shooting.check(system)
        self.system, self.shooting = system, shooting
        self.to_section = system.with_events(f"{system.name}_section_{shooting.section.name}",
                                             [shooting.section]).taylor(tol, events=(shooting.section.name,))
        self.plain = system.taylor(tol)
        self.index = {name: system.state_index(name) for name in system.state_names}

    def start(self, amplitude: float, free: float | None, fixed: dict | None = None) -> np.ndarray:
        """The start state; ``fixed`` overrides some of the Shooting's fixed values (a neighbouring family)."""
        x = np.zeros(self.system.n)
        for name, value in {**self.shooting.fixed, **(fixed or {})}.items():
            x[self.index[name]] = value
        x[self.index[self.shooting.vary]] = amplitude
        if self.shooting.free:
            x[self.index[self.shooting.free]] = free
        return x

    def run(self, x0: np.ndarray, pars: np.ndarray, skip: float = 0.0) -> tuple[np.ndarray, float] | None:
        """(state, time) at the first crossing of the section after ``skip`` [time units] (a crossing at the
        start itself does not count); None if the run ended otherwise (no crossing within t_max, non-finite)."""
        t0 = 0.0
        if skip > 0:
            ta = copy.deepcopy(self.plain)
            ta.time, ta.state[:], ta.pars[:] = 0.0, x0, pars[: len(ta.pars)]
            ta.propagate_until(skip)
            x0, t0 = ta.state.copy(), ta.time
        ta = copy.deepcopy(self.to_section)
        ta.time, ta.state[:], ta.pars[:] = t0, x0, pars[: len(ta.pars)]
        outcome = ta.propagate_until(self.shooting.t_max)[0]
        if System.stopping_event(outcome, (self.shooting.section,)) == 0 and ta.time - t0 <= MIN_TIME * max(
                1.0, abs(t0)):  # the start lies on the section: go on (heyoka's cooldown passes the start)
            outcome = ta.propagate_until(self.shooting.t_max)[0]
        if System.stopping_event(outcome, (self.shooting.section,)) != 0 or not np.all(np.isfinite(ta.state)):
            return None
        return ta.state.copy(), ta.time

    def closure(self, x0: np.ndarray, period: float, pars: np.ndarray) -> float:
        """max |x(period) - x0| / (scale + |x0|): how well an orbit closes after ``period``."""
        ta = copy.deepcopy(self.plain)
        ta.time, ta.state[:], ta.pars[:] = 0.0, x0, pars[: len(ta.pars)]
        ta.propagate_until(period)
        scale = np.asarray(self.system.state_scale) + np.abs(x0)
        return float(np.max(np.abs(ta.state - x0) / scale)) if np.all(np.isfinite(ta.state)) else math.inf

    def least_period_error(self, x0: np.ndarray, period: float, pars: np.ndarray) -> str:
        """'' if the orbit closes after ``period`` and after no period / k (k = 2 ... MAX_MULTIPLE); else why not."""
        error = self.closure(x0, period, pars)
        if not error <= CLOSURE_TOL:
            return (f"does not close after period_factor x the time to the section (error {error:.2g}): the "
                    "section is not where the orbit meets the second fixed plane, or period_factor is wrong (4 for "
                    "two reversors' planes, 2 for one)")
        for k in range(2, MAX_MULTIPLE + 1):
            if self.closure(x0, period / k, pars) <= CLOSURE_TOL:
                return (f"closes after 1/{k} of its period already: the section {self.shooting.section.name!r} is met "
                        f"at a multiple of the period (its direction), or period_factor = "
                        f"{self.shooting.period_factor:g} is {k} times too large")
        return ""

    def solve_free(self, amplitude: float, guess: float, pars: np.ndarray, fixed: dict | None = None) -> float:
        """The free start coordinate of the member with ``amplitude`` (and the ``fixed`` overrides), by secant
        steps from ``guess`` (NaN if they fail)."""
        condition = self.index[self.shooting.condition]

        def residual(b):
            hit = self.run(self.start(amplitude, b, fixed), pars)
            return np.nan if hit is None else hit[0][condition]

        try:
            value = newton(residual, guess, tol=1e-14, maxiter=50)
        except (RuntimeError, ValueError, OverflowError):
            return math.nan
        return float(value) if math.isfinite(value) and abs(residual(value)) < 1e-9 else math.nan

    def tangents(self, amplitude: float, free: float | None, pars: np.ndarray, along: tuple = ()) -> np.ndarray | None:
        """d(crossing state)/d(amplitude) and d(crossing state)/d(fixed value) for each name in ``along``, the
        columns of an (n, 1 + len(along)) array, by central differences of re-shot members (the free coordinate
        solved again at each); None where a neighbour cannot be shot."""
        columns = []
        for name in (None, *along):
            value = amplitude if name is None else self.shooting.fixed[name]
            h = TANGENT_STEP * max(1.0, abs(value))
            ends = []
            for step in (-h, h):
                a, fixed = (amplitude + step, None) if name is None else (amplitude, {name: value + step})
                b = None if free is None else self.solve_free(a, free, pars, fixed)
                hit = None if b is not None and not math.isfinite(b) else self.run(self.start(a, b, fixed), pars)
                if hit is None:
                    return None
                ends.append(hit[0])
            columns.append((ends[1] - ends[0]) / (2 * h))
        return np.column_stack(columns)


class _FamilyProblem(Problem):
    """F(free, amplitude) = condition at the section, continued by the core in the amplitude (its fold test)."""

    def __init__(self, shooter: Shooter, pars: np.ndarray, bounds: tuple, scale: tuple, free_bounds: tuple | None):
        self.shooter, self.pars = shooter, pars
        self.names = (shooter.shooting.free, shooter.shooting.vary)
        self.scale = np.asarray(scale, dtype=float)
        self.parameters = (1,)
        self.bounds = {1: tuple(bounds), **({0: tuple(free_bounds)} if free_bounds is not None else {})}
        self.condition = shooter.index[shooter.shooting.condition]

    def residual(self, u):
        hit = self.shooter.run(self.shooter.start(u[1], u[0]), self.pars)
        return np.array([np.nan if hit is None else hit[0][self.condition]])

    def jacobian(self, u):
        J = np.zeros((1, 2))
        for j in range(2):
            h = FD_STEP * max(1.0, abs(u[j]))
            up, down = u.copy(), u.copy()
            up[j] += h
            down[j] -= h
            J[0, j] = (self.residual(up)[0] - self.residual(down)[0]) / (2 * h)
        return J

    def state_jacobian(self, u):
        return self.jacobian(u)[:, :1]

    def tests(self, point):
        return {"fold": point.tangent[1]}


def symmetric_family(system: System, shooting: Shooting, start: tuple, bounds: tuple, pars=None, *,
                     options: Options | None = None, scale: tuple = (1.0, 1.0), free_bounds: tuple | None = None,
                     direction: int = 1, amplitudes=None) -> xr.Dataset:
    """The family of symmetric periodic orbits of ``system`` (reversible at ``pars``) through ``start`` =
    (amplitude, a guess of free) (e.g. from the linearisation; free ignored for a planar shooting), continued in
    the amplitude within ``bounds`` (and the free coordinate within ``free_bounds``), in ``direction`` (+1: the
    amplitude coordinate grows first; planar: the orbits at ``amplitudes``). ``scale``: typical sizes of (free,
    amplitude), the arclength metric. Dataset kind ``symmetric_family`` along ``orbit``: the start state, the
    state at the section, the period, the amplitude, the fold points of the amplitude (``fold`` = 1) and
    ``closure_error``; status ``completed`` (a bound reached), or the core's ``max_points``, ``stalled``,
    ``corrector_failed`` with its message."""
    shooter = Shooter(system, shooting)
    try:
        pars = system.with_pars(None, **pars) if isinstance(pars, dict) else system.with_pars(pars)
    except (TypeError, ValueError):
        raise ParameterError(f"pars = {pars!r}: give the values of {', '.join(system.parameter_names)} (a vector "
                             "or {name: value})") from None
    low, high = _pair(bounds, "bounds")
    if not low < high:
        raise ParameterError(f"bounds = {bounds!r}: give (low, high) amplitudes with low < high")
    if options is not None and not isinstance(options, Options):
        raise ParameterError("options: give a dynamics.Options")
    if direction not in (1, -1):
        raise ParameterError(f"direction = {direction!r}: give +1 or -1")
    if shooting.free is None:
        try:
            values = np.asarray(amplitudes if amplitudes is not None else [], dtype=float)
        except (TypeError, ValueError):
            raise ParameterError(f"amplitudes = {amplitudes!r}: give numbers") from None
        if values.ndim != 1 or values.size == 0 or not np.all(np.isfinite(values)):
            raise ParameterError("a planar shooting (no free state) needs the amplitudes of its orbits (numbers)")
        if not np.all((values >= low) & (values <= high)):
            raise ParameterError(f"amplitudes {values.min():.6g}-{values.max():.6g} leave the bounds {bounds}; give "
                                 "amplitudes inside them")
        rows = [(a, None, shooter.run(shooter.start(a, None), pars)) for a in values]
        folds, status, message = set(), "completed", f"{len(rows)} orbits"
    else:
        first, guess = _pair(start, "start (amplitude, a guess of the free state)")
        if not low <= first <= high:
            raise ParameterError(f"the start's amplitude {first:g} lies outside the bounds {bounds}")
        problem = _FamilyProblem(shooter, pars, (low, high), scale, free_bounds)
        free = shooter.solve_free(first, guess, pars)  # solved at the start's amplitude
        if not math.isfinite(free):
            raise ParameterError(f"no orbit of the family starts at {shooting.vary} = {first:.6g} near "
                                 f"{shooting.free} = {guess:.6g}; give a better guess (e.g. from the linearisation)")
        branch = continue_branch(problem, np.array([free, first]), options or Options(ds=0.05), direction=direction)
        folds = {sp.index for sp in branch.special_points if sp.kind == "fold"}
        rows = [(p.u[1], p.u[0], shooter.run(shooter.start(p.u[1], p.u[0]), pars)) for p in branch.points]
        status, message = branch.status, branch.message
    bad = [k for k, (_a, _b, hit) in enumerate(rows) if hit is None]
    if bad:
        raise ParameterError(f"the orbit with amplitude {rows[bad[0]][0]:.6g} does not reach the section "
                             f"{shooting.section.name!r} within t_max = {shooting.t_max:g}; give other bounds "
                             "or a larger t_max")
    starts = np.array([shooter.start(a, b) for a, b, _hit in rows])
    crossings = np.array([hit[0] for _a, _b, hit in rows])
    periods = np.array([shooting.period_factor * hit[1] for _a, _b, hit in rows])
    for k, (x, T) in enumerate(zip(starts, periods)):
        why = shooter.least_period_error(x, T, pars)
        if why:
            raise ParameterError(f"the orbit with amplitude {rows[k][0]:.6g} {why}")
    closure = np.array([shooter.closure(x, T, pars) for x, T in zip(starts, periods)])
    fold = np.array([k in folds for k in range(len(rows))], dtype=np.int8)
    units = system.units_of(shooting.vary)
    coords = {"orbit": index_coordinate("orbit", len(rows), "family member"), **state_coordinates(system)}
    ds = xr.Dataset({
        "amplitude": ("orbit", starts[:, shooter.index[shooting.vary]], {"units": units, "long_name":
                      f"start value of {shooting.vary} (the family's amplitude)"}),
        "start": (("orbit", "state"), starts, mixed_units("start state on the first fixed plane")),
        "crossing": (("orbit", "state"), crossings, mixed_units(f"state at the section {shooting.section.name}")),
        "period": ("orbit", periods, {"units": system.time_units, "long_name": "period"}),
        "fold": ("orbit", fold, flag_attrs("fold of the amplitude along the family", {"no": 0, "yes": 1})),
        "closure_error": ("orbit", closure, {"units": "1", "long_name": "max |x(period) - x(0)| / (scale + |x(0)|)"}),
    }, coords=coords)
    config = {**shooting.config(), "bounds": [low, high], "pars": dict(zip(system.parameter_names, map(float, pars)))}
    ds.attrs = make_attrs("symmetric_family", config, status, message, system=system.name)
    return ds
