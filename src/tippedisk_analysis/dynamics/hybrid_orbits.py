"""Periodic orbits of a :class:`~.hybrid.HybridSystem` by multi-segment shooting, and their Floquet multipliers
through saltation matrices.

An orbit is a cycle of K segments: segment k starts at x_k in mode m_k, flows for T_k, ends on guard g_k and
takes jump j_k into m_{k+1} with x_{k+1} = R_k(phi_k(T_k, x_k)). The unknowns (x_0..x_{K-1}, T_0..T_{K-1})
solve, for every k,

    x_{k+1} - R_k(phi_k(T_k, x_k)) = 0,     g_k(phi_k(T_k, x_k)) = 0,

a square system (the guards fix the phase); Newton takes its Jacobian from the modes' variational equations.
The monodromy is M = S_{K-1} Phi_{K-1} ... S_0 Phi_0 with the saltation matrix of each jump (time-independent
guards and resets; a forcing enters as a state, e.g. its phase as an oscillator)

    S = dR + (f_{k+1}(x_{k+1}) - dR f_k(x^-)) grad g^T / (grad g . f_k(x^-)),    x^- = phi_k(T_k, x_k),

which maps the flow before the jump onto the flow after it (so M keeps the trivial multiplier 1); where a field
is continuous across the switch and R is the identity (a sliding motion leaving its surface), S = I.

Every orbit is checked before it is called ``converged``: the event-driven run from x_0 over the period must take
the same guards and jumps and return to x_0 (a grazing or an earlier guard that shooting cannot see is caught
here), and the flow direction must be a multiplier-1 eigenvector of M.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import heyoka as hy
import numpy as np

from ..errors import ParameterError
from .flows import STABILITY, classify, floquet
from .hybrid import HybridRun, HybridSystem, simulate_hybrid

NEWTON_TOL = 1e-10  # max |residual| (relative to the state's size) of a converged orbit
RETURN_TOL = 1e-7  # max |x(period) - x_0| (relative) of the event-driven run that verifies it
STATUS = ("converged", "not_converged", "not_verified", "failed")


@dataclass(frozen=True)
class Leg:
    """One segment of a cycle: start in ``mode`` at ``state``, flow ``duration``, end on ``guard``, take its jump
    number ``jump``."""

    mode: str
    state: np.ndarray
    duration: float
    guard: str
    jump: int = 0


@dataclass
class HybridOrbit:
    legs: list  # the converged Legs
    period: float
    multipliers: np.ndarray  # sorted by modulus, descending
    trivial: np.ndarray  # mask of the trivial multiplier(s) (the flow direction's, and any declared)
    monodromy: np.ndarray
    saltations: list  # S_k of each jump
    status: str  # STATUS
    message: str
    residual: float
    iterations: int
    stability: str  # stable / unstable / marginal (of the nontrivial multipliers)


class _Segments:
    """Flow maps with variations of each mode (own integrator copies)."""

    def __init__(self, hybrid: HybridSystem, tol: float):
        self.hybrid, self.tol = hybrid, tol
        self._var = {m: copy.copy(s.taylor(tol, tangents=s.n)) for m, s in hybrid.modes.items()}

    def flow(self, mode: str, x, duration: float, pars) -> tuple[np.ndarray, np.ndarray]:
        """(phi(T, x), d phi / d x) of ``mode``."""
        system = self.hybrid.modes[mode]
        n = system.n
        ta = self._var[mode]
        ta.pars[:] = pars[: len(ta.pars)]
        ta.time = 0.0
        ta.state[:] = np.concatenate([np.asarray(x, float), np.eye(n).ravel()])
        outcome = ta.propagate_until(float(duration))[0]
        state = np.array(ta.state)
        if outcome != hy.taylor_outcome.time_limit or not np.all(np.isfinite(state)):
            raise FloatingPointError(f"the flow of mode {mode!r} over {duration:.6g} failed ({outcome!r})")
        return state[:n], state[n:].reshape(n, n)


def _gradient(hybrid: HybridSystem, mode: str, guard: str, x, pars) -> tuple[float, np.ndarray]:
    system = hybrid.modes[mode]
    g = hybrid.guard(mode, guard)
    cf = system.function(f"guard {guard}", [g.expression, *system.gradient_expressions([g.expression])],
                         f"the guard {guard} and its gradient")
    out = system.evaluate(cf, np.asarray(x, float), pars)
    return float(out[0]), out[1:]


def _reset(hybrid: HybridSystem, mode: str, guard: str, k: int, x, pars) -> tuple[np.ndarray, np.ndarray]:
    """(R(x), dR/dx) of jump ``k`` of ``guard``."""
    system = hybrid.modes[mode]
    g = hybrid.guard(mode, guard)
    exprs = hybrid.reset_expressions(g, g.jumps[k])
    cf = system.function(f"reset {guard} {k}", [*exprs, *system.gradient_expressions(exprs)],
                         f"the reset of {guard} and its Jacobian")
    out = system.evaluate(cf, np.asarray(x, float), pars)
    m = len(exprs)
    return out[:m], out[m:].reshape(m, system.n)


def saltation(hybrid: HybridSystem, mode: str, guard: str, k: int, x_minus, pars) -> np.ndarray:
    """S of jump ``k`` of ``guard`` from ``mode`` at the state x^- on the guard (module docstring)."""
    _g, grad = _gradient(hybrid, mode, guard, x_minus, pars)
    after, dR = _reset(hybrid, mode, guard, k, x_minus, pars)
    target = hybrid.guard(mode, guard).jumps[k].target
    f_minus = hybrid.modes[mode].f(x_minus, pars)
    f_plus = hybrid.modes[target].f(after, pars)
    rate = grad @ f_minus
    if abs(rate) < 1e-300:
        raise FloatingPointError(f"guard {guard!r} is grazed (its rate along the flow is zero): no saltation matrix")
    return dR + np.outer(f_plus - dR @ f_minus, grad) / rate


def _integrals(system, x, pars) -> tuple[np.ndarray, np.ndarray]:
    """(values, gradients (I, n)) of the system's first integrals at x (a family of orbits: their levels pin
    one member)."""
    exprs = list(system.integrals.values())
    if not exprs:
        return np.empty(0), np.empty((0, system.n))
    cf = system.function("integrals", [*exprs, *system.gradient_expressions(exprs)], "the first integrals")
    out = system.evaluate(cf, np.asarray(x, float), pars)
    return out[:len(exprs)], out[len(exprs):].reshape(len(exprs), system.n)


CYCLE_TOL = 1e-3  # relative distance of two states K jumps apart that legs_from_run takes for a closed cycle


def legs_from_run(run: HybridRun, n_legs: int | None = None) -> list:
    """The last ``n_legs`` complete segments of a run as a guess (each from its start to its jump). Without
    ``n_legs``: the shortest cycle at the run's end, K legs whose guards and jumps repeat and whose start
    returns within CYCLE_TOL (relative) after them; ParameterError if the run shows none."""
    switches = run.switches
    if n_legs is None:
        n_legs = _cycle_length(switches)
    if len(switches) < n_legs + 1:
        raise ParameterError(f"the run has {len(switches)} jumps; a guess of {n_legs} legs needs at least "
                             f"{n_legs + 1} (run longer)")
    legs = []
    for a, b in zip(switches[-n_legs - 1:-1], switches[-n_legs:]):
        legs.append(Leg(a.target, np.array(a.after), b.time - a.time, b.guard, b.jump))
    return legs


def _cycle_length(switches: list) -> int:
    keys = [(s.source, s.guard, s.jump, s.target) for s in switches]
    for K in range(1, len(switches) // 2 + 1):
        last, before = switches[-1], switches[-1 - K]
        if keys[-K:] != keys[-2 * K:-K] or last.target != before.target:
            continue
        size = max(1.0, float(np.max(np.abs(last.after))))
        if np.max(np.abs(last.after - before.after)) <= CYCLE_TOL * size:
            return K
    raise ParameterError(f"the run's last {len(switches)} jumps show no closed cycle of guards and jumps (within "
                         f"{CYCLE_TOL:g} relative); run longer, past the transient, or give n_legs")


def find_hybrid_orbit(hybrid: HybridSystem, legs, *, pars=None, tol: float = 1e-14, max_iterations: int = 30,
                      n_trivial: int | None = None) -> HybridOrbit:
    """The periodic orbit through the cycle of ``legs`` (a guess: e.g. :func:`legs_from_run`), its multipliers
    and stability, verified by an event-driven run (module docstring)."""
    legs = list(legs)
    if not legs:
        raise ParameterError("give at least one leg (mode, state, duration, guard)")
    for a, b in zip(legs, legs[1:] + legs[:1]):
        g = hybrid.guard(a.mode, a.guard)
        if not 0 <= a.jump < len(g.jumps) or g.jumps[a.jump].target != b.mode:
            raise ParameterError(f"leg in mode {a.mode!r} ends on {a.guard!r} but its jump {a.jump} does not lead to "
                                 f"the next leg's mode {b.mode!r}")
    pars = hybrid.with_pars(pars)
    seg = _Segments(hybrid, tol)
    sizes = [hybrid.modes[leg.mode].n for leg in legs]
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    K, N = len(legs), int(offsets[-1])
    u = np.concatenate([*(np.asarray(leg.state, float) for leg in legs), [leg.duration for leg in legs]])
    scale = max(1.0, float(np.max(np.abs(u[:N]))))
    first = hybrid.modes[legs[0].mode]
    levels = _integrals(first, u[:sizes[0]], pars)[0]  # the first mode's first integrals stay at the guess's
    n_eq = N + K + len(levels)

    def assemble(u):
        F, J = np.zeros(n_eq), np.zeros((n_eq, N + K))
        if len(levels):
            values, grads = _integrals(first, u[:sizes[0]], pars)
            F[N + K:], J[N + K:, :sizes[0]] = values - levels, grads
        ends = []
        for k, leg in enumerate(legs):
            nxt = (k + 1) % K
            x, T = u[offsets[k]:offsets[k + 1]], u[N + k]
            end, Phi = seg.flow(leg.mode, x, T, pars)
            after, dR = _reset(hybrid, leg.mode, leg.guard, leg.jump, end, pars)
            g, grad = _gradient(hybrid, leg.mode, leg.guard, end, pars)
            f = hybrid.modes[leg.mode].f(end, pars)
            rows = slice(offsets[nxt], offsets[nxt + 1])
            F[rows] = u[offsets[nxt]:offsets[nxt + 1]] - after
            J[rows, offsets[nxt]:offsets[nxt + 1]] += np.eye(sizes[nxt])
            J[rows, offsets[k]:offsets[k + 1]] -= dR @ Phi
            J[rows, N + k] -= dR @ f
            F[N + k] = g
            J[N + k, offsets[k]:offsets[k + 1]] = grad @ Phi
            J[N + k, N + k] = grad @ f
            ends.append((end, Phi))
        return F, J, ends

    status, message, iterations = "not_converged", "", 0
    try:
        F, J, ends = assemble(u)
        for iterations in range(1, max_iterations + 1):
            step = np.linalg.lstsq(J, -F, rcond=None)[0]
            norm0, lam = np.max(np.abs(F)), 1.0
            while True:  # damped: accept a step that lowers the residual, or keeps it at round-off
                trial = u + lam * step
                if np.all(trial[N:] > 0):
                    Ft, Jt, ends_t = assemble(trial)
                    if np.max(np.abs(Ft)) <= max(norm0, 0.1 * NEWTON_TOL * scale):
                        break
                lam /= 2
                if lam < 1e-3:
                    raise FloatingPointError("Newton's steps neither lower the residual nor keep every segment's "
                                             "duration positive; give a closer guess")
            u, F, J, ends = trial, Ft, Jt, ends_t
            if np.max(np.abs(F)) <= NEWTON_TOL * scale and np.max(np.abs(lam * step)) <= 1e-8 * scale:
                status = "converged"
                break
        else:
            message = f"Newton did not converge in {max_iterations} iterations (|F| = {np.max(np.abs(F)):.2e})"
    except (FloatingPointError, np.linalg.LinAlgError) as exc:
        status, message = "failed", str(exc)
    legs = [Leg(leg.mode, u[offsets[k]:offsets[k + 1]].copy(), float(u[N + k]), leg.guard, leg.jump)
            for k, leg in enumerate(legs)]
    residual = float(np.max(np.abs(F))) if status != "failed" else float("nan")
    if status == "failed":
        empty = np.empty(0)
        return HybridOrbit(legs, float(u[N:].sum()), empty, empty.astype(bool), np.empty((0, 0)), [], status,
                           message, residual, iterations, "unknown")
    saltations, M = [], np.eye(sizes[0])
    for k, leg in enumerate(legs):
        end, Phi = ends[k]
        S = saltation(hybrid, leg.mode, leg.guard, leg.jump, end, pars)
        saltations.append(S)
        M = S @ Phi @ M
    multipliers, trivial = floquet(M, hybrid.modes[legs[0].mode].f(legs[0].state, pars),
                                   hybrid.modes[legs[0].mode].n_trivial if n_trivial is None else n_trivial)
    flag, _n_unstable = classify(multipliers, trivial)
    stability = {v: k for k, v in STABILITY.items()}[flag]
    if status == "converged":
        status, message = _verify(hybrid, legs, pars, tol, M)
    return HybridOrbit(legs, float(sum(leg.duration for leg in legs)), multipliers, trivial, M, saltations, status,
                       message, residual, iterations, stability)


def _verify(hybrid: HybridSystem, legs: list, pars, tol: float, M: np.ndarray) -> tuple[str, str]:
    """('converged', summary) if the event-driven run from the orbit's start follows the legs and closes, and
    the flow direction is a multiplier-1 eigenvector of M; otherwise ('not_verified', the reason)."""
    period = sum(leg.duration for leg in legs)
    x0 = legs[0].state
    run = simulate_hybrid(hybrid, legs[0].mode, x0, period * (1 + 1e-9), pars=pars, tol=tol, max_switches=len(legs) + 1)
    taken = [(s.source, s.guard, s.jump) for s in run.switches]
    wanted = [(leg.mode, leg.guard, leg.jump) for leg in legs]
    if taken[:len(legs)] != wanted:
        return "not_verified", (f"the event-driven run from the orbit's start takes {taken[:len(legs)]}, not the "
                                f"legs' {wanted} (an earlier guard or a grazing the shooting cannot see)")
    back = run.switches[len(legs) - 1].after
    gap = float(np.max(np.abs(back - x0)) / max(1.0, np.max(np.abs(x0))))
    if gap > RETURN_TOL:
        return "not_verified", f"the event-driven run returns {gap:.2e} from the orbit's start"
    f0 = hybrid.modes[legs[0].mode].f(x0, pars)
    drift = float(np.linalg.norm(M @ f0 - f0) / max(np.linalg.norm(f0), 1e-300))
    if drift > 1e-6:
        return "not_verified", f"the monodromy does not keep the flow direction (|M f - f| / |f| = {drift:.1e})"
    return "converged", (f"period {period:.12g} in {len(legs)} leg(s); verified by an event-driven run "
                         f"(returns to {gap:.1e}); |M f - f| / |f| = {drift:.1e}")
