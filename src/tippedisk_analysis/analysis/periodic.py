"""Periodic orbits of autonomous ODEs: shooting with heyoka variational equations, Floquet multipliers,
branches of periodic orbits by pseudo-arclength continuation, and their bifurcations.

Generic (knows nothing of the disk); the tippedisk part is at the end of the module and, for the
model's friction (mu > 0, eps > 0), reports that there are no periodic orbits (docs/periodic_orbits.md).

**Systems.** An :class:`OdeSystem` is x' = f(x; p): heyoka variables and right-hand sides with runtime
parameters hy.par[i]. One Taylor integrator of the first-order variational equations
(``hy.var_ode_sys``, arguments: the states and the continued parameter) is compiled per (system,
tolerance, parameter) and process, and reused: the monodromy matrix comes from the same Taylor steps as
the orbit. :data:`TEXTBOOK` holds the systems the method is proven on (van der Pol, a rotated Hopf normal
form, the Bautin normal form, Roessler, a cycle times a Hopf normal form (Neimark-Sacker), a Hamiltonian
loop with energy-selecting damping (homoclinic), Lorenz for Lyapunov exponents).

**Shooting** (as AUTO / BifurcationKit / MatCont with shooting): m segments (m = 1: single shooting) of
duration T/m from the points x_0 .. x_{m-1}; unknowns u = (x_0, .., x_{m-1}, T[, p]); equations
phi(x_k, T/m) - x_{k+1} = 0 (x_m = x_0 + shift; shift: multiples of 2 pi in angle components), and a
phase condition:

* ``poincare``: (x_0 - x_ref) . f(x_ref) = 0, the hyperplane through the reference orbit's first point
  orthogonal to the flow there;
* ``integral``: int_0^1 (x(tau) - x_ref(tau)) . f(x_ref(tau)) d tau = 0 (periodic trapezoid rule on
  ``samples`` points), the orbit's phase closest to the reference's (AUTO's condition).

During continuation the reference is the last orbit found (:meth:`continuation.Problem.set_reference`).
Newton (Gauss-Newton, least-squares steps) uses the exact Jacobian: blocks phi_x (the variational
equations), -I, f(phi)/m for T and phi_p for the parameter.

**Floquet multipliers**: eigenvalues of the monodromy matrix M = phi_x(x_{m-1}) ... phi_x(x_0). The
trivial multiplier 1 of the flow direction (M f(x_0) = f(x_0)) is identified by its eigenvector and
deflated exactly for the test functions (the monodromy restricted to the quotient by f(x_0)); systems
with families of solutions declare further trivial multipliers (``n_trivial``), taken as those nearest 1.

**Special points** along a branch (test functions on the nontrivial multipliers mu_i; each located by
Brent's method on the arclength, on a smooth function: |mu| - 1 of the critical multiplier(s)):

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
  p - p_hc ~ exp(-lambda T).
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import math
import threading
from dataclasses import dataclass

import numpy as np
import xarray as xr

from ..compilation import compiling
from ..errors import ParameterError
from ..results import make_attrs
from . import continuation, normal_forms
from .vector_fields import CompiledField

TAYLOR_TOL = 1e-14  # the orbits close to ~1e-13 (relative), far below the Newton tolerance
NEWTON_TOL = 1e-10  # largest scaled Newton step at convergence
NEWTON_MAX_ITER = 25
MAX_STEPS = 200_000  # Taylor steps per integration before it counts as failed (a wild Newton iterate)
MAX_NEWTON_STEP = 0.5  # largest Newton step in scaled unknowns (a trust region: no jumps along near-null directions)
AMPLITUDE_TOL = 1e-7  # scaled amplitude below which a converged "orbit" is an equilibrium
MULTIPLIER_TOL = 1e-6  # |mu| within 1 +- this: marginal (also the acceptance of located PD / NS points)
N_SAMPLES = 128  # samples stored per orbit (and of the integral phase condition)

STATUS = {"converged": 0, "equilibrium": 1, "not_converged": 2, "nonfinite": 3}
STABILITY = {"stable": 0, "marginal": 1, "unstable": 2}
SPECIAL_KINDS = {"bound": 0, "fold": 1, "branch_point": 2, "period_doubling": 3, "neimark_sacker": 4,
                 "homoclinic": 5, "hopf": 6}


# ============================================================================ systems


@dataclass(frozen=True, eq=False)
class OdeSystem:
    """x' = f(x; p) as heyoka expressions.

    name: unique key of the compiled code (one name, one set of equations); variables / rhs: heyoka
    variables and right-hand sides (state_names order); pars: default runtime parameter values
    (hy.par[i] = pars[i]); parameter_names: their names; state_scale: typical magnitudes (Newton and
    continuation metric); n_trivial: trivial Floquet multipliers (1 + the number of independent first
    integrals or families of solutions); compact_mode: heyoka's compact mode for the variational
    integrator (large systems: compiles in seconds instead of minutes); observables: (name, units,
    expression) whose min/max over an orbit are stored as amplitude measures; integrals: (name, expression)
    first integrals (a conservative system's orbits come in families: the shooting problem pins their levels
    at x_0, a consistent overdetermined system that Gauss-Newton solves, and may continue in a level).
    """

    name: str
    state_names: tuple
    variables: tuple
    rhs: tuple
    pars: tuple
    parameter_names: tuple
    state_scale: tuple
    n_trivial: int = 1
    compact_mode: bool = False
    observables: tuple = ()
    description: str = ""
    integrals: tuple = ()  # (name, expression): first integrals; their levels are pinned (families of orbits)

    @property
    def n(self) -> int:
        return len(self.variables)

    def parameter_index(self, name: str) -> int:
        if name not in self.parameter_names:
            raise ParameterError(f"{self.name} has no parameter {name!r}; choose one of "
                                 f"{', '.join(self.parameter_names)}")
        return self.parameter_names.index(name)

    def with_pars(self, **values) -> np.ndarray:
        """The runtime parameter vector with some values replaced by name."""
        pars = np.array(self.pars, dtype=float)
        for name, value in values.items():
            pars[self.parameter_index(name)] = float(value)
        return pars


def _n_params(exprs) -> int:
    import heyoka as hy

    indices = [int(str(p)[1:]) for p in hy.get_params(list(exprs))]
    return max(indices) + 1 if indices else 0


_CACHE: dict = {}
_LOCK = threading.Lock()


def _cached(key, build):
    """``build()`` once per process and key (a compile: announced when slow, :func:`..compilation.compiling`)."""
    with _LOCK:
        if key not in _CACHE:
            with compiling(f"the {key[1]} integrators of {key[0]}"):
                _CACHE[key] = build()
        return _CACHE[key]


@dataclass(frozen=True)
class _Templates:
    variational: object  # taylor_adaptive of the variational system (args: states, then `free` parameters)
    plain: object  # taylor_adaptive of the system
    rhs: object  # cfunc of f
    observables: object | None  # cfunc of the observables
    n_par: int
    free: tuple


def _templates(system: OdeSystem, tol: float, free: tuple = ()) -> _Templates:
    """Compile (once per process; heyoka also caches on disk) the integrators of ``system``."""

    def build():
        import heyoka as hy

        sys = list(zip(system.variables, system.rhs))
        n_par = max(_n_params(system.rhs), max(free, default=-1) + 1)
        pars = np.zeros(n_par)
        x = np.zeros(system.n)
        args = [*system.variables, *(hy.par[i] for i in free)]
        vsys = hy.var_ode_sys(sys, args, order=1)
        var = hy.taylor_adaptive(vsys, x, pars=pars, tol=tol, compact_mode=system.compact_mode)
        plain = hy.taylor_adaptive(sys, x, pars=pars, tol=tol, compact_mode=system.compact_mode)
        rhs = hy.cfunc(list(system.rhs), list(system.variables))
        obs = (hy.cfunc([expr for _name, _units, expr in system.observables], list(system.variables))
               if system.observables else None)
        return _Templates(var, plain, rhs, obs, n_par, tuple(free))

    return _cached((system.name, "templates", float(tol), tuple(free)), build)


class FlowError(Exception):
    """An integration did not reach its end time (non-finite state)."""


class Flow:
    """Integrators of one system (own copies: not shared between threads)."""

    def __init__(self, system: OdeSystem, tol: float = TAYLOR_TOL, free: tuple = ()):
        t = _templates(system, tol, tuple(free))
        self.system, self.tol, self.free = system, tol, tuple(free)
        self.n, self.n_par = system.n, t.n_par
        self._var, self._plain = copy.copy(t.variational), copy.copy(t.plain)
        self._rhs, self._obs = t.rhs, t.observables
        self.n_args = self.n + len(self.free)
        self._identity = np.hstack([np.eye(self.n), np.zeros((self.n, len(self.free)))]).ravel()

    def _pars(self, pars) -> np.ndarray:
        return np.ascontiguousarray(np.asarray(pars, dtype=float)[: self.n_par])

    def rhs(self, x, pars) -> np.ndarray:
        """f at states x (n,) or (n, N)."""
        x = np.asarray(x, dtype=float)
        X = np.ascontiguousarray(x.reshape(self.n, -1))
        if self.n_par == 0 or self._rhs.nparams == 0:
            out = self._rhs(X)
        else:
            out = self._rhs(X, pars=np.ascontiguousarray(np.repeat(self._pars(pars)[: self._rhs.nparams, None],
                                                                   X.shape[1], axis=1)))
        return out[:, 0] if x.ndim == 1 else out

    def observables(self, X, pars) -> np.ndarray:
        """Observables at states X (n, N), shape (n_obs, N)."""
        X = np.ascontiguousarray(np.asarray(X, dtype=float).reshape(self.n, -1))
        if self._obs.nparams == 0:
            return self._obs(X)
        return self._obs(X, pars=np.ascontiguousarray(np.repeat(self._pars(pars)[: self._obs.nparams, None],
                                                                X.shape[1], axis=1)))

    def variational(self, x, t: float, pars, grid=None):
        """Integrate x and its variations from 0 to t: (end state, phi_x (n, n), phi_p (n, k)) and, if
        ``grid`` (times in [0, t], first 0) is given, the states (G, n) and phi_x, phi_p on it."""
        import heyoka as hy

        ta = self._var
        ta.time = 0.0
        ta.pars[:] = self._pars(pars)
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
        import heyoka as hy

        ta = self._plain
        ta.time = 0.0
        ta.pars[:] = self._pars(pars)
        ta.state[:] = x
        res = ta.propagate_grid(np.asarray(times, dtype=float), max_steps=MAX_STEPS)
        states = np.asarray(res[-1])
        if res[0] != hy.taylor_outcome.time_limit or len(states) != len(times) or not np.all(np.isfinite(states)):
            raise FlowError(f"the integration stopped ({res[0]!r}) at t = {ta.time:.6g}")
        return states

    def advance(self, x, t: float, pars) -> np.ndarray:
        """The state at time t from x (no variations)."""
        import heyoka as hy

        ta = self._plain
        ta.time = 0.0
        ta.pars[:] = self._pars(pars)
        ta.state[:] = x
        outcome = ta.propagate_until(float(t), max_steps=MAX_STEPS)[0]
        if outcome != hy.taylor_outcome.time_limit or not np.all(np.isfinite(ta.state)):
            raise FlowError(f"the integration stopped ({outcome!r}) at t = {ta.time:.6g} of {t:.6g}")
        return np.array(ta.state)


# ============================================================================ Floquet multipliers


def floquet(M: np.ndarray, flow_direction: np.ndarray, n_trivial: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Multipliers (eigenvalues of M, sorted by modulus, descending) and a mask of the trivial ones:
    the flow direction's (the eigenvector most parallel to f(x_0) among those with mu near 1), then the
    ``n_trivial`` - 1 others nearest 1."""
    vals, vecs = np.linalg.eig(M)
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
    """(stability flag of :data:`STABILITY`, number of nontrivial multipliers outside the unit circle)."""
    mod = np.abs(multipliers[~trivial])
    n_unstable = int(np.sum(mod > 1 + tol))
    if n_unstable:
        return STABILITY["unstable"], n_unstable
    return (STABILITY["stable"] if mod.size and np.all(mod < 1 - tol) else STABILITY["marginal"]), 0


