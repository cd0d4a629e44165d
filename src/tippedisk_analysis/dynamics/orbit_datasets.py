"""Periodic orbits and their branches as datasets of kind ``periodic_orbits``, for any :class:`.system.System`,
and an orbit read back from one (continued later by passing the same ``System``)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import xarray as xr

from ..errors import DatasetError, ParameterError
from ..results import config_of, index_coordinate, make_attrs
from . import continuation
from .datasets import (check_system, flag_attrs, label_coordinates, mixed_units, state_coordinates, summary,
                       unlocated_attrs)
from .flows import STABILITY
from .orbits import NEWTON_MAX_ITER, STATUS, find_orbit
from .orbit_base import N_SAMPLES, TRIVIAL_TOL, OrbitProblem, PeriodicOrbit
from .period_limits import KINDS as PERIOD_LIMITS
from .system import System

SPECIAL_KINDS = {"bound": 0, "fold": 1, "branch_point": 2, "period_doubling": 3, "neimark_sacker": 4,
                 "homoclinic": 5, "hopf": 6, "user": 7, "heteroclinic": 8, "snic": 9, "period_bound": 10, "event": 11}
"""int8 codes of ``special_kind`` in periodic-orbit datasets."""
MULTIPLIER_SOURCES = {"collocation": 0, "shooting": 1, "none": 2}
"""int8 codes of ``multiplier_source`` in collocation datasets (none: not computed, a singular collocation block;
the multipliers are stored as 0)."""


def branch_orbits(prob: OrbitProblem, br: continuation.Branch, n_samples: int = N_SAMPLES) -> list[PeriodicOrbit]:
    """The orbits of a branch's points (samples, multipliers, amplitude measures), each on its own mesh."""
    return [prob.orbit(p.u, "converged", "", None, p.newton_iterations, n_samples, p.discretisation)
            for p in br.points]


def branch_dataset(prob: OrbitProblem, br: continuation.Branch, info: dict | None = None,
                   n_samples: int = N_SAMPLES, extra=None) -> xr.Dataset:
    """A branch of periodic orbits as a dataset of kind ``periodic_orbits``; ``extra(orbits)``: more variables
    computed from the branch's orbits ({name: (dims, values, attrs)})."""
    orbits = branch_orbits(prob, br, n_samples)
    status = br.status
    labels = summary([f"{sp.label} at {prob.parameter} = {sp.u[prob.t_index + 1]:.10g}" for sp in br.special_points])
    message = f"branch of {len(orbits)} periodic orbits; {br.message}" + (f"; {labels}" if labels else "")
    config = {"options": dataclasses.asdict(br.options), **prob.config(),
              "bounds": {prob.names[i]: list(b) for i, b in prob.bounds.items()}, **(info or {})}
    ds = orbits_dataset(orbits, status, message, config, special=br.special_points, prob=prob,
                        arclength=br.array("arclength"), extra=extra(orbits) if extra else None)
    ds.attrs.update(unlocated_attrs(br))
    ends = [sp for sp in br.special_points if sp.kind in PERIOD_LIMITS]
    if ends:
        data = ends[-1].data
        ds.attrs.update(period_limit=ends[-1].kind, period_limit_reason=data["reason"])
        if math.isfinite(data["limit"]):
            ds.attrs.update(period_limit_value=data["limit"], period_limit_error=data["error"])
    return ds


