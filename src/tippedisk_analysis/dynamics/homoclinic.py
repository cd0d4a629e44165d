"""Homoclinic orbits of a saddle with a one-dimensional unstable (or stable) manifold (generic: knows nothing of
the disk).

Follow the one-dimensional manifold's branch from the saddle x_s, forward in time if it is the unstable
manifold, backward if it is the stable one. If it comes back near the saddle (``shift``: at x_s + shift, an
angle gone once round), it leaves again along the same one-dimensional direction, because every other
direction contracts there (in the branch's time). It leaves on the side sign(u), u = l . (x - x_s) with l the
left eigenvector of that direction. u changes sign where the branch lies in the complementary manifold: that is
a homoclinic orbit, of codimension one in the parameters (:func:`manifold_return`, :func:`homoclinic_point`).

The side is exact (no bias from the size of the neighbourhood), so bisection on it locates the parameter to any
tolerance. It checks itself: the time the branch spends near the saddle grows like ln(1 / abs(p - p_h)) / lambda_1
as p -> p_h, which a jump between two different returns does not do. With eigenvalues on the imaginary axis
(a saddle-centre), a return is a connection to the centre-stable manifold, a homoclinic orbit only where a
symmetry forces it; such points have status ``not_hyperbolic``.
"""

from __future__ import annotations

import copy
import math
import numbers
from dataclasses import dataclass

import heyoka as hy
import numpy as np
import xarray as xr

from ..errors import ParameterError
from .branches import bounds_pair
from .system import System

MANIFOLDS = {"unstable": 1.0, "stable": -1.0}  # the time direction in which the branch is followed
CENTRE_TOL = 1e-9  # |Re s| below this times max |s|: a centre eigenvalue
STAY_FACTOR = 8.0  # a located orbit stays near the saddle at least this many times 1/lambda_1 at the bracket ends
NEWTON_TOL = 1e-12  # the saddle is refined by Newton's method to this scaled residual
TOL = 1e-13  # Taylor tolerance
ESCAPE = 1e3  # scaled distance from the saddle at which a branch counts as gone for good
MAX_STEPS = 200_000  # Taylor steps per branch
INTERIOR_POINTS = 8  # homoclinic_point looks at this many points inside a bracket with an end of undefined side
ADVICE = {"never_left": "give a smaller radius: the loop stays within LEAVE radius of the saddle",
          "stayed": "give a larger t_max", "no_return": "give a larger radius or t_max, or narrow the bracket",
          "escaped": "narrow the bracket", "failed": "the step budget ran out; narrow the bracket"}
"""What to try when the branch's side is not defined, by its Return status."""
CURVE_WIDENINGS = 4  # homoclinic_curve widens a bracket without a change of side up to 2**4 times
FOLLOW_STEPS = 8  # Newton steps in which the saddle is followed from one parameter value to the next
LEAVE = 10.0  # the branch has left the saddle once it is this many radii from it; then its return counts


@dataclass(frozen=True)
class Return:
    """How the branch came back.

    side: +1 if it left the saddle's neighbourhood again on the side of the branch it started on, -1 on the other
    side, 0 if it did not (for ``no_return`` and ``escaped`` the side of its closest approach, a guess that guides
    the bisection); status: ``returned``, ``no_return`` (not back within radius by t_max), ``stayed`` (back, but
    not gone again by t_max), ``escaped`` (to infinity, or a non-finite state, before coming back),
    ``never_left`` (never LEAVE radius away from the saddle by t_max: a loop smaller than that) or ``failed`` (the
    step budget ran out); time: of the return [system time]; stay: the time from it until the branch is
    2 radius away along the one-dimensional direction; closest: the least scaled distance to the saddle on the
    way back."""

    side: int
    status: str
    time: float
    stay: float
    closest: float


