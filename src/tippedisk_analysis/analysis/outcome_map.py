"""Outcome maps: what the tippedisk does over a grid of (Omega, eps, mu, e, dgamma0).

Every grid point is one run of ODE Model 1 (Euler angles, bilateral contact at C1, smooth
Coulomb friction (2.29), Sect. 4.1) from the perturbed noninverted state of Table 3 with
alpha_dot(0) = Omega and gamma(0) = -pi/2 + dgamma0, until ``t_end``.

Classification (``outcome``, int8, see :data:`OUTCOMES`), checked in this order:

* ``failed``: the integrator produced a non-finite state;
* ``fell``: the tilt asin(sin beta) reached ``fall_angle`` before ``t_end`` (the Euler
  angles are singular at sin beta = 0, the run ends there);
* ``rolling``: the run reached ``t_end`` and gamma turned by at least 2 pi within the
  classification window (the disk rolls over its rim instead of settling: slow spins);
* ``inverted``: the run reached ``t_end`` and the mean of sin(gamma) over the
  classification window [t_end - window, t_end] is >= ``threshold`` (0.9): the centre of
  gravity S stayed above G (z_S - z_G = e sin(beta) sin(gamma), gamma near +pi/2);
* ``not_inverted``: the same mean is <= -threshold: S stayed below G (gamma near -pi/2);
* ``undecided``: anything else (still turning over, or large oscillations).

Window means are exact time averages: the ODE is augmented with the quadratures
Q1' = sin(gamma), Q2' = z_S, read at the window start and at the end of the run. For
runs that ended early (fell, failed) the means are over [t_end - window, t_final], or over
the whole run [0, t_final] if it ended before the window began.

Times that do not exist are stored as the fill value -1 s (documented in the variable's
attributes; the outcome says which): ``inversion_time`` (first upward crossing of
gamma = 0) and ``fall_time``.

Attractor classification (``classify="attractors"``, :mod:`.basins`): each run is instead assigned to
the attractor it reaches, found by recurrences in a cell grid (:mod:`.attractors`) with ``t_end`` as the
maximum horizon; runs with equal (eps, mu, e) share the attractors found so far and stop early when they
enter one. ``outcome`` is then the attractor id (>= 0, a table along the dimension ``attractor``) or a
negative label (undecided, left_grid, failed, fell, lift_off), plus ``assignment_time``; the window
quantities (gamma_turns, sin_gamma_mean, z_S_mean) are not computed.

Execution: heyoka batch mode (``batch_size`` SIMD lanes, default 4: on the development
machine ``hy.recommended_simd_size()`` = 8 was about 1.2-1.5x slower per run) over chunks of grid
points; chunks run on threads, or on a dask.distributed cluster (see :mod:`.sweeps`).
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import xarray as xr

from ..dynamics import sweeps
from ..errors import ParameterError
from ..models import ode
from ..results import describe, index_coordinate, make_attrs
from . import basins
from . import outcome_rules as rules
from .outcome_config import FILL_TIME, INITIAL_AXES, MODEL, OUTCOMES, SWEEPABLE, MapConfig, prepare
from .outcome_rules import BYTES_PER_POINT, RESULT_VARIABLES, kernel

__all__ = ["outcome_map"]


def run_chunk(config: MapConfig | dict, start: int, stop: int) -> dict:
    """Outcome of grid points [start, stop), by rules (:mod:`.outcome_rules`) or by attractors.

    Module-level and deterministic, so a dask worker can run it from the config alone.
    """
    if isinstance(config, dict):
        config = MapConfig.from_dict(config)
    if config.classify == "attractors":
        return _attractor_chunk(config, start, stop)
    return rules.run_rules(config, start, stop)

def assemble(config: MapConfig, results: dict) -> xr.Dataset:
    """Dataset with dims = swept parameters from flat per-point results (C order)."""
    if config.classify == "attractors":
        return _assemble_attractors(config, results)
    axes = config.axes()
    dims = tuple(axes)
    shape = config.shape
    data = {}
    for name, (dtype, units, long_name) in RESULT_VARIABLES.items():
        attrs = {"units": units, "long_name": long_name}
        if name in ("inversion_time", "fall_time", "lift_off_time"):
            attrs["fill_value_meaning"] = f"{FILL_TIME:g} s where the event did not happen"
        elif name == "valid":
            attrs.update(flag_values=np.array([0, 1], dtype=np.int8), flag_meanings="lift_off valid",
                         comment="exact: a heyoka event on lambda_N = 0 during the run (up to t_final)")
        elif name != "outcome":
            attrs["comment"] = "0 where outcome is failed (non-finite state): mask with the outcome flags"
        data[name] = (dims, np.asarray(results[name], dtype=dtype).reshape(shape), attrs)
    data["outcome"][2].update(
        flag_values=np.array(list(OUTCOMES.values()), dtype=np.int8),
        flag_meanings=" ".join(OUTCOMES),
        classification=("failed: non-finite state; fell: tilt reached fall_angle before t_end; "
                        f"inverted: mean sin(gamma) over [t_end - window, t_end] >= {config.threshold}; "
                        f"not_inverted: that mean <= -{config.threshold}; rolling (checked before those two): "
                        "gamma turned by >= 2 pi within the window; undecided: otherwise"),
    )
    coords = {}
    for name, values in axes.items():
        units, long_name, _ = SWEEPABLE[name]
        coords[name] = (name, values, {"units": units, "long_name": long_name,
                                       **({"comment": config.base_setup().disk.eccentricity_rule}
                                          if name == "e" else {})})
    counts = {k: int(np.sum(np.asarray(results["outcome"]) == v)) for k, v in OUTCOMES.items()}
    n_failed = counts["failed"]
    status = "completed" if n_failed == 0 else "partial"
    message = (f"{config.n_points} runs of {config.t_end:g} s: "
               + ", ".join(f"{v} {k}" for k, v in counts.items()))
    n_invalid = int(np.sum(np.asarray(results["valid"]) == 0))
    message += (f"; {n_invalid} run(s) with lambda_N < 0 (the contact would lift off: outside the bilateral model, "
                "see valid / lift_off_time)" if n_invalid else "; lambda_N > 0 in every run")
    if n_failed:
        message += "; failed runs hit a non-finite state: try a smaller --tol"
    ds = xr.Dataset(data, coords=coords,
                    attrs=make_attrs("outcome_map", config.to_dict(), status, message, model=MODEL,
                                     paper_model=ode.EULER.paper_name, swept=" ".join(dims),
                                     t_end=config.t_end, window=config.window,
                                     e_sweep=config.base_setup().disk.eccentricity_rule if "e" in axes else None))
    return describe(ds)


def outcome_map(ranges: dict, *, output=None, scheduler=None, threads: int | None = None, progress: bool = True,
                overwrite: bool = False, **options) -> xr.Dataset:
    """Outcome map over ``ranges`` ({name: (start, stop, n)} for names in :data:`SWEEPABLE`).

    ``output``: netCDF path; chunks go to ``<output>.chunks/`` as they finish and a rerun
    resumes. ``scheduler``: dask.distributed address (or ``"local:N"``); default: threads.
    ``overwrite``: discard a chunk directory left by another configuration.
    Further options: the fields of :class:`MapConfig` (t_end, window, tol, ...).
    """
    unknown = set(options) - {f.name for f in dataclasses.fields(MapConfig)}
    if unknown:
        raise ParameterError(f"outcome_map takes no option(s) {sorted(unknown)}; it takes "
                             f"{sorted(f.name for f in dataclasses.fields(MapConfig) if f.name != 'ranges')}")
    config = MapConfig(ranges=ranges, **options)
    return sweeps.run_sweep(sweep(config), output=output, scheduler=scheduler, threads=threads, progress=progress,
                            overwrite=overwrite)


def sweep(config: MapConfig) -> sweeps.Sweep:
    """The outcome map as a chunked, resumable :class:`.sweeps.Sweep`."""
    if config.classify == "attractors":
        return sweeps.Sweep("outcome map", config.to_dict(), config.n_points, int(config.chunk_size),
                            basins.chunk_variables(), run_chunk, functools.partial(assemble, config),
                            functools.partial(basins.warm_up, float(config.tol), int(config.batch_size)),
                            bytes_per_point=basins.BYTES_PER_POINT,
                            seconds_per_point=basins.SECONDS_PER_RUN_SECOND * config.t_end)
    return sweeps.Sweep("outcome map", config.to_dict(), config.n_points, int(config.chunk_size),
                        tuple(RESULT_VARIABLES), run_chunk, functools.partial(assemble, config),
                        functools.partial(kernel, float(config.tol), int(config.batch_size)),
                        bytes_per_point=BYTES_PER_POINT,
                        seconds_per_point=basins.SECONDS_PER_RUN_SECOND * config.t_end)



# --- classification by attractors (classify="attractors", module docstring) ---
def attractor_order(config: MapConfig) -> tuple[np.ndarray, int]:
    """(order, n_initial): the sweep visits the C-order flat indices ``order``, all initial conditions
    (omega, dgamma0) of one parameter point (eps, mu, e) in a row, so runs sharing the parameters share
    the attractors found; the j-th point of the sweep belongs to parameter group j // n_initial."""
    names = list(config.ranges)
    ic = [k for k, name in enumerate(names) if name in INITIAL_AXES]
    par = [k for k, name in enumerate(names) if name not in INITIAL_AXES]
    order = np.arange(config.n_points).reshape(config.shape).transpose(par + ic).ravel()
    return order, int(np.prod([config.shape[k] for k in ic]))


