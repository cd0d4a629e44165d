"""Whether a start inverts, and the initial spin above which it does (docs/inversion.md).

Criterion: a start *inverts* when the height of S, z_S, exceeds r + 0.8 e (INVERSION_HEIGHT) within the
horizon, 150 s at eps = 0.1 m/s and growing like 1/eps below it (:func:`horizon`: the drift that inverts the
disk is O(eps)); ``height`` sets another level (0.99: the top). Starts: Table 3's (upright, gamma0,
beta_dot = 0, no spin about the disk normal, no slip) with the initial spin alpha_dot given. A heyoka event finds the crossing, so a run's time is exact.

Models (MODELS):
* ``smooth``: ODE Model 1, symmetry-reduced (:mod:`tippedisk_analysis.models.reduced`: the contact exact);
* ``slow``: its slow flow (:mod:`tippedisk_analysis.models.slow_flow`), rolling with the first-order slip.
  It exists only inside the friction cone: a run that reaches the cone before S rises ends there (status
  ``cone``) and counts as not inverting (chosen; the smooth model slides from there).
* ``held``: the slow flow with the spin about the vertical held at the run's spin
  (:mod:`tippedisk_analysis.models.held_spin`, a reduced model): its threshold is one of the held spin.

Outcomes: ``inverted``; ``horizon``, ``fell`` (the tilt reached the fall angle) and ``cone`` do not invert;
``lift_off`` (the bilateral contact stops being valid) and ``nonfinite`` decide nothing.

How high S gets (:func:`highest_point`): the run goes on over the whole horizon and the largest z_S is taken
at the maxima of z_S (heyoka events on dz_S/dt). Over the initial spin it is a smooth curve, which the criterion
cuts at the threshold.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import math
import numbers
from dataclasses import dataclass

import heyoka as hy
import numpy as np
import xarray as xr
from tqdm.auto import tqdm

from .. import kinematics as kin
from ..dynamics import Event, System
from ..dynamics.poincare import crossings
from ..dynamics.symmetric_families import finite_real
from ..errors import ParameterError
from ..models import held_spin, ode, reduced, slow_flow
from ..parameters import InitialState, Setup
from ..results import make_attrs

__all__ = ["MODELS", "INVERSION_HEIGHT", "Outcome", "Threshold", "horizon", "system", "start_state", "check_start",
           "parameters",
           "outcome", "spin_threshold", "with_eps", "threshold_dataset", "Highest", "height_system",
           "highest_point", "highest_points", "highest_points_config", "ReductionCheck", "check_reduction",
           "run_inputs", "check_height"]

MODELS = ("smooth", "slow", "held")
INVERSION_HEIGHT = 0.8  # z_S > r + 0.8 e: S well above G
HORIZON = 150.0  # s, at eps = HORIZON_EPS
HORIZON_EPS = 0.1  # m/s
TOL = 1e-10  # Taylor tolerance of the runs
REDUCTION_EPS = 0.01  # m/s: the slow flow is checked against ODE Model 1 here
REDUCTION_TOL = 0.05  # (z_S - r) / e: the two highest points agree this well where the reduction holds
NOT_INVERTING = ("horizon", "fell", "cone")
EARLY_ENDS = ("cone", "lift_off", "nonfinite")  # a run that ends so stops before the horizon with its model invalid
UNDECIDED = ("lift_off", "nonfinite")


@dataclass(frozen=True)
class Outcome:
    """One run: ``status`` (module docstring), ``time`` [s] at which it ended (the inversion's time when
    inverted), ``inverted`` (None when the run decides nothing)."""

    spin: float
    status: str
    time: float

    @property
    def inverted(self) -> bool | None:
        return None if self.status in UNDECIDED else self.status == "inverted"


@dataclass(frozen=True)
class Threshold:
    """The initial spin above which a start inverts: ``spin`` [rad/s], the midpoint of ``low`` (a run that does
    not invert) and ``high`` (one that does), both run; ``status`` completed (one crossing in the scan, bisected
    to xtol, inverting above it), no_crossing, several_crossings (``crossings`` lists every bracket; also a single
    crossing below which the start inverts) or undecided (a run decided nothing: see ``runs``); ``runs`` every
    outcome, in the order run."""

    spin: float
    low: float
    high: float
    status: str
    message: str
    crossings: tuple
    runs: tuple


def horizon(eps: float) -> float:
    """The criterion's horizon [s]: HORIZON at eps >= HORIZON_EPS, HORIZON * HORIZON_EPS / eps below."""
    return HORIZON * max(1.0, HORIZON_EPS / float(eps))


