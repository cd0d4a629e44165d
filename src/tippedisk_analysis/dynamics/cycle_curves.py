"""Folds of cycles (LPC) continued in two parameters by a minimally augmented collocation system (as MatCont's
and BifurcationKit's): :func:`cycle_fold_curve`, reached through :func:`.branches.special_point_curve` with a
``periodic_orbits`` dataset.

Unknowns u = (T, p, q, nodes) on a fixed collocation mesh (:mod:`.collocation`; the mesh of the start orbit,
adapted to it). Equations: the collocation rows dx/dtau - T f(x; p, q) = 0, the integral phase condition and one
scalar g(u) = 0. With A the Jacobian of (collocation, phase) with respect to (T, nodes), square, g is the last
component of the bordered solve

    [[A, b], [c^T, 0]] [v; g] = [0; 1],

zero exactly where A is singular: at a fold of cycles the orbit branch's tangent (v_x, v_T, dp = 0) is A's null
vector. The borders b, c are the left and right null vectors of A at the last accepted point (Govaerts' minimally
augmented system). Its gradient is dg = -w^T (dA) v with w from the transposed solve; the second derivatives of f
in dA v are central differences of the compiled linearisation along v at the Gauss points (they shape Newton's
steps only: the residual, and so the curve, is exact to the collocation's accuracy).

Codimension-two points: a **cusp of cycles** (CP), where the fold's normal-form coefficient changes sign and the
curve has a cusp in the (p, q) plane, is detected where the curve's direction in that plane reverses (both
parameter components of the tangent pass through zero) and located there. Not detected: the 1:1 resonance, fold-flip
and fold-Neimark-Sacker points, and the curve's end at a generalised Hopf point (the cycle shrinking to an
equilibrium); the curve's multipliers are stored, so they can be read from them.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import xarray as xr
from scipy import sparse
from scipy.sparse import linalg as sparse_linalg

from ..errors import DatasetError, ParameterError
from ..results import config_of, index_coordinate, make_attrs
from . import continuation
from .collocation import NCOL, NTST, CollocationProblem
from .collocation_solver import Factorisation, Linearisation, assemble, sparse_jacobian
from .datasets import check_system, flag_attrs, mixed_units, state_coordinates, summary, unlocated_attrs
from .discretisations import PERIOD_WEIGHT
from .orbit_base import orbit_size
from .orbit_datasets import SPECIAL_KINDS as ORBIT_KINDS
from .system import System

CURVE_KINDS = {"cusp": 0, "user": 1}
"""int8 codes of ``special_kind`` in datasets of kind ``cycle_curve``."""
FD_STEP = 1e-6  # the central difference of f_x along v: this share of the state scale
CURVE_OPTIONS = {"ds": 0.02, "ds_max": 0.2, "max_points": 300, "easy_iterations": 5}


class CycleFoldProblem(continuation.Problem):
    """The fold of cycles of ``system`` in parameters (p, q) on collocation ``mesh`` (module docstring)."""

    def __init__(self, system: System, pars, parameters, mesh, *, scales=(1.0, 1.0), period_scale: float = 1.0,
                 bounds: dict | None = None):
        self.system, self.n, self.mesh = system, system.n, mesh
        self.pars = np.array(pars, dtype=float)
        self.free = tuple(parameters)
        self.indices = tuple(system.parameter_index(name) for name in self.free)
        # the orbit problem in p alone: its phase condition and its multipliers (from the condensed blocks)
        self.base = CollocationProblem(system, self.pars, mesh=mesh, parameter=self.free[0], adapt=0,
                                       error_tol=math.inf)
        self._linearisation = system.linearisation_function(self.indices)
        self.x_start = 3
        self.names = ("T", *self.free, *(f"{s}[{g}]" for g in range(mesh.n_nodes) for s in system.state_names))
        node_scale = np.asarray(system.state_scale)[None, :] / np.sqrt(mesh.weights)[:, None]
        self.scale = np.concatenate([[period_scale], scales, node_scale.ravel()])
        self.parameters = (1, 2)
        self.bounds = {1 + self.free.index(name): tuple(b) for name, b in (bounds or {}).items()}
        self._borders = None  # (b, c) of the bordered system, set by set_reference
        self._reference = None  # (u of the last reference, its direction in the parameter plane)
        self._memo: dict = {}

    # -- unknowns
    def split(self, u) -> tuple[np.ndarray, float, np.ndarray]:
        """(node states (n_nodes, n), T, (p, q))."""
        u = np.asarray(u, dtype=float)
        return u[3:].reshape(-1, self.n), float(u[0]), u[1:3]

    def runtime(self, u) -> np.ndarray:
        pars = self.pars.copy()
        pars[list(self.indices)] = u[1:3]
        return pars

    def _base_u(self, u) -> np.ndarray:
        return np.delete(np.asarray(u, dtype=float), 2)

    # -- evaluation
    def _evaluate(self, u) -> dict:
        key = np.asarray(u, dtype=float).tobytes()
        if key not in self._memo:
            if len(self._memo) > 8:
                self._memo.pop(next(iter(self._memo)))
            self._memo[key] = self._evaluation(u)
        return self._memo[key]

    def _at_gauss(self, X, pars) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(f, f_x, f_(p, q)) at the Gauss points: (ntst, m, n), (ntst, m, n, n), (ntst, m, n, 2)."""
        n, shape = self.n, X.shape[:-1]
        lin = self.base._at_gauss_points(self._linearisation, X, pars)
        return (lin[:, :n].reshape(*shape, n), lin[:, n:n + n * n].reshape(*shape, n, n),
                lin[:, n + n * n:].reshape(*shape, n, 2))

    def _evaluation(self, u) -> dict:
        mesh, n = self.mesh, self.n
        X, T, _pq = self.split(u)
        pars = self.runtime(u)
        if not (math.isfinite(T) and T > 0) or not np.all(np.isfinite(X)):
            return {"error": "the period is not positive or a node state is not finite"}
        xz, dxz = mesh.at_gauss(X)
        f, J, fp = self._at_gauss(xz, pars)
        if not (np.all(np.isfinite(J)) and np.all(np.isfinite(fp))):
            return {"error": "the right-hand side is not finite on the orbit"}
        blocks = assemble(J, mesh.h, T, mesh.basis.at_gauss, mesh.basis.slope_at_gauss)
        rows = mesh.ntst, mesh.m * n
        extras = np.stack([-f.reshape(rows), -T * fp[..., 0].reshape(rows), -T * fp[..., 1].reshape(rows)], axis=2)
        ev = {"X": X, "T": T, "pars": pars, "xz": xz, "f": f, "J": J, "blocks": blocks, "extras": extras,
              "collocation": (dxz - T * f).ravel()}
        ev.update(self._fold_test(ev))
        return ev

    def _orbit_matrix(self, ev: dict):
        """A: the Jacobian of (collocation, phase) with respect to (T, nodes), sparse."""
        phase = np.concatenate([[0.0], self.base._phase])[None, :]
        return sparse_jacobian(ev["blocks"], ev["extras"][:, :, :1], phase, self.mesh, self.n, 1)

    def _fold_test(self, ev: dict) -> dict:
        """g, its gradient with respect to u, and the null vectors v, w of the bordered system (module docstring)."""
        A = self._orbit_matrix(ev)
        size = A.shape[0]
        if self._borders is None:
            self._borders = _null_vectors(A)
        b, c = self._borders
        M = sparse.bmat([[A, sparse.csc_matrix(b[:, None])], [sparse.csc_matrix(c[None, :]), None]], format="csc")
        rhs = np.zeros(size + 1)
        rhs[-1] = 1.0
        try:
            lu = sparse_linalg.splu(M)
        except RuntimeError:  # exactly singular: the borders miss the null space
            return {"g": math.nan, "g_row": np.full(size + 2, math.nan)}
        vg, wh = lu.solve(rhs), lu.solve(rhs, trans="T")
        v, w = vg[:-1], wh[:-1]
        return {"g": float(vg[-1]), "g_row": self._gradient(ev, v, w), "v": v, "w": w}

    def _gradient(self, ev: dict, v: np.ndarray, w: np.ndarray) -> np.ndarray:
        """dg/du = -w^T (dA/du) v; the collocation rows of A v at Gauss point k are
        (slope terms) - T f_x(x_k) v_x(z_k) - f(x_k) v_T, the phase row is constant."""
        mesh, n, T = self.mesh, self.n, ev["T"]
        v_T, V = v[0], v[1:].reshape(-1, n)
        vz = mesh.at_gauss(V)[0]  # the variation at the Gauss points (ntst, m, n)
        wz = w[: mesh.n_nodes * n].reshape(mesh.ntst, mesh.m, n)  # the collocation rows' weights
        Jv = np.einsum("jkab,jkb->jka", ev["J"], vz)
        step = FD_STEP / max(float(np.max(np.abs(vz / np.asarray(self.system.state_scale)))), 1e-300)
        _f1, J_plus, fp_plus = self._at_gauss(ev["xz"] + step * vz, ev["pars"])
        _f2, J_minus, fp_minus = self._at_gauss(ev["xz"] - step * vz, ev["pars"])
        dJ, dfp = (J_plus - J_minus) / (2 * step), (fp_plus - fp_minus) / (2 * step)  # f_xx[v, .], f_xp v
        fp = self._at_gauss(ev["xz"], ev["pars"])[2]
        row = np.zeros(3 + mesh.n_nodes * n)
        row[0] = np.sum(wz * Jv)  # -w . d(A v)/dT, d(A v)/dT = -f_x v_x
        row[1:3] = np.einsum("jka,jkap->p", wz, T * dfp + v_T * fp)
        at_x = T * np.einsum("jka,jkab->jkb", wz, dJ) + v_T * np.einsum("jka,jkab->jkb", wz, ev["J"])
        nodal = np.einsum("ki,jkb->jib", mesh.basis.at_gauss, at_x)  # Gauss points to the interval's nodes
        grad = np.zeros((mesh.n_nodes, n))
        np.add.at(grad, mesh.intervals, nodal)
        row[3:] = grad.ravel()
        return row

    # -- the continuation problem
    def residual(self, u) -> np.ndarray:
        ev = self._evaluate(u)
        if "error" in ev:
            return np.full(self.mesh.n_nodes * self.n + 2, math.nan)
        return np.concatenate([ev["collocation"], [self.base._phase @ ev["X"].ravel()], [ev["g"]]])

    def _border_rows(self, ev: dict) -> np.ndarray:
        phase = np.concatenate([np.zeros(3), self.base._phase])
        return np.vstack([phase, ev["g_row"]])

    def linearise(self, u, scale, row=None) -> Linearisation:
        ev = self._evaluate(u)
        scale = np.asarray(scale, dtype=float)
        if "error" in ev or not np.all(np.isfinite(ev["g_row"])):
            return Linearisation(None, None, None, scale, 3, self.mesh, self.n)
        borders = self._border_rows(ev) if row is None else np.vstack([self._border_rows(ev), row / scale])
        return Linearisation(ev["blocks"], ev["extras"], borders, scale, 3, self.mesh, self.n)

    def jacobian(self, u):
        """The Jacobian as a scipy sparse matrix (for inspection)."""
        ev = self._evaluate(u)
        return sparse_jacobian(ev["blocks"], ev["extras"], self._border_rows(ev), self.mesh, self.n, 3)

    def set_reference(self, u) -> None:
        """The phase condition relative to the orbit u and the borders from the null vectors at u."""
        self.base.set_reference(self._base_u(u))
        self._memo.clear()
        ev = self._evaluate(u)
        if "v" in ev:
            self._borders = (ev["w"] / np.linalg.norm(ev["w"]), ev["v"] / np.linalg.norm(ev["v"]))
            self._memo.clear()
        self._reference = (np.asarray(u, dtype=float).tobytes(), None)

    # -- multipliers and codimension-two points
    def multipliers(self, u) -> tuple:
        """(multipliers by modulus, flow direction's mask, its |mu - 1|, status) from the condensed blocks."""
        ev = self._evaluate(u)
        if "error" in ev:
            return np.full(self.n, complex(math.nan)), np.zeros(self.n, bool), math.nan, ev["error"]
        condensed = Factorisation(ev["blocks"], ev["extras"], np.zeros((0, self.mesh.n_nodes, self.n)),
                                  np.zeros((0, 3)), self.mesh.m).condensed
        mu, _trivial, flow, flow_error, status, _message = self.base._multipliers(
            {"condensed": condensed, "f0": self.system.f(ev["X"][0], ev["pars"])})
        return mu, flow, flow_error, status

    def state_eigenvalues(self, u) -> np.ndarray:
        mu, flow = self.multipliers(u)[:2]
        rest = mu[~flow] if flow.any() else np.full(self.n - 1, complex(math.nan))
        return rest[np.argsort(-rest.real, kind="stable")]

    def _direction(self, point) -> float:
        """The parameter-plane part of the tangent along the reference's: negative where the curve has reversed
        in the (p, q) plane (a cusp). The reference is the direction at the last accepted point, taken when the
        core first tests that point."""
        t = point.tangent[1:3] * self.scale[1:3]
        key, ref = self._reference or (None, None)
        if ref is None:
            ref = t / max(np.linalg.norm(t), 1e-300)
            if point.u.tobytes() == key:
                self._reference = (key, ref)
        return float(t @ ref)

    def tests(self, point) -> dict:
        return {"cusp": self._direction(point)}

    def located_value(self, kind: str, point) -> float:
        return self._direction(point)

    def accept(self, kind, point, value, options) -> bool:
        return True

    def describe(self, kind: str, u) -> dict:
        return {"period": self.split(u)[1]}


