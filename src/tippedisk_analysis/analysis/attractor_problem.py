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

import functools
import math

import numpy as np

from ..defaults import MAP_TOL
from ..dynamics import attractors as at
from ..models import ode
from ..models.reduced import STATE_NAMES as REDUCED_NAMES
from . import stability
from . import stationary as st
from .reduced import full_from_reduced, reduced_from_full

MODEL = ode.EULER
PROJECTION = ("beta", "gamma", "alpha_dot")  # names the observe() cfunc can give: + beta_dot, gamma_dot
PROJECTION_UNITS = {"beta": "rad", "gamma": "rad", "alpha_dot": "rad s-1", "beta_dot": "rad s-1",
                    "gamma_dot": "rad s-1"}
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


def integrator(tol: float, batch_size: int):
    """Batch integrator of ODE Model 1 (its System, :func:`tippedisk_analysis.models.ode.as_system`): terminal
    events fall, lift-off; a non-terminal event at gamma = 0 upwards (the inversion)."""
    system = ode.as_system(MODEL)
    gamma = system.variables[MODEL.state_names.index("gamma")]
    return system.taylor(float(tol), batch=int(batch_size), events=("fell", "lift_off"),
                         nt_events=((gamma, at.FirstTime(), "positive"),))


@functools.lru_cache(maxsize=None)  # the System caches by expression text: fetch it once
def observables():
    """cfunc of (beta, gamma, alpha_dot, beta_dot, gamma_dot, E_tot, lambda_N, z_S, E_kin) over the model state."""
    variables, _sys, _fall, outputs = ode.system(MODEL)
    o = dict(zip(ode.OUTPUT_NAMES, outputs))
    return ode.as_system(MODEL).function("attractor observables", [
        o["beta"], variables[MODEL.state_names.index("gamma")], o["alpha_dot"], o["beta_dot"], o["gamma_dot"],
        o["E_kin"] + o["E_pot"], o["lambda_N"], o["z_S"], o["E_kin"]], "the observables of the attractor map")


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
            centroid = at.circular_mean(grid, cand.observed)
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
        return at.Description("wobbling", self.represent(cand.states[:, -1]), at.circular_mean(grid, cand.observed),
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