def _base_system(model: str) -> System:
    _check_model(model)
    return {"smooth": reduced.system, "slow": slow_flow.system, "held": held_spin.system}[model]()


@functools.lru_cache(maxsize=None)
def system(model: str, height: float = INVERSION_HEIGHT) -> System:
    """The model's System with the terminal event ``inverted`` (z_S rising through r + height e; the criterion:
    height 0.8) added."""
    base = _base_system(model)
    z_S = base.observables["z_S"][0]
    r, e = (hy.par[base.parameter_index(name)] for name in ("r", "e"))
    name = base.name + "_inversion" + ("" if height == INVERSION_HEIGHT else f"_{height:g}")
    return base.with_events(name, [Event("inverted", z_S - r - float(height) * e, "positive")])


def check_height(height) -> float:
    """``height`` as a level (z_S - r) / e in (0, 1) that S must pass; a one-line ParameterError otherwise."""
    height = finite_real(height, "height")
    if not 0 < height < 1:
        raise ParameterError(f"height = {height:g}: give the level (z_S - r) / e in (0, 1) that S must pass "
                             f"(the criterion: {INVERSION_HEIGHT}; the top: 0.99)")
    return height


def _check_model(model: str) -> None:
    if model not in MODELS:
        raise ParameterError(f"unknown model {model!r} for the inversion criterion; choose one of {', '.join(MODELS)}")


def start_state(model: str, spin: float, setup: Setup, gamma0: float) -> np.ndarray:
    """Table 3's start with initial spin ``spin`` [rad/s] and gamma0 [rad], as a state of ``model``."""
    _check_model(model)
    initial = InitialState(alpha_dot=float(spin), gamma=float(gamma0))
    rest = kin.rest_contact_state(setup.disk.r, initial.euler, initial.euler_rates)
    angles = [initial.beta, initial.gamma]
    if model == "smooth":
        return np.array([*angles, rest["v_G"][0], rest["v_G"][1], *rest["omega"]])
    if model == "held":
        return np.array([*angles, *initial.euler_rates[1:]])
    return np.array([*angles, *rest["omega"]])


def check_start(setup: Setup, gamma0: float) -> None:
    """ParameterError unless gamma0 [rad] is a finite angle in [-pi, pi] whose start has S below the criterion
    (z_S < r + 0.8 e): a start already counted as inverted has no threshold."""
    if not (math.isfinite(gamma0) and abs(gamma0) <= math.pi):
        raise ParameterError(f"gamma0 = {gamma0!r} rad: give an angle in [-pi, pi] (Table 3: -pi/2 + 0.1)")
    if setup.disk.e <= 0:
        raise ParameterError("e = 0: a balanced disk (S at G) has no inversion to predict; give an eccentricity "
                             "e > 0 [m] (Table 1: 0.0025)")
    z_S = float(system("slow").observe(start_state("slow", 0.0, setup, gamma0), parameters("slow", setup))["z_S"])
    disk = setup.disk
    if z_S >= disk.r + INVERSION_HEIGHT * disk.e:
        raise ParameterError(f"gamma0 = {gamma0:.4g} rad starts S at z_S = r + {(z_S - disk.r) / disk.e:.3f} e, "
                             f"already above the criterion r + {INVERSION_HEIGHT} e; give a start with S lower "
                             "(Table 3: gamma0 = -pi/2 + 0.1)")


