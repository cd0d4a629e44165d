"""The free disk's nutation, averaged: a two-dimensional slow flow in the amplitude and the spin (docs/inversion.md).

With the spin free the rolling disk (:func:`tippedisk_analysis.models.slow_flow.euler_system`, eps = 0) has a
two-parameter family of symmetric nutation orbits about the inverted spin: each starts upright (beta = pi/2) at
a turning point of gamma with amplitude a = pi/2 - gamma and spin alpha_dot = Omega0 there, swings S through the
top (gamma = pi/2, beta_dot = 0) and back. Friction moves a start across the family, O(eps) per revolution in
both labels (:func:`tippedisk_analysis.dynamics.drift_at` with ``along=("alpha_dot",)``), so to first order in eps

    d a / d(eps t) = F(a, Omega0),     d Omega0 / d(eps t) = G(a, Omega0),                           (N1)

a flow in the plane, independent of eps in the slow time eps t. Its assumptions: the precession (the family's
transverse oscillation) is not excited, and the start lies on the family (the first-order averaging of the slow
flow; the fast slip modes have relaxed). The held model (:mod:`.nutation_cycles`) is (N1) with G replaced by 0.
"""

from __future__ import annotations

import functools
import math
import numbers

import numpy as np
import xarray as xr
from scipy.integrate import solve_ivp

from .. import kinematics as kin
from ..dynamics import Event, drift_at
from ..dynamics.datasets import flag_attrs
from ..dynamics.symmetric_families import Shooter, Shooting, period_map
from ..errors import ParameterError
from ..models import slow_flow
from ..parameters import Setup
from ..results import make_attrs
from . import inversion

__all__ = ["shooting", "rates", "field", "averaged_path", "member_orbit", "precession_amplitude", "top_crossings",
           "turning_points", "euler_states"]

EPS_PROBES = (1e-4, 2e-4)  # m/s: the two values of eps at which the drift is measured (they must agree)
DRIFT_AGREEMENT = 1e-2  # relative, as dynamics.symmetric_families
_gamma = slow_flow.euler_system(True).variables[1]


def shooting(spin: float) -> Shooting:
    """From a turning point of gamma with the disk upright and spin alpha_dot = ``spin`` [rad/s] to the top."""
    return Shooting(fixed={"beta": 0.5 * math.pi, "gamma_dot": 0.0, "alpha_dot": float(spin)}, vary="gamma",
                    free="beta_dot", condition="beta_dot", section=Event("top", _gamma - 0.5 * math.pi, "positive"),
                    period_factor=4.0, t_max=60.0)


def _pars(setup: Setup | None) -> dict:
    setup = Setup() if setup is None else setup
    if not isinstance(setup, Setup):
        raise ParameterError(f"setup = {setup!r}: give a tippedisk_analysis.Setup (or None for Tables 1-3)")
    values = dict(zip(slow_flow.PARAMETER_NAMES, inversion.parameters("slow", setup)))
    return {**values, "eps": 0.0}


def _positive(value, what: str) -> float:
    if isinstance(value, bool) or not (isinstance(value, numbers.Real) and math.isfinite(value) and value > 0):
        raise ParameterError(f"{what} = {value!r}: give a positive number")
    return float(value)


def rates(amplitude: float, spin: float, setup: Setup | None = None, beta_dot_guess: float | None = None) -> dict:
    """(N1) at the member with amplitude a [rad] and spin Omega0 [rad/s] at its turning point: ``amplitude_rate``
    F [rad/m], ``spin_rate`` G [rad s-1 m-1], ``precession_rate`` sigma [1/m] (N2), ``period`` [s], ``beta_dot``
    at the start [rad/s], ``check`` (the
    two eps probes' relative difference) and ``valid`` (the period map has a double eigenvalue 1, no resonance,
    the probes agree)."""
    a, spin = _positive(amplitude, "amplitude"), _positive(spin, "spin")
    if a >= math.pi:
        raise ParameterError(f"amplitude = {a!r} rad: give a value between 0 and pi")
    pars = _pars(setup)
    guess = 1.2 * a if beta_dot_guess is None else float(beta_dot_guess)
    plan = shooting(spin)
    found = drift_at(slow_flow.euler_system(), plan, 0.5 * math.pi - a, guess, pars, "eps", EPS_PROBES,
                     unperturbed=slow_flow.euler_system(True), along=("alpha_dot",), transverse=True)
    period = found["period"]
    return {"amplitude_rate": -found["drift"] / period, "spin_rate": found["along_drift"]["alpha_dot"] / period,
            "precession_rate": float(np.mean(found["transverse_drift"])) / period,
            "period": period, "beta_dot": found["free"], "check": found["check"],
            "valid": found["valid"] and found["check"] <= DRIFT_AGREEMENT,
            "precession_valid": found["valid"] and found["transverse_check"] <= DRIFT_AGREEMENT}


