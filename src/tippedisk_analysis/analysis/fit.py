"""The tippedisk fitted to a measured motion: :func:`fit` (friction and disk parameters, initial states) on an ODE
model's :class:`~tippedisk_analysis.dynamics.System` by :func:`tippedisk_analysis.dynamics.fit`, and
:func:`read_record` (a CSV or netCDF record with a ``time`` column).

The ODE models (ode-euler, ode-quaternion) have the variational equations of an exact Jacobian. The set-valued,
Moreau and hybrid models have none: :func:`.fit_by_simulation` fits their friction, disk and gravity parameters by
finite differences on ``td.simulate`` (the same dataset, AIC and BIC, so that :func:`compare_fits` sets them beside
the smooth law). The record's columns are the model's states (x, y, alpha, beta, gamma, omega_x, ...) or its
outputs (z, z_S, alpha_dot, beta_dot, gamma_dot, lambda_N, ...) in SI units.
"""

from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path

import numpy as np
import xarray as xr
from scipy.optimize import least_squares

from ..dynamics.fit_dataset import compare_fits  # noqa: F401 (td.compare_fits)
from ..dynamics.fitting import HORIZONS
from ..dynamics.fitting import fit as fit_system
from ..errors import DatasetError, ParameterError
from ..models import ode
from ..parameters import InitialState, Setup, to_dict
from ..solvers import resolve

POSITIVE = ("mu", "eps", "m", "A", "B", "C", "r")  # freed parameters kept positive by a lower bound of 0


def fit(times, observed: dict, free=("mu", "eps"), *, model: str = "ode-euler", setup: Setup | None = None,
        initial: InitialState | None = None, sigma=None, bounds=None, horizons=HORIZONS, **options) -> xr.Dataset:
    """Fit ``free`` (parameters of the model's System such as mu, eps, e, or its initial states such as omega_z) to
    ``observed`` {column: values at ``times`` [s]} (NaN: missing), starting from ``setup`` (default Tables 1-2) and
    ``initial`` (default Table 3); parameters not freed keep their values. ``sigma`` [units of each column], when
    given, fixes the noise level; otherwise the covariance is scaled by the residual variance. Freed mu, eps, m, A,
    B, C and r get a lower bound 0 unless ``bounds`` names them. Further ``options`` go to
    :func:`tippedisk_analysis.dynamics.fit` (tol, max_nfev, identifiability_tol, weights, t0). Returns the dataset of
    kind ``fit`` with the model and the start (setup and initial state) as attributes. A model without variational
    equations (set-valued, Moreau, hybrid) is fitted by :func:`.fit_by_simulation` (parameters only)."""
    model = resolve(model).name
    if model not in ode.MODELS:
        return fit_by_simulation(times, observed, free, model=model, setup=setup, initial=initial, sigma=sigma,
                                 bounds=bounds, **options)
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


# -- models without variational equations: finite differences on td.simulate
PARAMETER_UNITS = {"mu": "1", "eps": "m s-1", "mu_tau": "1", "mu_R": "1", "contact_radius": "m", "m": "kg", "e": "m",
                   "r": "m", "A": "kg m2", "B": "kg m2", "C": "kg m2", "gravity": "m s-2"}
FRICTION = ("mu", "eps", "mu_tau", "mu_R", "contact_radius")
DIFF_STEP = 1e-4  # finite-difference step relative to max(1, |value|): above the time stepping's round-off
PENALTY = 1e6  # residual of a trial run that did not complete (the step is refused)


def _with(setup: Setup, values: dict) -> Setup:
    """``setup`` with friction, disk and gravity values replaced by ``values`` {name: value}."""
    friction = dataclasses.replace(setup.friction, **{k: v for k, v in values.items() if k in FRICTION})
    disk_values = {k: v for k, v in values.items() if k not in FRICTION and k != "gravity"}
    disk = dataclasses.replace(setup.disk, **disk_values) if disk_values else setup.disk
    return dataclasses.replace(setup, friction=friction, disk=disk,
                               **({"gravity": values["gravity"]} if "gravity" in values else {}))