def parameters(model: str, setup: Setup, spin: float | None = None) -> np.ndarray:
    """The model's runtime parameters for ``setup`` (eps from its friction; ``spin`` [rad/s]: the held spin, which
    the held model needs)."""
    _check_model(model)
    if model == "held" and spin is None:
        raise ParameterError("the held model needs the spin it holds: give spin in rad/s")
    values = dict(zip(ode.PARAMETER_NAMES, ode.parameter_vector(setup)), spin=spin)
    return np.array([values[name] for name in system(model).parameter_names])


def run_inputs(spin, setup: Setup | None, gamma0, horizon_s) -> tuple[float, Setup, float, float]:
    """The checked inputs of one run from Table 3's start: the initial spin [rad/s] (positive: a negative one
    is its mirror image), the setup (default Tables 1-3), gamma0 [rad] and the horizon [s] (default
    :func:`horizon`); one-line ParameterErrors otherwise."""
    spin = finite_real(spin, "spin")
    if spin <= 0:
        raise ParameterError(f"spin = {spin:g} rad/s: give a positive initial spin (a negative one is the mirror "
                             "image of the positive one)")
    setup = Setup() if setup is None else setup
    if not isinstance(setup, Setup):
        raise ParameterError(f"setup is a {type(setup).__name__}; give a Setup, e.g. Setup(disk=disk)")
    gamma0 = InitialState().gamma if gamma0 is None else finite_real(gamma0, "gamma0")
    check_start(setup, gamma0)
    t_end = horizon(setup.friction.eps) if horizon_s is None else finite_real(horizon_s, "horizon_s")
    if not t_end > 0:
        raise ParameterError(f"horizon = {t_end} s must be positive")
    return spin, setup, gamma0, t_end


def outcome(spin: float, *, model: str = "smooth", setup: Setup | None = None, gamma0: float | None = None,
            horizon_s: float | None = None, height: float = INVERSION_HEIGHT) -> Outcome:
    """Run ``model`` from Table 3's start at initial spin ``spin`` [rad/s] until it inverts (S passes r + height
    e), ends or reaches the horizon (default :func:`horizon` of the setup's eps)."""
    spin, setup, gamma0, t_end = run_inputs(spin, setup, gamma0, horizon_s)
    model_system = system(model, check_height(height))
    ta = copy.deepcopy(model_system.taylor(TOL, events=True))
    ta.time = 0.0
    ta.state[:] = start_state(model, spin, setup, gamma0)
    ta.pars[:] = parameters(model, setup, spin)[: len(ta.pars)]
    result = ta.propagate_until(t_end)[0]
    if not (np.all(np.isfinite(ta.state)) and math.isfinite(ta.time)):
        return Outcome(float(spin), "nonfinite", float(ta.time))
    if result == hy.taylor_outcome.time_limit:
        return Outcome(float(spin), "horizon", float(ta.time))
    index = System.stopping_event(result, model_system.events)
    if index is None:
        return Outcome(float(spin), "nonfinite", float(ta.time))
    return Outcome(float(spin), model_system.events[index].name, float(ta.time))


