"""The end of a branch of periodic orbits whose period grew to the bound ``period_max``: which infinite-period limit
it approaches, and at which parameter value p_c (with its uncertainty).

The equilibria where the last orbit is slowest decide the law; a fit of the branch's last orbits (period T
against parameter p) checks it and gives p_c:

* **homoclinic** orbit (HC): one hyperbolic saddle near the orbit; p = p_c + A exp(-lam T), i.e.
  T = -(1/lam) log|p - p_c| + const, with lam one of the saddle's leading rates lam_u or |lam_s| (the smallest
  |Re| of its unstable and of its stable eigenvalues; which one depends on the saddle quantity);
* **heteroclinic** cycle (HET): two or more saddles near the orbit; the same law with 1/lam = sum_i 1/lam_i
  (one passage per saddle, lam_i one of saddle i's leading rates);
* saddle-node on the invariant cycle (**SNIC**): no equilibrium near the orbit, but a fold of equilibria
  (a zero eigenvalue) at p_fold near its slowest point; T = C |p - p_c|^(-1/2) + T_0 + ..., fitted as
  p = p_c + c2 u^2 + c3 u^3 + c4 u^4 with u = 1/T (c3: the time T_0 away from the bottleneck), and p_c must
  agree with p_fold;
* otherwise ``period_bound`` (PB): the limit is not named (no equilibrium or fold near the orbit, a node or
  focus there, or the law does not fit), and no p_c is given.

The fit uses the orbits with T >= TAIL T_max; where the branch has fewer than MIN_TAIL of them, it is
continued back from its last orbit in steps of about (1 - TAIL) T_max / DENSE in T (those orbits are only
used for the fit). The uncertainty of p_c is the largest of twice its standard error (least-squares
covariance), the change of p_c when the first or the last orbit of the window is left out, and (log law)
the change when lam is fixed at the saddles' value.
"""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
from scipy.optimize import minimize_scalar, root

from . import continuation
from .orbit_base import OrbitProblem

KINDS = ("homoclinic", "heteroclinic", "snic", "period_bound")
TAIL = 0.5  # the power law is fitted to the orbits with T >= TAIL * T_max
MIN_TAIL, DENSE = 8, 16  # fewer orbits there than MIN_TAIL: DENSE more, (1 - TAIL) T_max / DENSE apart in T
LOG_POINTS = 8  # the log law is fitted to this many orbits nearest the end with p resolved from p_last
RESOLVED = 100  # p is resolved from p_last beyond RESOLVED * NOISE * max(1, |p|)
N_LOOK = 512  # samples of the last orbit searched for its slowest points
SLOW = 0.1  # a slow point: a local minimum of |f| / state_scale below SLOW times its maximum on the orbit
NEAR = 0.05  # an equilibrium is at a slow point within NEAR times the orbit's extent (max over the states)
ZERO = 1e-6  # an eigenvalue is zero below ZERO times the largest |eigenvalue|
FIT_TOL = 1e-2  # a law fits when the rms of its residuals relative to |p - p_c| is below FIT_TOL
NOISE = 1e-9  # relative accuracy of the orbits' parameter values (collocation: its discretisation error)
RATE_TOL = 0.2  # the fitted lam agrees with the saddles' within this relative difference
MAX_SADDLES = 4  # the rates of a heteroclinic cycle are combined over its first MAX_SADDLES saddles


@dataclasses.dataclass
class Equilibrium:
    """An equilibrium next to the orbit: its state, eigenvalues and (saddle) leading rates."""

    state: np.ndarray
    eigenvalues: np.ndarray
    rates: tuple  # (lam_u, |lam_s|) of a hyperbolic saddle; () otherwise

    @property
    def saddle(self) -> bool:
        return bool(self.rates)


