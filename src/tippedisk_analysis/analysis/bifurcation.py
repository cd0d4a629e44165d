"""Brute-force bifurcation diagram: a quantity at Poincaré crossings after transients vs Omega.

For each initial spin Omega = alpha_dot(0) the trajectory from Table 3 is integrated, the
crossings of the section (default ``beta_dot = 0``, upward) before ``t_transient`` are
skipped and the next ``max_crossings`` crossings are kept (:mod:`.poincare`). The crossings
of all Omega values are stored along one dimension ``point`` (a ragged set, no padding):
``omega_of_point`` says which Omega each belongs to; per Omega, ``n_crossings`` and the
run's ``status_code`` (flag values as in :data:`STATUS`).

Execution is a chunked, resumable :class:`.sweeps.Sweep` over the Omega values (threads, or a
dask cluster): with an ``output`` every finished chunk of Omega values is stored in
``<output>.chunks/`` and a rerun after Ctrl-C computes only the missing ones; the memory of the
result is estimated first and a diagram that cannot fit is refused.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import xarray as xr

from ..defaults import BIFURCATION_TOL, FALL_ANGLE
from ..errors import ParameterError
from ..models import ode
from ..parameters import InitialState, Setup, setup_from_dict, to_dict
from ..ranges import check_axis, check_range
from ..results import VARIABLES, describe, make_attrs
from ..dynamics import sweeps
from . import poincare

__all__ = ["bifurcation_diagram"]

STATUS = {"completed": 0, "fell": 1, "nonfinite": 2}
ANGLES = ("alpha", "gamma")  # stored wrapped into (-pi, pi] as ``value``
CHUNK_SIZE = 8
"""Omega values per stored chunk (a few seconds of work with the default 10-s runs)."""
SECONDS_PER_RUN_SECOND = 0.01
"""Work of one run per simulated second on one core at tol 1e-12 (measured 0.008 s)."""
PER_OMEGA = ("n_crossings", "status_code", "valid")
PER_CROSSING = ("omega_of_point", "time", "value", "beta", "gamma")


def _omega_axis(omega) -> dict | list:
    """The description of a range (start, stop, n) (nothing materialised yet) or of an array, for the config."""
    if isinstance(omega, tuple) and len(omega) == 3:
        start, stop, n = check_range(omega, "omega")
        return {"start": start, "stop": stop, "n": n}
    return check_axis(omega, "omega").tolist()


def _n_omega(config: dict) -> int:
    om = config["omega"]
    return int(om["n"]) if isinstance(om, dict) else len(om)


def _config_values(config: dict, start: int = 0, stop: int | None = None) -> np.ndarray:
    """The Omega values [start, stop) of the configuration (as numpy.linspace computes them)."""
    om = config["omega"]
    if isinstance(om, dict):
        return np.linspace(om["start"], om["stop"], om["n"])[start:stop] if om["n"] <= 1_000_000 else \
            _linspace_slice(om["start"], om["stop"], om["n"], start, om["n"] if stop is None else stop)
    return np.asarray(om, dtype=float)[start:stop]


def _linspace_slice(a: float, b: float, n: int, i0: int, i1: int) -> np.ndarray:
    step = (b - a) / (n - 1)
    values = a + np.arange(i0, i1) * step
    if i1 == n:
        values[-1] = b
    return values


def _setup_of(config: dict) -> tuple[Setup, InitialState]:
    return setup_from_dict(config["setup"]), InitialState(**config["initial"])


def run_chunk(config: dict, start: int, stop: int) -> dict:
    """Crossings of the Omega values [start, stop) (module-level: a dask worker runs it from the config)."""
    setup, initial = _setup_of(config)
    sec = poincare.Section(**config["section"])
    omegas = _config_values(config, start, stop)
    out = {k: [] for k in (*PER_OMEGA, *PER_CROSSING)}
    quantity = config["quantity"]
    for om in omegas:
        ds = poincare.poincare_section(sec, model=config["model"], setup=setup,
                                       initial=dataclasses.replace(initial, alpha_dot=float(om)),
                                       t_transient=config["t_transient"], t_end=config["t_end"],
                                       max_crossings=config["max_crossings"], tol=config["integrator"]["tol"],
                                       fall_angle=config["integrator"]["fall_angle"])
        n = ds.sizes["crossing"]
        out["n_crossings"].append(np.int64(n))
        out["status_code"].append(np.int8(STATUS[ds.attrs["status"]]))
        out["valid"].append(np.int8(ds.attrs["valid"]))
        value = ds[quantity].values
        if quantity in ANGLES:  # unwrapped angles: wrap into (-pi, pi] to compare crossings
            value = np.pi - np.mod(np.pi - value, 2 * np.pi)
        out["omega_of_point"].append(np.full(n, om))
        out["time"].append(ds["time"].values)
        out["value"].append(np.asarray(value, dtype=float))
        out["beta"].append(ds["beta"].values)
        out["gamma"].append(ds["gamma"].values)
    res = {k: np.array(out[k], dtype={"n_crossings": np.int64}.get(k, np.int8)) for k in PER_OMEGA}
    res.update({k: np.concatenate(out[k]).astype(float) if out[k] else np.empty(0) for k in PER_CROSSING})
    return res


def bifurcation_diagram(omega, *, quantity: str = "gamma", section: str = "beta_dot=0", direction: str = "positive",
                        setup: Setup | None = None, initial: InitialState | None = None, t_transient: float = 5.0,
                        t_end: float = 10.0, max_crossings: int | None = 50, tol: float = BIFURCATION_TOL,
                        fall_angle: float = FALL_ANGLE, progress: bool = True, threads: int | None = None,
                        output=None, scheduler=None, overwrite: bool = False,
                        chunk_size: int = CHUNK_SIZE) -> xr.Dataset:
    """``omega``: (start, stop, n) or an increasing array of spin rates [rad/s].

    Runs on ``threads`` threads (default: cores) or a dask ``scheduler`` (see :func:`.sweeps.run_sweep`);
    with ``output`` the diagram is stored chunk by chunk and a rerun resumes (``overwrite``:
    discard chunks of another configuration).
    """
    omega_config = _omega_axis(omega)
    model = ode.EULER
    names = poincare.quantities(model.name)
    if quantity not in names:
        raise ParameterError(f"quantity {quantity!r} unknown; choose one of {', '.join(names)}")
    sec = poincare.parse_section(section, direction, model.name)
    setup, initial = setup or Setup(), initial or InitialState()
    if not isinstance(setup, Setup) or not isinstance(initial, InitialState):
        raise ParameterError("setup and initial must be a Setup and an InitialState (tippedisk_analysis.Setup(...), "
                             "InitialState(...))")
    poincare._check(t_transient, t_end, max_crossings, tol, fall_angle)
    if int(chunk_size) != chunk_size or chunk_size < 1:
        raise ParameterError(f"chunk_size = {chunk_size!r} must be a positive integer")
    config = {"model": model.name, "setup": to_dict(setup), "initial": to_dict(initial), "quantity": quantity,
              "section": {"quantity": sec.quantity, "level": sec.level, "modulo": bool(sec.modulo),
                          "direction": sec.direction},
              "omega": omega_config, "t_transient": t_transient, "t_end": t_end, "max_crossings": max_crossings,
              "integrator": {"name": "heyoka.taylor_adaptive", "tol": tol, "fall_angle": fall_angle}}
    crossings = max_crossings if max_crossings is not None else 100 * (t_end - t_transient)
    sweep = sweeps.Sweep("bifurcation diagram", config, _n_omega(config), int(chunk_size), (*PER_OMEGA, *PER_CROSSING),
                         run_chunk, functools.partial(_assemble, config, sec),
                         functools.partial(poincare.compile_section, model.name, sec, float(tol)),
                         unit="Omega value", bytes_per_point=10 + 8 + 40 * crossings,
                         seconds_per_point=SECONDS_PER_RUN_SECOND * t_end)
    return sweeps.run_sweep(sweep, output=output, scheduler=scheduler, threads=threads, progress=progress,
                            overwrite=overwrite)


def _assemble(config: dict, sec: poincare.Section, merged: dict) -> xr.Dataset:
    omegas = _config_values(config)
    quantity = config["quantity"]
    units, long_name = VARIABLES.get(quantity, ("1", quantity))
    status, valid = merged["status_code"], merged["valid"]
    data = {
        "omega_of_point": ("point", merged["omega_of_point"],
                           {"units": "rad s-1", "long_name": "initial spin Omega of the crossing"}),
        "time": ("point", merged["time"]),
        "value": ("point", merged["value"], {"units": units, "long_name": f"{quantity} at the crossing ({long_name})"
                                             + (", wrapped into (-pi, pi]" if quantity in ANGLES else "")}),
        "beta": ("point", merged["beta"]),
        "gamma": ("point", merged["gamma"]),
        "n_crossings": ("omega", merged["n_crossings"].astype(np.int64),
                        {"units": "1", "long_name": "crossings kept after the transient"}),
        "status_code": ("omega", status.astype(np.int8),
                        {"flag_values": np.array(list(STATUS.values()), dtype=np.int8),
                         "flag_meanings": " ".join(STATUS), "long_name": "how the run ended"}),
        "valid": ("omega", valid.astype(np.int8),
                  {"flag_values": np.array([0, 1], dtype=np.int8), "flag_meanings": "lift_off valid",
                   "long_name": "1: lambda_N > 0 throughout the run (bilateral contact model valid)"}),
    }
    config = {**config, "omega": omegas.tolist() if len(omegas) <= 100_000 else config["omega"],
              "section": {**config["section"], "modulo": int(config["section"]["modulo"])}}
    n_fell = int(np.sum(status == STATUS["fell"]))
    n_nonfinite = int(np.sum(status == STATUS["nonfinite"]))
    n_invalid = len(valid) - int(np.sum(valid))
    message = (f"{len(omegas)} spin rates, {len(merged['time'])} crossings of {sec.label} after "
               f"t = {config['t_transient']:g} s; {n_fell} run(s) fell, {n_nonfinite} non-finite, "
               f"{n_invalid} with lambda_N < 0 (lift-off)")
    run_status = "completed" if n_fell == n_nonfinite == n_invalid == 0 else "partial"
    model = ode.MODELS[config["model"]]
    out = xr.Dataset(data, coords={"omega": ("omega", omegas, {"units": "rad s-1",
                                                               "long_name": "initial spin rate Omega = alpha_dot(0)"})},
                     attrs=make_attrs("bifurcation", config, run_status, message, model=model.name,
                                      paper_model=model.paper_name, quantity=quantity, section=sec.label,
                                      direction=sec.direction))
    return describe(out)
