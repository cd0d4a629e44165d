"""The Melnikov drift of a family of symmetric periodic orbits (:mod:`.symmetric_families`) under a perturbation.

For p != 0 the family breaks up, and a start on it
moves across it by O(p) per revolution: the Melnikov function of the family. With P the period map to the
section and DP0 its derivative on the family at p = 0 (DP0 t = t along the family tangent t, DP0 f = 0 along the
flow), the left eigenvector l of DP0 for the eigenvalue 1 takes out every other direction, so

    da per revolution = p l . dP/dp / (l . dx/da) + O(p^2),

a = the amplitude. dP/dp is measured at two small values of p, and the reported drift is their linear
extrapolation to p = 0; the two must agree (``drift_check``). dx/da comes from members re-shot at a +- 1e-6.
Where the drift changes sign along the family a periodic orbit of the perturbed system survives (a zero of the
Melnikov function); its sign says on which side starts drift. Where another eigenvalue of DP0 comes near 1 (a
resonance of the transverse oscillation with the family, a fold) l is not defined, and where one passes 1
between two members the family branches (the drift may have a pole there): such orbits are flagged
(``drift_valid`` = 0, with ``resonance_gap`` and ``branch_point``).

:func:`drift_at` also takes families of families (``along``: fixed start values that label the family too; l
becomes the left null space of DP0 - I, one vector per label) and the growth of the oscillation about the orbit
(``transverse``: the first-order change of the transverse multipliers' modulus, with the perturbed map
differentiated at its guiding point x0 + p z, (DP0 - I) z = (the drift along the family) - dP/dp).
"""

from __future__ import annotations

import json
import math

import numpy as np
import xarray as xr

from ..errors import ParameterError
from ..results import make_attrs
from .datasets import flag_attrs
from .symmetric_families import FD_STEP, Shooter, Shooting, finite_real
from .system import System

__all__ = ["family_drift", "drift_at", "period_map"]

RESONANCE_GAP = 0.05  # an eigenvalue of DP0 closer than this to 1 leaves the drift undefined
DRIFT_AGREEMENT = 1e-2  # the drift at the two parameter values must agree to this (relative)
ONE_TOL = 1e-3  # the period map's eigenvalue for the family tangent must lie this close to 1


def period_map(shooter: Shooter, x0: np.ndarray, pars: np.ndarray, skip: float):
    """(the crossing after ``skip`` [time units] from ``x0``, i.e. a period on for skip = (1 - 1 / (2 period_factor))
    periods, and the derivative of that map at ``x0`` by forward differences), or None where a run fails."""
    n = len(x0)
    base = shooter.run(x0, pars, skip)
    if base is None:
        return None
    D = np.zeros((n, n))
    for j in range(n):
        h = FD_STEP * max(1.0, abs(x0[j]))
        hit = shooter.run(x0 + h * np.eye(n)[j], pars, skip)
        if hit is None:
            return None
        D[:, j] = (hit[0] - base[0]) / h
    return base, D