def orbits_dataset(orbits: list[PeriodicOrbit], status: str, message: str, config: dict, *, special=(), prob=None,
                   arclength=None, extra: dict | None = None) -> xr.Dataset:
    """Orbits (or failed searches, by ``orbit_status``) as a dataset of kind ``periodic_orbits``.

    Dims: point (orbit), floquet (multipliers by modulus), sample (along one period), state,
    observable, runtime_parameter, special_point. Non-finite numbers of failed searches are stored as 0
    with the point's ``orbit_status`` saying why (never a silent NaN); a multiplier beyond the float range (above
    about 1e308) is stored as inf.
    """
    import heyoka as hy

    system: System = orbits[0].system
    n, N = system.n, max(len(o.times) for o in orbits)
    n_obs = len(system.observables)

    def clean(a):
        a = np.asarray(a, dtype=float)
        return np.where(np.isfinite(a), a, 0.0)

    def clean_multiplier(a):
        """A failed search's NaN becomes 0 (its orbit_status says so); a multiplier beyond the float range keeps
        its infinite part: it is unstable, not 0."""
        a = np.asarray(a, dtype=float)
        return np.where(np.isnan(a), 0.0, a)

    def resample(o, a):
        a = np.asarray(a, dtype=float)
        return a if len(a) == N else np.repeat(a[:1], N, axis=0)

    mu = np.array([o.multipliers for o in orbits])
    stab = np.array([o.classification() if o.converged or o.status == "not_converged"
                     else (STABILITY["marginal"], 0) for o in orbits])
    samples = np.array([resample(o, o.samples) for o in orbits])
    times = np.array([o.times if len(o.times) == N else np.zeros(N) for o in orbits])
    obs = np.array([resample(o, o.observables) for o in orbits]) if n_obs else np.zeros((len(orbits), N, 0))
    pars = np.array([o.pars for o in orbits])
    data = {
        "period": ("point", clean([o.period for o in orbits]), {"units": system.time_units, "long_name": "period T"}),
        "amplitude": ("point", clean([o.amplitude for o in orbits]),
                      {"units": "1", "long_name": "max_t |x(t) - mean x| in scaled states (x / state_scale)"}),
        "orbit_status": ("point", np.array([STATUS[o.status] for o in orbits], np.int8),
                         {"long_name": "outcome of the search: converged is a periodic orbit; equilibrium: Newton "
                                       "converged to a point (no orbit); not_converged: residual in `residual`",
                          "flag_values": np.array(list(STATUS.values()), np.int8), "flag_meanings": " ".join(STATUS)}),
        "stability": ("point", stab[:, 0].astype(np.int8),
                      {"long_name": "stability by the nontrivial Floquet multipliers (|mu| < 1: stable; marginal also "
                                    "where the multipliers fail their check, flow_multiplier_error)",
                       "flag_values": np.array(list(STABILITY.values()), np.int8),
                       "flag_meanings": " ".join(STABILITY)}),
        "n_unstable": ("point", stab[:, 1].astype(np.int32),
                       {"units": "1", "long_name": "nontrivial multipliers outside the unit circle"}),
        "residual": ("point", clean([min(o.residual, 1e300) for o in orbits]),
                     {"units": "1", "long_name": "largest residual of the orbit equations / state_scale of the (last) "
                                   "iterate: shooting max |phi(x_k, T/m) - x_(k+1)|, collocation max "
                                   "|dx/dtau - T f(x)| at the Gauss points"}),
        "newton_iterations": ("point", np.array([o.iterations for o in orbits], np.int32),
                              {"units": "1", "long_name": "Newton steps"}),
        "multiplier_real": (("point", "floquet"), clean_multiplier(mu.real),
                            {"units": "1", "long_name": "Floquet multipliers (monodromy eigenvalues) by modulus, "
                                                        "real part (of the last iterate unless converged)"}),
        "multiplier_imag": (("point", "floquet"), clean_multiplier(mu.imag),
                            {"units": "1", "long_name": "Floquet multipliers, imaginary part"}),
        "multiplier_trivial": (("point", "floquet"), np.array([o.trivial for o in orbits], np.int8),
                               {"long_name": "1: a trivial multiplier (flow direction; families of solutions)",
                                "flag_values": np.array([0, 1], np.int8), "flag_meanings": "nontrivial trivial"}),
        "initial_state": (("point", "state"), clean([o.states[0] for o in orbits]),
                          mixed_units("x_0: the orbit's first point (phase condition)")),
        "state_min": (("point", "state"), clean(samples.min(axis=1)), mixed_units("minimum over the orbit")),
        "state_max": (("point", "state"), clean(samples.max(axis=1)), mixed_units("maximum over the orbit")),
        "orbit": (("point", "sample", "state"), clean(samples),
                  mixed_units("states along one period at sample_time (the initial state repeated for a failed "
                              "search)")),
        "sample_time": (("point", "sample"), clean(times),
                        {"units": system.time_units, "long_name": "time along the orbit"}),
        "runtime_parameters": (("point", "runtime_parameter"), clean(pars),
                               mixed_units("values of the system's runtime parameters", "runtime_parameter")),
    }
    if orbits[0].parameter:
        data[orbits[0].parameter] = ("point", clean([o.value for o in orbits]),
                                     {"units": system.units_of(orbits[0].parameter),
                                      "long_name": f"continuation parameter {orbits[0].parameter}"})
    if n_obs:
        data["observable_min"] = (("point", "observable"), clean(obs.min(axis=1)),
                                  mixed_units("minimum over the orbit", "observable"))
        data["observable_max"] = (("point", "observable"), clean(obs.max(axis=1)),
                                  mixed_units("maximum over the orbit", "observable"))
        data["orbit_observables"] = (("point", "sample", "observable"), clean(obs),
                                     mixed_units("observables along the orbit", "observable"))
    data["flow_multiplier_error"] = ("point", clean([min(o.flow_multiplier_error, 1e300) for o in orbits]), {
        "units": "1", "long_name": "|mu - 1| of the flow direction's Floquet multiplier (the multipliers' check: "
                                   f"above {TRIVIAL_TOL:g}, a tenth of the nontrivial ones' distance from the unit "
                                   "circle and, in log |mu|, a tenth of their smallest |log |mu|| they decide no "
                                   "stability)"})
    data.update(_collocation_columns(orbits))
    if arclength is not None:
        data["arclength"] = ("point", np.asarray(arclength, float), {"units": "1", "long_name": "pseudo-arclength"})
    data.update(_special_table(list(special), system, orbits[0].parameter))
    data.update(extra or {})
    coords = {
        "point": index_coordinate("point", len(orbits), "orbit index (along the branch)"),
        "floquet": index_coordinate("floquet", n, "multiplier index"),
        "sample": index_coordinate("sample", N, "sample index along the orbit"),
        **state_coordinates(system),
        **label_coordinates("runtime_parameter", system.parameter_names[: pars.shape[1]],
                            [system.units_of(p) for p in system.parameter_names[: pars.shape[1]]],
                            "runtime parameter"),
        "special_point": index_coordinate("special_point", len(special), "special point"),
    }
    if n_obs:
        coords.update(label_coordinates("observable", system.observables,
                                        [system.units_of(k) for k in system.observables], "observable"))
    config = {"system": system.name, "system_key": system.key, "description": system.description,
              "heyoka_version": hy.__version__, "method": orbits[0].method, **config}
    attrs = make_attrs("periodic_orbits", config, status, message, **system.attrs(orbits[0].pars),
                       parameter=orbits[0].parameter or "", method=orbits[0].method,
                       labels=" ".join(sp.label for sp in special),
                       n_orbits=int(sum(o.converged for o in orbits)))
    return xr.Dataset(data, coords=coords, attrs=attrs)


