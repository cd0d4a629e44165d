"""Families of symmetric periodic orbits of a reversible System, and how a perturbation drifts them (Melnikov).

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

**The drift** (:func:`family_drift`, :func:`drift_at`). For p != 0 the family breaks up, and a start on it
moves across it by O(p) per revolution: the Melnikov function of the family. With P the period map to the
section and DP0 its derivative on the family at p = 0 (DP0 t = t along the family tangent t, DP0 f = 0 along the
flow), the left eigenvector l of DP0 for the eigenvalue 1 takes out every other direction, so

    da per revolution = p l . dP/dp / (l . dx/da) + O(p^2),

a = the amplitude. dP/dp is measured at two small values of p, and the reported drift is their linear
extrapolation to p = 0; the two must agree (``drift_check``). dx/da comes from members re-shot at a +- 1e-6.
Where the drift changes sign along the family a periodic orbit of the perturbed system survives (a zero of the
Melnikov function); its sign says on which side starts drift. Where another eigenvalue of DP0 comes near 1 (a
resonance of the transverse oscillation with the family, a fold) l is not defined, and where one passes 1
between two members the family branches (the drift may have a pole there): such orbits are flagged
(``drift_valid`` = 0, with ``resonance_gap`` and ``branch_point``).

:func:`drift_at` also takes families of families (``along``: fixed start values that label the family too; l
becomes the left null space of DP0 - I, one vector per label) and the growth of the oscillation about the orbit
(``transverse``: the first-order change of the transverse multipliers' modulus, with the perturbed map
differentiated at its guiding point x0 + p z, (DP0 - I) z = (the drift along the family) - dP/dp).
"""

from __future__ import annotations

import copy
import json
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

__all__ = ["Shooting", "Shooter", "symmetric_family", "family_drift", "drift_at", "period_map"]

TOL = 1e-13  # Taylor tolerance of the shooting runs
FD_STEP = 1e-7  # relative finite-difference step of the shooting Jacobian and of DP0
TANGENT_STEP = 1e-6  # relative amplitude step of the re-shot members that give the family's tangent
RESONANCE_GAP = 0.05  # an eigenvalue of DP0 closer than this to 1 leaves the drift undefined
DRIFT_AGREEMENT = 1e-2  # the drift at the two parameter values must agree to this (relative)
MIN_TIME = 1e-9  # a section crossing this soon after the start is the start itself (heyoka sees a zero at t = 0)
CLOSURE_TOL = 1e-6  # a member must return to its start after its period to this (state scale, relative)
MAX_MULTIPLE = 7  # a member must not close after period / k, k = 2 ... MAX_MULTIPLE
ONE_TOL = 1e-3  # the period map's eigenvalue for the family tangent must lie this close to 1


