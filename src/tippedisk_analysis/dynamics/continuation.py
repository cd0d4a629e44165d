"""Pseudo-arclength continuation (PALC) of solution curves F(u) = 0, with detection and location
of special points (branch switching: :mod:`.switching`). Generic: it knows nothing of the disk.

A :class:`Problem` supplies the unknowns u (states, then parameters), the residual F(u) and its
Jacobian F_u, the square "state Jacobian" whose eigenvalues decide stability (for a system with
a family of equilibria, the matrix with the family's structural zero deflated), and, for branch
switching, second directional derivatives. F may have more rows than n - 1 if it is consistent
(a family of equilibria makes rows dependent): steps are least-squares (Gauss-Newton) steps,
which converge quadratically to zero-residual solutions.

Algorithm (as in AUTO / BifurcationKit): scaled unknowns v = u / scale; tangent t = null vector
of F_u diag(scale) (smallest right singular vector), oriented along the previous one; predictor
v_k + ds t_k; corrector: Gauss-Newton on [F(v); t_k . (v - v_k) - ds]; adaptive ds (grow after
an easy correction, halve after a failure, stop below ds_min with a status); stop at parameter
bounds (located exactly), after max_points, or on a singular corrector. A branch says how it ended
(:attr:`Branch.status`): ``completed`` only at a bound or a terminal special point; ``max_points`` when the
point budget ran out; ``stalled`` when STALL_POINTS consecutive points moved the first free parameter by
less than STALL_TOL (relative): the branch is vertical there (a degenerate point, a family at one parameter
value) or creeps; ``corrector_failed``; ``singular`` where a linear system is singular (numpy's LinAlgError),
with the points so far kept.

Special points (test functions on the eigenvalues s_i of the state Jacobian):

* ``zero``: det changes sign (a real eigenvalue through 0). It is a **fold** (limit point) if the
  tangent's parameter component changes sign too, otherwise a **branch point**;
* ``hopf``: prod_{i<j} (s_i + s_j) changes sign (the bialternate product) and the pair crossing
  the imaginary axis is complex (a real pair with s_i + s_j = 0, a neutral saddle, is skipped).

Each is located along the arclength by Brent's method on a smooth function in eigenvalue units
(the real eigenvalue nearest 0; the real part of the complex pair nearest the imaginary axis;
the tangent's parameter component for folds) to |value| < ``locate_tol``, and inserted into
the branch as its own point. Problems may define their own test functions (``tests``,
``located_value``, ``accept``; e.g. on Floquet multipliers), a moving reference
(``set_reference``) and special points at which a branch ends (``terminal``).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from scipy.optimize import brentq

from ..errors import ParameterError
from .continuation_interface import Branch, Options, Point, Problem, SpecialPoint
from .detection import LABELS, label_points  # noqa: F401 (the labels belong to the core's interface)
from .linear_algebra import null_vector

START_TOL = 1e-6  # a start point's residual, relative to the size of its terms (it is corrected first)
ZERO_RATIO = 1e-3  # a located test function is this much smaller than at the ends (a pole or a jump is not)
STALL_POINTS, STALL_TOL = 30, 1e-10  # a branch whose last 30 points moved p by < 1e-10 (1 + |p|) has stalled
CHORD_RATE = 0.1  # chord steps go on while each shrinks the step at least tenfold (else a new Jacobian)
MAX_REFINEMENTS = 2  # finer discretisations tried for one step (Problem.refine) before the step is shortened
FOLD_NOISE = 1e-9  # a sign change of the tangent's parameter component below this on both sides is no fold
STATUSES = ("completed", "max_points", "stalled", "corrector_failed", "singular")
RESULTS = frozenset({"completed", "max_points", "degenerate"})  # branch statuses that are results, not failures
# (``degenerate``: an orbit branch from a degenerate Hopf point, :mod:`.orbit_branches`)

# ----------------------------------------------------------------------------- linear algebra


def _tangent(problem: Problem, u: np.ndarray, previous: np.ndarray | None) -> np.ndarray:
    return null_vector(lambda row: problem.linearise(u, problem.scale, row), len(u), previous, problem.parameters)


# ----------------------------------------------------------------------------- corrector


def correct(problem: Problem, u_guess: np.ndarray, constraint: tuple[np.ndarray, np.ndarray, float] | None,
            options: Options) -> tuple[np.ndarray | None, int]:
    """Newton on F(u) = 0 (+ the arclength constraint t . (v - v0) = ds in scaled unknowns): Gauss-Newton
    steps with a dense Jacobian; where the problem's linearisation is a factorisation that serves again
    (collocation), chord steps that keep it while they converge fast (a new one when a step shrinks by less than
    CHORD_RATE).

    Converged when the error left after the last step (Gauss-Newton: the step; chord steps: step * rate /
    (1 - rate), rate = step / previous step) is below options.tol (relative) and every residual row is at the
    round-off level of its terms
    (1e-9 sum_j |A_ij v_j|). Returns (u, iterations); u None if not converged within options.max_newton steps.
    """
    scale = problem.scale
    row = None if constraint is None else constraint[0]

    def residual(v):
        F = problem.residual(v * scale)
        return F if constraint is None else np.append(F, constraint[0] @ (v - constraint[1]) - constraint[2])

    v = u_guess / scale
    previous, rate, lin = math.inf, 1.0, None
    for it in range(1, options.max_newton + 1):
        F = residual(v)
        if not np.all(np.isfinite(F)):
            return None, it
        try:
            if lin is None or not lin.reusable or rate > CHORD_RATE:
                lin = problem.linearise(v * scale, scale, row)
            step = lin.solve(-F)
        except np.linalg.LinAlgError:  # a linearisation with non-finite entries (e.g. a run that failed)
            return None, it
        if not np.all(np.isfinite(step)):
            return None, it
        v = problem.project((v + step) * scale) / scale
        size = float(np.max(np.abs(step)))
        rate, previous = size / previous, size
        # the error left: the step (Gauss-Newton), or estimated from the contraction (chord steps)
        remaining = size if it == 1 or not lin.reusable else (size * rate / (1.0 - rate) if rate < 1.0 else math.inf)
        if remaining <= options.tol * (1.0 + np.max(np.abs(v))):
            F = residual(v)
            if np.all(np.abs(F) <= 1e-9 * (1.0 + lin.magnitude(v))):
                return v * scale, it
    return None, options.max_newton


def solve_at(problem: Problem, u_guess: np.ndarray, index: int, value: float, options: Options = Options()):
    """The solution with unknown ``index`` fixed at ``value`` (e.g. a curve's point at a given parameter
    value), by Gauss-Newton from ``u_guess``; None if it does not converge."""
    e = np.zeros(len(u_guess))
    e[index] = 1.0
    return correct(problem, np.asarray(u_guess, dtype=float), (e, np.zeros(len(u_guess)), value / problem.scale[index]),
                   options)[0]


def _step_to(problem, point: Point, sigma: float, options: Options) -> np.ndarray | None:
    """The branch point at scaled arclength sigma beyond ``point`` (predictor + corrector)."""
    return _step(problem, point, sigma, options)[0]


def _step(problem, point: Point, sigma: float, options: Options, guess: np.ndarray | None = None):
    """(u, corrector iterations) at scaled arclength sigma beyond ``point``, from the predictor or ``guess``."""
    v0 = point.u / problem.scale
    start = (v0 + sigma * point.tangent) * problem.scale if guess is None else guess
    return correct(problem, start, (point.tangent, v0, sigma), options)


def _make_point(problem, u, previous_tangent, arclength, iterations, special="") -> Point:
    return Point(u, _tangent(problem, u, previous_tangent), arclength,
                 problem.state_eigenvalues(u), iterations, special, problem.discretisation())


# ----------------------------------------------------------------------------- the branch


def continue_branch(problem: Problem, u0: np.ndarray, options: Options = Options(), direction: int = 1,
                    tangent: np.ndarray | None = None, detect: bool = True,
                    on_point: Callable[[Point], None] | None = None, marks=()) -> Branch:
    """Continue the solution branch through u0 (corrected first) in ``direction`` (+1: the parameter
    increases initially, -1: decreases; ignored if ``tangent`` is given). ``marks``: values of the first free
    parameter at which the branch's points are located exactly and reported as special points ``user`` (UZ1,
    ..., AUTO's user points), every time the branch passes them."""
    u0 = np.asarray(u0, dtype=float)
    if not np.all(np.isfinite(u0)):
        raise ParameterError("the start point has non-finite entries; give finite values")
    problem.set_reference(u0)
    F = problem.residual(u0)
    allowed = START_TOL * (1.0 + problem.linearise(u0, np.ones(len(u0))).magnitude(u0))
    if not np.all(np.abs(F) <= allowed):
        worst = int(np.argmax(np.abs(F) / allowed))
        raise ParameterError(f"the start point is not a solution (residual {abs(F[worst]):.3g} in equation {worst}); "
                             "give a point on the branch, e.g. a stationary solution or a point of a dataset")
    u, iterations = correct(problem, u0, None, options)
    if u is None:
        raise ParameterError("Newton's method did not converge from the start point; give a point on the branch")
    problem.set_reference(u)
    t = _tangent(problem, u, tangent)
    if tangent is None and direction * t[problem.parameters[0]] < 0:
        t = -t
    points = [Point(u, t, 0.0, problem.state_eigenvalues(u), iterations, "", problem.discretisation())]
    special: list[SpecialPoint] = []
    dropped: list[str] = []  # test-function sign changes that were not zeros
    ds, status, message, refinements, base, guess = abs(options.ds), "completed", "", 0, None, None
    first = problem.parameters[0]
    try:
        while True:
            if len(points) >= options.max_points:
                status, message = "max_points", (f"ran out of points (max_points = {options.max_points}) at "
                                                 f"{_where(problem, points[-1].u)}; raise max_points or ds_max")
                break
            if len(points) >= STALL_POINTS and _span(points, first) <= STALL_TOL * (1 + abs(points[-1].u[first])):
                status, message = "stalled", (f"stalled: {STALL_POINTS} points within {_span(points, first):.2g} of "
                                              f"{_where(problem, points[-1].u)} (a vertical branch, e.g. a canard "
                                              "explosion; raise ds_max or continue in another parameter)")
                break
            last = base or points[-1]  # the last point, or that point carried to a new discretisation
            u_new, iterations = _step(problem, last, ds, options, guess)
            guess = None
            if u_new is None:
                ds *= 0.5
                if ds < options.ds_min:
                    status = "corrector_failed"
                    message = (f"the corrector failed below ds_min = {options.ds_min:g} at {_where(problem, last.u)}; "
                               "a singular point or the end of the branch")
                    break
                continue
            if ds >= 2 * options.ds_min and problem.refine(u_new):  # too coarse: redo the step on the finer one
                refinements += 1
                if refinements > MAX_REFINEMENTS:  # the orbit changes too much over the step for any mesh: shorten it
                    ds *= 0.5
                else:  # from the rejected solution carried over (a far better guess than the predictor)
                    rejected = Point(u_new, last.tangent, last.arclength + ds, last.eigenvalues, iterations, "",
                                     last.discretisation)
                    guess = problem.carry(rejected)[0]
                base = _carried(problem, last, problem.carry(last))
                continue
            refinements = 0
            _locate_marks(problem, last, u_new, ds, marks, special, points, options)
            crossed = _first_bound_crossed(problem, last.u, u_new)
            if crossed is not None:
                end = _locate_bound(problem, last, u_new, ds, crossed, options)
                if end is None:  # the corrector fails between the last point and the bound: try a shorter step
                    ds *= 0.5
                    if ds < options.ds_min:
                        status, message = "corrector_failed", (f"the corrector failed before the bound "
                                                               f"{problem.names[crossed[0]]} = {crossed[1]:g}")
                        break
                    continue
                if detect:
                    _detect_and_locate(problem, last, end, special, points, options, dropped)
                points.append(end)
                message = f"reached the bound {problem.names[crossed[0]]} = {crossed[1]:g}"
                break
            new = _make_point(problem, u_new, last.tangent, last.arclength + ds, iterations)
            if detect:
                n_special = len(special)
                _detect_and_locate(problem, last, new, special, points, options, dropped)
                ends = [sp for sp in special[n_special:] if sp.kind in problem.terminal]
                if ends:  # the branch ends at the first terminal special point: drop what lies beyond it
                    del points[ends[0].index + 1:]
                    del special[special.index(ends[0]) + 1:]
                    message = problem.end_message(ends[0].kind, ends[0].u, _where(problem, ends[0].u))
                    break
            points.append(new)
            carried = problem.remesh(new)
            base = None if carried is None else _carried(problem, new, carried)
            problem.set_reference((base or new).u)
            if on_point is not None:
                on_point(points[-1])
            if iterations <= options.easy_iterations:
                ds = min(options.ds_max, ds * options.growth)
    except np.linalg.LinAlgError as err:  # a singular system no step size avoids: the points so far are kept
        status, message = "singular", (f"a singular linear system after {_where(problem, points[-1].u)} "
                                       f"({err}); the points so far are kept: shorten ds_max or refine the "
                                       "discretisation")
    if dropped:
        message += f"; {len(dropped)} sign change(s) of a test function not located as a zero (attribute unlocated)"
    label_points(special)
    return Branch(points, special, status, message, options, dropped)