def _collocation_columns(orbits: list[PeriodicOrbit]) -> dict:
    """The estimated discretisation error and the mesh intervals of collocation orbits (none for shooting)."""
    if not any(o.method == "collocation" and o.mesh is not None for o in orbits):
        return {}
    error = [o.discretisation_error if o.discretisation_error is not None else 1e300 for o in orbits]
    return {
        "discretisation_error": ("point", np.array(error),
                                 {"units": "1", "long_name": "estimated largest error of x(t) / state_scale along the "
                                                             "orbit (collocation; the period and the mesh values are "
                                                             "more accurate)", "comment": "1e300: not estimated (a "
                                                             "failed search)"}),
        "multiplier_source": ("point", np.array([MULTIPLIER_SOURCES[o.multiplier_source] for o in orbits], np.int8),
                              flag_attrs("the Floquet multipliers from the condensed collocation blocks (periodic "
                                         "QR), from a shooting monodromy, or none (a singular block: the multipliers "
                                         "are stored as 0 and decide no stability)", MULTIPLIER_SOURCES)),
        "ntst": ("point", np.array([len(o.mesh) - 1 if o.mesh is not None else 0 for o in orbits], np.int32),
                 {"units": "1", "long_name": "collocation mesh intervals of the orbit (0: a failed search)"}),
    }