def _real(value, what: str) -> float:
    """``value`` as a finite float, or a one-line ParameterError naming ``what``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise ParameterError(f"{what} = {value!r}: give a finite number")
    return float(value)


def _pair(value, what: str) -> tuple[float, float]:
    if isinstance(value, str) or not hasattr(value, "__len__") or len(value) != 2:
        raise ParameterError(f"{what} = {value!r}: give two numbers")
    return _real(value[0], what), _real(value[1], what)


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
            _real(value, f"fixed[{name!r}]")
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
        if not (_real(self.period_factor, "period_factor") > 0 and _real(self.t_max, "t_max") > 0):
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


def period_map(shooter: Shooter, x0: np.ndarray, pars: np.ndarray, skip: float):
    """(the crossing after ``skip`` [time units] from ``x0``, i.e. a period on for skip = (1 - 1 / (2 period_factor))
    periods, and the derivative of that map at ``x0`` by forward differences), or None where a run fails."""
    n = len(x0)
    base = shooter.run(x0, pars, skip)
    if base is None:
        return None
    D = np.zeros((n, n))
    for j in range(n):
        h = FD_STEP * max(1.0, abs(x0[j]))
        hit = shooter.run(x0 + h * np.eye(n)[j], pars, skip)
        if hit is None:
            return None
        D[:, j] = (hit[0] - base[0]) / h
    return base, D


def _orbit_drift(shooters: tuple, x0: np.ndarray, period: float, amplitude: float, free, pars: np.ndarray,
                 index: int, values: tuple, along: tuple = (), transverse: bool = False) -> dict:
    """One orbit's drift (at p -> 0, extrapolated from ``values``) of the amplitude and of the fixed start values
    named in ``along`` (a family of families: an array of 1 + len(along)), the two measured values of each, the
    resonance gap, the product of (mu - 1) over the transverse multipliers (its sign change between members marks
    a branch point) and whether the period map has as many eigenvalues 1 as the family has parameters (``one``).
    transverse: also d ln|mu| / dp per revolution of each transverse multiplier (``transverse_drift``, ordered by
    |arg mu|; NaN where a perturbed map cannot be run): whether the perturbation makes the transverse oscillation
    grow or decay."""
    shooter, base_shooter = shooters
    n, k = len(x0), 1 + len(along)
    out = {"drift": np.full(k, math.nan), "measured": np.full((k, 2), math.nan), "gap": 0.0, "transverse": 0.0,
           "one": True, "transverse_drift": np.full(max(n - k - 1, 0), math.nan), "transverse_check": math.inf}
    skip = period * (1.0 - 0.5 / shooter.shooting.period_factor)  # the next crossing is the one a period on
    mapped = period_map(base_shooter, x0, pars, skip)
    tangents = base_shooter.tangents(amplitude, free, pars, along)
    if mapped is None or tangents is None:
        return out
    base, D = mapped
    others = _transverse_multipliers(D, k)
    if others is None:  # two multipliers near 1 split (a fold or a resonance): no l
        return {**out, "one": False}
    out["gap"] = float(np.min(np.abs(others - 1.0))) if others.size else math.inf
    out["transverse"] = float(np.prod(others - 1.0).real) if others.size else 1.0
    ell = np.linalg.svd(D - np.eye(n))[0][:, -k:]  # the left null space of DP0 - I: l^T DP0 = l^T
    projected = ell.T @ tangents
    if not np.all(np.isfinite(projected)) or np.linalg.cond(projected) > 1e12:
        return out
    measured, guides = [], []
    for value in values:
        perturbed = pars.copy()
        perturbed[index] = value
        hit = shooter.run(x0, perturbed, skip)
        if hit is None:
            measured.append(np.full(k, math.nan))
            continue
        change = (hit[0] - base[0]) / value
        measured.append(np.linalg.solve(projected, ell.T @ change))
        # the perturbed map's guiding point x0 + p z: P_p(x0 + p z) = x0 + p z + p (drift along the family)
        guides.append(np.linalg.lstsq(D - np.eye(n), tangents @ measured[-1] - change, rcond=None)[0])
    (v1, v2), (d1, d2) = values, measured
    out["measured"] = np.column_stack([d1, d2])
    out["drift"] = (v2 * d1 - v1 * d2) / (v2 - v1)  # linear in p: the value at p = 0
    if transverse and others.size and len(guides) == 2:
        out["transverse_drift"], out["transverse_check"] = _transverse_drift(shooter, x0, guides, pars, index, values,
                                                                             skip, others)
    return out


def _transverse_multipliers(D: np.ndarray, k: int) -> np.ndarray | None:
    """The period map's multipliers other than its k eigenvalues 1 (the family's) and the flow's 0, ordered by
    |arg mu|; None unless k lie within ONE_TOL of 1."""
    w = np.linalg.eigvals(D)
    order = np.argsort(np.abs(w - 1.0))
    if abs(w[order[k - 1]] - 1.0) > ONE_TOL:
        return None
    rest = w[order[k:]]
    others = np.delete(rest, np.argmin(np.abs(rest)))
    return others[np.argsort(np.abs(np.angle(others)), kind="stable")]


def _transverse_drift(shooter, x0, guides, pars, index, values, skip, unperturbed) -> tuple[np.ndarray, float]:
    """d ln|mu| / dp per revolution of the transverse multipliers ``unperturbed`` (p = 0), each matched to the
    nearest multiplier of the perturbed map at both ``values`` and extrapolated linearly to p = 0. The perturbed
    map is differentiated at its guiding point x0 + p z (``guides``: z), where a start stays next to the family:
    its multipliers there, not at x0, are those the drifting start sees (where the transverse block depends on the
    state, the two differ at first order in p)."""
    rates = []
    for value, guide in zip(values, guides):
        perturbed = pars.copy()
        perturbed[index] = value
        mapped = period_map(shooter, x0 + value * guide, perturbed, skip)
        moved = None if mapped is None else np.linalg.eigvals(mapped[1])
        if moved is None:
            return np.full(unperturbed.size, math.nan), math.inf
        nearest = moved[[int(np.argmin(np.abs(moved - mu))) for mu in unperturbed]]
        rates.append((np.log(np.abs(nearest)) - np.log(np.abs(unperturbed))) / value)
    (v1, v2), (r1, r2) = values, rates
    check = float(np.max(np.abs(r1 - r2)) / max(float(np.max(np.abs(r2))), 1e-300))
    return (v2 * r1 - v1 * r2) / (v2 - v1), check


def _drift_setup(system, shooting, pars_by_name, parameter, values, unperturbed):
    try:
        values = tuple(_real(v, "values") for v in values)
    except TypeError:
        raise ParameterError(f"values = {values!r}: give two different small nonzero values of {parameter}") from None
    if len(values) != 2 or 0.0 in values or values[0] == values[1]:
        raise ParameterError(f"values = {values!r}: give two different small nonzero values of {parameter}")
    base_system = system if unperturbed is None else unperturbed
    for candidate in (system, base_system):
        if sorted(candidate.parameter_names) != sorted(pars_by_name):
            raise ParameterError(f"{candidate.name!r} has other parameters than the family; give the system it was "
                                 "computed on")
    pars = system.with_pars([pars_by_name[n] for n in system.parameter_names])
    index = system.parameter_index(parameter)
    if pars[index] != 0.0:
        raise ParameterError(f"the family was computed at {parameter} = {pars[index]:g}; compute it at 0")
    return (Shooter(system, shooting), Shooter(base_system, shooting)), pars, index, values


def drift_at(system: System, shooting: Shooting, amplitude: float, free_guess, pars, parameter: str,
             values: tuple = (1e-5, 2e-5), unperturbed: System | None = None, along: tuple = (),
             transverse: bool = False) -> dict:
    """The drift (per revolution per unit ``parameter``, extrapolated to 0) of the member of the family with
    ``amplitude`` (free coordinate solved from ``free_guess``) at ``pars`` (``parameter`` 0): {"drift",
    "period", "check", "valid", "free"} (valid: an eigenvalue 1, no resonance; check: the two values' relative
    difference; free: the solved free coordinate); a zero of it
    between two members is a cycle located exactly (see :func:`family_drift` for the rest).

    ``along``: names of ``fixed`` start coordinates that label the family too (a family of families, e.g. a
    conserved quantity's value or a state every member starts with): their drift per revolution comes as
    ``along_drift`` {name: value}, from the period map's left null space of the dimension 1 + len(along); the
    check then compares the two measured drift vectors, each component in units of its state scale.
    ``transverse``: also ``transverse_drift``, d ln|mu| / d(parameter) per revolution of each transverse
    multiplier mu (ordered by |arg mu|; a pair's two are equal): per unit time, the growth rate per unit
    parameter of the oscillation about the orbit (its Floquet exponent's real part); ``transverse_check``, the
    two values' relative difference."""
    try:
        vector = system.with_pars(None, **pars) if isinstance(pars, dict) else system.with_pars(pars)
    except (TypeError, ValueError):
        raise ParameterError(f"pars: give the values of {', '.join(system.parameter_names)}") from None
    if isinstance(along, str) or any(name not in shooting.fixed for name in along) or len(set(along)) != len(along):
        raise ParameterError(f"along = {along!r}: give names of the Shooting's fixed start values "
                             f"({', '.join(shooting.fixed)}), each once")
    pars = dict(zip(system.parameter_names, map(float, vector)))
    shooters, pars, index, values = _drift_setup(system, shooting, pars, parameter, values, unperturbed)
    base = shooters[1]
    amplitude = _real(amplitude, "amplitude")
    free = None if shooting.free is None else base.solve_free(amplitude, _real(free_guess, "free_guess"), pars)
    if free is not None and not math.isfinite(free):
        raise ParameterError(f"no member of the family at {shooting.vary} = {amplitude:.6g}")
    hit = base.run(base.start(amplitude, free), pars)
    if hit is None:
        raise ParameterError(f"the member at {shooting.vary} = {amplitude:.6g} does not reach the section")
    period = shooting.period_factor * hit[1]
    found = _orbit_drift(shooters, hit[0], period, amplitude, free, pars, index, values, tuple(along), transverse)
    scale = np.array([system.state_scale[system.state_index(name)] for name in (shooting.vary, *along)])
    d1, d2 = (found["measured"][:, j] / scale for j in (0, 1))
    check = float(np.linalg.norm(d1 - d2) / max(np.linalg.norm(d2), 1e-300))
    drift = found["drift"]
    valid = found["one"] and bool(np.all(np.isfinite(drift))) and found["gap"] > RESONANCE_GAP
    out = {"drift": float(drift[0]), "period": period, "check": check, "valid": bool(valid), "free": free}
    if along:
        out["along_drift"] = dict(zip(along, map(float, drift[1:])))
    if transverse:
        out["transverse_drift"] = [float(v) for v in found["transverse_drift"]]
        out["transverse_check"] = found["transverse_check"]
    return out


def family_drift(system: System, family: xr.Dataset, shooting: Shooting, parameter: str,
                 values: tuple = (1e-5, 2e-5), unperturbed: System | None = None) -> xr.Dataset:
    """The Melnikov drift of every orbit of ``family`` (from :func:`symmetric_family` with the same ``shooting``,
    at the parameters stored in it, where ``parameter`` is 0) measured at the small ``values`` and extrapolated
    to 0: ``drift`` [amplitude units per revolution per unit parameter], ``drift_rate`` (the same per unit
    time), ``drift_check`` (difference of the two measured values, relative to the larger of the drift and the
    family's median drift), ``resonance_gap`` (distance of the period map's nearest other eigenvalue from 1),
    ``branch_point`` (1 where another multiplier passes 1 between the orbit and the next: the family branches)
    and ``drift_valid`` (1 where the period map has an eigenvalue within ONE_TOL of 1, the gap exceeds
    RESONANCE_GAP, the two values agree to DRIFT_AGREEMENT, and the orbit is at no fold and next to no branch
    point). The family's end members are not evaluated. Status: the family's own when it ended short (e.g.
    ``max_points``), else ``completed`` (or ``degenerate``: no orbit passed the checks).
    ``unperturbed``: the same system written with ``parameter`` = 0 in its expressions, where the family was
    computed on it (heyoka's Taylor coefficients of 0 * g overflow where g is singular, and 0 * inf is no 0);
    it runs the period map at 0, ``system`` at the small values."""
    if not isinstance(family, xr.Dataset) or family.attrs.get("kind") != "symmetric_family" or "period" not in family:
        raise ParameterError("family: give a dataset of dynamics.symmetric_families.symmetric_family")
    try:
        config = json.loads(family.attrs["config"])
        stored_pars = config["pars"]
    except (KeyError, TypeError, ValueError):
        raise ParameterError("the family has no readable config; compute it again with symmetric_family") from None
    if any(config.get(key) != value for key, value in shooting.config().items()):
        raise ParameterError("the family was shot with another Shooting; give the one it was computed with")
    if family.attrs.get("system") not in (system.name, getattr(unperturbed, "name", None)):
        raise ParameterError(f"the family was computed on {family.attrs.get('system')!r}; give that system")
    shooters, pars, index, values = _drift_setup(system, shooting, stored_pars, parameter, values, unperturbed)
    crossings, periods, amplitude = family.crossing.values, family.period.values, family.amplitude.values
    free = family.start.sel(state=shooting.free).values if shooting.free else [None] * len(amplitude)
    size = len(amplitude)
    if size < 3:
        raise ParameterError(f"the family has {size} orbits; the drift needs neighbours on both sides (at least 3)")
    drift, measured = np.full(size, np.nan), np.full((size, 2), np.nan)
    gap, transverse, no_one = np.zeros(size), np.zeros(size), np.zeros(size, bool)
    for k in range(1, size - 1):
        found = _orbit_drift(shooters, crossings[k], periods[k], amplitude[k], free[k], pars, index, values)
        drift[k], measured[k], gap[k], transverse[k] = found["drift"][0], found["measured"][0], found["gap"], found[
            "transverse"]
        no_one[k] = not found["one"]
    finite = np.isfinite(drift) & np.all(np.isfinite(measured), axis=1)
    typical = float(np.median(np.abs(drift[finite]))) if finite.any() else 0.0
    check = np.where(finite, np.abs(measured[:, 0] - measured[:, 1])
                     / np.maximum(np.abs(drift), max(typical, 1e-300)), 0.0)
    branch = np.zeros(size, np.int8)
    crossed = transverse[1:-2] * transverse[2:-1] < 0  # another multiplier passes 1 between k and k + 1
    branch[1:-2] |= crossed
    branch[2:-1] |= crossed
    fold = family.fold.values
    near_fold = np.array([fold[max(k - 1, 0): k + 2].any() for k in range(size)])
    valid = (finite & (check <= DRIFT_AGREEMENT) & (gap > RESONANCE_GAP) & ~near_fold & (branch == 0)).astype(np.int8)
    drift[~finite] = 0.0
    units = _units_product(system.units_of(shooting.vary), system.units_of(parameter), -1)
    out = family.copy()
    out["drift"] = ("orbit", drift, {"units": units, "long_name": f"change of the amplitude per revolution per unit "
                                     f"{parameter} (Melnikov), extrapolated to {parameter} = 0"})
    out["drift_rate"] = ("orbit", drift / periods, {"units": _units_product(units, system.time_units, -1),
                                                    "long_name": f"drift per unit time per unit {parameter}"})
    out["drift_check"] = ("orbit", check, {"units": "1", "long_name": f"difference of the drift measured at "
                                           f"{parameter} = {values[0]:g} and {values[1]:g}, relative"})
    out["resonance_gap"] = ("orbit", gap, {"units": "1", "long_name": "distance from 1 of the period map's nearest "
                                           "other eigenvalue"})
    out["branch_point"] = ("orbit", branch, flag_attrs("another multiplier passes 1 next to this orbit",
                                                       {"no": 0, "yes": 1}))
    out["drift_valid"] = ("orbit", valid, flag_attrs("whether the drift is defined and checked (0: an end "
                                                     "member, a fold, a branch point, a resonance or a failed "
                                                     "check)", {"no": 0, "yes": 1}))
    inner = slice(1, -1)
    reasons = {"no eigenvalue 1 of the period map": int(no_one.sum()),
               "not finite": int((~finite & ~no_one)[inner].sum()),
               "nonlinear in " + parameter: int((finite & (check > DRIFT_AGREEMENT))[inner].sum()),
               "resonance": int((finite & (gap <= RESONANCE_GAP))[inner].sum()),
               "next to a fold": int(near_fold[inner].sum()), "next to a branch point": int(branch[inner].sum())}
    failed = ", ".join(f"{count} {why}" for why, count in reasons.items() if count)
    n_valid = int(valid.sum())
    message = f"drift of {n_valid} of {size - 2} inner orbits checked" + (f" (not: {failed})" if failed else "")
    status = "completed" if n_valid else "degenerate"
    if family.attrs.get("status") != "completed":  # the family itself ended short: that stays its status
        status, message = family.attrs.get("status"), f"{family.attrs.get('message')}; {message}"
    cfg = {**config, "parameter": parameter, "values": list(values)}
    out.attrs = make_attrs("symmetric_family", cfg, status, message, system=family.attrs.get("system"))
    return out


def _units_product(units: str, other: str, power: int) -> str:
    """UDUNITS ``units`` times ``other`` to ``power`` (products of symbols with integer exponents: "rad",
    "m s-1"), exponents collected: ("rad", "m s-1", -1) -> "rad m-1 s"."""
    exponents: dict[str, int] = {}
    for text, sign in ((units, 1), (other, power)):
        for factor in text.split():
            if factor == "1":
                continue
            symbol = factor.rstrip("-0123456789")
            exponents[symbol] = exponents.get(symbol, 0) + sign * int(factor[len(symbol):] or 1)
    return " ".join(s if e == 1 else f"{s}{e}" for s, e in exponents.items() if e) or "1"
