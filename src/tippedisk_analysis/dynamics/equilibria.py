"""Continuation problems for equilibria of a :class:`.system.System` (generic: knows nothing of the disk).

An equilibrium is f(x; p) = 0 together with pinned observables g_k(x; p) = c_k (``pins``: names of the
system's observables); each value c_k is a fixed number or a free unknown (a "pinned" continuation
parameter, e.g. the spin rate alpha_dot = Omega of a family of relative equilibria). The other
continuation parameters set runtime parameters of the system (:class:`Parameter`).

Problems of codimension one (Hopf and zero-eigenvalue curves in two parameters) add one
equation: the real part of the critical eigenvalue (pair) of the state Jacobian, with its exact
gradient from the second-derivative tensor (first-order eigenvalue perturbation).

A family of equilibria (``family`` given: J phi0 = 0 on every member) is handled by deflation:
the state Jacobian that decides stability drops the family's row and column
(tippedisk_analysis.analysis.stability proves this exact for the tippedisk); normal forms use the
line-of-equilibria coefficients of :mod:`.normal_forms`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import schur

from ..errors import ParameterError
from . import continuation, normal_forms
from .system import System
from .tensors import bilinear


@dataclass(frozen=True)
class Parameter:
    """A continuation parameter.

    runtime: ((index into the runtime parameter vector, coefficient), ...); its value sets
    pars[index] = coefficient * value (one entry for a parameter of the system; three for a common
    scale of three inertias). pin: index of the pinned observable g_k it equals instead (runtime empty).
    """

    name: str
    scale: float
    runtime: tuple = ()
    pin: int | None = None

    @classmethod
    def of(cls, system: System, name: str, scale: float = 1.0) -> Parameter:
        """The system's runtime parameter ``name``."""
        return cls(name, scale, runtime=((system.parameter_index(name), 1.0),))


REAL_TOL = 1e-7  # relative |Im s| below which an eigenvalue counts as real: the eigenvalues of a Jordan
# block (at a Bogdanov-Takens point) are only determined to sqrt(machine eps)


