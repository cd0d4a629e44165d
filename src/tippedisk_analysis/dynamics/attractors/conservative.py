"""Conservative flows have no attractors: the volume test of :func:`.system_basins.basins`, and what it stores per
start in their place.

Liouville: a flow x' = f(x) changes phase-space volume at the rate div f = tr(df/dx). Where its time average along
the runs is zero, volume is preserved, no set attracts a neighbourhood of positive volume, and the basin question has
no answer (Henon-Heiles: div f = 0; a Lotka-Volterra centre: div f = d/dt log(x y), zero on average).

The test (:func:`volume_test`): PROBES runs from starts spread over the box of initial values (a Halton sequence, not
the user's grid, whose symmetric points may be equilibria or invariant lines), sampled every ``dt`` to the horizon.
Over the second half of each run (past the transient) the log volume I(t) = int div f dt gives the mean divergence
(I's change over the half's length) and its error (I's range about its chord over that length): a conservative
flow's I is bounded and drifts by no more than it oscillates, a dissipative flow's falls steadily (constant damping:
a straight line, error 0). A run counts when its half holds MIN_BLOCKS blocks of two correlation times of div f (else
it is too short to tell). The flow is conservative when at least two probes count and every one has
|mean| <= Z error + ROUNDOFF rms(div f); a damped system, however weakly, keeps its attractors.

Per start in place of basins (:func:`conservative_chunk`): the outcome ``bounded`` (in the grid up to the horizon),
``left_grid`` (at its first exit), the System's terminal events, ``diverged`` (non-finite after leaving the grid) or
``failed``; the mean divergence and its error; the levels of the System's first integrals at the start and their
largest drift along the run (the integration's check).
"""

from __future__ import annotations

import copy
import dataclasses

import heyoka as hy
import numpy as np

from .records import DIVERGED, RecurrenceSettings

PROBES = 8  # runs of the volume test
MIN_BLOCKS = 4  # correlation-time pairs a run's second half must hold to tell
Z = 1.0  # a log volume that drifts by at most Z times its oscillation is bounded
ROUNDOFF = 1e-9  # share of rms(div f) below which a mean divergence is round-off
MIN_SAMPLES = 64  # finite samples of a run's second half needed to tell
BOUNDED = "bounded"


@dataclasses.dataclass
class Runs:
    """Per run: how it ended (a label of :func:`conservative_labels`), when, its mean divergence over its second
    half with the error and the rms of div f there (NaN: too short), its finite samples, the first integrals'
    levels at the start and their largest drift (k, N)."""

    outcome: np.ndarray
    end_time: np.ndarray
    divergence: np.ndarray
    error: np.ndarray
    rms: np.ndarray
    samples: np.ndarray
    level: np.ndarray
    drift: np.ndarray


@dataclasses.dataclass
class VolumeTest:
    conservative: bool
    divergence: np.ndarray  # (PROBES,) mean div f of each probe's second half (NaN: too short)
    error: np.ndarray  # (PROBES,)
    message: str


def conservative_labels(problem) -> dict[str, int]:
    """The outcome labels of runs of a conservative flow: ``bounded`` (0) and the problem's negative labels
    without ``undecided`` (a run that stays is bounded, not undecided)."""
    labels = {k: v for k, v in problem.labels().items() if k != "undecided"}
    return {BOUNDED: 0, **labels}


def halton(count: int, dims: int) -> np.ndarray:
    """(dims, count) points of the Halton sequence (bases 2, 3, 5) in (0, 1)."""
    out = np.empty((dims, count))
    for d, base in enumerate((2, 3, 5)[:dims]):
        for i in range(count):
            f, k, value = 1.0, i + 1, 0.0
            while k:
                f /= base
                value += f * (k % base)
                k //= base
            out[d, i] = value
    return out