@functools.lru_cache(maxsize=256)
def member_orbit(amplitude: float, spin: float, setup: Setup | None = None) -> tuple:
    """(state at the top, period, the precession's right and left eigenvectors of the period map there) of the
    rolling member (amplitude [rad], spin [rad/s])."""
    system = slow_flow.euler_system(True)
    pars = system.with_pars(None, **_pars(setup))
    shooter = Shooter(system, shooting(spin))
    found = rates(amplitude, spin, setup)
    hit = shooter.run(shooter.start(0.5 * math.pi - amplitude, found["beta_dot"]), pars)
    top, period = hit[0], 4.0 * hit[1]
    _, D = period_map(shooter, top, pars, 0.875 * period)
    w, right = np.linalg.eig(D)
    k = int(np.argmax(w.imag))  # the precession pair (the flow's 0 and the family's two 1 are real)
    w_left, left = np.linalg.eig(D.T)
    return top, period, right[:, k], left[:, int(np.argmin(np.abs(w_left - w[k])))]


def precession_amplitude(state, amplitude: float, spin: float, setup: Setup | None = None) -> float:
    """rho [rad]: the amplitude in beta of the precession about the member (amplitude [rad], spin [rad/s]) of a
    state (EULER_STATE_NAMES) at the top (gamma = pi/2, rising), from the left eigenvector l of the precession's
    multiplier: 2 |l . (x - x_top)| |v_beta| / |l . v|, independent of the precession's phase, blind to the
    family's directions (l . t = 0 along them)."""
    top, _period, v, left = member_orbit(round(float(amplitude), 4), round(float(spin), 4), setup)
    return float(2.0 * abs(left @ (np.asarray(state, dtype=float) - top)) * abs(v[0]) / abs(left @ v))


def field(amplitudes, spins, setup: Setup | None = None) -> xr.Dataset:
    """(N1) and (N2) on the grid ``amplitudes`` [rad] x ``spins`` [rad/s] (each increasing): ``amplitude_rate``,
    ``spin_rate``, ``precession_rate``, ``period``, ``exists`` (0 past the family's fold in the amplitude, where
    no member exists and the rates are 0) and ``valid`` (0 there, at the last member before the fold, and where
    the drift or sigma fails its checks; each counted in the message)."""
    a, spins = (np.asarray(v, dtype=float) for v in (amplitudes, spins))
    for name, v in (("amplitudes", a), ("spins", spins)):
        if v.ndim != 1 or v.size < 2 or not np.all(np.isfinite(v)) or np.any(np.diff(v) <= 0) or v[0] <= 0:
            raise ParameterError(f"{name}: give at least two positive increasing values")
    if a[-1] >= math.pi:
        raise ParameterError("amplitudes: give values below pi")
    shape = (spins.size, a.size)
    out = {key: np.full(shape, np.nan) for key in ("amplitude_rate", "spin_rate", "precession_rate", "period")}
    valid = np.zeros(shape, np.int8)
    for i, spin in enumerate(spins):
        guess = None
        for j, amplitude in enumerate(a):
            try:
                found = rates(amplitude, spin, setup, guess)
            except ParameterError:  # no member: past the fold of the family at this spin
                break
            guess = found["beta_dot"]
            for key in out:
                out[key][i, j] = found[key]
            valid[i, j] = found["valid"] and found["precession_valid"]
    exists = np.isfinite(out["period"]).astype(np.int8)
    ends = [(i, int(row.sum()) - 1) for i, row in enumerate(exists) if 0 < row.sum() < row.size]
    for i, j in ends:  # the member next to the family's fold: its multipliers approach 1 there
        valid[i, j] = 0
    missing = int(exists.size - exists.sum())
    failed = int((~valid.astype(bool)).sum()) - missing - len(ends)
    for key in out:  # no member: 0, flagged by exists = 0 (a dataset holds no NaN)
        out[key] = np.where(exists.astype(bool), out[key], 0.0)
    coords = {"spin": ("spin", spins, {"units": "rad s-1", "long_name": "spin alpha_dot at the turning point"}),
              "amplitude": ("amplitude", a, {"units": "rad", "long_name": "nutation amplitude pi/2 - gamma at the "
                                             "turning point"})}
    ds = xr.Dataset({
        "amplitude_rate": (("spin", "amplitude"), out["amplitude_rate"], {"units": "rad m-1", "long_name":
                           "d a / d(eps t) (N1)"}),
        "spin_rate": (("spin", "amplitude"), out["spin_rate"], {"units": "rad s-1 m-1", "long_name":
                      "d Omega0 / d(eps t) (N1)"}),
        "precession_rate": (("spin", "amplitude"), out["precession_rate"], {"units": "m-1", "long_name":
                            "growth rate sigma of the precession about the orbit per unit eps t (N2)"}),
        "period": (("spin", "amplitude"), out["period"], {"units": "s", "long_name": "period of the rolling orbit"}),
        "valid": (("spin", "amplitude"), valid, flag_attrs("drift and sigma defined and checked",
                                                           {"no": 0, "yes": 1})),
        "exists": (("spin", "amplitude"), exists, flag_attrs("a member of the family exists (no: past its fold, "
                                                             "the rates are 0 there)", {"no": 0, "yes": 1})),
    }, coords=coords)
    message = (f"{int(valid.sum())} of {valid.size} points checked; {missing} beyond the family's fold, "
               f"{len(ends)} next to it, {failed} failed their checks")
    ds.attrs = make_attrs("free_nutation_field", {"setup": repr(setup or Setup())}, "completed", message)
    return ds


