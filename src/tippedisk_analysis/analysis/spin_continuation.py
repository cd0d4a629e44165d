"""Continuation of the tippedisk's spinning solutions: branches of equilibria of the reduced
system (:mod:`.reduced`) in any parameter, and curves of their Hopf and zero-eigenvalue points
in two parameters, as datasets of kind ``"continuation"``.

Continuation parameters (:data:`PARAMETERS`): ``omega`` (the spin rate alpha_dot = Omega, a pin
of the family of relative equilibria), ``eps``, ``mu``, ``e`` (A, B, C about G held fixed, as in
the stability maps) and ``inertia`` (a common scale of A, B, C: 1 is Table 2).

The two families (Fig. 6) are lines of equilibria: the reduced Jacobian has the structural zero
of the family direction d x*/d Omega = sign e_omega_x at every member (:mod:`.stability`). The
residual [rhs, alpha_dot - Omega] therefore has dependent rows; the continuation core takes
Gauss-Newton steps, the state Jacobian for the test functions is the deflated one, and the
normal forms at special points are those of bifurcations from a line of equilibria without
parameters of a C^1 field (:mod:`.normal_forms`; the C^1 term comes from |gamma_T| in (2.29),
:func:`.reduced.nonsmooth_split`): hyperbolic, elliptic, or a repelling / attracting node; no
periodic orbits are born at the Hopf points and no branch of other equilibria at the zero-eigenvalue
points (docs/continuation.md).
"""

from __future__ import annotations

import dataclasses
import math

import heyoka as hy
import numpy as np
import xarray as xr

from ..defaults import SLIP_SMOOTHING
from ..dynamics import continuation
from ..dynamics.datasets import continuation_dataset, special_point
from ..dynamics.equilibria import EquilibriumProblem, Parameter
from ..errors import ParameterError
from ..models import ode
from ..models.reduced import STATE_SCALE
from ..parameters import Setup, to_dict
from ..results import config_of
from . import reduced
from . import stationary as st

__all__ = ["continue_branch", "continue_curve", "continue_from_point"]

PARAMETERS = {  # name: (units, long_name, scale of the arclength metric, default bounds of curves)
    "omega": ("rad s-1", "spin rate alpha_dot = Omega", 10.0, (0.0, 200.0)),
    "eps": ("m s-1", "smoothing velocity eps of (2.29)", 0.1, (1e-3, 1.0)),
    "mu": ("1", "friction coefficient mu (2.29)", 0.1, (0.0, 2.0)),
    "e": ("m", "eccentricity e (A, B, C about G held fixed)", 1e-3, (0.0, 0.01)),
    "inertia": ("1", "common scale of the inertia A, B, C about G (1: Table 2)", 1.0, (0.5, 2.0)),
}
CLASSES = {"": 0, "elliptic": 1, "hyperbolic": 2, "repelling_node": 3, "attracting_node": 4, "supercritical": 5,
           "subcritical": 6, "degenerate": 7}


def _parameter(name: str, setup: Setup) -> Parameter:
    if name not in PARAMETERS:
        raise ParameterError(f"unknown continuation parameter {name!r}; choose one of {', '.join(PARAMETERS)}")
    scale = PARAMETERS[name][2]
    if name in ("e", "inertia") and setup.disk.geometry is not None:
        raise ParameterError(f"a continuation in {name} holds A, B, C about G fixed or scales them, which a drilled "
                             "disk's geometry does not allow (its hole fixes them); give the disk by its values "
                             "(Disk(m, e, r, A, B, C); --disk given or table2)")
    if name == "omega":
        return Parameter(name, scale, pin=0)  # the pinned observable alpha_dot
    if name == "inertia":
        d = setup.disk
        return Parameter(name, scale, runtime=tuple((ode.PARAMETER_NAMES.index(k), v) for k, v in
                                                    (("A", d.A), ("B", d.B), ("C", d.C))))
    return Parameter(name, scale, runtime=((ode.PARAMETER_NAMES.index(name), 1.0),))


