"""The initial spin that reaches the inverted spin at omega_c with friction's work counted (docs/inversion_criterion.md).

(C5) balances the start's rolling energy against that of the inverted spin at omega_c,
E_spin(omega_c) = A omega_c^2 / 2 + m g (r + e), and leaves friction out. Its first-order correction counts
friction's work W on the way up, along the slow flow (:mod:`tippedisk_analysis.models.slow_flow`): from Table 3's
start with initial spin s [rad/s] the slow flow runs until its spin alpha_dot first falls to omega_c (a heyoka
event, at t*), and W(s) = E_tot(0) - E_tot(t*) [J]. The predicted spin solves

    E_0(s) - W(s) = E_spin(omega_c),                                                             (C7)

E_0(s) = T_1 s^2 + E_pot the start's energy (T_1: its kinetic energy at 1 rad/s; taken as the slow flow's E_tot,
which adds the slip's O(eps^2) kinetic energy; (C5) is (C7) with W = 0). So
the disk arrives at omega_c with the inverted spin's energy: (C7) predicts the spin that reaches the top
(z_S -> r + e), which the full model approaches as its threshold for r + 0.99 e. W is O(eps) power over a time
O(1/eps), so (C7) hardly depends on eps; the slow flow needs a small one (REDUCTION_EPS) to hold.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from scipy.optimize import brentq

from ..dynamics.poincare import crossings
from ..dynamics.symmetric_families import finite_real
from ..errors import ParameterError
from ..models import slow_flow
from ..parameters import Setup
from . import critical_spin as cs
from . import inversion
from .rolling import spin_state

__all__ = ["FrictionWork", "WorkPrediction", "friction_work", "spin_with_friction_work"]

STEP = 0.01  # relative: the search for a bracket of (C7) steps up from (C5) by this much of it
MAX_STEPS = 40  # up to 1.4 times (C5)


@dataclass(frozen=True)
class FrictionWork:
    """One slow-flow run from Table 3's start at initial spin ``spin`` [rad/s] until its spin first falls to
    ``omega_c`` [rad/s]: ``energy_start`` E_0 [J], ``work`` W [J] and ``time`` t* [s] (NaN unless ``status`` is
    completed; otherwise the run ended ``status`` (fell, lift_off, cone, horizon, nonfinite) first), ``height``
    (z_S - r) / e at t*."""

    spin: float
    omega_c: float
    energy_start: float
    work: float
    time: float
    height: float
    status: str


@dataclass(frozen=True)
class WorkPrediction:
    """(C7): the initial spin ``spin`` [rad/s] (NaN unless ``status`` is completed) that arrives at omega_c with
    E_spin [J], against (C5) ``spin_c5``; ``run`` the slow-flow run at it (its W and t*); ``status`` completed,
    no_critical_spin, slow_flow_ended (a run ended before its spin fell to omega_c: the slow flow does not hold
    there) or no_bracket (E_0 - W stays below E_spin up to 1.4 (C5)); ``message`` one line."""

    spin: float
    spin_c5: float
    omega_c: float
    energy_spin: float
    run: FrictionWork | None
    eps: float
    status: str
    message: str


def _checked(setup, gamma0, eps) -> tuple[Setup, float, float]:
    eps = finite_real(eps, "eps")
    if eps <= 0:
        raise ParameterError(f"eps = {eps:g} m/s: give the slow flow's smoothing eps > 0 (small: e.g. "
                             f"{inversion.REDUCTION_EPS})")
    _spin, setup, gamma0, _t = inversion.run_inputs(1.0, setup, gamma0, None)
    return inversion.with_eps(setup, eps), gamma0, eps


def friction_work(spin: float, omega_c: float, *, setup: Setup | None = None, gamma0: float | None = None,
                  eps: float = inversion.REDUCTION_EPS) -> FrictionWork:
    """W(s) of (C7): the slow flow (``setup``'s disk, friction smoothing ``eps`` [m/s]) from Table 3's start at
    initial spin ``spin`` [rad/s] until alpha_dot first falls through ``omega_c`` [rad/s] (horizon
    :func:`inversion.horizon`)."""
    setup, gamma0, eps = _checked(setup, gamma0, eps)
    spin, omega_c = finite_real(spin, "spin"), finite_real(omega_c, "omega_c")
    if not 0 < omega_c < spin:
        raise ParameterError(f"spin = {spin:g}, omega_c = {omega_c:g} rad/s: give 0 < omega_c < spin (the spin "
                             "must fall to omega_c)")
    system, pars = slow_flow.system(), inversion.parameters("slow", setup)
    start = inversion.start_state("slow", spin, setup, gamma0)
    run = crossings(system, start, "alpha_dot", omega_c, pars=pars, direction="negative",
                    t_end=inversion.horizon(eps), max_crossings=1, tol=inversion.TOL, events=True)
    e_start = float(system.observe(start, pars)["E_tot"])
    if not len(run.times):
        status = {"completed": "horizon"}.get(run.status, run.status)
        return FrictionWork(spin, omega_c, e_start, math.nan, math.nan, math.nan, status)
    at = system.observe(run.states[0], pars)
    return FrictionWork(spin, omega_c, e_start, e_start - float(at["E_tot"]), float(run.times[0]),
                        float((at["z_S"] - setup.disk.r) / setup.disk.e), "completed")


def spin_with_friction_work(setup: Setup | None = None, gamma0: float | None = None, *,
                            eps: float = inversion.REDUCTION_EPS, xtol: float = 1e-4) -> WorkPrediction:
    """Solve (C7) for the initial spin [rad/s] of Table 3's start (gamma0 [rad]; default Tables 1-3): step up from
    (C5) by STEP of it until E_0 - W exceeds E_spin(omega_c), then Brent's method to ``xtol`` [rad/s]."""
    setup, gamma0, eps = _checked(setup, gamma0, eps)
    if not (math.isfinite(xtol) and xtol > 0):
        raise ParameterError(f"xtol = {xtol!r}: give a positive tolerance in rad/s")
    found = cs.omega_critical(setup.disk, setup.gravity, setup.friction.mu)
    if found.status != "completed":
        return WorkPrediction(math.nan, math.nan, math.nan, math.nan, None, eps, "no_critical_spin", found.message)
    w_c = found.omega_critical
    e_spin = float(slow_flow.system().observe(spin_state("inverted", w_c), inversion.parameters("slow", setup))
                   ["E_tot"])
    c5 = cs.initial_spin_threshold(w_c, setup, gamma0)
    runs = {}

    def excess(spin):  # E_0 - W - E_spin [J]
        runs[spin] = friction_work(spin, w_c, setup=setup, gamma0=gamma0, eps=eps)
        if runs[spin].status != "completed":
            raise _Ended(spin)
        return runs[spin].energy_start - runs[spin].work - e_spin

    def result(spin, status, message):
        return WorkPrediction(spin, c5, w_c, e_spin, runs.get(spin), eps, status, message)

    try:
        low, high = c5, c5 * (1 + STEP)
        while excess(high) <= 0:
            low, high = high, high + STEP * c5
            if high > c5 * (1 + STEP * MAX_STEPS):
                return result(math.nan, "no_bracket", f"E_0 - W stays below E_spin(omega_c) up to {low:.6g} rad/s")
        spin = float(brentq(excess, low, high, xtol=xtol))
        excess(spin)
    except _Ended as ended:
        spin = ended.args[0]
        return result(math.nan, "slow_flow_ended", f"the slow flow from {spin:.6g} rad/s ended "
                      f"({runs[spin].status}) before its spin fell to omega_c = {w_c:.6g} rad/s: it does not hold for "
                      "this start; use the full model (inversion.spin_threshold)")
    work = runs[spin]
    return result(spin, "completed", f"{spin:.6g} rad/s ({100 * (spin / c5 - 1):+.2f} % of (C5) {c5:.6g}): friction "
                  f"does {1e3 * work.work:.4g} mJ of work before the spin first falls to omega_c = {w_c:.6g} rad/s "
                  f"(t* = {work.time:.4g} s at eps {eps:g} m/s)")


class _Ended(Exception):
    """A slow-flow run ended before its spin fell to omega_c (args: its initial spin)."""
