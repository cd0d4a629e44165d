"""The dataset schema: names, units, long names, and the netCDF round trip.

Every variable carries ``long_name`` and ``units`` (UDUNITS; "1" for dimensionless quantities and
indices; none only where the values along a label dimension mix units, which a ``comment`` and a
``<dim>_units`` coordinate say); the dataset carries the configuration that produced it as a JSON
string (``config``), the package version, and ``status`` / ``message`` saying how the run ended.
netCDF-safe throughout: no complex dtype, no bool or None attributes, categories as int8 with
``flag_values`` / ``flag_meanings``. A dataset holding a non-finite value is refused.

On disk (:func:`encode`, CF-1.8; :func:`decode` undoes it on :func:`load`):

* text is a fixed-width character array (dimension ``<name>_strlen``, UTF-8): what every netCDF reader
  and the CF checker understand, where netCDF-4 variable-length strings are not;
* a dimension labelled by text (``branch``, ``state``, ``label``, ...) has no coordinate variable (CF
  1.3: coordinate variables are numeric and monotonic); its labels are the auxiliary coordinate
  ``<dim>_label`` (CF 6.1), and the global attribute ``label_dimensions`` lists such dimensions, so
  that :func:`load` gives them back as the index (``ds.sel(branch="inverted")`` works as before);
* index coordinates (:func:`index_coordinate`) carry ``units = "1"``, and no variable has a ``_FillValue``
  (no missing values are ever stored).

Simulation statuses: ``completed`` (reached t_end); ``fell`` (the disk tilted down to the
fall angle, sin(beta) -> 0, the Euler singularity, and the run ended there); ``not_converged``
(Moreau: the prox iteration hit its limit in some steps, counted in ``convergence_failures``);
``nonfinite`` (the state became non-finite; the dataset ends at the last finite sample).
"""

from __future__ import annotations

import dataclasses
import json
import os
import shlex
import sys
from pathlib import Path

import numpy as np
import xarray as xr

from . import files
from .errors import DatasetError, TippediskError
from .version import __version__

PRODUCER = "tippedisk_analysis"
PAPER = ("Sailer, Eugster, Leine, The Tippedisk: a Tippetop Without Rotational Symmetry, Regul. Chaotic Dyn. 25 "
         "(2020) 553-580, doi:10.1134/S1560354720060052")
KIND_TITLES = {"simulation": "Simulation", "continuation": "Continuation", "periodic_orbits": "Periodic orbits",
               "lyapunov": "Lyapunov exponents", "poincare": "Poincare section", "basins": "Basins of attraction",
               "outcome_map": "Outcome map", "stability_map": "Stability map", "bifurcation": "Bifurcation diagram",
               "spin_passage": "Passage along the inverted spins",
               "symmetric_family": "Family of symmetric periodic orbits",
               "nutation_cycles": "Nutation cycles of the held-spin model",
               "homoclinic_orbits": "Homoclinic orbits", "fit": "Fit to a record"}

