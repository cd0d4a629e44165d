"""Periodic orbits of a :class:`.system.System` by (multiple) shooting: the continuation problem, and the
record of an orbit (:class:`PeriodicOrbit`).

m segments (m = 1: single shooting) of duration T/m from the points x_0 .. x_{m-1}; unknowns
u = (x_0, .., x_{m-1}, T[, p]); equations phi(x_k, T/m) - x_{k+1} = 0 (x_m = x_0 + shift; shift: multiples of
2 pi in angle components), a phase condition, the levels of the system's first integrals and of the pinned
states (``pins``: x_0[i] = level, which picks one orbit of a family that no first integral labels, e.g. the
symmetric orbits of a reversible system):

* ``poincare``: (x_0 - x_ref) . f(x_ref) = 0, the hyperplane through the reference orbit's first point
  orthogonal to the flow there;
* ``integral``: int_0^1 (x(tau) - x_ref(tau)) . f(x_ref(tau)) d tau = 0 (periodic trapezoid rule on
  ``samples`` points), the orbit's phase closest to the reference's (AUTO's condition).

During continuation the reference is the last orbit found (:meth:`.continuation.Problem.set_reference`).
Newton (Gauss-Newton) uses the exact Jacobian: blocks phi_x (the variational equations), -I, f(phi)/m for T
and phi_p for the parameter. The state Jacobian of the continuation core is the monodromy with the flow
direction deflated exactly (:func:`.flows.deflate`), so its eigenvalues are the nontrivial multipliers and
the special points come from them (:mod:`.orbit_branches`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from . import continuation
from .flows import MULTIPLIER_TOL, TAYLOR_TOL, Flow, FlowError, classify, deflate, floquet
from .system import System

N_SAMPLES = 128  # samples stored per orbit (and of the integral phase condition)


class ShootingProblem(continuation.Problem):
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
        self.system, self.m, self.phase, self.samples = system, int(segments), phase, int(samples)
        self.n = n = system.n
        self.pars = np.array(system.pars if pars is None else pars, dtype=float)
        self.integral_names = tuple(system.integrals)
        self.pins = {name: float(v) for name, v in (pins or {}).items()}
        self._pin_index = [system.state_index(name) for name in self.pins]
        self.level_names = (*self.integral_names, *self.pins)
        self.level_parameter = parameter if parameter in self.level_names else None
        self.p_index = None if parameter is None or self.level_parameter else system.parameter_index(parameter)
        self.parameter = parameter
        self.levels = dict(levels or {})
        missing = [name for name in self.integral_names if name not in self.levels and name != self.level_parameter]
        if missing:
            raise ParameterError(f"{system.name} has first integrals: give the levels of {', '.join(missing)} "
                                 "(find_orbit takes them from the guess)")
        self._integrals = system.integrals_field() if system.integrals else None
        self.flow = Flow(system, tol, () if self.p_index is None else (self.p_index,))
        self.shift = np.zeros(n) if shift is None else np.asarray(shift, dtype=float)
        self.names = tuple(f"{s}[{k}]" for k in range(self.m) for s in system.state_names) + (
            ("T",) + ((parameter,) if parameter else ()))
        self.scale = np.array([*np.tile(system.state_scale, self.m), period_scale]
                              + ([parameter_scale] if parameter else []), dtype=float)
        self.t_index = n * self.m
        self.parameters = (self.t_index + 1,) if parameter else ()
        self.bounds = {}
        for name, (low, high) in (bounds or {}).items():
            index = {"T": self.t_index, parameter: self.t_index + 1}.get(name)
            if index is None:
                raise ParameterError(f"bound on {name!r}: give bounds on T or the continuation parameter {parameter}")
            self.bounds[index] = (float(low), float(high))
        self._tau = np.arange(self.samples) / self.samples  # integral phase condition: tau_j = j / N
        self._ref = None
        self._half_ref = np.zeros(n)
        self._half_ref_norm = 0.0
        self.terminal = frozenset({"hopf"})
        self._memo: dict = {}

    # -- unknowns
    def split(self, u):
        u = np.asarray(u, dtype=float)
        X = u[: self.t_index].reshape(self.m, self.n)
        return X, float(u[self.t_index]), (float(u[self.t_index + 1]) if self.parameter else None)

    def runtime(self, u) -> np.ndarray:
        pars = self.pars.copy()
        if self.p_index is not None:
            pars[self.p_index] = u[self.t_index + 1]
        return pars

    def _level_rows(self, u, X0) -> tuple[np.ndarray, np.ndarray]:
        """I_j(x_0) - c_j and their gradients (rows of the Jacobian) for the first integrals, then
        x_0[i] - c_i for the pinned states."""
        k = len(self.level_names)
        if not k:
            return np.empty(0), np.empty((0, len(u)))
        rows = np.zeros((k, len(u)))
        values = np.empty(k)
        n_int = len(self.integral_names)
        if n_int:
            pars = self.runtime(u)
            values[:n_int] = self._integrals.values(X0, pars)
            rows[:n_int, : self.n] = self._integrals.tensor(X0, pars, 1, with_parameters=False)
        for j, i in enumerate(self._pin_index):
            values[n_int + j] = X0[i]
            rows[n_int + j, i] = 1.0
        target = np.array([self.levels.get(name, math.nan) for name in self.integral_names]
                          + list(self.pins.values()))
        if self.level_parameter:
            j = self.level_names.index(self.level_parameter)
            target[j] = u[self.t_index + 1]
            rows[j, self.t_index + 1] = -1.0
        return values - target, rows

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
               "f0": self.flow.rhs(X[0], pars), "half": (X[0] - x_half) / np.asarray(self.system.state_scale)}
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
        self._half_ref_norm = float(np.linalg.norm(ev["half"]))
        self._half_ref = ev["half"] / (self._half_ref_norm or 1.0)
        if self.phase == "poincare":
            self._ref = (ev["X"][0].copy(), ev["f0"].copy())
        else:
            xs = np.vstack([g[0] for g in ev["grid"]])
            self._ref = (xs, self.flow.rhs(xs.T, ev["pars"]).T.copy())

    def residual(self, u) -> np.ndarray:
        ev = self._evaluate(u)
        if "error" in ev:
            return np.full(self.n * self.m + 1 + len(self.level_names), np.nan)
        return np.concatenate([ev["F"], [self._phase_row(ev, u)[0]], self._level_rows(u, ev["X"][0])[0]])

    def jacobian(self, u) -> np.ndarray:
        ev = self._evaluate(u)
        if "error" in ev:
            return np.full((self.n * self.m + 1 + len(self.level_names), len(u)), np.nan)
        return np.vstack([ev["A"], self._phase_row(ev, u)[1], self._level_rows(u, ev["X"][0])[1]])

    def monodromy(self, u) -> np.ndarray:
        ev = self._evaluate(u)
        if "error" in ev:
            return np.full((self.n, self.n), np.nan)
        return ev["M"]

    def state_jacobian(self, u) -> np.ndarray:
        ev = self._evaluate(u)
        if "error" in ev:
            return np.full((self.n - 1, self.n - 1), np.nan)
        return deflate(ev["M"], ev["f0"])

    def second_derivative(self, u, a, b):  # pragma: no cover - branch switching of cycles uses directions
        raise ParameterError("periodic-orbit problems switch branches along critical eigenvectors, "
                             "not by the algebraic bifurcation equations")

    # -- test functions on the nontrivial multipliers (the deflated monodromy's eigenvalues)
    def _nontrivial(self, mu: np.ndarray) -> np.ndarray:
        mu = np.asarray(mu)
        for _ in range(self.system.n_trivial - 1):
            if len(mu):
                mu = np.delete(mu, np.argmin(np.abs(mu - 1.0)))
        return mu

    def tests(self, point) -> dict:
        mu = self._nontrivial(point.eigenvalues)
        i, j = np.triu_indices(len(mu), 1)
        tests = {"fold": float(point.tangent[self.parameters[0]]), "branch_point": _signed_product(mu - 1.0),
                 "period_doubling": _signed_product(mu + 1.0), "neimark_sacker": _signed_product(mu[i] * mu[j] - 1.0),
                 "hopf": self._signed_amplitude(point.u)}
        if self.integral_names:  # conservative: pairs on the unit circle are generic (elliptic), not a bifurcation
            del tests["neimark_sacker"]
        return tests

    def _signed_amplitude(self, u) -> float:
        """(x_0 - x(T/2)) / scale along the reference orbit's: changes sign where the branch passes through a
        Hopf point (zero amplitude; beyond it the same orbits return shifted by half a period)."""
        ev = self._evaluate(u)
        return math.nan if "error" in ev else float(ev["half"] @ self._half_ref)

    def located_value(self, kind: str, point) -> float:
        mu = self._nontrivial(point.eigenvalues)
        if kind == "fold":
            return float(point.tangent[self.parameters[0]])
        if kind == "hopf":
            return self._signed_amplitude(point.u)
        real = mu[np.abs(mu.imag) <= 1e-9 * max(1.0, np.abs(mu).max(initial=1.0))].real
        if kind == "branch_point":
            return float(real[np.argmin(np.abs(real - 1.0))] - 1.0) if real.size else math.nan
        if kind == "period_doubling":
            negative = real[real < 0]
            return float(-negative[np.argmin(np.abs(negative + 1.0))] - 1.0) if negative.size else math.nan
        if kind == "neimark_sacker":
            pairs = mu[mu.imag > 1e-9 * max(1.0, np.abs(mu).max(initial=1.0))]
            return float(np.abs(pairs[np.argmin(np.abs(np.abs(pairs) - 1.0))]) - 1.0) if pairs.size else math.nan
        return self.tests(point)[kind]

    def accept(self, kind: str, point, value: float, options) -> bool:
        if kind in ("period_doubling", "neimark_sacker", "branch_point"):
            return math.isfinite(value) and abs(value) <= max(MULTIPLIER_TOL, options.locate_tol)
        if kind in ("fold", "hopf"):
            # at a Hopf end the parameter turns too (p - p_H ~ r^2): not a fold of cycles; and the projected
            # amplitude of a large orbit may change sign as its shape turns: a Hopf end needs amplitude zero
            ev = self._evaluate(point.u)
            small = "error" not in ev and float(np.linalg.norm(ev["half"])) <= 1e-3 * self._half_ref_norm
            return ("error" not in ev) and (small if kind == "hopf" else not small)
        return True

    def describe(self, kind: str, u) -> dict:
        ev = self._evaluate(u)
        if "error" in ev:
            return {}
        mu, trivial = floquet(ev["M"], ev["f0"], self.system.n_trivial)
        rest = mu[~trivial]
        target = {"fold": 1.0, "branch_point": 1.0, "period_doubling": -1.0}.get(kind)
        if target is not None:
            crit = rest[np.argmin(np.abs(rest - target))]
        else:
            pairs = rest[np.abs(rest.imag) > 1e-9]
            crit = pairs[np.argmin(np.abs(np.abs(pairs) - 1.0))] if pairs.size else complex(math.nan)
        data = {"period": ev["T"], "multiplier_real": float(np.real(crit)), "multiplier_imag": float(np.imag(crit))}
        if kind == "hopf":
            data["frequency"] = 2 * math.pi / ev["T"]
        if kind == "neimark_sacker":
            theta = abs(float(np.angle(crit)))
            data["angle"] = theta
            data["strong_resonance"] = float(any(abs(theta - 2 * math.pi / q) < 1e-3 for q in (1, 2, 3, 4)))
        return data

    # -- orbits
    def orbit(self, u, status: str = "converged", message: str = "", residual: float | None = None,
              iterations: int = 0, n_samples: int = N_SAMPLES):
        """The orbit at u with samples, multipliers and amplitude measures."""
        X, T, p = self.split(u)
        pars = self.runtime(u)
        ev = self._evaluate(u)
        if "error" in ev:
            raise FlowError(ev["error"])
        mu, trivial = floquet(ev["M"], ev["f0"], self.system.n_trivial)
        times = T * np.arange(n_samples) / n_samples
        samples = self.flow.trajectory(X[0], times, pars)
        if residual is None:
            residual = float(np.max(np.abs(self.residual(u)[: self.n * self.m]) / np.tile(self.system.state_scale,
                                                                                        self.m)))
        return PeriodicOrbit(status, message, self.system, pars, X.copy(), T, p, self.parameter, residual, iterations,
                             mu, trivial, times, samples, self.flow.observables(samples.T, pars).T
                             if self.system.observables else np.empty((n_samples, 0)))


def _signed_product(values: np.ndarray) -> float:
    """Real part of prod(values) without over/underflow: sign times a bounded magnitude."""
    prod = complex(1.0)
    log_mag = 0.0
    for v in np.asarray(values, dtype=complex):
        a = abs(v)
        if a == 0:
            return 0.0
        prod *= v / a
        log_mag += math.log(a)
    return float(prod.real * math.exp(max(min(log_mag, 600.0), -600.0)))


@dataclass
class PeriodicOrbit:
    """A periodic orbit (status ``converged``) or the outcome of a Newton search that found none."""

    status: str  # a key of STATUS
    message: str
    system: System
    pars: np.ndarray
    states: np.ndarray  # (m, n) segment start points
    period: float
    value: float | None  # the continuation parameter's value (None: no parameter)
    parameter: str | None
    residual: float  # max |phi(x_k) - x_{k+1}| / scale
    iterations: int
    multipliers: np.ndarray  # complex (n,), by modulus descending
    trivial: np.ndarray  # bool (n,)
    times: np.ndarray  # (N,) sample times in [0, T)
    samples: np.ndarray  # (N, n)
    observables: np.ndarray  # (N, n_obs)

    @property
    def converged(self) -> bool:
        return self.status == "converged"

    @property
    def stability(self) -> int:
        return classify(self.multipliers, self.trivial)[0]

    @property
    def n_unstable(self) -> int:
        return classify(self.multipliers, self.trivial)[1]

    @property
    def amplitude(self) -> float:
        """``max_t |x(t) - mean x|`` in scaled units (x / state_scale)."""
        d = (self.samples - self.samples.mean(axis=0)) / np.asarray(self.system.state_scale)
        return float(np.sqrt((d * d).sum(axis=1)).max())

    @property
    def exponents(self) -> np.ndarray:
        """Floquet exponents log|mu| / T [1/s] (the growth rates of perturbations)."""
        with np.errstate(divide="ignore"):
            return np.log(np.abs(self.multipliers)) / self.period