def _carried(problem: Problem, point: Point, carried: tuple) -> Point:
    """The base of the next step: ``point`` carried to the problem's new discretisation ((u, tangent) of
    :meth:`Problem.carry` or :meth:`Problem.remesh`); the branch keeps the point as it was solved."""
    u, tangent = carried
    problem.set_reference(u)  # the phase condition on the new discretisation
    return Point(u, tangent, point.arclength, point.eigenvalues, point.newton_iterations, point.special,
                 problem.discretisation())


def _span(points: list, index: int) -> float:
    """How far the last STALL_POINTS points moved unknown ``index`` (stalled: below STALL_TOL (1 + |value|))."""
    return float(np.ptp([p.u[index] for p in points[-STALL_POINTS:]]))


def _where(problem: Problem, u: np.ndarray) -> str:
    return ", ".join(f"{problem.names[i]} = {u[i]:.10g}" for i in problem.parameters)


def _first_bound_crossed(problem: Problem, u_old, u_new):
    """(index, bound) of a bound the step leaves the box through, else None (a start on a bound may move in)."""
    for index, (low, high) in problem.bounds.items():
        if u_new[index] <= low < u_old[index] or (u_new[index] <= low and u_new[index] < u_old[index]):
            return index, low
        if u_new[index] >= high > u_old[index] or (u_new[index] >= high and u_new[index] > u_old[index]):
            return index, high
    return None


