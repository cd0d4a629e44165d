"""The recurrence problem of any :class:`~tippedisk_analysis.dynamics.System`, and its basins of attraction.

    grid = at.Grid(("u1", "u2"), (0.0, 0.0), (1.0, 6.0), (100, 100))
    ds = dy.basins(ab, grid, {"u1": (0.0, 1.0, 64), "u2": (0.0, 6.0, 64)}, pars=ab.with_pars(D=0.12))

The runs integrate the system in heyoka batch mode (its terminal events end a run and label it), observed
through the grid's coordinates (states or observables of the system, by name). The result is a dataset of
kind ``basins``: the attractor id (>= 0) or the negative label of every initial condition, the time it was
decided, the basin fractions, and the table of attractors (kind, period, amplitude, a state on it, the mean of
its observed coordinates), with the system's name and equations as attributes. The grid of initial
conditions runs as a resumable sweep (:mod:`tippedisk_analysis.dynamics.sweeps`: threads, or a dask
scheduler; finished chunks are kept next to ``output``).
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import math

import numpy as np
import xarray as xr

from ...errors import ParameterError, TippediskError
from ...results import index_coordinate, make_attrs
from .. import sweeps
from ..datasets import flag_attrs, label_coordinates, mixed_units, state_coordinates
from ..flows import STABILITY
from ..lyapunov import spectrum
from ..orbits import find_orbit
from ..system import System
from . import conservative
from .confirm import is_projection
from .mapping import map_points
from .problem import Problem, circular_mean, closest_return, describe, equilibrium_description
from .records import BASE_KINDS, Candidate, Description, Grid, RecurrenceSettings
from .sets import arc_indices, points_of, set_names
from .tables import assemble_table, chunk_result, column_names

TOL = 1e-10  # Taylor tolerance of the runs: classifications, not trajectories to round-off
NEWTON_STEPS = 30  # Newton iterations towards an equilibrium
RESIDUAL_TOL = 1e-12  # |f| / state_scale of an equilibrium, relative to the size of its terms
PERIOD_RTOL = 1e-3  # the shooting period of a periodic attractor against the recorded return time
NEIGHBOURHOOD = 2.0  # cells (max-norm) around an equilibrium that become its cells
SET_POINTS = 128  # points of a periodic or irregular attractor's set (:mod:`.sets`)
DENSE_SAMPLES = 4096  # samples of one period from which a periodic attractor's points are taken by arc length
LONG_WINDOWS = 10  # an irregular candidate's run goes on this many locate windows in search of a return
RETURN_REFERENCES = 8  # samples of the long run's second half tried as the state a return comes back to


class SystemProblem(Problem):
    """A :class:`~tippedisk_analysis.dynamics.System` for the recurrence core: integrated in batch mode with
    its terminal events (their names label the runs they end), observed through ``grid``'s coordinates."""

    escapes = True
    set_points = SET_POINTS
    rejection_reasons = ("not_equilibrium", "unstable_equilibrium", "orbit_not_closed", "unstable_orbit",
                         "contracting")

    def __init__(self, system: System, grid: Grid, *, tol: float = TOL, events=True):
        self.system, self.grid, self.tol = system, grid, float(tol)
        self.state_names = system.state_names
        self._events = tuple(e.name for e in system.terminal_events(events))
        self.terminal_labels = self._events
        self.kinds = BASE_KINDS
        for name in grid.names:
            if name not in system.state_names and name not in system.observables:
                raise ParameterError(f"grid coordinate {name!r} is neither a state nor an observable of "
                                     f"{system.name} ({', '.join((*system.state_names, *system.observables))})")
        self.state_scale = system.state_scale
        self.projection = is_projection(self)  # descriptions carry state_points (:mod:`.confirm`)

    def describe(self, candidate: Candidate, core) -> Description | None:
        """The generic description (:func:`.problem.describe`), each kind verified by a criterion of its own
        before it is an attractor (a window of the settings' length knows no time scale of the system: the slow
        part of a relaxation cycle looks like an equilibrium there):

        * an equilibrium: Newton's method from the settled state converges to a point within a cell (or
          ``equilibrium_spread`` cells) of it, whose residual |f| / state_scale is at Newton's level and whose
          eigenvalues all have negative real parts; or the samples contract to such a point in the Lyapunov
          function V = (x - x*)^T P (x - x*) of its linearisation (A^T P + P A = -I): a slow spiral;
        * a periodic orbit: shooting from the recorded state with the recorded period closes the orbit, with
          the period within ``PERIOD_RTOL`` of the recorded one and every nontrivial multiplier inside the unit
          circle; the cells of the whole orbit become the attractor's;
        * an orbit longer than the window: the run goes on for LONG_WINDOWS windows and the closest return
          (:func:`.problem.closest_return`) to one of RETURN_REFERENCES of its samples is the period guess of
          the shooting, verified as above (an orbit that winds several times: its neighbouring strands are no
          return);
        * irregular: no equilibrium or orbit verified, and the largest Lyapunov exponent is not negative
          (chaos or a torus); a contracting run is no attractor yet.

        A candidate that fails its check is no attractor (None): its run searches on, and is ``undecided``
        at the horizon, with the reason (``rejection_reasons``) of its last candidate."""
        desc = describe(self, candidate, core)
        if desc is not None and desc.kind == "equilibrium":
            return self._with_neighbourhood(desc, candidate.observed)
        if desc is not None and desc.kind == "periodic":
            verified = self._orbit_attractor(desc.representative, desc.period, candidate.pars, core.settings.dt)
            if verified is not None:
                return verified
        x = self._contracting_equilibrium(candidate.states, candidate.pars)
        if x is not None:
            equilibrium = equilibrium_description(self, candidate, {"state": x})
            return self._with_neighbourhood(equilibrium, candidate.observed)
        s = core.settings  # a longer look: a return, a slow contraction, or a run that does neither
        times = s.dt * np.arange(LONG_WINDOWS * candidate.times.size + 1)
        states = core.sample(candidate.states[:, -1], candidate.pars, times)
        if states is None:
            return None
        observed = self.observe(states, np.asarray(candidate.pars))
        for end in np.linspace(len(times) - 1, len(times) // 2, RETURN_REFERENCES).astype(int):
            # the closest return to the sample at ``end`` (the last sample may lie on a fast jump, which has
            # none; the latest return may be a neighbouring strand of an orbit that winds several times)
            lag = closest_return(self.grid, s, observed[:, : end + 1], times[: end + 1])
            if lag is not None:
                verified = self._orbit_attractor(states[:, end], lag, candidate.pars, s.dt)
                if verified is not None:
                    return verified
                break  # a near return of an orbit that does not close (a chaotic run comes close to itself)
        x = self._contracting_equilibrium(states, candidate.pars)
        if x is not None:
            return self._with_neighbourhood(equilibrium_description(self, candidate, {"state": x}), observed)
        if desc is None or desc.kind != "irregular":
            return None  # growing, or an equilibrium that failed its check: no attractor yet
        if not self._not_contracting(states[:, -1], candidate.pars, max(s.horizon, times[-1])):
            return None
        spread = 0.5 * np.ptp(self.grid.unwrap(observed), axis=1) * self.grid.widths  # the long run's, not the window's
        index = np.linspace(0, observed.shape[1], self.set_points, endpoint=False).astype(int)
        return dataclasses.replace(desc, centroid=circular_mean(self.grid, observed), spread=spread,
                                   points=observed[:, index], state_points=self._state_points(states[:, index]))

    def _state_points(self, states) -> np.ndarray | None:
        """``states`` (n, M) as a description's state_points where the grid is a projection, else None."""
        return np.array(states, dtype=float) if self.projection else None

    def _with_neighbourhood(self, desc: Description, observed) -> Description:
        """An equilibrium with the cells of the samples ``observed`` (D, L) within NEIGHBOURHOOD cells of it as
        its cells (a run through the window's earlier cells, e.g. past a saddle, is not yet in its basin)."""
        near = np.max(np.abs(self.grid.difference(observed, desc.centroid[:, None])), axis=0) <= NEIGHBOURHOOD
        keys = self.grid.keys(np.concatenate([desc.centroid[:, None], observed[:, near]], axis=1))
        return dataclasses.replace(desc, cells=tuple(int(k) for k in np.unique(keys[keys >= 0])),
                                   state_points=self._state_points(np.asarray(desc.representative)[:, None]))

    def _reject(self, reason: str) -> None:
        self.rejection = 1 + self.rejection_reasons.index(reason)

    def refine_equilibrium(self, state, pars, core) -> dict | None:
        """The settled state's equilibrium by Newton's method, if it is one and stable (:meth:`describe`)."""
        x0 = core.settle(state, pars)
        x = self._newton(x0, pars)
        if x is None:
            self._reject("not_equilibrium")
            return None
        if np.max(np.abs(self.grid.difference(*(self.observe(np.stack([x, x0], axis=1), pars)[:, k:k + 1]
                                                   for k in (0, 1))))) > max(1.0, core.settings.equilibrium_spread):
            self._reject("not_equilibrium")
            return None
        if np.max(np.linalg.eigvals(self.system.jacobian(x, pars)).real) >= 0:
            self._reject("unstable_equilibrium")
            return None
        return {"state": x}

    def _newton(self, x, pars) -> np.ndarray | None:
        """An equilibrium near x: Newton's method to a residual |f| / state_scale at round-off (below
        RESIDUAL_TOL of the size of its terms, then one more step), or None."""
        pars = np.asarray(pars, dtype=float)
        scale = self.system.state_scale
        converged = False
        for _ in range(NEWTON_STEPS):
            J = self.system.jacobian(x, pars)
            f = self.system.f(x, pars)
            if converged:
                return x
            converged = np.max(np.abs(f) / scale) <= RESIDUAL_TOL * (1.0 + np.abs(J) @ np.abs(x) / scale).max()
            try:
                x = x + np.linalg.solve(J, -f)
            except np.linalg.LinAlgError:
                return None
            if not np.all(np.isfinite(x)):
                return None
        return None

    def _contracting_equilibrium(self, states, pars) -> np.ndarray | None:
        """A stable equilibrium x* that the samples ``states`` (n, L) approach (:meth:`describe`), or None."""
        from scipy.linalg import solve_continuous_lyapunov

        pars = np.asarray(pars, dtype=float)
        x = self._newton(np.mean(states, axis=1), pars)
        if x is None:
            return None
        A = self.system.jacobian(x, pars)
        if np.max(np.linalg.eigvals(A).real) >= 0:
            return None
        P = solve_continuous_lyapunov(A.T, -np.eye(self.system.n))
        d = states - x[:, None]
        V = np.einsum("il,ij,jl->l", d, P, d)
        h = len(V) // 2
        return x if V[-1] < 0.5 * V[0] and V[h:].max() < V[:h].max() else None

    def _orbit_attractor(self, state, period: float, pars, dt: float) -> Description | None:
        """The periodic attractor through ``state`` if shooting with the guess ``period`` closes an orbit whose
        least period divides it (to 2 dt + PERIOD_RTOL) and whose nontrivial multipliers lie inside the unit
        circle; its description (centroid, spread, amplitude, cells) is that of the shooting orbit."""
        pars = np.asarray(pars, dtype=float)
        orbit = self._closed_orbit(state, period, pars)
        if orbit is None:
            self._reject("orbit_not_closed")
            return None
        turns = max(1, round(period / orbit.period))
        if abs(period - turns * orbit.period) > 2 * dt + PERIOD_RTOL * period:
            self._reject("orbit_not_closed")
            return None
        if orbit.stability != STABILITY["stable"]:
            self._reject("unstable_orbit")
            return None
        observed = self.observe(orbit.samples.T, pars)
        dense = self._one_period(orbit.states[0], float(orbit.period), pars)
        dense_observed = self.observe(dense, pars)
        index = arc_indices(self.grid, dense_observed, self.set_points)
        unwrapped = self.grid.unwrap(observed)
        keys = self.grid.keys(observed)
        k = self.amplitude_index
        return Description("periodic", orbit.states[0], circular_mean(self.grid, observed),
                           0.5 * np.ptp(unwrapped, axis=1) * self.grid.widths,
                           0.5 * float(np.ptp(unwrapped[k])) * self.grid.widths[k], float(orbit.period),
                           cells=tuple(int(c) for c in np.unique(keys[keys >= 0])),
                           points=dense_observed[:, index], state_points=self._state_points(dense[:, index]))

    def _closed_orbit(self, state, period: float, pars):
        """The converged shooting orbit through ``state`` near ``period`` (1, then 4 segments), or None. A rotation
        of k whole turns over ``period`` (:meth:`_rotation`) is tried as d orbits of k / d turns each, d a divisor
        of k from the largest, so that the orbit found has its least period."""
        shift = self._rotation(state, period, pars)
        k = 1 if shift is None else math.gcd(*(int(abs(round(t))) for t in self._turns(shift) if round(t)))
        for d in [d for d in range(k, 0, -1) if k % d == 0]:
            for segments in (1, 4):
                orbit = find_orbit(self.system, state, period / d, pars, segments=segments,
                                   shift=None if shift is None else shift / d)
                if orbit.converged:
                    return orbit
        return None

    def _turns(self, shift: np.ndarray) -> list:
        """Whole turns of ``shift`` in each state that is a periodic coordinate of the grid."""
        return [shift[self.system.state_index(name)] / (hi - lo) for name, per, lo, hi in
                zip(self.grid.names, self.grid.periodic, self.grid.lower, self.grid.upper)
                if per and name in self.system.state_names]

    def _rotation(self, state, period: float, pars) -> np.ndarray | None:
        """The shift x(period) - x(0) of the states that are periodic coordinates of the grid, in whole turns (a
        rotation: a pendulum running over the top closes on the cylinder, not in the plane); None if there is none."""
        turns = [(self.system.state_index(name), hi - lo) for name, per, lo, hi in
                 zip(self.grid.names, self.grid.periodic, self.grid.lower, self.grid.upper)
                 if per and name in self.system.state_names]
        if not turns:
            return None
        ta = copy.copy(self.system.taylor(self.tol))
        ta.time, ta.state[:] = 0.0, state
        if ta.pars.size:
            ta.pars[:] = pars[: ta.pars.size]
        ta.propagate_until(float(period))
        shift = np.zeros(self.system.n)
        for i, length in turns:
            shift[i] = length * np.round((ta.state[i] - state[i]) / length)
        return shift if np.any(shift) and np.all(np.isfinite(shift)) else None

    def _one_period(self, state, period: float, pars) -> np.ndarray:
        """(n, DENSE_SAMPLES) states of the orbit through ``state`` at equal time steps over one ``period``."""
        ta = copy.copy(self.system.taylor(self.tol))
        ta.time, ta.state[:] = 0.0, state
        if ta.pars.size:
            ta.pars[:] = np.asarray(pars, dtype=float)[: ta.pars.size]
        return ta.propagate_grid(np.linspace(0.0, period, DENSE_SAMPLES, endpoint=False))[-1].T

    def _not_contracting(self, state, pars, window: float) -> bool:
        """Whether the two largest Lyapunov exponents from ``state`` over ``window`` make an irregular attractor:
        the largest not negative (> -3 / window, the finite-time error of a neutral direction) and, besides the flow
        direction's zero, a second exponent that is positive or neutral (chaos: +, 0; a torus: 0, 0). One neutral
        exponent and the rest negative is a cycle that shooting did not close (a forced system's response): no
        irregular attractor; a negative largest one is a slow approach to something else."""
        band = 3.0 / window
        try:
            exponents = spectrum(self.system, state, pars, n_exponents=min(2, self.system.n), t_end=window,
                                 dt=window / 50).exponents
        except TippediskError:
            exponents = np.full(2, math.nan)
        if not exponents[0] > -band:
            self._reject("contracting")
            return False
        if len(exponents) > 1 and exponents[0] <= band and exponents[1] <= -band:
            self._reject("orbit_not_closed")
            return False
        return True

    def integrator(self, batch_size: int):
        return self.system.taylor(self.tol, batch=int(batch_size), events=self._events)

    def observe(self, states, pars):
        states = np.asarray(states, dtype=float).reshape(self.system.n, -1)
        observed = self.system.observe(states, pars) if any(n in self.system.observables for n in self.grid.names) \
            else {}
        return np.array([states[self.system.state_index(n)] if n in self.system.state_names else observed[n]
                         for n in self.grid.names])


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
