"""Cycle bifurcations continued in two parameters by minimally augmented collocation systems (as MatCont's and
BifurcationKit's): folds of cycles (LPC), period doublings (PD) and Neimark-Sacker points (NS), through
:func:`cycle_curve`, reached by :func:`.branches.special_point_curve` with a ``periodic_orbits`` dataset.

Unknowns u = (T, p, q[, theta], nodes) on a fixed collocation mesh (:mod:`.collocation`; the mesh of the start
orbit, adapted to it). Equations: the collocation rows dx/dtau - T f(x; p, q) = 0, the integral phase condition and
the test function g(u) = 0 of :mod:`.cycle_bordered` (one real equation for LPC and PD; for NS g is complex, two
equations, and the angle theta of the critical multipliers e^(+-i theta) is the extra unknown).

Codimension-two points, from the curve's multipliers (the trivial and the critical ones set aside; the others,
"the rest", from the condensed blocks by periodic QR) and theta:

* on LPC curves: a **cusp of cycles** (CP), where the curve's direction in the (p, q) plane reverses (both parameter
  components of the tangent pass through zero); **fold-flip** (LPPD), one of the rest through -1; **fold-Neimark-
  Sacker** (LPNS), a complex pair of the rest through the unit circle;
* on PD curves: the **1:2 resonance** (R2), one of the rest through -1; **fold-flip** (LPPD), one through +1;
  **flip-Neimark-Sacker** (PDNS), a complex pair through the circle;
* on NS curves: the **strong resonances** R1 to R4 where theta passes 2 pi / q (q = 1 .. 4; the curve ends at R1
  and R2, where the pair becomes real and the curve folds back onto itself with the conjugate multiplier); LPNS,
  PDNS and the **double Neimark-Sacker** point (NSNS) from the rest as above.

Not detected: the generalised period doubling (GPD) and the Chenciner point (their normal-form coefficients are not
computed), the 1:1 resonance on an LPC curve and the curve's end at a generalised Hopf point (the cycle shrinking
to an equilibrium); the stored multipliers show them.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import xarray as xr

from ..errors import DatasetError, ParameterError
from ..results import config_of, index_coordinate, make_attrs
from . import continuation
from .collocation import NCOL, NTST, CollocationProblem
from .collocation_floquet import signed_distance
from .collocation_solver import Factorisation, Linearisation, assemble, sparse_jacobian
from .cycle_bordered import CRITICAL, BorderedTest
from .datasets import check_system, flag_attrs, mixed_units, state_coordinates, summary, unlocated_attrs
from .discretisations import PERIOD_WEIGHT
from .orbit_base import orbit_size
from .orbit_datasets import SPECIAL_KINDS as ORBIT_KINDS
from .system import System

CURVE_LABELS = {"cusp": "CP", "user": "UZ", "fold_flip": "LPPD", "fold_neimark_sacker": "LPNS",
                "flip_neimark_sacker": "PDNS", "double_neimark_sacker": "NSNS", "resonance_1_1": "R1",
                "resonance_1_2": "R2", "resonance_1_3": "R3", "resonance_1_4": "R4"}
CURVE_KINDS = {kind: code for code, kind in enumerate(CURVE_LABELS)}
"""int8 codes of ``special_kind`` in datasets of kind ``cycle_curve``."""
CURVE_OPTIONS = {"ds": 0.02, "ds_max": 0.2, "max_points": 300, "easy_iterations": 5}
NAMES = {"fold": "folds of cycles", "period_doubling": "period doublings", "neimark_sacker": "Neimark-Sacker points"}
PAIR_KINDS = ("fold_neimark_sacker", "flip_neimark_sacker", "double_neimark_sacker")  # a complex pair on the circle
CUSP_SHARE = 1e-3  # a located cusp's tangent in the parameter plane: at most this share of the reference's
COMPLEX_PAIR = 1e-6  # |Im mu| of a pair of the rest that counts as complex at a located LPNS, PDNS or NSNS


class CycleCurveProblem(continuation.Problem):
    """The curve of ``critical`` cycle bifurcations (:data:`.cycle_bordered.CRITICAL`) of ``system`` in parameters
    (p, q) on collocation ``mesh`` (module docstring)."""

    def __init__(self, system: System, pars, parameters, mesh, *, critical: str = "fold", scales=(1.0, 1.0),
                 period_scale: float = 1.0, bounds: dict | None = None):
        self.system, self.n, self.mesh, self.critical = system, system.n, mesh, critical
        self.pars = np.array(pars, dtype=float)
        self.free = tuple(parameters)
        self.indices = tuple(system.parameter_index(name) for name in self.free)
        # the orbit problem in p alone: its phase condition and its multipliers (from the condensed blocks)
        self.base = CollocationProblem(system, self.pars, mesh=mesh, parameter=self.free[0], adapt=0,
                                       error_tol=math.inf)
        self._linearisation = system.linearisation_function(self.indices)
        angle = ("theta",) if critical == "neimark_sacker" else ()
        self.x_start = 3 + len(angle)
        self.names = ("T", *self.free, *angle,
                      *(f"{s}[{g}]" for g in range(mesh.n_nodes) for s in system.state_names))
        node_scale = np.asarray(system.state_scale)[None, :] / np.sqrt(mesh.weights)[:, None]
        self.scale = np.concatenate([[period_scale], scales, np.ones(len(angle)), node_scale.ravel()])
        self.parameters = (1, 2)
        self.bounds = {1 + self.free.index(name): tuple(b) for name, b in (bounds or {}).items()}
        self.terminal = frozenset({"resonance_1_1", "resonance_1_2"} if angle else ())
        self.test = BorderedTest(self, critical)
        self._reference = None  # (u of the last reference, its direction in the parameter plane)
        self._plane_size: dict = {}  # {u of the reference: the size of its tangent's parameter-plane part}
        self._memo: dict = {}

    # -- unknowns
    def split(self, u) -> tuple[np.ndarray, float, np.ndarray]:
        """(node states (n_nodes, n), T, (p, q))."""
        u = np.asarray(u, dtype=float)
        return u[self.x_start:].reshape(-1, self.n), float(u[0]), u[1:3]

    def theta(self, u) -> float:
        """The angle of the critical multiplier: theta (NS), pi (PD), 0 (LPC)."""
        return float(u[3]) if self.critical == "neimark_sacker" else (math.pi if self.critical == "period_doubling"
                                                                       else 0.0)

    def runtime(self, u) -> np.ndarray:
        pars = self.pars.copy()
        pars[list(self.indices)] = u[1:3]
        return pars

    def _base_u(self, u) -> np.ndarray:
        return np.delete(np.asarray(u, dtype=float), range(2, self.x_start))

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
        columns = [-f.reshape(rows), -T * fp[..., 0].reshape(rows), -T * fp[..., 1].reshape(rows)]
        columns += [np.zeros(rows)] * (self.x_start - 3)  # theta is not in the collocation rows
        ev = {"X": X, "T": T, "pars": pars, "xz": xz, "f": f, "J": J, "blocks": blocks,
              "extras": np.stack(columns, axis=2), "collocation": (dxz - T * f).ravel()}
        ev.update(self.test.evaluate(ev, self.theta(u)))
        return ev

    def _g_values(self, ev: dict) -> np.ndarray:
        """The test function's real equations: Re g (LPC, PD), or Re g and Im g (NS)."""
        g = ev["g"]
        return np.array([g.real, g.imag]) if self.critical == "neimark_sacker" else np.array([g.real])

    def _g_rows(self, ev: dict) -> np.ndarray:
        row = ev["g_row"]
        return np.vstack([row.real, row.imag]) if self.critical == "neimark_sacker" else row.real[None, :]

    # -- the continuation problem
    def residual(self, u) -> np.ndarray:
        ev = self._evaluate(u)
        if "error" in ev:
            return np.full(self.mesh.n_nodes * self.n + self.x_start - 1, math.nan)
        return np.concatenate([ev["collocation"], [self.base._phase @ ev["X"].ravel()], self._g_values(ev)])

    def _border_rows(self, ev: dict) -> np.ndarray:
        phase = np.concatenate([np.zeros(self.x_start), self.base._phase])
        return np.vstack([phase, self._g_rows(ev)])

    def linearise(self, u, scale, row=None) -> Linearisation:
        ev = self._evaluate(u)
        scale = np.asarray(scale, dtype=float)
        if "error" in ev or not np.all(np.isfinite(ev["g_row"])):
            return Linearisation(None, None, None, scale, self.x_start, self.mesh, self.n)
        borders = self._border_rows(ev) if row is None else np.vstack([self._border_rows(ev), row / scale])
        return Linearisation(ev["blocks"], ev["extras"], borders, scale, self.x_start, self.mesh, self.n)

    def jacobian(self, u):
        """The Jacobian as a scipy sparse matrix (for inspection)."""
        ev = self._evaluate(u)
        return sparse_jacobian(ev["blocks"], ev["extras"], self._border_rows(ev), self.mesh, self.n, self.x_start)

    def set_reference(self, u) -> None:
        """The phase condition relative to the orbit u and the borders from the null vectors at u."""
        self.base.set_reference(self._base_u(u))
        self._memo.clear()
        self.test.set_borders(self._evaluate(u))
        self._memo.clear()
        self._reference = (np.asarray(u, dtype=float).tobytes(), None)

    # -- multipliers and codimension-two points
    def multipliers(self, u) -> tuple:
        """(multipliers by modulus, flow direction's mask, its |mu - 1|, status) from the condensed blocks."""
        ev = self._evaluate(u)
        if "error" in ev:
            return np.full(self.n, complex(math.nan)), np.zeros(self.n, bool), math.nan, ev["error"]
        condensed = Factorisation(ev["blocks"], ev["extras"][:, :, :1], np.zeros((0, self.mesh.n_nodes, self.n)),
                                  np.zeros((0, 1)), self.mesh.m).condensed
        mu, _trivial, flow, flow_error, status, _message = self.base._multipliers(
            {"condensed": condensed, "f0": self.system.f(ev["X"][0], ev["pars"])})
        return mu, flow, flow_error, status

    def state_eigenvalues(self, u) -> np.ndarray:
        mu, flow = self.multipliers(u)[:2]
        rest = mu[~flow] if flow.any() else np.full(self.n - 1, complex(math.nan))
        return rest[np.argsort(-rest.real, kind="stable")]

    def rest(self, point) -> np.ndarray:
        """The nontrivial multipliers but the critical ones (the one nearest 1 for LPC, nearest -1 for PD, the
        pair nearest e^(+-i theta) for NS)."""
        mu = np.asarray(point.eigenvalues, dtype=complex)
        theta = self.theta(point.u)
        for target in ((1.0,) if self.critical == "fold" else (-1.0,) if self.critical == "period_doubling"
                       else (complex(math.cos(theta), math.sin(theta)), complex(math.cos(theta), -math.sin(theta)))):
            if mu.size:
                mu = np.delete(mu, int(np.argmin(np.abs(mu - target))))
        return mu

    def _direction(self, point) -> float:
        """The parameter-plane part of the tangent (in the parameters over their ``scales``) along the
        reference's: negative where the curve has reversed in the (p, q) plane (a cusp). The reference is the
        direction at the last accepted point, taken when the core first tests that point."""
        t = point.tangent[1:3]
        key, ref = self._reference or (None, None)
        if ref is None:
            ref = t / max(np.linalg.norm(t), 1e-300)
            if point.u.tobytes() == key:
                self._reference = (key, ref)
                self._plane_size = {key: float(np.linalg.norm(t))}
        return float(t @ ref)

    def tests(self, point) -> dict:
        rest = self.rest(point)
        i, j = np.triu_indices(len(rest), 1)
        plus, minus, circle = (signed_distance(values) for values in (rest - 1.0, rest + 1.0, rest[i] * rest[j] - 1.0))
        if self.critical == "fold":
            return {"cusp": self._direction(point), "fold_flip": minus, "fold_neimark_sacker": circle}
        if self.critical == "period_doubling":
            return {"resonance_1_2": minus, "fold_flip": plus, "flip_neimark_sacker": circle}
        theta = self.theta(point.u)
        return {"resonance_1_1": math.sin(theta / 2), "resonance_1_2": math.cos(theta / 2),
                "resonance_1_3": math.cos(theta) + 0.5, "resonance_1_4": math.cos(theta),
                "fold_neimark_sacker": plus, "flip_neimark_sacker": minus, "double_neimark_sacker": circle}

    def located_value(self, kind: str, point) -> float:
        return self._direction(point) if kind == "cusp" else self.tests(point)[kind]

    def accept(self, kind, point, value, options) -> bool:
        """A located cusp needs the tangent's whole parameter-plane part to vanish there (CUSP_SHARE of the
        reference's; a turn in one parameter alone reverses the direction too where that parameter dominates it).
        A located LPNS, PDNS or NSNS needs a complex pair of the rest on the unit circle (a real pair mu, 1/mu is
        a neutral saddle, no bifurcation)."""
        if kind == "cusp":
            key = (self._reference or (None,))[0]
            size = self._plane_size.get(key, math.inf)
            return bool(np.linalg.norm(point.tangent[1:3]) <= CUSP_SHARE * size)
        if kind in PAIR_KINDS:
            return bool(np.any(np.abs(self.rest(point).imag) > COMPLEX_PAIR))
        return True

    def describe(self, kind: str, u) -> dict:
        return {"period": self.split(u)[1], "theta": self.theta(u)}