def classify_end(prob: OrbitProblem, br: continuation.Branch) -> dict:
    """The infinite-period limit of a branch that ended at the period bound (module docstring): {"kind" (of
    KINDS), "limit" p_c and "error" (nan for period_bound), "rate" (lam or C), "reason", "law", the fitted
    "periods" and "values", the "equilibria" next to the orbit and the "fold" of equilibria}."""
    last = br.points[-1]
    prob.use(last.discretisation)
    equilibria, fold = _local_analysis(prob, last.u)
    out = {"periods": np.empty(0), "values": np.empty(0), "equilibria": equilibria, "fold": fold,
           "limit": math.nan, "error": math.nan, "rate": math.nan, "law": "", "residual": math.nan}
    saddles = [e for e in equilibria if e.saddle]
    if equilibria and len(saddles) < len(equilibria):
        return out | {"kind": "period_bound", "reason": "an equilibrium next to the orbit is not a hyperbolic saddle "
                      f"(eigenvalues {_short(next(e for e in equilibria if not e.saddle).eigenvalues)})"}
    if not saddles and fold is None:
        return out | {"kind": "period_bound", "reason": "no equilibrium and no fold of equilibria next to the "
                                                        "orbit's slowest point"}
    if saddles:
        kind, what = ("homoclinic" if len(saddles) == 1 else "heteroclinic"), f"{len(saddles)} saddle(s)"
        rates = sorted({1.0 / sum(1.0 / r for r in choice) for choice in
                        itertools.product(*(e.rates for e in saddles[:MAX_SADDLES]))})
        T, P = _log_window(prob, br, rates[-1])
        fit = fit_log_law(T, P, rates)
        p_end = prob.split(last.u)[2]
        if fit["fits"] and abs(P[-1] - fit["limit"]) * math.exp(-fit["rate"] * (T_max(prob, br) - T[-1])) <= (
                NOISE * max(1.0, abs(p_end))):  # the law puts the last orbit at the limit within the noise
            fit["limit"], fit["error"] = p_end, max(fit["error"], abs(fit["limit"] - p_end))
        out["expected_rate"] = expected = fit["expected_rate"]
    else:
        kind, what = "snic", "a fold of equilibria"
        T, P = _power_window(prob, br)
        fit = fit_power_law(T, P)
    out |= {"periods": T, "values": P, "law": "log" if saddles else "power",
            **{k: fit[k] for k in ("limit", "error", "rate", "residual")}}
    reason = fit["reason"]
    if fit["fits"] and saddles and abs(fit["rate"] / expected - 1.0) > RATE_TOL:
        reason = f"the fitted rate {fit['rate']:.4g} is not theirs ({expected:.4g})"
    if fit["fits"] and not saddles and abs(fit["limit"] - fold["value"]) > fit["error"]:
        reason = (f"the power law's limit {fit['limit']:.8g} +- {fit['error']:.2g} misses the fold at "
                  f"{fold['value']:.8g}")
    if reason:
        return out | {"kind": "period_bound", "limit": math.nan, "error": math.nan,
                      "reason": f"{what} next to the orbit but {reason}"}
    return out | {"kind": kind, "reason": ""}


def T_max(prob: OrbitProblem, br: continuation.Branch) -> float:
    return prob.split(br.points[-1].u)[1]


def _short(values) -> str:
    return ", ".join(f"{v:.3g}" for v in np.asarray(values))


# ------------------------------------------------------------------------------------------ the last orbits


def _branch_TP(prob: OrbitProblem, br: continuation.Branch) -> tuple[np.ndarray, np.ndarray]:
    return (np.array([prob.split(p.u)[1] for p in br.points]), np.array([prob.split(p.u)[2] for p in br.points]))


def _power_window(prob: OrbitProblem, br: continuation.Branch) -> tuple[np.ndarray, np.ndarray]:
    """(T, p) sorted by T of the orbits with T >= TAIL T_max: the branch's, and (if it has fewer than MIN_TAIL
    there) orbits at periods (1 - TAIL) T_max / DENSE apart back from its last one."""
    T, P = _branch_TP(prob, br)
    keep = T >= TAIL * T[-1]
    if keep.sum() < MIN_TAIL:
        back_T, back_P = _walk_back(prob, br, len(br.points) - 1, (1 - TAIL) * T[-1] / DENSE, DENSE)
        T, P = np.r_[T[keep], back_T], np.r_[P[keep], back_P]
        keep = T >= TAIL * T[-1] * (1 - 1e-12)
    order = np.argsort(T[keep])
    return T[keep][order], P[keep][order]


