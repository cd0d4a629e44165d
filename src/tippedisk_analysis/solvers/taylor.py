"""heyoka Taylor integration of the ODE models (Sect. 4.1).

One integrator is compiled per (model, tolerance) and process, with every physical
parameter a runtime parameter; heyoka's on-disk JIT cache makes later processes
start fast. Outputs are evaluated from the same expressions with a compiled function.
"""

from __future__ import annotations

import copy
import functools
import math
import threading
from dataclasses import dataclass

import heyoka as hy
import numpy as np
import xarray as xr

from ..defaults import FALL_ANGLE, SLIP_SMOOTHING, TAYLOR_TOL
from ..errors import IntegrationError, ParameterError
from ..models import ode
from ..parameters import InitialState, Setup, to_dict
from ..results import describe, flat_parameters, make_attrs


@dataclass(frozen=True)
class CompiledModel:
    model: ode.OdeModel
    integrator: object  # heyoka taylor_adaptive template (copied per run)
    outputs: object  # heyoka cfunc of ode.OUTPUT_NAMES


_THREAD = threading.local()


@functools.lru_cache(maxsize=None)
def compiled(model_name: str, tol: float) -> CompiledModel:
    """The model's integrator (terminal event: fell) and output function, from its System (compiled once per
    process; heyoka's disk cache makes later processes start fast)."""
    model = ode.MODELS[model_name]
    system = ode.as_system(model)
    outputs = system.function("outputs", ode.system(model)[3], f"the outputs of {model.paper_name}")
    return CompiledModel(model, system.taylor(tol, events=("fell",)), outputs)


@dataclass
class Trajectory:
    """Raw result of one integration on an output grid."""

    time: np.ndarray
    states: np.ndarray  # (n_time, n_state)
    outputs: np.ndarray  # (n_outputs, n_time)
    status: str
    message: str
    n_steps: int
    t_final: float


def integrate(model_name: str, setup: Setup, initial: InitialState | np.ndarray, t_end: float, dt_output: float,
              tol: float, fall_angle: float, slip_smoothing: float) -> Trajectory:
    """Integrate from ``initial``: an InitialState (closed contact at C1 without slip, (6.2)) or a full
    state vector of the model (ode.OdeModel.state_names order, e.g. from reduced.full_from_reduced)."""
    cm = compiled(model_name, tol)
    ta = _integrator(cm)
    pars = ode.parameter_vector(setup, fall_angle, slip_smoothing)
    ta.pars[:] = pars
    ta.time = 0.0
    ta.state[:] = initial if isinstance(initial, np.ndarray) else ode.initial_state_vector(cm.model, setup, initial)
    ta.reset_cooldowns()

    grid = output_grid(t_end, dt_output)
    outcome, _min_h, _max_h, n_steps, _cb, states = ta.propagate_grid(grid)
    states = np.asarray(states)
    time = grid[: len(states)]

    if int(outcome) == -1:  # terminal event 0: the disk fell; keep the state at the event
        states = np.vstack([states, ta.state[None, :]])
        time = np.append(time, ta.time)
    outputs = evaluate_outputs(cm.outputs, states, pars)
    finite = np.all(np.isfinite(states), axis=1) & np.all(np.isfinite(outputs), axis=0)
    if outcome == hy.taylor_outcome.err_nf_state or not finite.all():
        keep = len(finite) if finite.all() else int(np.argmin(finite))
        t_last = float(time[keep - 1]) if keep else 0.0
        message = (f"the state or its outputs became non-finite after t = {t_last:.6g} s; the dataset ends there. "
                   "Check the parameters (eps > 0) or try a smaller --tol")
        return Trajectory(time[:keep], states[:keep], outputs[:, :keep], "nonfinite", message, int(n_steps), t_last)
    if int(outcome) == -1:
        status = "fell"
        message = f"the disk fell (tilt down to {fall_angle:g} rad above the table) at t = {ta.time:.6g} s"
    elif outcome == hy.taylor_outcome.time_limit:
        status, message = "completed", f"reached t_end = {t_end:g} s"
    else:  # pragma: no cover - no other outcome is configured
        raise IntegrationError(f"heyoka stopped with unexpected outcome {outcome!r}")
    return Trajectory(time, states, outputs, status, message, int(n_steps), float(ta.time))


def _integrator(cm: CompiledModel):
    """This thread's working copy of the compiled integrator (copying one costs about 1 ms, a fifth of a
    5-s run): every run sets its time, state, parameters and event cooldowns, so a copy is reused."""
    copies = _THREAD.__dict__.setdefault("integrators", {})
    if id(cm) not in copies:  # cm lives in the lru_cache of compiled(): its id is never reused
        copies[id(cm)] = copy.copy(cm.integrator)
    return copies[id(cm)]


