"""The tippedisk as a problem of the recurrence core (:mod:`.attractors`): attractors of ODE Model 1.

Runs integrate ODE Model 1 (Sect. 4.1, the full Euler-angle model of
:mod:`tippedisk_analysis.models.ode`) in heyoka batch mode and are observed through the symmetry-invariant
projection (beta, gamma mod 2 pi, alpha_dot, beta_dot, gamma_dot): x, y, alpha are cyclic, so a spinning
solution (a relative equilibrium of the full model) is a fixed point of the projection, and the
representative states of the table are reduced states (:mod:`.reduced`, (beta, gamma, u_x, u_y,
omega_x, omega_y, omega_z)).

Terminal labels: ``fell`` (the tilt reached the fall angle, the Euler-angle singularity ahead) and
``lift_off`` (lambda_N fell through 0: the bilateral contact model stops being valid, so the run ends
there). Non-terminal: the first upward crossing of gamma = 0 (``inversion``).

Kinds: ``equilibrium`` (a spinning solution: Newton on the reduced system from the run's last state with
alpha_dot pinned, :func:`.stationary.solve`; branch from gamma; accepted only if it is the closed-form
stationary solution to 1e-6 and linearly stable, :func:`.stability.spectrum`, else the candidate is a
transient and the run searches on); ``rolling`` (gamma turned by at least 2 pi over the locate window:
the disk rolls on its rim); ``periodic`` and ``irregular`` from the generic description.

The spinning solutions form one-parameter families in Omega (docs/stability.md): cells see one
attractor per family segment. Equilibria of one branch whose Omega intervals touch (gap <= one
alpha_dot cell) are one attractor: a segment [omega_min, omega_max] of the family. All ``rolling``
candidates of one parameter point are one (pseudo-)attractor: rim rolling drifts slowly (energy decays,
``energy_drift`` < 0) and different runs join it at different stages.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
import xarray as xr

from ..compilation import compiling
from ..defaults import BATCH_SIZE, FALL_ANGLE, MAP_TOL, SLIP_SMOOTHING
from ..errors import ParameterError
from ..models import ode
from ..parameters import Disk, Friction, InitialState, Setup, to_dict
from ..ranges import parse_range
from ..results import describe as describe_units
from ..results import make_attrs
from ..dynamics import attractors as at
from ..dynamics import sweeps
from . import stability
from . import stationary as st
from .reduced import STATE_NAMES as REDUCED_NAMES
from .reduced import full_from_reduced, reduced_from_full

MODEL = ode.EULER
PROJECTION = ("beta", "gamma", "alpha_dot")  # names the observe() cfunc can give: + beta_dot, gamma_dot
KINDS = ("equilibrium", "periodic", "irregular", "rolling", "wobbling")
DRIFT_TOL = 1e-5  # 1/s: |relative energy change rate| above which an oscillation is a dissipating transient
EXTRA_NAMES = ("branch", "omega", "omega_min", "omega_max", "max_real_eig", "stationary_deviation",
               "energy_drift", "segment_min", "segment_max")
SEGMENT_SCAN = (60.0, 0.5)  # rad/s: half-width and step of the scan for the stable segment, edges then refined
STATIONARY_ATOL = 1e-6  # an equilibrium must equal the closed-form stationary solution to this (max-norm)

DEFAULT_GRID = {
    # name: (lower, upper, cells, periodic); cell widths pi/32 rad, pi/12 rad, 4 rad/s, shifted by half a cell
    # so that the spins (beta = pi/2, gamma = -+pi/2) lie at cell centres, not on cell boundaries
    "beta": (-math.pi / 64, math.pi + math.pi / 64, 33, False),
    "gamma": (-math.pi - math.pi / 24, math.pi - math.pi / 24, 24, True),
    "alpha_dot": (-300.0, 300.0, 150, False),
}
DEFAULT_RECURRENCE = {"dt": 0.05, "consecutive_recurrences": 40, "attractor_locate_steps": 100,
                      "consecutive_attractor_steps": 3, "consecutive_lost_steps": 20}


def default_grid() -> at.Grid:
    names = tuple(DEFAULT_GRID)
    lo, hi, n, per = zip(*DEFAULT_GRID.values())
    return at.Grid(names, lo, hi, n, per)


@functools.lru_cache(maxsize=8)
def integrator(tol: float, batch_size: int):
    """Batch integrator of ODE Model 1: terminal events fall, lift-off; nt event: gamma = 0 upwards."""
    import heyoka as hy

    variables, sys, fall, outputs = ode.system(MODEL)
    gamma = variables[MODEL.state_names.index("gamma")]
    lambda_N = outputs[ode.OUTPUT_NAMES.index("lambda_N")]
    B = int(batch_size)
    x0 = ode.initial_state_vector(MODEL, ode.Setup(), ode.InitialState())
    pars = ode.parameter_vector()
    neg, pos = hy.event_direction.negative, hy.event_direction.positive
    with compiling(f"the ODE Model 1 batch integrator ({B} lanes, tol {tol:g})"):
        return hy.taylor_adaptive_batch(
            sys, np.repeat(x0[:, None], B, axis=1), pars=np.repeat(pars[:, None], B, axis=1), tol=tol,
            t_events=[hy.t_event_batch(fall, direction=neg), hy.t_event_batch(lambda_N, direction=neg)],
            nt_events=[hy.nt_event_batch(gamma, at.FirstTime(), direction=pos)])


@functools.lru_cache(maxsize=1)
def observables():
    """cfunc of (beta, gamma, alpha_dot, beta_dot, gamma_dot, E_tot, lambda_N, z_S, E_kin) over the model state."""
    import heyoka as hy

    variables, _sys, _fall, outputs = ode.system(MODEL)
    o = dict(zip(ode.OUTPUT_NAMES, outputs))
    return hy.cfunc([o["beta"], variables[MODEL.state_names.index("gamma")], o["alpha_dot"], o["beta_dot"],
                     o["gamma_dot"], o["E_kin"] + o["E_pot"], o["lambda_N"], o["z_S"], o["E_kin"]], variables)


def evaluate_observables(states, pars) -> dict[str, np.ndarray]:
    cf = observables()
    states = np.ascontiguousarray(np.asarray(states, dtype=float).reshape(len(MODEL.state_names), -1))
    pars = np.asarray(pars, dtype=float)
    if pars.ndim == 1:
        pars = np.repeat(pars[:, None], states.shape[1], axis=1)
    out = cf(states, pars=np.ascontiguousarray(pars[: cf.nparams]))
    names = ("beta", "gamma", "alpha_dot", "beta_dot", "gamma_dot", "E_tot", "lambda_N", "z_S", "E_kin")
    return dict(zip(names, out))


def reduced_of(states) -> np.ndarray:
    """Reduced states (7, N) of model states (11, N)."""
    x = np.asarray(states, dtype=float).reshape(len(MODEL.state_names), -1)
    i = {n: k for k, n in enumerate(MODEL.state_names)}
    return reduced_from_full(x[i["alpha"]], x[i["beta"]], x[i["gamma"]], x[i["x_dot"]], x[i["y_dot"]],
                             x[i["omega_x"]], x[i["omega_y"]], x[i["omega_z"]])


def stable_segment(branch: str, omega: float, pars) -> tuple[float, float]:
    """The connected interval of linearly stable spins of ``branch`` containing ``omega`` [rad/s]: a scan of
    the largest nontrivial eigenvalue real part (:func:`.stability.spectrum`) over SEGMENT_SCAN, its sign
    changes refined with brentq to 1e-9 rad/s; an end of the scan counts as an edge."""
    from scipy.optimize import brentq

    half, step = SEGMENT_SCAN
    grid = omega + np.arange(-half, half + 0.5 * step, step)
    grid = np.sort(np.append(grid, omega))
    mre = stability.spectrum(branch, grid, pars).max_real_eig
    k = int(np.searchsorted(grid, omega))
    if not mre[k] < 0:
        return omega, omega

    def f(w):
        return stability.max_real_eig(branch, w, pars)

    lo = k
    while lo > 0 and mre[lo - 1] < 0:
        lo -= 1
    hi = k
    while hi < len(grid) - 1 and mre[hi + 1] < 0:
        hi += 1
    a = grid[lo] if lo == 0 else brentq(f, grid[lo - 1], grid[lo], xtol=1e-9)
    b = grid[hi] if hi == len(grid) - 1 else brentq(f, grid[hi], grid[hi + 1], xtol=1e-9)
    return float(a), float(b)


def _wrap(angle):
    return (np.asarray(angle) + math.pi) % (2 * math.pi) - math.pi


class TippediskProblem(at.Problem):
    """ODE Model 1 for the recurrence core (module docstring)."""

    state_names = MODEL.state_names
    terminal_labels = ("fell", "lift_off")
    nt_event_names = ("inversion",)
    kinds = KINDS
    extra_names = EXTRA_NAMES
    amplitude_index = 1  # gamma

    def __init__(self, tol: float = MAP_TOL, grid: at.Grid | None = None):
        self.tol = float(tol)
        self.grid = grid or default_grid()
        self._i = {n: k for k, n in enumerate(MODEL.state_names)}
        self._alpha_dot_width = float(self.grid.widths[list(self.grid.names).index("alpha_dot")]) \
            if "alpha_dot" in self.grid.names else 2.0

    # -- contract
    def integrator(self, batch_size: int):
        return integrator(self.tol, int(batch_size))

    def observe(self, states, pars):
        o = evaluate_observables(states, pars)
        return np.array([o[name] for name in self.grid.names])


    @property
    def representative_names(self):
        return REDUCED_NAMES

    def represent(self, state):
        red = reduced_of(state)[:, 0]
        red[1] = _wrap(red[1])
        return red

    def describe(self, cand: at.Candidate, core: at.DescribeContext):
        o = evaluate_observables(cand.states, cand.pars)
        t = cand.times
        E = o["E_tot"]
        span = max(float(t[-1] - t[0]), 1e-300)
        drift = float((E[-1] - E[0]) / (np.mean(np.abs(E)) * span)) if np.mean(np.abs(E)) > 0 else 0.0
        g = cand.states[self._i["gamma"]]
        turns = (g[-1] - g[0]) / (2 * math.pi)
        extra = {"branch": 0.0, "omega": float(np.mean(o["alpha_dot"])), "omega_min": float(np.min(o["alpha_dot"])),
                 "omega_max": float(np.max(o["alpha_dot"])), "max_real_eig": math.nan,
                 "stationary_deviation": math.nan, "energy_drift": drift}
        if abs(turns) >= 1.0:  # rolls on its rim
            grid = self.grid
            centroid = at._circular_mean(grid, cand.observed)
            half = len(t) // 2
            spread = 0.5 * np.ptp(grid.unwrap(cand.observed[:, half:]), axis=1) * grid.widths
            period = 2 * math.pi * span / abs(g[-1] - g[0])  # time per turn of gamma
            amplitude = 0.5 * float(np.ptp(o["beta"]))  # tilt oscillation
            return at.Description("rolling", self.represent(cand.states[:, -1]), centroid, spread, amplitude,
                                  period, extra)
        settings, grid = core.settings, self.grid
        a1, a2 = at.spreads(grid, cand.observed)
        if at.growing(settings, a1, a2):
            return None
        half = len(t) // 2
        if at.converging(settings, a1, a2):
            refined = self.refine_equilibrium(cand.states[:, -1], cand.pars, core)
            if refined is not None:
                return at.equilibrium_description(self, cand, refined)
        elif abs(drift) <= DRIFT_TOL:  # no measurable dissipation: a periodic orbit? (LaSalle says none exist)
            desc = at.describe(self, cand, core)
            if desc is not None and desc.kind != "equilibrium":
                desc.extra = extra
            return desc
        # a dissipating oscillation about the spin family, or near a spin that Newton + stability do not
        # accept (an unstable member, slowly approached or left): a transient
        extra["branch"] = float(np.sign(np.mean(np.sin(_wrap(g)))))
        return at.Description("wobbling", self.represent(cand.states[:, -1]), at._circular_mean(grid, cand.observed),
                              0.5 * np.ptp(grid.unwrap(cand.observed[:, half:]), axis=1) * grid.widths,
                              0.5 * float(np.ptp(g[half:])), -1.0, extra, transient=True)

    def refine_equilibrium(self, state, pars, core):
        """Newton on the reduced system (alpha_dot pinned), then the closed-form check and the stability."""
        red = reduced_of(state)[:, 0]
        omega = float(evaluate_observables(state, pars)["alpha_dot"][0])
        sol = st.solve(red, omega, pars)
        if not sol.converged:
            return None
        x = sol.state.copy()
        x[1] = _wrap(x[1])
        branch = "inverted" if math.sin(x[1]) > 0 else "noninverted"
        dev = float(np.max(np.abs(x - st.stationary_state(branch, omega)[:, 0])))
        if not dev <= STATIONARY_ATOL:
            return None
        eig = float(stability.spectrum(branch, [omega], pars).max_real_eig[0])
        if eig > 0:  # linearly unstable: the run passes a saddle slowly; it is a transient
            return None
        segment = stable_segment(branch, omega, pars)
        full = full_from_reduced(x)
        return {"state": full, "branch": st.branch_sign(branch), "omega": omega, "omega_min": omega,
                "omega_max": omega, "max_real_eig": eig, "stationary_deviation": dev, "energy_drift": 0.0,
                "segment_min": segment[0], "segment_max": segment[1]}

    def same_attractor(self, a, b):
        if a.kind != b.kind:
            return False
        if a.kind == "equilibrium":  # one connected segment of stable spins
            return a.extra["branch"] == b.extra["branch"] and self._gap(a, b) <= 0.0
        if a.kind == "rolling":
            return True
        if a.kind == "wobbling":
            return a.extra["branch"] == b.extra["branch"]
        return super().same_attractor(a, b)

    def distance(self, a, b):
        if a.kind != b.kind:
            return math.inf
        if a.kind == "equilibrium":
            return self._gap(a, b) / self._alpha_dot_width if a.extra["branch"] == b.extra["branch"] else math.inf
        if a.kind == "rolling":
            return 0.0
        if a.kind == "wobbling":
            return 0.0 if a.extra["branch"] == b.extra["branch"] else math.inf
        return super().distance(a, b)

    @staticmethod
    def _gap(a, b) -> float:
        """Gap between the stable segments of two equilibria [rad/s] (0: they overlap)."""
        return max(0.0, max(a.extra["segment_min"], b.extra["segment_min"]) - min(a.extra["segment_max"],
                                                                                 b.extra["segment_max"]))

    def combine(self, members):
        first = members[0]
        if first.kind not in ("equilibrium", "rolling", "wobbling"):
            return first
        extra = dict(first.extra)
        for k, fn in (("omega_min", min), ("omega_max", max), ("segment_min", min), ("segment_max", max)):
            vals = [m.extra[k] for m in members if np.isfinite(m.extra.get(k, math.nan))]
            extra[k] = fn(vals) if vals else math.nan
        for k in ("max_real_eig", "stationary_deviation"):
            vals = [m.extra[k] for m in members if np.isfinite(m.extra.get(k, math.nan))]
            extra[k] = max(vals) if vals else math.nan
        return at.Description(first.kind, first.representative, first.centroid, first.spread, first.amplitude,
                              first.period, extra, max(m.radius for m in members))

    def point_distance(self, desc, state, observed):
        """Equilibria: distance (cells) of the run's final state from the family member at its own alpha_dot
        (clamped to the attractor's Omega interval)."""
        if desc.kind != "equilibrium":
            return math.nan
        branch = "inverted" if desc.extra["branch"] > 0 else "noninverted"
        omega = min(max(float(observed[list(self.grid.names).index("alpha_dot")]) if "alpha_dot" in
                        self.grid.names else desc.extra["omega"], desc.extra["segment_min"]), desc.extra["segment_max"])
        member = st.stationary_state(branch, [omega])[:, 0]
        pars = ode.parameter_vector()  # the projection of a state does not depend on the parameters
        y_member = self.observe(full_from_reduced(member)[:, None], pars)
        return float(np.max(np.abs(self.grid.difference(observed, y_member[:, 0]))))


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
    "E_tot_final": (float, "J", "total energy at t_final"),
    "E_kin_final": (float, "J", "kinetic energy at t_final"),
    "beta_final": (float, "rad", "Euler angle beta at t_final"),
    "gamma_final": (float, "rad", "Euler angle gamma at t_final (unwrapped)"),
    "alpha_dot_final": (float, "rad s-1", "alpha_dot at t_final"),
    "z_S_final": (float, "m", "height of S at t_final"),
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
                            {"units": "SI", "long_name": "representative reduced state (a state on the attractor; "
                                                         "equilibria: the Newton-refined spin)"}),
        "attractor_centroid": (("attractor", "projection"),
                               np.array([d.centroid for d in table], dtype=float).reshape(n, len(PROJECTION)),
                               {"units": "SI", "long_name": "mean of the observed coordinates on the attractor"}),
        "attractor_n_points": (("attractor",), counts, {"units": "1", "long_name": "runs assigned to it"}),
    }
    return outcome.astype(np.int16), dv, table