def base_value(name: str, setup: Setup) -> float:
    """The value of a continuation parameter in ``setup`` (omega has none: give it)."""
    return {"eps": setup.friction.eps, "mu": setup.friction.mu, "e": setup.disk.e, "inertia": 1.0}[name]


def _onto_family(branch: str):
    """Projection onto the closed-form family of ``branch``: x = x*(Omega) (stationary_state).

    The reduced rhs is only C^1 at zero slip (|gamma_T| in (2.29)); states a round-off away from
    the family carry slips of ~1e-13 m/s, comparable with the analytic |gamma_T|'s delta = 1e-12 m/s,
    where its curvature ~1/delta corrupts second derivatives. On the closed form the slip is ~1e-17.
    """
    def project(u: np.ndarray, prob: EquilibriumProblem) -> np.ndarray:
        omega = prob.pin_targets(u)[0]
        out = u.copy()
        out[: prob.n] = st.stationary_state(branch, [omega])[:, 0]
        return out

    return project


def problem(free: list[str], setup: Setup | None = None, *, branch: str = "inverted", omega: float | None = None,
            bounds: dict | None = None, critical: str | None = None,
            slip_smoothing: float = SLIP_SMOOTHING) -> EquilibriumProblem:
    """The continuation problem of ``branch`` with free parameters ``free`` (names of :data:`PARAMETERS`).

    omega: the fixed spin rate when ``omega`` is not free; bounds: {name: (low, high)};
    critical: None (equilibria), "hopf" or "zero" (a curve of such points in two parameters).
    """
    setup = setup or Setup()
    if len(set(free)) != len(free):
        raise ParameterError(f"continuation parameters {free} repeat a name; give distinct names")
    params = [_parameter(name, setup) for name in free]
    if "omega" not in free and (omega is None or not math.isfinite(omega)):
        raise ParameterError("give the spin rate omega [rad/s] when omega is not a continuation parameter")
    bounds = bounds or {}
    for name, (low, high) in bounds.items():
        if name not in free:
            raise ParameterError(f"bound on {name!r}, which is not a continuation parameter ({', '.join(free)})")
        if not (math.isfinite(low) and math.isfinite(high) and low < high):
            raise ParameterError(f"bounds of {name}: give finite LOW < HIGH, not {low}:{high}")
    pars = ode.parameter_vector(setup, slip_smoothing=slip_smoothing)
    return EquilibriumProblem(reduced.system(), params, pars=pars, pins=("alpha_dot",), state_scale=STATE_SCALE,
                              pin_values={} if "omega" in free else {0: float(omega)},
                              bounds={free.index(k): v for k, v in bounds.items()}, family=reduced.OMEGA_X_INDEX,
                              critical=critical, nonsmooth=reduced.nonsmooth_split, project=_onto_family(branch),
                              family_sign=st.branch_sign(branch))  # d x*/d Omega = sign e_omega_x


def _check_in_bounds(name, value, bounds):
    if name in bounds:
        low, high = bounds[name]
        if not low <= value <= high:
            raise ParameterError(f"the start {name} = {value:g} lies outside the bounds [{low:g}, {high:g}]; "
                                 "give a start inside them")


