"""Periodic orbits of a :class:`.system.System` by (multiple) shooting: the continuation problem.

m segments (m = 1: single shooting) of duration T/m from the points x_0 .. x_{m-1}; unknowns
u = (x_0, .., x_{m-1}, T[, p]); equations phi(x_k, T/m) - x_{k+1} = 0 (x_m = x_0 + shift; shift: multiples of
2 pi in angle components), a phase condition, and the levels of first integrals and pinned states
(:mod:`.orbit_base`):

* ``poincare``: (x_0 - x_ref) . f(x_ref) = 0, the hyperplane through the reference orbit's first point
  orthogonal to the flow there;
* ``integral``: int_0^1 (x(tau) - x_ref(tau)) . f(x_ref(tau)) d tau = 0 (periodic trapezoid rule on
  ``samples`` points), the orbit's phase closest to the reference's (AUTO's condition).

During continuation the reference is the last orbit found (:meth:`.continuation.Problem.set_reference`).
Newton (Gauss-Newton) uses the exact Jacobian: blocks phi_x (the variational equations), -I, f(phi)/m for T
and phi_p for the parameter. The monodromy is the product of the segments' phi_x.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ParameterError
from .flows import TAYLOR_TOL, Flow, FlowError
from .orbit_base import N_SAMPLES, OrbitProblem, PeriodicOrbit, orbit_size
from .system import System


class ShootingProblem(OrbitProblem):
    """Periodic orbits of ``system`` by (multiple) shooting; a continuation problem if ``parameter`` is set.

    Unknowns u = (x_0, .., x_{m-1}, T[, p]); residual [phi(x_k, T/m) - x_{k+1} (k < m), phase]; the state
    Jacobian of the continuation core is the deflated monodromy (its eigenvalues: the nontrivial
    multipliers), so special points come from the multipliers (module docstring).
    """

    def __init__(self, system: System, pars=None, *, segments: int = 1, phase: str = "poincare",
                 parameter: str | None = None, parameter_scale: float = 1.0, period_scale: float = 1.0,
                 bounds: dict | None = None, shift=None, tol: float = TAYLOR_TOL, samples: int = N_SAMPLES,
                 levels: dict | None = None, pins: dict | None = None):
        if int(segments) != segments or segments < 1:
            raise ParameterError(f"segments = {segments!r}; give a positive integer")
        if phase not in ("poincare", "integral"):
            raise ParameterError(f"phase condition {phase!r} unknown; give 'poincare' or 'integral'")
        if samples % segments:
            samples = segments * math.ceil(samples / segments)
        self.m, self.phase, self.samples = int(segments), phase, int(samples)
        super().__init__(system, pars, self.m, parameter=parameter, levels=levels, pins=pins, bounds=bounds)
        n = self.n
        self.flow = Flow(system, tol, () if self.p_index is None else (self.p_index,))
        self.shift = np.zeros(n) if shift is None else np.asarray(shift, dtype=float)
        self.names = tuple(f"{s}[{k}]" for k in range(self.m) for s in system.state_names) + (
            ("T",) + ((parameter,) if parameter else ()))
        self.scale = np.array([*np.tile(system.state_scale, self.m), period_scale]
                              + ([parameter_scale] if parameter else []), dtype=float)
        self._tau = np.arange(self.samples) / self.samples  # integral phase condition: tau_j = j / N
        self._ref = None
        self._memo: dict = {}

    method = "shooting"

    @property
    def node_times(self) -> np.ndarray:
        """tau = t / T of the segment starts (m,)."""
        return np.arange(self.m) / self.m

    def config(self) -> dict:
        return {"method": "shooting", "segments": self.m, "phase": self.phase, "tol": self.flow.tol}

    # -- unknowns
    def unknowns(self, state, period: float, value: float | None = None) -> np.ndarray:
        """u from one point of the orbit and its period (segment points by integration)."""
        pars = self.pars.copy()
        if self.p_index is not None:
            if value is None:
                value = pars[self.p_index]
            pars[self.p_index] = value
        X = [np.asarray(state, dtype=float)]
        for _ in range(1, self.m):
            X.append(self.flow.advance(X[-1], period / self.m, pars))
        return np.concatenate([np.ravel(X), [period], [value] if self.parameter else []])

    # -- evaluation (cached: the core asks for the residual, the Jacobian and the state Jacobian at one u)
    def _evaluate(self, u) -> dict:
        key = np.asarray(u, dtype=float).tobytes()
        hit = self._memo.get(key)
        if hit is not None:
            return hit
        X, T, _p = self.split(u)
        pars = self.runtime(u)
        n, m = self.n, self.m
        h = T / m
        ends, Phis, Phips, grid = [], [], [], []
        per = self.samples // m
        try:
            if not (math.isfinite(T) and T > 0):
                raise FlowError(f"the period T = {T:.6g} is not positive")
            for k in range(m):
                times = (self._tau[k * per:(k + 1) * per] - k / m) * T if self.phase == "integral" else None
                y, Phi, Phip, gp = self.flow.variational(X[k], h, pars, times)
                ends.append(y)
                Phis.append(Phi)
                Phips.append(Phip)
                grid.append(gp)
        except FlowError as exc:
            out = {"error": str(exc)}
            self._remember(key, out)
            return out
        nu = len(u)
        F = np.empty(n * m)
        A = np.zeros((n * m, nu))
        for k in range(m):
            rows = slice(k * n, (k + 1) * n)
            nxt = X[(k + 1) % m] + (self.shift if k == m - 1 else 0.0)
            F[rows] = ends[k] - nxt
            A[rows, k * n:(k + 1) * n] = Phis[k]
            j = (k + 1) % m
            A[rows, j * n:(j + 1) * n] -= np.eye(n)
            A[rows, self.t_index] = self.flow.rhs(ends[k], pars) / m
            if self.p_index is not None:
                A[rows, self.t_index + 1] = Phips[k][:, 0]
        M = np.eye(n)
        for Phi in Phis:
            M = Phi @ M
        k0 = m // 2  # the point half a period on: the signed amplitude x_0 - x(T/2) vanishes at a Hopf point
        try:
            x_half = X[k0] if 2 * k0 == m else self.flow.advance(X[k0], (0.5 - k0 / m) * T, pars)
        except FlowError as exc:
            out = {"error": str(exc)}
            self._remember(key, out)
            return out
        out = {"F": F, "A": A, "M": M, "pars": pars, "X": X, "T": T, "ends": ends, "grid": grid,
               "f0": self.flow.rhs(X[0], pars), "half": (X[0] - x_half) / np.asarray(self.system.state_scale),
               "size": orbit_size(np.vstack([X, x_half, *(g[0] for g in grid if g is not None)]),
                                  self.system.state_scale)}
        self._remember(key, out)
        return out

    def _remember(self, key, value) -> None:
        if len(self._memo) > 8:
            self._memo.pop(next(iter(self._memo)))
        self._memo[key] = value

    def _phase_row(self, ev: dict, u) -> tuple[float, np.ndarray]:
        row = np.zeros(len(u))
        if self._ref is None:
            raise RuntimeError("set_reference was not called")  # pragma: no cover
        if self.phase == "poincare":
            x_ref, f_ref = self._ref
            row[: self.n] = f_ref
            return float((ev["X"][0] - x_ref) @ f_ref), row
        x_ref, f_ref = self._ref  # (N, n) each
        w = 1.0 / self.samples
        per = self.samples // self.m
        value = 0.0
        for k in range(self.m):
            xs, Phis, Phips = ev["grid"][k]
            fr = f_ref[k * per:(k + 1) * per]
            value += w * np.sum((xs - x_ref[k * per:(k + 1) * per]) * fr)
            row[k * self.n:(k + 1) * self.n] = w * np.einsum("ji,jik->k", fr, Phis)
            local = self._tau[k * per:(k + 1) * per] - k / self.m
            fx = self.flow.rhs(xs.T, ev["pars"]).T
            row[self.t_index] += w * np.sum(np.sum(fr * fx, axis=1) * local)
            if self.p_index is not None:
                row[self.t_index + 1] += w * np.einsum("ji,jik->k", fr, Phips)[0]
        return value, row

    def set_reference(self, u) -> None:
        ev = self._evaluate(u)
        if "error" in ev:
            return
        self._remember_half(ev)
        if self.phase == "poincare":
            self._ref = (ev["X"][0].copy(), ev["f0"].copy())
        else:
            xs = np.vstack([g[0] for g in ev["grid"]])
            self._ref = (xs, self.flow.rhs(xs.T, ev["pars"]).T.copy())

    def residual(self, u) -> np.ndarray:
        ev = self._evaluate(u)
        if "error" in ev:
            return np.full(self.n * self.m + 1 + len(self.level_names), np.nan)
        return np.concatenate([ev["F"], [self._phase_row(ev, u)[0]], self.level_rows(u, ev["X"][0])[0]])

    def jacobian(self, u) -> np.ndarray:
        ev = self._evaluate(u)
        if "error" in ev:
            return np.full((self.n * self.m + 1 + len(self.level_names), len(u)), np.nan)
        return np.vstack([ev["A"], self._phase_row(ev, u)[1], self.level_rows(u, ev["X"][0])[1]])

    # -- the orbit traversed twice (period doubling)
    def propagate(self, u, v) -> np.ndarray:
        """The variation v at x_0 carried along the orbit to the segment starts, (m, n)."""
        X, T, _p = self.split(u)
        out = [np.asarray(v, dtype=float)]
        for k in range(self.m - 1):
            out.append(self.flow.variational(X[k], T / self.m, self.runtime(u))[1] @ out[-1])
        return np.array(out)

    def doubled(self, u) -> tuple[ShootingProblem, np.ndarray]:
        """The problem of twice the period (2m segments) and u as its solution, the orbit traversed twice."""
        X, T, p = self.split(u)
        bounds = {("T" if i == self.t_index else self.parameter): ((2 * lo, 2 * hi) if i == self.t_index else (lo, hi))
                  for i, (lo, hi) in self.bounds.items()}
        double = ShootingProblem(self.system, self.runtime(u), segments=2 * self.m, phase=self.phase,
                                 parameter=self.parameter, parameter_scale=self.scale[-1], period_scale=2 * self.scale[
                                     self.t_index], bounds=bounds, tol=self.flow.tol, samples=2 * self.samples,
                                 levels=self.levels, pins=self.pins)
        return double, np.concatenate([X.ravel(), X.ravel(), [2 * T, p]])

    # -- orbits
    def orbit(self, u, status: str = "converged", message: str = "", residual: float | None = None,
              iterations: int = 0, n_samples: int = N_SAMPLES, discretisation=None):
        """The orbit at u with samples, multipliers and amplitude measures (``discretisation``: unused, the
        segments are fixed)."""
        X, T, p = self.split(u)
        pars = self.runtime(u)
        ev = self._evaluate(u)
        if "error" in ev:
            raise FlowError(ev["error"])
        mu, trivial = self.floquet(ev)
        times = T * np.arange(n_samples) / n_samples
        samples = self.flow.trajectory(X[0], times, pars)
        if residual is None:
            residual = float(np.max(np.abs(self.residual(u)[: self.n * self.m]) / np.tile(self.system.state_scale,
                                                                                        self.m)))
        return PeriodicOrbit(status, message, self.system, pars, X.copy(), T, p, self.parameter, residual, iterations,
                             mu, trivial, times, samples, self.flow.observables(samples.T, pars).T
                             if self.system.observables else np.empty((n_samples, 0)),
                             flow_multiplier_error=self.flow_multiplier_error(u))
