"""Families of symmetric periodic orbits of a reversible System, and how a perturbation drifts them (Melnikov).

A System x' = f(x; p) that is **reversible** at p = 0 (a reversor R with f(Rx) = -R f(x)) has families of
symmetric periodic orbits: an orbit that starts on the fixed plane of R and reaches the fixed plane again is
closed (an orbit through both fixed planes of two reversors R1, R2 closes after four times that time). Each
family member is found by shooting: the start lies on the first plane (``fixed`` state values), one start
coordinate ``vary`` is the family's amplitude, another ``free`` is solved for so that the state ``condition``
vanishes where the orbit first crosses ``section`` (the second plane). The family is continued in (free, vary)
by the generic pseudo-arclength core (:mod:`.continuation`), which locates its folds (the largest amplitude a
family reaches). Without a ``free`` coordinate (a planar system) every amplitude is an orbit.

**The drift** (:func:`family_drift`). For p != 0 the family breaks up, and a start on it moves across it by
O(p) per revolution: the Melnikov function of the family. With P the return map to the section and
DP0 its derivative on the family at p = 0 (DP0 t = t along the family tangent t, DP0 f = 0 along the flow),
the left eigenvector l of DP0 for the eigenvalue 1 takes out every other direction, so

    da per revolution = p l . dP/dp / (l . dx/da) + O(p^2),

a = the amplitude. Where it changes sign along the family a periodic orbit of the perturbed system survives
(a zero of the Melnikov function); its sign says on which side starts drift. The derivative dP/dp is measured
at two small values of p and must agree (``drift_check``); where another eigenvalue of DP0 comes near 1 (a
resonance of the transverse oscillation with the family, or a fold) l is not defined and the orbit is flagged
(``drift_valid`` = 0, ``resonance_gap``).
"""

from __future__ import annotations

import copy
import json
import math
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

__all__ = ["Shooting", "Shooter", "symmetric_family", "family_drift"]

TOL = 1e-13  # Taylor tolerance of the shooting runs
FD_STEP = 1e-7  # relative finite-difference step of the shooting Jacobian and of DP0
RESONANCE_GAP = 0.05  # an eigenvalue of DP0 closer than this to 1 leaves the drift undefined
DRIFT_AGREEMENT = 1e-2  # the drift per unit parameter at the two parameter values must agree to this (relative)
SKIP = 0.25  # fraction of the period run before the return map looks for the section
MIN_TIME = 1e-9  # a section crossing this soon after the start is the start itself (heyoka sees a zero at t = 0)
CLOSURE_TOL = 1e-6  # a member must return to its start after its period to this (state scale, relative)
ONE_TOL = 1e-3  # the return map's eigenvalue for the family tangent must lie this close to 1


@dataclass(frozen=True)
class Shooting:
    """How a family member is shot: from ``fixed`` (state name: value) with ``vary`` = the amplitude and ``free``
    solved for (None: planar, nothing to solve), to the first crossing of ``section`` (an :class:`Event`), where
    the state ``condition`` must vanish; the period is ``period_factor`` times the time to the section (4 for
    an orbit through the fixed planes of two reversors, 2 for one)."""

    fixed: dict
    vary: str
    section: Event
    free: str | None = None
    condition: str | None = None
    period_factor: float = 4.0
    t_max: float = 1e3

    def check(self, system: System) -> None:
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
        if not (self.period_factor > 0 and self.t_max > 0):
            raise ParameterError("period_factor and t_max must be positive")