def saddle(system: System, state, pars, manifold: str = "unstable") -> tuple:
    """(x_s refined by Newton's method, eigenvalues, the one-dimensional direction v (scaled norm 1, its largest
    scaled component positive), its left eigenvector l with l . v = 1, lambda_1, the number of centre
    eigenvalues) of the equilibrium near ``state``.
    ParameterError unless exactly one eigenvalue has the sign of ``manifold``."""
    if manifold not in MANIFOLDS:
        raise ParameterError(f"manifold = {manifold!r}: choose one of {', '.join(MANIFOLDS)}")
    try:
        x = np.array(state, dtype=float)
    except (TypeError, ValueError):
        x = None
    if x is None or x.shape != (system.n,):
        raise ParameterError(f"state = {state!r}: give the saddle as {system.n} numbers "
                             f"({', '.join(system.state_names)})")
    scale = system.state_scale
    for _ in range(30):
        f = system.f(x, pars)
        if not np.max(np.abs(f / scale)) >= NEWTON_TOL:  # converged, or a non-finite state
            break
        try:
            x = x - np.linalg.solve(system.jacobian(x, pars), f)
        except np.linalg.LinAlgError:
            break
    if not np.max(np.abs(system.f(x, pars) / scale)) < NEWTON_TOL:
        raise ParameterError(f"no equilibrium of {system.name} near {np.array2string(np.asarray(state))}: Newton's "
                             "method did not converge; give a state closer to the saddle")
    J = system.jacobian(x, pars)
    w, V = np.linalg.eig(J)
    wl, W = np.linalg.eig(J.T)
    size = np.max(np.abs(w))
    sign = MANIFOLDS[manifold]
    centre = np.abs(w.real) <= CENTRE_TOL * size
    chosen = np.flatnonzero((sign * w.real > 0) & ~centre)
    if len(chosen) != 1 or abs(w[chosen[0]].imag) > CENTRE_TOL * size:
        raise ParameterError(f"the equilibrium's {manifold} manifold is {len(chosen)}-dimensional (eigenvalues "
                             f"{np.array2string(w, precision=4)}); give a saddle whose {manifold} manifold is "
                             "one-dimensional, or follow the other manifold")
    k = chosen[0]
    v = V[:, k].real / np.linalg.norm(V[:, k].real / scale)
    v = v * math.copysign(1.0, v[int(np.argmax(np.abs(v / scale)))])  # its largest scaled component positive
    l_ = W[:, int(np.argmin(np.abs(wl - w[k])))].real
    return x, w, v, l_ / (l_ @ v), float(w[k].real), int(centre.sum())


def _positive(name: str, value) -> None:
    if isinstance(value, bool) or not (isinstance(value, numbers.Real) and math.isfinite(value) and value > 0):
        raise ParameterError(f"{name} = {value!r}: give a positive number")


def _checked(system: System, shift, radius, offset, t_max) -> np.ndarray:
    """The shift as a state vector; ParameterError for a bad shift, radius, offset or t_max."""
    for name, value in (("radius", radius), ("offset", offset), ("t_max", t_max)):
        _positive(name, value)
    if shift is None:
        return np.zeros(system.n)
    try:
        shift = np.array(shift, dtype=float)
    except (TypeError, ValueError):
        shift = None
    if shift is None or shift.shape != (system.n,) or not np.all(np.isfinite(shift)):
        raise ParameterError(f"shift: give {system.n} finite numbers, one per state ({', '.join(system.state_names)}),"
                             " e.g. an angle's 2 pi and zeros")
    return shift


class _SaddleTrack:
    """The saddle near ``state`` at ``pars``, followed in ``parameter`` by Newton's method in FOLLOW_STEPS steps
    from the nearest value already done."""

    def __init__(self, system: System, state, parameter: str, pars, manifold: str):
        self.system, self.manifold = system, manifold
        self.index = system.parameter_index(parameter)
        self.base = system.with_pars(pars)
        self.done = [(self.base[self.index], saddle(system, state, self.base, manifold)[0])]

    def at(self, value: float) -> tuple[np.ndarray, np.ndarray]:
        """(the saddle, the parameter vector) at ``value``."""
        start, xs = min(self.done, key=lambda vs: abs(vs[0] - value))
        pars = self.base.copy()
        for step in np.linspace(start, value, FOLLOW_STEPS + 1)[1:]:
            pars[self.index] = step
            try:
                xs = saddle(self.system, xs, pars, self.manifold)[0]
            except ParameterError as exc:
                raise ParameterError(f"the saddle was lost at {self.system.parameter_names[self.index]} = {step:.10g} "
                                     f"({exc}); narrow the bracket") from None
        self.done.append((value, xs))
        return xs, pars


