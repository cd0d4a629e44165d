"""Stability maps of the spinning solutions over the spin rate Omega and eps (and mu, e),
and the critical spin speeds Omega_c where a branch changes stability.

:func:`stability_map` evaluates, for both stationary families of Sect. 6 (Fig. 6), the six
nontrivial eigenvalues of the reduced Jacobian (:mod:`.stability`) on a grid, in one batched
call of the compiled Jacobian, and returns a labelled ``xarray.Dataset`` (kind
``"stability_map"``). Critical spin speeds are the zeros of max_real_eig(Omega) at fixed
(eps, mu, e): every sign change between neighbouring grid values of Omega is refined with
``scipy.optimize.brentq`` to a relative accuracy far below 1e-6 (``CRITICAL_RTOL``). Sign
changes between grid points closer than the grid spacing to each other can be missed: refine
the Omega grid if in doubt. Points where max_real_eig is exactly 0 on the grid are reported
as critical without refinement.
"""

from __future__ import annotations

import dataclasses
import sys

import heyoka as hy
import numpy as np
import xarray as xr
from scipy.optimize import brentq
from tqdm import tqdm

from ..defaults import CRITICAL_RTOL, EIG_ATOL, EIG_RTOL, SLIP_SMOOTHING
from ..errors import Interrupted
from ..ranges import check_axis
from ..resources import check_memory
from ..models import ode
from ..parameters import Setup, eccentricity_columns, to_dict
from ..results import index_coordinate, make_attrs
from . import reduced, stability
from . import stationary as st

__all__ = ["stability_map", "critical_speeds", "find_critical_speeds", "critical_speed_curves"]

BRANCH_NAMES = tuple(st.BRANCHES)
CRITICAL_PAD = -1.0e30  # padding of omega_critical beyond n_critical (not a _FillValue: never masked to NaN)
STABILITY_BLOCK = 32_768
"""Grid points evaluated per call of the compiled Jacobian (~50 MB of working memory)."""
BYTES_PER_POINT = 450.0
"""Memory per grid point (both branches): the dataset (~250 B), the parameter vectors (~100 B) and the
netCDF encoding. Measured: a 3000 x 3000 map peaks at 3.3 GB (367 B per point) and takes 2 min 15 s."""
SWEEPABLE = {"eps": ("m s-1", "smoothing velocity eps of the regularised Coulomb law (2.29)"),
             "mu": ("1", "friction coefficient mu (2.29)"),
             "e": ("m", "eccentricity e = |r_GS| of the centre of gravity")}
"""Swept names; an e sweep holds fixed what ``setup.disk`` says (:attr:`Disk.eccentricity_rule`: the
inertia about G for a disk given by values, the hole geometry but its offset b for a drilled disk)."""


def _validated(setup: Setup, name: str, values: np.ndarray) -> None:
    """Run the parameter validation of Friction / Disk on every swept value (ParameterError names the fix)."""
    for v in np.unique(values):
        if name in ("eps", "mu"):
            dataclasses.replace(setup.friction, **{name: float(v)})
        elif name == "e":
            setup.disk.with_eccentricity(float(v))


def _parameter_grid(setup: Setup, sweeps: dict, slip_smoothing: float, shape) -> np.ndarray:
    """(11, prod(shape)) runtime parameters, ode.PARAMETER_NAMES order, for the flattened grid."""
    base = ode.parameter_vector(setup, slip_smoothing=slip_smoothing)
    pars = np.repeat(base[:, None], int(np.prod(shape)), axis=1)
    dims = list(sweeps)
    for axis, name in enumerate(dims, start=1):  # axis 0 is omega
        values = np.asarray(sweeps[name], dtype=float)
        index_shape = [1] * len(shape)
        index_shape[axis] = len(values)
        # e moves with what the disk holds fixed (Disk.with_eccentricity): m, A, B, C change for a drilled disk
        columns = eccentricity_columns(setup.disk, values) if name == "e" else {name: values}
        for key, column in columns.items():
            pars[ode.PARAMETER_NAMES.index(key)] = np.broadcast_to(column.reshape(index_shape), shape).ravel()
    return pars