def spin_threshold(*, model: str = "smooth", setup: Setup | None = None, gamma0: float | None = None,
                   bracket: tuple = (20.0, 50.0), scan: int = 13, xtol: float = 1e-3,
                   horizon_s: float | None = None, height: float = INVERSION_HEIGHT) -> Threshold:
    """The initial spin above which Table 3's start inverts (module docstring; S passes r + height e), for
    ``model``: ``scan`` spins across ``bracket`` [rad/s] find where the outcome changes, each change is bisected
    to ``xtol``."""
    _check_model(model)
    height = check_height(height)
    try:
        low, high = map(float, bracket)
    except (TypeError, ValueError):
        low = high = math.nan
    if not (math.isfinite(low) and math.isfinite(high) and 0 < low < high):
        raise ParameterError(f"bracket = {bracket!r}: give two spins 0 < low < high in rad/s")
    if not (isinstance(scan, numbers.Integral) and scan >= 2 and xtol > 0):
        raise ParameterError(f"scan = {scan!r} and xtol = {xtol!r}: give an integer scan >= 2 spins and xtol > 0 "
                             "rad/s")
    _low, setup, gamma0, _t_end = run_inputs(low, setup, gamma0, horizon_s)
    runs = []

    def decide(spin):
        runs.append(outcome(spin, model=model, setup=setup, gamma0=gamma0, horizon_s=horizon_s, height=height))
        return runs[-1].inverted

    spins = np.linspace(low, high, int(scan))
    decided = [(s, d) for s, d in zip(spins, map(decide, spins)) if d is not None]
    bad = [r for r in runs if r.inverted is None]
    note = (f"; {len(bad)} scanned run(s) decided nothing (first: {bad[0].spin:.6g} rad/s ended {bad[0].status} at "
            f"t = {bad[0].time:.6g} s)" if bad else "")
    if len(decided) < 2:
        return _threshold(math.nan, math.nan, math.nan, "undecided", "fewer than two scanned runs decided" + note,
                          (), runs)
    pairs = [(a, b, da) for (a, da), (b, db) in zip(decided, decided[1:]) if da != db]
    if not pairs:
        what = "inverts" if decided[0][1] else "does not invert"
        return _threshold(math.nan, math.nan, math.nan, "no_crossing", f"every decided spin in [{low:g}, {high:g}] "
                          f"rad/s {what}; widen the bracket"
                          + (" or scan more finely (runs that decided nothing may hide a crossing)" if bad else "")
                          + note, (), runs)
    crossings = []
    for a, b, below in pairs:
        while b - a > xtol:
            mid = 0.5 * (a + b)
            decision = decide(mid)
            if decision is None:
                return _threshold(math.nan, math.nan, math.nan, "undecided", f"the run at {mid:.6g} rad/s, between "
                                  f"{a:.6g} and {b:.6g}, ended {runs[-1].status}" + note, tuple(crossings), runs)
            a, b = (mid, b) if decision == below else (a, mid)
        crossings.append((a, b))
    (a, b) = crossings[0]
    spin = 0.5 * (a + b)
    if len(crossings) == 1 and not pairs[0][2]:
        return _threshold(spin, a, b, "completed", f"inverts above {spin:.6g} rad/s, not below ({len(runs)} runs)"
                          + note, tuple(crossings), runs)
    where = ", ".join(f"{0.5 * (x + y):.6g}" for x, y in crossings)
    return _threshold(spin, a, b, "several_crossings", f"the outcome changes at {where} rad/s (inverts at "
                      f"{decided[0][0]:g} rad/s: {decided[0][1]}); no single threshold" + note, tuple(crossings), runs)


@dataclass(frozen=True)
class Highest:
    """The highest point S reaches on one run from Table 3's start at ``spin`` [rad/s], within the horizon or
    until the run ended (``status`` at ``t_end`` [s]: ``horizon``, or the model's event ``fell``, ``cone``,
    ``lift_off``, or ``nonfinite``): ``height`` (z_S - r) / e there, ``time`` [s] and ``energy_lost`` E_tot(0) -
    E_tot(time) [J] (friction's work; for the held model also the holding torque's). The criterion holds where
    height exceeds INVERSION_HEIGHT."""

    spin: float
    height: float
    time: float
    energy_lost: float
    status: str
    t_end: float


@functools.lru_cache(maxsize=None)
def height_system(model: str) -> System:
    """The model's System with the observable ``z_S_rate`` (dz_S/dt, m/s): its downward zeros are z_S's maxima."""
    base = _base_system(model)
    rate = base.rate_of(base.observables["z_S"][0])
    return base.with_observables(base.name + "_height", {"z_S_rate": (rate, "m s-1")})