def manifold_return(system: System, state, pars=None, *, manifold: str = "unstable", branch: float | str = 1.0,
                    shift=None, radius: float = 0.05, offset: float = 1e-7, t_max: float = 200.0) -> Return:
    """Follow one branch of the one-dimensional ``manifold`` of the saddle near ``state`` and report how it comes
    back within ``radius`` (scaled distance) of the saddle (+ ``shift``). ``branch``: +1 or -1, the side of the
    eigenvector v of :func:`saddle`, or "+name" / "-name", the side on which state ``name`` grows or falls;
    ``offset``: the start's scaled distance from the saddle; ``t_max``: in the system's time. The other
    directions only contract near the saddle, so the branch leaves it along the one-dimensional one; ``radius``
    must exceed what is left of them when the branch comes back (the side itself does not depend on it)."""
    shift = _checked(system, shift, radius, offset, t_max)
    pars = system.with_pars(pars)
    xs, _w, v, l_, lam, _centre = saddle(system, state, pars, manifold)
    branch = _branch_sign(system, branch, v)
    target = xs + shift
    scale = system.state_scale
    ta = copy.deepcopy(system.taylor(TOL))
    ta.time = 0.0
    ta.pars[:] = np.asarray(pars, dtype=float)[: len(ta.pars)]
    ta.state[:] = xs + offset * branch * v
    direction = MANIFOLDS[manifold]
    max_step = direction * 0.25 / abs(lam)  # a step moves u by at most a factor e^0.25 near the saddle

    def distance(x, to):
        return float(np.max(np.abs((x - to) / scale)))

    left = distance(np.asarray(ta.state), target) > LEAVE * radius
    closest, side_closest, entered_at, steps, farthest = math.inf, 0, None, 0, 0.0
    while abs(ta.time) < t_max:
        outcome = ta.step(max_step)[0]
        x, steps = np.asarray(ta.state), steps + 1
        d = distance(x, target)
        blown_up = outcome == hy.taylor_outcome.err_nf_state or not d < ESCAPE
        if entered_at is None and blown_up:
            return Return(side_closest, "escaped", math.nan, 0.0, closest)
        if outcome not in (hy.taylor_outcome.success, hy.taylor_outcome.time_limit) or steps > MAX_STEPS:
            return Return(0, "failed", abs(ta.time), 0.0, closest)
        if not left:
            left = distance(x, xs) > LEAVE * radius and d > LEAVE * radius
            continue
        farthest = max(farthest, d)
        if d < closest and d < 0.5 * farthest:  # on the way back, not on the way out
            closest, side_closest = d, int(math.copysign(1.0, branch * (l_ @ (x - target))))
        if entered_at is None and d < radius:
            entered_at = abs(ta.time)
        elif entered_at is not None and (abs(u := branch * float(l_ @ (x - target))) > 2 * radius
                                         or d > LEAVE * radius):
            return Return(int(math.copysign(1.0, u)), "returned", entered_at, abs(ta.time) - entered_at, closest)
    if not left:
        return Return(0, "never_left", math.nan, 0.0, closest)
    if entered_at is None:
        return Return(side_closest, "no_return", math.nan, 0.0, closest)
    return Return(0, "stayed", entered_at, abs(ta.time) - entered_at, closest)


def manifold_branch(system: System, state, pars=None, *, manifold: str = "unstable", branch: float | str = 1.0,
                    duration: float = 1.0, samples: int = 400, offset: float = 1e-7) -> tuple[np.ndarray, np.ndarray]:
    """(times, states (samples, n)) along the branch of :func:`manifold_return` for ``duration`` (backward in
    time for the stable manifold: times fall from 0), e.g. to draw a located homoclinic orbit."""
    _positive("offset", offset)
    _positive("duration", duration)
    if isinstance(samples, bool) or not (isinstance(samples, numbers.Integral) and samples >= 2):
        raise ParameterError(f"samples = {samples!r}: give a whole number of at least 2")
    pars = system.with_pars(pars)
    xs, _w, v, _l, _lam, _centre = saddle(system, state, pars, manifold)
    ta = copy.deepcopy(system.taylor(TOL))
    ta.time = 0.0
    ta.pars[:] = np.asarray(pars, dtype=float)[: len(ta.pars)]
    ta.state[:] = xs + offset * _branch_sign(system, branch, v) * v
    times = MANIFOLDS[manifold] * np.linspace(0.0, float(duration), int(samples))
    result = ta.propagate_grid(times, max_steps=MAX_STEPS)
    states = np.asarray(result[-1])
    if result[0] != hy.taylor_outcome.time_limit or len(states) != len(times) or not np.all(np.isfinite(states)):
        raise ParameterError(f"the branch stopped ({result[0]!r}) at t = {ta.time:.6g} of {times[-1]:.6g}; give a "
                             "shorter duration")
    return times, states