def continue_branch(branch: str = "inverted", parameter: str = "omega", start: float | None = None,
                    stop: float | None = None, *, setup: Setup | None = None, omega: float | None = None,
                    options: continuation.Options | None = None, direction: int | None = None) -> xr.Dataset:
    """Continue a family of spinning solutions (Fig. 6) in ``parameter`` from ``start`` to ``stop``.

    ``parameter`` = "omega": from the stationary solution at Omega = start; any other parameter:
    at the fixed spin rate ``omega`` from the parameter value ``start`` (default: setup's value).
    Special points (Hopf, zero-eigenvalue branch points, folds) are located and described.
    """
    setup = setup or Setup()
    sign = st.branch_sign(branch)
    if parameter == "omega":
        if start is None or stop is None:
            raise ParameterError("give start and stop spin rates [rad/s] for a continuation in omega")
        omega0 = float(start)
    else:
        _parameter(parameter, setup)
        start = base_value(parameter, setup) if start is None else float(start)
        if stop is None:
            raise ParameterError(f"give the end value of {parameter} (stop)")
        if omega is None:
            raise ParameterError(f"give the spin rate omega [rad/s] at which to continue in {parameter}")
        omega0 = float(omega)
    for value in (start, stop):
        if not math.isfinite(value):
            raise ParameterError(f"start and stop of {parameter} must be finite numbers")
    if start == stop:
        raise ParameterError(f"start = stop = {start:g}: give two different values of {parameter}")
    low, high = sorted((float(start), float(stop)))
    if parameter != "omega":
        for value in (low, high):  # the dataclasses validate the range's ends (eps > 0, 0 <= e < r, ...)
            _setup_at(setup, parameter, value)
    prob = problem([parameter], setup, branch=branch, omega=None if parameter == "omega" else omega0,
                   bounds={parameter: (low, high)})
    x0 = st.stationary_state(branch, [omega0])[:, 0]
    u0 = np.append(x0, start)
    options = options or continuation.Options(ds_max=0.2 if parameter == "omega" else 0.05)
    br = continuation.continue_branch(prob, u0, options, direction=direction or (1 if stop > start else -1))
    return branch_dataset(br, prob, setup, {"branch": branch, "sign": sign, "parameters": [parameter],
                                            "start": start, "stop": stop, "omega": omega0})


def _setup_at(setup: Setup, name: str, value: float) -> Setup:
    """Setup with parameter ``name`` at ``value`` (validated by the dataclasses; inertia scales A, B, C)."""
    if name in ("eps", "mu"):
        return dataclasses.replace(setup, friction=dataclasses.replace(setup.friction, **{name: value}))
    if name == "e":
        return dataclasses.replace(setup, disk=dataclasses.replace(setup.disk, e=value))
    if name == "inertia":
        d = setup.disk
        return dataclasses.replace(setup, disk=dataclasses.replace(d, A=value * d.A, B=value * d.B, C=value * d.C))
    return setup


def _setup_with(setup: Setup, values: dict) -> Setup:
    for name, value in values.items():
        if not (name == "inertia" and value == 1.0):
            setup = _setup_at(setup, name, value)
    return setup


def branch_dataset(br: continuation.Branch, prob: EquilibriumProblem, setup: Setup, info: dict) -> xr.Dataset:
    """The branch as a dataset of kind "continuation": the generic schema of every System's branch
    (:func:`tippedisk_analysis.dynamics.datasets.continuation_dataset`) with the tippedisk's columns added: the
    continuation parameters of PARAMETERS along the branch (Omega, inertia, ...), lambda_N, and the normal-form
    table of the special points."""
    system = prob.system
    u = br.array("u")
    n = prob.n
    pars = np.array([prob.runtime(ui) for ui in u])
    ev = np.array([p.eigenvalues for p in br.points])
    lam = np.atleast_1d(system.observe(u[:, :n].T, pars.T)["lambda_N"])
    columns = {
        **{name: ("point", _values_along(name, u, prob, setup),
                  {"units": PARAMETERS[name][0], "long_name": PARAMETERS[name][1]}) for name in PARAMETERS},
        **{name: ("point", u[:, i], _STATE_ATTRS[name]) for i, name in enumerate(reduced.STATE_NAMES)},
        "lambda_N": ("point", lam, {"units": "N", "long_name": "normal force at C1"}),
        "eig_real": (("point", "eig"), ev.real, {"units": "s-1", "long_name": "real part of the nontrivial "
                                                 "eigenvalues (spin-family zero deflated), descending"}),
        "eig_imag": (("point", "eig"), ev.imag, {"units": "rad s-1", "long_name": "imaginary part of the nontrivial "
                                                 "eigenvalues"}),
        **_special_table(br)}
    ds = continuation_dataset(br, prob, {"setup": to_dict(setup), **info, "slip_smoothing": float(
        prob.pars[ode.PARAMETER_NAMES.index("slip_smoothing")]), "heyoka_version": hy.__version__}, columns)
    labels = ", ".join(f"{sp.label} at " + ", ".join(f"{p.name} = {sp.u[n + j]:.8g}" for j, p in
                                                       enumerate(prob.free)) for sp in br.special_points)
    what = ("curve of " + {"hopf": "Hopf", "zero": "zero-eigenvalue"}[prob.critical] + " points") \
        if prob.critical else f"{info.get('branch', '')} branch"
    ds.attrs.update(message=f"{what}: {len(u)} points; {br.message}" + (f"; {labels}" if labels else ""),
                    title="Continuation of the stationary spinning solutions of the tippedisk", model="ode-euler",
                    paper_model="ODE Model 1 (reduced by the rotational symmetry)")
    return ds