def _null_vectors(A) -> tuple[np.ndarray, np.ndarray]:
    """(left, right) unit null vectors of a nearly singular sparse A by two steps of inverse iteration."""
    lu = sparse_linalg.splu(A.tocsc())
    rng = np.random.default_rng(1)
    pair = []
    for trans in ("T", "N"):
        x = rng.normal(size=A.shape[0])
        for _ in range(2):
            x = lu.solve(x / np.linalg.norm(x), trans=trans)
        pair.append(x / np.linalg.norm(x))
    return pair[0], pair[1]


def _fold_start(system: System, branch: xr.Dataset, label: str) -> tuple[int, np.ndarray, float, np.ndarray]:
    """(index, x(0), period, runtime parameters) of the fold of cycles ``label`` of an orbit branch."""
    check_system(branch, system)
    labels = [str(v) for v in branch["special_label"].values]
    if label not in labels:
        raise ParameterError(f"no special point {label!r} in the orbit branch; it has {', '.join(labels) or 'none'}")
    k = labels.index(label)
    kind = list(ORBIT_KINDS)[list(ORBIT_KINDS.values()).index(int(branch["special_kind"].values[k]))]
    if kind != "fold":
        raise ParameterError(f"{label} is a {kind} point; curves of cycles start at a fold of cycles (LP)")
    index = int(branch["special_index"].values[k])
    pars = np.asarray(system.pars, dtype=float).copy()
    stored = branch["runtime_parameters"].values[index]
    pars[: len(stored)] = stored
    return index, branch["initial_state"].values[index].astype(float), float(branch["period"].values[index]), pars


