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
from scipy.integrate import RK45

from .. import kinematics as kin
from ..dynamics import Event, Options, drift_at
from ..dynamics.datasets import flag_attrs
from ..dynamics.melnikov import period_map
from ..dynamics.symmetric_families import Shooter, Shooting, symmetric_family
from ..errors import ParameterError
from ..models import slow_flow
from ..parameters import Setup
from ..results import make_attrs
from . import inversion

__all__ = ["NoMember", "shooting", "first_branch", "rates", "field", "averaged_path", "member_orbit",
           "precession_amplitude", "precession_along", "top_crossings", "turning_points", "euler_states"]

EPS_PROBES = (1e-4, 2e-4)  # m/s: the two values of eps at which the drift is measured (they must agree)
DRIFT_AGREEMENT = 1e-2  # relative, as dynamics.melnikov
START_AMPLITUDE = 0.01  # rad: the family's first member, and the smallest amplitude asked for
BRANCH_SPIN_STEP = 0.25  # rad/s: the family's first branch is traced at spins on this grid (the nearest serves)
BRANCH_TOL = 0.05  # rad/s: a member's beta_dot must lie this close to the traced branch's (else another branch)
BRANCH_STEP = 0.15  # the largest continuation step along the branch (larger ones jumped past folds at 32.5 rad/s)
SETTLED = 0.02  # rad: an averaged path whose nutation decays below this has reached the inverted spins (a = 0)
FOLD_MARGIN = 0.05  # rad: members are resolved up to this far below the first branch's fold
RATE_FLOORS = (1.0, 5.0)  # rad/m, rad s-1 m-1: typical |F|, |G| (medians 1.6, 4.2 on the study's grid): the two
# eps probes must agree to DRIFT_AGREEMENT of the larger of a rate and its floor (a zero of F is no failure)
_gamma = slow_flow.euler_system(True).variables[1]


class NoMember(ParameterError):
    """No member of the nutation family's first branch at the amplitude and spin asked for."""


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