# ============================================================================ the shooting problem


class ShootingProblem(continuation.Problem):
    """Periodic orbits of ``system`` by (multiple) shooting; a continuation problem if ``parameter`` is set.

    Unknowns u = (x_0, .., x_{m-1}, T[, p]); residual [phi(x_k, T/m) - x_{k+1} (k < m), phase]; the state
    Jacobian of the continuation core is the deflated monodromy (its eigenvalues: the nontrivial
    multipliers), so special points come from the multipliers (module docstring).
    """

    def __init__(self, system: OdeSystem, pars=None, *, segments: int = 1, phase: str = "poincare",
                 parameter: str | None = None, parameter_scale: float = 1.0, period_scale: float = 1.0,
                 bounds: dict | None = None, shift=None, tol: float = TAYLOR_TOL, samples: int = N_SAMPLES,
                 levels: dict | None = None):
        if int(segments) != segments or segments < 1:
            raise ParameterError(f"segments = {segments!r}; give a positive integer")
        if phase not in ("poincare", "integral"):
            raise ParameterError(f"phase condition {phase!r} unknown; give 'poincare' or 'integral'")
        if samples % segments:
            samples = segments * math.ceil(samples / segments)
        self.system, self.m, self.phase, self.samples = system, int(segments), phase, int(samples)
        self.n = n = system.n
        self.pars = np.array(system.pars if pars is None else pars, dtype=float)
        self.integral_names = tuple(name for name, _e in system.integrals)
        self.level_parameter = parameter if parameter in self.integral_names else None
        self.p_index = None if parameter is None or self.level_parameter else system.parameter_index(parameter)
        self.parameter = parameter
        self.levels = dict(levels or {})
        missing = [name for name in self.integral_names if name not in self.levels and name != self.level_parameter]
        if missing:
            raise ParameterError(f"{system.name} has first integrals: give the levels of {', '.join(missing)} "
                                 "(find_orbit takes them from the guess)")
        self._integrals = _integrals_field(system) if system.integrals else None
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
        """I_j(x_0) - c_j and their gradients (rows of the Jacobian) for the first integrals."""
        k = len(self.integral_names)
        if not k:
            return np.empty(0), np.empty((0, len(u)))
        pars = self.runtime(u)
        values = self._integrals.values(X0, pars)
        grads = self._integrals.tensor(X0, pars, 1, with_parameters=False)
        rows = np.zeros((k, len(u)))
        rows[:, : self.n] = grads
        target = np.array([self.levels.get(name, math.nan) for name in self.integral_names])
        if self.level_parameter:
            j = self.integral_names.index(self.level_parameter)
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
            return np.full(self.n * self.m + 1 + len(self.integral_names), np.nan)
        return np.concatenate([ev["F"], [self._phase_row(ev, u)[0]], self._level_rows(u, ev["X"][0])[0]])

    def jacobian(self, u) -> np.ndarray:
        ev = self._evaluate(u)
        if "error" in ev:
            return np.full((self.n * self.m + 1 + len(self.integral_names), len(u)), np.nan)
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
        if kind == "fold":  # at a Hopf end the parameter turns too (p - p_H ~ r^2): not a fold of cycles
            ev = self._evaluate(point.u)
            return "error" not in ev and float(np.linalg.norm(ev["half"])) > 1e-3 * self._half_ref_norm
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
              iterations: int = 0, n_samples: int = N_SAMPLES) -> "PeriodicOrbit":
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
    system: OdeSystem
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
        """max_t |x(t) - mean x| in scaled units (x / state_scale)."""
        d = (self.samples - self.samples.mean(axis=0)) / np.asarray(self.system.state_scale)
        return float(np.sqrt((d * d).sum(axis=1)).max())

    @property
    def exponents(self) -> np.ndarray:
        """Floquet exponents log|mu| / T [1/s] (the growth rates of perturbations)."""
        with np.errstate(divide="ignore"):
            return np.log(np.abs(self.multipliers)) / self.period


# ============================================================================ Newton


def find_orbit(system: OdeSystem, state, period: float, pars=None, *, segments: int = 1, phase: str = "poincare",
               shift=None, tol: float = TAYLOR_TOL, newton_tol: float = NEWTON_TOL,
               max_iter: int = NEWTON_MAX_ITER, amplitude_tol: float = AMPLITUDE_TOL) -> PeriodicOrbit:
    """A periodic orbit near (``state``, ``period``) by Newton's method; always returns a status.

    Gauss-Newton on the shooting equations with the phase condition fixed at the guess (least-squares
    steps of at most MAX_NEWTON_STEP in scaled unknowns, halved while they increase the residual).
    Statuses: ``converged`` (a periodic orbit);
    ``equilibrium`` (Newton converged, or was converging, to a point: amplitude below ``amplitude_tol``
    -- an equilibrium is a solution of the shooting equations for every T, never an orbit);
    ``not_converged`` (the message holds the residual of the last iterate); ``nonfinite``.
    """
    if not (isinstance(period, int | float) and math.isfinite(period) and period > 0):
        raise ParameterError(f"period guess T = {period!r} must be a positive number")
    state = np.asarray(state, dtype=float)
    if state.shape != (system.n,) or not np.all(np.isfinite(state)):
        raise ParameterError(f"the state guess must be {system.n} finite numbers ({', '.join(system.state_names)})")
    levels = integral_levels(system, state, pars) if system.integrals else None
    prob = ShootingProblem(system, pars, segments=segments, phase=phase, period_scale=float(period), shift=shift,
                           tol=tol, levels=levels)
    scale = prob.scale
    try:
        u = prob.unknowns(state, float(period))
    except FlowError as exc:
        return _failed(prob, state, period, "nonfinite", f"the guess cannot be integrated: {exc}")
    prob.set_reference(u)

    def norm(F):
        return float(np.linalg.norm(F)) if np.all(np.isfinite(F)) else math.inf

    F = prob.residual(u)
    if not np.isfinite(norm(F)):
        return _failed(prob, state, period, "nonfinite", "the guess cannot be integrated over the period")
    status, it = "not_converged", 0
    for it in range(1, max_iter + 1):
        A = prob.jacobian(u) * scale[None, :]
        step = np.linalg.lstsq(A, -F, rcond=None)[0]
        r0, lam = norm(F), min(1.0, MAX_NEWTON_STEP / max(np.max(np.abs(step)), 1e-300))
        while True:
            trial = u + lam * step * scale
            F_trial = prob.residual(trial)
            if norm(F_trial) <= max(r0, 1e-300) * (1 - 1e-4 * lam) or lam < 1e-4 or norm(F_trial) < 1e-12:
                break
            lam *= 0.5
        if not np.isfinite(norm(F_trial)):
            return _failed(prob, prob.split(u)[0][0], prob.split(u)[1], "nonfinite",
                           f"the Newton iterate {it} left the domain of the equations (non-finite flow)")
        u, F = trial, F_trial
        if lam * np.max(np.abs(step)) <= newton_tol * (1.0 + np.max(np.abs(u / scale))):
            A = prob.jacobian(u)
            if np.all(np.abs(F) <= 1e-9 * (1.0 + np.abs(A) @ np.abs(u))):
                status = "converged"
            break
    residual = float(np.max(np.abs(F[: system.n * prob.m]) / np.tile(system.state_scale, prob.m)))
    try:
        orbit = prob.orbit(u, status, "", residual, it)
    except FlowError as exc:
        return _failed(prob, prob.split(u)[0][0], prob.split(u)[1], "nonfinite", str(exc))
    if orbit.amplitude < amplitude_tol:
        orbit.status = "equilibrium"
        orbit.message = (f"Newton {'converged' if status == 'converged' else 'was converging'} to an equilibrium "
                         f"(amplitude {orbit.amplitude:.2g} in scaled units after {it} steps, residual "
                         f"{residual:.2g}): not a periodic orbit")
    elif status == "converged":
        orbit.message = (f"periodic orbit, T = {orbit.period:.12g}, {it} Newton steps, residual {residual:.2g}; "
                         f"{_stability_text(orbit)}")
    else:
        orbit.message = (f"Newton did not converge in {it} steps: residual {residual:.3g} (max |phi(x_k, T/m) - "
                         f"x_(k+1)| / scale) at T = {orbit.period:.6g}, amplitude {orbit.amplitude:.3g}; no periodic "
                         "orbit near the guess")
    return orbit