def _special_table(special: list, system: System, parameter: str | None) -> dict:
    def get(key):
        return np.array([float(np.ravel([sp.data.get(key, 0.0)])[0]) if np.isfinite(
            np.ravel([sp.data.get(key, 0.0)])[0]) else 0.0 for sp in special])

    return {
        "special_kind": ("special_point", np.array([SPECIAL_KINDS[sp.kind] for sp in special], np.int8),
                         flag_attrs("type of the special point", SPECIAL_KINDS)),
        "special_label": ("special_point", np.array([sp.label for sp in special], dtype=str),
                          {"long_name": "label: LP fold of cycles, BP branch point, PD period doubling, NS "
                                        "Neimark-Sacker; at the period bound HC approach to a homoclinic orbit, "
                                        "HET to a heteroclinic cycle, SNIC to a saddle-node on the invariant cycle, "
                                        "PB no limit named; EVENT an orbit reaches a terminal event of the "
                                        "System (the branch ends there)"}),
        "special_index": ("special_point", np.array([sp.index for sp in special], np.int32),
                          {"units": "1", "long_name": "index along dim point"}),
        "special_value": ("special_point", np.array([sp.value if np.isfinite(sp.value) else 0.0 for sp in special]),
                          {"long_name": "located test function (|mu| - 1 of the critical multiplier; HC, HET, SNIC: "
                                        "p - p_c)"}),
        "special_multiplier_real": ("special_point", get("multiplier_real"),
                                    {"units": "1", "long_name": "critical multiplier, real part"}),
        "special_multiplier_imag": ("special_point", get("multiplier_imag"),
                                    {"units": "1", "long_name": "critical multiplier, imaginary part"}),
        "special_angle": ("special_point", get("angle"), {"units": "rad", "long_name": "NS: rotation angle arg mu"}),
        "special_limit": ("special_point", get("limit"),
                          {"units": system.units_of(parameter) if parameter else "1",
                           "long_name": "HC, HET, SNIC: the limit p_c of the infinite period fitted to the last "
                                        "orbits (0 elsewhere)"}),
        "special_limit_error": ("special_point", get("error"),
                                {"units": system.units_of(parameter) if parameter else "1",
                                 "long_name": "HC, HET, SNIC: uncertainty of special_limit (0 elsewhere)"}),
    }


def orbit_from_dataset(ds: xr.Dataset, point: int, system: System, *, max_iter: int = NEWTON_MAX_ITER) -> PeriodicOrbit:
    """The orbit stored at ``point`` of a dataset of kind ``periodic_orbits`` of ``system``, corrected by Newton
    (runtime parameters, first point, period, segments and phase condition come from the dataset)."""
    if ds.attrs.get("kind") != "periodic_orbits":
        raise DatasetError(f"the dataset is of kind {ds.attrs.get('kind')!r}; give a periodic_orbits dataset "
                           "(orbit_branch, tippedisk periodic-orbits)")
    check_system(ds, system)
    n_points = ds.sizes["point"]
    if not -n_points <= point < n_points:
        raise ParameterError(f"point {point} does not exist; the dataset has points 0 .. {n_points - 1}")
    if int(ds.orbit_status.values[point]) != STATUS["converged"]:
        status = list(STATUS)[int(ds.orbit_status.values[point])]
        raise ParameterError(f"point {point} is not a periodic orbit (orbit_status {status}); give a converged point")
    config = config_of(ds)
    pars = ds.runtime_parameters.values[point]
    method = config.get("method", "shooting")
    options = ({"ntst": int(config.get("ntst", 0)) or None, "ncol": int(config.get("ncol", 0)) or None}
               if method == "collocation" else
               {"segments": int(config.get("segments", 1)), "phase": config.get("phase", "poincare")})
    orbit = find_orbit(system, ds.initial_state.values[point], float(ds.period.values[point]),
                       np.concatenate([pars, np.asarray(system.pars)[len(pars):]]), method=method, max_iter=max_iter,
                       **options)
    parameter = ds.attrs.get("parameter") or None
    if parameter:
        orbit.parameter, orbit.value = parameter, float(orbit.pars[system.parameter_index(parameter)])
    return orbit
