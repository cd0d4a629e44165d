"""The nutation cycles of the held-spin model: how large a nutation the inverted spin damps (docs/inversion.md).

At eps = 0 the held model (:func:`tippedisk_analysis.models.held_spin.rolling_system`: the disk rolls, its spin
about the vertical held at Omega) is reversible, and its inverted spin is a centre of two pairs: the nutation
(about 6 rad/s) and the precession (about 28 rad/s). The nutation spans a family of symmetric periodic orbits
(:mod:`tippedisk_analysis.dynamics.symmetric_families`): each starts upright (beta = pi/2) at a turning point of
gamma, swings S through the top (gamma = pi/2, beta_dot = 0) and back. Its **amplitude** a = pi/2 - gamma at the
turning point says how far S swings from straight above G (a = pi: S straight below G).

Friction moves a start across the family: per revolution its amplitude changes by eps times the Melnikov drift
of the orbit, O(eps) per period, so O(1) per unit slow time eps t (``drift_rate`` per unit eps is d a / d(eps t)).
For small amplitudes it is (C3)'s real part of the nutation pair, which turns negative at omega_c (the Hopf
point HOPF2 of the held model). Where it changes sign along the family a nutation cycle survives friction
(:func:`cycles`). Above omega_c one is left, repelling: the nutation decays inside it and grows outside, in the
amplitude averaged over the phase (the precession grows on both sides at every eps > 0). It appears at a fold of
cycles just below omega_c (:func:`fold_of_cycles`), where it meets the small attracting cycle born at omega_c.

The lower spin (S below G) is a saddle-centre of the rolling held model. At one held spin its unstable
manifold reaches the top with beta_dot = 0, on the fixed plane of a reversor, and so returns to it: a symmetric
homoclinic orbit (:func:`homoclinic_spin`). With friction the lower spin's precession grows, so its unstable
manifold is three-dimensional and its stable manifold one-dimensional; a homoclinic orbit needs that stable
manifold, followed backwards, to come back to the spin (:func:`lower_spin_scan`).
"""

from __future__ import annotations

import copy
import json
import math
import numbers

import numpy as np
import xarray as xr

from scipy.integrate import solve_ivp
from scipy.optimize import brentq, minimize_scalar

from ..dynamics import Event, Options
from ..dynamics.homoclinic import homoclinic_scan
from ..dynamics.melnikov import drift_at, family_drift
from ..dynamics.orbit_branches import continue_orbits
from ..dynamics.orbits import find_orbit
from ..dynamics.symmetric_families import Shooter, Shooting, symmetric_family
from ..errors import ParameterError
from ..models import held_spin
from ..parameters import Setup
from . import critical_spin, inversion

__all__ = ["SHOOTING", "EPS_PROBES", "family", "drift", "cycles", "repelling_cycle", "fold_of_cycles",
           "repelling_cycle_end", "held_fold_of_cycles", "amplitude_of", "orbit_amplitude", "averaged_amplitude",
           "homoclinic_spin", "lower_spin_scan"]

_gamma = held_spin.rolling_system().variables[1]
SHOOTING = Shooting(fixed={"beta": 0.5 * math.pi, "gamma_dot": 0.0}, vary="gamma", free="beta_dot",
                    condition="beta_dot", section=Event("top", _gamma - 0.5 * math.pi, "positive"),
                    period_factor=4.0, t_max=60.0)
"""From a turning point of gamma with the disk upright to the top, where beta_dot = 0 (both reversors' planes)."""
EPS_PROBES = (1e-5, 2e-5)  # m/s: the two values of eps at which the drift is measured (they must agree)
START_AMPLITUDE = 0.01  # rad: the family's first member, from the linearisation
FREE_BOUNDS = (-0.5, 30.0)  # rad/s: beta_dot at the start; the family's lower branch past its fold leaves it