def _start(system: System, branch: xr.Dataset, label: str) -> tuple:
    """(critical kind, index, x(0), period, runtime parameters, theta) of the special point ``label`` of an orbit
    branch: a fold of cycles, period doubling or Neimark-Sacker point."""
    check_system(branch, system)
    labels = [str(v) for v in branch["special_label"].values]
    if label not in labels:
        raise ParameterError(f"no special point {label!r} in the orbit branch; it has {', '.join(labels) or 'none'}")
    k = labels.index(label)
    kind = list(ORBIT_KINDS)[list(ORBIT_KINDS.values()).index(int(branch["special_kind"].values[k]))]
    if kind not in CRITICAL:
        raise ParameterError(f"{label} is a {kind} point; curves of cycles start at a fold of cycles (LP), a period "
                             "doubling (PD) or a Neimark-Sacker point (NS)")
    index = int(branch["special_index"].values[k])
    pars = np.asarray(system.pars, dtype=float).copy()
    stored = branch["runtime_parameters"].values[index]
    pars[: len(stored)] = stored
    theta = float(branch["special_angle"].values[k]) if kind == "neimark_sacker" else math.nan
    return (kind, index, branch["initial_state"].values[index].astype(float), float(branch["period"].values[index]),
            pars, theta)


def cycle_curve(system: System, branch: xr.Dataset, label: str, parameters, *, bounds: dict,
                scales: dict | None = None, ntst: int | None = None, ncol: int | None = None, marks=(),
                options: continuation.Options | None = None, **option_keywords) -> xr.Dataset:
    """The curve of cycle bifurcations through ``label`` (an LP, PD or NS point of ``branch``, a ``periodic_orbits``
    dataset of collocation orbits of ``system``) in the two ``parameters`` (p, q), both ways within ``bounds``
    {name: (low, high)}, with its codimension-two points (module docstring); ``ntst``, ``ncol``: the mesh (default
    the start orbit's; the mesh is adapted to that orbit and then fixed); ``marks``: values of the first parameter
    where the curve's points are computed exactly (user points UZ1, ...); ``options`` or its fields as keywords (ds,
    ds_max, max_points, ...). A dataset of kind ``cycle_curve``."""
    if branch.attrs.get("kind") != "periodic_orbits":
        raise DatasetError(f"the dataset is of kind {branch.attrs.get('kind')!r}; give a periodic_orbits dataset")
    parameters = list(parameters)
    if len(parameters) != 2 or len(set(parameters)) != 2:
        raise ParameterError(f"give two different parameters for a curve, not {parameters}")
    if branch.attrs.get("parameter") not in parameters:
        raise ParameterError(f"the branch was continued in {branch.attrs.get('parameter')!r}: make it one of the "
                             f"curve's parameters {parameters}")
    critical, index, state, period, pars, theta = _start(system, branch, label)
    config = config_of(branch)
    ntst = ntst or (int(branch["ntst"].values[index]) if "ntst" in branch else config.get("ntst", NTST))
    ncol = ncol or int(config.get("ncol", NCOL))
    orbit = CollocationProblem(system, pars, ntst=ntst, ncol=ncol, parameter=parameters[0])
    X = orbit.split(orbit.unknowns(state, period))[0]  # the integrated orbit on a mesh adapted to it
    scales = dict(scales or {})
    prob = CycleCurveProblem(system, pars, parameters, orbit.mesh, critical=critical,
                             scales=[scales.get(p, 1.0) for p in parameters], period_scale=PERIOD_WEIGHT * period,
                             bounds=bounds)
    u0 = np.concatenate([[period], pars[list(prob.indices)], [theta] if critical == "neimark_sacker" else [],
                         X.ravel()])
    if options is not None and option_keywords:
        raise ParameterError("give either options=Options(...) or the option keywords (ds, ds_max, ...), not both")
    opts = options or continuation.Options(**(CURVE_OPTIONS | option_keywords))
    prob.set_reference(u0)
    u0 = continuation.solve_at(prob, u0, 2, u0[2], opts)
    if u0 is None:
        raise ParameterError(f"no {NAMES[critical][:-1]} found next to {label} at the fixed {parameters[1]}: raise "
                             "ntst")
    br = continuation.continue_both_ways(prob, u0, opts, marks=marks)
    counts: dict = {}
    for sp in br.special_points:  # the curves' own labels (CP1, LPPD1, R3_1, ...)
        counts[sp.kind] = counts.get(sp.kind, 0) + 1
        prefix = CURVE_LABELS[sp.kind]
        sp.label = prefix + ("_" if prefix[-1].isdigit() else "") + str(counts[sp.kind])
    return curve_dataset(prob, br, {"source_label": label, "parameters": parameters, "ntst": prob.mesh.ntst,
                                    "ncol": prob.mesh.m})