def stability_map(omega, eps, *, mu=None, e=None, setup: Setup | None = None,
                  slip_smoothing: float = SLIP_SMOOTHING, critical: bool = True, progress: bool = True) -> xr.Dataset:
    """Eigenvalue stability of both spinning branches on the grid omega x eps (x mu x e).

    omega [rad/s] and eps [m/s]: 1-D arrays (dims of the result); mu [-] and e [m]: None
    (take ``setup``'s value, default Tables 1-2) or 1-D arrays (further dims). Returns a
    Dataset with dims (branch, omega, eps[, mu][, e], eig) and, if ``critical``, the critical
    spin speeds ``omega_critical`` (branch, eps[, mu][, e], crossing) with ``n_critical``.
    The grid is evaluated in blocks of ``STABILITY_BLOCK`` points (bounded working memory, a
    progress bar on stderr for long maps); the result's memory is estimated first and a map
    that cannot fit is refused (ResourceError).
    """
    setup = setup or Setup()
    omega = _as_axis(omega, "omega")
    sweeps = {"eps": _as_axis(eps, "eps")}
    for name, values in (("mu", mu), ("e", e)):
        if values is not None:
            sweeps[name] = _as_axis(values, name)
    shape = (len(omega), *(len(v) for v in sweeps.values()))
    n = int(np.prod(shape, dtype=float))
    check_memory(n * BYTES_PER_POINT, f"a stability map of {n:,} points per branch",
                 "use fewer grid points (smaller N)")
    for name, values in sweeps.items():
        _validated(setup, name, values)
    pars = _parameter_grid(setup, sweeps, slip_smoothing, shape)
    om_flat = np.broadcast_to(omega.reshape(-1, *([1] * len(sweeps))), shape).ravel()

    dims = ("omega", *sweeps)
    nb = len(BRANCH_NAMES)
    fields = {"eig_real": np.empty((nb, n, stability.N_EIG)), "eig_imag": np.empty((nb, n, stability.N_EIG)),
              "max_real_eig": np.empty((nb, n)), "n_unstable": np.empty((nb, n), dtype=np.int32),
              "stability": np.empty((nb, n), dtype=np.int8), "lambda_N": np.empty((nb, n)),
              "residual": np.empty((nb, n))}
    bar = tqdm(total=nb * n, unit="point", desc="stability map", file=sys.stderr, delay=2.0,
               disable=not progress, dynamic_ncols=True)
    done = 0
    try:
        for b, branch in enumerate(BRANCH_NAMES):
            for s0 in range(0, n, STABILITY_BLOCK):
                s1 = min(n, s0 + STABILITY_BLOCK)
                x = st.stationary_state(branch, om_flat[s0:s1])
                spec = stability.spectrum(branch, om_flat[s0:s1], pars[:, s0:s1])
                ev = reduced.evaluate(x, pars[:, s0:s1])
                fields["eig_real"][b, s0:s1] = spec.eigenvalues.real
                fields["eig_imag"][b, s0:s1] = spec.eigenvalues.imag
                fields["max_real_eig"][b, s0:s1] = spec.max_real_eig
                fields["n_unstable"][b, s0:s1] = spec.n_unstable
                fields["stability"][b, s0:s1] = spec.stability
                fields["lambda_N"][b, s0:s1] = ev["lambda_N"]
                fields["residual"][b, s0:s1] = np.max(np.abs(ev["rhs"]), axis=0)
                done += s1 - s0
                bar.update(s1 - s0)
    except KeyboardInterrupt:
        raise Interrupted(f"interrupted after {done:,} of {nb * n:,} points; nothing stored (a stability map is "
                          "computed in memory in one go: rerun to start again, or use a smaller grid)",
                          stored=0, total=nb * n) from None
    finally:
        bar.close()
    del pars
    for key in ("eig_real", "eig_imag"):
        fields[key] = fields[key].reshape(nb, *shape, stability.N_EIG)
    for key in ("max_real_eig", "n_unstable", "stability", "lambda_N", "residual"):
        fields[key] = fields[key].reshape(nb, *shape)

    bdims = ("branch", *dims)
    ds = xr.Dataset(
        {
            "eig_real": ((*bdims, "eig"), fields["eig_real"], {
                "units": "s-1", "long_name": "real part of the nontrivial eigenvalues of the reduced Jacobian",
                "comment": "sorted by real part, descending; the structural zero of the spin family is excluded"}),
            "eig_imag": ((*bdims, "eig"), fields["eig_imag"], {
                "units": "rad s-1",
                "long_name": "imaginary part of the nontrivial eigenvalues of the reduced Jacobian"}),
            "max_real_eig": (bdims, fields["max_real_eig"], {
                "units": "s-1", "long_name": "largest real part of the nontrivial eigenvalues (growth rate)"}),
            "n_unstable": (bdims, fields["n_unstable"], {
                "units": "1", "long_name": "number of eigenvalues with real part above the tolerance"}),
            "stability": (bdims, fields["stability"], {
                "long_name": "linear stability of the stationary solution",
                "flag_values": np.array(list(stability.STABILITY_FLAGS.values()), dtype=np.int8),
                "flag_meanings": " ".join(stability.STABILITY_FLAGS),
                "comment": f"tolerance on real parts: {EIG_ATOL:g} s-1 + {EIG_RTOL:g} * max |eigenvalue|"}),
            "lambda_N": (bdims, fields["lambda_N"], {
                "units": "N", "long_name": "normal contact force at C1 of the stationary solution"}),
            "residual": (bdims, fields["residual"], {
                "units": "1", "long_name": "max |right-hand side| of the reduced system at the stationary solution",
                "comment": "mixed units (rad s-1, m s-2, rad s-2); round-off level: the Jacobian times the "
                           "rounding of pi/2 (cos(pi/2) = 6e-17 in double precision)"}),
        },
        coords={
            "branch": ("branch", np.array(BRANCH_NAMES), {"long_name": "stationary solution family (Fig. 6)",
                                                          "comment": "noninverted: beta = pi/2, gamma = -pi/2; "
                                                                     "inverted: beta = pi/2, gamma = pi/2"}),
            "omega": ("omega", omega, {"units": "rad s-1", "long_name": "spin rate alpha_dot = Omega"}),
            **{name: (name, values, {"units": SWEEPABLE[name][0], "long_name": SWEEPABLE[name][1],
                                     **({"comment": setup.disk.eccentricity_rule} if name == "e" else {})})
               for name, values in sweeps.items()},
            "eig": index_coordinate("eig", stability.N_EIG, "eigenvalue index (by real part)"),
        },
    )
    n_found = 0
    if critical:
        crit = critical_speeds(ds, setup=setup, slip_smoothing=slip_smoothing)
        ds = ds.merge(crit)
        n_found = int(crit["n_critical"].sum())
    config = {
        "setup": to_dict(setup),
        "omega": _range_config(omega),
        **{name: _range_config(values) for name, values in sweeps.items()},
        **({"e_sweep": setup.disk.eccentricity_rule} if "e" in sweeps else {}),
        "slip_smoothing": slip_smoothing,
        "reduced_state": list(reduced.STATE_NAMES),
        "stability_tolerance": {"atol": EIG_ATOL, "rtol": EIG_RTOL},
        "critical_rtol": CRITICAL_RTOL,
        "heyoka_version": hy.__version__,
    }
    ds.attrs = make_attrs("stability_map", config, "completed",
                          f"{ds.sizes['omega']} x {int(np.prod(shape[1:]))} points per branch"
                          + (f"; {n_found} critical spin speeds" if critical else ""),
                          title="Eigenvalue stability of the stationary spinning solutions of the tippedisk",
                          model="ode-euler", paper_model="ODE Model 1 (reduced by the rotational symmetry)")
    return ds