def _log_window(prob: OrbitProblem, br: continuation.Branch, rate: float) -> tuple[np.ndarray, np.ndarray]:
    """(T, p) sorted by T of the LOG_POINTS orbits nearest the end whose p differs from the last one's by more
    than RESOLVED NOISE max(1, |p|) (closer they carry no information on the law): the branch's, and if it has
    fewer than LOG_POINTS within LOG_POINTS steps of ln(10) / (2 lam) (half a decade in p - p_c each) below its
    first orbit within that of the end, orbits that far apart walked back from that orbit."""
    T, P = _branch_TP(prob, br)

    def resolved(P):
        return np.abs(P - P[len(br.points) - 1]) > RESOLVED * NOISE * max(1.0, abs(P[len(br.points) - 1]))

    step = math.log(10.0) / (2.0 * rate)
    anchor = int(np.flatnonzero(~resolved(P))[0])  # the first orbit within RESOLVED NOISE of the end
    if np.sum(resolved(P) & (T >= T[anchor] - LOG_POINTS * step)) < LOG_POINTS:
        before = T[: anchor][resolved(P)[: anchor]]
        n = min(4 * LOG_POINTS, math.ceil((T[anchor] - (before.max() if before.size else T[0])) / step) + LOG_POINTS)
        back_T, back_P = _walk_back(prob, br, anchor, step, n)
        T, P = np.r_[T, back_T], np.r_[P, back_P]
    keep = resolved(P)
    order = np.argsort(T[keep])[-LOG_POINTS:]
    return T[keep][order], P[keep][order]


def _walk_back(prob: OrbitProblem, br: continuation.Branch, start: int, step: float, n: int):
    """(T, p) of up to n orbits at periods ``step`` apart below that of the branch's point ``start``, each by
    Newton's method with T fixed (the arclength constraint along T) from the secant predictor, on that point's
    discretisation; a step that fails is halved (up to 4 times), then the walk stops; it stops at the
    branch's first period."""
    point = br.points[start]
    prob.use(point.discretisation)
    k = prob.t_index
    e_T = np.zeros(len(point.u))
    e_T[k] = 1.0
    T_low = prob.split(br.points[0].u)[1]
    found, halvings = [np.asarray(point.u, float)], 0
    while len(found) <= n and found[-1][k] - step > T_low and halvings <= 4:
        u = found[-1]
        T_new = u[k] - step
        guess = u.copy() if len(found) < 2 else u + (u - found[-2]) * (T_new - u[k]) / (u[k] - found[-2][k])
        guess[k] = T_new
        prob.set_reference(u)
        new, _it = continuation.correct(prob, guess, (e_T, u / prob.scale, (T_new - u[k]) / prob.scale[k]),
                                        br.options)
        if new is None:
            step, halvings = 0.5 * step, halvings + 1
            continue
        found.append(new)
    back = np.array(found[1:]).reshape(-1, len(point.u))
    return back[:, k], back[:, k + 1]


# ---------------------------------------------------------------------------------- the local equilibria