class EquilibriumProblem(continuation.Problem):
    """Unknowns u = (x, free parameter values); residual [f(x; p), g_k(x) - c_k, (critical eigenvalue)]."""

    def __init__(self, system: System, free: list[Parameter], *, pars=None, pins=(), state_scale=None,
                 pin_values: dict | None = None, bounds: dict | None = None, family: int | None = None,
                 critical: str | None = None, nonsmooth=None, project=None, family_sign: float = 1.0):
        self.system = system
        self.free = list(free)
        tensor_parameters = sorted({i for p in self.free for i, _c in p.runtime})
        self._derivative = [tuple((tensor_parameters.index(i), c) for i, c in p.runtime) for p in self.free]
        self.field = system.field(pins, tensor_parameters)
        self.n = system.n
        self.pars = system.pars.copy() if pars is None else np.array(pars, dtype=float)
        self.pin_values = dict(pin_values or {})  # pin index -> fixed value (pins not freed)
        self.family = family  # state index of the family direction (deflated), or None
        self.family_sign = family_sign  # d x[family] / d s of the family's own coordinate s
        self.keep = [i for i in range(self.n) if i != family]
        if critical not in (None, "hopf", "zero"):
            raise ParameterError(f"critical = {critical!r}; give 'hopf', 'zero' or None")
        self.critical = critical
        self._borders = None  # (w0, v0) of the bordered zero test, set by set_reference
        self.nonsmooth = nonsmooth  # (x, pars) -> (G_xs, Gamma): the C^1 term N(w) = (G_xs w)|Gamma w|
        self._project = project  # (u, problem) -> u on a closed-form solution manifold, or None
        self.names = (*system.state_names, *(p.name for p in self.free))
        state_scale = system.state_scale if state_scale is None else state_scale
        self.scale = np.array([*state_scale, *(p.scale for p in self.free)], dtype=float)
        self.parameters = tuple(range(self.n, self.n + len(self.free)))
        self.bounds = {self.n + i: tuple(b) for i, b in (bounds or {}).items()}
        self.n_pins = len(tuple(pins))
        for k in range(self.n_pins):
            if k not in self.pin_values and not any(p.pin == k for p in self.free):
                raise ParameterError(f"pin function {k} needs a value or a free parameter")

    def project(self, u: np.ndarray) -> np.ndarray:
        return u if self._project is None else self._project(u, self)

    # -- evaluation helpers
    def runtime(self, u: np.ndarray) -> np.ndarray:
        pars = self.pars.copy()
        for p, value in zip(self.free, u[self.n:]):
            for index, coefficient in p.runtime:
                pars[index] = coefficient * value
        return pars

    def pin_targets(self, u: np.ndarray) -> np.ndarray:
        targets = np.array([self.pin_values.get(k, np.nan) for k in range(self.n_pins)])
        for p, value in zip(self.free, u[self.n:]):
            if p.pin is not None:
                targets[p.pin] = value
        return targets

    def _first(self, u):
        return self.field.tensor(u[: self.n], self.runtime(u), 1)

    def _parameter_columns(self, T: np.ndarray) -> np.ndarray:
        """d outputs / d free parameters from a tensor's parameter slots (last axis)."""
        cols = np.zeros((*T.shape[:-1], len(self.free)))
        for j, derivative in enumerate(self._derivative):
            for position, coefficient in derivative:
                cols[..., j] += coefficient * T[..., self.n + position]
        return cols

    def state_jacobian(self, u: np.ndarray) -> np.ndarray:
        J = self._first(u)[: self.n, : self.n]
        return J[np.ix_(self.keep, self.keep)]

    # -- the critical eigenvalue(s) (codimension-one curves)
    def set_reference(self, u: np.ndarray) -> None:
        """The borders of the zero test: the singular vectors of J's smallest singular value at ``u``."""
        if self.critical == "zero":
            U, _sv, Vt = np.linalg.svd(self.state_jacobian(u))
            self._borders = (U[:, -1].copy(), Vt[-1].copy())

    def _critical_indices(self, ev: np.ndarray) -> list[int]:
        """Eigenvalues of the critical pair (hopf: the two whose sum is nearest 0 among complex-conjugate
        and real pairs, so a Hopf curve continues through a Bogdanov-Takens point as a neutral-saddle
        curve) or the real eigenvalue nearest 0 (zero)."""
        tiny = REAL_TOL * max(1.0, np.abs(ev).max())
        real = [i for i in range(len(ev)) if abs(ev[i].imag) <= tiny]
        if self.critical == "zero":
            return [min(real, key=lambda i: abs(ev[i].real))] if real else []
        pairs = [(i, int(np.argmin(np.abs(ev - np.conj(ev[i]))))) for i in range(len(ev)) if ev[i].imag > tiny]
        pairs += [(a, b) for k, a in enumerate(real) for b in real[k + 1:]]
        return list(min(pairs, key=lambda ij: abs(ev[ij[0]] + ev[ij[1]]))) if pairs else []

    def _critical_row(self, u: np.ndarray, T1: np.ndarray) -> tuple[float, np.ndarray]:
        """The critical quantity and its exact gradient with respect to u.

        zero: g of the bordered system [[J, w0], [v0^T, 0]] [v; g] = [0; 1], zero iff J is singular,
        dg = -w^T dJ v (Govaerts' minimally augmented system; smooth through a Bogdanov-Takens point,
        unlike the eigenvalue). The borders are the singular vectors of the smallest singular value at
        the last accepted point (:meth:`set_reference`), fixed while a point is corrected;
        hopf: half the trace of J on the critical pair's invariant subspace (Re lambda for a complex
        pair), d tr = tr(W^T dJ V), smooth through a Bogdanov-Takens point where the pair turns real.
        """
        Jd = T1[: self.n, : self.n][np.ix_(self.keep, self.keep)]
        T2 = self.field.tensor(u[: self.n], self.runtime(u), 2)[: self.n]
        T2d = T2[np.ix_(self.keep, self.keep, np.arange(T2.shape[2]))]
        if self.critical == "zero":
            if self._borders is None:
                self.set_reference(u)
            left, right = self._borders
            k = Jd.shape[0]
            M = np.block([[Jd, left[:, None]], [right[None, :], np.zeros((1, 1))]])
            rhs = np.zeros(k + 1)
            rhs[-1] = 1.0
            vg, wh = np.linalg.solve(M, rhs), np.linalg.solve(M.T, rhs)
            dvalue = -np.einsum("i,ijk,j->k", wh[:k], T2d, vg[:k])
            grad = np.concatenate([dvalue[: self.n], self._parameter_columns(dvalue[None, :])[0]])
            return float(vg[-1]), grad
        vals = np.linalg.eigvals(Jd)
        idx = self._critical_indices(vals)
        if not idx:
            return np.nan, np.full(len(u), np.nan)
        chosen = vals[idx]
        try:
            V = _invariant_basis(Jd, chosen)  # orthonormal bases of the right and left invariant subspaces:
            L = _invariant_basis(Jd.T, chosen)  # well conditioned where the pair's eigenvectors merge (BT)
        except np.linalg.LinAlgError:
            return np.nan, np.full(len(u), np.nan)
        W = L @ np.linalg.inv(V.T @ L)  # W^T V = I: the spectral projector is V W^T
        weight = 1.0 / len(idx)  # lambda_0, or the mean of the pair
        dvalue = weight * np.einsum("ia,ijk,ja->k", W, T2d, V).real  # tr(W^T dJ V) per tensor argument
        value = weight * float(np.sum(chosen).real)
        grad = np.concatenate([dvalue[: self.n], self._parameter_columns(dvalue[None, :])[0]])
        return value, grad

    def tests(self, point) -> dict[str, float]:
        """Equilibrium branches: fold, branch point, Hopf. Curves: their codimension-two points."""
        if self.critical is None:
            return super().tests(point)
        ev = point.eigenvalues
        idx = self._critical_indices(ev)
        if not idx:
            return {}
        others = np.delete(ev, idx)
        i, j = np.triu_indices(len(others), 1)
        out = {}
        if self.critical == "hopf":
            kappa = float((ev[idx[0]] * ev[idx[1]]).real)  # omega^2 on a Hopf curve, < 0 on a neutral saddle
            out["bogdanov_takens"] = kappa
            if kappa > 0:  # the other tests only on the Hopf part of the curve
                out["zero_hopf"] = float(np.prod(others).real)
                out["double_hopf"] = float(np.prod(others[i] + others[j]).real)
                nf = self.describe("hopf", point.u)
                if self.family is None:
                    if nf["class"] != "not_smooth":
                        out["bautin"] = nf["l1"]
                else:
                    out["line_saddle_change"] = nf["a"] * nf["b"]
                    out["line_focus_node"] = nf["k"] ** 2 + 4 * nf["a"] * nf["b"]
        else:
            out["bogdanov_takens"] = float(np.prod(others).real)  # a second real eigenvalue through 0
            out["zero_hopf"] = float(np.prod(others[i] + others[j]).real)
            nf = self.describe("fold_or_bp", point.u)
            if self.family is None:
                if nf.get("class") != "not_smooth":
                    out["cusp"] = nf["a"]
            else:
                out["line_saddle_change"] = nf["a"] * nf["b"]
                out["line_focus_node"] = (nf["k"] + nf["c"]) ** 2 + 4 * nf["a"] * nf["b"]
        return {k: v for k, v in out.items() if np.isfinite(v)}

    def located_value(self, kind: str, point) -> float:
        if self.critical is None:
            return super().located_value(kind, point)
        return self.tests(point).get(kind, np.nan)

    def accept(self, kind, point, value, options) -> bool:
        """Curves: a zero of the double-Hopf or zero-Hopf test is the special point only if the other
        eigenvalues hold a complex pair (resp. a real eigenvalue) on the axis there, not a real pair
        s, -s (a neutral saddle) or a complex pair with s_i + s_j = 0 off the axis."""
        if self.critical is None:
            return super().accept(kind, point, value, options)
        if not np.isfinite(value):
            return False
        ev = point.eigenvalues
        others = np.delete(ev, self._critical_indices(ev))
        tol = max(options.locate_tol, REAL_TOL * max(1.0, np.abs(ev).max()))
        pair_on_axis = np.any((others.imag > tol) & (np.abs(others.real) <= tol))
        real_at_zero = np.any(np.abs(others) <= tol)
        if kind == "double_hopf" or (kind == "zero_hopf" and self.critical == "zero"):
            return bool(pair_on_axis)
        if kind == "zero_hopf" or (kind == "bogdanov_takens" and self.critical == "zero"):
            return bool(real_at_zero)
        return True

    # -- Problem interface
    def residual(self, u: np.ndarray) -> np.ndarray:
        out = self.field.values(u[: self.n], self.runtime(u))
        F = np.concatenate([out[: self.n], out[self.n:] - self.pin_targets(u)])
        if self.critical is not None:
            T1 = self._first(u)
            F = np.append(F, self._critical_row(u, T1)[0])
        return F

    def jacobian(self, u: np.ndarray) -> np.ndarray:
        T1 = self._first(u)
        A = np.hstack([T1[:, : self.n], self._parameter_columns(T1)])
        for j, p in enumerate(self.free):
            if p.pin is not None:
                A[self.n + p.pin, self.n + j] -= 1.0
        if self.critical is not None:
            A = np.vstack([A, self._critical_row(u, T1)[1]])
        return A

    def second_derivative(self, u: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        if self.critical is not None:
            raise NotImplementedError("branch switching on codimension-one curves")
        T2 = self.field.tensor(u[: self.n], self.runtime(u), 2)

        def lift(v):  # unknown-space vector -> tensor-argument vector
            arg = np.zeros(T2.shape[1])
            arg[: self.n] = v[: self.n]
            for j, derivative in enumerate(self._derivative):
                for position, coefficient in derivative:
                    arg[self.n + position] += coefficient * v[self.n + j]
            return arg

        return bilinear(T2, lift(a), lift(b))

    # -- normal forms of located points
    def family_tangent(self) -> np.ndarray | None:
        if self.family is None:
            return None
        phi0 = np.zeros(self.n)
        phi0[self.family] = self.family_sign
        return phi0

    def _nonsmooth_term(self, x, pars):
        if self.nonsmooth is None:
            return None
        G_xs, Gamma = self.nonsmooth(x, pars)
        return lambda w: (G_xs @ w) * np.linalg.norm(Gamma @ w)

    def describe(self, kind: str, u: np.ndarray) -> dict:
        """The normal-form coefficients of special point ``kind`` at ``u`` and ``smooth``: whether the field is
        smooth enough there for them (:meth:`.tensors.Field.has_kink`: no kink of the Jacobian; at a Hopf point,
        where l1 takes third derivatives, none of the second derivatives either). Of an isolated equilibrium,
        where it is not, the class is ``not_smooth`` and l1, a are 0 (not applicable). On a line of equilibria
        ``smooth`` is None: its normal forms carry the declared C^1 term (``nonsmooth``) and need no check."""
        x, pars = u[: self.n], self.runtime(u)
        orders = (1, 2) if kind == "hopf" else (1,)
        smooth = (None if self.family is not None
                  else not any(self.field.has_kink(x, pars, order, self.scale) for order in orders))
        return {**self._coefficients(kind, x, pars, smooth), "smooth": smooth}

    def _coefficients(self, kind: str, x: np.ndarray, pars: np.ndarray, smooth: bool | None) -> dict:
        n = self.n
        J = self.field.tensor(x, pars, 1, with_parameters=False)[:n]
        B = self.field.tensor(x, pars, 2, with_parameters=False)[:n]
        phi0 = self.family_tangent()
        N = self._nonsmooth_term(x, pars)
        if kind == "hopf":
            if phi0 is not None:
                nf = normal_forms.line_hopf(J, B, phi0, N)
                return {"frequency": nf["frequency"], "a": nf["a"], "b": nf["b"], "k": nf["k"], "class": nf["class"]}
            if smooth is False:
                return {"frequency": normal_forms.hopf_frequency(J), "l1": 0.0, "l1_scale": 0.0,
                        "class": "not_smooth"}
            C = self.field.tensor(x, pars, 3, with_parameters=False)[:n]
            nf = normal_forms.first_lyapunov_coefficient(J, B, C)
            return {"frequency": nf["frequency"], "l1": nf["l1"], "l1_scale": nf["scale"],
                    "class": "degenerate" if nf["degenerate"] else "supercritical" if nf["l1"] < 0 else "subcritical"}
        if kind in ("branch_point", "fold", "fold_or_bp") and phi0 is not None:
            nf = normal_forms.line_transcritical(J, B, phi0, N)
            return {"a": nf["a"], "b": nf["b"], "c": nf["c"], "k": nf["k"], "class": nf["class"],
                    "class_negative": nf["class_negative"]}
        if kind in ("fold", "fold_or_bp"):
            if smooth is False:
                return {"a": 0.0, "class": "not_smooth"}
            return {"a": normal_forms.fold_coefficient(J, B)["a"]}
        if kind == "bogdanov_takens":
            return {"jordan_block": int(_is_jordan_block(J[np.ix_(self.keep, self.keep)]))}
        return {}


def _is_jordan_block(J: np.ndarray) -> bool:
    """Whether the eigenvalue nearest 0 is a double eigenvalue with a single eigenvector (Bogdanov-Takens)."""
    vals = np.linalg.eigvals(J)
    order = np.argsort(np.abs(vals))
    scale = max(1.0, np.abs(vals).max())
    if abs(vals[order[1]]) > 1e-4 * scale:
        return False
    return np.linalg.matrix_rank(J, tol=1e-6 * scale) == J.shape[0] - 1


def _invariant_basis(J: np.ndarray, eigenvalues: np.ndarray) -> np.ndarray:
    """Orthonormal real basis of the invariant subspace of J belonging to ``eigenvalues`` (one real
    eigenvalue, or a complex-conjugate or real pair), from an ordered real Schur decomposition.

    The eigenvalues Schur selects are matched to the targets by a threshold of half the distance from
    the targets to the rest of the spectrum (robust where a pair merges into a Jordan block, whose
    eigenvalues are only determined to sqrt(eps))."""
    targets = np.asarray(eigenvalues)
    spectrum = np.linalg.eigvals(J)
    dist = np.array([np.min(np.abs(np.concatenate([targets, np.conj(targets)]) - z)) for z in spectrum])
    order = np.argsort(dist)
    dim = 1 if len(targets) == 1 else 2
    gap = dist[order[dim]] if len(spectrum) > dim else np.inf
    threshold = 0.5 * (dist[order[dim - 1]] + gap)

    def selected(re, im=0.0):
        z = complex(re, im)
        return bool(np.min(np.abs(np.concatenate([targets, np.conj(targets)]) - z)) < threshold)

    _T, Z, sdim = schur(J, output="real", sort=selected)
    if sdim != dim:
        raise np.linalg.LinAlgError(f"ordered Schur form selected {sdim} eigenvalues, not {dim}")
    return Z[:, :dim]