def _pars(spin: float, setup: Setup | None, eps: float = 0.0) -> np.ndarray:
    setup = Setup() if setup is None else setup
    if not isinstance(setup, Setup):
        raise ParameterError(f"setup = {setup!r}: give a tippedisk_analysis.Setup (or None for Tables 1-3)")
    if isinstance(spin, bool) or not (isinstance(spin, numbers.Real) and math.isfinite(spin) and spin > 0):
        raise ParameterError(f"spin = {spin!r}: give the held spin in rad/s, e.g. 30.5")
    pars = inversion.parameters("held", setup, float(spin)).copy()
    pars[held_spin.system().parameter_index("eps")] = eps
    return pars


def amplitude_of(ds: xr.Dataset) -> np.ndarray:
    """a = pi/2 - gamma at the family's starts [rad]."""
    return 0.5 * math.pi - ds.amplitude.values


def orbit_amplitude(states: np.ndarray) -> float:
    """a = pi/2 - the smallest gamma [rad] over samples (N, 4) of a nutation orbit (e.g. a PeriodicOrbit's)."""
    return float(0.5 * math.pi - np.asarray(states)[:, 1].min())


def averaged_amplitude(ds: xr.Dataset, start: float, slow_times) -> np.ndarray:
    """The nutation amplitude [rad] at the slow times eps t [m] (increasing, from 0) of the averaged flow
    d a / d(eps t) = D(a) of a :func:`drift` dataset (its checked members up to the first fold, interpolated),
    from ``start`` [rad]."""
    _check_drift(ds)
    a = amplitude_of(ds)
    end = np.flatnonzero(ds.fold.values)
    keep = ds.drift_valid.values.astype(bool) & (np.arange(a.size) < (end[0] if end.size else a.size))
    order = np.argsort(a[keep])
    grid, rate = a[keep][order], ds.amplitude_rate.values[keep][order]
    times = np.asarray(slow_times, dtype=float)
    flow = solve_ivp(lambda _s, y: [np.interp(y[0], grid, rate)], (0.0, times[-1]), [float(start)],
                     dense_output=True, rtol=1e-9, atol=1e-12)
    return flow.sol(times)[0]


def family(spin: float, setup: Setup | None = None, *, max_amplitude: float = 3.1, max_points: int = 150) -> xr.Dataset:
    """The nutation family of the rolling held model at ``spin`` [rad/s] (disk of ``setup``), from amplitude
    START_AMPLITUDE to ``max_amplitude`` [rad] or until beta_dot at the start leaves FREE_BOUNDS (past a fold)."""
    if not (isinstance(max_amplitude, numbers.Real) and 0.1 < max_amplitude < math.pi):
        raise ParameterError(f"max_amplitude = {max_amplitude!r} rad: give a value between 0.1 and pi")
    if not (isinstance(max_points, numbers.Integral) and max_points >= 3):
        raise ParameterError(f"max_points = {max_points!r}: give an integer of at least 3")
    system = held_spin.rolling_system()
    pars = _pars(spin, setup)
    J = system.jacobian(held_spin.spin_state("inverted"), pars)
    w, V = np.linalg.eig(J)
    upper = w.imag > 1e-9
    if upper.sum() != 2 or np.abs(w.real).max() > 1e-9 * np.abs(w).max():
        raise ParameterError(f"at {spin:g} rad/s the inverted spin is no centre of two pairs; the nutation family "
                             "exists above the spin where the pairs collide (18.3 rad/s for Tables 1-2)")
    k = np.flatnonzero(upper)[np.argmin(w.imag[upper])]  # the slower pair: the nutation
    v = V[:, k] * np.exp(-1j * (np.angle(V[:, k][3]) - 0.5 * math.pi))  # gamma_dot's component imaginary
    b0 = -v.real[2] / v.real[1] * START_AMPLITUDE  # beta_dot at the turning point gamma = pi/2 - a
    return symmetric_family(system, SHOOTING, (0.5 * math.pi - START_AMPLITUDE, b0),
                            (0.5 * math.pi - max_amplitude, 0.5 * math.pi - 0.5 * START_AMPLITUDE), pars,
                            options=Options(ds=0.05, ds_max=0.1, max_points=max_points), free_bounds=FREE_BOUNDS,
                            direction=-1)