def table_coords() -> dict:
    return {"reduced_state": ("reduced_state", list(REDUCED_NAMES), {"long_name": "reduced state (analysis/reduced)"}),
            "projection": ("projection", list(PROJECTION), {"long_name": "observed coordinates of the cell grid"})}


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



# --------------------------------------------------------------- basins over initial conditions
INITIAL = {
    # name: (units, long_name, InitialState field, Table 3 value)
    "omega": ("rad s-1", "initial spin Omega = alpha_dot(0)", "alpha_dot", 40.0),
    "beta0": ("rad", "initial inclination beta(0) (pi/2: upright)", "beta", 0.5 * math.pi),
    "dgamma0": ("rad", "gamma(0) + pi/2 (0: S straight below G)", "gamma", 0.1),
    "beta_dot0": ("rad s-1", "initial rate beta_dot(0)", "beta_dot", 0.0),
    "gamma_dot0": ("rad s-1", "initial rate gamma_dot(0) (Table 3: -alpha_dot cos beta, no spin about the "
                              "disk normal)", "gamma_dot", None),
}
PARAMETERS = {"eps": ("m s-1", "smoothing velocity eps of (2.29)"), "mu": ("1", "friction coefficient mu"),
              "e": ("m", "eccentricity e")}
CHUNK_SIZE = 256  # runs per stored chunk of basin sweeps (~1-2 s of work)
SPECIAL_ORDER = ("undecided", "left_grid", "failed", "fell", "lift_off")


