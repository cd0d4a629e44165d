"""The basins of attraction of any :class:`~tippedisk_analysis.dynamics.System` (:func:`basins`): the runs as a
resumable sweep of the recurrence problem :class:`.system_problem.SystemProblem`, and their datasets.

    grid = at.Grid(("u1", "u2"), (0.0, 0.0), (1.0, 6.0), (100, 100))
    ds = dy.basins(ab, grid, {"u1": (0.0, 1.0, 64), "u2": (0.0, 6.0, 64)}, pars=ab.with_pars(D=0.12))

The runs integrate the system in heyoka batch mode (its terminal events end a run and label it), observed
through the grid's coordinates (states or observables of the system, by name). The result is a dataset of
kind ``basins``: the attractor id (>= 0) or the negative label of every initial condition, the time it was
decided, the basin fractions, and the table of attractors (kind, period, amplitude, a state on it, the mean of
its observed coordinates, its points), with the system's name and equations as attributes. The grid of initial
conditions runs as a resumable sweep (:mod:`tippedisk_analysis.dynamics.sweeps`: threads, or a dask
scheduler; finished chunks are kept next to ``output``). A conservative flow (:mod:`.conservative`) has no
attractors: its dataset says how each run ended instead.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import xarray as xr

from ...errors import ParameterError
from ...results import index_coordinate, make_attrs
from .. import sweeps
from ..datasets import flag_attrs, label_coordinates, mixed_units, state_coordinates
from ..system import System
from . import conservative
from .mapping import map_points
from .records import BASE_KINDS, Grid, RecurrenceSettings
from .sets import points_of, set_names
from .system_problem import TOL, SystemProblem
from .tables import assemble_table, chunk_result, column_names


@functools.lru_cache(maxsize=8)
def _problem(system: System, grid: Grid, tol: float) -> SystemProblem:
    return SystemProblem(system, grid, tol=tol)


def _initial_states(system: System, state, axes: dict, start: int, stop: int) -> np.ndarray:
    values = {name: np.linspace(*axis) for name, axis in axes.items()}
    shape = tuple(int(a[2]) for a in axes.values())
    idx = np.unravel_index(np.arange(start, stop), shape)
    x0 = np.repeat(np.asarray(state, dtype=float)[:, None], stop - start, axis=1)
    for (name, v), i in zip(values.items(), idx):
        x0[system.state_index(name)] = v[i]
    return x0


def basin_chunk(system: System, config: dict, start: int, stop: int) -> dict:
    """Points [start, stop) of a basin map of ``system`` (module-level: a dask worker runs it)."""
    grid = Grid.from_dict(config["grid"])
    prob = SystemProblem(system, grid, tol=float(config["tol"]))  # one per chunk: it records rejections
    x0 = _initial_states(system, config["state"], config["axes"], start, stop)
    res = map_points(prob, RecurrenceSettings(**config["recurrence"]), x0, np.asarray(config["pars"]),
                     np.zeros(stop - start, dtype=np.int64), int(config["batch_size"]))
    out = chunk_result(prob, res, start)
    out.update({f"final_{n}": res.final_states[i] for i, n in enumerate(system.state_names)})
    out["rejection"] = res.rejections
    return out


def _table(system: System, prob: SystemProblem, table: list, outcome: np.ndarray) -> dict:
    """The attractor table's variables (dimension ``attractor``; empty for a conservative flow)."""
    grid, m = prob.grid, len(table)
    return {
        "basin_fraction": ("attractor", np.array([np.mean(outcome == i) for i in range(m)], dtype=float),
                           {"units": "1", "long_name": "share of the initial conditions in the basin"}),
        "attractor_kind": ("attractor", np.array([BASE_KINDS.index(d.kind) for d in table], dtype=np.int8),
                           flag_attrs("kind of attractor", {k: i for i, k in enumerate(BASE_KINDS)})),
        "attractor_period": ("attractor", np.array([d.period for d in table], dtype=float),
                             {"units": system.time_units,
                              "long_name": "period (periodic attractors; fill -1: none)"}),
        "attractor_amplitude": ("attractor", np.array([d.amplitude for d in table], dtype=float),
                                {"units": system.units_of(grid.names[0]),
                                 "long_name": "half peak-to-peak of the first observed coordinate"}),
        "attractor_state": (("attractor", "state"), np.array([d.representative for d in table], dtype=float)
                            .reshape(m, system.n),
                            mixed_units("a state on the attractor (equilibria: the settled state)")),
        "attractor_centroid": (("attractor", "observed"), np.array([d.centroid for d in table], dtype=float)
                               .reshape(m, len(grid.names)),
                               mixed_units("mean of the observed coordinates on the attractor", "observed")),
        "attractor_set": (("attractor", "set_point", "observed"),
                          np.array([points_of(d, prob.set_points).T for d in table], dtype=float)
                          .reshape(m, prob.set_points, len(grid.names)),
                          mixed_units("the attractor as a set: one period at equal time steps (periodic), samples "
                                      "of a long run (irregular), the point repeated (equilibrium)", "observed")),
    }


