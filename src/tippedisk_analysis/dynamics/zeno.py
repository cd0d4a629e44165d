"""Leaving a guard's zero without skipping a crossing, and switch times that accumulate (Zeno), for
:func:`~.hybrid.simulate_hybrid`.

Departure. Where a mode is entered on a guard's zero (a reset onto its own guard, as a bounce; the surface a
sliding motion has just left), heyoka would find that zero again at once. The run first takes the stretch
over which the guard leaves the band |g| < BAND eps_g about zero (eps_g = ROUND_OFF times the size of the
states it reads). The stretch is read off the Taylor polynomials of one step, x(t0 + tau) = sum_k c_k tau^k
(exact for a polynomial flow), with every terminal event evaluated on a geometric grid of tau: its length
follows the guard's own rate, BAND eps_g / |dg/dt|, or (BAND eps_g k! / |g^(k)|)^(1/k) where the first k - 1
derivatives vanish (a sliding exit). Nothing in it goes unseen: a guard that leaves into the side it fires on (g falling
for a ``negative`` guard) fires at once; any other event whose sign turns in it fires at its root there; a
guard that stays in the band for the whole step rests on its zero for that step.

Accumulation. Switch times t_k approaching t_z with intervals d_k = t_k - t_{k-1} that shrink geometrically,
d_k = r d_{k-1}, have t_z = t_k + d_k r / (1 - r) (Aitken's delta-squared extrapolation). A run stops with
``zeno`` once ZENO_INTERVALS such intervals (of every p-th switch, p = 1, 2, 3, for cycles of p switches)
agree on t_z and the time left is below ZENO_LEFT of the time run; or once ZENO_INSTANT switches fall within
the time round-off of one instant (the motion stays on a guard).
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field

import heyoka as hy
import numpy as np

ROUND_OFF = 1e-13  # a guard within this (relative to the size of the states it reads) of zero is at zero
BAND = 10.0  # a guard has left its zero once |g| >= BAND * its round-off (heyoka's cooldown uses the same factor)
OCTAVES, PER_OCTAVE, UNIFORM = 70, 8, 64  # the tau grid: geometric down to 2^-70 of the step, and uniform
ZENO_INTERVALS = 8  # consecutive geometric intervals before an accumulation is believed
ZENO_AGREEMENT = 1e-2  # the last three extrapolations of t_z agree to this fraction of the time left
ZENO_LEFT = 1e-4  # a run stops once the time left to t_z is below this fraction of the time run
ZENO_INSTANT = 16  # this many switches within the time round-off of one instant stop a run
TIME_ROUND_OFF = 1e-12  # [time units, relative to max(1, |t|)] intervals this short are round-off
ZENO_TAIL = 3 * (ZENO_INTERVALS + 2)  # the switch times :func:`accumulation` needs (the last ones)


@dataclass
class Departure:
    """Where the integration of a mode entered at (t0, x0) starts: (time, state) past every guard's zero, the
    output samples inside the stretch; or the event (index into the mode's terminal events) that fires in it
    at (time, state); or status ``nonfinite`` when the step's Taylor coefficients overflow."""

    time: float
    state: np.ndarray
    samples: list = field(default_factory=list)  # [(t, x)] at output times inside the stretch
    fired: int | None = None
    status: str = "ok"
    rests: bool = False  # a guard stayed on its zero for the whole step


class Departures:
    """Per mode of a hybrid system: an event-free Taylor integrator (its step's coefficients; never heyoka's
    event detection, so an overflowing step gives no log line) and the mode's terminal events as one function."""

    def __init__(self, hybrid, tol: float, pars: np.ndarray):
        self.hybrid, self.pars = hybrid, pars
        self._probe, self._events, self._reads = {}, {}, {}
        self.tol = tol

    def _for(self, mode: str):
        if mode not in self._probe:
            system = self.hybrid.system(mode)
            ta = copy.copy(system.taylor(self.tol))
            ta.pars[:] = self.pars[: len(ta.pars)]
            self._probe[mode] = ta
            self._events[mode] = self.hybrid.modes[mode].function(
                "terminal events", [e.expression for e in system.events], "the terminal events") if system.events \
                else None
            names = [str(v) for v in system.variables]
            self._reads[mode] = [[names.index(v) for v in hy.get_variables(e.expression)] for e in system.events]
        return self._probe[mode], self._events[mode]

    def bands(self, mode: str, x: np.ndarray) -> np.ndarray:
        """Each terminal event's round-off at state x: ROUND_OFF times the size (at least 1) of the states it
        reads (an unrelated large state, a position or an angle run up, leaves it alone)."""
        self._for(mode)
        return np.array([ROUND_OFF * max(1.0, float(np.max(np.abs(x[idx])))) if idx else ROUND_OFF
                         for idx in self._reads[mode]])

    def values(self, mode: str, states) -> np.ndarray:
        """The mode's terminal events (its own, then its guards) at states (n,) or (n, N)."""
        function = self._for(mode)[1]
        if function is None:
            return np.zeros((0, *np.shape(states)[1:]))
        return self.hybrid.modes[mode].evaluate(function, states, self.pars)

    def depart(self, mode: str, t0: float, x0: np.ndarray, t_end: float, grid) -> Departure:
        """Where to start ``mode`` entered at (t0, x0): past every guard's zero, step after step while a guard
        rests on it."""
        samples = []
        while True:
            dep = self._depart_step(mode, t0, x0, t_end, grid)
            samples += dep.samples
            if not dep.rests or dep.time <= t0 or dep.time >= t_end:
                dep.samples = samples
                return dep
            t0, x0 = dep.time, dep.state

    def _depart_step(self, mode: str, t0: float, x0: np.ndarray, t_end: float, grid) -> Departure:
        ta, _f = self._for(mode)
        ta.time, ta.state[:] = t0, x0
        _outcome, h = ta.step(max_delta_t=max(t_end - t0, 0.0), write_tc=True)
        tc = np.array(ta.tc)
        if not (math.isfinite(h) and np.all(np.isfinite(tc))):
            return Departure(t0, x0, status="nonfinite")
        ends = self.values(mode, polynomial(tc, np.array([0.0, abs(h)])))  # events overflow too (heyoka's step)
        if not np.all(np.isfinite(ends)):
            return Departure(t0, x0, status="nonfinite")
        events = self.hybrid.system(mode).events
        n_own = len(self.hybrid.modes[mode].events)
        band = self.bands(mode, x0)
        v0 = ends[:, 0]
        at_zero = [i for i in range(n_own, len(events)) if abs(v0[i]) <= band[i]]
        if not at_zero:
            return Departure(t0, x0)
        step = abs(h)
        taus = np.unique(np.concatenate([[0.0], step * 2.0 ** (-np.arange(OCTAVES * PER_OCTAVE, -1, -1) / PER_OCTAVE),
                                         np.linspace(0.0, step, UNIFORM + 1)]))
        X = polynomial(tc, taus)
        V = self.values(mode, X)
        start, fire = {}, None  # start: where each guard at zero has left its band (the stretch before is in it)
        for i in at_zero:
            out = np.flatnonzero(np.abs(V[i]) >= BAND * band[i])
            start[i] = int(out[0]) if out.size else len(taus) - 1  # none: it rests on its zero for the whole step
            if out.size and fires_on(events[i].direction, V[i, start[i]]):
                fire = (0, i) if fire is None else min(fire, (0, i))
        clear = max(start.values())
        if fire is not None:  # at once: the flow leaves the zero into the guard's firing side
            return Departure(t0, x0, fired=fire[1])
        for i in range(len(events)):  # any event turning sign inside the stretch (after its own) fires at its root
            for j in range(start.get(i, 0) + 1, clear + 1):
                if crosses(events[i].direction, V[i, j - 1], V[i, j]):
                    tau = self._root(mode, i, tc, taus[j - 1], taus[j])
                    fire = (tau, i) if fire is None else min(fire, (tau, i))
                    break
        if fire is not None:
            return Departure(t0 + fire[0], polynomial(tc, np.array([fire[0]]))[:, 0], fired=fire[1])
        t_clear = t0 + taus[clear]
        samples = []
        if grid is not None:
            inside = grid[(grid > t0) & (grid <= t_clear)]
            samples = list(zip(inside, polynomial(tc, inside - t0).T))
        return Departure(t_clear, X[:, clear].copy(), samples, rests=clear == len(taus) - 1)

    def _root(self, mode: str, i: int, tc: np.ndarray, a: float, b: float) -> float:
        """tau in [a, b] where event i changes sign (bisection on the step's polynomials)."""
        fa = self.values(mode, polynomial(tc, np.array([a]))[:, 0])[i]
        for _ in range(60):
            m = 0.5 * (a + b)
            fm = self.values(mode, polynomial(tc, np.array([m]))[:, 0])[i]
            if (fm > 0) == (fa > 0):
                a, fa = m, fm
            else:
                b = m
        return b


def polynomial(tc: np.ndarray, taus: np.ndarray) -> np.ndarray:
    """States (n, len(taus)) from a step's Taylor coefficients tc (n, order + 1) at offsets taus (Horner)."""
    out = np.repeat(tc[:, -1:], len(taus), axis=1)
    for k in range(tc.shape[1] - 2, -1, -1):
        out = out * taus + tc[:, k:k + 1]
    return out


def fires_on(direction: str, value: float) -> bool:
    """Whether a guard leaving its zero to ``value`` has crossed it in its direction."""
    return (direction == "negative" and value < 0) or (direction == "positive" and value > 0)


def crosses(direction: str, before: float, after: float) -> bool:
    """Whether an event going from ``before`` to ``after`` crosses zero in its direction."""
    down, up = before > 0 >= after, before < 0 <= after
    return down if direction == "negative" else up if direction == "positive" else down or up


def accumulation(times, t_start: float) -> tuple[float, int, float] | None:
    """(t_z, p, r) when switch ``times`` accumulate (module docstring): the extrapolated time, the switches per
    cycle and the ratio of the last intervals (0 for switches within round-off of one instant); else None."""
    t = np.asarray(times, dtype=float)
    if len(t) > ZENO_INSTANT and np.ptp(t[-ZENO_INSTANT:]) <= ZENO_INSTANT * TIME_ROUND_OFF * max(1.0, abs(t[-1])):
        return float(t[-1]), 1, 0.0
    for p in (1, 2, 3):
        sub = t[::-1][::p][::-1][-(ZENO_INTERVALS + 2):]
        if len(sub) < ZENO_INTERVALS + 2:
            return None
        d = np.diff(sub)
        if np.any(d <= TIME_ROUND_OFF * max(1.0, abs(sub[-1]))):
            continue
        r = d[1:] / d[:-1]
        if not np.all(r < 1.0):
            continue
        estimates = sub[2:] + d[1:] * r / (1 - r)
        left = estimates[-1] - sub[-1]
        if np.ptp(estimates[-3:]) <= ZENO_AGREEMENT * left and left <= ZENO_LEFT * (estimates[-1] - t_start):
            return float(estimates[-1]), p, float(r[-1])
    return None