def initial_state(setup: Setup, values: dict) -> np.ndarray:
    """Model state (11,) of initial values {INITIAL name: value} (the rest from Table 3)."""
    kw = {}
    for name, v in values.items():
        field = INITIAL[name][2]
        kw[field] = -0.5 * math.pi + float(v) if name == "dgamma0" else float(v)
    return ode.initial_state_vector(MODEL, setup, InitialState(**kw))


def _setup(base: dict, params: dict) -> Setup:
    """The stored setup with the parameters eps, mu, e set; e with what the disk holds fixed
    (Disk.with_eccentricity: A, B, C about G, or the drilled disk's hole moves)."""
    s = Setup(Disk(**base["disk"]), Friction(**base["friction"]), base["gravity"])
    fric = {k: float(v) for k, v in params.items() if k in ("eps", "mu")}
    disk = s.disk.with_eccentricity(float(params["e"])) if "e" in params else s.disk
    return dataclasses.replace(s, friction=dataclasses.replace(s.friction, **fric), disk=disk)


BYTES_PER_POINT = 8.0 * (len(chunk_variables()) + len(POINT_VARIABLES) + 4)
"""Memory of one run's results in a basin sweep (sweeps.MERGE_FACTOR covers the copies at the merge)."""
SECONDS_PER_RUN_SECOND = 1e-3
"""Work of one run per simulated second on one core, batch 4 (benchmarks/bench_attractors.py); the horizon
t_end bounds a run (most are assigned earlier), so estimates from it err on the long side."""


