"""Reference implementations for the tests and benchmarks: simple, slow, independent of the fast paths.

Nothing in the library imports this module (tests/test_layering.py fails if anything does).
"""

from __future__ import annotations

import copy
import functools

import heyoka as hy
import numpy as np

from .analysis import outcome_config
from .analysis import outcome_rules as rules
from .analysis import reduced
from .models import ode


def finite_difference_jacobian(state, pars, h: float = 1e-6) -> np.ndarray:
    """Central differences of the compiled reduced right-hand side, shape (7, 7)."""
    x = np.asarray(state, dtype=float).reshape(reduced.N_STATE)
    steps = h * (1.0 + np.abs(x))
    plus = x[:, None] + np.diag(steps)
    minus = x[:, None] - np.diag(steps)
    pars = np.asarray(pars, dtype=float)
    fp = reduced.evaluate(plus, pars)["rhs"]
    fm = reduced.evaluate(minus, pars)["rhs"]
    return (fp - fm) / (2 * steps[None, :])


class _FirstCrossing:
    """nt_event callback: the time of the first crossing."""

    def __init__(self):
        self.first = outcome_config.FILL_TIME

    def __call__(self, ta, time, d_sign):
        if self.first == outcome_config.FILL_TIME:
            self.first = time


@functools.lru_cache(maxsize=4)
def _scalar_integrator(tol: float):
    """Scalar heyoka integrator of the outcome map's augmented system (the batch kernel's twin)."""
    system, extra, crossings = rules.augmented_system()
    return system.taylor(tol, events=("fell",), extra=extra, nt_events=tuple((x, _FirstCrossing(), d)
                                                                             for x, d in crossings))


def outcome_chunk_scalar(config: outcome_config.MapConfig | dict, start: int, stop: int) -> dict:
    """The same as :func:`.outcome_map.run_chunk`, one run at a time with a scalar integrator."""
    if isinstance(config, dict):
        config = outcome_config.MapConfig.from_dict(config)
    x0, pars = outcome_config.prepare(config, start, stop)
    n = stop - start
    n_state = x0.shape[0] - 2
    i_gamma = ode.EULER.state_names.index("gamma")
    raw = {"final_state": np.empty_like(x0), "t_final": np.empty(n), "t_window": np.zeros(n),
           "q_window": np.zeros((2, n)), "gamma_window": x0[i_gamma].copy(), "fell": np.zeros(n, bool),
           "failed": np.zeros(n, bool), "inversion_time": np.full(n, outcome_config.FILL_TIME),
           "lift_off_time": np.full(n, outcome_config.FILL_TIME)}
    t_w = config.t_end - config.window
    ta = copy.copy(_scalar_integrator(float(config.tol)))
    for i in range(n):
        ta.time = 0.0
        ta.state[:] = x0[:, i]
        ta.pars[:] = pars[:, i]
        ta.reset_cooldowns()
        inversion, lift_off = (event.callback for event in ta.nt_events)
        inversion.first = lift_off.first = outcome_config.FILL_TIME
        for t_target in ((t_w,) if t_w > 0 else ()) + (config.t_end,):
            outcome = ta.propagate_until(t_target)[0]
            if outcome != hy.taylor_outcome.time_limit:
                raw["fell" if int(outcome) == -1 else "failed"][i] = True
                break
            if t_target == t_w:
                raw["q_window"][:, i] = ta.state[n_state:]
                raw["gamma_window"][i] = ta.state[i_gamma]
                raw["t_window"][i] = t_w
        raw["final_state"][:, i] = ta.state
        raw["t_final"][i] = ta.time
        raw["inversion_time"][i] = inversion.first
        raw["lift_off_time"][i] = lift_off.first
    return rules._finish(config, rules.kernel(float(config.tol), int(config.batch_size)), raw, pars)


def segment_flow(system, pars, x, duration: float) -> tuple[np.ndarray, np.ndarray]:
    """(x(duration), its state Jacobian) of a :class:`~tippedisk_analysis.dynamics.System` by scipy's DOP853 at
    rtol = atol = 1e-13 on the variational equations (independent of heyoka)."""
    from scipy.integrate import solve_ivp

    n = system.n

    def rhs(_t, z):
        return np.concatenate([system.f(z[:n], pars), (system.jacobian(z[:n], pars) @ z[n:].reshape(n, n)).ravel()])

    sol = solve_ivp(rhs, (0.0, duration), np.concatenate([x, np.eye(n).ravel()]), method="DOP853", rtol=1e-13,
                    atol=1e-13)
    if not sol.success:
        raise RuntimeError(sol.message)
    return sol.y[:n, -1], sol.y[n:, -1].reshape(n, n)


def shooting_referee(system, pars, starts, period: float, iterations: int = 8) -> tuple[float, list]:
    """A periodic orbit by multiple shooting on len(starts) segments of equal length: (period, the segments'
    Jacobians) after Newton's iteration on x_k+1 = phi(x_k, T / K) (x_K = x_0) with the phase
    (x_0 - x_0^start) . f(x_0^start) = 0, every flow by :func:`segment_flow`."""
    K, n = starts.shape
    x, T = np.array(starts, dtype=float), float(period)
    anchor, f_anchor = x[0].copy(), system.f(x[0], pars)
    for _ in range(iterations):
        ends, jacobians = zip(*(segment_flow(system, pars, x[k], T / K) for k in range(K)))
        F = np.concatenate([np.concatenate([ends[k] - x[(k + 1) % K] for k in range(K)]),
                            [(x[0] - anchor) @ f_anchor]])
        J = np.zeros((K * n + 1, K * n + 1))
        for k in range(K):
            J[k * n:(k + 1) * n, k * n:(k + 1) * n] = jacobians[k]
            J[k * n:(k + 1) * n, ((k + 1) % K) * n:((k + 1) % K + 1) * n] -= np.eye(n)
            J[k * n:(k + 1) * n, -1] = system.f(ends[k], pars) / K
        J[-1, :n] = f_anchor
        step = np.linalg.lstsq(J, -F, rcond=None)[0]
        x += step[:-1].reshape(K, n)
        T += step[-1]
        if np.max(np.abs(step)) < 1e-12 * (1 + T):
            break
    return T, [segment_flow(system, pars, x[k], T / K)[1] for k in range(K)]


def product_multipliers(jacobians) -> list:
    """The eigenvalues of the product of the segments' Jacobians in 100-digit arithmetic (mpmath), by modulus
    descending."""
    import mpmath

    mpmath.mp.dps = 100
    M = mpmath.eye(len(jacobians[0]))
    for J in jacobians:
        M = mpmath.matrix(np.asarray(J).tolist()) * M
    return sorted(mpmath.eig(M)[0], key=lambda z: -abs(z))