def _as_axis(values, name: str) -> np.ndarray:
    return check_axis(values, name)


def _range_config(values: np.ndarray) -> dict:
    return {"start": float(values[0]), "stop": float(values[-1]), "n": int(values.size)}


def critical_speeds(ds: xr.Dataset, *, setup: Setup | None = None, slip_smoothing: float = SLIP_SMOOTHING) -> xr.Dataset:
    """Omega_c: zeros of max_real_eig along ``omega`` of a map, refined by brentq.

    Returns ``omega_critical`` [rad/s] (branch, other dims, crossing), padded with
    CRITICAL_PAD beyond ``n_critical``; ``critical_direction`` (+1: stable above Omega_c,
    -1: unstable above, 0: padding) and ``critical_frequency`` = ``|Im|`` of the eigenvalue
    crossing the imaginary axis [rad/s] (0 for a real eigenvalue, > 0 for a Hopf pair).
    """
    setup = setup or Setup()
    other = [d for d in ds["max_real_eig"].dims if d not in ("branch", "omega")]
    omega = ds["omega"].values
    mre = ds["max_real_eig"].transpose("branch", *other, "omega").values
    found = np.empty(mre.shape[:-1], dtype=object)
    for idx in np.ndindex(*mre.shape[:-1]):
        branch = str(ds["branch"].values[idx[0]])
        sweeps = {d: float(ds[d].values[i]) for d, i in zip(other, idx[1:])}
        pars = _parameter_grid(setup, {k: [v] for k, v in sweeps.items()}, slip_smoothing,
                               (1, *([1] * len(sweeps))))[:, 0]
        found[idx] = _roots(branch, omega, mre[idx], pars)
    n_max = max(1, max(len(f) for f in found.flat))
    values = np.full((*found.shape, n_max), CRITICAL_PAD)
    direction = np.zeros((*found.shape, n_max), dtype=np.int8)
    frequency = np.zeros((*found.shape, n_max))
    counts = np.zeros(found.shape, dtype=np.int32)
    for idx in np.ndindex(*found.shape):
        counts[idx] = len(found[idx])
        for k, (om, d, f) in enumerate(found[idx]):
            values[(*idx, k)], direction[(*idx, k)], frequency[(*idx, k)] = om, d, f
    cdims = ("branch", *other, "crossing")
    return xr.Dataset({
        "omega_critical": (cdims, values, {
            "units": "rad s-1", "long_name": "critical spin speed Omega_c (max_real_eig changes sign)",
            "padding_value": CRITICAL_PAD,
            "comment": f"the first n_critical entries along crossing are valid, in increasing Omega; the rest hold "
                       f"padding_value {CRITICAL_PAD:g}; refined by brentq to rtol {CRITICAL_RTOL:g}"}),
        "critical_direction": (cdims, direction, {
            "long_name": "stability change at Omega_c with increasing Omega",
            "flag_values": np.array([-1, 0, 1], dtype=np.int8),
            "flag_meanings": "destabilising padding stabilising"}),
        "critical_frequency": (cdims, frequency, {
            "units": "rad s-1", "long_name": "|imaginary part| of the eigenvalue crossing at Omega_c",
            "comment": "0: a real eigenvalue crosses zero; > 0: a complex pair crosses (Hopf); 0 for padding"}),
        "n_critical": (("branch", *other), counts, {
            "units": "1", "long_name": "number of critical spin speeds found in the omega range"}),
    }, coords={"crossing": index_coordinate("crossing", n_max, "critical speed index")})


