"""The recurrence problem of any :class:`~tippedisk_analysis.dynamics.System` (:class:`SystemProblem`): how a
candidate is verified as an equilibrium, a periodic orbit or an irregular attractor before it is one. Its basins:
:mod:`.system_basins`.
"""

from __future__ import annotations

import copy
import dataclasses
import math

import numpy as np

from ...errors import ParameterError, TippediskError
from ..flows import STABILITY
from ..lyapunov import spectrum
from ..orbits import find_orbit
from ..system import System
from .confirm import is_projection
from .problem import Problem, circular_mean, closest_return, describe, equilibrium_description
from .records import BASE_KINDS, Candidate, Description, Grid
from .sets import arc_indices

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