def evaluate_outputs(outputs, states: np.ndarray, pars: np.ndarray) -> np.ndarray:
    """Outputs of ode.OUTPUT_NAMES (compiled function ``outputs``) at each row of ``states``, shape (15, n)."""
    n = len(states)
    if n == 0:
        return np.empty((len(ode.OUTPUT_NAMES), 0))
    par_block = np.repeat(pars[: outputs.nparams, None], n, axis=1)
    return outputs(np.ascontiguousarray(states.T), pars=par_block)


def output_grid(t_end: float, dt_output: float) -> np.ndarray:
    """0, dt, 2 dt, ... up to t_end (t_end included)."""
    n = int(math.floor(t_end / dt_output + 1e-9))
    grid = dt_output * np.arange(n + 1)
    if t_end - grid[-1] > 1e-9 * dt_output:
        grid = np.append(grid, t_end)
    return grid


def run(model_name: str, setup: Setup, initial: InitialState, t_end: float, *, dt_output: float = 1e-3,
        tol: float = TAYLOR_TOL, fall_angle: float = FALL_ANGLE, slip_smoothing: float = SLIP_SMOOTHING) -> xr.Dataset:
    """Integrate an ODE model and return the labelled dataset (schema of results.py)."""
    if not (isinstance(fall_angle, int | float) and 0 < fall_angle < math.pi / 2):
        raise ParameterError(f"fall_angle = {fall_angle!r} rad must lie in (0, pi/2) for {model_name} (sin beta = 0 "
                             f"is the Euler-angle singularity); give e.g. {FALL_ANGLE:g}")
    traj = integrate(model_name, setup, initial, t_end, dt_output, tol, fall_angle, slip_smoothing)
    model = ode.MODELS[model_name]
    data = dict(zip(model.state_names, traj.states.T))
    data.update(zip(ode.OUTPUT_NAMES, traj.outputs))
    if model is ode.QUATERNION:
        data["quaternion_norm_error"] = np.sqrt(sum(data[p] ** 2 for p in model.orientation)) - 1.0
    lam = data["lambda_N"]
    attrs = {"n_steps": traj.n_steps, "t_final": traj.t_final, "lambda_N_min": float(lam.min()) if lam.size else 0.0}
    if traj.status == "fell":
        attrs["t_fell"] = traj.t_final
    message = traj.message
    if lam.size and lam.min() < 0:
        t_neg = float(traj.time[np.argmax(lam < 0)])
        message += (f"; lambda_N < 0 from t = {t_neg:.6g} s: the disk would lift off, outside the bilateral "
                    "model's validity (use a Moreau model)")
    options = {"tol": tol, "fall_angle": fall_angle, "slip_smoothing": slip_smoothing}
    return simulation_dataset(model_name, model.paper_name, setup, initial, t_end, dt_output, options, traj.time,
                              data, traj.status, message, attrs)


def simulation_dataset(model_name: str, paper_model: str, setup: Setup, initial: InitialState, t_end: float,
                       dt_output: float, options: dict, time: np.ndarray, data: dict, status: str, message: str,
                       attrs: dict, variables: dict | None = None) -> xr.Dataset:
    """The dataset of every Taylor-integrated run of the disk (ODE Models 1/2, hybrid-euler): the columns ``data``
    (states and outputs along ``time``; alpha and gamma made continuous, E_tot added), ``variables`` of the
    model's own (e.g. the contact mode), the config (with the integrator ``options``: tol, fall_angle, ...) and
    the attributes of results.py plus ``attrs``."""
    data = dict(data)
    for angle in ("alpha", "gamma"):  # continuous angles (the quaternion model recovers them wrapped)
        data[angle] = np.unwrap(data[angle])
    data["E_tot"] = data["E_kin"] + data["E_pot"]
    config = {"model": model_name, "setup": to_dict(setup), "initial": to_dict(initial), "t_end": t_end,
              "dt_output": dt_output,
              "integrator": {"name": "heyoka.taylor_adaptive", "heyoka_version": hy.__version__, **options}}
    columns = {name: ("time", np.asarray(values, dtype=float)) for name, values in data.items()}
    ds = xr.Dataset({**columns, **(variables or {})}, coords={"time": time},
                    attrs=make_attrs("simulation", config, status, message, model=model_name, paper_model=paper_model,
                                     **attrs, integrator="heyoka.taylor_adaptive", tol=options["tol"],
                                     **flat_parameters(setup)))
    return describe(ds)