_STATE_ATTRS = {
    "beta": {"units": "rad", "long_name": "Euler angle beta"},
    "gamma": {"units": "rad", "long_name": "Euler angle gamma"},
    "u_x": {"units": "m s-1", "long_name": "velocity of G along e_x^R"},
    "u_y": {"units": "m s-1", "long_name": "velocity of G along e_y^R"},
    "omega_x": {"units": "rad s-1", "long_name": "angular velocity, body x-component"},
    "omega_y": {"units": "rad s-1", "long_name": "angular velocity, body y-component"},
    "omega_z": {"units": "rad s-1", "long_name": "angular velocity, body z-component"},
}


def _values_along(name: str, u: np.ndarray, prob: EquilibriumProblem, setup: Setup) -> np.ndarray:
    free = [p.name for p in prob.free]
    if name in free:
        return u[:, prob.n + free.index(name)].copy()
    if name == "omega":
        return np.full(len(u), prob.pin_values[0])
    return np.full(len(u), base_value(name, setup))


def _special_table(br) -> dict:
    """The tippedisk's normal-form columns of the special points (the generic table has kind, label, index,
    value, frequency, l1)."""
    sps = br.special_points
    keys = ("a", "b", "c", "k", "l1")
    table = {k: np.array([float(sp.data.get(k, 0.0)) for sp in sps]) for k in keys}
    return {
        "special_label": ("special_point", np.array([sp.label for sp in sps], dtype=str),
                          {"long_name": "label, e.g. HOPF1 (tippedisk continue --from-point FILE:LABEL)"}),
        "special_class": ("special_point", np.array([CLASSES[sp.data.get("class", "")] for sp in sps], np.int8),
                          {"long_name": "normal-form class", "flag_values": np.array(list(CLASSES.values()), np.int8),
                           "flag_meanings": " ".join(k or "none" for k in CLASSES)}),
        "special_a": ("special_point", table["a"], {"long_name": "normal-form coefficient a = d Re s / d Omega along "
                                                    "the line of equilibria (s = Omega - Omega_c)", "units": "rad-1"}),
        "special_b": ("special_point", table["b"], {"long_name": "normal-form coefficient b: drift of the spin rate, "
                                                    "d s / dt = b |z|^2 (line Hopf) or b z^2 (line transcritical)"}),
        "special_c": ("special_point", table["c"], {"long_name": "normal-form coefficient c: z' = a s z + c z^2 "
                                                    "(line transcritical)"}),
        "special_k": ("special_point", table["k"], {"long_name": "normal-form coefficient k of the C^1 term: "
                                                    "r' = a s r + k r^2 (line Hopf), z' = ... + k z|z| (line "
                                                    "transcritical); from |gamma_T| in (2.29)"}),
        "special_l1": ("special_point", table["l1"], {"long_name": "first Lyapunov coefficient (isolated Hopf "
                                                      "points only; 0 on a line of equilibria)"}),
    }