def highest_point(spin: float, *, model: str = "smooth", setup: Setup | None = None, gamma0: float | None = None,
                  horizon_s: float | None = None) -> Highest:
    """Run ``model`` from Table 3's start at initial spin ``spin`` [rad/s] over the horizon (default
    :func:`horizon`; the run goes on past the criterion) and return the highest point S reaches: the largest of
    z_S at the start, at every maximum of z_S (heyoka events on dz_S/dt, located to the integrator's tolerance)
    and at the end."""
    spin, setup, gamma0, t_end = run_inputs(spin, setup, gamma0, horizon_s)
    model_system, pars = height_system(model), parameters(model, setup, spin)
    start = start_state(model, spin, setup, gamma0)
    run = crossings(model_system, start, "z_S_rate", 0.0, pars=pars, direction="negative", t_end=t_end,
                    tol=TOL, events=True)
    times = np.concatenate([[0.0], run.times, [run.t_final]])
    states = np.vstack([start, run.states, run.final])
    finite = np.all(np.isfinite(states), axis=1)
    observed = model_system.observe(states[finite].T, pars)
    best = int(np.argmax(observed["z_S"]))
    status = {"completed": "horizon"}.get(run.status, run.status)
    return Highest(float(spin), float((observed["z_S"][best] - setup.disk.r) / setup.disk.e),
                   float(times[finite][best]), float(observed["E_tot"][0] - observed["E_tot"][best]), status,
                   run.t_final)


@dataclass(frozen=True)
class ReductionCheck:
    """The slow flow (the reduction) against ODE Model 1 for one start at eps = REDUCTION_EPS: both runs' highest
    points. The reduction ``holds`` where they agree to REDUCTION_TOL; a start that slides in its first swing
    leaves the slow manifold, and the slow flow ends at the cone or lifts off instead (docs/inversion.md)."""

    slow: Highest
    full: Highest

    @property
    def holds(self) -> bool:
        return abs(self.slow.height - self.full.height) <= REDUCTION_TOL


def check_reduction(spin: float, setup: Setup | None = None, gamma0: float | None = None) -> ReductionCheck:
    """:class:`ReductionCheck` of Table 3's start at initial spin ``spin`` [rad/s] (``setup``'s eps replaced)."""
    setup = with_eps(setup, REDUCTION_EPS)
    return ReductionCheck(*(highest_point(spin, model=m, setup=setup, gamma0=gamma0) for m in ("slow", "smooth")))


def highest_points_config(model: str, setup: Setup, gamma0: float, horizon_s: float | None) -> dict:
    """The ``config`` attribute of :func:`highest_points` for these inputs (a study compares it to resume)."""
    return {"model": model, "setup": repr(setup), "gamma0": gamma0, "tol": TOL,
            "horizon_s": horizon(setup.friction.eps) if horizon_s is None else float(horizon_s)}