def curve_dataset(prob: CycleCurveProblem, br: continuation.Branch, info: dict) -> xr.Dataset:
    """A curve of cycle bifurcations as a dataset of kind ``cycle_curve``: p, q, the period, the critical angle
    theta, x(0), the amplitude, the multipliers, the test g and the special points."""
    system = prob.system
    u = br.array("u")
    p, q = prob.free
    spectra = [prob.multipliers(ui) for ui in u]
    mu = np.array([s[0] for s in spectra])
    ok = np.isfinite(mu)
    scale = np.asarray(system.state_scale)
    x0 = prob.x_start
    data = {
        p: ("point", u[:, 1], {"units": system.units_of(p), "long_name": f"parameter {p}"}),
        q: ("point", u[:, 2], {"units": system.units_of(q), "long_name": f"parameter {q}"}),
        "period": ("point", u[:, 0], {"units": system.time_units, "long_name": "period T of the critical cycle"}),
        "theta": ("point", np.array([prob.theta(ui) for ui in u]),
                  {"units": "rad", "long_name": "angle of the critical multiplier e^(i theta): 0 LPC, pi PD"}),
        "initial_state": (("point", "state"), u[:, x0:x0 + prob.n], mixed_units("x_0: the orbit's first node")),
        "amplitude": ("point", np.array([orbit_size(prob.split(ui)[0], scale) for ui in u]),
                      {"units": "1", "long_name": "largest distance of the nodes from their mean, in scaled states"}),
        "discretisation_error": ("point", np.array([prob.mesh.error_estimate(prob.split(ui)[0], scale) for ui in u]),
                                 {"units": "1", "long_name": "estimated error of x(t) / state_scale on the curve's "
                                                             "fixed mesh (raise ntst where it grows)"}),
        "multiplier_real": (("point", "floquet"), np.where(ok, mu.real, 0.0),
                            {"units": "1", "long_name": "Floquet multipliers by modulus (the trivial one and the "
                                                        "critical ones on the circle), real part"}),
        "multiplier_imag": (("point", "floquet"), np.where(ok, mu.imag, 0.0),
                            {"units": "1", "long_name": "Floquet multipliers, imaginary part"}),
        "multipliers_computed": ("point", np.all(ok, axis=1).astype(np.int8),
                                 flag_attrs("whether the multipliers were computed (no: a singular condensed "
                                            "block, stored as 0)", {"no": 0, "yes": 1})),
        "fold_test": ("point", np.array([abs(prob._evaluate(ui)["g"]) for ui in u]),
                      {"units": "1", "long_name": "|g| of the bordered collocation system (zero on the curve)"}),
        "arclength": ("point", br.array("arclength"), {"units": "1", "long_name": "pseudo-arclength"}),
        "special_kind": ("special_point", np.array([CURVE_KINDS[sp.kind] for sp in br.special_points], np.int8),
                         flag_attrs("type of the special point", CURVE_KINDS)),
        "special_label": ("special_point", np.array([sp.label for sp in br.special_points], dtype=str),
                          {"long_name": "label: CP cusp of cycles, R1-R4 strong resonances, LPPD fold-flip, LPNS "
                                        "fold-Neimark-Sacker, PDNS flip-Neimark-Sacker, NSNS double Neimark-Sacker, "
                                        "UZ user point (marks)"}),
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
                          f"{system.name}: curve of {NAMES[prob.critical]}, {len(u)} points; {br.message}"
                          + (f"; {labels}" if labels else ""), **system.attrs(prob.pars), parameters=f"{p} {q}",
                          critical="fold_of_cycles" if prob.critical == "fold" else prob.critical,
                          labels=" ".join(sp.label for sp in br.special_points), **unlocated_attrs(br))
    return ds