class _Record:
    """The model as :mod:`tippedisk_analysis.dynamics.fit_dataset` reads a system: names, units, attributes."""

    def __init__(self, model: str, observed: list[str], units: dict):
        self.name, self.state_names, self.observables, self.time_units = f"tippedisk {model}", (), observed, "s"
        self._units = units

    def units_of(self, name: str) -> str:
        return self._units.get(name, "1")

    def attrs(self, pars) -> dict:
        return {"system": self.name, "system_parameters": "; ".join(f"{k} = {float(v)!r}" for k, v in pars.items())}


class SimulationProblem:
    """Residuals r = (y(t_i) - d_i) / sigma of ``model`` run by ``td.simulate`` (interpolated linearly to the
    samples) and their Jacobian by forward differences: what :func:`.fit_dataset.summary` and ``status_of`` read."""

    def __init__(self, times, observed: dict, free, model: str, setup: Setup, initial: InitialState, sigma, options):
        from ..dynamics.fitting import FitProblem
        from ..solvers import simulate

        self.times = FitProblem._check_times(times)
        self.model, self.setup, self.initial, self.options, self._simulate = model, setup, initial, options, simulate
        bad = [k for k in free if k not in PARAMETER_UNITS or (k not in FRICTION + ("gravity",)
                                                                and not hasattr(setup.disk, k))]
        if bad:
            raise ParameterError(f"{model} is fitted by finite differences on its simulation, which frees parameters "
                                 f"only; {bad[0]!r} is not one: free some of {', '.join(PARAMETER_UNITS)}")
        self.free = list(free)
        self.start = np.array([float(getattr(setup.friction if k in FRICTION else setup if k == "gravity"
                                             else setup.disk, k)) for k in self.free])
        run = self._run_dataset(self.start, start=True)
        if run is None:
            raise ParameterError(f"{model} cannot be run over the record from the start; give a start closer to the "
                                 "data or a shorter record")
        outputs = [k for k, v in run.data_vars.items() if v.dims == ("time",)]
        unknown = [k for k in observed if k not in outputs]
        if unknown:
            raise ParameterError(f"{model} has no state or output {unknown[0]!r}; name columns as its outputs: "
                                 f"{', '.join(outputs)}")
        self.names = list(observed)
        self.data = np.column_stack([np.broadcast_to(np.asarray(observed[k], float), self.times.shape)
                                     for k in self.names])
        self.used = np.isfinite(self.data)
        empty = [k for j, k in enumerate(self.names) if not self.used[:, j].any()]
        if empty:
            raise ParameterError(f"column {empty[0]!r} holds no finite value; drop it or give its samples")
        if self.used.sum() <= len(self.free):
            raise ParameterError(f"{int(self.used.sum())} observed samples for {len(self.free)} free values; give more "
                                 "samples than free values (or free fewer)")
        self.sigma_given = sigma is not None
        self.scale = np.full(self.data.shape, 1.0 / (1.0 if sigma is None else float(sigma)))
        units = {**PARAMETER_UNITS, **{k: run[k].attrs.get("units", "1") for k in self.names}}
        self.system, self.runs, self._jac = _Record(model, self.names, units), 0, None
        self._cache: tuple | None = None

    def _run_dataset(self, theta, start: bool = False):
        """The simulation at ``theta`` (None if it did not complete); at the start a refused setting is raised."""
        values = dict(zip(self.free, map(float, theta)))
        try:
            run = self._simulate(self.model, float(self.times[-1] - self.times[0]), setup=_with(self.setup, values),
                                 initial=self.initial, **self.options)
        except ParameterError:  # a trial value outside the physical range (e.g. a negative mass)
            if start:
                raise
            return None
        return run if run.attrs["status"] == "completed" else None

    def run(self, theta):
        """(no states, the observed series at the samples, None); a run that did not complete: NaN."""
        theta = np.asarray(theta, float)
        if self._cache is None or not np.array_equal(self._cache[0], theta):
            self.runs += 1
            run = self._run_dataset(theta)
            t = self.times - self.times[0]
            Y = (np.full(self.data.shape, np.nan) if run is None else
                 np.column_stack([np.interp(t, run.time.values, run[k].values) for k in self.names]))
            self._cache = (theta.copy(), Y)
        return np.empty((len(self.times), 0)), self._cache[1], None

    def residuals(self, theta) -> np.ndarray:
        Y = self.run(theta)[1]
        r = ((Y - self.data) * self.scale)[self.used]
        return np.where(np.isfinite(r), r, PENALTY)

    def jacobian(self, theta) -> np.ndarray:
        """Forward differences with steps DIFF_STEP * max(1, |value|)."""
        theta = np.asarray(theta, float)
        r0 = self.residuals(theta)
        J = np.empty((r0.size, theta.size))
        for k in range(theta.size):
            step = np.zeros_like(theta)
            step[k] = DIFF_STEP * max(1.0, abs(theta[k]))
            J[:, k] = (self.residuals(theta + step) - r0) / step[k]
        self.residuals(theta)  # leave the cache at theta
        return J

    def unpack(self, theta):
        return np.empty(0), dict(zip(self.free, map(float, theta)))