def drift(spin: float, setup: Setup | None = None, *, max_amplitude: float = 3.1, max_points: int = 150) -> xr.Dataset:
    """:func:`family` with each orbit's Melnikov drift under friction (:func:`.family_drift`, per unit eps) and
    ``amplitude_rate`` = d a / d(eps t) [rad/m], the nutation amplitude's rate in the slow time (negative: the
    nutation decays; the generic ``drift_rate`` is that of gamma at the start, the opposite sign)."""
    ds = family(spin, setup, max_amplitude=max_amplitude, max_points=max_points)
    out = family_drift(held_spin.system(), ds, SHOOTING, "eps", EPS_PROBES, unperturbed=held_spin.rolling_system())
    out["amplitude_rate"] = ("orbit", -out.drift_rate.values, {"units": "rad m-1", "long_name": "d a / d(eps t): "
                             "the nutation amplitude's rate in the slow time (negative: the nutation decays)"})
    return out


def _check_drift(ds) -> None:
    if not (isinstance(ds, xr.Dataset) and ds.attrs.get("kind") == "symmetric_family"
            and ds.attrs.get("system") == held_spin.rolling_system().name and "amplitude_rate" in ds):
        raise ParameterError("give a dataset of nutation_cycles.drift (the held model's nutation family with its "
                             "drift)")


def _member(ds: xr.Dataset, a: float, free_guess: float) -> tuple[float, float]:
    """(d a / d(eps t) [rad/m], period [s]) of the member with amplitude ``a`` of the family in ``ds`` (its stored
    parameters); the rate NaN where its drift fails its checks."""
    pars = json.loads(ds.attrs["config"])["pars"]
    found = drift_at(held_spin.system(), SHOOTING, 0.5 * math.pi - a, free_guess, pars, "eps", EPS_PROBES,
                     unperturbed=held_spin.rolling_system())
    return (-found["drift"] / found["period"] if found["valid"] else math.nan), found["period"]


def _spin_grows(ds: xr.Dataset) -> bool:
    """Whether the smallest nutations grow: the sign of the inverted spin's nutation pair at eps -> 0."""
    pars = dict(json.loads(ds.attrs["config"])["pars"], eps=1e-6)
    held = held_spin.system()
    w = np.linalg.eigvals(held.jacobian(held_spin.spin_state("inverted"), held.with_pars(None, **pars)))
    upper = w[w.imag > 1e-9]
    return bool(upper[np.argmin(upper.imag)].real > 0)