def cycle_fold_curve(system: System, branch: xr.Dataset, label: str, parameters, *, bounds: dict,
                     scales: dict | None = None, ntst: int | None = None, ncol: int | None = None, marks=(),
                     options: continuation.Options | None = None, **option_keywords) -> xr.Dataset:
    """The curve of folds of cycles through ``label`` (an LP of ``branch``, a ``periodic_orbits`` dataset of
    collocation orbits of ``system``) in the two ``parameters`` (p, q), both ways within ``bounds`` {name: (low,
    high)}, with its cusps of cycles; ``ntst``, ``ncol``: the mesh (default the fold's orbit's; the mesh is adapted
    to that orbit and then fixed); ``marks``: values of the first parameter where the curve's points are computed
    exactly (user points UZ1, ...); ``options`` or its fields as keywords (ds, ds_max, max_points, ...). A dataset of
    kind ``cycle_curve``."""
    if branch.attrs.get("kind") != "periodic_orbits":
        raise DatasetError(f"the dataset is of kind {branch.attrs.get('kind')!r}; give a periodic_orbits dataset")
    parameters = list(parameters)
    if len(parameters) != 2 or len(set(parameters)) != 2:
        raise ParameterError(f"give two different parameters for a curve, not {parameters}")
    if branch.attrs.get("parameter") not in parameters:
        raise ParameterError(f"the branch was continued in {branch.attrs.get('parameter')!r}: make it one of the "
                             f"curve's parameters {parameters}")
    index, state, period, pars = _fold_start(system, branch, label)
    config = config_of(branch)
    ntst = ntst or (int(branch["ntst"].values[index]) if "ntst" in branch else config.get("ntst", NTST))
    ncol = ncol or int(config.get("ncol", NCOL))
    orbit = CollocationProblem(system, pars, ntst=ntst, ncol=ncol, parameter=parameters[0])
    X = orbit.split(orbit.unknowns(state, period))[0]  # the integrated orbit on a mesh adapted to it
    scales = dict(scales or {})
    prob = CycleFoldProblem(system, pars, parameters, orbit.mesh, scales=[scales.get(p, 1.0) for p in parameters],
                            period_scale=PERIOD_WEIGHT * period, bounds=bounds)
    u0 = np.concatenate([[period], pars[list(prob.indices)], X.ravel()])
    if options is not None and option_keywords:
        raise ParameterError("give either options=Options(...) or the option keywords (ds, ds_max, ...), not both")
    opts = options or continuation.Options(**(CURVE_OPTIONS | option_keywords))
    prob.set_reference(u0)
    u0 = continuation.solve_at(prob, u0, 2, u0[2], opts)
    if u0 is None:
        raise ParameterError(f"no fold of cycles found next to {label} at the fixed {parameters[1]}: raise ntst")
    br = continuation.continue_both_ways(prob, u0, opts, marks=marks)
    return curve_dataset(prob, br, {"source_label": label, "parameters": parameters, "ntst": prob.mesh.ntst,
                                    "ncol": prob.mesh.m})