def homoclinic_point(system: System, state, parameter: str, bracket, pars=None, *, manifold: str = "unstable",
                     branch: float | str = 1.0, shift=None, radius: float = 0.05, offset: float = 1e-7,
                     t_max: float = 200.0, xtol: float = 1e-10) -> dict:
    """The value of ``parameter`` in ``bracket`` at which the branch of :func:`manifold_return` is a homoclinic
    orbit, by bisection on the side it leaves on. ``state``: the saddle (roughly) at ``pars``; it is followed to
    each value by Newton's method in small steps. Checks itself: at the final bracket's ends the branch
    returns, leaves on opposite sides, and stays near the saddle at least STAY_FACTOR / lambda_1; the side at
    both ends is the same with the offset ten times smaller. Far from the point, where the branch does not come
    back within ``radius``, the side of its closest approach guides the bisection.

    ``xtol``: the final bracket's width relative to max(1, abs(value)). If the side is not defined at an end of the
    bracket, INTERIOR_POINTS inside it are tried. {"value", "status", "message", "saddle" and "eigenvalues" (at
    the point), "lambda_1", "return_time", "stay", "evaluations"}; status ``completed``, ``no_crossing`` (the
    same side, or an undefined one, at the ends of the bracket and at the points inside), ``not_verified`` (a
    check failed) or ``not_hyperbolic`` (the saddle has centre eigenvalues: a connection to its centre-stable
    manifold)."""
    low, high = bounds_pair(bracket, parameter)
    if isinstance(xtol, bool) or not (isinstance(xtol, numbers.Real) and math.isfinite(xtol) and xtol > 0):
        raise ParameterError(f"xtol = {xtol!r}: give a positive number (the bracket's final width relative to "
                             "max(1, abs(value)))")
    _checked(system, shift, radius, offset, t_max)
    track = _SaddleTrack(system, state, parameter, pars, manifold)
    count = 0

    def run(value, off=offset):
        nonlocal count
        count += 1
        xs, p = track.at(value)
        return manifold_return(system, xs, p, manifold=manifold, branch=branch, shift=shift, radius=radius,
                               offset=off, t_max=t_max)

    result = {"value": math.nan, "saddle": np.full(system.n, math.nan), "eigenvalues": np.full(system.n, math.nan + 0j),
              "lambda_1": math.nan, "return_time": math.nan, "stay": math.nan}
    ends = run(low), run(high)
    if 0 in (ends[0].side, ends[1].side):  # an end where the side is undefined: look inside for a change of side
        inside = np.linspace(low, high, INTERIOR_POINTS + 2)
        sides = [ends[0], *(run(v) for v in inside[1:-1]), ends[1]]
        pairs = [k for k in range(len(sides) - 1) if sides[k].side * sides[k + 1].side < 0]
        if pairs:
            k = pairs[0]
            low, high, ends = inside[k], inside[k + 1], (sides[k], sides[k + 1])
    if not (ends[0].side * ends[1].side < 0):
        said = "; ".join(f"at {v:.10g} it {r.status}" + (f" on side {r.side:+d}" if r.side else f" ({ADVICE[r.status]})"
                         if r.status in ADVICE else "") for v, r in zip((low, high), ends))
        return {**result, "status": "no_crossing", "evaluations": count,
                "message": f"no change of side in {parameter}: {said}"}
    floor = False
    while high - low > xtol * max(1.0, abs(low)):
        mid = 0.5 * (low + high)
        if not low < mid < high:
            floor = True
            break
        r = run(mid)
        if r.side == 0:
            return {**result, "value": mid, "status": "not_verified", "evaluations": count,
                    "message": f"at {parameter} = {mid:.12g} the branch {r.status}: the side is not defined there ("
                               f"{ADVICE.get(r.status, 'narrow the bracket')})"}
        if r.side == ends[0].side:
            low, ends = mid, (r, ends[1])
        else:
            high, ends = mid, (ends[0], r)
    value = 0.5 * (low + high)
    xs, w, _v, _l, lam, centre = saddle(system, *track.at(value), manifold)
    result.update(value=value, saddle=xs, eigenvalues=w, lambda_1=lam, return_time=0.5 * (ends[0].time + ends[1].time),
                  stay=min(r.stay for r in ends), evaluations=count)
    small = run(low, offset / 10), run(high, offset / 10)
    problems = [f"at {parameter} = {v:.12g} the branch {r.status} (closest {r.closest:.3g}; "
                f"{ADVICE.get(r.status, 'narrow the bracket')})" for v, r in zip((low, high), ends)
                if r.status != "returned"]
    if result["stay"] * abs(lam) < STAY_FACTOR:
        problems.append(f"the branch stays near the saddle only {result['stay']:.3g} (lambda_1 {lam:.4g}): a jump "
                        "between two returns, not a homoclinic orbit")
    if [r.side for r in small] != [r.side for r in ends]:
        problems.append(f"with the offset {offset / 10:g} the sides at the ends are {[r.side for r in small]}, "
                        f"not {[r.side for r in ends]}: the bracket ({high - low:.3g} wide) is narrower than the "
                        "integration resolves; give a larger xtol (or a smaller offset)")
    if problems:
        return {**result, "status": "not_verified", "message": "; ".join(problems)}
    accuracy = f" (to {high - low:.2g}, the floating-point floor)" if floor else ""
    if centre:
        return {**result, "status": "not_hyperbolic",
                "message": f"the saddle has {centre} centre eigenvalues: the branch returns to its centre-stable "
                           f"manifold at {parameter} = {value:.12g}{accuracy}, a homoclinic orbit only if a symmetry "
                           "forces it"}
    return {**result, "status": "completed",
            "message": f"homoclinic orbit at {parameter} = {value:.12g}{accuracy}, back after "
                       f"{result['return_time']:.6g}"}