def _attractor_chunk(config: MapConfig, start: int, stop: int) -> dict:
    order, n_ic = attractor_order(config)
    x0, pars = prepare(config, start, stop, index=order[start:stop])
    groups = np.arange(start, stop) // n_ic
    return basins.run_points(x0[: len(ode.EULER.state_names)], pars, groups, tol=config.tol,
                             batch_size=config.batch_size, horizon=config.t_end, recurrence=config.recurrence,
                             key_base=start)


def _assemble_attractors(config: MapConfig, results: dict) -> xr.Dataset:
    order, n_ic = attractor_order(config)
    outcome, table_vars, table = basins.attractor_table(results, np.arange(config.n_points) // n_ic)
    axes = config.axes()
    dims, shape = tuple(axes), config.shape

    def grid_values(v):  # sweep order -> C order on the grid
        out = np.empty_like(np.asarray(v))
        out[order] = v
        return out.reshape(shape)

    flag_values, flag_meanings = basins.outcome_flags(table)
    data = {"outcome": (dims, grid_values(outcome), {
        "units": "1", "long_name": "attractor id (>= 0, see dimension attractor) or negative label",
        "flag_values": flag_values, "flag_meanings": flag_meanings,
        "classification": "recurrences in a cell grid (dynamics/attractors, analysis/basins.py)"})}
    data["assignment_time"] = (dims, grid_values(results["t_assign"]), {
        "units": "s", "long_name": "time at which the run was assigned to an attractor or labelled"})
    for name, (dtype, units, long_name) in basins.POINT_VARIABLES.items():
        attrs = {"units": units, "long_name": long_name}
        if name.endswith("_time"):
            attrs["fill_value_meaning"] = f"{FILL_TIME:g} s where the event did not happen"
        elif name == "valid":
            attrs.update(flag_values=np.array([0, 1], dtype=np.int8), flag_meanings="lift_off valid")
        data[name] = (dims, grid_values(np.asarray(results[name], dtype=dtype)), attrs)
    data.update(table_vars)
    coords = {name: (name, values, {"units": SWEEPABLE[name][0], "long_name": SWEEPABLE[name][1],
                                    **({"comment": config.base_setup().disk.eccentricity_rule} if name == "e" else {})})
              for name, values in axes.items()}
    coords["attractor"] = index_coordinate("attractor", len(table), "attractor id")
    coords.update(basins.table_coords())
    message = basins.summary(outcome, table, config.n_points, config.t_end)
    status = "partial" if np.any(outcome == basins.labels()["failed"]) else "completed"
    ds = xr.Dataset(data, coords=coords,
                    attrs=make_attrs("outcome_map", config.to_dict(), status, message, model=MODEL,
                                     paper_model=ode.EULER.paper_name, swept=" ".join(dims), t_end=config.t_end,
                                     classify="attractors",
                                     e_sweep=config.base_setup().disk.eccentricity_rule if "e" in axes else None))
    return describe(ds)
