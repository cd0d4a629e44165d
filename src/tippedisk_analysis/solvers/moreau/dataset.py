"""Datasets of Moreau runs: the schema variables (:mod:`tippedisk_analysis.results`) from stored rows."""

from __future__ import annotations

import numpy as np
import xarray as xr

from ... import kinematics as kin
from ...parameters import InitialState, Setup, to_dict
from ...results import describe, make_attrs
from . import layout as L
from .driver import integrate
from .models import EULER, MODELS, QUATERNION, MoreauModel

IMPULSE_VARIABLES = {"P_N": L.IMPULSE_N, "P_Tx": L.IMPULSE_TX, "P_Ty": L.IMPULSE_TY, "P_tau": L.IMPULSE_TAU,
                     "P_R": L.IMPULSE_R}


def run(model_name: str, setup: Setup, initial: InitialState, t_end: float, **options) -> xr.Dataset:
    """Simulate a Moreau model and return the dataset (schema of :mod:`tippedisk_analysis.results`)."""
    model = MODELS[model_name]
    rows, status_code, failures, steps, wall, used = integrate(model, setup, initial, t_end, **options)
    data = outputs(model, setup, rows, used["dt"])
    status = L.STATUS_NAMES[status_code]
    t_final = steps * used["dt"]
    if status == "completed":
        message = f"reached t_end = {t_end:g} s in {steps} steps"
    elif status == "fell":
        message = (f"the disk came within fall_angle = {used['fall_angle']:g} rad of horizontal at t = "
                   f"{t_final:.6g} s, the Euler-angle singularity; use a quaternion model to continue")
    else:
        message = (f"non-finite state at t = {t_final:.6g} s; the dataset ends at the last stored sample; "
                   "try a smaller --dt")
    if failures:
        status = "not_converged" if status == "completed" else status
        message += (f"; the prox iteration hit max_iter = {used['max_iter']} in {failures} step(s): "
                    "raise --max-iter or --tol, or lower the r_* gains")
    config = {"model": model_name, "setup": to_dict(setup), "initial": to_dict(initial), "t_end": t_end,
              "integrator": {"name": "moreau-midpoint (numba)", **used}}
    time = data.pop("time")
    per_contact = {k: data.pop(k) for k in IMPULSE_VARIABLES}
    ds = xr.Dataset({name: ("time", np.asarray(v, dtype=float)) for name, v in data.items()},
                    coords={"time": time, "contact": np.array([1, 2, 3], dtype=np.int8)},
                    attrs=make_attrs("simulation", config, status, message, model=model_name,
                                     paper_model=model.paper_name, n_steps=steps, t_final=t_final,
                                     convergence_failures=failures, wall_time=wall))
    for name, values in per_contact.items():
        ds[name] = (("time", "contact"), values)
        ds[name.replace("P_", "lambda_") + "_contact"] = (("time", "contact"), values / used["dt"])
    ds["n_closed"] = ds["n_closed"].astype(np.int8)
    ds["contact"].attrs.update(long_name="candidate contact point C_i", units="1")
    if model.parameterization == QUATERNION:
        for name in ("alpha_dot", "beta_dot", "gamma_dot"):
            ds[name].attrs["comment"] = ("a fill of 0 where euler_rates_defined = 0 (the disk horizontal, sin beta "
                                         "= 0: Euler rates are undefined there)")
        ds["euler_rates_defined"] = ds["euler_rates_defined"].astype(np.int8)
        ds["euler_rates_defined"].attrs.update(long_name="whether the Euler rates are defined (sin beta != 0)",
                                               flag_values=np.array([0, 1], np.int8), flag_meanings="no yes")
    return describe(ds)