def homoclinic_scan(system: System, state, parameter: str, values, pars=None, **keywords) -> xr.Dataset:
    """:func:`manifold_return` at each of ``values`` of ``parameter`` (the saddle followed along them), and every
    change of side between neighbours located by :func:`homoclinic_point` (keywords: both functions'). Variables
    over ``value``: side, return_status, closest; over ``crossing``: the located value, its status, stay,
    return time and message.
    A homoclinic orbit between two values with the same side (an even number of crossings) is not seen."""
    values = _values(values, parameter)
    point_keywords = {k: keywords.pop(k) for k in ("xtol",) if k in keywords}
    track = _SaddleTrack(system, state, parameter, pars, keywords.get("manifold", "unstable"))
    returns = []
    for value in values:
        xs, p = track.at(value)
        returns.append(manifold_return(system, xs, p, **keywords))
    crossings = []
    for k in range(len(values) - 1):
        if returns[k].side * returns[k + 1].side < 0:
            xs, p = track.at(values[k])
            crossings.append(homoclinic_point(system, xs, parameter, values[k: k + 2], p, **keywords,
                                              **point_keywords))
    ds = xr.Dataset({"side": ("value", [r.side for r in returns]),
                     "return_status": ("value", [r.status for r in returns]),
                     "closest": ("value", [r.closest for r in returns]),
                     "crossing_value": ("crossing", [c["value"] for c in crossings]),
                     "crossing_status": ("crossing", np.array([c["status"] for c in crossings], dtype=str)),
                     "crossing_stay": ("crossing", [c["stay"] for c in crossings]),
                     "crossing_return_time": ("crossing", [c["return_time"] for c in crossings]),
                     "crossing_message": ("crossing", np.array([c["message"] for c in crossings], dtype=str))},
                    coords={"value": values})
    ds["value"].attrs = {"long_name": parameter, "units": system.units_of(parameter)}
    ds["side"].attrs = {"long_name": "+1: the branch left the saddle again on its own side; -1: on the other"}
    ds["closest"].attrs = {"long_name": "least scaled distance to the saddle on the way back", "units": "1"}
    ds["crossing_stay"].attrs = {"units": system.time_units}
    ds["crossing_return_time"].attrs = {"units": system.time_units}
    ds.attrs = {"title": f"homoclinic scan of {system.name} in {parameter}", "system": system.name,
                "manifold": keywords.get("manifold", "unstable")}
    return ds