@dataclasses.dataclass(frozen=True)
class BasinConfig(sweeps.Grid):
    """Basins over (one or) two initial values at fixed parameters (stored in the dataset, checked on resume)."""

    axes: dict  # INITIAL name -> [start, stop, n]
    initial: dict = dataclasses.field(default_factory=dict)  # other INITIAL names -> value (default Table 3)
    parameters: dict = dataclasses.field(default_factory=dict)  # eps, mu, e -> value (default Tables 1-2, Sect. 6)
    t_end: float = 60.0  # maximum horizon
    tol: float = MAP_TOL
    fall_angle: float = FALL_ANGLE
    slip_smoothing: float = SLIP_SMOOTHING
    chunk_size: int = CHUNK_SIZE
    batch_size: int = BATCH_SIZE
    recurrence: dict | None = None
    setup: dict = dataclasses.field(default_factory=lambda: to_dict(Setup()))

    def __post_init__(self):
        if not self.axes or len(self.axes) > 2:
            raise ParameterError("basins need one or two initial-value ranges, e.g. --dgamma0 -3.1:3.1:256 "
                                 "--beta0 1.2:1.9:256")
        unknown = (set(self.axes) | set(self.initial)) - set(INITIAL)
        if unknown:
            raise ParameterError(f"unknown initial value(s) {sorted(unknown)}; give {', '.join(INITIAL)}")
        if set(self.axes) & set(self.initial):
            raise ParameterError(f"{sorted(set(self.axes) & set(self.initial))} given as a range and as a value; "
                                 "give one")
        if set(self.parameters) - set(PARAMETERS):
            raise ParameterError(f"unknown parameter(s) {sorted(set(self.parameters) - set(PARAMETERS))}; "
                                 f"give {', '.join(PARAMETERS)}")
        axes = {k: [float(v[0]), float(v[1]), int(v[2])] for k, v in self.axes.items()}
        for k, v in axes.items():
            parse_range(f"{v[0]!r}:{v[1]!r}:{v[2]}", k)
        object.__setattr__(self, "axes", axes)
        object.__setattr__(self, "initial", {k: float(v) for k, v in self.initial.items()})
        object.__setattr__(self, "parameters", {k: float(v) for k, v in self.parameters.items()})
        _validate_common(self)
        setup = self.physical_setup()
        for name, (a, b, _n) in axes.items():  # the ends of every range through the dataclasses
            for v in (a, b):
                initial_state(setup, {**self.initial, name: v})

    @property
    def grid_ranges(self) -> dict:
        return self.axes

    def physical_setup(self) -> Setup:
        return _setup(self.setup, self.parameters)

    def to_dict(self) -> dict:
        return {"model": MODEL.name, **dataclasses.asdict(self)}

    @classmethod
    def from_dict(cls, d: dict) -> BasinConfig:
        return cls(**{k: v for k, v in d.items() if k != "model"})


