"""Rule-based classification of outcome-map runs (``classify="rules"``, see :mod:`.outcome_map`).

ODE Model 1 is augmented with the quadratures Q1' = sin(gamma), Q2' = z_S (exact window means) and run in
heyoka batch mode; first crossings (inversion gamma = 0, lift-off lambda_N = 0) are non-terminal events,
the fall is terminal. :func:`run_rules` returns the per-point :data:`RESULT_VARIABLES`.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import math

import numpy as np

from ..models import ode
from ..models.variables import FINAL_STATE_VARIABLES
from .outcome_config import FILL_TIME, OUTCOMES, MapConfig, prepare

class _FirstCrossing:
    """Batch nt_event callback: the first crossing per lane (gamma = 0 upwards; lambda_N = 0 downwards)."""

    def __init__(self):
        self.first = None  # per-lane first crossing time (FILL_TIME if none yet)
        self.done = None  # lanes whose run ended: events there are ignored

    def __call__(self, ta, time, d_sign, batch_idx):
        if self.first is not None and not self.done[batch_idx] and self.first[batch_idx] == FILL_TIME:
            self.first[batch_idx] = time


def augmented_system():
    """ODE Model 1 as a System with the quadratures Q1' = sin(gamma), Q2' = z_S (window means) as extra
    equations, and the non-terminal events of the first inversion (gamma = 0 upwards) and lift-off (lambda_N = 0
    downwards): (system, extra, nt_events) for :meth:`~tippedisk_analysis.dynamics.System.taylor`."""
    import heyoka as hy

    system = ode.as_system(ode.EULER)
    q1, q2 = hy.make_vars("Q_sin_gamma", "Q_z_S")
    gamma = system.variables[system.state_index("gamma")]
    extra = ((q1, hy.sin(gamma)), (q2, system.observables["z_S"][0]))
    return system, extra, ((gamma, "positive"), (system.observables["lambda_N"][0], "negative"))


@dataclasses.dataclass(frozen=True)
class BatchKernel:
    integrator: object  # taylor_adaptive_batch template
    outputs: object  # cfunc of ode.OUTPUT_NAMES over the model state
    batch_size: int


@functools.lru_cache(maxsize=4)
def kernel(tol: float, batch_size: int = 4) -> BatchKernel:
    """Compiled batch integrator and outputs (cached per process; heyoka also caches on disk)."""
    system, extra, crossings = augmented_system()
    B = int(batch_size)
    batch = system.taylor(tol, batch=B, events=("fell",), extra=extra,
                          nt_events=tuple((x, _FirstCrossing(), d) for x, d in crossings))
    outputs = system.function("outputs", ode.system(ode.EULER)[3], "the outputs of ODE Model 1")
    return BatchKernel(batch, outputs, B)


RESULT_VARIABLES = {
    # name: (dtype, units, long_name)
    "outcome": (np.int8, "1", "classified outcome of the run"),
    "inversion_time": (float, "s", "first upward crossing of gamma = 0 (fill -1: none)"),
    "lift_off_time": (float, "s", "first time lambda_N fell through 0 (fill -1: the contact held)"),
    "valid": (np.int8, "1", "1: lambda_N > 0 throughout (the bilateral contact model held), 0: it would lift off"),
    "fall_time": (float, "s", "time the tilt reached fall_angle (fill -1: did not fall)"),
    "t_final": (float, "s", "time the run ended"),
    "gamma_turns": (float, "1", "(gamma(t_final) - gamma(window start)) / (2 pi)"),
    "sin_gamma_mean": (float, "1", "time mean of sin(gamma) over the classification window"),
    "z_S_mean": (float, "m", "time mean of z_S over the classification window"),
    **FINAL_STATE_VARIABLES,
}

BYTES_PER_POINT = sum(np.dtype(dtype).itemsize for dtype, _, _ in RESULT_VARIABLES.values())
"""Memory of one grid point's results (the dataset; sweeps.MERGE_FACTOR covers the copies at the merge)."""


