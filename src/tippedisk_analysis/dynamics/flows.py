"""Integration of a :class:`.system.System` with its first-order variational equations, and Floquet
multipliers of a monodromy matrix.

A :class:`Flow` holds its own copies of the system's Taylor integrators (templates compiled once per system,
:meth:`.system.System.taylor`), so each thread of an analysis makes its own. The monodromy matrix comes from the
same Taylor steps as the orbit (heyoka's ``var_ode_sys``).
"""

from __future__ import annotations

import copy

import heyoka as hy
import numpy as np

from .spectra import STABILITY_FLAGS as STABILITY
from .system import System

TAYLOR_TOL = 1e-14  # the orbits close to ~1e-13 (relative), far below the Newton tolerance
MAX_STEPS = 200_000  # Taylor steps per integration before it counts as failed (a wild Newton iterate)
MULTIPLIER_TOL = 1e-6  # |mu| within 1 +- this: marginal (also the acceptance of located PD / NS points)


class FlowError(Exception):
    """An integration did not reach its end time (non-finite state)."""


class Flow:
    """Integrators of one system (own copies: not shared between threads)."""

    def __init__(self, system: System, tol: float = TAYLOR_TOL, free: tuple = ()):
        self.system, self.tol, self.free = system, tol, tuple(free)
        self.n = system.n
        self._var = copy.copy(system.taylor(tol, tangents=system.n, parameters=self.free))
        self._plain = copy.copy(system.taylor(tol))
        self.n_args = self.n + len(self.free)
        self._identity = np.hstack([np.eye(self.n), np.zeros((self.n, len(self.free)))]).ravel()

    @staticmethod
    def _load(ta, pars) -> None:
        ta.pars[:] = np.asarray(pars, dtype=float)[: len(ta.pars)]

    def rhs(self, x, pars) -> np.ndarray:
        """f at states x (n,) or (n, N)."""
        return self.system.evaluate(self.system.rhs_function(), x, pars)

    def observables(self, X, pars) -> np.ndarray:
        """Observables at states X (n, N), shape (n_obs, N)."""
        return self.system.evaluate(self.system.observables_function(), np.asarray(X).reshape(self.n, -1), pars)

    def variational(self, x, t: float, pars, grid=None):
        """Integrate x and its variations from 0 to t: (end state, phi_x (n, n), phi_p (n, k)) and, if
        ``grid`` (times in [0, t], first 0) is given, the states (G, n) and phi_x, phi_p on it."""
        ta = self._var
        ta.time = 0.0
        self._load(ta, pars)
        st = ta.state
        st[: self.n] = x
        st[self.n:] = self._identity
        if grid is None:
            outcome = ta.propagate_until(float(t), max_steps=MAX_STEPS)[0]
            if outcome != hy.taylor_outcome.time_limit:
                raise FlowError(f"the integration stopped ({outcome!r}) at t = {ta.time:.6g} of {t:.6g}")
            out = np.array(ta.state)
            grid_part = None
        else:
            g = np.append(np.asarray(grid, dtype=float), float(t))
            res = ta.propagate_grid(g, max_steps=MAX_STEPS)
            outcome, states = res[0], np.asarray(res[-1])
            if outcome != hy.taylor_outcome.time_limit or len(states) != len(g):
                raise FlowError(f"the integration stopped ({outcome!r}) at t = {ta.time:.6g} of {t:.6g}")
            out = states[-1]
            gs = states[:-1]
            G = gs[:, self.n:].reshape(len(gs), self.n, self.n_args)
            grid_part = (gs[:, : self.n], G[:, :, : self.n], G[:, :, self.n:])
        if not np.all(np.isfinite(out)):
            raise FlowError(f"the state became non-finite before t = {t:.6g}")
        V = out[self.n:].reshape(self.n, self.n_args)
        return out[: self.n], V[:, : self.n], V[:, self.n:], grid_part

    def trajectory(self, x, times, pars) -> np.ndarray:
        """States (len(times), n) on ``times`` (first 0) without variations."""
        ta = self._plain
        ta.time = 0.0
        self._load(ta, pars)
        ta.state[:] = x
        res = ta.propagate_grid(np.asarray(times, dtype=float), max_steps=MAX_STEPS)
        states = np.asarray(res[-1])
        if res[0] != hy.taylor_outcome.time_limit or len(states) != len(times) or not np.all(np.isfinite(states)):
            raise FlowError(f"the integration stopped ({res[0]!r}) at t = {ta.time:.6g}")
        return states

    def advance(self, x, t: float, pars) -> np.ndarray:
        """The state at time t from x (no variations)."""
        ta = self._plain
        ta.time = 0.0
        self._load(ta, pars)
        ta.state[:] = x
        outcome = ta.propagate_until(float(t), max_steps=MAX_STEPS)[0]
        if outcome != hy.taylor_outcome.time_limit or not np.all(np.isfinite(ta.state)):
            raise FlowError(f"the integration stopped ({outcome!r}) at t = {ta.time:.6g} of {t:.6g}")
        return np.array(ta.state)


# ---------------------------------------------------------------------------- Floquet multipliers


def floquet(M: np.ndarray | None, flow_direction: np.ndarray, n_trivial: int = 1,
            eigen: tuple | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Multipliers (eigenvalues of M, or ``eigen`` = (values, vectors) computed otherwise, sorted by modulus,
    descending) and a mask of the trivial ones: the flow direction's (the eigenvector most parallel to f(x_0)
    among those with mu near 1), then the ``n_trivial`` - 1 others nearest 1."""
    vals, vecs = np.linalg.eig(M) if eigen is None else eigen
    order = np.argsort(-np.abs(vals), kind="stable")
    vals, vecs = vals[order], vecs[:, order]
    trivial = np.zeros(len(vals), bool)
    f = flow_direction / (np.linalg.norm(flow_direction) or 1.0)
    near = np.abs(vals - 1.0) <= 1e-3 + 1e-3 * np.abs(vals - 1.0).min()
    candidates = np.flatnonzero(near) if near.any() else np.arange(len(vals))
    align = np.abs(np.conj(vecs[:, candidates]).T @ f) / np.linalg.norm(vecs[:, candidates], axis=0)
    trivial[candidates[np.argmax(align - np.abs(vals[candidates] - 1.0))]] = True
    for _ in range(max(n_trivial - 1, 0)):
        rest = np.flatnonzero(~trivial)
        trivial[rest[np.argmin(np.abs(vals[rest] - 1.0))]] = True
    return vals, trivial


def deflate(M: np.ndarray, f: np.ndarray) -> np.ndarray:
    """The monodromy on the quotient by the flow direction: Q2^T M Q2, Q = [f/|f|, Q2] orthonormal.
    At an orbit M f = f, so Q^T M Q is block upper triangular and this block holds the other multipliers."""
    n = len(f)
    Q = np.linalg.qr(np.column_stack([f, np.eye(n)]))[0][:, :n]
    return Q[:, 1:].T @ M @ Q[:, 1:]


def classify(multipliers: np.ndarray, trivial: np.ndarray, tol: float = MULTIPLIER_TOL) -> tuple[int, int]:
    """(stability flag of :data:`.spectra.STABILITY_FLAGS`, number of nontrivial multipliers outside the unit
    circle)."""
    mod = np.abs(multipliers[~trivial])
    n_unstable = int(np.sum(mod > 1 + tol))
    if n_unstable:
        return STABILITY["unstable"], n_unstable
    return (STABILITY["stable"] if mod.size and np.all(mod < 1 - tol) else STABILITY["marginal"]), 0