def averaged_path(amplitude: float, spin: float, slow_time: float, setup: Setup | None = None,
                  samples: int = 50) -> xr.Dataset:
    """(N1) integrated from (a [rad], Omega0 [rad/s]) over the slow time eps t = ``slow_time`` [m]: ``amplitude``
    and ``spin`` at ``samples`` slow times. Status ``completed``, or ``left_family`` where the path reaches a
    point without a checked drift (past the fold, a resonance), which ends it."""
    slow_time = _positive(slow_time, "slow_time")
    state = {"guess": None, "where": None}

    def rhs(_s, y):
        try:
            found = rates(y[0], y[1], setup, state["guess"])
        except ParameterError:
            found = {"valid": False}
        if not found["valid"]:
            state["where"] = (float(y[0]), float(y[1]))
            raise _LeftFamily
        state["guess"] = found["beta_dot"]
        return [found["amplitude_rate"], found["spin_rate"]]

    times = np.linspace(0.0, slow_time, int(samples))
    status, message = "completed", f"reached eps t = {slow_time:g} m"
    try:
        flow = solve_ivp(rhs, (0.0, slow_time), [_positive(amplitude, "amplitude"), _positive(spin, "spin")],
                         dense_output=True, rtol=1e-6, atol=1e-7)
        values = flow.sol(times)
    except _LeftFamily:
        a_end, spin_end = state["where"]
        status = "left_family"
        message = f"no checked drift at a = {a_end:.4f} rad, Omega0 = {spin_end:.4f} rad/s"
        times, values = times[:1], np.array([[amplitude], [spin]])
    ds = xr.Dataset({"amplitude": ("slow_time", values[0], {"units": "rad", "long_name": "nutation amplitude"}),
                     "spin": ("slow_time", values[1], {"units": "rad s-1", "long_name": "spin at the turning point"})},
                    coords={"slow_time": ("slow_time", times, {"units": "m", "long_name": "eps t"})})
    ds.attrs = make_attrs("free_nutation_path", {"amplitude": amplitude, "spin": spin}, status, message)
    return ds


class _LeftFamily(Exception):
    """The averaged path reached a point without a checked drift."""


def euler_states(reduced_states) -> np.ndarray:
    """States (N, 5) in EULER_STATE_NAMES of ODE Model 1's reduced states (N, 7) (:mod:`..models.reduced`: beta,
    gamma, u_x, u_y, omega): the angles and their rates; the velocity of G, which rolling fixes, is dropped."""
    x = np.asarray(reduced_states, dtype=float)
    alpha_d, beta_d, gamma_d = kin.euler_rate_entries_from_omega(x[:, 0], x[:, 1], x[:, 4], x[:, 5], x[:, 6])
    return np.column_stack([x[:, 0], x[:, 1], alpha_d, beta_d, gamma_d])


def top_crossings(times, states) -> tuple[np.ndarray, np.ndarray]:
    """(times [s], states) where gamma rises through pi/2 in a run sampled at ``times`` (states (N, 5) in
    EULER_STATE_NAMES), linearly interpolated between samples."""
    x = np.asarray(states, dtype=float)
    g = x[:, 1]
    k = np.flatnonzero((g[:-1] < 0.5 * math.pi) & (g[1:] >= 0.5 * math.pi))
    f = ((0.5 * math.pi - g[k]) / (g[k + 1] - g[k]))[:, None]
    t = np.asarray(times, dtype=float)
    return t[k] + f[:, 0] * (t[k + 1] - t[k]), x[k] + f * (x[k + 1] - x[k])


def turning_points(times, gamma, alpha_dot) -> dict:
    """(time [s], a [rad], Omega0 [rad/s]) at the turning points of gamma below the top (its local minima) of a
    run sampled at ``times``: where a run lies in the plane of (N1)."""
    g = np.asarray(gamma, dtype=float)
    k = np.flatnonzero((g[1:-1] < g[:-2]) & (g[1:-1] <= g[2:]) & (g[1:-1] < 0.5 * math.pi)) + 1
    return {"time": np.asarray(times)[k], "amplitude": 0.5 * math.pi - g[k], "spin": np.asarray(alpha_dot)[k]}