def _validate_common(cfg) -> None:
    if not (math.isfinite(cfg.t_end) and cfg.t_end > 0):
        raise ParameterError(f"t_end = {cfg.t_end!r} s must be positive; give the maximum horizon, e.g. 60")
    sweeps.check_run_settings(cfg)
    recurrence_settings(cfg.t_end, cfg.recurrence)
    _setup(cfg.setup, cfg.parameters)  # ParameterError naming the fix


def _basin_points(cfg: BasinConfig, start: int, stop: int):
    axes = cfg.axis_values()
    idx = np.unravel_index(np.arange(start, stop), cfg.shape)
    setup = cfg.physical_setup()
    x0 = np.empty((len(MODEL.state_names), stop - start))
    for j in range(stop - start):
        values = {**cfg.initial, **{name: axes[name][i[j]] for name, i in zip(axes, idx)}}
        x0[:, j] = initial_state(setup, values)
    return x0, ode.parameter_vector(setup, cfg.fall_angle, cfg.slip_smoothing)


def basin_chunk(config: BasinConfig | dict, start: int, stop: int) -> dict:
    """Points [start, stop) of a basin map (module-level: a dask worker runs it from the config alone)."""
    cfg = BasinConfig.from_dict(config) if isinstance(config, dict) else config
    x0, pars = _basin_points(cfg, start, stop)
    return run_points(x0, pars, np.zeros(stop - start, dtype=np.int64), tol=cfg.tol, batch_size=cfg.batch_size,
                      horizon=cfg.t_end, recurrence=cfg.recurrence, key_base=start)