def _orbit_drift(shooters: tuple, x0: np.ndarray, period: float, amplitude: float, free, pars: np.ndarray,
                 index: int, values: tuple, along: tuple = (), transverse: bool = False) -> dict:
    """One orbit's drift (at p -> 0, extrapolated from ``values``) of the amplitude and of the fixed start values
    named in ``along`` (a family of families: an array of 1 + len(along)), the two measured values of each, the
    resonance gap, the product of (mu - 1) over the transverse multipliers (its sign change between members marks
    a branch point) and whether the period map has as many eigenvalues 1 as the family has parameters (``one``).
    transverse: also d ln abs(mu) / dp per revolution of each transverse multiplier (``transverse_drift``, ordered by
    abs(arg mu); NaN where a perturbed map cannot be run): whether the perturbation makes the transverse oscillation
    grow or decay."""
    shooter, base_shooter = shooters
    n, k = len(x0), 1 + len(along)
    out = {"drift": np.full(k, math.nan), "measured": np.full((k, 2), math.nan), "gap": 0.0, "transverse": 0.0,
           "one": True, "transverse_drift": np.full(max(n - k - 1, 0), math.nan), "transverse_check": math.inf}
    skip = period * (1.0 - 0.5 / shooter.shooting.period_factor)  # the next crossing is the one a period on
    mapped = period_map(base_shooter, x0, pars, skip)
    tangents = base_shooter.tangents(amplitude, free, pars, along)
    if mapped is None or tangents is None:
        return out
    base, D = mapped
    others = _transverse_multipliers(D, k)
    if others is None:  # two multipliers near 1 split (a fold or a resonance): no l
        return {**out, "one": False}
    out["gap"] = float(np.min(np.abs(others - 1.0))) if others.size else math.inf
    out["transverse"] = float(np.prod(others - 1.0).real) if others.size else 1.0
    ell = np.linalg.svd(D - np.eye(n))[0][:, -k:]  # the left null space of DP0 - I: l^T DP0 = l^T
    projected = ell.T @ tangents
    if not np.all(np.isfinite(projected)) or np.linalg.cond(projected) > 1e12:
        return out
    measured, guides = [], []
    for value in values:
        perturbed = pars.copy()
        perturbed[index] = value
        hit = shooter.run(x0, perturbed, skip)
        if hit is None:
            measured.append(np.full(k, math.nan))
            continue
        change = (hit[0] - base[0]) / value
        measured.append(np.linalg.solve(projected, ell.T @ change))
        # the perturbed map's guiding point x0 + p z: P_p(x0 + p z) = x0 + p z + p (drift along the family)
        guides.append(np.linalg.lstsq(D - np.eye(n), tangents @ measured[-1] - change, rcond=None)[0])
    (v1, v2), (d1, d2) = values, measured
    out["measured"] = np.column_stack([d1, d2])
    out["drift"] = (v2 * d1 - v1 * d2) / (v2 - v1)  # linear in p: the value at p = 0
    if transverse and others.size and len(guides) == 2:
        out["transverse_drift"], out["transverse_check"] = _transverse_drift(shooter, x0, guides, pars, index, values,
                                                                             skip, others)
    return out


def _transverse_multipliers(D: np.ndarray, k: int) -> np.ndarray | None:
    """The period map's multipliers other than its k eigenvalues 1 (the family's) and the flow's 0, ordered by
    abs(arg mu); None unless k lie within ONE_TOL of 1."""
    w = np.linalg.eigvals(D)
    order = np.argsort(np.abs(w - 1.0))
    if abs(w[order[k - 1]] - 1.0) > ONE_TOL:
        return None
    rest = w[order[k:]]
    others = np.delete(rest, np.argmin(np.abs(rest)))
    return others[np.argsort(np.abs(np.angle(others)), kind="stable")]


def _transverse_drift(shooter, x0, guides, pars, index, values, skip, unperturbed) -> tuple[np.ndarray, float]:
    """d ln abs(mu) / dp per revolution of the transverse multipliers ``unperturbed`` (p = 0), each matched to the
    nearest multiplier of the perturbed map at both ``values`` and extrapolated linearly to p = 0. The perturbed
    map is differentiated at its guiding point x0 + p z (``guides``: z), where a start stays next to the family:
    its multipliers there, not at x0, are those the drifting start sees (where the transverse block depends on the
    state, the two differ at first order in p)."""
    rates = []
    for value, guide in zip(values, guides):
        perturbed = pars.copy()
        perturbed[index] = value
        mapped = period_map(shooter, x0 + value * guide, perturbed, skip)
        moved = None if mapped is None else np.linalg.eigvals(mapped[1])
        if moved is None:
            return np.full(unperturbed.size, math.nan), math.inf
        nearest = moved[[int(np.argmin(np.abs(moved - mu))) for mu in unperturbed]]
        rates.append((np.log(np.abs(nearest)) - np.log(np.abs(unperturbed))) / value)
    (v1, v2), (r1, r2) = values, rates
    check = float(np.max(np.abs(r1 - r2)) / max(float(np.max(np.abs(r2))), 1e-300))
    return (v2 * r1 - v1 * r2) / (v2 - v1), check