def _source(ds: xr.Dataset, index: int):
    config = config_of(ds)
    setup = Setup(**{k: v for k, v in config["setup"].items() if k == "gravity"},
                  disk=dataclasses.replace(Setup().disk, **config["setup"]["disk"]),
                  friction=dataclasses.replace(Setup().friction, **config["setup"]["friction"]))
    values = {name: float(ds[name].values[index]) for name in PARAMETERS}
    state = np.array([float(ds[name].values[index]) for name in reduced.STATE_NAMES])
    return setup, config.get("branch", "inverted"), values, state


def continue_curve(ds: xr.Dataset, label: str, parameters=("omega", "eps"), *, bounds: dict | None = None,
                   options: continuation.Options | None = None) -> xr.Dataset:
    """The curve through special point ``label`` (Hopf or zero eigenvalue) of a continuation dataset in two
    ``parameters``, in both directions, with its codimension-two points (Bogdanov-Takens, zero-Hopf,
    double Hopf, and the changes of class of the line-of-equilibria normal form)."""
    index, kind = special_point(ds, label)
    if kind not in ("hopf", "branch_point", "fold"):
        raise ParameterError(f"{label} is a {kind} point; two-parameter curves start at a Hopf or zero-eigenvalue point")
    parameters = list(parameters)
    if len(parameters) != 2:
        raise ParameterError(f"give two parameters for a curve, not {parameters}")
    setup, branch, values, state = _source(ds, index)
    for name in parameters:
        _parameter(name, setup)
    bounds = {name: tuple(PARAMETERS[name][3]) for name in parameters} | dict(bounds or {})
    for name in parameters:
        _check_in_bounds(name, values[name], bounds)
    critical = "hopf" if kind == "hopf" else "zero"
    fixed = {name: value for name, value in values.items() if name not in parameters and name != "omega"}
    setup = _setup_with(setup, fixed)  # the fixed parameters keep the source point's values
    prob = problem(parameters, setup, branch=branch, omega=values["omega"], bounds=bounds, critical=critical)
    u0 = np.append(state, [values[name] for name in parameters])
    br = continuation.continue_both_ways(prob, u0, options or continuation.Options(ds=0.02, ds_max=0.05))
    return branch_dataset(br, prob, setup, {"branch": branch, "sign": st.branch_sign(branch),
                                            "parameters": parameters, "source_label": label,
                                            "source_values": values, "omega": values["omega"]})


def continue_from_point(ds: xr.Dataset, label: str, parameter: str, stop: float, *,
                        options: continuation.Options | None = None) -> xr.Dataset:
    """A branch in one ``parameter`` through point ``label`` of a continuation dataset (e.g. in mu from the
    Hopf point of a branch in Omega), the other parameters held at that point's values."""
    index, _kind = special_point(ds, label)
    setup, branch, values, state = _source(ds, index)
    _parameter(parameter, setup)
    start = values[parameter]
    if not math.isfinite(stop) or stop == start:
        raise ParameterError(f"give a finite end value of {parameter} different from the start {start:g}")
    low, high = sorted((start, float(stop)))
    if parameter != "omega":
        for value in (low, high):
            _setup_at(setup, parameter, value)
    fixed = {name: value for name, value in values.items() if name not in (parameter, "omega")}
    setup = _setup_with(setup, fixed)
    prob = problem([parameter], setup, branch=branch, omega=None if parameter == "omega" else values["omega"],
                   bounds={parameter: (low, high)})
    options = options or continuation.Options(ds_max=0.2 if parameter == "omega" else 0.05)
    br = continuation.continue_branch(prob, np.append(state, start), options, direction=1 if stop > start else -1)
    return branch_dataset(br, prob, setup, {"branch": branch, "sign": st.branch_sign(branch),
                                            "parameters": [parameter], "start": start, "stop": float(stop),
                                            "omega": values["omega"], "source_label": label})