def _point_data(dims, shape, results, outcome, table, reorder=None):
    """outcome, assignment_time and POINT_VARIABLES as data variables over ``dims``."""

    def values(v, dtype=None):
        v = np.asarray(v, dtype=dtype)
        if reorder is not None:
            out = np.empty_like(v)
            out[reorder] = v
            v = out
        return v.reshape(shape)

    flag_values, flag_meanings = outcome_flags(table)
    data = {"outcome": (dims, values(outcome), {
        "units": "1", "long_name": "attractor id (>= 0, see dimension attractor) or negative label",
        "flag_values": flag_values, "flag_meanings": flag_meanings,
        "classification": "recurrences in a cell grid (dynamics/attractors, analysis/basins.py)"})}
    data["assignment_time"] = (dims, values(results["t_assign"], float), {
        "units": "s", "long_name": "time at which the run was assigned to an attractor or labelled"})
    for name, (dtype, units, long_name) in POINT_VARIABLES.items():
        attrs = {"units": units, "long_name": long_name}
        if name.endswith("_time"):
            attrs["fill_value_meaning"] = "-1 s where the event did not happen"
        elif name == "valid":
            attrs.update(flag_values=np.array([0, 1], dtype=np.int8), flag_meanings="lift_off valid")
        data[name] = (dims, values(results[name], dtype), attrs)
    return data


def _fractions(outcome: np.ndarray, n_attractors: int) -> tuple[np.ndarray, np.ndarray]:
    """(fraction per attractor, fraction per SPECIAL_ORDER label) of a set of runs."""
    outcome = np.asarray(outcome).ravel()
    n = max(outcome.size, 1)
    lab = labels()
    return (np.array([np.sum(outcome == i) / n for i in range(n_attractors)]),
            np.array([np.sum(outcome == lab[name]) / n for name in SPECIAL_ORDER]))


def assemble_basins(cfg: BasinConfig, results: dict) -> xr.Dataset:
    outcome, table_vars, table = attractor_table(results, np.zeros(cfg.n_points, dtype=np.int64))
    axes = cfg.axis_values()
    dims = tuple(axes)
    data = _point_data(dims, cfg.shape, results, outcome, table)
    data.update(table_vars)
    frac, special = _fractions(outcome, len(table))
    data["basin_fraction"] = (("attractor",), frac, {"units": "1", "long_name": "share of the runs in the basin"})
    data["label_fraction"] = (("label",), special, {"units": "1", "long_name": "share of the runs with this label"})
    coords = {name: (name, values, {"units": INITIAL[name][0], "long_name": INITIAL[name][1]})
              for name, values in axes.items()}
    coords["attractor"] = ("attractor", np.arange(len(table)), {"long_name": "attractor id"})
    coords["label"] = ("label", list(SPECIAL_ORDER), {"long_name": "labels of runs without an attractor"})
    coords.update(table_coords())
    message = summary(outcome, table, cfg.n_points, cfg.t_end)
    status = "partial" if np.any(outcome == labels()["failed"]) else "completed"
    setup = cfg.physical_setup()
    ds = xr.Dataset(data, coords=coords, attrs=make_attrs(
        "basins", cfg.to_dict(), status, message, model=MODEL.name, paper_model=MODEL.paper_name,
        swept=" ".join(dims), t_end=cfg.t_end, eps=setup.friction.eps, mu=setup.friction.mu, e=setup.disk.e,
        fixed_initial=" ".join(f"{k}={v:g}" for k, v in cfg.initial.items())))
    return describe_units(ds)


def basin_sweep(cfg: BasinConfig) -> sweeps.Sweep:
    return sweeps.Sweep("basins", cfg.to_dict(), cfg.n_points, int(cfg.chunk_size), chunk_variables(), basin_chunk,
                        functools.partial(assemble_basins, cfg),
                        functools.partial(warm_up, float(cfg.tol), int(cfg.batch_size)),
                        bytes_per_point=BYTES_PER_POINT, seconds_per_point=SECONDS_PER_RUN_SECOND * cfg.t_end)


