"""The generic dataset schema of branches of any :class:`.system.System` (kind ``continuation``).

A branch is a dataset along ``point``: every state and every runtime parameter of the system as a variable
(the continued ones vary, the others hold their value), the eigenvalues along ``eig``, the stability, and
the special points as a table along ``special_point`` (kind, label such as HOPF1, index along ``point``,
the located test function, the Hopf frequency and the normal-form coefficient). The system's name,
fingerprint, state and parameter names and its equations are attributes: a stored branch is plotted by the
generic figures and continued later by passing the same ``System`` (:func:`point_of` checks the
fingerprint). The equations are text to read, never evaluated.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import xarray as xr

from ..errors import DatasetError, ParameterError
from ..results import index_coordinate, make_attrs
from . import spectra
from .continuation import Branch
from .system import System

SPECIAL_KINDS = {"bound": 0, "fold": 1, "branch_point": 2, "hopf": 3, "bogdanov_takens": 4, "zero_hopf": 5,
                 "double_hopf": 6, "bautin": 7, "cusp": 8, "line_saddle_change": 9, "line_focus_node": 10, "user": 11}
"""int8 codes of ``special_kind`` in continuation datasets (flag_values / flag_meanings)."""
SMOOTH_FLAGS = {False: 0, True: 1, None: 2}  # special_smooth: describe's "smooth", None where it has none


def flag_attrs(long_name: str, flags: dict) -> dict:
    return {"long_name": long_name, "flag_values": np.array(list(flags.values()), np.int8),
            "flag_meanings": " ".join(k or "none" for k in flags)}


def label_coordinates(dim: str, names, units, long_name: str) -> dict:
    """The text labels of dimension ``dim`` and their UDUNITS units, ``<dim>_units`` (values along such a
    dimension mix units: variables over it carry :func:`mixed_units` instead of a ``units`` attribute)."""
    return {dim: (dim, np.array(list(names), dtype=str), {"long_name": long_name}),
            f"{dim}_units": (dim, np.array(list(units), dtype=str), {"long_name": f"units of each {dim}"})}


def state_coordinates(system: System, names=None) -> dict:
    """``state`` and ``state_units`` of ``system`` (or of its states ``names``)."""
    names = system.state_names if names is None else tuple(names)
    return label_coordinates("state", names, [system.units_of(n) for n in names], "state variable")


def mixed_units(long_name: str, dim: str = "state") -> dict:
    """Attributes of a variable whose values along ``dim`` have different units (CF has no per-element units)."""
    return {"long_name": long_name, "comment": f"the units differ along {dim}: see the coordinate {dim}_units"}


def special_table(br: Branch, system: System, kinds: dict = SPECIAL_KINDS) -> dict:
    """The special points of a branch as data variables along ``special_point``."""
    sps = br.special_points
    return {
        "special_kind": ("special_point", np.array([kinds[sp.kind] for sp in sps], dtype=np.int8),
                         flag_attrs("type of the special point", kinds)),
        "special_label": ("special_point", np.array([sp.label for sp in sps], dtype=str),
                          {"long_name": "label, e.g. HOPF1 (a start for special_point_curve or orbit_branch)"}),
        "special_index": ("special_point", np.array([sp.index for sp in sps], dtype=np.int32),
                          {"units": "1", "long_name": "index of the special point along dim point"}),
        "special_value": ("special_point", np.array([sp.value for sp in sps]),
                          {"long_name": "test function at the located point: the critical eigenvalue's real part for "
                                        "Hopf and zero-eigenvalue points, the tangent component for folds",
                           "comment": f"units: {system.per_time()} (eigenvalues), 1 (tangent components)"}),
        "special_frequency": ("special_point", np.array([float(sp.data.get("frequency", 0.0)) for sp in sps]),
                              {"long_name": "frequency |Im s| of the critical pair (Hopf), 0 otherwise",
                               "units": system.per_time("rad")}),
        "special_l1": ("special_point", np.array([float(sp.data.get("l1", 0.0)) for sp in sps]),
                       {"long_name": "first Lyapunov coefficient of Hopf points (< 0 supercritical, > 0 subcritical)"}),
        "special_degenerate": ("special_point", np.array([sp.data.get("class") == "degenerate" for sp in sps],
                                                         dtype=np.int8),
                               flag_attrs("l1 zero to round-off of its terms (a degenerate Hopf point)",
                                          {"no": 0, "yes": 1})),
        "special_smooth": ("special_point", np.array([SMOOTH_FLAGS[sp.data.get("smooth")] for sp in sps],
                                                     dtype=np.int8),
                           flag_attrs("whether the vector field is smooth enough at the point for its normal form "
                                      "(no: a kink of the Jacobian, e.g. a |x| x term, or at a Hopf point of the "
                                      "second derivatives; l1 and the fold coefficient do not apply and are 0)",
                                      {"no": 0, "yes": 1, "not_checked": 2})),
    }


def continuation_dataset(br: Branch, prob, info: dict | None = None, columns: dict | None = None) -> xr.Dataset:
    """A branch (or a curve of special points) of an :class:`.equilibria.EquilibriumProblem` as a dataset;
    ``columns`` {name: (dims, values, attrs)} are a caller's own variables (added, or replacing the generic ones
    of that name)."""
    system: System = prob.system
    u = br.array("u")
    n = prob.n
    ev = np.array([p.eigenvalues for p in br.points])
    stab, n_unstable, max_re = spectra.classify(ev)
    pars = np.array([prob.runtime(ui) for ui in u])
    residual = np.array([np.max(np.abs(system.f(ui[:n], pi))) for ui, pi in zip(u, pars)])
    data = {name: ("point", u[:, i], {"units": system.units.get(name, "1"), "long_name": f"state {name}"})
            for i, name in enumerate(system.state_names)}
    for j, name in enumerate(system.parameter_names):
        data[name] = ("point", pars[:, j], {"units": system.units_of(name), "long_name": f"parameter {name}"})
    for p, column in zip(prob.free, u[:, n:].T):  # free unknowns that are not runtime parameters (pins)
        if p.name not in data:
            data[p.name] = ("point", column, {"units": "1", "long_name": f"continuation parameter {p.name}"})
    data.update({
        "eig_real": (("point", "eig"), ev.real, {"units": system.per_time(), "long_name": "real part of the "
                                                 "eigenvalues, descending"}),
        "eig_imag": (("point", "eig"), ev.imag, {"units": system.per_time(), "long_name": "imaginary part of the "
                                                 "eigenvalues"}),
        "n_unstable": ("point", n_unstable, {"units": "1", "long_name": "eigenvalues with positive real part"}),
        "stability": ("point", stab, flag_attrs("linear stability", spectra.STABILITY_FLAGS)),
        "max_real_eig": ("point", max_re, {"units": system.per_time(), "long_name": "largest real part of the "
                                           "eigenvalues"}),
        "arclength": ("point", br.array("arclength"), {"units": "1", "long_name": "pseudo-arclength in scaled "
                                                       "unknowns (u / scale)"}),
        "residual": ("point", residual, {"long_name": "max |right-hand side| at the point",
                                         "comment": "the largest component, in its state's units per time"}),
        "newton_iterations": ("point", br.array("newton_iterations").astype(np.int32),
                              {"units": "1", "long_name": "corrector iterations"}),
    })
    if prob.critical == "hopf":
        kappa = [float(np.prod(p.eigenvalues[prob._critical_indices(p.eigenvalues)]).real) for p in br.points]
        data["critical_product"] = ("point", np.array(kappa), {
            "units": f"{system.time_units}-2" if system.time_units != "1" else "1",
            "long_name": "product of the critical pair of eigenvalues",
            "comment": "omega^2 > 0 on the Hopf curve; < 0 on its continuation beyond a Bogdanov-Takens point, "
                       "a neutral saddle (a real pair s, -s: no bifurcation)"})
    data.update(special_table(br, system))
    data.update(columns or {})
    ds = xr.Dataset(data, coords={
        "point": index_coordinate("point", len(u), "point along the branch"),
        "eig": index_coordinate("eig", ev.shape[1], "eigenvalue index"),
        "special_point": index_coordinate("special_point", len(br.special_points), "special point index")})
    free = [p.name for p in prob.free]
    labels = summary([f"{sp.label} at " + ", ".join(f"{name} = {sp.u[n + j]:.8g}" for j, name in enumerate(free))
                      + (NOT_SMOOTH_NOTE if sp.data.get("smooth") is False
                         else DEGENERATE_NOTE if sp.data.get("class") == "degenerate" else "")
                      for sp in br.special_points])
    what = (f"curve of {'Hopf' if prob.critical == 'hopf' else 'zero-eigenvalue'} points" if prob.critical
            else "branch of equilibria")
    config = {"system": system.name, "system_key": system.key, **(info or {}), "free": free,
              "critical": prob.critical or "", "pars": list(map(float, prob.pars)),
              "bounds": {free[i - n]: list(b) for i, b in prob.bounds.items()},
              "options": dataclasses.asdict(br.options)}
    ds.attrs = make_attrs("continuation", config, br.status,
                          f"{system.name}: {what}, {len(u)} points; {br.message}" + (f"; {labels}" if labels else ""),
                          **system.attrs(prob.pars), parameters=" ".join(free),
                          critical=prob.critical or "equilibria",
                          labels=" ".join(sp.label for sp in br.special_points), **unlocated_attrs(br))
    return ds


DEGENERATE_NOTE = " (degenerate: l1 = 0, a generalised Hopf point or a centre)"
NOT_SMOOTH_NOTE = " (the field has a kink there: no normal-form coefficient)"


def summary(items: list[str], limit: int = 6) -> str:
    """``items`` joined for a one-line message: the first ``limit`` and how many more."""
    more = f" and {len(items) - limit} more" if len(items) > limit else ""
    return ", ".join(items[:limit]) + more


def unlocated_attrs(br) -> dict:
    """The attribute ``unlocated`` (where test functions changed sign without a zero), if there are any."""
    return {"unlocated": "; ".join(br.unlocated)} if br.unlocated else {}


def special_point(ds: xr.Dataset, label: str, kinds: dict = SPECIAL_KINDS) -> tuple[int, str]:
    """(index along ``point``, kind) of the special point ``label`` (e.g. "HOPF1") of a continuation dataset."""
    if ds.attrs.get("kind") != "continuation":
        raise DatasetError(f"the dataset is of kind {ds.attrs.get('kind')!r}, not a continuation; give a branch "
                           "(equilibrium_branch, spin_continuation, tippedisk continue)")
    labels = [str(v) for v in ds["special_label"].values]
    if label not in labels:
        raise ParameterError(f"no special point {label!r} in the dataset; it has {', '.join(labels) or 'none'}")
    k = labels.index(label)
    kind = list(kinds)[list(kinds.values()).index(int(ds["special_kind"].values[k]))]
    return int(ds["special_index"].values[k]), kind


def check_system(ds: xr.Dataset, system: System) -> None:
    """DatasetError unless ``ds`` was computed for ``system`` (the same equations and names)."""
    stored = ds.attrs.get("system_key")
    if stored is None:  # written before datasets carried the fingerprint: the name and the states must match
        names = str(ds.attrs.get("state_names", " ".join(system.state_names))).split()
        if ds.attrs.get("system") == system.name and names == list(system.state_names):
            return
    if stored != system.key:
        raise DatasetError(f"the dataset belongs to system {ds.attrs.get('system', '?')!r} (key {stored}), not to "
                           f"{system.name!r} (key {system.key}); pass the System the dataset was computed with")


def point_of(ds: xr.Dataset, system: System, index: int) -> tuple[np.ndarray, np.ndarray]:
    """(state, runtime parameters) of point ``index`` of a branch dataset of ``system``."""
    check_system(ds, system)
    state = np.array([float(ds[name].values[index]) for name in system.state_names])
    pars = np.array([float(ds[name].values[index]) for name in system.parameter_names])
    return state, pars
