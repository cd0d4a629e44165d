"""Branches of periodic orbits of a :class:`.system.System` by pseudo-arclength continuation of the shooting
problem (:mod:`.shooting`), started at an orbit or at a Hopf point, and their special points.

**At a Hopf point** (:func:`hopf_start`, :func:`orbit_branch`) the branch starts as AUTO's does: with the
parameter free, from the zero-amplitude orbit x(t) = x_H (period T_H = 2 pi / omega) along the branch's tangent,
the critical eigenvector's rotation Re(q exp(i omega t)) with no change of T and p (both change to second
order in the amplitude), by the arclength-constrained corrector. At a fixed parameter the orbits next to a
Hopf point are ill-conditioned (p - p_H ~ r^2): the constraint on the amplitude removes that.

**Special points** along a branch (test functions on the nontrivial multipliers mu_i, each located by Brent's
method on the arclength, on a smooth function: |mu| - 1 of the critical multiplier(s)):

* ``fold`` of cycles (LP): the tangent's parameter component changes sign (a multiplier passes +1);
* ``branch_point`` of cycles (BP): prod (mu_i - 1) changes sign without a fold;
* ``period_doubling`` (PD): prod (mu_i + 1) changes sign (a real multiplier through -1);
  :func:`switch_period_doubling` continues the emanating orbit of twice the period;
* ``neimark_sacker`` (NS): prod_{i<j} (mu_i mu_j - 1) changes sign and the critical pair is complex
  (a reciprocal real pair, a neutral saddle, is rejected); the rotation angle arg mu is reported;
* ``hopf`` (H): the amplitude x_0 - x(T/2) changes sign: the branch reached the equilibrium it was born
  from and ends there;
* approach to a **homoclinic** orbit (HC): the period grows without bound; the branch stops at the
  period bound and reports the last periods and the limiting parameter extrapolated from
  p - p_hc ~ exp(-lambda T);
* ``event`` (EVENT): an orbit reaches one of the System's terminal events (where a run of the model ends, e.g.
  the edge of its domain); with ``end_at_events`` the branch ends there and its message names the event.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from ..errors import ParameterError
from . import continuation, normal_forms, period_limits
from .branches import bounds_pair
from .datasets import point_of, special_point
from .flows import TAYLOR_TOL
from .orbit_datasets import branch_dataset
from .orbits import integral_levels
from .collocation_mesh import Mesh
from .discretisations import (BRANCH_OPTIONS, CONTINUE_OPTIONS, DEFAULT_METHOD, check_method, make_problem,
                              method_options, period_scale)
from .orbit_base import N_SAMPLES, OrbitProblem, PeriodicOrbit
from .system import System


def orbit_problem(orbit: PeriodicOrbit, parameter: str, *, method: str | None = None, parameter_scale: float = 1.0,
                  bounds: dict | None = None, period_max: float | None = None, tol: float = TAYLOR_TOL, pinned=(),
                  **discretisation) -> tuple[OrbitProblem, np.ndarray]:
    """The continuation problem through ``orbit`` in ``parameter`` (a runtime parameter, a first integral's
    level or a pinned state) and its start unknowns u0, by ``method`` (default the orbit's own) with the
    ``discretisation`` options of :mod:`.discretisations`; ``pinned``: states held at the start orbit's values."""
    if not orbit.converged:
        raise ParameterError(f"the start is not a periodic orbit (status {orbit.status}): {orbit.message}")
    system = orbit.system
    method = check_method(method or orbit.method)
    pins = {name: float(orbit.states[0][system.state_index(name)]) for name in pinned}
    k = None if parameter in system.integrals or parameter in pins else system.parameter_index(parameter)
    bounds = dict(bounds or {})
    if period_max is not None:
        bounds["T"] = (0.0, float(period_max))
    levels = integral_levels(system, orbit.states[0], orbit.pars)
    value = {**levels, **pins}[parameter] if k is None else orbit.pars[k]
    same = orbit.method == method
    if method == "shooting":
        discretisation["segments"] = discretisation.get("segments") or (len(orbit.states) if same else 1)
        same = same and discretisation["segments"] == len(orbit.states)
    elif same and discretisation.get("ntst") in (None, len(orbit.mesh) - 1) and discretisation.get("ncol") in (
            None, orbit_ncol(orbit)):
        discretisation["mesh"] = Mesh(orbit.mesh, orbit_ncol(orbit))
    else:
        same = False
    prob = make_problem(method, system, orbit.pars, parameter=parameter, parameter_scale=parameter_scale,
                        period_scale=period_scale(method, orbit.period), bounds=bounds, tol=tol, levels=levels,
                        pins=pins, **discretisation)
    u0 = prob.pack(orbit.states, orbit.period, value) if same else prob.unknowns(orbit.states[0], orbit.period, value)
    return prob, u0


def orbit_ncol(orbit: PeriodicOrbit) -> int:
    """ncol of a collocation orbit (its nodes per mesh interval)."""
    return len(orbit.states) // (len(orbit.mesh) - 1)


def continue_orbits(orbit: PeriodicOrbit, parameter: str, *, bounds=None, direction: int = 1,
                    both_ways: bool = False, options: continuation.Options | None = None, marks=(),
                    end_at_events: bool = False, **problem_options):
    """The branch of periodic orbits through ``orbit`` in ``parameter`` by PALC within ``bounds`` (a (low, high)
    pair for ``parameter``, or {name or "T": (low, high)}), with its special points
    (fold of cycles, branch point, period doubling, Neimark-Sacker, approach to a homoclinic orbit at the
    period bound ``period_max``; user points at ``marks``; an orbit that reaches a terminal event of the System,
    where the branch ends if ``end_at_events``); ``problem_options``: those of :func:`orbit_problem` (method,
    ntst, ncol, segments, ...).

    Returns ``(branch, problem)``: ``branch`` is the continuation core's :class:`.continuation.Branch` (its
    ``points`` each hold the unknowns ``u`` of the problem's discretisation, the arclength and the Floquet
    multipliers as ``eigenvalues``; ``special_points``, ``status`` and ``message``), ``problem`` the
    :class:`.orbit_base.OrbitProblem` that reads them (``problem.orbit(u)`` is one :class:`PeriodicOrbit`). ``dy.branch_dataset(problem, branch)`` makes the dataset of kind
    ``periodic_orbits`` that :func:`orbit_branch` returns, with periods, states, multipliers and special points."""
    if bounds is not None and not isinstance(bounds, dict):
        bounds = {parameter: bounds_pair(bounds, parameter)}
    prob, u0 = orbit_problem(orbit, parameter, bounds=bounds, **problem_options)
    prob.end_at_events(end_at_events)
    options = options or continuation.Options(**CONTINUE_OPTIONS[prob.method])
    if both_ways:
        br = continuation.continue_both_ways(prob, u0, options, marks=marks)
    else:
        br = continuation.continue_branch(prob, u0, options, direction=direction, marks=marks)
    _mark_period_limit(prob, br)
    return br, prob


def _mark_period_limit(prob: OrbitProblem, br: continuation.Branch) -> None:
    """If the branch ended at the period bound, add a special point at its last point that names the
    infinite-period limit (:func:`.period_limits.classify_end`): ``homoclinic``, ``heteroclinic``, ``snic`` with
    the limit p_c and its uncertainty, or ``period_bound`` (not named, with the reason), and say so in the
    branch's message."""
    if prob.t_index not in prob.bounds or not br.points:
        return
    T_max = prob.bounds[prob.t_index][1]
    last = br.points[-1]
    if last.special != "bound" or abs(last.u[prob.t_index] - T_max) > 1e-9 * T_max:
        return
    end = period_limits.classify_end(prob, br)
    T_first, T_last, p = prob.split(br.points[0].u)[1], prob.split(last.u)[1], prob.parameter
    data = {"period": T_last, **{k: end[k] for k in ("limit", "error", "rate", "law", "reason")},
            "last_periods": end["periods"][-5:].tolist(), "last_values": end["values"][-5:].tolist(),
            "equilibria": [e.state.tolist() for e in end["equilibria"]],
            "fold": None if end["fold"] is None else end["fold"]["value"]}
    br.special_points.append(continuation.SpecialPoint(end["kind"], len(br.points) - 1, last.u, last.eigenvalues,
                                                       float(prob.split(last.u)[2] - end["limit"]), data))
    continuation.label_points(br.special_points)
    br.message += f"; the period grew to {T_last:.6g} (from {T_first:.6g}): " + period_limits.describe(end, p)


def homoclinic_limit(T: np.ndarray, P: np.ndarray) -> tuple[float, float]:
    """(p_hc, lam) of p = p_hc + A exp(-lam T) through the last points of a branch whose period grows
    (least squares in log|dp/dT| = log(lam A) - lam T, then p_hc = p + (dp/dT) / lam at the last point)."""
    order = np.argsort(T)
    T, P = T[order], P[order]
    keep = T >= T[-1] - 0.5 * (T[-1] - T[0])
    T, P = T[keep], P[keep]
    dT, dP = np.diff(T), np.diff(P)
    ok = (dT > 0) & (dP != 0)
    if ok.sum() < 2:
        return float(P[-1]), math.nan
    Tm, slope = 0.5 * (T[1:] + T[:-1])[ok], (dP / dT)[ok]
    fit = np.polyfit(Tm, np.log(np.abs(slope)), 1)
    lam = -fit[0]
    if not lam > 0:
        return float(P[-1]), math.nan
    return float(P[-1] + slope[-1] / lam * math.exp(-lam * (T[-1] - Tm[-1]))), float(lam)


def switch_period_doubling(prob: OrbitProblem, br: continuation.Branch, label: str, *, h: float = 0.02,
                           options: continuation.Options | None = None):
    """Continue the orbit of twice the period emanating from the period-doubling point ``label`` of ``br``.

    In the problem of period 2T (the orbit traversed twice: 2m segments, or the mesh twice) the PD orbit is a
    branch point whose second kernel direction is the PD eigenvector v (M v = -v), propagated along the orbit:
    +v(t) on the first pass, -v(t) on the second. The corrector with the constraint along that direction lands on
    the doubled orbit. Returns (Branch, doubled problem); ParameterError if it falls back onto the old one.
    """
    labels = [sp.label for sp in br.special_points]
    if label not in labels:
        raise ParameterError(f"no special point {label!r} on the branch; it has {', '.join(labels) or 'none'}")
    sp = br.special_points[labels.index(label)]
    if sp.kind != "period_doubling":
        raise ParameterError(f"{label} is a {sp.kind} point; give a period-doubling point (PD)")
    prob.use(br.points[sp.index].discretisation)
    u = sp.u
    ev = prob._evaluate(u)
    vals, vecs = np.linalg.eig(ev["M"])
    v = vecs[:, np.argmin(np.abs(vals + 1.0))].real
    v /= np.linalg.norm(v / prob.system.state_scale)
    along = prob.propagate(u, v)
    double, u2 = prob.doubled(u)
    d = double.pack(np.vstack([along, -along]), 0.0, 0.0) / double.scale
    d /= np.linalg.norm(d)
    options = options or br.options
    double.set_reference(u2)
    v0 = u2 / double.scale
    half = len(along)
    for sign in (1.0, -1.0):
        start, _ = continuation.correct(double, (v0 + sign * h * d) * double.scale, (sign * d, v0, h), options)
        if start is None:
            continue
        Xs = double.split(start)[0]
        gap = np.max(np.abs(Xs[0] - Xs[half]) / np.asarray(prob.system.state_scale))
        if gap > 1e-3 * h:
            branch = continuation.continue_branch(double, start, options, tangent=sign * d)
            _mark_period_limit(double, branch)
            return branch, double
    raise ParameterError(f"no orbit of twice the period found next to {label} (the corrector fell back onto the "
                         "old orbit); try a larger h")


# ---------------------------------------------------------------------------- the start at a Hopf point


def _critical_pair(J: np.ndarray, scale: np.ndarray) -> tuple[float, np.ndarray]:
    """(omega, q) of the eigenvalue pair nearest the imaginary axis: J q = i omega q, |q / scale| = 1."""
    vals, vecs = np.linalg.eig(J)
    tiny = 1e-9 * max(1.0, np.abs(vals).max())
    upper = np.flatnonzero(vals.imag > tiny)
    if not upper.size:
        raise ParameterError("the equilibrium has no complex eigenvalue pair: not a Hopf point")
    i = upper[np.argmin(np.abs(vals[upper].real))]
    if abs(vals[i].real) > 1e-6 * abs(vals[i]):
        raise ParameterError(f"the critical eigenvalues {vals[i]:.6g} are not on the imaginary axis: give a Hopf "
                             "point (a located HOPF point of a branch)")
    q = vecs[:, i] / np.linalg.norm(vecs[:, i] / scale)
    return float(vals[i].imag), q


def hopf_start(system: System, state, pars, parameter: str, *, method: str = DEFAULT_METHOD,
               bounds: dict | None = None, period_max: float | None = None, ds: float = 0.01,
               parameter_scale: float = 1.0, tol: float = TAYLOR_TOL, options: continuation.Options | None = None,
               **discretisation) -> tuple[OrbitProblem, np.ndarray, np.ndarray]:
    """(problem, u, tangent): the first orbit of the branch born at the Hopf point (``state``, ``pars``) in
    ``parameter``, at scaled arclength ``ds`` from the zero-amplitude orbit along the Hopf tangent (module
    docstring), and the tangent to continue along. ``bounds`` {"T" or parameter: (low, high)}; ``method`` and
    its ``discretisation`` options: :mod:`.discretisations` (shooting: 4 segments, the integral phase
    condition)."""
    pars = system.with_pars(pars)
    k = system.parameter_index(parameter)
    state = np.asarray(state, dtype=float)
    omega, q = _critical_pair(system.jacobian(state, pars), system.state_scale)
    period = 2 * math.pi / omega
    bounds = dict(bounds or {})
    if period_max is not None:
        bounds["T"] = (0.0, float(period_max))
    prob = make_problem(method, system, pars, default_segments=4, default_phase="integral", parameter=parameter,
                        parameter_scale=parameter_scale, period_scale=period_scale(method, period), bounds=bounds,
                        tol=tol, **discretisation)
    tau = prob.node_times
    base = prob.pack(np.tile(state, len(tau)), period, pars[k])
    rotation = (q[None, :] * np.exp(2j * math.pi * tau)[:, None]).real  # Re(q e^{i omega t}) at the nodes
    tangent = prob.pack(rotation, 0.0, 0.0) / prob.scale
    tangent /= np.linalg.norm(tangent)
    options = options or continuation.Options()
    v0 = base / prob.scale
    for step in ds * 0.5 ** np.arange(6):  # a smaller first orbit if the corrector fails
        guess = (v0 + step * tangent) * prob.scale
        prob.set_reference(guess)
        u, _it = continuation.correct(prob, guess, (tangent, v0, step), options)
        if u is not None:
            return prob, u, tangent
    raise ParameterError(f"{system.name}: no periodic orbit next to the Hopf point at {parameter} = {pars[k]:.8g} "
                         "(the corrector failed for every first step); check that it is a Hopf point")


VERTICAL_SPAN = 1e-6  # a branch from a Hopf point whose parameter moves less than this (relative) is looked at


def _explain_stall(system: System, state, pars, parameter: str, br: continuation.Branch) -> None:
    """A branch from a Hopf point that stalled, failed or barely moved at its parameter value: if the point is
    degenerate (l1 = 0 to round-off) the orbits form a vertical family there (status ``degenerate``), not a
    branch in the parameter."""
    J, B, C = (system.field().tensor(state, pars, k, with_parameters=False) for k in (1, 2, 3))
    nf = normal_forms.first_lyapunov_coefficient(J, B, C)
    if not nf["degenerate"]:
        return
    value = pars[system.parameter_index(parameter)]
    br.status = "degenerate"
    br.message = (f"the Hopf point at {parameter} = {value:.10g} is degenerate (l1 = {nf['l1']:.2g}, its terms "
                  f"{nf['scale']:.2g}): the orbits form a vertical family at that value (a centre, as where the "
                  f"system is conservative) and no branch in {parameter} emanates; the {len(br.points)} orbits "
                  "computed lie on that family (start from an orbit off the point: find_orbit, continue_orbits)")


def orbit_branch(system: System, branch: xr.Dataset, label: str, *, bounds, method: str = DEFAULT_METHOD,
                 period_max: float | None = None, parameter_scale: float = 1.0, marks=(),
                 options: continuation.Options | None = None, n_samples: int = N_SAMPLES,
                 end_at_events: bool = False, **keywords) -> xr.Dataset:
    """The branch of periodic orbits born at Hopf point ``label`` of ``branch`` (a dataset of
    :func:`.branches.equilibrium_branch` for ``system``), continued in the branch's parameter within ``bounds``
    = (low, high), with its special points; ``period_max`` stops it at that period (the approach to a
    homoclinic orbit is reported with its extrapolated parameter); ``marks``: parameter values where the orbits
    are computed exactly (user points UZ1, ...); ``end_at_events``: the branch ends at the first orbit that reaches
    a terminal event of the System (e.g. a model's edge; else that orbit is marked EVENT and the branch goes on);
    ``method``: collocation (``ntst``, ``ncol``, ``adapt``,
    ``error_tol``, ``ntst_max``) or shooting (``segments``, ``phase``); the other ``keywords`` are those of
    :class:`.continuation.Options` (ds, ds_max, max_points, ...). A dataset of kind ``periodic_orbits``."""
    index, kind = special_point(branch, label)
    if kind != "hopf":
        raise ParameterError(f"{label} is a {kind} point; periodic orbits are born at a Hopf point")
    parameters = branch.attrs.get("parameters", "").split()
    if len(parameters) != 1:
        raise ParameterError(f"{label} lies on a curve in {', '.join(parameters)}; give a branch in one parameter")
    parameter = parameters[0]
    state, pars = point_of(branch, system, index)
    return hopf_branch(system, state, pars, parameter, bounds=bounds, method=method, period_max=period_max,
                       parameter_scale=parameter_scale, marks=marks, options=options, n_samples=n_samples,
                       config={"source_label": label}, end_at_events=end_at_events, **keywords)


def hopf_branch(system: System, state, pars, parameter: str, *, bounds, method: str = DEFAULT_METHOD,
                period_max: float | None = None, parameter_scale: float = 1.0, marks=(),
                options: continuation.Options | None = None, n_samples: int = N_SAMPLES, config: dict | None = None,
                end_at_events: bool = False, **keywords) -> xr.Dataset:
    """The branch of periodic orbits born at the Hopf point (``state``, ``pars``) in ``parameter``, as
    :func:`orbit_branch` (which finds the point on an equilibrium branch); ``config``: more provenance."""
    pars = system.with_pars(pars)
    low, high = bounds_pair(bounds, parameter)
    discretisation, option_keywords = method_options(keywords)
    if options is not None and option_keywords:
        raise ParameterError("give either options=Options(...) or the option keywords (ds, ds_max, ...), not both")
    options = options or continuation.Options(**(BRANCH_OPTIONS[check_method(method)] | option_keywords))
    prob, u, tangent = hopf_start(system, state, pars, parameter, method=method, bounds={parameter: (low, high)},
                                  period_max=period_max, parameter_scale=parameter_scale, options=options,
                                  **discretisation)
    prob.end_at_events(end_at_events)
    br = continuation.continue_branch(prob, u, options, tangent=tangent, marks=marks)
    _mark_period_limit(prob, br)
    values = np.array([prob.split(p.u)[2] for p in br.points])
    hopf_value = pars[system.parameter_index(parameter)]
    if br.status in ("stalled", "corrector_failed") or np.ptp(values) <= VERTICAL_SPAN * (1 + abs(hopf_value)):
        _explain_stall(system, state, pars, parameter, br)  # a vertical family at a degenerate Hopf point?
    return branch_dataset(prob, br, {"source": "hopf", **(config or {}), "hopf_state": list(map(float, state)),
                                     "hopf_value": float(pars[system.parameter_index(parameter)]),
                                     "system_key": system.key}, n_samples)
