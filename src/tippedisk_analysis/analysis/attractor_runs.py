"""The tippedisk's attractors over many runs: runs of a sweep chunk mapped to attractors
(:class:`.attractor_problem.TippediskProblem`), per-point results, the table of attractors with its
physical labels, and the one-line summary. Used by basins, basin fractions and outcome maps."""

from __future__ import annotations

import functools
import math

import numpy as np

from ..defaults import MAP_TOL
from ..dynamics import attractors as at
from ..dynamics.datasets import label_coordinates, mixed_units
from ..models import ode
from ..models.reduced import STATE_NAMES as REDUCED_NAMES
from ..models.reduced import STATE_UNITS
from ..models.variables import FINAL_STATE_VARIABLES
from . import stationary as st
from .attractor_problem import (DEFAULT_RECURRENCE, EXTRA_NAMES, KINDS, MODEL, PROJECTION, PROJECTION_UNITS,
                                TippediskProblem, default_grid, evaluate_observables, integrator, observables)

# ------------------------------------------------------------------ runs of many points (sweeps)
MATCH_THRESHOLD = 1.0  # TippediskProblem.distance: alpha_dot cells between stable segments; cells otherwise


@functools.lru_cache(maxsize=8)
def problem(tol: float = MAP_TOL) -> TippediskProblem:
    return TippediskProblem(tol)


def labels() -> dict[str, int]:
    """Negative labels of runs without an attractor: undecided, left_grid, failed, fell, lift_off."""
    return at.Problem.labels(TippediskProblem.__new__(TippediskProblem))


def recurrence_settings(horizon: float, recurrence: dict | None = None) -> at.RecurrenceSettings:
    return at.RecurrenceSettings(**{**DEFAULT_RECURRENCE, **(recurrence or {}), "horizon": float(horizon)})


POINT_VARIABLES = {
    # name: (dtype, units, long_name); per run, at the time it was decided (t_final)
    "t_final": (float, "s", "time the run was decided: assigned to an attractor, fell, lifted off, or the horizon"),
    "inversion_time": (float, "s", "first upward crossing of gamma = 0 before t_final (fill -1: none)"),
    "fall_time": (float, "s", "time the tilt reached fall_angle (fill -1: did not fall)"),
    "lift_off_time": (float, "s", "time lambda_N fell through 0, ending the run (fill -1: the contact held)"),
    "valid": (np.int8, "1", "1: lambda_N > 0 until t_final, 0: it would lift off (the run ended there)"),
    "attractor_distance": (float, "1", "equilibria: distance (grid cells, max-norm) of the final state from the "
                                       "family member at its alpha_dot in the attractor's Omega interval (fill -1)"),
    **FINAL_STATE_VARIABLES,
}


def run_points(x0, pars, groups, *, tol: float, batch_size: int, horizon: float, recurrence: dict | None,
               key_base: int) -> dict[str, np.ndarray]:
    """Map initial states (11, N) of ODE Model 1 to attractors; per-point arrays for a sweep chunk
    (:data:`POINT_VARIABLES`, the core's ``att_*`` description columns, ``att_key``, ``t_assign``)."""
    prob = problem(float(tol))
    res = at.map_points(prob, recurrence_settings(horizon, recurrence), x0, pars, groups, int(batch_size))
    out = at.chunk_result(prob, res, key_base)
    lab = prob.labels()
    o = evaluate_observables(res.final_states, pars)
    fell = res.labels == lab["fell"]
    lifted = res.labels == lab["lift_off"]
    inv = res.event_times["inversion"]
    out.update({
        "t_final": res.t_assign,
        "inversion_time": np.where(np.isfinite(inv), inv, -1.0),
        "fall_time": np.where(fell, res.t_assign, -1.0),
        "lift_off_time": np.where(lifted, res.t_assign, -1.0),
        "valid": (~lifted).astype(np.int8),
        "E_tot_final": o["E_tot"], "E_kin_final": o["E_kin"], "beta_final": o["beta"],
        "gamma_final": res.final_states[MODEL.state_names.index("gamma")], "alpha_dot_final": o["alpha_dot"],
        "z_S_final": o["z_S"],
    })
    for name, v in out.items():  # never a NaN (failed runs): 0
        if v.dtype.kind == "f":
            out[name] = np.where(np.isfinite(v), v, 0.0)
    return out