def highest_points(spins, *, model: str = "smooth", setup: Setup | None = None, gamma0: float | None = None,
                   horizon_s: float | None = None, progress: bool = False) -> xr.Dataset:
    """:func:`highest_point` at each of ``spins`` [rad/s] as a dataset (kind ``highest_point``, dim ``spin``)."""
    try:
        spins = np.asarray(spins, dtype=float)
    except (TypeError, ValueError):
        spins = np.array([])
    if spins.ndim != 1 or not spins.size or not np.all(np.isfinite(spins) & (spins > 0)):
        raise ParameterError("spins: give a list of positive initial spins in rad/s, e.g. [32.5, 33.5]")
    _spin, setup, gamma0, _t_end = run_inputs(spins[0], setup, gamma0, horizon_s)
    rows = [highest_point(w, model=model, setup=setup, gamma0=gamma0, horizon_s=horizon_s)
            for w in tqdm(spins, desc=f"highest point ({model})", disable=not progress, unit="run")]
    ended = {"horizon": 0, "fell": 1, "cone": 2, "lift_off": 3, "nonfinite": 4}
    ds = xr.Dataset(
        {"height": ("spin", [h.height for h in rows],
                    {"units": "1", "long_name": "highest (z_S - r) / e of the run"}),
         "time": ("spin", [h.time for h in rows], {"units": "s", "long_name": "time at which S is highest"}),
         "energy_lost": ("spin", [h.energy_lost for h in rows],
                         {"units": "J", "long_name": "energy lost from the start until S is highest"}),
         "end_time": ("spin", [h.t_end for h in rows], {"units": "s", "long_name": "time at which the run ended"}),
         "ending": ("spin", np.array([ended[h.status] for h in rows], dtype=np.int8),
                    {"long_name": "how the run ended", "flag_values": np.arange(len(ended), dtype=np.int8),
                     "flag_meanings": " ".join(ended)})},
        coords={"spin": ("spin", spins, {"units": "rad s-1", "long_name": "initial spin alpha_dot(0)"})})
    early = sum(h.status in EARLY_ENDS for h in rows)
    status = "partial" if early else "completed"
    heights = ds.height.values
    message = (f"{len(rows)} runs; highest (z_S - r) / e from {heights.min():.4g} to {heights.max():.4g}"
               + (f"; {early} run(s) ended where the model stops being valid (the slow flow at the friction cone, "
                  "lift-off, a non-finite state): their highest point is the one up to there" if early else ""))
    ds.attrs = make_attrs("highest_point", highest_points_config(model, setup, gamma0, horizon_s), status, message,
                          title=f"Highest point of S from the Table 3 start over the initial spin ({model})")
    return ds


def _threshold(spin, low, high, status, message, crossings, runs) -> Threshold:
    return Threshold(float(spin), float(low), float(high), status, message, tuple(crossings), tuple(runs))


def with_eps(setup: Setup | None, eps: float) -> Setup:
    """``setup`` (default Tables 1-3) with the friction smoothing eps [m/s]."""
    setup = Setup() if setup is None else setup
    return dataclasses.replace(setup, friction=dataclasses.replace(setup.friction, eps=float(eps)))


STATUS_FLAGS = {"completed": 0, "several_crossings": 1, "no_crossing": 2, "undecided": 3}
RUN_FLAGS = {"padding": -1, "inverted": 0, "horizon": 1, "fell": 2, "cone": 3, "lift_off": 4, "nonfinite": 5}
PADDING = -1.0
FOUND = ("completed", "several_crossings")  # statuses with a located crossing