def _locate_marks(problem, last: Point, u_new: np.ndarray, ds: float, marks, special: list, points: list,
                  options: Options) -> None:
    """The points at the ``marks`` of the first parameter passed between ``last`` and ``u_new``, in order."""
    index = problem.parameters[0]
    a, b = last.u[index], u_new[index]
    found = []
    for value in marks:
        if (a < value <= b) or (b <= value < a):
            point = _locate_bound(problem, last, u_new, ds, (index, float(value)), options, "user")
            if point is not None:
                found.append(point)
    for point in sorted(found, key=lambda p: p.arclength):
        points.append(point)
        special.append(SpecialPoint("user", len(points) - 1, point.u, point.eigenvalues, 0.0,
                                    problem.describe("user", point.u)))


def _locate_bound(problem, last: Point, u_new: np.ndarray, ds: float, crossed, options,
                  kind: str = "bound") -> Point | None:
    """The branch point where unknown ``index`` equals ``bound``, between ``last`` and ``u_new``: Newton with that
    unknown fixed from the secant between them, else (near a fold, where that is singular) Brent on the
    arclength; None if the corrector fails there."""
    index, bound = crossed
    v0 = last.u / problem.scale
    w = (bound - last.u[index]) / (u_new[index] - last.u[index])
    e = np.zeros(len(v0))
    e[index] = 1.0
    u, _it = correct(problem, (1 - w) * last.u + w * u_new, (e, np.zeros(len(v0)), bound / problem.scale[index]),
                     options)
    sigma = math.nan if u is None else float(last.tangent @ (u / problem.scale - v0))
    if not -1e-9 * ds <= sigma <= ds * (1 + 1e-9):

        def g(sigma):
            u = _step_to(problem, last, sigma, options)
            return (u[index] - bound) if u is not None else math.nan

        try:
            sigma = brentq(g, 0.0, ds, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200) if g(0.0) != 0 else 0.0
        except ValueError:  # the corrector failed inside the step
            return None
        u = _step_to(problem, last, sigma, options)
        if u is None:
            return None
    u[index] = bound  # exact: the corrector solved to round-off
    return _make_point(problem, u, last.tangent, last.arclength + sigma, 0, kind)