@functools.lru_cache(maxsize=64)
def first_branch(spin: float, setup: Setup | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(a [rad], beta_dot at the start [rad/s]) along the family's first branch at ``spin`` [rad/s]: traced by
    continuation from START_AMPLITUDE up to the family's first fold in the amplitude (past it the members belong
    to other branches)."""
    system = slow_flow.euler_system(True)
    pars = system.with_pars(None, **_pars(setup))
    spin = _positive(spin, "spin")
    w = np.linalg.eigvals(system.jacobian(np.array([0.5 * math.pi, 0.5 * math.pi, spin, 0.0, 0.0]), pars))
    if np.sum(w.imag > 1e-9) != 2 or np.abs(w.real).max() > 1e-9 * np.abs(w).max():
        raise NoMember(f"at {spin:g} rad/s the inverted spin is no centre of two pairs, so no nutation family "
                       "surrounds it (for Tables 1-2 give a spin above 18.3 rad/s)")
    plan = shooting(spin)
    b0 = Shooter(system, plan).solve_free(0.5 * math.pi - START_AMPLITUDE, 1.2 * START_AMPLITUDE, pars)
    if not math.isfinite(b0):
        raise NoMember(f"no small nutation orbit found at {spin:g} rad/s")
    ds = symmetric_family(system, plan, (0.5 * math.pi - START_AMPLITUDE, b0),
                          (0.5 * math.pi - 3.1, 0.5 * math.pi - 0.5 * START_AMPLITUDE), pars,
                          options=Options(ds=0.1, ds_max=BRANCH_STEP, max_points=150), free_bounds=(-0.5, 30.0),
                          direction=-1)
    a, beta_dot = 0.5 * math.pi - ds.amplitude.values, ds.start.sel(state="beta_dot").values
    # the first fold (the core locates it), the first turn of a, or a jump to another branch, whichever first
    ends = [*np.flatnonzero(ds.fold.values), *np.flatnonzero(np.diff(a) <= 0),
            *np.flatnonzero(np.abs(np.diff(beta_dot)) > 2 * BRANCH_STEP), a.size - 1]
    end = min(ends) + 1
    return a[:end], beta_dot[:end]


def _member(amplitude: float, spin: float, setup: Setup | None) -> float:
    """beta_dot [rad/s] to start solving for the member (amplitude [rad], spin [rad/s]) on the first branch."""
    key = round(round(spin / BRANCH_SPIN_STEP) * BRANCH_SPIN_STEP, 6)
    a, beta_dot = first_branch(key, setup)
    if amplitude < START_AMPLITUDE:
        raise NoMember(f"a = {amplitude:g} rad: give at least {START_AMPLITUDE:g} rad (the family's first member)")
    if amplitude > a[-1] - FOLD_MARGIN:
        raise NoMember(f"a = {amplitude:g} rad: at {key:g} rad/s the nutation family's first branch folds at "
                       f"{a[-1]:.4f} rad; members are resolved up to {FOLD_MARGIN:g} rad below it")
    return float(np.interp(amplitude, a, beta_dot))


def rates(amplitude: float, spin: float, setup: Setup | None = None) -> dict:
    """(N1) at the member with amplitude a [rad] and spin Omega0 [rad/s] at its turning point: ``amplitude_rate``
    F [rad/m], ``spin_rate`` G [rad s-1 m-1], ``precession_rate`` sigma [1/m] (N2), ``period`` [s], ``beta_dot``
    at the start [rad/s], ``check`` (the two eps probes' difference, relative to the larger of each rate and its
    floor RATE_FLOORS), ``valid`` (the period map has a double eigenvalue 1, no resonance, the probes agree to
    DRIFT_AGREEMENT), ``reason`` (why not) and ``precession_valid`` (the same for sigma).
    The member is the one on the family's first branch (:func:`first_branch`), up to FOLD_MARGIN below its fold;
    NoMember (a ParameterError) beyond, or where none is."""
    a, spin = _positive(amplitude, "amplitude"), _positive(spin, "spin")
    if a >= math.pi:
        raise ParameterError(f"amplitude = {a!r} rad: give a value between 0 and pi")
    pars = _pars(setup)
    guess = _member(a, spin, setup)
    plan = shooting(spin)
    try:
        found = drift_at(slow_flow.euler_system(), plan, 0.5 * math.pi - a, guess, pars, "eps", EPS_PROBES,
                         unperturbed=slow_flow.euler_system(True), along=("alpha_dot",), transverse=True)
    except ParameterError as error:
        raise NoMember(f"a = {a:g} rad, Omega0 = {spin:g} rad/s: {error}") from None
    if abs(found["free"] - guess) > BRANCH_TOL:
        raise NoMember(f"a = {a:g} rad, Omega0 = {spin:g} rad/s: the member found (beta_dot {found['free']:.4f} "
                       f"rad/s) is not on the first branch (beta_dot {guess:.4f} rad/s there)")
    period = found["period"]
    rate = np.array([-found["drift"], found["along_drift"]["alpha_dot"]]) / period
    probes = np.array(found["probes"]) * np.array([-1.0, 1.0]) / period  # (F, G) at the two eps probes
    spread = np.abs(probes[0] - probes[1]) / np.maximum(np.abs(rate), RATE_FLOORS)
    agree = bool(np.all(spread <= DRIFT_AGREEMENT))
    return {"amplitude_rate": float(rate[0]), "spin_rate": float(rate[1]),
            "precession_rate": float(np.mean(found["transverse_drift"])) / period,
            "period": period, "beta_dot": found["free"], "check": float(spread.max()),
            "valid": found["valid"] and agree,
            "reason": found["reason"] or ("" if agree else f"the two eps probes differ by {spread.max():.2g} of "
                                                           "the rates"),
            "precession_valid": found["valid"] and found["transverse_check"] <= DRIFT_AGREEMENT}


@functools.lru_cache(maxsize=256)
def member_orbit(amplitude: float, spin: float, setup: Setup | None = None) -> tuple:
    """(state at the top, period, the precession's right and left eigenvectors of the period map there) of the
    rolling member (amplitude [rad], spin [rad/s])."""
    system = slow_flow.euler_system(True)
    pars = system.with_pars(None, **_pars(setup))
    shooter = Shooter(system, shooting(spin))
    gamma0 = 0.5 * math.pi - amplitude
    beta_dot = shooter.solve_free(gamma0, _member(amplitude, spin, setup), pars)
    hit = None if not math.isfinite(beta_dot) else shooter.run(shooter.start(gamma0, beta_dot), pars)
    if hit is None:
        raise NoMember(f"no member of the nutation family at a = {amplitude:g} rad, Omega0 = {spin:g} rad/s")
    top, period = hit[0], 4.0 * hit[1]
    _, D = period_map(shooter, top, pars, 0.875 * period)
    w, right = np.linalg.eig(D)
    k = int(np.argmax(w.imag))  # the precession pair (the flow's 0 and the family's two 1 are real)
    w_left, left = np.linalg.eig(D.T)
    return top, period, right[:, k], left[:, int(np.argmin(np.abs(w_left - w[k])))]


def precession_amplitude(state, amplitude: float, spin: float, setup: Setup | None = None) -> float:
    """rho [rad]: the amplitude in beta of the precession about the member (amplitude [rad], spin [rad/s]) of a
    state (EULER_STATE_NAMES) at the top (gamma = pi/2, rising), from the left eigenvector l of the precession's
    multiplier: 2 abs(l . (x - x_top)) abs(v_beta) / abs(l . v), independent of the precession's phase, blind to the
    family's directions (l . t = 0 along them)."""
    x = np.asarray(state, dtype=float)
    if x.shape != (len(slow_flow.EULER_STATE_NAMES),) or not np.all(np.isfinite(x)):
        raise ParameterError(f"state: give one finite state ({', '.join(slow_flow.EULER_STATE_NAMES)}), shape "
                             f"{x.shape} given")
    _pars(setup)
    a, spin = _positive(amplitude, "amplitude"), _positive(spin, "spin")
    top, _period, v, left = member_orbit(round(a, 4), round(spin, 4), setup)
    return float(2.0 * abs(left @ (x - top)) * abs(v[0]) / abs(left @ v))


def field(amplitudes, spins, setup: Setup | None = None) -> xr.Dataset:
    """(N1) and (N2) on the grid ``amplitudes`` [rad] x ``spins`` [rad/s] (each increasing): ``amplitude_rate``,
    ``spin_rate``, ``precession_rate``, ``period``, ``exists`` (0 past the family's fold in the amplitude, where
    no member is resolved, FOLD_MARGIN below it and beyond, and the rates are 0) and ``valid`` (0 there and where
    the drift or sigma fails its checks; each counted in the message)."""
    try:
        a, spins = (np.asarray(v, dtype=float) for v in (amplitudes, spins))
    except (TypeError, ValueError):
        raise ParameterError("amplitudes, spins: give two sequences of numbers [rad], [rad/s]") from None
    for name, v in (("amplitudes", a), ("spins", spins)):
        if v.ndim != 1 or v.size < 2 or not np.all(np.isfinite(v)) or np.any(np.diff(v) <= 0) or v[0] <= 0:
            raise ParameterError(f"{name}: give at least two positive increasing values")
    if a[-1] >= math.pi:
        raise ParameterError("amplitudes: give values below pi")
    _pars(setup)  # a bad setup is an error, not a family without members
    shape = (spins.size, a.size)
    out = {key: np.full(shape, np.nan) for key in ("amplitude_rate", "spin_rate", "precession_rate", "period")}
    valid = np.zeros(shape, np.int8)
    for i, spin in enumerate(spins):
        for j, amplitude in enumerate(a):
            try:
                found = rates(amplitude, spin, setup)
            except NoMember:  # past the fold of the family's first branch at this spin
                break
            for key in out:
                out[key][i, j] = found[key]
            valid[i, j] = found["valid"] and found["precession_valid"]
    exists = np.isfinite(out["period"]).astype(np.int8)
    missing = int(exists.size - exists.sum())
    failed = int((~valid.astype(bool)).sum()) - missing
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
        "exists": (("spin", "amplitude"), exists, flag_attrs("a member of the first branch is resolved (no: within "
                                                             f"{FOLD_MARGIN:g} rad of its fold or past it; the rates "
                                                             "are 0 there)", {"no": 0, "yes": 1})),
    }, coords=coords)
    message = (f"{int(valid.sum())} of {valid.size} points checked; {missing} beyond the first branch (less "
               f"than {FOLD_MARGIN:g} rad below its fold, or past it), {failed} failed their checks")
    ds.attrs = make_attrs("free_nutation_field", {"setup": repr(setup or Setup())}, "completed", message)
    return ds


