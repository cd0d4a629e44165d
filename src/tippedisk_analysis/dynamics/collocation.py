"""Periodic orbits of a :class:`.system.System` by orthogonal collocation (as AUTO-07p, COLSYS, MatCont, COCO):
the continuation problem.

Time is scaled to tau = t / T in [0, 1]: dx/dtau = T f(x; p). The orbit is a continuous periodic piecewise
polynomial of degree m = ncol on ntst mesh intervals (:mod:`.collocation_mesh`); unknowns u = (x at the
ntst m nodes, T[, p]). Equations:

* collocation: dx/dtau - T f(x) = 0 at the m Gauss-Legendre points of every interval (n ntst m rows);
* the integral phase condition int_0^1 x(tau) . x_ref'(tau) dtau = 0 in scaled states (x / state_scale), x_ref
  the reference orbit (the last one found during continuation; AUTO's condition: int x_ref . x_ref' = 0 for a
  periodic x_ref, so it is int (x - x_ref) . x_ref'), exact by the Gauss rule;
* the levels of first integrals and pinned states at x(0) (:mod:`.orbit_base`); with them the system has more
  rows than unknowns and is solved by least squares (:mod:`.linear_algebra`).

The Jacobian is a scipy sparse matrix: one block of n m x n (m + 1) entries per interval, the T and p columns and
the border rows, from one call of the System's compiled linearisation (f, f_x, f_p) at all Gauss points; no dense
matrix of its size is formed. The Floquet multipliers come from the same blocks: condensed per mesh interval to
pencils (A_j, B_j) with A_j x_j + B_j x_j+1 = 0, their product's eigenvalues by periodic QR sweeps
(:mod:`.periodic_schur`), never the monodromy formed: each multiplier keeps its relative accuracy where they
spread over many orders of magnitude (violently unstable, fast-slow orbits). Stability and the test functions
count the multipliers outside the unit circle and measure their distances from +1, -1 and the circle
(:meth:`CollocationProblem.tests`), bounded however large the multipliers are. A singular block makes the orbit's
multipliers NaN with the reason in its message, never an exception. Shooting referees an orbit on request
(:func:`.orbits.find_orbit` with method ``shooting`` from its x(0) and period), not on every orbit.

Every ``adapt`` accepted points of a branch the mesh is adapted (equidistributing the error estimate,
:meth:`.collocation_mesh.Mesh.adapted`) and the orbit interpolated onto it; where an orbit's estimated error
(:meth:`.collocation_mesh.Mesh.error_estimate`) exceeds ``error_tol``, the mesh gets the intervals the estimate
asks for (as COCO's adaptive NTST), up to ``ntst_max``. Each orbit records its estimated error.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ParameterError
from .collocation_mesh import Mesh
from .collocation_solver import Factorisation, Linearisation, assemble, sparse_jacobian
from .flows import TAYLOR_TOL, Flow, FlowError
from .collocation_floquet import CollocationFloquet, formed_monodromy
from .orbit_base import N_SAMPLES, OrbitProblem, PeriodicOrbit, orbit_size
from .system import System

NTST, NCOL = 40, 4  # default mesh intervals and collocation points per interval
ADAPT = 3  # the mesh is adapted every ADAPT accepted points of a branch (AUTO's IAD)
ERROR_TOL = 1e-6  # largest estimated error of x(t) / state_scale on a branch before the mesh gets more intervals
NTST_GROWTH = 16  # ... up to this many times the start's intervals (ntst_max)
GROWTH_MARGIN = 2.0  # a mesh that grows aims at error_tol / GROWTH_MARGIN
MESH_PASSES = 4  # adaptations of the mesh to an integrated guess before the first Newton step
SPECTRA_KEPT = 1000  # multipliers of orbits kept for the dataset of a branch
REMESH_CHANGE = 1e-3  # a new mesh is taken if a mesh point moves by more than this share of its interval


class _Evaluation(dict):
    """The evaluation of u; ``multipliers``, ``M`` (monodromy), ``f0`` and ``half`` are computed when first asked
    for."""

    def __init__(self, compute, **items):
        super().__init__(**items)
        self._compute = compute

    def __missing__(self, key):
        value = self._compute(self, key)
        self[key] = value
        return value


class CollocationProblem(CollocationFloquet, OrbitProblem):
    """Periodic orbits of ``system`` by collocation on ``mesh`` (default: ``ntst`` uniform intervals of ``ncol``
    points); a continuation problem if ``parameter`` is set (module docstring). Unknowns u = (T[, p], nodes).

    ``adapt``: the mesh is adapted every ``adapt`` accepted points of a branch (0: never); ``error_tol``: where an
    accepted orbit's estimated error exceeds it, the mesh gets more intervals (up to ``ntst_max``, default
    NTST_GROWTH times ``ntst``; ``math.inf``: ntst fixed); ``tol``: the Taylor integrator of guesses."""

    method = "collocation"

    def __init__(self, system: System, pars=None, *, ntst: int = NTST, ncol: int = NCOL, mesh: Mesh | None = None,
                 parameter: str | None = None, parameter_scale: float = 1.0, period_scale: float = 1.0,
                 bounds: dict | None = None, levels: dict | None = None, pins: dict | None = None,
                 adapt: int = ADAPT, error_tol: float = ERROR_TOL, ntst_max: int | None = None,
                 tol: float = TAYLOR_TOL):
        self.mesh = mesh if mesh is not None else Mesh.uniform(ntst, ncol)
        super().__init__(system, pars, self.mesh.n_nodes, parameter=parameter, levels=levels, pins=pins,
                         bounds=bounds, period_first=True)
        if int(adapt) != adapt or adapt < 0:
            raise ParameterError(f"adapt = {adapt!r}; give a whole number of points (0: never adapt the mesh)")
        if not (isinstance(error_tol, int | float) and error_tol > 0):
            raise ParameterError(f"error_tol = {error_tol!r}; give a positive number (math.inf: ntst fixed)")
        self.adapt, self._since_adapt = int(adapt), 0
        self.error_tol = float(error_tol)
        self.ntst_max = int(ntst_max) if ntst_max is not None else NTST_GROWTH * self.mesh.ntst
        self.period_scale, self.parameter_scale = float(period_scale), float(parameter_scale)
        self.flow = Flow(system, tol)
        self._linearisation = system.linearisation_function(() if self.p_index is None else (self.p_index,))
        self._rhs = system.rhs_function()
        self._tiled = None  # (parameters, points, count) and the parameters tiled over the Gauss points
        self._memo: dict = {}
        self._spectra: dict = {}  # (u, mesh) -> the multipliers of an orbit evaluated before
        self._basis = None  # the last periodic Schur basis at x(0): the next orbit's sweeps start from it
        self._phase = np.zeros(0)
        self.use(self.mesh)

    @property
    def n_collocation(self) -> int:
        """Collocation rows (n ntst ncol)."""
        return self.mesh.n_nodes * self.n

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, unknowns) of the Jacobian: collocation, phase and level rows; T[, p] and the nodes."""
        return self.n_collocation + 1 + len(self.level_names), self.x_start + self.n_collocation

    @property
    def names(self) -> tuple[str, ...]:
        return (("T",) + ((self.parameter,) if self.parameter else ())
                + tuple(f"{s}[{g}]" for g in range(self.n_nodes) for s in self.system.state_names))

    # -- the mesh
    @property
    def node_times(self) -> np.ndarray:
        """tau of the nodes (n_nodes,)."""
        return self.mesh.times

    def use(self, mesh: Mesh) -> None:
        """Make the unknowns refer to ``mesh`` (ncol as the problem's; the number of intervals may differ)."""
        if mesh.m != self.mesh.m:
            raise ParameterError(f"a mesh of ncol = {mesh.m} for a problem of ncol = {self.mesh.m}")
        self.mesh = mesh
        self.n_nodes = mesh.n_nodes
        if len(self._phase) != mesh.n_nodes * self.n:  # set_reference gives it on the new mesh
            self._phase = np.zeros(mesh.n_nodes * self.n)
        self.scale = self._scale_of(mesh)
        self._memo.clear()

    def _scale_of(self, mesh: Mesh) -> np.ndarray:
        """The scale of the unknowns on ``mesh``: the nodes' by their quadrature weights (the arclength measures
        the orbit's L2 norm over the period), the period's and the parameter's."""
        node_scale = np.asarray(self.system.state_scale)[None, :] / np.sqrt(mesh.weights)[:, None]
        return np.concatenate([[self.period_scale], [self.parameter_scale] if self.parameter else [],
                               node_scale.ravel()])

    def discretisation(self) -> Mesh:
        return self.mesh

    def remesh(self, point) -> tuple[np.ndarray, np.ndarray] | None:
        """The accepted point on a new mesh: at once if its estimated error exceeds error_tol / GROWTH_MARGIN (so
        that the next orbit, a step on, stays below error_tol), else every ``adapt`` points; the mesh that
        equidistributes the error, with more intervals where the estimate asks for them (:meth:`_better`)."""
        self._since_adapt += 1
        X = self.split(point.u)[0]
        due = self.adapt and self._since_adapt >= self.adapt
        if not (due or self.mesh.error_estimate(X, self.system.state_scale) > self.error_tol / GROWTH_MARGIN):
            return None
        self._since_adapt = 0
        return self.carry(point) if self._better(X) else None

    def refine(self, u) -> bool:
        """Where the estimated error of the orbit u exceeds ``error_tol``: the problem switched to a better mesh
        (:meth:`_better`); False if the error is below the tolerance or the mesh cannot change."""
        X = self.split(u)[0]
        if self.mesh.error_estimate(X, self.system.state_scale) <= self.error_tol or not self._better(X):
            return False
        self._since_adapt = 0
        return True

    def _better(self, X) -> bool:
        """Switch to the mesh that equidistributes the error of the orbit X, with the intervals (up to ntst_max)
        that bring it to error_tol / GROWTH_MARGIN^2; False if that mesh is the present one (REMESH_CHANGE)."""
        scale = self.system.state_scale
        needed = self.mesh.needed_intervals(X, scale, self.error_tol / GROWTH_MARGIN ** 2)
        new = self.mesh.adapted(X, scale, min(self.ntst_max, max(self.mesh.ntst, needed)))
        if new.ntst == self.mesh.ntst and np.max(np.abs(new.tau - self.mesh.tau)) <= REMESH_CHANGE * new.h.min():
            return False
        self.use(new)
        return True

    def carry(self, point) -> tuple[np.ndarray, np.ndarray]:
        """(u, unit tangent) of a point on the present mesh: its orbit and its tangent (a variation of the
        orbit) evaluated by the polynomials of its own mesh."""
        old = point.discretisation
        variation = point.tangent * self._scale_of(old)
        u = np.concatenate([point.u[: self.x_start], old.evaluate(self._nodes(point.u), self.mesh.times).ravel()])
        known = self._spectra.get((point.u.tobytes(), old.tau.tobytes()))
        if known is not None:  # the same orbit, interpolated: its multipliers stay
            self._spectra[self._key(u)] = known
        tangent = np.concatenate([variation[: self.x_start],
                                  old.evaluate(self._nodes(variation), self.mesh.times).ravel()]) / self.scale
        return u, tangent / np.linalg.norm(tangent)

    def _nodes(self, u) -> np.ndarray:
        """The node states of u (n_nodes, n) on whatever mesh u refers to."""
        return np.asarray(u, dtype=float)[self.x_start:].reshape(-1, self.n)

    def improved(self, u) -> np.ndarray | None:
        """u on a better mesh, the problem switched to it: with more intervals if its error exceeds
        ``error_tol`` (:meth:`refine`), else adapted (:meth:`adapted`); None if the mesh stays."""
        old = self.mesh
        if self.refine(u):
            return np.concatenate([u[: self.x_start], old.evaluate(self._nodes(u), self.mesh.times).ravel()])
        return self.adapted(u)

    def adapted(self, u) -> np.ndarray | None:
        """u on the mesh of as many intervals adapted to its orbit, with the problem switched to it; None if the
        mesh stays (REMESH_CHANGE)."""
        X, T, p = self.split(u)
        new = self.mesh.adapted(X, self.system.state_scale)
        if np.max(np.abs(new.tau - self.mesh.tau)[1:-1] / np.minimum(new.h[:-1], new.h[1:])) <= REMESH_CHANGE:
            return None
        X_new = self.mesh.evaluate(X, new.times)
        self.use(new)
        return self.pack(X_new, T, p)

    def config(self) -> dict:
        return {"method": "collocation", "ntst": self.mesh.ntst, "ncol": self.mesh.m, "adapt": self.adapt,
                "error_tol": self.error_tol if math.isfinite(self.error_tol) else None, "ntst_max": self.ntst_max,
                "phase": "integral", "tol": self.flow.tol}

    # -- unknowns
    def unknowns(self, state, period: float, value: float | None = None) -> np.ndarray:
        """u from one point of the orbit and its period: the integrated guess at the nodes of a mesh adapted to
        it (:data:`MESH_PASSES` passes, if the problem adapts meshes)."""
        pars = self.pars.copy()
        if self.p_index is not None:
            value = pars[self.p_index] if value is None else value
            pars[self.p_index] = value
        state = np.asarray(state, dtype=float)
        for _ in range(MESH_PASSES if self.adapt else 0):
            X = self._integrated(state, period, pars)
            self.use(self.mesh.adapted(X, self.system.state_scale))
        return self.pack(self._integrated(state, period, pars), period, value)

    def _integrated(self, state, period: float, pars) -> np.ndarray:
        return self.flow.trajectory(state, period * self.mesh.times, pars)

    # -- evaluation
    def _key(self, u) -> tuple:
        """u and the mesh it refers to (the memo's and the multipliers' key)."""
        return np.asarray(u, dtype=float).tobytes(), self.mesh.tau.tobytes()

    def _evaluate(self, u) -> dict:
        key = self._key(u)
        hit = self._memo.get(key)
        if hit is not None:
            return hit
        out = self._evaluation(u, key)
        if len(self._memo) > 8:
            self._memo.pop(next(iter(self._memo)))
        self._memo[key] = out
        return out

    def _evaluation(self, u, key=None) -> dict:
        mesh, n, m = self.mesh, self.n, self.mesh.m
        X, T, _p = self.split(u)
        pars = self.runtime(u)
        if not (math.isfinite(T) and T > 0) or not np.all(np.isfinite(X)):
            return {"error": f"the period T = {T:.6g} is not positive" if not T > 0 else "non-finite node states"}
        xz, dxz = mesh.at_gauss(X)
        lin = self._at_gauss_points(self._linearisation, xz, pars)
        if not np.all(np.isfinite(lin)):
            return {"error": "the right-hand side is not finite on the orbit"}
        f = lin[:, :n].reshape(xz.shape)
        J = lin[:, n:n + n * n].reshape(*xz.shape, n)
        blocks = assemble(J, mesh.h, T, mesh.basis.at_gauss, mesh.basis.slope_at_gauss)
        columns = [-f.reshape(mesh.ntst, m * n)]  # d/dT, then d/dp
        if self.p_index is not None:
            columns.append(-T * lin[:, n + n * n:].reshape(mesh.ntst, m * n))
        elif self.parameter:  # the level of a first integral or a pinned state: no column in the collocation
            columns.append(np.zeros((mesh.ntst, m * n)))
        levels, level_rows = self.level_rows(u, X[0])
        return _Evaluation(self._lazy, collocation=(dxz - T * f).ravel(), levels=levels, level_rows=level_rows, X=X,
                           T=T, pars=pars, blocks=blocks, extras=np.stack(columns, axis=2), key=key)

    def _lazy(self, ev: dict, key: str):
        if key == "condensed":  # the stage-1 blocks of the elimination, without border rows
            return Factorisation(ev["blocks"], ev["extras"], np.zeros((0, self.n_nodes, self.n)),
                                 np.zeros((0, self.x_start)), self.mesh.m).condensed
        if key == "multipliers":  # (mu by modulus descending, trivial and flow masks, flow error, status, message)
            known = self._spectra.get(ev["key"])  # a point of the branch: the dataset asks again
            if known is None:
                known = self._spectra[ev["key"]] = self._multipliers(ev)
                if len(self._spectra) > SPECTRA_KEPT:
                    self._spectra.pop(next(iter(self._spectra)))
            return known
        if key == "M":  # the monodromy formed (for inspection and branch switching; the multipliers never use it)
            return formed_monodromy(*ev["condensed"])
        if key == "f0":
            return self.system.f(ev["X"][0], ev["pars"])
        if key == "size":
            return orbit_size(ev["X"], self.system.state_scale)
        if key == "half":
            x_half = self.mesh.evaluate(ev["X"], [0.5])[0]
            return (ev["X"][0] - x_half) / np.asarray(self.system.state_scale)
        raise KeyError(key)

    def residual(self, u) -> np.ndarray:
        """The residual alone (no Jacobian: chord steps need none), unless u was evaluated already."""
        hit = self._memo.get(self._key(u))
        if hit is not None:
            return np.full(self.shape[0], np.nan) if "error" in hit else self._residual_of(hit)
        X, T, _p = self.split(u)
        if not (math.isfinite(T) and T > 0) or not np.all(np.isfinite(X)):
            return np.full(self.shape[0], np.nan)
        xz, dxz = self.mesh.at_gauss(X)
        f = self._at_gauss_points(self._rhs, xz, self.runtime(u))
        levels = self.level_rows(u, X[0])[0]
        return np.concatenate([(dxz - T * f.reshape(xz.shape)).ravel(), [self._phase @ X.ravel()], levels])

    def _at_gauss_points(self, function, xz: np.ndarray, pars: np.ndarray) -> np.ndarray:
        """A compiled function of the System at the Gauss points (ntst, m, n): (ntst m, outputs); the parameters
        tiled once per parameter vector and mesh size."""
        states = np.ascontiguousarray(xz.reshape(-1, self.n).T)
        if function.nparams == 0:
            return function(states).T
        key = (pars.tobytes(), states.shape[1], function.nparams)
        if self._tiled is None or self._tiled[0] != key:
            self._tiled = key, np.ascontiguousarray(np.repeat(pars[: function.nparams, None], states.shape[1], axis=1))
        return function(states, pars=self._tiled[1]).T

    def _residual_of(self, ev: dict) -> np.ndarray:
        """The residual of an evaluation with the present phase condition (set_reference changes it)."""
        return np.concatenate([ev["collocation"], [self._phase @ ev["X"].ravel()], ev["levels"]])

    def _borders(self, ev: dict) -> np.ndarray:
        """The border rows (phase condition, levels) of an evaluation, in the layout of u."""
        return np.vstack([np.concatenate([np.zeros(self.x_start), self._phase]), ev["level_rows"]])

    def linearise(self, u, scale, row=None) -> Linearisation:
        """The Newton system at u in the unknowns u / scale (with ``row`` appended), factorised by the block
        elimination of :mod:`.collocation_solver`."""
        ev = self._evaluate(u)
        scale = np.asarray(scale, dtype=float)
        if "error" in ev:
            return Linearisation(None, None, None, scale, self.x_start, self.mesh, self.n)
        borders = self._borders(ev) if row is None else np.vstack([self._borders(ev), row / scale])
        lin = Linearisation(ev["blocks"], ev["extras"], borders, scale, self.x_start, self.mesh, self.n)
        if "condensed" not in ev:  # the condensation of the intervals does not see the border rows
            ev["condensed"] = lin.factorisation.condensed
        return lin

    def jacobian(self, u):
        """The Jacobian as a scipy sparse matrix (for inspection; Newton solves with :meth:`linearise`)."""
        ev = self._evaluate(u)
        if "error" in ev:
            raise FlowError(ev["error"])
        return sparse_jacobian(ev["blocks"], ev["extras"], self._borders(ev), self.mesh, self.n, self.x_start)

    def set_reference(self, u) -> None:
        """The phase condition relative to the orbit u (its derivative at the Gauss points, scaled)."""
        X = self.split(u)[0]
        mesh = self.mesh
        _x, slope = mesh.at_gauss(X)
        scale2 = np.asarray(self.system.state_scale) ** 2
        quadrature = mesh.basis.at_gauss.T * mesh.basis.weights[None, :]  # (m+1, m): int L_i g = sum_k w_k L_i(z_k) g_k
        weights = mesh.h[:, None, None] * (quadrature @ (slope / scale2))  # (ntst, m+1, n) per interval node
        coefficients = weights[:, :mesh.m].copy()
        coefficients[:, 0] += np.roll(weights[:, mesh.m], 1, axis=0)  # a mesh point ends the interval before
        self._phase = coefficients.reshape(-1, self.n).ravel()
        if np.all(np.isfinite(X)):
            scale = np.asarray(self.system.state_scale)
            self._remember_half({"half": (X[0] - mesh.evaluate(X, [0.5])[0]) / scale, "size": orbit_size(X, scale)})

    # -- the orbit traversed twice (period doubling)
    def propagate(self, u, v) -> np.ndarray:
        """The variation v at x(0) carried along the orbit by the collocation equations, at the nodes (n_nodes, n)."""
        n, m = self.n, self.mesh.m
        blocks = self._evaluate(u)["blocks"].reshape(self.mesh.ntst, m * n, (m + 1) * n)
        out = np.empty((self.mesh.n_nodes + 1, n))
        out[0] = v
        for j, block in enumerate(blocks):  # given the left node, the interior and right nodes solve the block
            out[j * m + 1:(j + 1) * m + 1] = np.linalg.solve(block[:, n:], -block[:, :n] @ out[j * m]).reshape(m, n)
        return out[:-1]

    def doubled(self, u) -> tuple[CollocationProblem, np.ndarray]:
        """The problem of twice the period (the mesh twice, on [0, 1/2] and [1/2, 1]) and u as its solution."""
        X, T, p = self.split(u)
        tau = np.concatenate([self.mesh.tau / 2, 0.5 + self.mesh.tau[1:] / 2])
        bounds = {("T" if i == self.t_index else self.parameter): ((2 * lo, 2 * hi) if i == self.t_index else (lo, hi))
                  for i, (lo, hi) in self.bounds.items()}
        double = CollocationProblem(self.system, self.runtime(u), mesh=Mesh(tau, self.mesh.m), parameter=self.parameter,
                                    parameter_scale=self.parameter_scale, period_scale=2 * self.period_scale,
                                    bounds=bounds, levels=self.levels, pins=self.pins, adapt=self.adapt,
                                    error_tol=self.error_tol, ntst_max=2 * self.ntst_max, tol=self.flow.tol)
        return double, double.pack(np.vstack([X, X]), 2 * T, p)

    # -- orbits
    def orbit(self, u, status: str = "converged", message: str = "", residual: float | None = None,
              iterations: int = 0, n_samples: int = N_SAMPLES, discretisation: Mesh | None = None) -> PeriodicOrbit:
        """The orbit at u (on ``discretisation``, the point's mesh, default the current one) with samples,
        multipliers and the estimated discretisation error (a point of a branch keeps the multipliers computed
        when it was accepted)."""
        if discretisation is not None and discretisation is not self.mesh:
            self.use(discretisation)
        X, T, p = self.split(u)
        pars = self.runtime(u)
        known = self._spectra.get(self._key(u))
        if known is None:
            ev = self._evaluate(u)
            if "error" in ev:
                raise FlowError(ev["error"])
            known = ev["multipliers"]
        mu, trivial, _flow, flow_error, multiplier_status, multiplier_message = known
        if multiplier_status != "completed":
            message = "; ".join(filter(None, (message, multiplier_message)))
        samples = self.mesh.evaluate(X, np.arange(n_samples) / n_samples)
        if residual is None:
            residual = float(np.max(np.abs(self.residual(u)[: self.n_collocation].reshape(-1, self.n))
                                    / np.asarray(self.system.state_scale)))
        observables = (self.flow.observables(samples.T, pars).T if self.system.observables
                       else np.empty((n_samples, 0)))
        return PeriodicOrbit(status, message, self.system, pars, X.copy(), T, p, self.parameter, residual, iterations,
                             mu, trivial, T * np.arange(n_samples) / n_samples, samples, observables,
                             method="collocation",
                             discretisation_error=self.mesh.error_estimate(X, self.system.state_scale),
                             mesh=self.mesh.tau.copy(), flow_multiplier_error=flow_error,
                             multiplier_source="collocation" if multiplier_status == "completed" else "none")