def _local_analysis(prob: OrbitProblem, u) -> tuple[list[Equilibrium], dict | None]:
    """The equilibria found by Newton's method within NEAR of the slow points of the orbit at u (the one of the
    slowest point, then saddles), and (if the slowest point has none) the fold of equilibria within NEAR of it
    {"value", "state", "eigenvalues"} or None."""
    system, pars = prob.system, prob.runtime(u)
    orbit = prob.orbit(u, n_samples=N_LOOK, discretisation=None)
    X = orbit.samples
    scale = np.asarray(system.state_scale)
    speed = np.linalg.norm(system.f(X.T, pars).T / scale, axis=1)
    extent = float(np.max(np.ptp(X / scale, axis=0)))
    slow = (speed <= np.roll(speed, 1)) & (speed <= np.roll(speed, -1)) & (speed <= SLOW * speed.max())
    minima = np.flatnonzero(slow)
    minima = minima[np.argsort(speed[minima])][:8]
    found: list[Equilibrium] = []
    for i in minima:  # the slowest first: its equilibrium decides; the other slow points add saddles
        x = _newton_equilibrium(system, X[i], pars)
        if x is None or np.linalg.norm((X[i] - x) / scale) > NEAR * extent:
            if not found:
                break
            continue
        ev = np.linalg.eigvals(system.jacobian(x, pars))
        new = Equilibrium(x, ev, _saddle_rates(ev))
        if (found and not new.saddle) or any(np.linalg.norm((x - e.state) / scale) <= 1e-6 * extent for e in found):
            continue
        found.append(new)
    if found or prob.p_index is None or not minima.size:
        return found, None
    fold = _fold_of_equilibria(system, X[minima[0]], pars, prob.p_index)
    if fold is None or np.linalg.norm((X[minima[0]] - fold["state"]) / scale) > NEAR * extent:
        return found, None
    return found, fold


def _saddle_rates(ev: np.ndarray) -> tuple:
    """(lam_u, |lam_s|), the smallest |Re| of the unstable and of the stable eigenvalues, of a hyperbolic
    saddle; () otherwise."""
    re = ev.real
    if np.any(np.abs(re) <= ZERO * np.abs(ev).max()) or not (np.any(re > 0) and np.any(re < 0)):
        return ()
    return float(re[re > 0].min()), float(-re[re < 0].max())


def _newton_equilibrium(system, x0, pars, max_iter: int = 30) -> np.ndarray | None:
    """f(x) = 0 by Newton's method from x0 (None if it does not converge to 1e-10 in scaled states)."""
    x, scale = np.array(x0, float), np.asarray(system.state_scale)
    for _ in range(max_iter):
        try:
            dx = np.linalg.solve(system.jacobian(x, pars), -system.f(x, pars))
        except np.linalg.LinAlgError:
            return None
        x = x + dx
        if not np.all(np.isfinite(x)):
            return None
        if np.max(np.abs(dx) / scale) <= 1e-10 * (1 + np.max(np.abs(x) / scale)):
            return x
    return None


def _fold_of_equilibria(system, x0, pars, k: int) -> dict | None:
    """{"value", "state", "eigenvalues"} of the fold of equilibria f(x, p_k) = 0, g(x, p_k) = 0 nearest (x0,
    pars): g the bordered test function ([[J, b], [c^T, 0]] [v; g] = [0; 1], b and c the singular vectors of J at
    x0 for its smallest singular value); None if Newton fails or the zero eigenvalue is not there."""
    U, _s, Vt = np.linalg.svd(system.jacobian(x0, pars))
    b, c = U[:, -1], Vt[-1]
    n = system.n

    def at(z):
        p = pars.copy()
        p[k] = z[n]
        return z[:n], p

    def equations(z):
        x, p = at(z)
        J = system.jacobian(x, p)
        border = np.block([[J, b[:, None]], [c[None, :], np.zeros((1, 1))]])
        g = np.linalg.solve(border, np.r_[np.zeros(n), 1.0])[n]
        return np.r_[system.f(x, p), g]

    try:
        sol = root(equations, np.r_[x0, pars[k]], method="hybr", options={"xtol": 1e-13})
    except np.linalg.LinAlgError:
        return None
    x, p = at(sol.x)
    if not sol.success or not np.all(np.isfinite(sol.x)):
        return None
    ev = np.linalg.eigvals(system.jacobian(x, p))
    if np.min(np.abs(ev)) > 1e3 * ZERO * np.abs(ev).max():
        return None
    return {"value": float(sol.x[n]), "state": x, "eigenvalues": ev}