def averaged_path(amplitude: float, spin: float, slow_time: float, setup: Setup | None = None,
                  samples: int = 50) -> xr.Dataset:
    """(N1) integrated from (a [rad], Omega0 [rad/s]) over the slow time eps t = ``slow_time`` [m]: ``amplitude``
    and ``spin`` at ``samples`` equally spaced slow times. Status ``completed``; ``settled`` where the nutation
    has decayed below SETTLED (the path has reached the inverted spins, a line of equilibria of (N1)); or
    ``left_family`` where it reaches a point without a checked drift (past the fold, a resonance). The path up
    to where it ended is kept: the samples before, and the last point reached."""
    slow_time = _positive(slow_time, "slow_time")
    if isinstance(samples, bool) or not isinstance(samples, numbers.Integral) or samples < 2:
        raise ParameterError(f"samples = {samples!r}: give an integer of at least 2")
    y = np.array([_positive(amplitude, "amplitude"), _positive(spin, "spin")])
    rates(*y, setup)  # a start without a member is an error, not a path that left the family

    def rhs(_s, z):
        if z[0] < SETTLED:
            raise _Ended("settled", f"the nutation decays below {SETTLED:g} rad")
        try:
            found = rates(z[0], z[1], setup)
        except NoMember as error:
            raise _Ended("left_family", str(error)) from None
        if not found["valid"]:
            raise _Ended("left_family", f"no checked drift at a = {z[0]:.4f} rad, Omega0 = {z[1]:.4f} rad/s: "
                                        f"{found['reason']}")
        return [found["amplitude_rate"], found["spin_rate"]]

    times = np.linspace(0.0, slow_time, int(samples))
    solver = RK45(rhs, 0.0, y, slow_time, rtol=1e-6, atol=1e-7)
    steps = []  # the dense output of each completed step
    status, message = "completed", f"reached eps t = {slow_time:g} m"
    while solver.status == "running":
        try:
            solver.step()
        except _Ended as end:
            status, message = end.args
            break
        if solver.status == "failed":
            status, message = "left_family", f"the integrator failed at eps t = {solver.t:g} m"
            break
        steps.append(solver.dense_output())
    reached = steps[-1].t_max if steps else 0.0
    if status != "completed":  # the samples up to where it ended, and that point
        times = np.append(times[times < reached], reached)
    values = np.array([y if t == 0.0 else next(d for d in steps if d.t_min <= t <= d.t_max)(t) for t in times]).T
    ds = xr.Dataset({"amplitude": ("slow_time", values[0], {"units": "rad", "long_name": "nutation amplitude"}),
                     "spin": ("slow_time", values[1], {"units": "rad s-1", "long_name": "spin at the turning point"})},
                    coords={"slow_time": ("slow_time", times[: values.shape[1]], {"units": "m", "long_name":
                                                                                   "eps t"})})
    if status != "completed":
        message += (f"; the path is kept up to eps t = {reached:g} m (a = {values[0][-1]:.4f} rad, Omega0 = "
                    f"{values[1][-1]:.4f} rad/s)")
    ds.attrs = make_attrs("free_nutation_path", {"amplitude": float(amplitude), "spin": float(spin),
                                                 "slow_time": slow_time}, status, message)
    return ds