def _drift_setup(system, shooting, pars_by_name, parameter, values, unperturbed):
    try:
        values = tuple(finite_real(v, "values") for v in values)
    except TypeError:
        raise ParameterError(f"values = {values!r}: give two different small nonzero values of {parameter}") from None
    if len(values) != 2 or 0.0 in values or values[0] == values[1]:
        raise ParameterError(f"values = {values!r}: give two different small nonzero values of {parameter}")
    base_system = system if unperturbed is None else unperturbed
    for candidate in (system, base_system):
        if sorted(candidate.parameter_names) != sorted(pars_by_name):
            raise ParameterError(f"{candidate.name!r} has other parameters than the family; give the system it was "
                                 "computed on")
    pars = system.with_pars([pars_by_name[n] for n in system.parameter_names])
    index = system.parameter_index(parameter)
    if pars[index] != 0.0:
        raise ParameterError(f"the family was computed at {parameter} = {pars[index]:g}; compute it at 0")
    return (Shooter(system, shooting), Shooter(base_system, shooting)), pars, index, values


def drift_at(system: System, shooting: Shooting, amplitude: float, free_guess, pars, parameter: str,
             values: tuple = (1e-5, 2e-5), unperturbed: System | None = None, along: tuple = (),
             transverse: bool = False) -> dict:
    """The drift (per revolution per unit ``parameter``, extrapolated to 0) of the member of the family with
    ``amplitude`` (free coordinate solved from ``free_guess``) at ``pars`` (``parameter`` 0): {"drift",
    "period", "check", "valid", "reason", "free", "probes"} (check: the two values' relative difference; probes:
    the drifts measured at the two values, each the amplitude's and then the along labels'; valid: an
    eigenvalue 1 for each label, no resonance, finite; reason: why not, '' if valid; free: the solved free
    coordinate). ``valid`` leaves ``check`` to the caller: relative to the drift itself it grows without bound
    at a zero of the drift, where the drift is still right (:func:`family_drift` judges it against the family's
    median drift). The member must close after its period and after no fraction of it
    (else a one-line error). A zero of the drift between two members is a cycle located exactly (see
    :func:`family_drift` for the rest).

    ``along``: names of ``fixed`` start coordinates that label the family too (a family of families, e.g. a
    conserved quantity's value or a state every member starts with): their drift per revolution comes as
    ``along_drift`` {name: value}, from the period map's left null space of the dimension 1 + len(along); the
    check then compares the two measured drift vectors, each component in units of its state scale.
    ``transverse``: also ``transverse_drift``, d ln abs(mu) / d(parameter) per revolution of each transverse
    multiplier mu (ordered by abs(arg mu); a pair's two are equal): per unit time, the growth rate per unit
    parameter of the oscillation about the orbit (its Floquet exponent's real part); ``transverse_check``, the
    two values' relative difference."""
    if not isinstance(system, System) or not isinstance(shooting, Shooting) or not (
            unperturbed is None or isinstance(unperturbed, System)):
        raise ParameterError("give a dynamics.System, a Shooting and (optionally) the unperturbed System")
    try:
        vector = system.with_pars(None, **pars) if isinstance(pars, dict) else system.with_pars(pars)
    except (TypeError, ValueError):
        raise ParameterError(f"pars: give the values of {', '.join(system.parameter_names)}") from None
    along = () if along is None else along
    if (isinstance(along, str) or not isinstance(along, tuple | list) or not all(isinstance(n, str) for n in along)
            or any(name not in shooting.fixed for name in along) or len(set(along)) != len(along)):
        raise ParameterError(f"along = {along!r}: give a tuple of names of the Shooting's fixed start values "
                             f"({', '.join(shooting.fixed)}), each once")
    if not isinstance(transverse, bool):
        raise ParameterError(f"transverse = {transverse!r}: give True or False")
    pars = dict(zip(system.parameter_names, map(float, vector)))
    shooters, pars, index, values = _drift_setup(system, shooting, pars, parameter, values, unperturbed)
    base = shooters[1]
    amplitude = finite_real(amplitude, "amplitude")
    free = None if shooting.free is None else base.solve_free(amplitude, finite_real(free_guess, "free_guess"), pars)
    if free is not None and not math.isfinite(free):
        raise ParameterError(f"no member of the family at {shooting.vary} = {amplitude:.6g}")
    hit = base.run(base.start(amplitude, free), pars)
    if hit is None:
        raise ParameterError(f"the member at {shooting.vary} = {amplitude:.6g} does not reach the section")
    period = shooting.period_factor * hit[1]
    error = base.least_period_error(base.start(amplitude, free), period, pars)
    if error:
        raise ParameterError(f"the member at {shooting.vary} = {amplitude:.6g} {error}")
    found = _orbit_drift(shooters, hit[0], period, amplitude, free, pars, index, values, tuple(along), transverse)
    scale = np.array([system.state_scale[system.state_index(name)] for name in (shooting.vary, *along)])
    d1, d2 = (found["measured"][:, j] / scale for j in (0, 1))
    check = float(np.linalg.norm(d1 - d2) / max(np.linalg.norm(d2), 1e-300))
    drift = found["drift"]
    reason = _invalid_reason(found, len(along))
    out = {"drift": float(drift[0]), "period": period, "check": check, "valid": not reason, "reason": reason,
           "free": free, "probes": found["measured"].T.tolist()}
    if along:
        out["along_drift"] = dict(zip(along, map(float, drift[1:])))
    if transverse:
        out["transverse_drift"] = [float(v) for v in found["transverse_drift"]]
        out["transverse_check"] = found["transverse_check"] if found["transverse_drift"].size else 0.0
    return out