def probe_starts(system, axes: dict, state) -> np.ndarray:
    """(n, PROBES) starts of the volume test: Halton points in the box of the initial values ``axes``."""
    x0 = np.repeat(np.asarray(state, dtype=float)[:, None], PROBES, axis=1)
    h = halton(PROBES, len(axes))
    for d, (name, (a, b, _n)) in enumerate(axes.items()):
        x0[system.state_index(name)] = a + (b - a) * h[d]
    return x0


def _divergence_function(system):
    div = sum((hy.diff(f, v) for f, v in zip(system.rhs, system.variables)), hy.expression(0.0))
    return system.function("divergence", [div], "the divergence")


def correlation_time(d: np.ndarray) -> int:
    """Samples over which d stays correlated: 4 times the first zero of its autocorrelation (a period where d
    oscillates), 0 where d is constant to round-off."""
    v = d - d.mean()
    if np.max(np.abs(v)) <= ROUNDOFF * np.max(np.abs(d)):
        return 0
    spectrum = np.fft.rfft(v, 2 * len(v))
    ac = np.fft.irfft(spectrum * np.conj(spectrum))[: len(v)]
    below = np.flatnonzero(ac <= 0)
    return 4 * int(below[0]) if len(below) else len(v)


def _mean_and_error(times: np.ndarray, d: np.ndarray) -> tuple[float, float, float]:
    """Over the second half of ``times``: the mean of d, its error, and the rms of d; NaN where the half holds fewer
    than MIN_BLOCKS blocks of two correlation times. The error is the range of the log volume I(t) = int d dt about
    its chord, over the half's length: a bounded I (a conservative flow) drifts by no more than it oscillates."""
    half = len(d) // 2
    t, v = times[half:], d[half:]
    if len(v) < MIN_SAMPLES or len(v) < MIN_BLOCKS * 2 * correlation_time(v):
        return np.nan, np.nan, np.nan
    volume = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
    length = t[-1] - t[0]
    residual = volume - volume[-1] * (t - t[0]) / length
    return float(volume[-1] / length), float(np.ptp(residual) / length), float(np.sqrt(np.mean(v * v)))


def sample_runs(problem, settings: RecurrenceSettings, x0, pars, batch_size: int) -> Runs:
    """Runs of ``problem``'s System from the starts x0 (n, N), sampled every ``settings.dt`` to the horizon."""
    system = problem.system
    x0, pars = np.asarray(x0, dtype=float), np.asarray(pars, dtype=float)
    N = x0.shape[1]
    labels = conservative_labels(problem)
    times = settings.dt * np.arange(int(np.floor(settings.horizon / settings.dt + 1e-9)) + 1)
    div_fn = _divergence_function(system)
    integrals = list(system.integrals.values())
    int_fn = system.function("integrals", integrals, "the first integrals") if integrals else None
    template = problem.integrator(batch_size)
    B = template.batch_size
    runs = Runs(np.zeros(N, dtype=np.int64), np.zeros(N), np.full(N, np.nan), np.full(N, np.nan),
                np.full(N, np.nan), np.zeros(N, dtype=np.int64), np.zeros((len(integrals), N)), np.zeros((len(integrals), N)))
    err_nf = hy.taylor_outcome.err_nf_state
    for first in range(0, N, B):
        lanes = np.minimum(np.arange(first, first + B), N - 1)  # idle lanes repeat the last start
        out, ends = _block_runs(template, problem, x0[:, lanes], times, pars)
        for lane, p in enumerate(range(first, min(first + B, N))):
            X = out[:, :, lane].T
            finite = np.all(np.isfinite(X), axis=0)
            k = int(np.argmin(finite)) if not finite.all() else len(times)
            X = X[:, :k]
            keys = problem.grid.keys(problem.observe(X, pars)) if k else np.zeros(0, dtype=np.int64)
            outside = np.flatnonzero(keys < 0)
            res, t_stop, x_stop = ends[lane]
            event = system.stopping_event(res, problem.terminal_labels)
            if event is not None:
                label, end = problem.terminal_labels[event], t_stop
            elif res == err_nf or k < len(times):  # non-finite: an escape if it was outside the grid on the way
                # heyoka stops at the step that overflowed: its finite components tell an escape to infinity
                last = np.nan_to_num(x_stop[:, None], nan=0.0, posinf=1e300, neginf=-1e300)
                gone = len(outside) or problem.grid.keys(problem.observe(last, pars))[0] < 0
                label, end = (DIVERGED if gone else "failed"), float(times[max(k - 1, 0)])
            elif len(outside):
                label, end = "left_grid", float(times[outside[0]])
            else:
                label, end = BOUNDED, float(times[-1])
            runs.outcome[p], runs.end_time[p], runs.samples[p] = labels[label], end, k
            if k:
                d = system.evaluate(div_fn, X, pars)[0]
                runs.divergence[p], runs.error[p], runs.rms[p] = _mean_and_error(times[:k], d)
            if int_fn is not None:
                levels = system.evaluate(int_fn, np.concatenate([x0[:, p:p + 1], X], axis=1), pars).reshape(
                    len(integrals), -1)
                runs.level[:, p] = levels[:, 0]
                runs.drift[:, p] = np.max(np.abs(levels - levels[:, :1]), axis=1)
    return runs