def _roots(branch: str, omega: np.ndarray, mre: np.ndarray, pars: np.ndarray) -> list[tuple[float, int, float]]:
    """Sign changes of max_real_eig on the grid, refined: (Omega_c, direction, frequency)."""
    def f(om):
        return stability.max_real_eig(branch, om, pars)

    roots = []
    for i in range(len(omega) - 1):
        a, b, fa, fb = omega[i], omega[i + 1], mre[i], mre[i + 1]
        if fa * fb < 0:
            root = brentq(f, a, b, xtol=1e-14 * max(1.0, abs(a), abs(b)), rtol=CRITICAL_RTOL, maxiter=200)
            direction = 1 if fb < 0 else -1
        elif fb == 0.0 and fa != 0.0:  # exactly zero on the grid: no refinement needed
            root, direction = b, (1 if fa > 0 else -1)
        else:
            continue
        ev = stability.spectrum(branch, [root], pars).eigenvalues[0]
        roots.append((float(root), direction, float(abs(ev[0].imag))))
    return roots


def find_critical_speeds(branch: str, omega, setup: Setup | None = None,
                         slip_smoothing: float = SLIP_SMOOTHING) -> list[tuple[float, int, float]]:
    """Critical spin speeds of one branch for one parameter set, searched on the grid ``omega``:
    a list of (Omega_c [rad/s], direction (+1 stabilising, -1 destabilising with increasing Omega),
    ``|Im s|`` of the crossing eigenvalue [rad/s])."""
    st.branch_sign(branch)
    omega = _as_axis(omega, "omega")
    pars = ode.parameter_vector(setup, slip_smoothing=slip_smoothing)
    return _roots(branch, omega, stability.spectrum(branch, omega, pars).max_real_eig, pars)


def critical_speed_curves(ds: xr.Dataset) -> dict[str, xr.DataArray]:
    """Omega_c(eps, ...) per branch with the padding masked as NaN (for plots and analysis in memory;
    the stored dataset keeps the padding value and ``n_critical``)."""
    valid = ds["crossing"] < ds["n_critical"]
    masked = ds["omega_critical"].where(valid)
    return {str(b): masked.sel(branch=b) for b in ds["branch"].values}