# name: (units, long_name)
VARIABLES: dict[str, tuple[str, str]] = {
    "time": ("s", "time"),
    "x": ("m", "x-coordinate of the geometric centre G"),
    "y": ("m", "y-coordinate of the geometric centre G"),
    "z": ("m", "height of the geometric centre G"),
    "alpha": ("rad", "Euler angle alpha (precession, about e_z^I), unwrapped"),
    "beta": ("rad", "Euler angle beta (inclination, about e_x^R)"),
    "gamma": ("rad", "Euler angle gamma (rotation about the disk normal), unwrapped"),
    "p0": ("1", "quaternion component p0"),
    "p1": ("1", "quaternion component p1"),
    "p2": ("1", "quaternion component p2"),
    "p3": ("1", "quaternion component p3"),
    "quaternion_norm_error": ("1", "|p| - 1"),
    "x_dot": ("m s-1", "x-velocity of G"),
    "y_dot": ("m s-1", "y-velocity of G"),
    "z_dot": ("m s-1", "z-velocity of G"),
    "alpha_dot": ("rad s-1", "rate of alpha"),
    "beta_dot": ("rad s-1", "rate of beta"),
    "gamma_dot": ("rad s-1", "rate of gamma"),
    "omega_x": ("rad s-1", "angular velocity, body x-component"),
    "omega_y": ("rad s-1", "angular velocity, body y-component"),
    "omega_z": ("rad s-1", "angular velocity, body z-component"),
    "z_S": ("m", "height of the centre of gravity S"),
    "g_N1": ("m", "gap of the contact point C1"),
    "gamma_N1": ("m s-1", "normal relative velocity at C1"),
    "lambda_N": ("N", "normal contact force at C1"),
    "slip_x": ("m s-1", "sliding velocity at C1, x-component (gamma_Tx)"),
    "slip_y": ("m s-1", "sliding velocity at C1, y-component (gamma_Ty)"),
    "E_kin": ("J", "kinetic energy"),
    "E_pot": ("J", "potential energy m g z_S"),
    "E_tot": ("J", "total energy E_kin + E_pot"),
    "P_friction": ("W", "power of the friction force at C1"),
    "W_friction": ("J", "work done by friction since t = 0"),
    # Moreau time stepping (solvers/moreau.py)
    "g_N2": ("m", "gap of the candidate contact point C2"),
    "g_N3": ("m", "gap of the candidate contact point C3"),
    "P_N": ("N s", "normal impulse of the last step of the storage interval, per contact"),
    "P_Tx": ("N s", "tangential impulse (e_x^I) of the last step, per contact"),
    "P_Ty": ("N s", "tangential impulse (e_y^I) of the last step, per contact"),
    "P_tau": ("N s", "pivoting impulse (force per contact radius) of the last step, per contact"),
    "P_R": ("N s", "contour friction impulse of the last step, per contact"),
    "lambda_N_contact": ("N", "mean normal force P_N / dt of the last step, per contact"),
    "lambda_Tx_contact": ("N", "mean tangential force P_Tx / dt of the last step, per contact"),
    "lambda_Ty_contact": ("N", "mean tangential force P_Ty / dt of the last step, per contact"),
    "lambda_tau_contact": ("N", "mean pivoting force P_tau / dt of the last step, per contact"),
    "lambda_R_contact": ("N", "mean contour friction force P_R / dt of the last step, per contact"),
    "n_closed": ("1", "number of closed contacts (g_N <= 0 at the midpoint) in the last step"),
    "prox_iterations_max": ("1", "largest number of prox iterations per step in the storage interval"),
    "prox_iterations_mean": ("1", "mean number of prox iterations per step in the storage interval"),
}

def index_coordinate(dim: str, n: int, long_name: str) -> tuple:
    """The coordinate 0, 1, ..., n - 1 of dimension ``dim`` (an index: dimensionless, int32)."""
    return (dim, np.arange(n, dtype=np.int32), {"units": "1", "long_name": long_name})


def describe(ds: xr.Dataset) -> xr.Dataset:
    """Attach units and long_name to every known variable and coordinate (in place; returns ``ds``)."""
    for name, var in ds.variables.items():
        if name in VARIABLES:
            units, long_name = VARIABLES[name]
            var.attrs.setdefault("units", units)
            var.attrs.setdefault("long_name", long_name)
    return ds


def check_finite(ds: xr.Dataset) -> None:
    """Raise DatasetError if any numeric variable holds a NaN or infinity."""
    for name, var in ds.variables.items():
        if np.issubdtype(var.dtype, np.floating) and not np.all(np.isfinite(var.values)):
            raise DatasetError(f"variable {name!r} holds non-finite values; refusing to store a silent NaN")


def invocation() -> str:
    """What made a dataset, for CF's ``history``: the ``tippedisk`` command line, or the Python program."""
    program = Path(sys.argv[0]).name if sys.argv and sys.argv[0] else "python"
    if program in ("tippedisk", "__main__.py"):
        return shlex.join(["tippedisk", *sys.argv[1:]])
    return f"python {program}" if program not in ("-c", "") else "python -c"