def cycles(ds: xr.Dataset, refine: bool = True) -> dict:
    """The nutation cycles that survive friction in a :func:`drift` dataset: the amplitudes [rad] where
    d a / d(eps t) changes sign on the family's first branch (up to its first fold), located by Brent's method on
    re-shot members (``refine``; else interpolated between members); {"cycles": [{"amplitude", "period" [s],
    "kind"}], "status"}. ``kind`` is ``repelling`` (the nutation decays inside it and grows outside, in the
    amplitude averaged over the phase) or ``attracting``. A cycle below the family's first checked member is
    found from the sign of the smallest nutations (the spin's own eigenvalues). Status ``completed`` (at least
    one), ``none_decays`` (the nutation grows at every amplitude), ``all_decay`` (it decays at every amplitude up
    to the fold, or to max_amplitude where the family has none there), ``incomplete`` (the family ended short of
    both, e.g. at max_points; with a ``message``) or ``unchecked`` (a sign change next to an orbit whose drift is
    not checked)."""
    _check_drift(ds)
    a, rate = amplitude_of(ds), ds.amplitude_rate.values
    free = ds.start.sel(state=SHOOTING.free).values
    valid = ds.drift_valid.values.astype(bool)
    first = np.flatnonzero(ds.fold.values)
    end = int(first[0]) if first.size else len(a)
    idx = [k for k in range(end) if valid[k]]
    if not idx:
        return {"cycles": [], "status": "unchecked"}
    brackets = []  # (low amplitude, its rate, free there, member index above)
    if (rate[idx[0]] < 0) == _spin_grows(ds):  # the smallest nutations do the opposite of the first member
        brackets.append((0.0, -rate[idx[0]], 0.0, idx[0]))
    for c in np.flatnonzero(np.sign(rate[idx][1:]) != np.sign(rate[idx][:-1])):
        i, j = idx[c], idx[c + 1]
        if j != i + 1:
            return {"cycles": [], "status": "unchecked"}
        brackets.append((a[i], rate[i], free[i], j))
    found = []
    for a_low, rate_low, free_low, j in brackets:
        known: dict = {}

        def rate_at(x, a_low=a_low, free_low=free_low, j=j, known=known):  # each member is shot once
            if x not in known:
                known[x] = _member(ds, x, free_low + (x - a_low) / (a[j] - a_low) * (free[j] - free_low))
            return known[x]

        amplitude = a_low + rate_low / (rate_low - rate[j]) * (a[j] - a_low)  # interpolated, unless refined
        if refine:
            low = a_low
            for _ in range(6 if a_low == 0.0 else 0):  # an amplitude below the cycle, with the smallest's sign
                low = (low or a[j]) * 0.25
                if np.sign(rate_at(low)[0]) == np.sign(rate_low):
                    break
            if low > 0 and np.sign(rate_at(low)[0]) == np.sign(rate_low):
                def finite_rate(x):
                    value = rate_at(x)[0]
                    if not math.isfinite(value):
                        raise ValueError("a member's drift failed its checks")
                    return value

                try:
                    amplitude = brentq(finite_rate, low, a[j], xtol=1e-7)
                except ValueError:
                    pass  # keep the interpolated amplitude
        found.append({"amplitude": float(amplitude), "period": float(rate_at(amplitude)[1]),
                      "kind": "repelling" if rate_low < 0 else "attracting"})
    if found:
        return {"cycles": found, "status": "completed"}
    if not first.size and ds.attrs.get("status") != "completed":  # the family ended short of its fold and bound
        return {"cycles": [], "status": "incomplete", "message": f"the family ended at a = {a.max():.4g} rad "
                f"({ds.attrs.get('message')}); no cycle below it: give more max_points"}
    return {"cycles": [], "status": "all_decay" if rate[idx[0]] < 0 else "none_decays"}


def repelling_cycle(ds: xr.Dataset) -> dict:
    """The largest repelling cycle of :func:`cycles` ({"amplitude", "period", "kind"}), or {"status": ...} of
    :func:`cycles` when there is none."""
    found = cycles(ds)
    repelling = [c for c in found["cycles"] if c["kind"] == "repelling"]
    return repelling[-1] if repelling else {"status": found["status"] if found["status"] != "completed" else
                                            "no_repelling_cycle"}


def _spins(bracket) -> tuple[float, float]:
    """A bracket of held spins (low, high), 0 < low < high [rad/s], or a one-line ParameterError."""
    ok = (not isinstance(bracket, str) and hasattr(bracket, "__len__") and len(bracket) == 2
          and all(isinstance(x, numbers.Real) and math.isfinite(x) for x in bracket) and 0 < bracket[0] < bracket[1])
    if not ok:
        raise ParameterError(f"bracket = {bracket!r}: give held spins (low, high) with 0 < low < high [rad/s]")
    return float(bracket[0]), float(bracket[1])