# ----------------------------------------------------------------------------- special points


def _detect_and_locate(problem, last: Point, new: Point, special: list, points: list, options: Options,
                       dropped: list) -> None:
    """Test functions between ``last`` and ``new``; located points are appended to ``points``, sign
    changes that are not zeros (poles, jumps) or could not be located are named in ``dropped``."""
    before, after = problem.tests(last), problem.tests(new)
    changed = [kind for kind in before if kind in after and before[kind] * after[kind] < 0]
    if "fold" in changed and max(abs(before["fold"]), abs(after["fold"])) < FOLD_NOISE:
        changed.remove("fold")  # the tangent is vertical: its parameter component changes sign by round-off
    if "fold" in changed and "branch_point" in changed:
        changed.remove("branch_point")  # a real eigenvalue through 0 with the tangent turning: a fold
    located = []
    for kind in changed:
        found = _locate(problem, kind, last, new, options)
        if found is None:
            dropped.append(f"{kind} near {_where(problem, new.u)}")
        elif isinstance(found, str):
            dropped.append(f"{kind} near {_where(problem, new.u)} not confirmed: {found}")
        elif found is not REJECTED:
            located.append(found)
    for point, value, kind in sorted(located, key=lambda item: item[0].arclength):
        points.append(point)
        special.append(SpecialPoint(kind, len(points) - 1, point.u, point.eigenvalues, value,
                                    problem.describe(kind, point.u)))