def make_attrs(kind: str, config: dict, status: str, message: str, **extra) -> dict:
    """Dataset attributes in netCDF-safe types, with CF's ``title`` (``extra["title"]`` or the kind and the model
    or system), ``history`` (:func:`invocation` and the package version) and ``references`` (the paper for the
    disk's datasets; the package for any System's)."""
    subject = extra.get("model") or extra.get("system") or ""
    subject += f" ({extra['paper_model']})" if extra.get("paper_model") else ""
    title = extra.pop("title", None) or (f"{KIND_TITLES.get(kind, kind)} of {subject}" if subject else
                                         KIND_TITLES.get(kind, kind))
    references = f"{PRODUCER} {__version__}" + (f"; {PAPER}" if "model" in extra else "")
    attrs = {
        "title": title,
        "producer": PRODUCER,
        "producer_version": __version__,
        "kind": kind,
        "config": json.dumps(config, sort_keys=True),
        "status": status,
        "message": message,
        "Conventions": "CF-1.8",
        "history": f"{invocation()} ({PRODUCER} {__version__})",
        "references": references,
    }
    for key, value in extra.items():
        if isinstance(value, bool):
            value = int(value)
        if value is None:
            continue
        attrs[key] = value
    return attrs


def flat_parameters(setup) -> dict:
    """Physical parameters as flat attributes, e.g. ``disk_r``, ``friction_eps``, ``gravity``."""
    flat = {"gravity": setup.gravity}
    for group in ("disk", "friction"):
        for key, value in dataclasses.asdict(getattr(setup, group)).items():
            if isinstance(value, dict):  # the drilled-disk geometry: disk_geometry_rho, ...
                flat.update({f"{group}_{key}_{k}": v for k, v in value.items()})
            elif value is not None:
                flat[f"{group}_{key}"] = value
    flat["disk_source"] = setup.disk.source
    return flat


def require_samples(ds: xr.Dataset, what: str = "draw") -> None:
    """DatasetError if a dimension of samples is empty (e.g. a run that became non-finite at once)."""
    empty = [d for d in ("time", "crossing", "point", "omega") if ds.sizes.get(d, None) == 0]
    if empty:
        raise DatasetError(f"the {ds.attrs.get('kind', '')} dataset holds no samples (dimension {empty[0]!r} is empty; "
                           f"status {ds.attrs.get('status', '?')}: {ds.attrs.get('message', '')}); nothing to {what}")


def config_of(ds: xr.Dataset) -> dict:
    """The configuration stored in a dataset (DatasetError if it has none that reads as a JSON object)."""
    try:
        config = json.loads(ds.attrs["config"])
    except (KeyError, TypeError, ValueError):
        config = None
    if not isinstance(config, dict):
        raise DatasetError("the dataset's attribute 'config' is missing or not JSON: it is damaged or not one of "
                           "ours; give a file written by tippedisk")
    return config


LABEL_DIMENSIONS = "label_dimensions"
"""Global attribute: the dimensions whose text labels are stored as the auxiliary coordinate <dim>_label."""


def _is_text(var) -> bool:
    return var.dtype.kind in "USO"


def encode(ds: xr.Dataset) -> tuple[xr.Dataset, dict]:
    """The on-disk (CF-1.8) form of ``ds`` and its netCDF encoding (module docstring)."""
    out = ds.copy()
    relabelled = []
    for dim in list(ds.dims):
        if dim in ds.coords and _is_text(ds[dim]):
            label = f"{dim}_label"
            if label in ds.variables:
                raise DatasetError(f"the dataset holds both a text dimension {dim!r} and a variable {label!r}; "
                                   f"rename {label!r}")
            var = ds[dim].variable.to_base_variable()
            out = out.drop_vars(dim).assign_coords({label: var})
            relabelled.append(dim)
    if relabelled:
        out.attrs[LABEL_DIMENSIONS] = " ".join(relabelled)
    encoding = {}
    for name, var in out.variables.items():
        if _is_text(var):
            if var.dtype.kind == "O":
                out[name] = var.astype(str)
            encoding[name] = {"dtype": "S1", "char_dim_name": f"{name}_strlen"}
            continue
        enc = {"_FillValue": None}
        if np.issubdtype(var.dtype, np.number) and name in out.data_vars:
            enc.update(zlib=True, complevel=4)
        encoding[name] = enc
    return out, encoding