def fold_of_cycles(setup: Setup | None = None, bracket: tuple | None = None, xtol: float = 1e-4) -> dict:
    """The held spin [rad/s] below omega_c at which the attracting and the repelling nutation cycle meet (a fold
    of cycles): bisection of whether d a / d(eps t) < 0 anywhere on the family's first branch below amplitude
    0.6 rad (``bracket`` default: omega_c - 0.05 to omega_c). {"spin", "low", "high", "status"}: ``completed``,
    ``no_fold`` (cycles at both ends or at neither: the bracket holds no fold)."""
    setup = Setup() if setup is None else setup
    if not isinstance(setup, Setup):
        raise ParameterError(f"setup = {setup!r}: give a tippedisk_analysis.Setup (or None for Tables 1-3)")
    if bracket is None:
        omega_c = critical_spin.omega_critical(setup.disk, setup.gravity).omega_critical
        bracket = (omega_c - 0.05, omega_c)
    low, high = _spins(bracket)
    if not (isinstance(xtol, numbers.Real) and 0 < xtol < high - low):
        raise ParameterError(f"xtol = {xtol!r}: give a positive tolerance [rad/s] smaller than the bracket")

    def has_cycles(spin):
        ds = drift(spin, setup, max_amplitude=0.6, max_points=40)
        a, rate, valid = amplitude_of(ds), ds.amplitude_rate.values, ds.drift_valid.values.astype(bool)
        return bool(np.any(rate[valid] / a[valid] < 0))

    if has_cycles(low) or not has_cycles(high):
        return {"spin": math.nan, "low": low, "high": high, "status": "no_fold"}
    while high - low > xtol:
        mid = 0.5 * (low + high)
        low, high = (low, mid) if has_cycles(mid) else (mid, high)
    return {"spin": 0.5 * (low + high), "low": low, "high": high, "status": "completed"}


def _peak_rate(ds: xr.Dataset) -> tuple[float, float, bool]:
    """(largest d a / d(eps t) [rad/m] at an interior local maximum on the family's first branch, its amplitude
    [rad], True), refined between the neighbours of the largest member (members re-shot): where it is positive,
    the nutation grows between two cycles, a repelling one below and an attracting one above. Without an
    interior maximum, (the largest checked member's rate, its amplitude, False); (nan, nan, False) without
    checked members."""
    a, rate = amplitude_of(ds), ds.amplitude_rate.values
    free = ds.start.sel(state=SHOOTING.free).values
    first = np.flatnonzero(ds.fold.values)
    end = int(first[0]) if first.size else len(a)
    valid = ds.drift_valid.values.astype(bool)
    peaks = [j for j in range(1, end - 1) if valid[j - 1:j + 2].all() and rate[j] >= max(rate[j - 1], rate[j + 1])]
    if not peaks:  # the rate falls or rises all along: its largest checked member (no cycles pair there)
        checked = np.flatnonzero(valid[:end])
        if not checked.size:
            return math.nan, math.nan, False
        j = int(checked[np.argmax(rate[checked])])
        return float(rate[j]), float(a[j]), False
    j = max(peaks, key=lambda k: rate[k])

    def minus_rate(x):
        guess = np.interp(x, a[j - 1:j + 2], free[j - 1:j + 2])
        value = _member(ds, x, guess)[0]
        return -value if math.isfinite(value) else math.inf  # a member whose drift fails its checks never wins

    found = minimize_scalar(minus_rate, bounds=(a[j - 1], a[j + 1]), method="bounded", options={"xatol": 1e-5})
    if -found.fun >= rate[j]:
        return float(-found.fun), float(found.x), True
    return float(rate[j]), float(a[j]), True


PEAK_JUMP = 0.05  # rad/m and rad: the peak's rate and amplitude may change at most this much across a fold