def _stability_text(orbit: PeriodicOrbit) -> str:
    flag, n_unstable = classify(orbit.multipliers, orbit.trivial)
    word = {0: "stable", 1: "marginal", 2: f"unstable ({n_unstable} multiplier(s) outside the unit circle)"}[flag]
    big = orbit.multipliers[~orbit.trivial]
    return f"{word}, largest nontrivial |multiplier| {np.abs(big).max(initial=0.0):.6g}"


def _integrals_field(system: OdeSystem) -> CompiledField:
    return _cached((system.name, "integrals"), lambda: CompiledField([e for _n, e in system.integrals],
                                                                      system.variables))


def integral_levels(system: OdeSystem, state, pars=None) -> dict:
    """The first integrals' values at ``state`` ({name: value})."""
    if not system.integrals:
        return {}
    pars = np.array(system.pars if pars is None else pars, dtype=float)
    values = _integrals_field(system).values(np.asarray(state, dtype=float), pars)
    return dict(zip((name for name, _e in system.integrals), map(float, values)))


def _failed(prob: ShootingProblem, state, period, status, message) -> PeriodicOrbit:
    n = prob.n
    return PeriodicOrbit(status, message, prob.system, prob.pars.copy(), np.atleast_2d(state).copy(), float(period),
                         None, None, math.inf, 0, np.full(n, complex(math.nan)), np.zeros(n, bool), np.zeros(1),
                         np.atleast_2d(state).copy(), np.zeros((1, len(prob.system.observables))))


def monodromy_fd(system: OdeSystem, state, period: float, pars=None, h: float = 1e-6,
                 tol: float = TAYLOR_TOL) -> np.ndarray:
    """Monodromy by central finite differences of the flow (an independent check of the variational one)."""
    flow = Flow(system, tol)
    pars = np.array(system.pars if pars is None else pars, dtype=float)
    state = np.asarray(state, dtype=float)
    M = np.empty((system.n, system.n))
    for j in range(system.n):
        d = h * system.state_scale[j]
        e = np.zeros(system.n)
        e[j] = d
        M[:, j] = (flow.advance(state + e, period, pars) - flow.advance(state - e, period, pars)) / (2 * d)
    return M


# ============================================================================ textbook systems


@dataclass(frozen=True)
class Textbook:
    """A textbook system with a known start: a Hopf point (parameter value and equilibrium) or an orbit guess."""

    build: object  # () -> OdeSystem
    parameter: str  # the natural continuation parameter
    start: dict  # {"hopf": (value, state)} or {"orbit": (value, state, period)}
    facts: str  # what is known exactly (the tests check it)