def threshold_dataset(cases: dict) -> xr.Dataset:
    """The thresholds of ``cases`` {label: (model, setup, Threshold)} as one dataset (kind
    ``inversion_threshold``, dim ``case``; every run of each along ``run``, padded)."""
    labels = list(cases)
    n_runs = max(len(th.runs) for _m, _s, th in cases.values())

    def column(get):
        return np.array([get(*cases[k]) for k in labels], dtype=float)

    def padded(get, fill):
        table = np.full((len(labels), n_runs), fill)
        for i, k in enumerate(labels):
            values = [get(r) for r in cases[k][2].runs]
            table[i, :len(values)] = values
        return table

    def found(th, value):
        return value if th.status in FOUND else PADDING

    def at_high(th):
        return next((r.time for r in th.runs if r.spin == th.high), PADDING) if th.status in FOUND else PADDING

    spin_attrs = {"units": "rad s-1", "padding_value": PADDING, "comment": "-1: no threshold (status)"}
    ds = xr.Dataset(
        {"spin_threshold": ("case", column(lambda m, s, th: found(th, th.spin)),
                            {**spin_attrs, "long_name": "initial spin above which the start inverts (first crossing)",
                             "comment": "-1: no threshold (status); model held: the held spin"}),
         "spin_low": ("case", column(lambda m, s, th: found(th, th.low)),
                      {**spin_attrs, "long_name": "highest spin run that does not invert"}),
         "spin_high": ("case", column(lambda m, s, th: found(th, th.high)),
                       {**spin_attrs, "long_name": "lowest spin run that inverts"}),
         "second_crossing": ("case", column(lambda m, s, th: 0.5 * sum(th.crossings[1]) if len(th.crossings) > 1
                                            else PADDING),
                             {**spin_attrs, "long_name": "the next spin at which the outcome changes"}),
         "inversion_time": ("case", column(lambda m, s, th: at_high(th)),
                            {"units": "s", "padding_value": PADDING, "long_name": "time the run at spin_high takes to "
                             "lift S to r + 0.8 e"}),
         "eps": ("case", column(lambda m, s, th: s.friction.eps),
                 {"units": "m s-1", "long_name": "friction smoothing"}),
         "e": ("case", column(lambda m, s, th: s.disk.e), {"units": "m", "long_name": "eccentricity of S"}),
         "r": ("case", column(lambda m, s, th: s.disk.r), {"units": "m", "long_name": "disk radius"}),
         "m": ("case", column(lambda m, s, th: s.disk.m), {"units": "kg", "long_name": "disk mass"}),
         "A": ("case", column(lambda m, s, th: s.disk.A), {"units": "kg m2", "long_name": "inertia A about G"}),
         "B": ("case", column(lambda m, s, th: s.disk.B), {"units": "kg m2", "long_name": "inertia B about G"}),
         "C": ("case", column(lambda m, s, th: s.disk.C), {"units": "kg m2", "long_name": "inertia C about G"}),
         "model": ("case", np.array([MODELS.index(cases[k][0]) for k in labels], dtype=np.int8),
                   {"long_name": "model run", "flag_values": np.arange(len(MODELS), dtype=np.int8),
                    "flag_meanings": " ".join(MODELS)}),
         "threshold_status": ("case", np.array([STATUS_FLAGS[cases[k][2].status] for k in labels], dtype=np.int8),
                              {"long_name": "outcome of the threshold search",
                               "flag_values": np.array(list(STATUS_FLAGS.values()), dtype=np.int8),
                               "flag_meanings": " ".join(STATUS_FLAGS)}),
         "run_spin": (("case", "run"), padded(lambda r: r.spin, PADDING),
                      {**spin_attrs, "long_name": "initial spin of each run", "comment": "-1: padding"}),
         "run_time": (("case", "run"), padded(lambda r: r.time, PADDING),
                      {"units": "s", "padding_value": PADDING, "long_name": "time at which each run ended"}),
         "run_outcome": (("case", "run"), padded(lambda r: RUN_FLAGS[r.status], RUN_FLAGS["padding"]).astype(np.int8),
                         {"long_name": "how each run ended", "flag_values": np.array(list(RUN_FLAGS.values()),
                                                                                     dtype=np.int8),
                          "flag_meanings": " ".join(RUN_FLAGS)})},
        coords={"case": ("case", np.array(labels, dtype=object), {"long_name": "case label"})})
    statuses = {cases[k][2].status for k in labels}
    status = "completed" if statuses <= set(FOUND) else "partial"
    config = {"criterion": f"z_S > r + {INVERSION_HEIGHT:g} e within {HORIZON:g} s at eps >= {HORIZON_EPS:g} m/s, "
                           f"{HORIZON:g} * {HORIZON_EPS:g} / eps s below", "tol": TOL,
              "cases": {k: {"model": cases[k][0], "message": cases[k][2].message} for k in labels}}
    spin = "held" if all(cases[k][0] == "held" for k in labels) else "initial"
    ds.attrs = make_attrs("inversion_threshold", config, status,
                          f"{len(labels)} thresholds of the {spin} spin ({', '.join(sorted(statuses))})",
                          title=f"{spin.capitalize()} spin above which the Table 3 start inverts")
    return ds