def _coordinates(system: System, prob: SystemProblem, axes: dict, m: int) -> dict:
    coords = {name: (name, np.linspace(*axis), {"units": system.units_of(name),
                                                "long_name": f"initial {name}"}) for name, axis in axes.items()}
    coords.update({"attractor": index_coordinate("attractor", m, "attractor id"),
                   "set_point": index_coordinate("set_point", prob.set_points, "point of an attractor's set"),
                   **state_coordinates(system),
                   **label_coordinates("observed", prob.grid.names, [system.units_of(n) for n in prob.grid.names],
                                       "observed coordinate of the cell grid")})
    return coords


def _outcome(labels: dict, table: list, values: np.ndarray, dims: tuple, shape: tuple, long_name: str) -> tuple:
    """``outcome``: categorical int16 (attractor ids >= 0 where there is a table) with flag_values/meanings."""
    order = sorted(labels.items(), key=lambda kv: kv[1])
    flag_values = np.array([v for _k, v in order] + list(range(len(table))), dtype=np.int16)
    flag_meanings = " ".join([k for k, _v in order] + [f"A{i}_{d.kind}" for i, d in enumerate(table)])
    return (dims, np.asarray(values).reshape(shape).astype(np.int16),
            {"units": "1", "long_name": long_name, "flag_values": flag_values, "flag_meanings": flag_meanings})


def _assemble(system: System, config: dict, results: dict) -> xr.Dataset:
    grid = Grid.from_dict(config["grid"])
    prob = SystemProblem(system, grid, tol=float(config["tol"]))
    n = int(np.prod([a[2] for a in config["axes"].values()]))
    outcome, table, _first = assemble_table(prob, results, np.zeros(n, dtype=np.int64), 1.0)
    axes = config["axes"]
    dims = tuple(axes)
    shape = tuple(int(a[2]) for a in axes.values())
    labels = prob.labels()
    data = {
        "outcome": _outcome(labels, table, outcome, dims, shape,
                            "attractor id (>= 0, see dimension attractor) or negative label"),
        "assignment_time": (dims, np.asarray(results["t_assign"]).reshape(shape), {
            "units": system.time_units,
            "long_name": "time at which the run was assigned to an attractor or labelled"}),
        **_table(system, prob, table, outcome),
    }
    coords = _coordinates(system, prob, axes, len(table))
    counts = ", ".join(f"{int(np.sum(outcome == v))} {k}" for k, v in labels.items())
    rejection = np.asarray(results["rejection"]).astype(np.int8)
    reasons = SystemProblem.rejection_reasons
    why = ", ".join(f"{int(np.sum(rejection == i + 1))} {r}" for i, r in enumerate(reasons)
                    if np.any(rejection == i + 1))
    message = (f"{system.name}: {n} runs, {len(table)} attractor(s) (" + ", ".join(
        f"A{i} {d.kind} {np.mean(outcome == i):.3g}" for i, d in enumerate(table)) + f"); {counts}"
        + (f" (last candidate: {why})" if why else ""))
    undecided = int(np.sum(outcome == labels["undecided"]))
    status = "partial" if np.any(outcome == labels["failed"]) else "completed"
    data["rejection"] = (dims, rejection.reshape(shape), flag_attrs(
        "why the last attractor candidate of an undecided run failed its check (0: none)",
        {"none": 0, **{r: i + 1 for i, r in enumerate(reasons)}}))
    attrs = make_attrs("basins", config, status, message, **system.attrs(np.asarray(config["pars"])),
                       swept=" ".join(dims), undecided=undecided, volume_test=config.get("volume_test", ""))
    return xr.Dataset(data, coords=coords, attrs=attrs)