def chunk_variables() -> tuple[str, ...]:
    prob = TippediskProblem.__new__(TippediskProblem)
    prob.grid = default_grid()
    return ("att_key", "t_assign", *at.column_names(prob), *POINT_VARIABLES)


def outcome_flags(table: list) -> tuple[np.ndarray, str]:
    """flag_values and flag_meanings of ``outcome``: the negative labels, then one name per attractor
    (``A<id>_<kind>[_<branch>]``)."""
    lab = labels()
    values = sorted(lab.values()) + list(range(len(table)))
    meanings = [k for k, _ in sorted(lab.items(), key=lambda kv: kv[1])]
    for i, d in enumerate(table):
        name = f"A{i}_{d.kind}"
        b = d.extra.get("branch", 0.0)
        if d.kind in ("equilibrium", "wobbling") and np.isfinite(b) and b != 0:
            name += "_inverted" if b > 0 else "_noninverted"
        meanings.append(name)
    return np.array(values, dtype=np.int16), " ".join(meanings)


def attractor_table(cols: dict, groups, threshold: float = MATCH_THRESHOLD):
    """Global attractor ids of the points and the table variables (dim ``attractor``) from merged chunk columns.

    Returns (outcome (N,) int16, data variables {name: (dims, values, attrs)}, table [Description])."""
    prob = TippediskProblem.__new__(TippediskProblem)
    TippediskProblem.__init__(prob)
    outcome, table, _first = at.assemble_table(prob, cols, np.asarray(groups), threshold)
    n = len(table)
    ex = {k: np.array([d.extra.get(k, math.nan) for d in table], dtype=float) for k in EXTRA_NAMES}
    is_eq = np.array([d.kind == "equilibrium" for d in table], dtype=bool)

    def fill(values, where, value):
        values = np.asarray(values, dtype=float)
        return np.where(where & np.isfinite(values), values, value)

    counts = np.array([int(np.sum(outcome == i)) for i in range(n)], dtype=np.int64)
    flag_kind = {"flag_values": np.arange(len(KINDS), dtype=np.int8), "flag_meanings": " ".join(KINDS)}
    dv = {
        "attractor_kind": (("attractor",), np.array([KINDS.index(d.kind) for d in table], dtype=np.int8),
                           {"units": "1", "long_name": "kind of attractor", **flag_kind}),
        "attractor_branch": (("attractor",), fill(ex["branch"], np.ones(n, bool), 0.0).astype(np.int8),
                             {"units": "1", "long_name": "spin branch: +1 inverted, -1 noninverted, 0 none",
                              "flag_values": np.array([-1, 0, 1], dtype=np.int8),
                              "flag_meanings": "noninverted none inverted"}),
        "attractor_omega": (("attractor",), fill(ex["omega"], np.ones(n, bool), 0.0),
                            {"units": "rad s-1", "long_name": "spin rate alpha_dot of the representative "
                                                              "(equilibria) or its mean over the locate window"}),
        "attractor_omega_min": (("attractor",), fill(ex["omega_min"], np.ones(n, bool), 0.0),
                                {"units": "rad s-1", "long_name": "smallest alpha_dot: of the equilibria merged "
                                                                  "into a family segment, else over the window"}),
        "attractor_omega_max": (("attractor",), fill(ex["omega_max"], np.ones(n, bool), 0.0),
                                {"units": "rad s-1", "long_name": "largest alpha_dot (as omega_min)"}),
        "attractor_segment_min": (("attractor",), fill(ex["segment_min"], is_eq, 0.0),
                                  {"units": "rad s-1", "long_name": "lower end of the connected segment of linearly "
                                                                    "stable spins (equilibria; 0 otherwise)"}),
        "attractor_segment_max": (("attractor",), fill(ex["segment_max"], is_eq, 0.0),
                                  {"units": "rad s-1", "long_name": "upper end of that segment (equilibria)"}),
        "attractor_period": (("attractor",), np.array([d.period for d in table], dtype=float),
                             {"units": "s", "long_name": "period (periodic: refined; rolling: time per turn "
                                                         "of gamma; fill -1: none)"}),
        "attractor_amplitude": (("attractor",), np.array([d.amplitude for d in table], dtype=float),
                                {"units": "rad", "long_name": "half peak-to-peak of gamma (rolling: of beta)"}),
        "attractor_max_real_eig": (("attractor",), fill(ex["max_real_eig"], is_eq, 0.0),
                                   {"units": "s-1", "long_name": "largest real part of the nontrivial eigenvalues "
                                                                 "(equilibria; 0 for other kinds)"}),
        "attractor_stationary_deviation": (("attractor",), fill(ex["stationary_deviation"], is_eq, -1.0),
                                           {"units": "1", "long_name": "max |x* - closed-form stationary solution| "
                                                                       "of the Newton-refined equilibrium (fill -1)"}),
        "attractor_energy_drift": (("attractor",), fill(ex["energy_drift"], np.ones(n, bool), 0.0),
                                   {"units": "s-1", "long_name": "(E(end) - E(start)) / (mean E * window) over "
                                                                 "the locate window (0 for equilibria)"}),
        "attractor_radius": (("attractor",), np.array([d.radius for d in table], dtype=float),
                             {"units": "1", "long_name": "largest distance (grid cells, max-norm) of the "
                                                         "attractor's cells from its centroid"}),
        "attractor_state": (("attractor", "reduced_state"),
                            np.array([d.representative for d in table], dtype=float).reshape(n, len(REDUCED_NAMES)),
                            mixed_units("representative reduced state (a state on the attractor; equilibria: the "
                                        "Newton-refined spin)", "reduced_state")),
        "attractor_centroid": (("attractor", "projection"),
                               np.array([d.centroid for d in table], dtype=float).reshape(n, len(PROJECTION)),
                               mixed_units("mean of the observed coordinates on the attractor", "projection")),
        "attractor_n_points": (("attractor",), counts, {"units": "1", "long_name": "runs assigned to it"}),
    }
    return outcome.astype(np.int16), dv, table