class _Ended(Exception):
    """The averaged path ended: (status, message)."""


def precession_along(times, states, setup: Setup | None = None) -> np.ndarray:
    """Rows (time [s], rho [rad], a [rad], Omega0 [rad/s]), one per top crossing of a run sampled at ``times``
    (``states`` (N, 5) in EULER_STATE_NAMES): the precession's amplitude about the member of the run's last
    turning point; crossings before the first turning point, or whose member is not resolved, are left out."""
    x = np.asarray(states, dtype=float)
    turns = turning_points(times, x[:, 1], x[:, 2])
    rows = []
    for t, state in zip(*top_crossings(times, x)):
        before = turns["time"] < t
        if not before.any():
            continue
        a, spin = turns["amplitude"][before][-1], turns["spin"][before][-1]
        try:
            rows.append((t, precession_amplitude(state, a, spin, setup), a, spin))
        except NoMember:  # the run lies beyond the family's first branch here
            continue
    return np.array(rows).reshape(-1, 4)


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
    if not (np.ndim(times) == g.ndim == np.ndim(alpha_dot) == 1 and len(times) == g.size == len(alpha_dot)):
        raise ParameterError("times, gamma, alpha_dot: give three sequences of the same length")
    k = np.flatnonzero((g[1:-1] < g[:-2]) & (g[1:-1] <= g[2:]) & (g[1:-1] < 0.5 * math.pi)) + 1
    return {"time": np.asarray(times)[k], "amplitude": 0.5 * math.pi - g[k], "spin": np.asarray(alpha_dot)[k]}