def repelling_cycle_end(setup: Setup | None = None, bracket: tuple = (30.9, 31.0), xtol: float = 1e-5) -> dict:
    """The held spin [rad/s] above omega_c at which the repelling nutation cycle meets an attracting cycle above
    it and both vanish: a fold of cycles of the drift (eps -> 0). Brent's method on the largest rate between the
    two (:func:`_peak_rate`), which falls through zero there; ``bracket`` (default for Tables 1-2) must hold that
    sign change. Checks itself: 2 xtol either side of the root the peak is an interior maximum of the rate, of
    opposite signs, and moves by less than PEAK_JUMP. {"spin", "amplitude" (where the two cycles meet, rad),
    "status", "message"}: ``completed``; ``no_fold`` (the bracket holds no sign change: also where the cycles meet
    at the family's fold itself, where the drift fails its checks, or where an attracting cycle below meets the
    repelling one); ``not_verified`` (the sign change is a jump, not a fold). :func:`held_fold_of_cycles`
    finds the held model's own fold without the drift's."""
    low, high = _spins(bracket)
    if not (isinstance(xtol, numbers.Real) and 0 < xtol < high - low):
        raise ParameterError(f"xtol = {xtol!r}: give a positive tolerance [rad/s] smaller than the bracket")
    known: dict = {}

    def peak(spin):
        if spin not in known:
            known[spin] = _peak_rate(drift(spin, setup, max_amplitude=3.1))
        return known[spin][0]

    failed = {"spin": math.nan, "amplitude": math.nan}
    at_low, at_high = peak(low), peak(high)
    if not (at_low > 0 > at_high):
        return {**failed, "status": "no_fold", "message": f"the drift's peak does not fall through zero over "
                f"{low:g}-{high:g} rad/s ({at_low:.4g} and {at_high:.4g} rad/m at the ends)"}
    spin = brentq(peak, low, high, xtol=xtol)
    sides = [max(low, spin - 2 * xtol), min(high, spin + 2 * xtol)]
    for side in sides:
        peak(side)
    (rate_low, a_low, inner_low), (rate_high, a_high, inner_high) = known[sides[0]], known[sides[1]]
    sides_text = (f"the peak goes from {rate_low:.4g} rad/m at a = {a_low:.4g} rad to {rate_high:.4g} rad/m at "
                  f"a = {a_high:.4g} rad across {spin:.8g} rad/s")
    if not (inner_low and inner_high and rate_low >= 0 >= rate_high and abs(rate_low - rate_high) < PEAK_JUMP
            and abs(a_low - a_high) < PEAK_JUMP):
        return {**failed, "status": "not_verified", "message": f"{sides_text}: a jump, not a fold of cycles"}
    peak(spin)  # brentq's root is one of its evaluations, or else evaluated here
    return {"spin": float(spin), "amplitude": known[spin][1], "status": "completed", "message": sides_text}


START_TOL = 0.02  # rad: the held model's orbit must start this close to the drift's repelling cycle


