"""Brute-force bifurcation diagram: a quantity at Poincaré crossings after transients vs Omega.

For each initial spin Omega = alpha_dot(0) the trajectory from Table 3 is integrated, the
crossings of the section (default ``beta_dot = 0``, upward) before ``t_transient`` are
skipped and the next ``max_crossings`` crossings are kept (:mod:`.poincare`). The crossings
of all Omega values are stored along one dimension ``point`` (a ragged set, no padding):
``omega_of_point`` says which Omega each belongs to; per Omega, ``n_crossings`` and the
run's ``status_code`` (flag values as in :data:`STATUS`).
"""

from __future__ import annotations

import dataclasses
import os
import sys
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import xarray as xr

from ..defaults import BIFURCATION_TOL, FALL_ANGLE
from ..errors import ParameterError
from ..models import ode
from ..parameters import InitialState, Setup, to_dict
from ..results import VARIABLES, describe, make_attrs
from . import poincare

STATUS = {"completed": 0, "fell": 1, "nonfinite": 2}
ANGLES = ("alpha", "gamma")  # stored wrapped into (-pi, pi] as ``value``


def bifurcation_diagram(omega, *, quantity: str = "gamma", section: str = "beta_dot=0", direction: str = "positive",
                        setup: Setup | None = None, initial: InitialState | None = None, t_transient: float = 5.0,
                        t_end: float = 10.0, max_crossings: int = 50, tol: float = BIFURCATION_TOL,
                        fall_angle: float = FALL_ANGLE, progress: bool = True, threads: int | None = None) -> xr.Dataset:
    """``omega``: (start, stop, n) or an array of spin rates [rad/s]; runs on ``threads`` threads (default: cores)."""
    from tqdm import tqdm

    omegas = np.linspace(*omega) if isinstance(omega, tuple) else np.asarray(omega, dtype=float)
    if omegas.ndim != 1 or len(omegas) == 0 or not np.all(np.isfinite(omegas)):
        raise ParameterError("omega must be a non-empty list of finite spin rates [rad/s]; give e.g. 20:80:61")
    model = ode.EULER
    names = poincare.quantities(model.name)
    if quantity not in names:
        raise ParameterError(f"quantity {quantity!r} unknown; choose one of {', '.join(names)}")
    sec = poincare.parse_section(section, direction, model.name)
    setup, initial = setup or Setup(), initial or InitialState()
    rows, n_cross, status, valid = [], [], [], []

    def one(om):
        return poincare.poincare_section(sec, model=model.name, setup=setup,
                                         initial=dataclasses.replace(initial, alpha_dot=float(om)),
                                         t_transient=t_transient, t_end=t_end, max_crossings=max_crossings, tol=tol,
                                         fall_angle=fall_angle)

    poincare._check(t_transient, t_end, max_crossings, tol, fall_angle)
    poincare.section_integrator(model.name, sec.quantity, sec.modulo, sec.direction, float(tol))  # compile once
    with ThreadPoolExecutor(max_workers=threads or os.cpu_count() or 1) as ex:  # heyoka releases the GIL
        runs = list(tqdm(ex.map(one, omegas), total=len(omegas), desc="bifurcation", unit="Omega", delay=2.0,
                         disable=not progress, file=sys.stderr))
    for om, ds in zip(omegas, runs):
        n_cross.append(ds.sizes["crossing"])
        status.append(STATUS[ds.attrs["status"]])
        valid.append(int(ds.attrs["valid"]))
        value = ds[quantity].values
        if quantity in ANGLES:  # unwrapped angles: wrap into (-pi, pi] to compare crossings
            value = np.pi - np.mod(np.pi - value, 2 * np.pi)
        rows.append((np.full(ds.sizes["crossing"], om), ds["time"].values, value,
                     ds["beta"].values, ds["gamma"].values))
    cols = [np.concatenate([r[k] for r in rows]) for k in range(5)]
    units, long_name = VARIABLES.get(quantity, ("1", quantity))
    data = {
        "omega_of_point": ("point", cols[0], {"units": "rad s-1", "long_name": "initial spin Omega of the crossing"}),
        "time": ("point", cols[1]),
        "value": ("point", cols[2], {"units": units, "long_name": f"{quantity} at the crossing ({long_name})"
                                                + (", wrapped into (-pi, pi]" if quantity in ANGLES else "")}),
        "beta": ("point", cols[3]),
        "gamma": ("point", cols[4]),
        "n_crossings": ("omega", np.array(n_cross, dtype=np.int64),
                        {"units": "1", "long_name": "crossings kept after the transient"}),
        "status_code": ("omega", np.array(status, dtype=np.int8),
                        {"flag_values": np.array(list(STATUS.values()), dtype=np.int8),
                         "flag_meanings": " ".join(STATUS), "long_name": "how the run ended"}),
        "valid": ("omega", np.array(valid, dtype=np.int8),
                  {"flag_values": np.array([0, 1], dtype=np.int8), "flag_meanings": "lift_off valid",
                   "long_name": "1: lambda_N > 0 throughout the run (bilateral contact model valid)"}),
    }
    config = {"model": model.name, "setup": to_dict(setup), "initial": to_dict(initial), "quantity": quantity,
              "section": {"quantity": sec.quantity, "level": sec.level, "modulo": int(sec.modulo),
                          "direction": sec.direction},
              "omega": omegas.tolist(), "t_transient": t_transient, "t_end": t_end, "max_crossings": max_crossings,
              "integrator": {"name": "heyoka.taylor_adaptive", "tol": tol, "fall_angle": fall_angle}}
    n_fell = int(np.sum(np.array(status) == STATUS["fell"]))
    n_nonfinite = int(np.sum(np.array(status) == STATUS["nonfinite"]))
    n_invalid = len(valid) - int(np.sum(valid))
    message = (f"{len(omegas)} spin rates, {len(cols[0])} crossings of {sec.label} after t = {t_transient:g} s"
               f"; {n_fell} run(s) fell, {n_nonfinite} non-finite, {n_invalid} with lambda_N < 0 (lift-off)")
    run_status = "completed" if n_fell == n_nonfinite == n_invalid == 0 else "partial"
    out = xr.Dataset(data, coords={"omega": ("omega", omegas, {"units": "rad s-1",
                                                               "long_name": "initial spin rate Omega = alpha_dot(0)"})},
                     attrs=make_attrs("bifurcation", config, run_status, message, model=model.name,
                                      paper_model=model.paper_name, quantity=quantity, section=sec.label,
                                      direction=sec.direction))
    return describe(out)