def table_coords() -> dict:
    return {**label_coordinates("reduced_state", REDUCED_NAMES, [STATE_UNITS[n] for n in REDUCED_NAMES],
                                "reduced state (analysis/reduced)"),
            **label_coordinates("projection", PROJECTION, [PROJECTION_UNITS[n] for n in PROJECTION],
                                "observed coordinates of the cell grid")}


def warm_up(tol: float, batch_size: int) -> None:
    """Compile (or load from heyoka's cache) what the threads share, once, before they start."""
    import scipy.optimize  # noqa: F401 (stable_segment; imported once, not inside the threads)

    integrator(float(tol), int(batch_size))
    observables()
    from .reduced import evaluate, jacobian

    x = st.stationary_state("inverted", [30.0])
    evaluate(x, ode.parameter_vector())
    jacobian(x, ode.parameter_vector())


def summary(outcome, table: list, n: int, horizon: float) -> str:
    """One line: counts per label and per kind of attractor."""
    outcome = np.asarray(outcome)
    parts = [f"{n} runs, horizon {horizon:g} s"]
    for name, v in sorted(labels().items(), key=lambda kv: -kv[1]):
        parts.append(f"{int(np.sum(outcome == v))} {name}")
    kinds: dict[str, int] = {}
    for i, d in enumerate(table):
        kinds[d.kind] = kinds.get(d.kind, 0) + int(np.sum(outcome == i))
    parts += [f"{c} {k}" for k, c in kinds.items()]
    n_transient = sum(d.kind in ("rolling", "wobbling") for d in table)
    return ", ".join(parts) + (f"; table: {len(table) - n_transient} attractor(s) and {n_transient} transient "
                               "state(s) (rolling, wobbling: energy still decreasing)")