def homoclinic_curve(system: System, state, parameter: str, second: str, values, bracket, pars=None,
                     **keywords) -> xr.Dataset:
    """The homoclinic orbit of :func:`homoclinic_point` continued in a ``second`` parameter over ``values`` (in
    order; ``pars`` holds the first one): at each value it is located in a bracket as wide as ``bracket``, centred
    on the value extrapolated from the previous points, from the previous point's saddle; if the side does not
    change there, in one 2, 4, ... 2**CURVE_WIDENINGS times as wide (which may find another homoclinic orbit).
    Variables over ``point``: ``parameter``, ``second``, status, message, return_time, stay, lambda_1 and the
    saddle's eigenvalues."""
    values = _values(values, second)
    index, second_index = system.parameter_index(parameter), system.parameter_index(second)
    if index == second_index:
        raise ParameterError(f"second = {second!r} is the parameter the orbit is located in; give another one")
    low, high = bounds_pair(bracket, parameter)
    width, found, points = high - low, [], []
    p = system.with_pars(pars)
    for value in values:
        p[second_index] = value
        if found:
            (s1, h1), (s0, h0) = found[-1], found[-2] if len(found) > 1 else found[-1]
            centre = h1 + ((h1 - h0) * (value - s1) / (s1 - s0) if s1 != s0 else 0.0)
            low, high = centre - 0.5 * width, centre + 0.5 * width
            p[index] = h1
        for widening in range(CURVE_WIDENINGS + 1):  # no change of side: the bracket, 2, 4, ... times as wide
            half = 0.5 * (high - low) * 2 ** widening
            point = homoclinic_point(system, state, parameter, (0.5 * (low + high) - half, 0.5 * (low + high) + half),
                                     p, **keywords)
            if point["status"] != "no_crossing":
                break
        points.append(point)
        if point["status"] in ("completed", "not_hyperbolic"):
            found.append((value, point["value"]))
            state = point["saddle"]
    w = np.array([pt["eigenvalues"] for pt in points])
    ds = xr.Dataset({parameter: ("point", [pt["value"] for pt in points]), second: ("point", values),
                     "status": ("point", np.array([pt["status"] for pt in points], dtype=str)),
                     "message": ("point", np.array([pt["message"] for pt in points], dtype=str)),
                     "return_time": ("point", [pt["return_time"] for pt in points]),
                     "stay": ("point", [pt["stay"] for pt in points]),
                     "lambda_1": ("point", [pt["lambda_1"] for pt in points]),
                     "eigenvalue_real": (("point", "eigenvalue"), w.real),
                     "eigenvalue_imag": (("point", "eigenvalue"), w.imag)})
    ds[parameter].attrs = {"long_name": f"{parameter} of the homoclinic orbit", "units": system.units_of(parameter)}
    ds[second].attrs = {"long_name": second, "units": system.units_of(second)}
    ds["status"].attrs = {"long_name": "completed, not_hyperbolic, not_verified or no_crossing"}
    for name in ("return_time", "stay"):
        ds[name].attrs = {"units": system.time_units}
    ds.attrs = {"title": f"homoclinic orbit of {system.name} in ({parameter}, {second})", "system": system.name,
                "manifold": keywords.get("manifold", "unstable")}
    return ds


def _branch_sign(system: System, branch, v: np.ndarray) -> float:
    """+1 or -1: the multiple of v that starts ``branch`` (+1, -1, or "+name" / "-name": state ``name`` grows
    or falls)."""
    if isinstance(branch, str):
        if branch[:1] not in ("+", "-") or branch[1:] not in system.state_names:
            raise ParameterError(f"branch = {branch!r}: give +1, -1 or '+name' / '-name' with a state name of "
                                 f"{system.name} ({', '.join(system.state_names)})")
        component = v[system.state_index(branch[1:])]
        if component == 0.0:
            raise ParameterError(f"branch = {branch!r}: {branch[1:]} does not move along the manifold; use +1 or -1")
        return math.copysign(1.0, component) * (1.0 if branch[0] == "+" else -1.0)
    if isinstance(branch, bool) or not (isinstance(branch, numbers.Real) and branch in (1, -1)):
        raise ParameterError(f"branch = {branch!r}: give +1, -1 or '+name' / '-name'")
    return float(branch)


def _values(values, name: str) -> np.ndarray:
    try:
        values = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        values = np.array([math.nan])
    if values.ndim != 1 or len(values) == 0 or not np.all(np.isfinite(values)):
        raise ParameterError(f"values of {name}: give a one-dimensional sequence of finite numbers")
    return values