def fit_by_simulation(times, observed: dict, free=("mu",), *, model: str, setup: Setup | None = None,
                      initial: InitialState | None = None, sigma=None, bounds=None, max_nfev: int = 100,
                      identifiability_tol: float = 1e-6, **simulate_options) -> xr.Dataset:
    """Fit the parameters ``free`` (friction, disk, gravity) of a model without variational equations (set-valued,
    Moreau, hybrid) to ``observed`` by ``scipy.optimize.least_squares`` (trust region reflective) with a
    forward-difference Jacobian on ``td.simulate`` from the initial state ``initial`` at ``times[0]``; one solve on
    the whole record (no continuation in the horizon: every run costs a simulation). ``sigma``: one number [units
    of each column] or None. Returns the dataset of kind ``fit`` of :func:`fit`, with ``jacobian`` = finite
    differences in its attributes; the time stepping's non-smoothness (stick-slip, impacts) makes the standard
    errors approximate."""
    from ..dynamics.fit_dataset import Stage, fit_dataset
    from ..dynamics.fitting import _bounds

    setup = Setup() if setup is None else setup
    initial = InitialState() if initial is None else initial
    free = [free] if isinstance(free, str) else list(free)
    if sigma is not None and not (np.isscalar(sigma) and np.isfinite(sigma) and sigma > 0):
        raise ParameterError(f"sigma = {sigma!r}: a fit by simulation takes one positive number for every column")
    unknown = set(simulate_options) - {"dt", "dt_output", "tol"}
    if unknown:
        raise ParameterError(f"a fit by simulation takes no option(s) {sorted(unknown)}; it takes max_nfev, "
                             "identifiability_tol and the simulation's dt, dt_output, tol")
    problem = SimulationProblem(times, observed, free, model, setup, initial, sigma, simulate_options)
    bounds = {**{k: (0.0, None) for k in free if k in POSITIVE}, **dict(bounds or {})}
    lower, upper = _bounds(problem, bounds)
    res = least_squares(problem.residuals, problem.start, jac=problem.jacobian, bounds=(lower, upper), method="trf",
                        x_scale="jac", ftol=1e-10, xtol=1e-10, gtol=1e-10, max_nfev=max_nfev)
    stage = Stage(len(problem.times), res.x, int(res.status), int(res.nfev), int(res.njev or 0),
                  np.asarray(res.active_mask, dtype=int), str(res.message))
    config = {"free": problem.free, "observed": problem.names, "model": model, "max_nfev": int(max_nfev),
              "identifiability_tol": float(identifiability_tol), "sigma_given": int(problem.sigma_given),
              "jacobian": "forward differences on td.simulate", "diff_step": DIFF_STEP, **simulate_options}
    ds = fit_dataset(problem, [stage], config, identifiability_tol)
    info = resolve(model)
    ds.attrs.update({"model": info.name, "paper_model": info.paper_name, "jacobian": "finite differences",
                     "start_setup": _json(to_dict(setup)), "start_initial": _json(to_dict(initial)),
                     "title": f"Fit of {info.name} to a record"})
    return ds