def outputs(model: MoreauModel, setup: Setup, rows: np.ndarray, dt: float) -> dict:
    """Schema variables from stored rows (vectorized numpy, using :mod:`tippedisk_analysis.kinematics`)."""
    d = setup.disk
    q, u = rows[:, L.COL_Q:L.COL_Q + 7], rows[:, L.COL_U:L.COL_U + 6]
    data = {"time": rows[:, L.COL_TIME], "x": q[:, 0], "y": q[:, 1], "z": q[:, 2]}
    if model.parameterization == EULER:
        R = kin.rotation_from_euler(q[:, 3], q[:, 4], q[:, 5])
        euler = q[:, 3:6].T
        rates = u[:, 3:6]
        omega = kin.omega_from_euler_rates(q[:, 4], q[:, 5], rates)
    else:
        p = q[:, 3:7]
        for k in range(4):
            data[f"p{k}"] = p[:, k]
        data["quaternion_norm_error"] = np.linalg.norm(p, axis=1) - 1.0
        R = kin.rotation_from_quaternion(p / np.linalg.norm(p, axis=1)[:, None])
        euler = np.array(kin.euler_from_rotation(R))
        euler[0], euler[2] = np.unwrap(euler[0]), np.unwrap(euler[2])
        omega = u[:, 3:6]
        with np.errstate(divide="ignore", invalid="ignore"):
            rates = kin.euler_rates_from_omega(euler[1], euler[2], omega)
        defined = np.all(np.isfinite(rates), axis=1)  # a horizontal disk (sin beta = 0) has no Euler rates
        data["euler_rates_defined"] = defined.astype(np.int8)
        rates = np.where(defined[:, None], rates, 0.0)  # a fill, flagged by euler_rates_defined
    for k, name in enumerate(("alpha", "beta", "gamma")):
        data[name] = euler[k]
        data[name + "_dot"] = rates[:, k]
    for k, name in enumerate(("x_dot", "y_dot", "z_dot")):
        data[name] = u[:, k]
    for k, name in enumerate(("omega_x", "omega_y", "omega_z")):
        data[name] = omega[:, k]
    r_GS = d.e * R[:, :, 0]
    omega_I = np.einsum("nij,nj->ni", R, omega)
    v_S = u[:, :3] + np.cross(omega_I, r_GS)
    inertia = np.array(list(d.inertia_S.values()))
    data["z_S"] = q[:, 2] + r_GS[:, 2]
    data["E_kin"] = 0.5 * d.m * np.sum(v_S**2, axis=1) + 0.5 * np.sum(inertia * omega**2, axis=1)
    data["E_pot"] = d.m * setup.gravity * data["z_S"]
    data["E_tot"] = data["E_kin"] + data["E_pot"]
    for i in range(L.N_CONTACTS):
        data[f"g_N{i + 1}"] = rows[:, L.COL_GAP + i]
    # slip and normal velocity at C1 (2.13)-(2.15), from the stored gap geometry
    sin_beta = np.hypot(R[:, 0, 2], R[:, 1, 2])
    safe = np.where(sin_beta > 0, sin_beta, 1.0)
    ey = np.stack([-R[:, 2, 2] * R[:, 0, 2] / safe, -R[:, 2, 2] * R[:, 1, 2] / safe, sin_beta], axis=1)  # (2.8)
    v_C1 = u[:, :3] + np.cross(omega_I, -d.r * ey)
    data["slip_x"], data["slip_y"], data["gamma_N1"] = v_C1[:, 0], v_C1[:, 1], v_C1[:, 2]
    impulses = {name: rows[:, L.COL_IMPULSE + kind * L.N_CONTACTS:L.COL_IMPULSE + (kind + 1) * L.N_CONTACTS]
                for name, kind in IMPULSE_VARIABLES.items()}
    data["lambda_N"] = impulses["P_N"][:, 0] / dt
    data["n_closed"] = rows[:, L.COL_N_CLOSED]
    data["prox_iterations_max"] = rows[:, L.COL_ITER_MAX]
    data["prox_iterations_mean"] = rows[:, L.COL_ITER_MEAN]
    data.update(impulses)
    return data
