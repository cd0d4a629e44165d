"""Fit a :class:`.system.System`'s runtime parameters and initial states to a measured motion.

Residuals r = sqrt(w) (y(t_i; theta) - d_i) / sigma over the observed samples d_i (NaN: missing) of states and
observables y; their Jacobian dr/dtheta comes from heyoka's first-order variational equations along the same
Taylor run (dx/dx0, dx/dp and the chain rule through the observables), never from finite differences.
scipy.optimize.least_squares (trust region reflective, bounds) minimises |r|^2 / 2.

Start: a continuation in the horizon. The fit to the first part of the record (default 1/16, then 1/8, 1/4, 1/2)
starts the fit to the next part: a motion that rotates, oscillates or inverts has a rugged cost over a long record,
while over a short one the start lies in the basin of the minimum and each longer fit starts close to its own.
A part too short to determine the free values (a linearised standard error above a value's magnitude at the start)
is skipped: its minimum follows the noise (the disk's mu and eps trade off over the first 0.1 s).

Uncertainty at the optimum: cov = s^2 (J^T J)^-1 with s^2 = |r|^2 / (m - p) (m samples, p free values) when sigma
is not given, s^2 = 1 when it is. The column-scaled Jacobian J D (unit columns) = U S V^T: a singular value below
``identifiability_tol`` names the combination V[:, k] the data cannot determine (:mod:`.fit_dataset` stores all).
"""

from __future__ import annotations

import copy

import heyoka as hy
import numpy as np
from scipy.optimize import least_squares

from ..errors import ParameterError
from .fit_dataset import Stage, fit_dataset
from .system import System

MAX_STEPS = 200_000  # Taylor steps of the start's run before it counts as failed
STEP_FACTOR = 20  # a trial run needing this many times the start's steps counts as failed (a stiff trial point)
PENALTY = 1e6  # a trial point whose run fails gets residuals PENALTY * (1 + rms of the start's): the step is refused


class RunFailed(Exception):
    """The model's run did not reach the last sample (non-finite state or the step limit)."""


def _as_series(value, names, n: int, what: str, default: float) -> dict[str, np.ndarray]:
    """``value`` (None, a number, or {name: number or array of n}) as positive arrays of n per observed name."""
    by_name = value if isinstance(value, dict) else {name: value for name in names}
    unknown = [k for k in by_name if k not in names]
    if unknown:
        raise ParameterError(f"{what} names {unknown[0]!r}, which is not observed; give {what} for "
                             f"{', '.join(names)}")
    out = {}
    for name in names:
        v = by_name.get(name)
        arr = np.full(n, default) if v is None else np.broadcast_to(np.asarray(v, dtype=float), (n,)).copy()
        if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
            raise ParameterError(f"{what} of {name!r} holds a value <= 0 or non-finite; give positive numbers")
        out[name] = arr
    return out


