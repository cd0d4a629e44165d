"""The tippedisk as a problem of the recurrence core (:mod:`.attractors`): attractors of ODE Model 1.

Runs integrate ODE Model 1 (Sect. 4.1, the full 13-state Euler-angle model of
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

import functools
import math

import numpy as np

from ..defaults import FALL_ANGLE, MAP_TOL, SLIP_SMOOTHING
from ..models import ode
from . import attractors as at
from . import stability
from . import stationary as st
from .reduced import STATE_NAMES as REDUCED_NAMES
from .reduced import reduced_from_full

MODEL = ode.EULER
PROJECTION = ("beta", "gamma", "alpha_dot")  # names the observe() cfunc can give: + beta_dot, gamma_dot
KINDS = ("equilibrium", "periodic", "irregular", "rolling", "wobbling")
DRIFT_TOL = 1e-5  # 1/s: |relative energy change rate| above which an oscillation is a dissipating transient
EXTRA_NAMES = ("branch", "omega", "omega_min", "omega_max", "max_real_eig", "stationary_deviation",
               "energy_drift", "segment_min", "segment_max")
SEGMENT_SCAN = (60.0, 0.5)  # rad/s: half-width and step of the scan for the stable segment, edges then refined
STATIONARY_ATOL = 1e-6  # an equilibrium must equal the closed-form stationary solution to this (max-norm)

DEFAULT_GRID = {
    # name: (lower, upper, cells, periodic); cell widths 0.1 rad, 0.26 rad, 2 rad/s
    "beta": (0.0, math.pi, 32, False),
    "gamma": (-math.pi, math.pi, 24, True),
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
    """Reduced states (7, N) of model states (13, N)."""
    x = np.asarray(states, dtype=float).reshape(len(MODEL.state_names), -1)
    i = {n: k for k, n in enumerate(MODEL.state_names)}
    return reduced_from_full(x[i["alpha"]], x[i["beta"]], x[i["gamma"]], x[i["x_dot"]], x[i["y_dot"]],
                             x[i["omega_x"]], x[i["omega_y"]], x[i["omega_z"]])


def full_of(reduced, r: float) -> np.ndarray:
    """A model state (13,) of a reduced state (alpha = x = y = 0, contact closed, W_friction = 0)."""
    beta, gamma, u_x, u_y, w_x, w_y, w_z = np.asarray(reduced, dtype=float)
    beta_dot = w_x * math.cos(gamma) - w_y * math.sin(gamma)
    return np.array([0.0, 0.0, r * math.sin(beta), 0.0, beta, gamma, u_x, u_y, r * math.cos(beta) * beta_dot,
                     w_x, w_y, w_z, 0.0])


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
        desc = at.describe(self, cand, core)
        if desc is None:
            if at.growing(core.settings, *at.spreads(self.grid, cand.observed)):
                return None
            # near a spin that Newton + stability do not accept (an unstable member of the family,
            # slowly approached or left): a dissipating wobble, a transient (checked by the drift below)
            grid = self.grid
            half = len(t) // 2
            desc = at.Description("irregular", self.represent(cand.states[:, -1]), at._circular_mean(grid, cand.observed),
                                  0.5 * np.ptp(grid.unwrap(cand.observed[:, half:]), axis=1) * grid.widths,
                                  0.5 * float(np.ptp(g[half:])), -1.0)
        if desc.kind == "equilibrium":
            return desc
        desc.extra = extra
        if abs(drift) > DRIFT_TOL:  # dissipates: no periodic orbit, a slowly evolving wobble about a spin
            desc.kind = "wobbling"
            desc.extra["branch"] = float(np.sign(np.mean(np.sin(_wrap(g)))))
        return desc

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
        full = full_of(x, float(pars[ode.PARAMETER_NAMES.index("r")]))
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
        y_member = self.observe(full_of(member, float(pars[ode.PARAMETER_NAMES.index("r")]))[:, None], pars)
        return float(np.max(np.abs(self.grid.difference(observed, y_member[:, 0]))))


def parameter_vector(setup, fall_angle: float = FALL_ANGLE, slip_smoothing: float = SLIP_SMOOTHING):
    return ode.parameter_vector(setup, fall_angle, slip_smoothing)


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
    """Map initial states (13, N) of ODE Model 1 to attractors; per-point arrays for a sweep chunk
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
    return ", ".join(parts) + f"; {len(table)} attractors"