def _planar_rotation(n: int, seed: int = 3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.linalg.qr(rng.normal(size=(n, n)))[0]


def _vanderpol() -> OdeSystem:
    import heyoka as hy

    x, y = hy.make_vars("x", "y")
    mu = hy.par[0]
    return OdeSystem("vanderpol", ("x", "y"), (x, y), (y, mu * (1 - x * x) * y - x), (1.0,), ("mu",), (1.0, 1.0),
                     description="van der Pol oscillator x'' - mu (1 - x^2) x' + x = 0")


HOPF_ROTATION = _planar_rotation(3)


def _hopf() -> OdeSystem:
    """Hopf normal form z' = (beta + i omega) z + (l1 + i c) z |z|^2 with a slave w' = -w + u v, rotated in R^3."""
    import heyoka as hy

    x = hy.make_vars("x1", "x2", "x3")
    beta, omega, l1, c = (hy.par[i] for i in range(4))
    R = HOPF_ROTATION
    u, v, w = (sum(R[j, i] * x[j] for j in range(3)) for i in range(3))  # xi = R^T x
    r2 = u * u + v * v
    g = [beta * u - omega * v + (l1 * u - c * v) * r2, omega * u + beta * v + (c * u + l1 * v) * r2, -w + u * v]
    rhs = tuple(sum(R[i, j] * g[j] for j in range(3)) for i in range(3))  # x' = R g
    return OdeSystem("hopf_normal_form", ("x1", "x2", "x3"), tuple(x), rhs, (0.0, 1.0, -1.0, 0.5),
                     ("beta", "omega", "l1", "c"), (1.0, 1.0, 1.0),
                     description="Hopf normal form (rotated in R^3): cycles r^2 = -beta/l1, T = 2 pi/(omega + c r^2)")


def _bautin() -> OdeSystem:
    import heyoka as hy

    x, y = hy.make_vars("x", "y")
    beta, ell = hy.par[0], hy.par[1]
    r2 = x * x + y * y
    a = beta + ell * r2 - r2 * r2
    return OdeSystem("bautin", ("x", "y"), (x, y), (a * x - y, x + a * y), (0.0, 1.0), ("beta", "l"), (1.0, 1.0),
                     description="Bautin normal form z' = (beta + i) z + l z|z|^2 - z|z|^4: fold of cycles at "
                                 "beta = -l^2/4, r^2 = l/2")


def _roessler() -> OdeSystem:
    import heyoka as hy

    x, y, z = hy.make_vars("x", "y", "z")
    a, b, c = hy.par[0], hy.par[1], hy.par[2]
    return OdeSystem("roessler", ("x", "y", "z"), (x, y, z), (-y - z, x + a * y, b + z * (x - c)), (0.2, 0.2, 2.5),
                     ("a", "b", "c"), (1.0, 1.0, 1.0), description="Roessler system")


def _torus() -> OdeSystem:
    """A limit cycle times a Hopf normal form: (x1, x2) r' = r(1 - r^2), theta' = 1; z = x3 + i x4,
    z' = (beta + k x1 + i omega2) z - z |z|^2. The cycle r = 1, z = 0 has multipliers 1, exp(-4 pi) and
    exp(2 pi (beta +- i omega2)) (the mean of x1 over the cycle is 0): a Neimark-Sacker point at beta = 0
    with angle 2 pi omega2 (mod 2 pi)."""
    import heyoka as hy

    x1, x2, x3, x4 = hy.make_vars("x1", "x2", "x3", "x4")
    beta, k, w2 = hy.par[0], hy.par[1], hy.par[2]
    r2 = x1 * x1 + x2 * x2
    z2 = x3 * x3 + x4 * x4
    g = beta + k * x1 - z2
    return OdeSystem("torus", ("x1", "x2", "x3", "x4"), (x1, x2, x3, x4),
                     (x1 * (1 - r2) - x2, x2 * (1 - r2) + x1, g * x3 - w2 * x4, w2 * x3 + g * x4),
                     (-0.1, 0.5, math.sqrt(2.0)), ("beta", "k", "omega2"), (1.0, 1.0, 1.0, 1.0),
                     description="limit cycle x Hopf normal form: Neimark-Sacker at beta = 0")


def _homoclinic() -> OdeSystem:
    """x' = y, y' = x - x^2 - y (H - c), H = y^2/2 - x^2/2 + x^3/3: dH/dt = -y^2 (H - c), so the level set
    H = c is an attracting periodic orbit for c in (-1/6, 0) (a Hopf point at c = -1/6, the centre (1, 0)),
    and H = 0 the homoclinic loop of the saddle (0, 0) (eigenvalues +-1): the period grows without bound
    as c -> 0."""
    import heyoka as hy

    x, y = hy.make_vars("x", "y")
    c = hy.par[0]
    H = y * y / 2 - x * x / 2 + x * x * x / 3
    return OdeSystem("homoclinic_loop", ("x", "y"), (x, y), (y, x - x * x - y * (H - c)), (-0.1,), ("c",),
                     (1.0, 1.0), description="Hamiltonian loop with energy-selecting damping: homoclinic at c = 0")


def _duffing() -> OdeSystem:
    """The conservative Duffing oscillator x'' + x + k x^3 = 0: energy E = v^2/2 + x^2/2 + k x^4/4, a family of
    periodic orbits parametrised by E (period by quadrature), two trivial multipliers (flow and energy)."""
    import heyoka as hy

    x, v = hy.make_vars("x", "v")
    k = hy.par[0]
    return OdeSystem("duffing", ("x", "v"), (x, v), (v, -x - k * x * x * x), (1.0,), ("k",), (1.0, 1.0),
                     n_trivial=2, integrals=(("E", v * v / 2 + x * x / 2 + k * x ** 4 / 4),),
                     description="conservative Duffing oscillator: a family of orbits in the energy")


def _lorenz() -> OdeSystem:
    import heyoka as hy

    x, y, z = hy.make_vars("x", "y", "z")
    s, r, b = hy.par[0], hy.par[1], hy.par[2]
    return OdeSystem("lorenz", ("x", "y", "z"), (x, y, z), (s * (y - x), x * (r - z) - y, x * y - b * z),
                     (10.0, 28.0, 8.0 / 3.0), ("sigma", "rho", "beta"), (10.0, 10.0, 10.0),
                     description="Lorenz system")


TEXTBOOK = {
    "vanderpol": Textbook(_vanderpol, "mu", {"orbit": (1.0, (2.0, 0.0), 6.66)},
                          "mu = 1: T = 6.6632868593231 (literature); planar: nontrivial multiplier exp(int div f dt)"),
    "hopf": Textbook(_hopf, "beta", {"hopf": (0.0, (0.0, 0.0, 0.0))},
                     "supercritical Hopf at beta = 0: r^2 = -beta/l1, T = 2 pi/(omega + c r^2)"),
    "bautin": Textbook(_bautin, "beta", {"hopf": (0.0, (0.0, 0.0))},
                       "subcritical Hopf at beta = 0 (l1 = l); fold of cycles at beta = -l^2/4, r^2 = l/2; T = 2 pi"),
    "roessler": Textbook(_roessler, "c", {"orbit": (2.5, (4.3, 0.0, 0.03), 6.0)},
                         "a = b = 0.2: period doubling near c = 2.83"),
    "torus": Textbook(_torus, "beta", {"orbit": (-0.1, (1.0, 0.0, 0.0, 0.0), 2 * math.pi)},
                      "Neimark-Sacker at beta = 0, angle 2 pi sqrt(2) mod 2 pi"),
    "homoclinic": Textbook(_homoclinic, "c", {"hopf": (-1.0 / 6.0, (1.0, 0.0))},
                           "Hopf at c = -1/6, homoclinic loop at c = 0 (saddle eigenvalues +-1)"),
    "duffing": Textbook(_duffing, "E", {"orbit": (0.5, (1.0, 0.0), 5.0)},
                        "conservative: orbits in a family parametrised by the energy E (a level of a first integral)"),
    "lorenz": Textbook(_lorenz, "rho", {}, "sigma 10, rho 28, beta 8/3: Lyapunov exponents 0.9056, 0, -14.5723"),
}


@functools.lru_cache(maxsize=None)
def textbook_system(name: str) -> OdeSystem:
    if name not in TEXTBOOK:
        raise ParameterError(f"unknown system {name!r}; choose one of {', '.join(TEXTBOOK)}")
    return TEXTBOOK[name].build()


# ============================================================================ starting guesses


def _field(system: OdeSystem, index: int) -> CompiledField:
    import heyoka as hy

    return _cached((system.name, "field", index), lambda: CompiledField(system.rhs, system.variables, [hy.par[index]]))


@dataclass(frozen=True)
class HopfGuess:
    """An orbit guess near a Hopf point of an isolated equilibrium (Kuznetsov's normal form)."""

    value: float  # parameter value of the guess, value_H + dp
    state: np.ndarray  # x_H + 2 Re(r q)
    period: float  # 2 pi / omega
    value_hopf: float
    equilibrium: np.ndarray
    omega: float
    l1: float  # first Lyapunov coefficient
    a: float  # d Re(lambda) / d parameter
    radius: float  # r of z in x = x_H + z q + conj(z q), r^2 = -a dp / l1


def hopf_guess(system: OdeSystem, parameter: str, value: float, state, *, radius: float = 0.05,
               dp: float | None = None, pars=None) -> HopfGuess:
    """Start of a periodic-orbit branch at a Hopf point (``value``, ``state`` of the equilibrium, corrected by
    Newton): critical eigenvector q and frequency omega of the Jacobian, first Lyapunov coefficient l1 and
    a = d Re lambda / dp from exact derivative tensors; the orbit of radius r lies at dp = -l1 r^2 / a
    (or at the given dp with r from the same relation, or r if l1 vanishes)."""
    k = system.parameter_index(parameter)
    field = _field(system, k)
    pars = np.array(system.pars if pars is None else pars, dtype=float)
    pars[k] = value
    n = system.n
    x = np.asarray(state, dtype=float).copy()
    for _ in range(20):  # the equilibrium, by Newton at the given parameter value
        T1 = field.tensor(x, pars, 1)
        step = np.linalg.solve(T1[:, :n], -field.values(x, pars))
        x += step
        if np.max(np.abs(step)) < 1e-14 * (1 + np.max(np.abs(x))):
            break
    T1, T2 = field.tensor(x, pars, 1), field.tensor(x, pars, 2)
    J, B = T1[:, :n], T2[:, :n, :n]
    C = field.tensor(x, pars, 3, with_parameters=False)
    nf = normal_forms.first_lyapunov_coefficient(J, B, C)
    if abs(nf["eigenvalue"].real) > 1e-6 * max(1.0, nf["frequency"]):
        raise ParameterError(f"{system.name}: the critical eigenvalue at {parameter} = {value:g} is "
                             f"{nf['eigenvalue']:.4g}, not imaginary: give a Hopf point")
    q, p = nf["q"], nf["p"]
    x_p = -np.linalg.solve(J, T1[:, n])
    a = float(np.vdot(p, T2[:, :n, n] @ q + np.einsum("ijk,j,k->i", B, x_p, q)).real)
    l1 = nf["l1"]
    if dp is None:
        if abs(l1) < 1e-12:
            raise ParameterError(f"{system.name}: l1 = {l1:.2g} vanishes at the Hopf point (a Bautin point); give dp")
        dp = -l1 * radius ** 2 / a
    elif abs(l1) > 1e-12 and -a * dp / l1 > 0:
        radius = math.sqrt(-a * dp / l1)
    guess = x + 2 * (radius * q).real
    return HopfGuess(value + dp, guess, 2 * math.pi / nf["frequency"], value, x, nf["frequency"], l1, a, radius)


def orbit_from_hopf(system: OdeSystem, parameter: str, value: float, state, *, radius: float = 0.05,
                    pars=None, **newton) -> tuple[PeriodicOrbit, HopfGuess]:
    """The periodic orbit of radius ~``radius`` born at the Hopf point (Newton from :func:`hopf_guess`)."""
    g = hopf_guess(system, parameter, value, state, radius=radius, pars=pars)
    p = np.array(system.pars if pars is None else pars, dtype=float)
    p[system.parameter_index(parameter)] = g.value
    orbit = find_orbit(system, g.state, g.period, p, **newton)
    orbit.value, orbit.parameter = g.value, parameter
    return orbit, g


def simulation_guess(system: OdeSystem, state, pars=None, *, index: int = 0, level: float | None = None,
                     transient: float = 100.0, max_time: float = 1000.0, dt: float = 0.01,
                     tol: float = TAYLOR_TOL):
    """(state, return time) of a Poincaré return of a simulation: after ``transient``, two successive upward
    crossings of x[index] = level (default: the value at the end of the transient), located by Newton on
    the crossing time from samples ``dt`` apart."""
    flow = Flow(system, tol)
    pars = np.array(system.pars if pars is None else pars, dtype=float)
    x = np.asarray(state, dtype=float)
    if transient > 0:
        x = flow.advance(x, transient, pars)
    level = float(x[index]) if level is None else float(level)
    crossings: list = []
    t0, n_grid = 0.0, 1000
    while t0 < max_time and len(crossings) < 2:
        times = dt * np.arange(n_grid + 1)
        states = flow.trajectory(x, times, pars)
        g = states[:, index] - level
        for j in np.flatnonzero((g[:-1] < 0) & (g[1:] >= 0)):
            s = times[j] + dt * (-g[j]) / (g[j + 1] - g[j])
            for _ in range(30):
                z = flow.advance(x, s, pars)
                ds = -(z[index] - level) / flow.rhs(z, pars)[index]
                s += ds
                if abs(ds) < 1e-15 * (1 + s):
                    break
            crossings.append((t0 + s, flow.advance(x, s, pars)))
            if len(crossings) == 2:
                break
        x, t0 = states[-1], t0 + times[-1]
    if len(crossings) < 2:
        raise ParameterError(f"{system.name}: no two crossings of {system.state_names[index]} = {level:g} within "
                             f"{max_time:g} time units after the transient; choose another section or start")
    (ta, xa), (tb, _xb) = crossings
    return xa, tb - ta


def orbit_from_dataset(ds: xr.Dataset, point: int, *, max_iter: int = NEWTON_MAX_ITER) -> PeriodicOrbit:
    """The orbit stored at ``point`` of a dataset of kind ``periodic_orbits``, corrected by Newton (its system,
    runtime parameters, first point, period, segments and phase condition come from the dataset)."""
    from ..errors import DatasetError
    from ..results import config_of

    if ds.attrs.get("kind") != "periodic_orbits":
        raise DatasetError(f"the dataset is of kind {ds.attrs.get('kind')!r}; give a file written by "
                           "tippedisk periodic-orbits")
    n_points = ds.sizes["point"]
    if not -n_points <= point < n_points:
        raise ParameterError(f"point {point} does not exist; the dataset has points 0 .. {n_points - 1}")
    if int(ds.orbit_status.values[point]) != STATUS["converged"]:
        status = list(STATUS)[int(ds.orbit_status.values[point])]
        raise ParameterError(f"point {point} is not a periodic orbit (orbit_status {status}); give a converged point")
    config = config_of(ds)
    name = ds.attrs.get("system", "")
    if name == "tippedisk_reduced":
        system = tippedisk_system(_setup_from(config["setup"]))
    else:
        keys = [k for k in TEXTBOOK if textbook_system(k).name == name]
        if not keys:
            raise DatasetError(f"system {name!r} of the dataset is unknown to this version; give a dataset of one of "
                               f"{', '.join(TEXTBOOK)}")
        system = textbook_system(keys[0])
    pars = ds.runtime_parameters.values[point]
    orbit = find_orbit(system, ds.initial_state.values[point], float(ds.period.values[point]),
                       np.concatenate([pars, np.asarray(system.pars)[len(pars):]]),
                       segments=int(config.get("segments", 1)), phase=config.get("phase", "poincare"),
                       max_iter=max_iter)
    parameter = ds.attrs.get("parameter") or None
    if parameter:
        orbit.parameter, orbit.value = parameter, float(orbit.pars[system.parameter_index(parameter)])
    return orbit


# ============================================================================ branches


def orbit_problem(orbit: PeriodicOrbit, parameter: str, *, parameter_scale: float = 1.0, bounds: dict | None = None,
                  segments: int | None = None, phase: str = "poincare", period_max: float | None = None,
                  tol: float = TAYLOR_TOL) -> tuple[ShootingProblem, np.ndarray]:
    """The continuation problem through ``orbit`` in ``parameter`` and its start unknowns u0."""
    if not orbit.converged:
        raise ParameterError(f"the start is not a periodic orbit (status {orbit.status}): {orbit.message}")
    system = orbit.system
    k = None if parameter in dict(system.integrals) else system.parameter_index(parameter)
    bounds = dict(bounds or {})
    if period_max is not None:
        bounds["T"] = (0.0, float(period_max))
    m = segments or len(orbit.states)
    levels = integral_levels(system, orbit.states[0], orbit.pars)
    value = levels[parameter] if k is None else orbit.pars[k]
    prob = ShootingProblem(system, orbit.pars, segments=m, phase=phase, parameter=parameter,
                           parameter_scale=parameter_scale, period_scale=orbit.period, bounds=bounds, tol=tol,
                           levels=levels)
    u0 = (np.concatenate([orbit.states.ravel(), [orbit.period, value]]) if m == len(orbit.states)
          else prob.unknowns(orbit.states[0], orbit.period, value))
    return prob, u0


def continue_orbits(orbit: PeriodicOrbit, parameter: str, *, bounds: dict | None = None, direction: int = 1,
                    both_ways: bool = False, options: continuation.Options | None = None, **problem_options):
    """The branch of periodic orbits through ``orbit`` in ``parameter`` by PALC, with its special points
    (fold of cycles, branch point, period doubling, Neimark-Sacker, approach to a homoclinic orbit at the
    period bound ``period_max``). Returns (Branch, ShootingProblem)."""
    prob, u0 = orbit_problem(orbit, parameter, bounds=bounds, **problem_options)
    options = options or continuation.Options(ds=0.02, ds_max=0.1, max_points=200)
    if both_ways:
        br = continuation.continue_both_ways(prob, u0, options)
    else:
        br = continuation.continue_branch(prob, u0, options, direction=direction)
    _mark_homoclinic(prob, br)
    return br, prob


def _mark_homoclinic(prob: ShootingProblem, br: continuation.Branch) -> None:
    """If the branch ended at the period bound with the period growing and the parameter converging, add a
    special point ``homoclinic`` at the last point with the limit p_hc of p - p_hc ~ A exp(-lam T)."""
    if prob.t_index not in prob.bounds or not br.points:
        return
    T_max = prob.bounds[prob.t_index][1]
    last = br.points[-1]
    if last.special != "bound" or abs(last.u[prob.t_index] - T_max) > 1e-9 * T_max:
        return
    T = np.array([p.u[prob.t_index] for p in br.points])
    P = np.array([p.u[prob.t_index + 1] for p in br.points])
    limit, rate = homoclinic_limit(T, P)
    data = {"period": float(T[-1]), "limit": limit, "rate": rate, "last_periods": T[-5:].tolist(),
            "last_values": P[-5:].tolist()}
    br.special_points.append(continuation.SpecialPoint("homoclinic", len(br.points) - 1, last.u, last.eigenvalues,
                                                       float(P[-1] - limit), data))
    continuation._label(br.special_points)
    br.message += (f"; the period grew to {T[-1]:.6g} (from {T[0]:.6g}) while {prob.parameter} converged: approach "
                   f"to a homoclinic orbit at {prob.parameter} ~ {limit:.8g} (p - p_hc ~ exp(-{rate:.4g} T))")


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


def switch_period_doubling(prob: ShootingProblem, br: continuation.Branch, label: str, *, h: float = 0.02,
                           options: continuation.Options | None = None):
    """Continue the orbit of twice the period emanating from the period-doubling point ``label`` of ``br``.

    In the problem of period 2T (2m segments) the PD orbit traversed twice is a branch point whose second
    kernel direction is the PD eigenvector v (M v = -v), propagated along the orbit: +phi(t_k) v on the first
    pass, -phi(t_k) v on the second. The corrector with the constraint along that direction lands on the
    doubled orbit. Returns (Branch, doubled ShootingProblem); ParameterError if it falls back onto the old one.
    """
    labels = [sp.label for sp in br.special_points]
    if label not in labels:
        raise ParameterError(f"no special point {label!r} on the branch; it has {', '.join(labels) or 'none'}")
    sp = br.special_points[labels.index(label)]
    if sp.kind != "period_doubling":
        raise ParameterError(f"{label} is a {sp.kind} point; give a period-doubling point (PD)")
    u = sp.u
    X, T, p = prob.split(u)
    ev = prob._evaluate(u)
    vals, vecs = np.linalg.eig(ev["M"])
    v = vecs[:, np.argmin(np.abs(vals + 1.0))].real
    v /= np.linalg.norm(v / prob.system.state_scale)
    m = prob.m
    double = ShootingProblem(prob.system, prob.runtime(u), segments=2 * m, phase=prob.phase, parameter=prob.parameter,
                             parameter_scale=prob.scale[-1], period_scale=2 * T,
                             bounds={("T" if i == prob.t_index else prob.parameter):
                                     ((2 * lo, 2 * hi) if i == prob.t_index else (lo, hi))
                                     for i, (lo, hi) in prob.bounds.items()}, tol=prob.flow.tol,
                             samples=2 * prob.samples, levels=prob.levels)
    vk = [v]
    for k in range(m - 1):
        vk.append(_segment_phi(prob, u, k) @ vk[-1])
    direction = np.concatenate([*vk, *(-w for w in vk), [0.0, 0.0]])
    u2 = np.concatenate([X.ravel(), X.ravel(), [2 * T, p]])
    d = direction / double.scale
    d /= np.linalg.norm(d)
    options = options or br.options
    double.set_reference(u2)
    v0 = u2 / double.scale
    for sign in (1.0, -1.0):
        start, _ = continuation.correct(double, (v0 + sign * h * d) * double.scale, (sign * d, v0, h), options)
        if start is None:
            continue
        Xs = double.split(start)[0]
        gap = np.max(np.abs(Xs[0] - Xs[m]) / np.asarray(prob.system.state_scale))
        if gap > 1e-3 * h:
            branch = continuation.continue_branch(double, start, options, tangent=sign * d)
            _mark_homoclinic(double, branch)
            return branch, double
    raise ParameterError(f"no orbit of twice the period found next to {label} (the corrector fell back onto the "
                         "old orbit); try a larger h")


def _segment_phi(prob: ShootingProblem, u, k: int) -> np.ndarray:
    X, T, _p = prob.split(u)
    return prob.flow.variational(X[k], T / prob.m, prob.runtime(u))[1]


# ============================================================================ datasets


def branch_orbits(prob: ShootingProblem, br: continuation.Branch, n_samples: int = N_SAMPLES) -> list[PeriodicOrbit]:
    """The orbits of a branch's points (samples, multipliers, amplitude measures)."""
    return [prob.orbit(p.u, "converged", "", None, p.newton_iterations, n_samples) for p in br.points]


def branch_dataset(prob: ShootingProblem, br: continuation.Branch, info: dict | None = None,
                   n_samples: int = N_SAMPLES) -> xr.Dataset:
    """A branch of periodic orbits as a dataset of kind ``periodic_orbits``."""
    orbits = branch_orbits(prob, br, n_samples)
    status = "completed" if br.status == "completed" else "partial"
    labels = ", ".join(f"{sp.label} at {prob.parameter} = {sp.u[prob.t_index + 1]:.10g}" for sp in br.special_points)
    message = f"branch of {len(orbits)} periodic orbits; {br.message}" + (f"; {labels}" if labels else "")
    config = {"options": dataclasses.asdict(br.options), "segments": prob.m, "phase": prob.phase,
              "tol": prob.flow.tol, "bounds": {prob.names[i]: list(b) for i, b in prob.bounds.items()},
              **(info or {})}
    return orbits_dataset(orbits, status, message, config, special=br.special_points, prob=prob,
                          arclength=br.array("arclength"))


def orbits_dataset(orbits: list[PeriodicOrbit], status: str, message: str, config: dict, *, special=(), prob=None,
                   arclength=None, extra: dict | None = None) -> xr.Dataset:
    """Orbits (or failed searches, by ``orbit_status``) as a dataset of kind ``periodic_orbits``.

    Dims: point (orbit), floquet (multipliers by modulus), sample (along one period), state,
    observable, runtime_parameter, special_point. Non-finite numbers of failed searches are stored as 0
    with the point's ``orbit_status`` saying why (never a silent NaN).
    """
    import heyoka as hy

    system = orbits[0].system
    n, N = system.n, max(len(o.times) for o in orbits)
    n_obs = len(system.observables)

    def clean(a):
        a = np.asarray(a, dtype=float)
        return np.where(np.isfinite(a), a, 0.0)

    def resample(o, a):
        a = np.asarray(a, dtype=float)
        return a if len(a) == N else np.repeat(a[:1], N, axis=0)

    mu = np.array([o.multipliers for o in orbits])
    stab = np.array([classify(o.multipliers, o.trivial) if o.converged or o.status == "not_converged"
                     else (STABILITY["marginal"], 0) for o in orbits])
    samples = np.array([resample(o, o.samples) for o in orbits])
    times = np.array([o.times if len(o.times) == N else np.zeros(N) for o in orbits])
    obs = np.array([resample(o, o.observables) for o in orbits]) if n_obs else np.zeros((len(orbits), N, 0))
    pars = np.array([o.pars for o in orbits])
    data = {
        "period": ("point", clean([o.period for o in orbits]), {"units": "s", "long_name": "period T"}),
        "amplitude": ("point", clean([o.amplitude for o in orbits]),
                      {"units": "1", "long_name": "max_t |x(t) - mean x| in scaled states (x / state_scale)"}),
        "orbit_status": ("point", np.array([STATUS[o.status] for o in orbits], np.int8),
                         {"long_name": "outcome of the search: converged is a periodic orbit; equilibrium: Newton "
                                       "converged to a point (no orbit); not_converged: residual in `residual`",
                          "flag_values": np.array(list(STATUS.values()), np.int8), "flag_meanings": " ".join(STATUS)}),
        "stability": ("point", stab[:, 0].astype(np.int8),
                      {"long_name": "stability by the nontrivial Floquet multipliers (|mu| < 1: stable)",
                       "flag_values": np.array(list(STABILITY.values()), np.int8),
                       "flag_meanings": " ".join(STABILITY)}),
        "n_unstable": ("point", stab[:, 1].astype(np.int32),
                       {"units": "1", "long_name": "nontrivial multipliers outside the unit circle"}),
        "residual": ("point", clean([min(o.residual, 1e300) for o in orbits]),
                     {"units": "1", "long_name": "max |phi(x_k, T/m) - x_(k+1)| / state_scale of the (last) iterate"}),
        "newton_iterations": ("point", np.array([o.iterations for o in orbits], np.int32),
                              {"units": "1", "long_name": "Newton steps"}),
        "multiplier_real": (("point", "floquet"), clean(mu.real),
                            {"units": "1", "long_name": "Floquet multipliers (monodromy eigenvalues) by modulus, "
                                                        "real part (of the last iterate unless converged)"}),
        "multiplier_imag": (("point", "floquet"), clean(mu.imag),
                            {"units": "1", "long_name": "Floquet multipliers, imaginary part"}),
        "multiplier_trivial": (("point", "floquet"), np.array([o.trivial for o in orbits], np.int8),
                               {"long_name": "1: a trivial multiplier (flow direction; families of solutions)",
                                "flag_values": np.array([0, 1], np.int8), "flag_meanings": "nontrivial trivial"}),
        "initial_state": (("point", "state"), clean([o.states[0] for o in orbits]),
                          {"long_name": "x_0: the orbit's first point (phase condition)"}),
        "state_min": (("point", "state"), clean(samples.min(axis=1)), {"long_name": "minimum over the orbit"}),
        "state_max": (("point", "state"), clean(samples.max(axis=1)), {"long_name": "maximum over the orbit"}),
        "orbit": (("point", "sample", "state"), clean(samples),
                  {"long_name": "states along one period at sample_time (the initial state repeated for a failed "
                                "search)"}),
        "sample_time": (("point", "sample"), clean(times), {"units": "s", "long_name": "time along the orbit"}),
        "runtime_parameters": (("point", "runtime_parameter"), clean(pars),
                               {"long_name": "values of the system's runtime parameters"}),
    }
    if orbits[0].parameter:
        data[orbits[0].parameter] = ("point", clean([o.value for o in orbits]),
                                     {"long_name": f"continuation parameter {orbits[0].parameter}"})
    if n_obs:
        data["observable_min"] = (("point", "observable"), clean(obs.min(axis=1)),
                                  {"long_name": "minimum over the orbit"})
        data["observable_max"] = (("point", "observable"), clean(obs.max(axis=1)),
                                  {"long_name": "maximum over the orbit"})
        data["orbit_observables"] = (("point", "sample", "observable"), clean(obs),
                                     {"long_name": "observables along the orbit"})
    if arclength is not None:
        data["arclength"] = ("point", np.asarray(arclength, float), {"units": "1", "long_name": "pseudo-arclength"})
    data.update(_special_table(list(special), prob))
    data.update(extra or {})
    coords = {
        "point": ("point", np.arange(len(orbits), dtype=np.int32), {"long_name": "orbit index (along the branch)"}),
        "floquet": ("floquet", np.arange(n, dtype=np.int32), {"long_name": "multiplier index"}),
        "sample": ("sample", np.arange(N, dtype=np.int32), {"long_name": "sample index along the orbit"}),
        "state": ("state", np.array(system.state_names, dtype=str), {"long_name": "state variable"}),
        "runtime_parameter": ("runtime_parameter", np.array(system.parameter_names[: pars.shape[1]], dtype=str),
                              {"long_name": "runtime parameter"}),
        "special_point": ("special_point", np.arange(len(special), dtype=np.int32), {"long_name": "special point"}),
    }
    if n_obs:
        coords["observable"] = ("observable", np.array([name for name, _u, _e in system.observables], dtype=str),
                                {"long_name": "observable", "units": " ".join(u for _n, u, _e in system.observables)})
    config = {"system": system.name, "description": system.description, "heyoka_version": hy.__version__, **config}
    attrs = make_attrs("periodic_orbits", config, status, message, system=system.name,
                       parameter=orbits[0].parameter or "", labels=" ".join(sp.label for sp in special),
                       n_orbits=int(sum(o.converged for o in orbits)))
    return xr.Dataset(data, coords=coords, attrs=attrs)


def _special_table(special: list, prob) -> dict:
    def get(key):
        return np.array([float(np.ravel([sp.data.get(key, 0.0)])[0]) if np.isfinite(
            np.ravel([sp.data.get(key, 0.0)])[0]) else 0.0 for sp in special])

    return {
        "special_kind": ("special_point", np.array([SPECIAL_KINDS[sp.kind] for sp in special], np.int8),
                         {"long_name": "type of the special point", "flag_values": np.array(
                             list(SPECIAL_KINDS.values()), np.int8), "flag_meanings": " ".join(SPECIAL_KINDS)}),
        "special_label": ("special_point", np.array([sp.label for sp in special], dtype=str),
                          {"long_name": "label: LP fold of cycles, BP branch point, PD period doubling, NS "
                                        "Neimark-Sacker, HC approach to a homoclinic orbit"}),
        "special_index": ("special_point", np.array([sp.index for sp in special], np.int32),
                          {"long_name": "index along dim point"}),
        "special_value": ("special_point", np.array([sp.value if np.isfinite(sp.value) else 0.0 for sp in special]),
                          {"long_name": "located test function (|mu| - 1 of the critical multiplier; HC: p - p_hc)"}),
        "special_multiplier_real": ("special_point", get("multiplier_real"),
                                    {"long_name": "critical multiplier, real part"}),
        "special_multiplier_imag": ("special_point", get("multiplier_imag"),
                                    {"long_name": "critical multiplier, imaginary part"}),
        "special_angle": ("special_point", get("angle"), {"units": "rad", "long_name": "NS: rotation angle arg mu"}),
        "special_limit": ("special_point", get("limit"), {"long_name": "HC: extrapolated parameter of the homoclinic "
                                                                       "orbit"}),
    }


# ============================================================================ the tippedisk
#
# For mu > 0, eps > 0 and lambda_N > 0 the reduced system (:mod:`.reduced`) has no periodic orbits:
# dE/dt = -mu lambda_N |gamma_T|^2 / (|gamma_T| + eps) <= 0, so along a closed orbit the slip vanishes
# identically, the friction force vanishes, and the only such motions are the spinning equilibria
# (docs/continuation.md, docs/periodic_orbits.md). The functions below run the machinery anyway, from a Hopf
# point or from a simulation, and report what Newton finds: an equilibrium or no convergence, with the
# energy lost over the trial period as the reason.

TIPPEDISK_SCALE = (1.0, 1.0, 0.1, 0.1, 10.0, 10.0, 10.0)  # rad, rad, m/s, m/s, rad/s x 3 (spin_continuation)
TIPPEDISK_OBSERVABLES = (("z_S", "m"), ("E_tot", "J"), ("lambda_N", "N"), ("alpha_dot", "rad s-1"),
                         ("slip", "m s-1"))


@functools.lru_cache(maxsize=None)
def _tippedisk_expressions():
    """Observables of the reduced state (the expressions of :func:`.reduced.reduced_system`)."""
    import heyoka as hy

    from . import reduced

    red = reduced.reduced_system()
    values = {"z_S": red.z_S, "E_tot": red.E_tot, "lambda_N": red.lambda_N, "alpha_dot": red.alpha_dot,
              "slip": hy.sqrt(red.slip[0] ** 2 + red.slip[1] ** 2)}
    return red, tuple((name, units, values[name]) for name, units in TIPPEDISK_OBSERVABLES)


def tippedisk_system(setup=None) -> OdeSystem:
    """The reduced tippedisk (7 states, :mod:`.reduced`) as an :class:`OdeSystem` at ``setup``'s parameters.

    With friction: two trivial Floquet multipliers, the flow direction and the spin family. Without friction
    (mu = 0) the disk is conservative: the first integrals E_tot and L_z (the vertical angular momentum about
    S: the contact force is vertical, so it has no moment about the vertical through S) are pinned, and the
    trivial multipliers are three (flow, energy, angular momentum)."""
    from ..models import ode
    from . import reduced

    red, observables = _tippedisk_expressions()
    pars = ode.parameter_vector(setup)
    conservative = pars[ode.PARAMETER_NAMES.index("mu")] == 0.0
    integrals = tuple((name, expr) for name, _u, expr in observables if name == "E_tot") + (
        ("L_z", _vertical_angular_momentum(red)),) if conservative else ()
    return OdeSystem("tippedisk_reduced", reduced.STATE_NAMES, tuple(red.variables), tuple(red.rhs),
                     tuple(pars), ode.PARAMETER_NAMES, TIPPEDISK_SCALE, n_trivial=3 if conservative else 2,
                     compact_mode=True, observables=observables, integrals=integrals,
                     description="reduced tippedisk, ODE Model 1 (" + ("frictionless: conservative" if conservative
                                 else "smooth Coulomb friction") + ", bilateral contact)")


def _vertical_angular_momentum(red):
    """e_z^I . Theta_S omega: e_z^I in body components (sin g sin b, cos g sin b, cos b) ((3.1): G_from_I then
    B_from_G), Theta_S = diag(A, B - m e^2, C - m e^2) (about S)."""
    import heyoka as hy

    from ..models import ode

    beta, gamma, _ux, _uy, w_x, w_y, w_z = red.variables
    m, e = ode.P["m"], ode.P["e"]
    sb = hy.sin(beta)
    return (ode.P["A"] * w_x * hy.sin(gamma) * sb + (ode.P["B"] - m * e * e) * w_y * hy.cos(gamma) * sb
            + (ode.P["C"] - m * e * e) * w_z * hy.cos(beta))


def _setup_from(config_setup: dict):
    from ..parameters import Disk, Friction, Setup

    return Setup(disk=Disk(**config_setup["disk"]), friction=Friction(**config_setup["friction"]),
                 gravity=config_setup.get("gravity", Setup().gravity))


def _energy_change(orbit: PeriodicOrbit) -> float:
    """E(x(T)) - E(x_0) along the (trial) orbit [J]: zero on a periodic orbit."""
    if orbit.status == "nonfinite":
        return 0.0
    flow = Flow(orbit.system)
    try:
        end = flow.advance(orbit.states[0], orbit.period, orbit.pars)
    except FlowError:
        return 0.0
    e = flow.observables(np.column_stack([orbit.states[0], end]), orbit.pars)[1]
    return float(e[1] - e[0])


def _tippedisk_summary(orbits: list[PeriodicOrbit], what: str) -> tuple[str, str]:
    found = [o for o in orbits if o.converged]
    if found:
        return "completed", f"{what}: {len(found)} periodic orbit(s) found"
    counts = {s: sum(o.status == s for o in orbits) for s in STATUS if s != "converged"}
    parts = ", ".join(f"{v} {k.replace('_', ' ')}" for k, v in counts.items() if v)
    return "no_orbit", (f"{what}: no periodic orbit ({parts}). With friction (mu > 0, eps > 0) the energy "
                        "decreases wherever the disk slips, so no motion but the spinning equilibria closes "
                        "(docs/periodic_orbits.md)")


def tippedisk_orbits_from_hopf(ds: xr.Dataset, label: str, amplitudes=(1e-3, 1e-2, 5e-2), *,
                               max_iter: int = NEWTON_MAX_ITER) -> xr.Dataset:
    """Newton for a periodic orbit of the reduced tippedisk from the Hopf point ``label`` of a continuation
    dataset (kind ``continuation``): guesses x_H + 2 r Re(q) (q the critical eigenvector, unit in scaled
    states) with period 2 pi / omega for each r in ``amplitudes``. Status ``completed`` if an orbit
    converged, else ``no_orbit`` (every point's ``orbit_status`` says what Newton found)."""
    from ..results import config_of
    from . import reduced
    from . import spin_continuation as sc

    index, kind = sc.special_point(ds, label)
    if kind != "hopf":
        raise ParameterError(f"{label} is a {kind} point; periodic orbits start at a Hopf point (HOPFn)")
    config = config_of(ds)
    setup = _setup_from(config["setup"])
    values = {name: float(ds[name].values[index]) for name in sc.PARAMETERS}
    if values["inertia"] != 1.0 or any(n in config.get("free", []) for n in ("eps", "mu", "e")):
        setup = sc._setup_with(setup, {k: v for k, v in values.items() if k != "omega"})
    system = tippedisk_system(setup)
    pars = np.array(system.pars)
    x_h = np.array([float(ds[name].values[index]) for name in reduced.STATE_NAMES])
    J = reduced.jacobian(x_h, pars)[0]
    scale = np.asarray(TIPPEDISK_SCALE)
    vals, vecs = np.linalg.eig(J / scale[:, None] * scale[None, :])  # in scaled states
    k = np.argmin(np.where(vals.imag > 1e-9, np.abs(vals.real), np.inf))
    omega, q = float(vals[k].imag), vecs[:, k] / np.linalg.norm(vecs[:, k])
    orbits, energy = [], []
    for r in amplitudes:
        guess = x_h + 2 * (r * q).real * scale
        orbit = find_orbit(system, guess, 2 * math.pi / omega, pars, max_iter=max_iter)
        orbits.append(orbit)
        energy.append(_energy_change(orbit))
    status, message = _tippedisk_summary(orbits, f"from {label} (Omega = {values['omega']:.8g} rad/s, frequency "
                                                  f"{omega:.6g} rad/s)")
    extra = {
        "guess_amplitude": ("point", np.asarray(amplitudes, float),
                            {"units": "1", "long_name": "r of the guess x_H + 2 r Re(q) (q unit in scaled states)"}),
        "energy_change": ("point", np.array(energy), {"units": "J", "long_name": "E(x(T)) - E(x_0) over the period "
                                                      "of the last iterate (0 on a periodic orbit)"}),
    }
    cfg = {"source": "hopf", "source_label": label, "source_values": values, "setup": _to_dict(setup),
           "amplitudes": list(map(float, amplitudes)), "hopf_frequency": omega, "hopf_state": x_h.tolist()}
    return orbits_dataset(orbits, status, message, cfg, extra=extra)


def _to_dict(setup) -> dict:
    from ..parameters import to_dict

    return to_dict(setup)


def tippedisk_returns(setup, initial, t_end: float, *, section: str = "beta_dot=0", tol: float = TAYLOR_TOL):
    """Poincaré returns of an ODE Model 1 run (:mod:`.poincare`): times, reduced states (n, 7), E_tot and
    W_friction at the crossings, and the run's status."""
    from ..models import ode
    from . import poincare, reduced

    sec = poincare.parse_section(section)
    cr = poincare.crossings(sec, setup=setup, initial=initial, t_end=t_end, tol=tol)
    names = ode.EULER.state_names
    S = cr.states
    col = {name: S[:, names.index(name)] for name in names}
    X = reduced.reduced_from_full(col["alpha"], col["beta"], col["gamma"], col["x_dot"], col["y_dot"],
                                  col["omega_x"], col["omega_y"], col["omega_z"]).T
    return cr, X, col["W_friction"]


def tippedisk_orbits_from_run(run: xr.Dataset, *, crossing: int = -2, section: str = "beta_dot=0",
                              max_iter: int = NEWTON_MAX_ITER) -> xr.Dataset:
    """Newton for a periodic orbit of the reduced tippedisk from a Poincaré return of a simulation (a dataset
    of kind ``simulation`` of an ODE model; the run is repeated with ODE Model 1 and its section crossings
    located by events). Guess: the reduced state at crossing ``crossing`` and the return time to the next
    (gamma shifted by the multiple of 2 pi it turned). Holds the returns (dim ``crossing``): return time,
    energy and friction work per return, distance between successive returns."""
    from ..models import ode
    from ..parameters import InitialState
    from ..results import config_of

    if run.attrs.get("kind") != "simulation":
        raise ParameterError(f"the dataset is of kind {run.attrs.get('kind')!r}; give a simulation written by "
                             "tippedisk simulate")
    config = config_of(run)
    if config.get("model") not in ode.MODELS:
        raise ParameterError(f"the run is of model {config.get('model')!r}; give a run of an ODE model "
                             "(ode-euler or ode-quaternion): the reduced system is ODE Model 1's")
    setup = _setup_from(config["setup"])
    initial = InitialState(**config["initial"])
    cr, X, W = tippedisk_returns(setup, initial, float(config["t_end"]), section=section)
    n = len(cr.times)
    if n < 2:
        raise ParameterError(f"the run has {n} crossing(s) of {section}; give a longer run (two returns needed)")
    if not -n <= crossing < n - 1 or crossing == -1:
        raise ParameterError(f"crossing = {crossing} must index a crossing with a successor (0 .. {n - 2}, or "
                             f"-2 .. -{n})")
    k = crossing % n
    system = tippedisk_system(setup)
    pars = np.array(system.pars)
    flow = Flow(system)
    E = flow.observables(X.T, pars)[1]
    shift = np.zeros(7)
    shift[1] = 2 * math.pi * round((X[k + 1, 1] - X[k, 1]) / (2 * math.pi))
    orbit = find_orbit(system, X[k], float(cr.times[k + 1] - cr.times[k]), pars, shift=shift, max_iter=max_iter)
    status, message = _tippedisk_summary([orbit], f"from the return at t = {cr.times[k]:.6g} s of the run "
                                                  f"({cr.status}, {n} crossings of {section})")
    dE = np.diff(E)
    message += (f"; energy change per return: last {dE[-1]:.3g} J, largest |dE| {np.abs(dE).max():.3g} J, "
                f"every return loses energy: {bool(np.all(dE <= 1e-12))}")
    scale = np.asarray(TIPPEDISK_SCALE)
    wrapped = X.copy()
    wrapped[:, 1] = np.angle(np.exp(1j * X[:, 1]))
    dist = np.linalg.norm(np.diff(wrapped, axis=0) / scale, axis=1)
    extra = {
        "return_time": ("crossing", cr.times, {"units": "s", "long_name": f"time of the crossing of {section}"}),
        "return_period": ("crossing", np.append(np.diff(cr.times), 0.0),
                          {"units": "s", "long_name": "time to the next return (0 at the last)"}),
        "return_energy": ("crossing", E, {"units": "J", "long_name": "total energy at the crossing"}),
        "return_energy_change": ("crossing", np.append(dE, 0.0),
                                 {"units": "J", "long_name": "E_tot at the next return minus E_tot here (0 at the "
                                                             "last)"}),
        "return_friction_work": ("crossing", np.append(np.diff(W), 0.0),
                                 {"units": "J", "long_name": "work of the friction force until the next return"}),
        "return_distance": ("crossing", np.append(dist, 0.0),
                            {"units": "1", "long_name": "|x_(k+1) - x_k| / state_scale between successive returns "
                                                        "(gamma modulo 2 pi)"}),
        "return_state": (("crossing", "state"), X, {"long_name": "reduced state at the crossing"}),
        "energy_change": ("point", np.array([_energy_change(orbit)]),
                          {"units": "J", "long_name": "E(x(T)) - E(x_0) over the period of the last iterate"}),
    }
    cfg = {"source": "run", "run_config": config, "section": section, "crossing": int(k),
           "setup": _to_dict(setup), "model_used": "ode-euler"}
    ds = orbits_dataset([orbit], status, message, cfg, extra=extra)
    ds = ds.assign_coords(crossing=("crossing", np.arange(n, dtype=np.int32), {"long_name": "crossing index"}))
    return ds


# ============================================================================ the frictionless tippedisk
#
# With mu = 0 the disk is conservative (energy and the vertical angular momentum about S are first
# integrals) and its spinning equilibria are saddle-centres: near each, the Lyapunov centre theorem gives a
# family of periodic orbits for the elliptic pair (the other imaginary pair, +-i Omega, is the turning of
# S's horizontal velocity in the rotating frame). These are the only periodic orbits of the tippedisk here.


def tippedisk_lyapunov_orbit(setup, branch: str = "inverted", omega: float = 40.0, radius: float = 1e-3, *,
                             max_iter: int = NEWTON_MAX_ITER) -> PeriodicOrbit:
    """A periodic orbit of the frictionless reduced tippedisk (mu = 0) near the spinning equilibrium of
    ``branch`` at spin rate ``omega``: guess x* + 2 r Re(q) on the elliptic eigenpair (q unit in scaled
    states), period 2 pi / frequency, the levels of E_tot and L_z pinned at the guess's."""
    from . import reduced
    from . import stationary as st

    system = tippedisk_system(setup)
    if not system.integrals:
        raise ParameterError("periodic orbits of the tippedisk exist without friction only: give mu = 0 (with "
                             "mu > 0 the energy decreases wherever the disk slips, docs/periodic_orbits.md)")
    x = st.stationary_state(branch, [omega])[:, 0]
    scale = np.asarray(TIPPEDISK_SCALE)
    vals, vecs = np.linalg.eig(reduced.jacobian(x, np.asarray(system.pars))[0])
    elliptic = [i for i in range(len(vals)) if vals[i].imag > 1e-6 * abs(omega)
                and abs(vals[i].real) < 1e-8 * abs(vals[i]) and abs(vals[i].imag - abs(omega)) > 1e-6 * abs(omega)]
    if not elliptic:
        raise ParameterError(f"the {branch} equilibrium at Omega = {omega:g} rad/s has no elliptic eigenpair besides "
                             f"+-i Omega (eigenvalues {np.round(vals, 4)}); choose another spin rate")
    k = elliptic[0]
    q = vecs[:, k] / np.linalg.norm(vecs[:, k] / scale)
    return find_orbit(system, x + 2 * (radius * q).real, 2 * math.pi / vals[k].imag, max_iter=max_iter)


def tippedisk_full_model_check(orbit: PeriodicOrbit, setup, *, tol: float = TAYLOR_TOL,
                               section: str = "beta_dot=0") -> dict:
    """An orbit of the reduced tippedisk checked with ODE Model 1 (11 states): the lifted initial state
    (:func:`.reduced.full_from_reduced`) integrated over one period returns to the orbit (``return_error``:
    max |x(T) - x_0| / scale of the reduced states), and the period equals the return time of the section
    crossings located by :mod:`.poincare`'s event integrator (``section_period``)."""
    import copy as _copy

    import heyoka as hy

    from ..defaults import FALL_ANGLE, SLIP_SMOOTHING
    from ..models import ode
    from ..solvers import taylor
    from . import poincare, reduced

    x0 = orbit.states[0]
    full0 = reduced.full_from_reduced(x0)
    tr = taylor.integrate("ode-euler", setup, full0, orbit.period, orbit.period, tol, FALL_ANGLE, SLIP_SMOOTHING)
    names = ode.EULER.state_names
    end = {name: tr.states[-1, names.index(name)] for name in names}
    x1 = reduced.reduced_from_full(end["alpha"], end["beta"], end["gamma"], end["x_dot"], end["y_dot"],
                                   end["omega_x"], end["omega_y"], end["omega_z"])[:, 0]
    error = float(np.max(np.abs(x1 - x0) / np.asarray(TIPPEDISK_SCALE)))
    sec = poincare.parse_section(section)
    si = poincare.section_integrator("ode-euler", sec.quantity, sec.modulo, sec.direction, float(tol))
    ta = _copy.copy(si.integrator)
    pars = np.append(ode.parameter_vector(setup), sec.level)
    ta.pars[:] = pars
    ta.time = 0.0
    ta.state[:] = full0
    ta.reset_cooldowns()
    rec = ta.nt_events[0].callback
    rec.t_transient, rec.level, rec.modulo, rec.times, rec.states = 0.0, sec.level, sec.modulo, [], []
    ta.propagate_until(2.5 * orbit.period)
    times = np.array(rec.times)
    if ta.time < 2.5 * orbit.period or len(times) < 2:
        raise ParameterError(f"the orbit crosses {section} fewer than twice in 2.5 periods; choose another section")
    return {"return_error": error, "section_period": float(times[1] - times[0]), "section_times": times,
            "period": orbit.period, "outcome": str(hy.taylor_outcome.time_limit)}


def tippedisk_lyapunov_family(setup, branch: str = "inverted", omega: float = 40.0, energy_max: float | None = None,
                              *, radius: float = 1e-3, options: continuation.Options | None = None):
    """The family of periodic orbits of the frictionless tippedisk born at the spinning equilibrium (Lyapunov
    centre theorem), continued in the energy level E_tot away from the equilibrium (towards the equilibrium
    the shooting system becomes singular at the centre: start close to it instead) at fixed L_z.
    Returns (Branch, ShootingProblem)."""
    orbit = tippedisk_lyapunov_orbit(setup, branch, omega, radius)
    if not orbit.converged:
        raise ParameterError(f"no start orbit: {orbit.message}")
    e0 = integral_levels(orbit.system, orbit.states[0], orbit.pars)["E_tot"]
    e1 = e0 + 0.1 if energy_max is None else float(energy_max)
    if not e1 > e0:
        raise ParameterError(f"energy_max = {e1:g} J must exceed the start orbit's energy {e0:.6g} J")
    br, prob = continue_orbits(orbit, "E_tot", bounds={"E_tot": (e0 - 1e-3 * abs(e0), e1)}, direction=1,
                               parameter_scale=0.01,
                               options=options or continuation.Options(ds=0.02, ds_max=0.1, max_points=200))
    return br, prob


def tippedisk_branch_dataset(prob: ShootingProblem, br: continuation.Branch, info: dict | None = None) -> xr.Dataset:
    """:func:`branch_dataset` of a tippedisk branch with ``valid`` per orbit: lambda_N > 0 all along it (the
    bilateral contact model holds); orbits with lambda_N < 0 somewhere would lift off."""
    ds = branch_dataset(prob, br, info)
    lam = ds.observable_min.sel(observable="lambda_N").values
    valid = (lam > 0).astype(np.int8)
    ds["valid"] = ("point", valid, {"long_name": "1: lambda_N > 0 along the whole orbit (bilateral contact holds)",
                                    "flag_values": np.array([0, 1], np.int8), "flag_meanings": "lift_off valid"})
    name = prob.parameter
    if valid.all():
        ds.attrs["message"] += "; lambda_N > 0 on every orbit"
    else:
        first = int(np.argmin(valid))
        ds.attrs["message"] += (f"; lambda_N < 0 on the orbits from {name} = {float(ds[name][first]):.6g} on (min "
                                f"{lam.min():.3g} N): the contact would lift off there, outside the bilateral model "
                                "(see valid)")
    return ds