class FitProblem:
    """Residuals and their exact Jacobian for fitting ``free`` (names of initial states and runtime parameters) of
    ``system`` to ``observed`` {state or observable name: values at ``times``} (NaN: a missing sample).

    ``pars``/``state``: the values at the start (parameters not freed keep them); ``t0``: the time of the initial
    state (default ``times[0]``); ``sigma``, ``weights``: a number or {name: number or array} (default 1).
    """

    def __init__(self, system: System, times, observed: dict, free, *, pars=None, state=None, sigma=None,
                 weights=None, t0: float | None = None, tol: float = 1e-12):
        self.system, self.tol = system, float(tol)
        self.times = self._check_times(times)
        self.t0 = float(self.times[0] if t0 is None else t0)
        if not np.isfinite(self.t0) or self.t0 > self.times[0]:
            raise ParameterError(f"t0 = {t0!r} lies after the first sample ({self.times[0]:.6g}); give t0 <= times[0]")
        self.names, self.data = self._check_observed(observed)
        self.free = self._check_free(free)
        self.pars = system.with_pars(pars)
        self.state = self._check_state(state)
        self.used = np.isfinite(self.data)  # (N, m)
        n_used = int(self.used.sum())
        if n_used <= len(self.free):
            raise ParameterError(f"{n_used} observed samples for {len(self.free)} free values; give more samples than "
                                 "free values (or free fewer)")
        sig = _as_series(sigma, self.names, len(self.times), "sigma", 1.0)
        wts = _as_series(weights, self.names, len(self.times), "weights", 1.0)
        self.sigma_given = sigma is not None
        self.scale = np.column_stack([np.sqrt(wts[k]) / sig[k] for k in self.names])  # r = scale * (y - d)
        self.free_states = [k for k in self.free if k in system.state_names]
        self.free_pars = [k for k in self.free if k in system.parameter_names]
        self.tangents = 1 + max(map(system.state_index, self.free_states)) if self.free_states else 0
        self.columns = [system.state_index(k) if k in system.state_names else
                        self.tangents + self.free_pars.index(k) for k in self.free]
        self.n_args = self.tangents + len(self.free_pars)
        start = np.zeros((system.n, self.n_args))
        start[range(self.tangents), range(self.tangents)] = 1.0  # d x0 / d x0[:tangents] = I, d x0 / d p = 0
        self._variations0 = start.ravel()
        self._ta = copy.copy(system.taylor(self.tol, tangents=self.tangents, parameters=self.free_pars))
        self._observables = self._observable_function()
        self.runs = 0  # model runs (each with its sensitivities)
        self.max_steps, self.steps = MAX_STEPS, 0  # the step limit of a run; the steps of the last run
        self._cache: tuple | None = None

    # -- input checks (one line each, naming the fix)
    @staticmethod
    def _check_times(times) -> np.ndarray:
        t = np.asarray(times, dtype=float)
        if t.ndim != 1 or t.size < 2 or not np.all(np.isfinite(t)):
            raise ParameterError("times must be a 1-D array of at least 2 finite sample times")
        steps = np.diff(t)
        if np.any(steps <= 0):
            i = int(np.flatnonzero(steps <= 0)[0])
            kind = "repeats" if steps[i] == 0 else "goes back"
            raise ParameterError(f"times {kind} at sample {i + 1} (t = {t[i + 1]:.9g} after {t[i]:.9g}); give "
                                 "strictly increasing times (sort the record and drop duplicate samples)")
        return t

    def _check_observed(self, observed) -> tuple[list[str], np.ndarray]:
        if not isinstance(observed, dict) or not observed:
            raise ParameterError("observed must be a non-empty dict {state or observable name: values at times}")
        allowed = (*self.system.state_names, *self.system.observables)
        columns = []
        for name, values in observed.items():
            if name not in allowed:
                raise ParameterError(f"{self.system.name} has no state or observable {name!r} to compare with the "
                                     f"data; name columns as one of {', '.join(allowed)}")
            v = np.asarray(values, dtype=float)
            if v.shape != self.times.shape:
                raise ParameterError(f"observed {name!r} has shape {v.shape}, times {self.times.shape}; give one "
                                     "value per sample time (NaN where it is missing)")
            if not np.any(np.isfinite(v)):
                raise ParameterError(f"observed {name!r} holds no finite value; drop the column or fill it")
            if np.any(np.isinf(v)):
                raise ParameterError(f"observed {name!r} holds an infinite value; mark missing samples with NaN")
            columns.append(v)
        return list(observed), np.column_stack(columns)

    def _check_free(self, free) -> list[str]:
        names = [free] if isinstance(free, str) else list(free)
        allowed = (*self.system.state_names, *self.system.parameter_names)
        if not names:
            raise ParameterError(f"free names nothing; give parameters and/or initial states of {self.system.name} "
                                 f"({', '.join(allowed)})")
        for k in names:
            if k not in allowed:
                raise ParameterError(f"{self.system.name} has no parameter or state {k!r} to fit; free some of "
                                     f"{', '.join(allowed)}")
        if len(set(names)) != len(names):
            raise ParameterError(f"free names {names}: a name repeats; name each value once")
        return names

    def _check_state(self, state) -> np.ndarray:
        sys = self.system
        if state is None:
            raise ParameterError(f"give the initial state at t0 (state = {{{', '.join(sys.state_names)}}} or a "
                                 f"vector of {sys.n}); freed states start from it")
        if isinstance(state, dict):
            missing = [k for k in sys.state_names if k not in state]
            if missing or len(state) != sys.n:
                extra = [k for k in state if k not in sys.state_names]
                raise ParameterError(f"state: {'no ' + repr(missing[0]) if missing else 'unknown ' + repr(extra[0])};"
                                     f" give every state of {sys.name} ({', '.join(sys.state_names)})")
            x = np.array([float(state[k]) for k in sys.state_names])
        else:
            x = np.asarray(state, dtype=float).ravel()
        if x.shape != (sys.n,) or not np.all(np.isfinite(x)):
            raise ParameterError(f"state: give {sys.n} finite numbers ({', '.join(sys.state_names)})")
        return x

    def _observable_function(self):
        """cfunc of each observed observable followed by its gradient in the states and the free parameters."""
        obs = [k for k in self.names if k in self.system.observables]
        if not obs:
            return None
        exprs = [self.system.observables[k][0] for k in obs]
        args = [*self.system.variables, *(hy.par[self.system.parameter_index(k)] for k in self.free_pars)]
        jac = np.asarray(hy.diff_tensors(exprs, diff_args=args, diff_order=1).jacobian)
        outputs = [*exprs, *jac.ravel()]  # values, then the gradients row by row
        return self.system.function(f"fit:{','.join(self.free_pars)}", outputs, "the observables' gradients")

    # -- the model and its sensitivities
    @property
    def start(self) -> np.ndarray:
        """The free values at the start, in the order of ``free``."""
        return np.array([self.state[self.system.state_index(k)] if k in self.system.state_names else
                         self.pars[self.system.parameter_index(k)] for k in self.free])

    def unpack(self, theta) -> tuple[np.ndarray, np.ndarray]:
        """(initial state, runtime parameters) with the free values ``theta``."""
        x0, pars = self.state.copy(), self.pars.copy()
        for k, v in zip(self.free, theta):
            if k in self.system.state_names:
                x0[self.system.state_index(k)] = v
            else:
                pars[self.system.parameter_index(k)] = v
        return x0, pars

    def run(self, theta, n_samples: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The model at the first ``n_samples`` times: states (N, n), observed series (N, m) and their sensitivities
        d y / d theta (N, m, p). Raises :class:`RunFailed` if the run stops early."""
        N = len(self.times) if n_samples is None else int(n_samples)
        key = (N, tuple(np.asarray(theta, dtype=float)))
        if self._cache is not None and self._cache[0] == key:
            return self._cache[1]
        sys, n, ta = self.system, self.system.n, self._ta
        x0, pars = self.unpack(theta)
        ta.time = self.t0
        ta.pars[:] = pars[: len(ta.pars)]
        ta.state[:n] = x0
        ta.state[n:] = self._variations0
        grid = self.times[:N] if self.times[0] == self.t0 else np.append(self.t0, self.times[:N])
        self.runs += 1
        res = ta.propagate_grid(grid, max_steps=self.max_steps)
        self.steps = int(res[3])
        out = np.asarray(res[-1])
        if res[0] != hy.taylor_outcome.time_limit or len(out) != len(grid) or not np.all(np.isfinite(out)):
            raise RunFailed(f"the run stopped ({res[0]!r}) at t = {ta.time:.6g} before t = {grid[-1]:.6g}")
        out = out[len(grid) - N:]
        X = out[:, :n]
        S = out[:, n:].reshape(N, n, self.n_args)[:, :, self.columns]  # d x / d theta
        Y, dY = np.empty((N, len(self.names))), np.empty((N, len(self.names), len(self.free)))
        if self._observables is not None:
            obs = [k for k in self.names if k in sys.observables]
            values = sys.evaluate(self._observables, X.T, pars).T  # (N, n_obs * (1 + n + k))
            n_obs, k_par = len(obs), len(self.free_pars)
            grad = values[:, n_obs:].reshape(N, n_obs, n + k_par)
        for j, name in enumerate(self.names):
            if name in sys.state_names:
                Y[:, j], dY[:, j] = X[:, sys.state_index(name)], S[:, sys.state_index(name)]
                continue
            q = obs.index(name)
            Y[:, j] = values[:, q]
            dY[:, j] = np.einsum("ti,tip->tp", grad[:, q, :n], S)  # chain rule through the states
            for c, k in enumerate(self.free):  # explicit dependence of the observable on a free parameter
                if k in self.free_pars:
                    dY[:, j, c] += grad[:, q, n + self.free_pars.index(k)]
        result = (X, Y, dY)
        self._cache = (key, result)
        return result

    def residuals(self, theta, n_samples: int | None = None) -> np.ndarray:
        """r = scale (y - d) over the observed samples among the first ``n_samples`` (time-major)."""
        N = len(self.times) if n_samples is None else int(n_samples)
        _X, Y, _dY = self.run(theta, N)
        used = self.used[:N]
        return (self.scale[:N] * (Y - self.data[:N]))[used]

    def jacobian(self, theta, n_samples: int | None = None) -> np.ndarray:
        """d r / d theta (m, p) from the variational equations."""
        N = len(self.times) if n_samples is None else int(n_samples)
        _X, _Y, dY = self.run(theta, N)
        return (self.scale[:N, :, None] * dY)[self.used[:N]]


HORIZONS = (0.0625, 0.125, 0.25, 0.5, 1.0)  # the continuation in the horizon: fractions of the record


def solve(problem: FitProblem, *, bounds=None, horizons=HORIZONS, max_nfev: int = 200) -> list[Stage]:
    """Trust-region least squares on growing horizons (fractions of the record), each starting from the last."""
    p = len(problem.free)
    lower, upper = _bounds(problem, bounds)
    fractions = [float(h) for h in horizons]
    if not fractions or fractions[-1] != 1.0 or not 0 < fractions[0] or\
            any(a >= b for a, b in zip(fractions, fractions[1:])):
        raise ParameterError(f"horizons = {horizons!r}: give increasing fractions of the record in (0, 1] ending at 1, "
                             "e.g. (0.0625, 0.125, 0.25, 0.5, 1.0), or (1.0,) for one solve on the whole record")
    theta = problem.start
    try:
        start_rms = float(np.sqrt(np.mean(problem.residuals(theta) ** 2)))
    except RunFailed as exc:
        raise ParameterError(f"the model cannot be run over the record from the start ({exc}); give a start closer to "
                             "the data or a shorter record") from None
    problem.max_steps = max(1000, STEP_FACTOR * problem.steps)
    penalty = PENALTY * (1.0 + start_rms)
    t = problem.times
    stages = []
    for frac in fractions:
        N = int(np.searchsorted(t, t[0] + frac * (t[-1] - t[0]), side="right")) if frac < 1 else len(t)
        if problem.used[:N].sum() <= 2 * p and frac < 1:
            continue  # too short a part to say anything; the next horizon starts from the same values
        try:
            problem.residuals(theta, N)
        except RunFailed:  # the last horizon's estimate cannot be run over this one: start again from the start
            theta = problem.start
        if frac < 1 and _undetermined(problem, theta, N):
            continue  # its minimum would follow the noise (e.g. the disk's mu, eps -> 0 on 0.1 s): start later

        def fun(th, N=N):
            try:
                return problem.residuals(th, N)
            except RunFailed:
                return np.full(int(problem.used[:N].sum()), penalty)

        res = least_squares(fun, theta, jac=lambda th, N=N: problem.jacobian(th, N), bounds=(lower, upper),
                            method="trf", x_scale="jac", ftol=1e-12, xtol=1e-12, gtol=1e-12, max_nfev=max_nfev)
        theta = res.x
        stages.append(Stage(N, res.x, int(res.status), int(res.nfev), int(res.njev or 0),
                            np.asarray(res.active_mask, dtype=int), str(res.message)))
    return stages


def _undetermined(problem: FitProblem, theta, N: int) -> bool:
    """Whether the first ``N`` samples leave a free value undetermined at ``theta``: a linearised standard error
    s |(J^T J)^-1|_kk^(1/2) (s^2 from these residuals, 1 with sigma) above |theta_k| for a non-zero theta_k, or a
    Jacobian column or combination without weight."""
    r, J = problem.residuals(theta, N), problem.jacobian(theta, N)
    m, p = J.shape
    norms = np.linalg.norm(J, axis=0)
    if np.any(norms == 0):
        return True
    _U, S, Vt = np.linalg.svd(J / norms, full_matrices=False)
    if S[-1] <= 1e-12 * S[0]:
        return True
    s = 1.0 if problem.sigma_given else float(np.sqrt(r @ r / (m - p)))
    stderr = s * np.linalg.norm(Vt.T / S, axis=1) / norms
    theta = np.asarray(theta, dtype=float)
    return bool(np.any((stderr > np.abs(theta)) & (theta != 0)))


def _bounds(problem: FitProblem, bounds) -> tuple[np.ndarray, np.ndarray]:
    lower, upper = np.full(len(problem.free), -np.inf), np.full(len(problem.free), np.inf)
    start = problem.start
    for name, pair in dict(bounds or {}).items():
        if name not in problem.free:
            raise ParameterError(f"bounds name {name!r}, which is not free; bound some of {', '.join(problem.free)}")
        try:
            lo, hi = (-np.inf if pair[0] is None else float(pair[0])), (np.inf if pair[1] is None else float(pair[1]))
        except (TypeError, ValueError):
            raise ParameterError(f"bounds of {name!r} = {pair!r}: give a pair (lower, upper), None for no bound") \
                from None
        i = problem.free.index(name)
        if not lo < hi:
            raise ParameterError(f"bounds of {name!r}: lower {lo} is not below upper {hi}; give lower < upper")
        if not lo <= start[i] <= hi:
            raise ParameterError(f"the start {name} = {start[i]:.6g} lies outside its bounds ({lo}, {hi}); give a "
                                 "start inside them")
        lower[i], upper[i] = lo, hi
    return lower, upper


def fit(system: System, times, observed: dict, free, *, pars=None, state=None, sigma=None, bounds=None,
        weights=None, t0: float | None = None, horizons=HORIZONS, tol: float = 1e-12, max_nfev: int = 200,
        identifiability_tol: float = 1e-6):
    """Fit ``free`` (names of runtime parameters and/or initial states) of ``system`` to ``observed`` {state or
    observable name: values at ``times``} (NaN: missing) from the start ``pars`` and ``state`` (the state at ``t0``,
    default ``times[0]``); returns a dataset of kind ``fit`` (:mod:`.fit_dataset`).

    sigma: the samples' standard deviations (number or {name: number or array}); without it the covariance is
    scaled by the residual variance. bounds: {name: (lower, upper)} (None: unbounded). weights: relative weights
    like sigma^-2. horizons: the continuation in the horizon (fractions of the record; (1.0,) for one solve).
    tol: the Taylor integrator's tolerance. identifiability_tol: a singular value of the column-scaled Jacobian
    below it names a combination the data cannot determine (status ``not_identifiable``).
    """
    problem = FitProblem(system, times, observed, free, pars=pars, state=state, sigma=sigma, weights=weights, t0=t0,
                         tol=tol)
    stages = solve(problem, bounds=bounds, horizons=horizons, max_nfev=max_nfev)
    config = {"free": problem.free, "observed": problem.names, "t0": problem.t0,
              "horizons": [float(h) for h in horizons], "tol": float(tol), "max_nfev": int(max_nfev),
              "identifiability_tol": float(identifiability_tol), "sigma_given": int(problem.sigma_given),
              "bounds": {k: [None if b is None or not np.isfinite(float(b)) else float(b) for b in v]
                         for k, v in (bounds or {}).items()},
              "start": dict(zip(problem.free, map(float, problem.start)))}
    return fit_dataset(problem, stages, config, identifiability_tol)