def curve_dataset(prob: CycleFoldProblem, br: continuation.Branch, info: dict) -> xr.Dataset:
    """A curve of folds of cycles as a dataset of kind ``cycle_curve``: p, q, the period, x(0), the amplitude,
    the multipliers, the fold test g and the special points."""
    system = prob.system
    u = br.array("u")
    p, q = prob.free
    spectra = [prob.multipliers(ui) for ui in u]
    mu = np.array([s[0] for s in spectra])
    ok = np.isfinite(mu)
    scale = np.asarray(system.state_scale)
    data = {
        p: ("point", u[:, 1], {"units": system.units_of(p), "long_name": f"parameter {p}"}),
        q: ("point", u[:, 2], {"units": system.units_of(q), "long_name": f"parameter {q}"}),
        "period": ("point", u[:, 0], {"units": system.time_units, "long_name": "period T of the fold's cycle"}),
        "initial_state": (("point", "state"), u[:, 3:3 + prob.n], mixed_units("x_0: the orbit's first node")),
        "amplitude": ("point", np.array([orbit_size(prob.split(ui)[0], scale) for ui in u]),
                      {"units": "1", "long_name": "largest distance of the nodes from their mean, in scaled states"}),
        "multiplier_real": (("point", "floquet"), np.where(ok, mu.real, 0.0),
                            {"units": "1", "long_name": "Floquet multipliers by modulus (two are 1 on the curve), "
                                                        "real part"}),
        "multiplier_imag": (("point", "floquet"), np.where(ok, mu.imag, 0.0),
                            {"units": "1", "long_name": "Floquet multipliers, imaginary part"}),
        "multipliers_computed": ("point", np.all(ok, axis=1).astype(np.int8),
                                 flag_attrs("whether the multipliers were computed (no: a singular condensed "
                                            "block, stored as 0)", {"no": 0, "yes": 1})),
        "fold_test": ("point", np.array([prob._evaluate(ui)["g"] for ui in u]),
                      {"units": "1", "long_name": "g of the bordered collocation system (zero on the curve)"}),
        "arclength": ("point", br.array("arclength"), {"units": "1", "long_name": "pseudo-arclength"}),
        "special_kind": ("special_point", np.array([CURVE_KINDS[sp.kind] for sp in br.special_points], np.int8),
                         flag_attrs("type of the special point", CURVE_KINDS)),
        "special_label": ("special_point", np.array([sp.label for sp in br.special_points], dtype=str),
                          {"long_name": "label: CP cusp of cycles, UZ user point (marks)"}),
        "special_index": ("special_point", np.array([sp.index for sp in br.special_points], np.int32),
                          {"units": "1", "long_name": "index along dim point"}),
    }
    ds = xr.Dataset(data, coords={"point": index_coordinate("point", len(u), "point along the curve"),
                                  "floquet": index_coordinate("floquet", prob.n, "multiplier index"),
                                  **state_coordinates(system),
                                  "special_point": index_coordinate("special_point", len(br.special_points),
                                                                    "special point")})
    labels = summary([f"{sp.label} at {p} = {sp.u[1]:.8g}, {q} = {sp.u[2]:.8g}" for sp in br.special_points])
    config = {"system": system.name, "system_key": system.key, **info, "pars": list(map(float, prob.pars)),
              "bounds": {prob.names[i]: list(b) for i, b in prob.bounds.items()},
              "options": dataclasses.asdict(br.options)}
    ds.attrs = make_attrs("cycle_curve", config, br.status,
                          f"{system.name}: curve of folds of cycles, {len(u)} points; {br.message}"
                          + (f"; {labels}" if labels else ""), **system.attrs(prob.pars), parameters=f"{p} {q}",
                          critical="fold_of_cycles", labels=" ".join(sp.label for sp in br.special_points),
                          **unlocated_attrs(br))
    return ds
