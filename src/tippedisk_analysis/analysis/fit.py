"""The tippedisk fitted to a measured motion: :func:`fit` (friction and disk parameters, initial states) on an ODE
model's :class:`~tippedisk_analysis.dynamics.System` by :func:`tippedisk_analysis.dynamics.fit`, and
:func:`read_record` (a CSV or netCDF record with a ``time`` column).

Only the ODE models (ode-euler, ode-quaternion) have the variational equations a fit needs; the set-valued and
Moreau models are refused with a one-line error. The record's columns are the model's states (x, y, alpha, beta,
gamma, omega_x, ...) or its outputs (z, z_S, alpha_dot, beta_dot, gamma_dot, lambda_N, ...) in SI units.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import xarray as xr

from ..dynamics.fit_dataset import compare_fits  # noqa: F401 (td.compare_fits)
from ..dynamics.fitting import HORIZONS
from ..dynamics.fitting import fit as fit_system
from ..errors import DatasetError, ParameterError
from ..models import ode
from ..parameters import InitialState, Setup, to_dict

POSITIVE = ("mu", "eps", "m", "A", "B", "C", "r")  # freed parameters kept positive by a lower bound of 0


def fit(times, observed: dict, free=("mu", "eps"), *, model: str = "ode-euler", setup: Setup | None = None,
        initial: InitialState | None = None, sigma=None, bounds=None, horizons=HORIZONS, **options) -> xr.Dataset:
    """Fit ``free`` (parameters of the model's System such as mu, eps, e, or its initial states such as omega_z) to
    ``observed`` {column: values at ``times`` [s]} (NaN: missing), starting from ``setup`` (default Tables 1-2) and
    ``initial`` (default Table 3); parameters not freed keep their values. ``sigma`` [units of each column], when
    given, fixes the noise level; otherwise the covariance is scaled by the residual variance. Freed mu, eps, m, A,
    B, C and r get a lower bound 0 unless ``bounds`` names them. Further ``options`` go to
    :func:`tippedisk_analysis.dynamics.fit` (tol, max_nfev, identifiability_tol, weights, t0). Returns the dataset of
    kind ``fit`` with the model and the start (setup and initial state) as attributes."""
    if model not in ode.MODELS:
        raise ParameterError(f"model {model!r} cannot be fitted: a fit needs the variational equations of an ODE "
                             f"model; choose one of {', '.join(ode.MODELS)} (set-valued and Moreau models have no "
                             "sensitivities)", cli=f"--model {model} cannot be fitted; choose one of "
                             f"{', '.join(ode.MODELS)} (set-valued and Moreau models have no sensitivities)")
    setup = Setup() if setup is None else setup
    initial = InitialState() if initial is None else initial
    ode_model = ode.MODELS[model]
    system = ode.as_system(ode_model)
    free = [free] if isinstance(free, str) else list(free)
    bounds = dict(bounds or {})
    for name in free:
        if name in POSITIVE and name not in bounds:
            bounds[name] = (0.0, None)
    state = ode.initial_state_vector(ode_model, setup, initial)
    ds = fit_system(system, times, observed, free, pars=ode.parameter_vector(setup), state=state, sigma=sigma,
                    bounds=bounds, horizons=horizons, **options)
    ds.attrs.update({"model": model, "paper_model": ode_model.paper_name, "start_setup": _json(to_dict(setup)),
                     "start_initial": _json(to_dict(initial))})  # the fitted values: system_parameters
    return ds


def _json(value) -> str:
    return json.dumps(value, sort_keys=True)


def read_record(path: str | os.PathLike) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """(times [s], {column: values}) of a CSV (a header row naming ``time`` and the columns; empty cells or NaN
    for missing samples) or netCDF (a ``time`` coordinate and variables along it) record."""
    path = Path(path)
    if not path.is_file():
        raise DatasetError(f"'{path}' does not exist or is not a file; give a CSV or netCDF record with a time column")
    if path.suffix.lower() in (".nc", ".nc4", ".cdf"):
        try:
            with xr.open_dataset(path) as ds:
                ds = ds.load()
        except Exception as exc:  # netCDF4 raises OSError / ValueError for foreign files
            raise DatasetError(f"'{path}' is not a readable netCDF file ({exc.__class__.__name__}); give a CSV or "
                               "netCDF record") from None
        if "time" not in ds.variables:
            raise DatasetError(f"'{path}' has no variable 'time'; name the sample times 'time' [s]")
        columns = {k: np.asarray(v.values, dtype=float) for k, v in ds.data_vars.items() if v.dims == ("time",)}
        return np.asarray(ds["time"].values, dtype=float), columns
    try:
        table = np.genfromtxt(path, delimiter=",", names=True, dtype=float, encoding="utf-8")
    except (ValueError, OSError) as exc:
        raise DatasetError(f"'{path}' is not a CSV table of numbers ({exc}); give a header row and numbers") from None
    names = table.dtype.names or ()
    if "time" not in names:
        raise DatasetError(f"'{path}' has no column 'time' (columns: {', '.join(names) or 'none'}); name the sample "
                           "times 'time' [s]")
    return np.atleast_1d(table["time"]), {k: np.atleast_1d(table[k]) for k in names if k != "time"}
