"""The discretisations of periodic orbits by name (as scipy's ``solve_ivp`` dispatches its methods): ``shooting``
(:mod:`.shooting`) and ``collocation`` (:mod:`.collocation`), and the one function that builds either from the
options a user gives.

Options that belong to one method only: ``segments``, ``phase`` and ``shift`` (shooting); ``ntst``, ``ncol``,
``mesh``, ``adapt``, ``error_tol`` and ``ntst_max`` (collocation). ``None`` means the method's default; an option
of the other method is an error that names the method it belongs to.
"""

from __future__ import annotations

from ..errors import ParameterError
from .collocation import CollocationProblem
from .orbit_base import OrbitProblem
from .shooting import ShootingProblem
from .system import System

METHODS = {"shooting": ShootingProblem, "collocation": CollocationProblem}
DEFAULT_METHOD = "collocation"
"""Branches of orbits and Hopf starts use collocation by default: on 'ab' (Hopf to period 50) it needs fewer
points at equal accuracy and is faster, and it follows stiff and canard cycles shooting cannot (docs/dynamics.md,
benchmarks/bench_periodic.py)."""
BRANCH_OPTIONS = {"shooting": {"ds": 0.02, "ds_max": 0.2, "max_points": 300},
                  "collocation": {"ds": 0.02, "ds_max": 0.5, "max_points": 300, "easy_iterations": 5}}
"""Step control of a branch from a Hopf point by method (scaled arclength; collocation measures an orbit by its
L2 norm over the period, shooting by its m segment points)."""
CONTINUE_OPTIONS = {"shooting": {"ds": 0.02, "ds_max": 0.1, "max_points": 200},
                    "collocation": {"ds": 0.02, "ds_max": 0.5, "max_points": 200, "easy_iterations": 5}}
"""Step control of a branch from an orbit (continue_orbits) by method."""
PERIOD_WEIGHT = 10.0  # collocation: the period's scale is 10 times the start period's (its weight in the norm 1/10)
OWN = {"shooting": ("segments", "phase", "shift"),
       "collocation": ("ntst", "ncol", "mesh", "adapt", "error_tol", "ntst_max", "phase")}
"""The options that belong to one method (phase: shooting's condition; collocation takes only "integral")."""
OPTIONS = frozenset(name for names in OWN.values() for name in names)


def check_method(method: str) -> str:
    if method not in METHODS:
        raise ParameterError(f"unknown method {method!r} for periodic orbits; choose one of {', '.join(METHODS)}")
    return method


def method_options(keywords: dict) -> tuple[dict, dict]:
    """(the discretisation's options, the rest) of keyword arguments."""
    return ({k: v for k, v in keywords.items() if k in OPTIONS},
            {k: v for k, v in keywords.items() if k not in OPTIONS})


def period_scale(method: str, period: float) -> float:
    """The period's scale in the arclength of ``method``: shooting, the start period; collocation, PERIOD_WEIGHT
    times it (the orbit's shape measures a step, as the period is left out of AUTO-07p's norm)."""
    return period * (PERIOD_WEIGHT if method == "collocation" else 1.0)


def make_problem(method: str, system: System, pars=None, *, default_segments: int = 1,
                 default_phase: str = "poincare", **options) -> OrbitProblem:
    """The problem of ``method`` for ``system``: ``options`` are the method's own (:data:`OWN`; None: its
    default) and the common ones (parameter, parameter_scale, period_scale, bounds, levels, pins, tol)."""
    check_method(method)
    own = {k: v for k, v in options.items() if k in OPTIONS and v is not None}
    common = {k: v for k, v in options.items() if k not in OPTIONS}
    for name in own:
        if name not in OWN[method] and not (name == "phase" and own[name] == "integral"):
            other = next(m for m, names in OWN.items() if name in names)
            raise ParameterError(f"{name} is an option of {other}, not of {method}; drop it or give "
                                 f"method={other!r}")
    if method == "shooting":
        return ShootingProblem(system, pars, segments=own.get("segments", default_segments),
                               phase=own.get("phase", default_phase), shift=own.get("shift"), **common)
    if own.get("phase", "integral") != "integral":
        raise ParameterError(f"collocation uses the integral phase condition, not {own['phase']!r}; drop phase")
    own.pop("phase", None)
    return CollocationProblem(system, pars, **own, **common)