def held_fold_of_cycles(spin: float, eps: float, setup: Setup | None = None, *, max_points: int = 60) -> dict:
    """The held model's own fold of cycles at friction ``eps`` [m/s]: its periodic orbit at ``spin`` [rad/s] next
    to the repelling cycle of :func:`drift` (found by shooting; it must lie within START_TOL of it), continued
    in the held spin (``dy.continue_orbits``, shooting) up to its first fold of cycles. Where the drift's fold
    is located (:func:`repelling_cycle_end`) it tends to it as eps -> 0 (for Tables 1-2 at O(eps^2)).
    {"spin", "amplitude" [rad], "period" [s], "start_amplitude", "status", "message"}: ``completed``,
    ``no_cycle`` (no repelling cycle at ``spin``), ``not_converged`` (shooting found no orbit), ``off_cycle`` (it
    found another orbit) or ``no_fold`` (none within ``max_points`` orbits or 1 rad/s)."""
    if isinstance(eps, bool) or not (isinstance(eps, numbers.Real) and 0 < eps < 0.1):
        raise ParameterError(f"eps = {eps!r}: give the friction's smoothing eps in m/s, 0 < eps < 0.1")
    ds = drift(spin, setup, max_amplitude=3.1)
    star = repelling_cycle(ds)
    failed = {"spin": math.nan, "amplitude": math.nan, "period": math.nan, "start_amplitude": math.nan}
    if "amplitude" not in star:
        return {**failed, "status": "no_cycle", "message": f"no repelling cycle at {spin:g} rad/s ({star['status']})"}
    k = int(np.argmin(np.abs(amplitude_of(ds) - star["amplitude"])))
    pars = _pars(spin, setup, eps)
    orbit = find_orbit(held_spin.system(), ds.start.values[k], float(ds.period.values[k]), pars)
    if not orbit.converged:
        return {**failed, "status": "not_converged", "message": orbit.message}
    start = orbit_amplitude(orbit.samples)
    if abs(start - star["amplitude"]) > START_TOL:
        return {**failed, "start_amplitude": start, "status": "off_cycle", "message": f"shooting found an orbit at "
                f"a = {start:.4f} rad, not the repelling cycle at a* = {star['amplitude']:.4f} rad; try another spin"}
    br, prob = continue_orbits(orbit, "spin", bounds={"spin": (spin - 1.0, spin + 1.0)}, method="shooting",
                               options=Options(ds=0.02, ds_max=0.3, max_points=max_points))
    folds = [sp for sp in br.special_points if sp.kind == "fold"]
    if not folds:
        return {**failed, "start_amplitude": start, "status": "no_fold", "message": br.message}
    u = folds[0].u
    system = held_spin.system()
    ta = copy.deepcopy(system.taylor(1e-12))  # templates are shared
    ta.time, ta.state[:] = 0.0, u[: prob.t_index]
    ta.pars[:] = _pars(float(u[prob.t_index + 1]), setup, eps)[: len(ta.pars)]
    states = ta.propagate_grid(np.linspace(0.0, float(u[prob.t_index]), 801))[-1]
    return {"spin": float(u[prob.t_index + 1]), "amplitude": orbit_amplitude(states), "period": float(u[prob.t_index]),
            "start_amplitude": start, "status": "completed",
            "message": f"the first fold of cycles on the held model's branch from {spin:g} rad/s, orbit "
                       f"{folds[0].index} of {len(br.points)}"}


MANIFOLD_OFFSET = 1e-8  # start of the unstable manifold: this far from the lower spin along its eigenvector
RETURN_TOL = 1e-5  # the homoclinic orbit must come back this close to the lower spin (state scale)


def _top_of_unstable_manifold(spin: float, setup: Setup | None, offset: float = MANIFOLD_OFFSET) -> tuple:
    """(state at the first crossing of the top, time) of the lower spin's unstable manifold (gamma increasing)
    in the rolling held model; None if it does not get there."""
    system = held_spin.rolling_system()
    pars, lower = _pars(spin, setup), held_spin.spin_state("lower")
    w, V = np.linalg.eig(system.jacobian(lower, pars))
    k = int(np.argmax(w.real))
    if not (abs(w[k].imag) < 1e-9 and w[k].real > 1e-6):
        raise ParameterError(f"at {spin:g} rad/s the lower spin has no real unstable eigenvalue: it is no saddle "
                             "there; give another bracket")
    v = V[:, k].real / np.linalg.norm(V[:, k].real)
    return Shooter(system, SHOOTING).run(lower + offset * np.sign(v[1]) * v, pars)