def _locate(problem, kind: str, last: Point, new: Point, options: Options):
    """Brent on the arclength between two points, on the problem's smooth located_value if it
    brackets the zero, else on the detecting test function: (point, value, kind); None if it cannot be located,
    REJECTED if the problem declines the point, the problem's reason if it could not confirm it."""
    cache: dict[float, Point | None] = {}

    span = new.arclength - last.arclength

    def at(sigma):
        if sigma not in cache:
            u = _step_to(problem, last, sigma, options)
            if u is None:  # approach from the other end
                u = _step_to(problem, new, sigma - span, options)
            cache[sigma] = None if u is None else _make_point(problem, u, last.tangent, last.arclength + sigma, 0)
        return cache[sigma]

    def smooth(sigma):
        point = at(sigma)
        return math.nan if point is None else problem.located_value(kind, point)

    def detecting(sigma):
        point = at(sigma)
        return math.nan if point is None else problem.tests(point)[kind]

    for f in (smooth, detecting):
        ends = f(0.0), f(span)
        if all(map(math.isfinite, ends)) and ends[0] * ends[1] < 0:
            break
    else:
        return None
    try:
        sigma = brentq(f, 0.0, span, xtol=1e-14 * max(1.0, span), rtol=4 * np.finfo(float).eps, maxiter=200)
    except ValueError:  # the corrector failed inside the interval
        return None
    if not abs(f(sigma)) <= ZERO_RATIO * max(map(abs, ends)):
        return None  # the sign changed through a pole or a jump, not a zero
    point = at(sigma)
    value = smooth(sigma)
    verdict = problem.accept(kind, point, value, options)
    if isinstance(verdict, str):  # the problem could not confirm it (the reason)
        return verdict
    if not verdict:  # e.g. a neutral saddle where a Hopf test vanishes: not a special point
        return REJECTED
    point.special = kind
    return point, float(value), kind


REJECTED = object()  # _locate: a zero the problem declines (no special point, nothing to report)


def continue_both_ways(problem: Problem, u0: np.ndarray, options: Options = Options(), detect: bool = True,
                       marks=()) -> Branch:
    """The branch through u0 in both directions, as one branch ordered from one end to the other
    (arclength 0 at u0, negative on the first part)."""
    start = problem.discretisation()
    backward = continue_branch(problem, u0, options, direction=-1, detect=detect, marks=marks)
    problem.use(start)
    forward = continue_branch(problem, u0, options, tangent=-backward.points[0].tangent, detect=detect, marks=marks)
    n_back = len(backward.points)
    points = []
    for p in reversed(backward.points):
        points.append(Point(p.u, -p.tangent, -p.arclength, p.eigenvalues, p.newton_iterations, p.special,
                            p.discretisation))
    points += forward.points[1:]
    special = [SpecialPoint(sp.kind, n_back - 1 - sp.index, sp.u, sp.eigenvalues, sp.value, sp.data)
               for sp in reversed(backward.special_points)]
    special += [SpecialPoint(sp.kind, n_back - 1 + sp.index, sp.u, sp.eigenvalues, sp.value, sp.data)
                for sp in forward.special_points]
    label_points(special)
    status = next((b.status for b in (backward, forward) if b.status != "completed"), "completed")
    return Branch(points, special, status, f"one end: {backward.message}; other end: {forward.message}", options,
                  backward.unlocated + forward.unlocated)