# ------------------------------------------------------------------------------------------------ the laws


def _weighted_fit(columns, P: np.ndarray, reweight: int = 3) -> tuple[np.ndarray, np.ndarray, float]:
    """(coefficients, covariance, rms relative residual) of P ~ X c, X = columns(): least squares in the relative
    residual (p - model) / (|p - p_c| + NOISE max(1, |p|)) (the laws hold asymptotically: the last orbits count
    as much as the first), the weights from the previous p_c (first p_last); covariance scaled by the residual
    variance."""
    X = columns
    floor = NOISE * max(1.0, float(np.max(np.abs(P))))
    limit = P[-1]
    for _ in range(reweight):
        w = 1.0 / (np.abs(P - limit) + floor)
        coef, *_ = np.linalg.lstsq(X * w[:, None], P * w, rcond=None)
        limit = coef[0]
    rel = (P - X @ coef) * w
    dof = max(len(P) - X.shape[1], 1)
    cov = np.linalg.pinv((X * w[:, None]).T @ (X * w[:, None])) * float(rel @ rel) / dof
    return coef, cov, float(np.sqrt(np.mean(rel * rel)))


def _log_scan(T, P, rates: np.ndarray, reweight: int = 3) -> np.ndarray:
    """The rms relative residual of :func:`_weighted_fit` for p = p_c + A exp(-lam (T - T_last)) at each of
    ``rates`` at once (batched QR least squares, the same weights and reweighting)."""
    X = np.stack(np.broadcast_arrays(1.0, np.exp(-np.outer(rates, T - T[-1]))), axis=-1)  # (rates, orbits, 2)
    floor = NOISE * max(1.0, float(np.max(np.abs(P))))
    limit = np.full(len(rates), P[-1])
    for _ in range(reweight):
        w = 1.0 / (np.abs(P[None, :] - limit[:, None]) + floor)
        Q, R = np.linalg.qr(X * w[..., None])
        coef = np.linalg.solve(R, np.einsum("rni,rn->ri", Q, P * w)[..., None])[..., 0]
        limit = coef[:, 0]
    rel = (P - np.einsum("rni,ri->rn", X, coef)) * w
    return np.sqrt(np.mean(rel * rel, axis=1))


def _log_fit(T, P, rate=None) -> tuple[float, float, float, float]:
    """(p_c, its standard error, lam, rms relative residual) of p = p_c + A exp(-lam (T - T_last)); lam by a scan
    and Brent's method on the residual (variable projection) unless given."""
    def fit(lam):
        return _weighted_fit(np.column_stack([np.ones_like(T), np.exp(-lam * (T - T[-1]))]), P)

    if rate is None:
        width = T[-1] - T[0]
        grid = np.geomspace(0.3 / width, 100.0 / width, 80)
        best = grid[int(np.argmin(_log_scan(T, P, grid)))]
        q = minimize_scalar(lambda q: fit(math.exp(q))[2], bounds=(math.log(best / 1.2), math.log(best * 1.2)),
                            method="bounded").x
        rate = math.exp(q)
    coef, cov, rms = fit(rate)
    return float(coef[0]), float(math.sqrt(max(cov[0, 0], 0.0))), float(rate), rms


def _power_fit(T, P, order: int = 3) -> tuple[float, float, float, float]:
    """(p_c, its standard error, C, rms relative residual) of p = p_c + sum_k c_k u^k (k = 2 .. order),
    u = T_last / T (u^3: the time spent away from the bottleneck); C = T_last sqrt|c_2| of
    T ~ C |p - p_c|^(-1/2)."""
    u = T[-1] / T
    coef, cov, rms = _weighted_fit(np.column_stack([u ** k for k in (0, *range(2, order + 1))]), P)
    return float(coef[0]), float(math.sqrt(max(cov[0, 0], 0.0))), float(T[-1] * math.sqrt(abs(coef[1]))), rms