def basins(axes: dict, *, output=None, scheduler=None, threads: int | None = None, progress: bool = True,
           overwrite: bool = False, **options) -> xr.Dataset:
    """Basins of attraction over ``axes`` ({INITIAL name: (start, stop, n)}, one or two) at fixed parameters.

    Options: the fields of :class:`BasinConfig` (initial, parameters, t_end, tol, ...). ``output``: netCDF
    path, resumable chunks in ``<output>.chunks/`` (``overwrite`` discards chunks of another configuration);
    ``scheduler``: dask address or ``local:N``.
    """
    cfg = BasinConfig(axes=dict(axes), **options)
    return sweeps.run_sweep(basin_sweep(cfg), output=output, scheduler=scheduler, threads=threads, progress=progress,
                            overwrite=overwrite)


# ------------------------------------------------ basin fractions continued over a parameter
@dataclasses.dataclass(frozen=True)
class FractionsConfig:
    """Basin fractions of ``samples`` random initial conditions (uniform in ``ranges``, fixed ``seed``) at each
    value of ``parameter`` (an initial value such as omega, or a parameter eps, mu, e)."""

    parameter: str
    values: list  # [start, stop, n]
    ranges: dict  # INITIAL name -> [low, high] sampled uniformly
    samples: int = 200
    seed: int = 0
    initial: dict = dataclasses.field(default_factory=dict)
    parameters: dict = dataclasses.field(default_factory=dict)
    t_end: float = 60.0
    tol: float = MAP_TOL
    fall_angle: float = FALL_ANGLE
    slip_smoothing: float = SLIP_SMOOTHING
    chunk_size: int = CHUNK_SIZE
    batch_size: int = BATCH_SIZE
    recurrence: dict | None = None
    setup: dict = dataclasses.field(default_factory=lambda: to_dict(Setup()))

    def __post_init__(self):
        if self.parameter not in INITIAL and self.parameter not in PARAMETERS:
            raise ParameterError(f"cannot continue over {self.parameter!r}; give one of "
                                 f"{', '.join([*INITIAL, *PARAMETERS])}")
        v = parse_range(f"{self.values[0]!r}:{self.values[1]!r}:{int(self.values[2])}", self.parameter)
        object.__setattr__(self, "values", [v[0], v[1], v[2]])
        ranges = {k: [float(a), float(b)] for k, (a, b) in self.ranges.items()}
        if set(ranges) - set(INITIAL) or self.parameter in ranges:
            raise ParameterError(f"sampled ranges must be initial values other than the continued one "
                                 f"({', '.join(n for n in INITIAL if n != self.parameter)})")
        for k, (a, b) in ranges.items():
            if not (math.isfinite(a) and math.isfinite(b) and a <= b):
                raise ParameterError(f"range of {k} must be finite LOW <= HIGH")
        object.__setattr__(self, "ranges", ranges)
        if int(self.samples) != self.samples or self.samples < 1:
            raise ParameterError(f"samples = {self.samples!r} must be a positive integer")
        if (set(self.initial) - set(INITIAL)) or (set(self.parameters) - set(PARAMETERS)):
            raise ParameterError(f"initial values are {', '.join(INITIAL)}; parameters are {', '.join(PARAMETERS)}")
        object.__setattr__(self, "initial", {k: float(x) for k, x in self.initial.items()})
        object.__setattr__(self, "parameters", {k: float(x) for k, x in self.parameters.items()})
        _validate_common(self)
        for value in (v[0], v[1]):
            setup, init = self._at(value)
            for corner in (0, 1):
                initial_state(setup, {**init, **{k: r[corner] for k, r in ranges.items()}})

    def parameter_values(self) -> np.ndarray:
        return np.linspace(*self.values)

    @property
    def n_points(self) -> int:
        return int(self.values[2]) * int(self.samples)

    @property
    def shared_attractors(self) -> bool:
        """Continuing over an initial value: one system, so all runs share the attractors found."""
        return self.parameter in INITIAL

    def sample(self) -> dict[str, np.ndarray]:
        """The sampled initial values (same for every parameter value)."""
        rng = np.random.default_rng(int(self.seed))
        return {k: rng.uniform(a, b, int(self.samples)) for k, (a, b) in self.ranges.items()}

    def _at(self, value) -> tuple[Setup, dict]:
        if self.parameter in PARAMETERS:
            return _setup(self.setup, {**self.parameters, self.parameter: value}), dict(self.initial)
        return _setup(self.setup, self.parameters), {**self.initial, self.parameter: value}

    def to_dict(self) -> dict:
        return {"model": MODEL.name, **dataclasses.asdict(self)}

    @classmethod
    def from_dict(cls, d: dict) -> FractionsConfig:
        return cls(**{k: v for k, v in d.items() if k != "model"})