def conservative_chunk(system: System, config: dict, start: int, stop: int) -> dict:
    """Points [start, stop) of a conservative flow's map (module-level: a dask worker runs it)."""
    prob = SystemProblem(system, Grid.from_dict(config["grid"]), tol=float(config["tol"]))
    x0 = _initial_states(system, config["state"], config["axes"], start, stop)
    runs = conservative.sample_runs(prob, RecurrenceSettings(**config["recurrence"]), x0, np.asarray(config["pars"]),
                                    int(config["batch_size"]))
    return {"outcome": runs.outcome, "end_time": runs.end_time, "divergence": runs.divergence, "error": runs.error,
            **{f"level_{k}": runs.level[i] for i, k in enumerate(system.integrals)},
            **{f"drift_{k}": runs.drift[i] for i, k in enumerate(system.integrals)}}


def _assemble_conservative(system: System, config: dict, results: dict) -> xr.Dataset:
    """No attractors: per start the outcome (bounded, left_grid, ...), the end of its run, its mean divergence and
    the levels of the first integrals at the start (:mod:`.conservative`); the attractor table is empty."""
    prob = SystemProblem(system, Grid.from_dict(config["grid"]), tol=float(config["tol"]))
    axes = config["axes"]
    dims, shape = tuple(axes), tuple(int(a[2]) for a in axes.values())
    n = int(np.prod(shape))
    labels = conservative.conservative_labels(prob)
    outcome = np.asarray(results["outcome"])
    rate = system.per_time()
    data = {
        "outcome": _outcome(labels, [], outcome, dims, shape,
                            "how the run ended (a conservative flow has no attractors)"),
        "assignment_time": (dims, np.asarray(results["end_time"]).reshape(shape), {
            "units": system.time_units, "long_name": "time at which the run ended (the horizon if bounded)"}),
        **_table(system, prob, [], outcome),
    }
    decided = np.isfinite(np.asarray(results["divergence"]))
    for name, key, long_name in (("divergence_mean", "divergence", "mean divergence tr(df/dx) over the run's "
                                  "second half (fill 0: too short)"),
                                 ("divergence_error", "error",
                                  "its error: the log volume's range about its chord / the time")):
        data[name] = (dims, np.where(decided, np.asarray(results[key]), 0.0).reshape(shape),
                      {"units": rate, "long_name": long_name})
    data["divergence_decided"] = (dims, decided.astype(np.int8).reshape(shape), flag_attrs(
        "whether the run was long enough for its mean divergence (two correlation times per block)",
        {"too_short": 0, "decided": 1}))
    coords = _coordinates(system, prob, axes, 0)
    if system.integrals:
        names = tuple(system.integrals)
        units = ["1"] * len(names)
        data["integral_level"] = (dims + ("integral",), np.stack([np.asarray(results[f"level_{k}"]) for k in names],
                                                                 axis=-1).reshape(*shape, len(names)),
                                  mixed_units("level of the first integral at the start", "integral"))
        data["integral_drift"] = (dims + ("integral",), np.stack([np.asarray(results[f"drift_{k}"]) for k in names],
                                                                 axis=-1).reshape(*shape, len(names)),
                                  mixed_units("largest |change| of the first integral along the run", "integral"))
        coords.update(label_coordinates("integral", names, units, "first integral of the system"))
    counts = ", ".join(f"{int(np.sum(outcome == v))} {k}" for k, v in labels.items())
    levels = "".join(f"; {k} from {np.min(results[f'level_{k}']):.6g} to {np.max(results[f'level_{k}']):.6g} "
                     f"(drift <= {np.max(results[f'drift_{k}']):.1g})" for k in system.integrals)
    message = (f"{system.name}: conservative flow, no attractors ({config['volume_test']}); {n} runs: {counts}"
               + levels)
    attrs = make_attrs("basins", config, "conservative", message, **system.attrs(np.asarray(config["pars"])),
                       swept=" ".join(dims), undecided=0, volume_test=config["volume_test"])
    return xr.Dataset(data, coords=coords, attrs=attrs)