def _law(fit, alternatives, T, P, n_params: int) -> dict:
    """{"limit", "error", "rate", "residual", "fits", "reason"} of ``fit`` (T, P) -> (p_c, sigma, rate, rms)
    through the window; the error: the largest of 2 sigma, the changes of p_c without the window's first or
    last orbit and under the ``alternatives`` (other fits of the same law), and NOISE max(1, |p_c|)."""
    if len(T) < n_params + 2:
        return {"limit": math.nan, "error": math.nan, "rate": math.nan, "residual": math.nan, "fits": False,
                "reason": f"only {len(T)} orbits near the end to fit (lower ds_max)"}
    limit, sigma, rate, rms = fit(T, P)
    others = [*(a(T, P)[0] for a in alternatives), *(fit(t, p)[0] for t, p in ((T[1:], P[1:]), (T[:-1], P[:-1]))
                                                    if len(t) >= n_params + 2)]
    error = max(2.0 * sigma, NOISE * max(1.0, abs(limit)), *(abs(o - limit) for o in others if math.isfinite(o)))
    out = {"limit": limit, "error": error, "rate": rate, "residual": rms, "fits": True, "reason": ""}
    if not rms <= FIT_TOL:
        return out | {"fits": False, "reason": f"the law does not fit the last {len(T)} orbits (rms relative "
                                              f"residual {rms:.2g})"}
    return out


def fit_log_law(T, P, rates=()) -> dict:
    """p = p_c + A exp(-lam T) through the window (T, p) (module docstring), checked against lam fixed at the
    one of the saddles' ``rates`` nearest the fitted lam ("expected_rate"): {"limit", "error", "rate" lam,
    "expected_rate", "residual", "fits", "reason"}."""
    T, P = np.asarray(T, float), np.asarray(P, float)
    expected = math.nan
    if rates and len(T) >= 5:
        free = _log_fit(T, P)[2]
        expected = min(rates, key=lambda r: abs(math.log(r / free)))
    alternatives = [] if math.isnan(expected) else [lambda T, P: _log_fit(T, P, expected)]
    return _law(_log_fit, alternatives, T, P, 3) | {"expected_rate": expected}


def fit_power_law(T, P) -> dict:
    """p = p_c + c2 u^2 + c3 u^3 + c4 u^4, u = T_last / T, through the window (T, p) (module docstring), checked
    against the cubic in u: {"limit", "error", "rate" C of T ~ C |p - p_c|^(-1/2), "residual", "fits",
    "reason"}."""
    return _law(_power_fit4, [_power_fit], np.asarray(T, float), np.asarray(P, float), 4)


def _power_fit4(T, P):
    return _power_fit(T, P, 4)


def describe(end: dict, parameter: str) -> str:
    """One line naming the limit of :func:`classify_end` (or why none is named)."""
    where = f"{parameter} ~ {end['limit']:.8g} +- {end['error']:.2g}"
    if end["kind"] == "homoclinic":
        return (f"approach to a homoclinic orbit at {where} (p - p_c ~ exp(-{end['rate']:.4g} T); the saddle's "
                f"leading rate {end['expected_rate']:.4g})")
    if end["kind"] == "heteroclinic":
        return (f"approach to a heteroclinic cycle through {len(end['equilibria'])} saddles at {where} (p - p_c ~ "
                f"exp(-{end['rate']:.4g} T); 1/sum of the saddles' 1/rate {end['expected_rate']:.4g})")
    if end["kind"] == "snic":
        return (f"approach to a saddle-node on the invariant cycle (SNIC) at {where} (T ~ {end['rate']:.4g} "
                f"|p - p_c|^(-1/2); the fold of equilibria at {parameter} = {end['fold']['value']:.10g})")
    return (f"no infinite-period limit named: {end['reason']} (period_bound; raise period_max, lower ds_max, or "
            "locate the limit directly, e.g. homoclinic_point)")