def fractions_chunk(config: FractionsConfig | dict, start: int, stop: int) -> dict:
    cfg = FractionsConfig.from_dict(config) if isinstance(config, dict) else config
    values, samples, S = cfg.parameter_values(), cfg.sample(), int(cfg.samples)
    x0 = np.empty((len(MODEL.state_names), stop - start))
    pars = np.empty((len(ode.PARAMETER_NAMES), stop - start))
    cache = {}
    for j, p in enumerate(range(start, stop)):
        k, i = divmod(p, S)
        if k not in cache:
            cache[k] = cfg._at(values[k])
        setup, init = cache[k]
        x0[:, j] = initial_state(setup, {**init, **{name: v[i] for name, v in samples.items()}})
        pars[:, j] = ode.parameter_vector(setup, cfg.fall_angle, cfg.slip_smoothing)
    groups = np.zeros(stop - start, dtype=np.int64) if cfg.shared_attractors else np.arange(start, stop) // S
    return run_points(x0, pars, groups, tol=cfg.tol, batch_size=cfg.batch_size, horizon=cfg.t_end,
                      recurrence=cfg.recurrence, key_base=start)


def assemble_fractions(cfg: FractionsConfig, results: dict) -> xr.Dataset:
    S, values = int(cfg.samples), cfg.parameter_values()
    groups = np.zeros(cfg.n_points, dtype=np.int64) if cfg.shared_attractors else np.arange(cfg.n_points) // S
    outcome, table_vars, table = attractor_table(results, groups)
    n_att = len(table)
    par = cfg.parameter
    frac = np.zeros((len(values), n_att))
    special = np.zeros((len(values), len(SPECIAL_ORDER)))
    oc = outcome.reshape(len(values), S)
    for k in range(len(values)):
        frac[k], special[k] = _fractions(oc[k], n_att)
    inverted = np.array([d.kind == "equilibrium" and d.extra.get("branch", 0) > 0 for d in table], dtype=bool)
    data = _point_data((par, "sample"), (len(values), S), results, outcome, table)
    data.update(table_vars)
    data["basin_fraction"] = ((par, "attractor"), frac, {"units": "1", "long_name": "share of the sampled runs "
                                                                                      "in the basin"})
    data["label_fraction"] = ((par, "label"), special, {"units": "1", "long_name": "share of the runs with this "
                                                                                  "label"})
    data["inverted_fraction"] = ((par,), frac[:, inverted].sum(axis=1) if n_att else np.zeros(len(values)), {
        "units": "1", "long_name": "share of the runs that end in a stable inverted spin (equilibrium attractors "
                                   "of the inverted branch)"})
    samples = cfg.sample()
    for name, v in samples.items():
        data[f"sample_{name}"] = (("sample",), v, {"units": INITIAL[name][0], "long_name": "sampled " + INITIAL[name][1]})
    units, long_name = (INITIAL[par][:2] if par in INITIAL else PARAMETERS[par])
    coords = {par: (par, values, {"units": units, "long_name": long_name}),
              "sample": ("sample", np.arange(S), {"long_name": "sampled initial condition"}),
              "attractor": ("attractor", np.arange(n_att), {"long_name": "attractor id (matched across " + par + ")"}),
              "label": ("label", list(SPECIAL_ORDER), {"long_name": "labels of runs without an attractor"})}
    coords.update(table_coords())
    message = summary(outcome, table, cfg.n_points, cfg.t_end) + (
        f"; inverted share {float(data['inverted_fraction'][1].min()):.3g}-{float(data['inverted_fraction'][1].max()):.3g}")
    status = "partial" if np.any(outcome == labels()["failed"]) else "completed"
    ds = xr.Dataset(data, coords=coords, attrs=make_attrs(
        "basin_fractions", cfg.to_dict(), status, message, model=MODEL.name, paper_model=MODEL.paper_name,
        parameter=par, t_end=cfg.t_end, shared_attractors=cfg.shared_attractors))
    return describe_units(ds)


def fractions_sweep(cfg: FractionsConfig) -> sweeps.Sweep:
    return sweeps.Sweep("basin fractions", cfg.to_dict(), cfg.n_points, int(cfg.chunk_size), chunk_variables(),
                        fractions_chunk, functools.partial(assemble_fractions, cfg),
                        functools.partial(warm_up, float(cfg.tol), int(cfg.batch_size)),
                        bytes_per_point=BYTES_PER_POINT, seconds_per_point=SECONDS_PER_RUN_SECOND * cfg.t_end)


def basin_fractions(parameter: str, values, ranges: dict, *, output=None, scheduler=None, threads: int | None = None,
                    progress: bool = True, overwrite: bool = False, **options) -> xr.Dataset:
    """Basin fractions continued over ``parameter`` (values (start, stop, n)); ``ranges`` {INITIAL name:
    (low, high)} are sampled (``samples`` per value, ``seed``). Attractors are matched across the values
    (global continuation); continuing over an initial value (omega) they are shared outright."""
    cfg = FractionsConfig(parameter=parameter, values=list(values), ranges=dict(ranges), **options)
    return sweeps.run_sweep(fractions_sweep(cfg), output=output, scheduler=scheduler, threads=threads,
                            progress=progress, overwrite=overwrite)