RENAMED = {("lyapunov", "history"): "running_exponents"}
"""Variables renamed since older files were written: (kind, old name) -> name (a 2-D ``history`` shared its
name with its dimension, which CF 1.8 reserves for coordinate variables)."""


def decode(ds: xr.Dataset) -> xr.Dataset:
    """The in-memory form of a dataset read from disk: text labels back as the index of their dimension, the
    names of :data:`RENAMED` for files written before."""
    for (kind, old), new in RENAMED.items():
        if ds.attrs.get("kind") == kind and old in ds.variables and old not in ds.indexes and new not in ds.variables:
            ds = ds.rename_vars({old: new})
            if new in ds.coords:  # read as a coordinate: it had its dimension's name
                ds = ds.reset_coords(new)
    dims = str(ds.attrs.get(LABEL_DIMENSIONS, "")).split()
    for dim in dims:
        label = f"{dim}_label"
        if label in ds.variables:
            var = ds[label].variable.to_base_variable().astype(str)  # netCDF char arrays read as objects
            ds = ds.drop_vars(label).assign_coords({dim: var})
    for name, var in ds.variables.items():
        if var.dtype.kind == "O" and name not in ds.indexes:
            ds[name] = var.astype(str)
    if dims:
        ds.attrs = {k: v for k, v in ds.attrs.items() if k != LABEL_DIMENSIONS}
    return ds


def save(ds: xr.Dataset, path: str | os.PathLike, *, overwrite: bool = True) -> Path:
    """Write ``ds`` as compressed netCDF4 atomically (:func:`tippedisk_analysis.files.atomic_write`).

    Refuses (:class:`OutputError`, before writing) a directory or device as ``path``, a missing or
    unwritable directory, and an existing file if ``overwrite`` is False.
    """
    if not isinstance(ds, xr.Dataset):
        raise DatasetError(f"save needs an xarray.Dataset (e.g. the result of simulate()), not "
                           f"{type(ds).__name__}; wrap arrays with xarray.Dataset(...) first")
    if not isinstance(path, str | os.PathLike):
        raise DatasetError(f"path = {path!r} is a {type(path).__name__}; give a file name such as 'run.nc'")
    check_finite(ds)
    path = files.check_output(path, overwrite=overwrite)
    stored, encoding = encode(ds)
    return files.atomic_write(path, lambda tmp: stored.to_netcdf(tmp, engine="netcdf4", encoding=encoding))


def load(path: str | os.PathLike) -> xr.Dataset:
    """Read a dataset written by this package (fully into memory)."""
    if not isinstance(path, str | os.PathLike):
        raise DatasetError(f"path = {path!r} is a {type(path).__name__}; give a file name such as 'run.nc'")
    path = Path(path)
    shown = files.show(path)
    if path.is_dir():
        raise DatasetError(f"'{shown}' is a directory; give the path of a .nc file written by tippedisk")
    if not path.is_file():
        raise DatasetError(f"'{shown}' does not exist; give the path of a .nc file written by tippedisk")
    if not files.utf8_encodable(path):
        raise DatasetError(f"'{shown}' is not a valid UTF-8 file name, which netCDF cannot open; rename the file")
    from .resources import check_memory

    try:
        with files.deferred_interrupt(), xr.open_dataset(path, engine="netcdf4") as ds:
            if ds.attrs.get("producer") != PRODUCER or "kind" not in ds.attrs:
                raise DatasetError(f"'{shown}' was not written by tippedisk_analysis; give a .nc file written by "
                                   "tippedisk")
            check_memory(ds.nbytes, f"loading '{shown}'", "load a part of it with xarray.open_dataset(...).isel(...)")
            ds = ds.load()
    except TippediskError:
        raise
    except Exception as exc:  # netCDF4 raises OSError / ValueError for foreign files
        raise DatasetError(f"'{shown}' is not a netCDF dataset ({exc.__class__.__name__}); "
                           "give a .nc file written by tippedisk") from None
    return decode(ds)