def homoclinic_spin(setup: Setup | None = None, bracket: tuple = (30.0, 36.0)) -> dict:
    """The held spin [rad/s] in ``bracket`` at which the lower spin's unstable manifold crosses the top with
    beta_dot = 0 (the fixed plane of the reversor (beta, pi - gamma, -beta_dot, gamma_dot)), so that it returns
    to the lower spin: a symmetric homoclinic orbit of the rolling held model. Checks itself: the orbit, run on
    for as long again, comes back to within RETURN_TOL of the lower spin. {"spin", "tilt_at_top" (beta - pi/2,
    rad), "return_distance", "status"}: ``completed``, ``no_crossing`` (beta_dot keeps its sign at the ends of
    the bracket) or ``not_verified`` (the return check failed)."""
    low, high = _spins(bracket)

    def beta_dot(spin):
        hit = _top_of_unstable_manifold(spin, setup)
        return math.nan if hit is None else float(hit[0][2])

    ends = beta_dot(low), beta_dot(high)
    if not (np.all(np.isfinite(ends)) and ends[0] * ends[1] < 0):
        return {"spin": math.nan, "tilt_at_top": math.nan, "return_distance": math.nan, "status": "no_crossing"}
    spin = brentq(beta_dot, low, high, xtol=1e-10, rtol=1e-14)
    top, time = _top_of_unstable_manifold(spin, setup)
    system = held_spin.rolling_system()
    ta = copy.deepcopy(system.taylor(1e-13))  # templates are shared
    ta.time, ta.state[:], ta.pars[:] = time, top, _pars(spin, setup)[: len(ta.pars)]
    states = ta.propagate_grid(np.linspace(time, 2.0 * time, 4001))[-1]
    lower = held_spin.spin_state("lower") + np.array([0.0, 2.0 * math.pi, 0.0, 0.0])  # gamma went once round
    distance = float(np.min(np.abs((states - lower) / np.array(system.state_scale)).max(axis=1)))
    return {"spin": float(spin), "tilt_at_top": float(top[0] - 0.5 * math.pi), "return_distance": distance,
            "status": "completed" if distance < RETURN_TOL else "not_verified"}


LOWER_SPINS = tuple(np.round(np.arange(26.0, 36.01, 0.25), 2))  # rad/s: the default scan of lower_spin_scan
LOWER_RADIUS = 0.1  # scaled: on the e = 3.5 mm disk the branch comes back no closer than 0.051 (precession left)


def lower_spin_scan(eps: float, setup: Setup | None = None, spins=LOWER_SPINS, **options) -> xr.Dataset:
    """The lower spin's one-dimensional stable manifold in the held model with friction (eps > 0 [m/s]), followed
    backwards from the side S arrives on (gamma increasing) over the top and back to the lower spin, at each held
    spin [rad/s] in ``spins`` (:func:`tippedisk_analysis.dynamics.homoclinic.homoclinic_scan`). side +1: it
    leaves the lower spin again rolling on over the top (gamma still falling, backwards in time); -1: it turns
    back. Every change of side is bisected and checked; only a ``completed`` crossing is a homoclinic orbit of
    the lower spin. ``options``: ``radius`` (default LOWER_RADIUS), ``offset``, ``t_max``, ``xtol`` of the generic
    functions. For eps = 0 see :func:`homoclinic_spin`."""
    if isinstance(eps, bool) or not (isinstance(eps, numbers.Real) and math.isfinite(eps) and eps > 0):
        raise ParameterError(f"eps = {eps!r}: give the friction parameter in m/s, e.g. 0.005 (for eps = 0 use "
                             "nutation_cycles.homoclinic_spin)")
    pars = _pars(held_spin.DEFAULT_SPIN, setup, float(eps))  # the lower spin is an equilibrium at every spin
    ds = homoclinic_scan(held_spin.system(), held_spin.spin_state("lower"), "spin", spins, pars,
                         manifold="stable", branch="-gamma", shift=(0.0, -2.0 * math.pi, 0.0, 0.0),
                         **{"radius": LOWER_RADIUS, **options})
    ds.attrs.update(eps=float(eps), homoclinic_orbits=int(np.sum(ds.crossing_status.values == "completed")))
    return ds