def basins(system: System, grid: Grid, axes: dict, *, state=None, pars=None, horizon: float = 100.0,
           recurrence: dict | None = None, tol: float = TOL, batch_size: int = 4, chunk_size: int = 256,
           output=None, threads: int | None = None, scheduler=None, progress: bool = True) -> xr.Dataset:
    """Basins of attraction of ``system``, found by recurrences in ``grid`` (a
    :class:`~tippedisk_analysis.dynamics.attractors.Grid` over states or observables), over one or two initial
    states ``axes`` ({state name: (start, stop, n)}), the other states at ``state`` (default zeros), parameters
    ``pars`` (default the system's).

    What to choose:

    * ``grid``: its coordinates should tell the attractors apart (a forced system: its phase, e.g. both u and w of a
      phase oscillator); where they miss states, attractors that cross in the projection share cells and a run
      is assigned by cells only where its full state is near the attractor's (:mod:`.confirm`), which costs
      more runs that locate and describe; its box must hold them (a run
      outside it for ``consecutive_lost_steps`` samples is ``left_grid``), and its cells must be finer than the
      distance between them (two sets closer than ``merge_distance`` = 1.5 cells are one attractor);
    * ``axes``: the starts (n per axis); they need not lie in the grid;
    * ``horizon``: the longest run, in the system's time unit: several of its slowest periods or transients
      (a run not decided by then is ``undecided``, with the reason of its last candidate); the volume test below
      needs four pairs of correlation times of the divergence in the second half of a run;
    * ``recurrence``: fields of :class:`~tippedisk_analysis.dynamics.attractors.RecurrenceSettings`: ``dt`` the
      sampling step (several samples per cell crossed), ``consecutive_recurrences`` and ``attractor_locate_steps``
      (the window, ``attractor_locate_steps`` dt: what a candidate is judged on);
    * ``tol``: the Taylor tolerance of the runs.

    Attractors are compared as sets (:mod:`.sets`): closed orbits by their curve and period, irregular sets by
    their points, equilibria by their point; the dataset stores each attractor's points (``attractor_set``).
    First a volume test (:mod:`.conservative`) runs a few probes: where the mean divergence tr(df/dx) is zero within
    its error the flow preserves phase-space volume and has no attractors: the status is ``conservative``, the
    attractor table is empty and each start gets how its run ended (``bounded``, ``left_grid``, ...), its mean
    divergence and the levels of the System's first integrals at the start. Otherwise the status is ``completed``
    (``partial`` where runs failed)."""
    if not 1 <= len(axes) <= 2:
        raise ParameterError("basins need one or two initial-state ranges, e.g. {'u1': (0, 1, 64)}")
    axes = {name: [float(a), float(b), int(n)] for name, (a, b, n) in axes.items()}
    for name, (a, b, n) in axes.items():
        system.state_index(name)
        if not (math.isfinite(a) and math.isfinite(b) and a < b and n >= 2):
            raise ParameterError(f"range of {name} = ({a:g}, {b:g}, {n}): give start < stop and n >= 2")
    state = np.zeros(system.n) if state is None else np.asarray(state, dtype=float)
    settings = RecurrenceSettings(**{**(recurrence or {}), "horizon": float(horizon)})
    config = {"system": system.name, "system_key": system.key, "axes": axes, "state": list(map(float, state)),
              "pars": list(map(float, system.with_pars(pars))), "grid": grid.to_dict(), "tol": float(tol),
              "batch_size": int(batch_size), "recurrence": settings.to_dict()}
    prob = SystemProblem(system, grid, tol=tol)
    variables = ("att_key", "t_assign", "attractor_distance", *column_names(prob),
                 *(f"final_{n}" for n in system.state_names), "rejection", *set_names(prob))
    n_points = int(np.prod([a[2] for a in axes.values()]))
    volume = conservative.volume_test(prob, settings, axes, state, np.asarray(config["pars"]), int(batch_size))
    config["volume_test"] = volume.message
    if volume.conservative:
        names = ("outcome", "end_time", "divergence", "error", *(f"{w}_{k}" for w in ("level", "drift")
                                                                 for k in system.integrals))
        sweep = sweeps.Sweep(f"runs of {system.name}", config, n_points, int(chunk_size), names,
                             functools.partial(conservative_chunk, system),
                             functools.partial(_assemble_conservative, system, config),
                             functools.partial(_problem(system, grid, float(tol)).integrator, int(batch_size)),
                             bytes_per_point=8.0 * (len(names) + 4), seconds_per_point=1e-4 * horizon)
        return sweeps.run_sweep(sweep, output=output, threads=threads, scheduler=scheduler, progress=progress)
    sweep = sweeps.Sweep(f"basins of {system.name}", config, n_points, int(chunk_size), variables,
                         functools.partial(basin_chunk, system), functools.partial(_assemble, system, config),
                         functools.partial(_problem(system, grid, float(tol)).integrator, int(batch_size)),
                         bytes_per_point=8.0 * (len(variables) + 4), seconds_per_point=1e-4 * horizon)
    return sweeps.run_sweep(sweep, output=output, threads=threads, scheduler=scheduler, progress=progress)