class Shooter:
    """Runs to the section (and round again, for the return map) with the System's compiled integrators."""

    def __init__(self, system: System, shooting: Shooting, tol: float = TOL):
        shooting.check(system)
        self.system, self.shooting = system, shooting
        self.to_section = system.with_events(f"{system.name}_section_{shooting.section.name}",
                                             [shooting.section]).taylor(tol, events=(shooting.section.name,))
        self.plain = system.taylor(tol)
        self.index = {name: system.state_index(name) for name in system.state_names}

    def start(self, amplitude: float, free: float | None) -> np.ndarray:
        x = np.zeros(self.system.n)
        for name, value in self.shooting.fixed.items():
            x[self.index[name]] = value
        x[self.index[self.shooting.vary]] = amplitude
        if self.shooting.free:
            x[self.index[self.shooting.free]] = free
        return x

    def run(self, x0: np.ndarray, pars: np.ndarray, skip: float = 0.0) -> tuple[np.ndarray, float] | None:
        """(state, time) at the first crossing of the section after ``skip`` [time units]; None if the run
        ended otherwise (no crossing within t_max, non-finite)."""
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

    def solve_free(self, amplitude: float, guess: float, pars: np.ndarray) -> float:
        """The free start coordinate of the member with ``amplitude``, by secant steps from ``guess`` (NaN if
        they fail)."""
        condition = self.index[self.shooting.condition]

        def residual(b):
            hit = self.run(self.start(amplitude, b), pars)
            return np.nan if hit is None else hit[0][condition]

        try:
            value = newton(residual, guess, tol=1e-14, maxiter=50)
        except (RuntimeError, ValueError, OverflowError):
            return math.nan
        return float(value) if math.isfinite(value) and abs(residual(value)) < 1e-9 else math.nan

    def tangent(self, amplitude: float, free: float | None, pars: np.ndarray) -> np.ndarray | None:
        """d(crossing state)/d(amplitude) along the family, by central differences of re-shot members (the free
        coordinate solved again at each); None where a neighbour cannot be shot."""
        h = 1e-6 * max(1.0, abs(amplitude))
        ends = []
        for a in (amplitude - h, amplitude + h):
            b = None if free is None else self.solve_free(a, free, pars)
            hit = None if b is not None and not math.isfinite(b) else self.run(self.start(a, b), pars)
            if hit is None:
                return None
            ends.append(hit[0])
        return (ends[1] - ends[0]) / (2 * h)


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
    amplitude), the arclength metric. Dataset kind ``symmetric_family``
    along ``orbit``: the start state, the state at the section, the period, the amplitude, and the fold points
    of the amplitude (``fold`` = 1); status ``completed`` (a bound reached), or the core's ``max_points``,
    ``stalled``, ``corrector_failed`` with its message."""
    pars = system.with_pars(pars)
    shooter = Shooter(system, shooting)
    low, high = bounds
    if not (math.isfinite(low) and math.isfinite(high) and low < high):
        raise ParameterError(f"bounds = {bounds!r}: give finite (low, high) amplitudes with low < high")
    if shooting.free is None:
        values = np.asarray(amplitudes if amplitudes is not None else [], dtype=float)
        if values.ndim != 1 or values.size == 0:
            raise ParameterError("a planar shooting (no free state) needs the amplitudes of its orbits")
        if not np.all((values >= low) & (values <= high)):
            raise ParameterError(f"amplitudes {values.min():.6g}-{values.max():.6g} leave the bounds {bounds}; give "
                                 "amplitudes inside them")
        rows = [(a, None, shooter.run(shooter.start(a, None), pars)) for a in values]
        folds, status, message = set(), "completed", f"{len(rows)} orbits"
    else:
        problem = _FamilyProblem(shooter, pars, bounds, scale, free_bounds)
        if len(start) != 2 or not all(isinstance(v, int | float) and math.isfinite(v) for v in start):
            raise ParameterError(f"start = {start!r}: give (amplitude, a guess of {shooting.free}) as two numbers")
        free = shooter.solve_free(float(start[0]), float(start[1]), pars)  # solved at the start's amplitude
        if not math.isfinite(free):
            raise ParameterError(f"no orbit of the family starts at {shooting.vary} = {start[0]:.6g} near "
                                 f"{shooting.free} = {start[1]:.6g}; give a better guess (e.g. from the linearisation)")
        branch = continue_branch(problem, np.array([free, start[0]], dtype=float), options or Options(ds=0.05),
                                 direction=direction)
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
    closure = np.array([shooter.closure(x, T, pars) for x, T in zip(starts, periods)])
    half = shooter.closure(starts[0], 0.5 * periods[0], pars)
    if half <= CLOSURE_TOL:
        raise ParameterError(f"the orbit with amplitude {rows[0][0]:.6g} closes after half its period already: "
                             f"the section {shooting.section.name!r} is met at a multiple of the period (its "
                             f"direction) or period_factor = {shooting.period_factor:g} is too large")
    if not np.all(closure <= CLOSURE_TOL):
        k = int(np.argmax(closure))
        raise ParameterError(f"the orbit with amplitude {rows[k][0]:.6g} does not close after period_factor x the time "
                             f"to the section (error {closure[k]:.2g}): the section is not where the orbit meets the "
                             "second fixed plane, or period_factor is wrong (4 for two reversors' planes, 2 for one; "
                             "the section's direction must skip the start)")
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
    config = {"fixed": shooting.fixed, "vary": shooting.vary, "free": shooting.free, "condition": shooting.condition,
              "section": shooting.section.name, "period_factor": shooting.period_factor, "bounds": list(bounds),
              "pars": dict(zip(system.parameter_names, map(float, pars)))}
    ds.attrs = make_attrs("symmetric_family", config, status, message, system=system.name)
    return ds


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


def family_drift(system: System, family: xr.Dataset, shooting: Shooting, parameter: str,
                 values: tuple = (1e-5, 2e-5), unperturbed: System | None = None) -> xr.Dataset:
    """The Melnikov drift of every orbit of ``family`` (from :func:`symmetric_family` at the parameters stored in
    it, where ``parameter`` is 0) when ``parameter`` takes the small ``values``: ``drift`` [amplitude units per
    revolution per unit parameter], ``drift_rate`` (the same per unit time), ``drift_check`` (difference between
    the two values, relative to the larger of the drift and the family's median drift), ``resonance_gap``
    (distance of the return map's nearest other eigenvalue from 1), ``branch_point`` (1 where another multiplier
    passes 1 between the orbit and the next: the family branches there and the drift has a pole) and
    ``drift_valid`` (1 where the return map has an eigenvalue within ONE_TOL of 1, the gap exceeds
    RESONANCE_GAP, the two values agree to DRIFT_AGREEMENT, and the orbit is at no fold and next to no branch
    point). The family tangent comes from re-shot members at
    amplitude +- 1e-6 (relative). The family's end members are not evaluated.
    ``unperturbed``: the same system written with ``parameter`` = 0 in its expressions, where the family was
    computed on it (heyoka's Taylor coefficients of 0 * g overflow where g is singular, and 0 * inf is no 0);
    it runs the return map at 0, ``system`` at the small values."""
    if not isinstance(family, xr.Dataset) or family.attrs.get("kind") != "symmetric_family":
        raise ParameterError("family: give a dataset of dynamics.symmetric_families.symmetric_family")
    config = json.loads(family.attrs["config"])
    base_system = system if unperturbed is None else unperturbed
    for candidate in (system, base_system):
        if sorted(candidate.parameter_names) != sorted(config["pars"]) or family.attrs.get("system") not in (
                system.name, base_system.name):
            raise ParameterError(f"the family was computed on {family.attrs.get('system')!r}, not on "
                                 f"{candidate.name!r}; give the system it was computed on")
    try:
        values = tuple(float(v) for v in values)
    except TypeError:
        raise ParameterError(f"values = {values!r}: give two different small nonzero values of {parameter}") from None
    if len(values) != 2 or not all(math.isfinite(v) and v != 0 for v in values) or values[0] == values[1]:
        raise ParameterError(f"values = {values!r}: give two different small nonzero values of {parameter}")
    shooter, base_shooter = Shooter(system, shooting), Shooter(base_system, shooting)
    pars = system.with_pars([config["pars"][n] for n in system.parameter_names])
    index = system.parameter_index(parameter)
    if pars[index] != 0.0:
        raise ParameterError(f"the family was computed at {parameter} = {pars[index]:g}; compute it at 0")
    crossings, periods = family.crossing.values, family.period.values
    amplitude = family.amplitude.values
    free = family.start.sel(state=shooting.free).values if shooting.free else [None] * len(amplitude)
    n, size = system.n, len(amplitude)
    drift = np.full((size, 2), np.nan)
    gap, transverse, no_one = np.zeros(size), np.zeros(size), np.zeros(size, bool)
    for k in range(1, size - 1):
        x0, period = crossings[k], periods[k]
        skip = SKIP * period
        base = base_shooter.run(x0, pars, skip)
        tangent = base_shooter.tangent(amplitude[k], free[k], pars)
        if base is None or tangent is None:
            continue
        D = np.zeros((n, n))
        for j in range(n):
            h = FD_STEP * max(1.0, abs(x0[j]))
            hit = base_shooter.run(x0 + h * np.eye(n)[j], pars, skip)
            if hit is None:
                break
            D[:, j] = (hit[0] - base[0]) / h
        else:
            w, left = np.linalg.eig(D.T)
            one = int(np.argmin(np.abs(w - 1.0)))
            if abs(w[one] - 1.0) > ONE_TOL:  # two multipliers near 1 split (a fold or a resonance): no l
                no_one[k] = True
                continue
            flow = int(np.argmin(np.abs(np.where(np.arange(n) == one, np.inf, w))))  # the flow's eigenvalue 0
            others = np.delete(w, [one, flow])
            gap[k] = float(np.min(np.abs(others - 1.0))) if others.size else math.inf
            transverse[k] = float(np.prod(others - 1.0).real) if others.size else 1.0
            ell = left[:, one].real
            for i, value in enumerate(values):
                perturbed = pars.copy()
                perturbed[index] = value
                hit = shooter.run(x0, perturbed, skip)
                if hit is not None:
                    drift[k, i] = float(ell @ (hit[0] - base[0]) / value / (ell @ tangent))
    finite = np.all(np.isfinite(drift), axis=1)
    typical = float(np.median(np.abs(drift[finite, 1]))) if finite.any() else 0.0
    check = np.where(finite, np.abs(drift[:, 0] - drift[:, 1]) / np.maximum(np.abs(drift[:, 1]), max(typical, 1e-300)),
                     np.inf)
    branch = np.zeros(size, np.int8)
    crossed = (transverse[1:-2] * transverse[2:-1] < 0)  # another multiplier passes 1 between k and k + 1
    branch[1:-2] |= crossed
    branch[2:-1] |= crossed
    fold = family.fold.values
    near_fold = np.array([fold[max(k - 1, 0): k + 2].any() for k in range(size)])
    valid = (finite & (check <= DRIFT_AGREEMENT) & (gap > RESONANCE_GAP) & ~near_fold & (branch == 0)).astype(np.int8)
    drift[~finite] = 0.0
    check[~finite] = 0.0
    units = _units_product(system.units_of(shooting.vary), system.units_of(parameter), -1)
    out = family.copy()
    out["drift"] = ("orbit", drift[:, 1], {"units": units, "long_name": f"change of the amplitude per revolution per "
                                           f"unit {parameter} (Melnikov), at {parameter} = {values[1]:g}"})
    out["drift_rate"] = ("orbit", drift[:, 1] / periods, {"units": _units_product(units, system.time_units, -1),
                                                          "long_name": f"drift per unit time per unit {parameter}"})
    out["drift_check"] = ("orbit", check, {"units": "1", "long_name": f"difference of the drift at {parameter} = "
                                           f"{values[0]:g} and {values[1]:g}, relative"})
    out["resonance_gap"] = ("orbit", gap, {"units": "1", "long_name": "distance from 1 of the return map's nearest "
                                           "other eigenvalue"})
    out["branch_point"] = ("orbit", branch, flag_attrs("another multiplier passes 1 next to this orbit",
                                                       {"no": 0, "yes": 1}))
    out["drift_valid"] = ("orbit", valid, flag_attrs("whether the drift is defined and checked (0: an end "
                                                     "member, a fold, a branch point, a resonance or a failed "
                                                     "check)", {"no": 0, "yes": 1}))
    n_valid, inner = int(valid.sum()), max(size - 2, 0)
    inner_ = slice(1, -1)
    reasons = {"no eigenvalue 1 of the return map": int(no_one.sum()),
               "not finite": int((~finite & ~no_one)[inner_].sum()),
               "nonlinear in " + parameter: int((finite & (check > DRIFT_AGREEMENT))[inner_].sum()),
               "resonance": int((finite & (gap <= RESONANCE_GAP))[inner_].sum()),
               "next to a fold": int(near_fold[inner_].sum()), "next to a branch point": int(branch[inner_].sum())}
    failed = ", ".join(f"{count} {why}" for why, count in reasons.items() if count)
    status = "completed" if n_valid else "degenerate"
    message = f"drift of {n_valid} of {inner} inner orbits checked" + (f" (not: {failed})" if failed else "")
    cfg = {**config, "parameter": parameter, "values": list(values)}
    out.attrs = make_attrs("symmetric_family", cfg, status, message, system=family.attrs.get("system"))
    return out