def _block_runs(template, problem, x0: np.ndarray, times: np.ndarray, pars: np.ndarray) -> tuple[np.ndarray, list]:
    """The samples (K, n, B) at ``times`` of the batch's runs from x0 (n, B), NaN after a run stops, and per lane
    (outcome, time, state) where it stopped. heyoka ends a batch's ``propagate_grid`` for every lane when one lane
    fails or stops at an event: a lane cut short that way is run again in a batch of its own start only."""
    def propagate(starts):
        ta = copy.copy(template)
        B = ta.batch_size
        ta.set_time(np.zeros(B))
        ta.state[:] = starts
        if ta.pars.size:
            ta.pars[:] = np.repeat(pars[: ta.pars.shape[0], None], B, axis=1)
        if problem.terminal_labels:
            ta.reset_cooldowns()
        out = ta.propagate_grid(np.repeat(times[:, None], B, axis=1))[-1]
        return out, [(ta.propagate_res[i][0], float(ta.time[i]), np.array(ta.state[:, i])) for i in range(B)]

    out, ends = propagate(x0)
    own_end = (hy.taylor_outcome.time_limit, hy.taylor_outcome.err_nf_state)
    for lane, (res, _, _) in enumerate(ends):
        if res not in own_end and problem.system.stopping_event(res, problem.terminal_labels) is None:
            alone, alone_ends = propagate(np.repeat(x0[:, lane:lane + 1], x0.shape[1], axis=1))
            out[:, :, lane], ends[lane] = alone[:, :, 0], alone_ends[0]
    return out, ends


def volume_test(problem, settings: RecurrenceSettings, axes: dict, state, pars, batch_size: int) -> VolumeTest:
    """Whether the flow preserves phase-space volume along PROBES runs (module docstring)."""
    system = problem.system
    x0 = probe_starts(system, axes, state)
    runs = sample_runs(problem, settings, x0, pars, batch_size)
    used = np.isfinite(runs.divergence)
    zero = np.abs(runs.divergence) <= Z * runs.error + ROUNDOFF * runs.rms
    conservative = bool(used.sum() >= 2 and np.all(zero[used]))
    worst = int(np.nanargmax(np.abs(runs.divergence) - Z * runs.error)) if used.any() else -1
    if worst < 0:
        message = f"no probe ran {MIN_SAMPLES} samples: the volume test could not decide"
    else:
        message = (f"mean divergence tr(df/dx) along {int(used.sum())} of {PROBES} probe runs "
                   f"{'zero' if conservative else 'not zero'} within its error (largest "
                   f"{runs.divergence[worst]:.3g} +- {runs.error[worst]:.2g})")
    return VolumeTest(conservative, runs.divergence, runs.error, message)