def _invalid_reason(found: dict, extra: int) -> str:
    """Why an orbit's drift is not valid ('' if it is)."""
    if not found["one"]:
        return f"the period map has fewer than {1 + extra} eigenvalues within {ONE_TOL:g} of 1 (a fold, a resonance)"
    if not np.all(np.isfinite(found["drift"])):
        return "a perturbed run failed, or the family's tangents are not independent"
    if found["gap"] <= RESONANCE_GAP:
        return (f"another multiplier lies within {found['gap']:.2g} of 1: a resonance, or a label of the family "
                "not named in along")
    return ""


def family_drift(system: System, family: xr.Dataset, shooting: Shooting, parameter: str,
                 values: tuple = (1e-5, 2e-5), unperturbed: System | None = None) -> xr.Dataset:
    """The Melnikov drift of every orbit of ``family`` (from :func:`symmetric_family` with the same ``shooting``,
    at the parameters stored in it, where ``parameter`` is 0) measured at the small ``values`` and extrapolated
    to 0: ``drift`` [amplitude units per revolution per unit parameter], ``drift_rate`` (the same per unit
    time), ``drift_check`` (difference of the two measured values, relative to the larger of the drift and the
    family's median drift), ``resonance_gap`` (distance of the period map's nearest other eigenvalue from 1),
    ``branch_point`` (1 where another multiplier passes 1 between the orbit and the next: the family branches)
    and ``drift_valid`` (1 where the period map has an eigenvalue within ONE_TOL of 1, the gap exceeds
    RESONANCE_GAP, the two values agree to DRIFT_AGREEMENT, and the orbit is at no fold and next to no branch
    point). The family's end members are not evaluated. Status: the family's own when it ended short (e.g.
    ``max_points``), else ``completed`` (or ``degenerate``: no orbit passed the checks).
    ``unperturbed``: the same system written with ``parameter`` = 0 in its expressions, where the family was
    computed on it (heyoka's Taylor coefficients of 0 * g overflow where g is singular, and 0 * inf is no 0);
    it runs the period map at 0, ``system`` at the small values."""
    if not isinstance(family, xr.Dataset) or family.attrs.get("kind") != "symmetric_family" or "period" not in family:
        raise ParameterError("family: give a dataset of dynamics.symmetric_family")
    try:
        config = json.loads(family.attrs["config"])
        stored_pars = config["pars"]
    except (KeyError, TypeError, ValueError):
        raise ParameterError("the family has no readable config; compute it again with symmetric_family") from None
    if any(config.get(key) != value for key, value in shooting.config().items()):
        raise ParameterError("the family was shot with another Shooting; give the one it was computed with")
    if family.attrs.get("system") not in (system.name, getattr(unperturbed, "name", None)):
        raise ParameterError(f"the family was computed on {family.attrs.get('system')!r}; give that system")
    shooters, pars, index, values = _drift_setup(system, shooting, stored_pars, parameter, values, unperturbed)
    crossings, periods, amplitude = family.crossing.values, family.period.values, family.amplitude.values
    free = family.start.sel(state=shooting.free).values if shooting.free else [None] * len(amplitude)
    size = len(amplitude)
    if size < 3:
        raise ParameterError(f"the family has {size} orbits; the drift needs neighbours on both sides (at least 3)")
    drift, measured = np.full(size, np.nan), np.full((size, 2), np.nan)
    gap, transverse, no_one = np.zeros(size), np.zeros(size), np.zeros(size, bool)
    for k in range(1, size - 1):
        found = _orbit_drift(shooters, crossings[k], periods[k], amplitude[k], free[k], pars, index, values)
        drift[k], measured[k], gap[k], transverse[k] = found["drift"][0], found["measured"][0], found["gap"], found[
            "transverse"]
        no_one[k] = not found["one"]
    finite = np.isfinite(drift) & np.all(np.isfinite(measured), axis=1)
    typical = float(np.median(np.abs(drift[finite]))) if finite.any() else 0.0
    check = np.where(finite, np.abs(measured[:, 0] - measured[:, 1])
                     / np.maximum(np.abs(drift), max(typical, 1e-300)), 0.0)
    branch = np.zeros(size, np.int8)
    crossed = transverse[1:-2] * transverse[2:-1] < 0  # another multiplier passes 1 between k and k + 1
    branch[1:-2] |= crossed
    branch[2:-1] |= crossed
    fold = family.fold.values
    near_fold = np.array([fold[max(k - 1, 0): k + 2].any() for k in range(size)])
    valid = (finite & (check <= DRIFT_AGREEMENT) & (gap > RESONANCE_GAP) & ~near_fold & (branch == 0)).astype(np.int8)
    drift[~finite] = 0.0
    units = _units_product(system.units_of(shooting.vary), system.units_of(parameter), -1)
    out = family.copy()
    out["drift"] = ("orbit", drift, {"units": units, "long_name": f"change of the amplitude per revolution per unit "
                                     f"{parameter} (Melnikov), extrapolated to {parameter} = 0"})
    out["drift_rate"] = ("orbit", drift / periods, {"units": _units_product(units, system.time_units, -1),
                                                    "long_name": f"drift per unit time per unit {parameter}"})
    out["drift_check"] = ("orbit", check, {"units": "1", "long_name": f"difference of the drift measured at "
                                           f"{parameter} = {values[0]:g} and {values[1]:g}, relative"})
    out["resonance_gap"] = ("orbit", gap, {"units": "1", "long_name": "distance from 1 of the period map's nearest "
                                           "other eigenvalue"})
    out["branch_point"] = ("orbit", branch, flag_attrs("another multiplier passes 1 next to this orbit",
                                                       {"no": 0, "yes": 1}))
    out["drift_valid"] = ("orbit", valid, flag_attrs("whether the drift is defined and checked (0: an end "
                                                     "member, a fold, a branch point, a resonance or a failed "
                                                     "check)", {"no": 0, "yes": 1}))
    inner = slice(1, -1)
    reasons = {"no eigenvalue 1 of the period map": int(no_one.sum()),
               "not finite": int((~finite & ~no_one)[inner].sum()),
               "nonlinear in " + parameter: int((finite & (check > DRIFT_AGREEMENT))[inner].sum()),
               "resonance": int((finite & (gap <= RESONANCE_GAP))[inner].sum()),
               "next to a fold": int(near_fold[inner].sum()), "next to a branch point": int(branch[inner].sum())}
    failed = ", ".join(f"{count} {why}" for why, count in reasons.items() if count)
    n_valid = int(valid.sum())
    message = f"drift of {n_valid} of {size - 2} inner orbits checked" + (f" (not: {failed})" if failed else "")
    status = "completed" if n_valid else "degenerate"
    if family.attrs.get("status") != "completed":  # the family itself ended short: that stays its status
        status, message = family.attrs.get("status"), f"{family.attrs.get('message')}; {message}"
    cfg = {**config, "parameter": parameter, "values": list(values)}
    out.attrs = make_attrs("symmetric_family", cfg, status, message, system=family.attrs.get("system"))
    return out


def _units_product(units: str, other: str, power: int) -> str:
    """UDUNITS ``units`` times ``other`` to ``power`` (products of symbols with integer exponents: "rad",
    "m s-1"), exponents collected: ("rad", "m s-1", -1) -> "rad m-1 s"."""
    exponents: dict[str, int] = {}
    for text, sign in ((units, 1), (other, power)):
        for factor in text.split():
            if factor == "1":
                continue
            symbol = factor.rstrip("-0123456789")
            exponents[symbol] = exponents.get(symbol, 0) + sign * int(factor[len(symbol):] or 1)
    return " ".join(s if e == 1 else f"{s}{e}" for s, e in exponents.items() if e) or "1"