def _finish(config: MapConfig, k: BatchKernel, raw: dict, pars: np.ndarray) -> dict:
    """Classification and final outputs from the raw per-point results."""
    n_state = len(ode.EULER.state_names)
    final = raw["final_state"]
    outs = k.outputs(np.ascontiguousarray(final[:n_state]), pars=np.ascontiguousarray(pars[: k.outputs.nparams]))
    o = dict(zip(ode.OUTPUT_NAMES, outs))
    t_final, t_w = raw["t_final"], raw["t_window"]
    span = t_final - t_w
    sin_mean = (final[n_state] - raw["q_window"][0]) / np.where(span > 0, span, 1.0)
    zs_mean = (final[n_state + 1] - raw["q_window"][1]) / np.where(span > 0, span, 1.0)
    sin_mean = np.where(span > 0, sin_mean, np.sin(final[ode.EULER.state_names.index("gamma")]))
    zs_mean = np.where(span > 0, zs_mean, o["z_S"])
    outcome = np.full(t_final.shape, OUTCOMES["undecided"], dtype=np.int8)
    outcome[sin_mean >= config.threshold] = OUTCOMES["inverted"]
    outcome[sin_mean <= -config.threshold] = OUTCOMES["not_inverted"]
    turns = (final[ode.EULER.state_names.index("gamma")] - raw["gamma_window"]) / (2 * math.pi)
    outcome[np.abs(turns) >= 1.0] = OUTCOMES["rolling"]
    outcome[raw["fell"]] = OUTCOMES["fell"]
    outcome[raw["failed"]] = OUTCOMES["failed"]
    res = {
        "outcome": outcome,
        "inversion_time": raw["inversion_time"],
        "lift_off_time": raw["lift_off_time"],
        "valid": (raw["lift_off_time"] < 0).astype(np.int8),
        "fall_time": np.where(raw["fell"], t_final, FILL_TIME),
        "t_final": t_final,
        "gamma_turns": turns,
        "sin_gamma_mean": sin_mean,
        "z_S_mean": zs_mean,
        "E_tot_final": o["E_kin"] + o["E_pot"],
        "E_kin_final": o["E_kin"],
        "beta_final": o["beta"],
        "gamma_final": o["gamma"],
        "alpha_dot_final": o["alpha_dot"],
        "z_S_final": o["z_S"],
    }
    failed = raw["failed"]
    for name, values in res.items():  # never a NaN: non-finite values (failed runs) stored as 0, times as -1
        if values.dtype.kind == "f":
            res[name] = np.where(np.isfinite(values), values, FILL_TIME if "time" in name else 0.0)
    res["outcome"][failed | ~np.isfinite(outs).all(axis=0)] = OUTCOMES["failed"]
    return res


def run_rules(config: MapConfig, start: int, stop: int) -> dict:
    """Rule-based outcome of grid points [start, stop): batch mode, SIMD lanes of the kernel's batch size."""
    k = kernel(float(config.tol), int(config.batch_size))
    B = k.batch_size
    x0, pars = prepare(config, start, stop)
    n = stop - start
    raw = {"final_state": np.empty_like(x0), "t_final": np.empty(n), "t_window": np.empty(n),
           "q_window": np.zeros((2, n)), "gamma_window": np.empty(n), "fell": np.zeros(n, bool),
           "failed": np.zeros(n, bool), "inversion_time": np.full(n, FILL_TIME),
           "lift_off_time": np.full(n, FILL_TIME)}
    ta_template = copy.copy(k.integrator)  # one integrator per chunk, reused batch after batch
    for b0 in range(0, n, B):
        lanes = np.arange(b0, min(b0 + B, n))
        idx = np.concatenate([lanes, np.full(B - len(lanes), lanes[-1])])  # pad with the last point
        res = _run_batch(ta_template, x0[:, idx], pars[:, idx], config)
        m = len(lanes)
        for key, val in res.items():
            raw[key][..., lanes] = val[..., :m]
    return _finish(config, k, raw, pars)


def _run_batch(ta, x0: np.ndarray, pars: np.ndarray, config: MapConfig) -> dict:
    import heyoka as hy

    B = x0.shape[1]
    ta.set_time(np.zeros(B))
    ta.state[:] = x0
    ta.pars[:] = pars
    ta.reset_cooldowns()
    inversion, lift_off = (event.callback for event in ta.nt_events)
    done = np.zeros(B, bool)
    for rec in (inversion, lift_off):
        rec.first, rec.done = np.full(B, FILL_TIME), done
    fell, failed = np.zeros(B, bool), np.zeros(B, bool)
    final = np.empty_like(x0)
    t_final = np.empty(B)
    t_w = config.t_end - config.window
    q_window = np.zeros((2, B))
    t_window = np.zeros(B)  # window start actually used (0 if the run ended before it)
    n_state = x0.shape[0] - 2
    i_gamma = ode.EULER.state_names.index("gamma")
    gamma_window = x0[i_gamma].copy()

    def advance(t_target):
        while True:
            ta.propagate_until(t_target)
            for i, r in enumerate(ta.propagate_res):
                if done[i]:
                    continue
                oc = r[0]
                if oc == hy.taylor_outcome.time_limit:
                    continue
                if int(oc) == -1:  # terminal event 0: the disk fell
                    fell[i] = True
                elif oc == hy.taylor_outcome.err_nf_state:
                    failed[i] = True
                else:
                    continue  # stopped because another lane triggered its terminal event
                done[i] = True
                final[:, i] = ta.state[:, i]
                t_final[i] = ta.time[i]
            active = np.flatnonzero(~done)
            if len(active) == 0 or np.all(ta.time[active] >= t_target):
                return
            # lanes that ended shadow an active lane from here on (their events are ignored)
            j = active[0]
            times = np.array(ta.time)
            st = np.array(ta.state)
            for i in np.flatnonzero(done):
                st[:, i] = st[:, j]
                times[i] = times[j]
            ta.state[:] = st
            ta.set_time(times)
            ta.reset_cooldowns()

    if t_w > 0:
        advance(t_w)
        alive = ~done
        q_window[:, alive] = ta.state[n_state:, alive]
        gamma_window[alive] = ta.state[i_gamma, alive]
        t_window[alive] = t_w
    advance(config.t_end)
    alive = ~done
    final[:, alive] = ta.state[:, alive]
    t_final[alive] = ta.time[alive]
    return {"final_state": final, "t_final": t_final, "t_window": t_window, "q_window": q_window,
            "gamma_window": gamma_window, "fell": fell, "failed": failed, "inversion_time": inversion.first.copy(),
            "lift_off_time": lift_off.first.copy()}
