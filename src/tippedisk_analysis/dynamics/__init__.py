"""A generic dynamics layer: declare a system once (:class:`System`), run every analysis on it.

Knows nothing of the disk (it imports nothing of models, solvers, parameters, kinematics or the tippedisk
analyses; tests/test_layering.py enforces it). The tippedisk's analyses (:mod:`tippedisk_analysis.analysis`)
are built on top of it. The names below are imported on first use.
"""

from __future__ import annotations

import importlib

_PUBLIC = {
    # declaration and the textbook catalogue
    "System": "system", "Event": "system", "Field": "tensors", "textbook_system": "systems", "TEXTBOOK": "systems",
    "Textbook": "systems",
    # continuation and equilibria
    "Options": "continuation", "Branch": "continuation", "continue_branch": "continuation",
    "continue_both_ways": "continuation", "switch_branch": "switching", "EquilibriumProblem": "equilibria",
    "Parameter": "equilibria", "equilibrium_branch": "branches", "special_point_curve": "branches",
    "point_of": "datasets", "special_point": "datasets",
    # periodic orbits
    "Flow": "flows", "FlowError": "flows", "STABILITY": "flows", "classify": "flows", "STATUS": "orbits",
    "find_orbit": "orbits", "orbit_from_hopf": "orbits", "simulation_guess": "orbits",
    "integral_levels": "orbits", "monodromy_fd": "orbits", "ShootingProblem": "shooting",
    "PeriodicOrbit": "orbit_base", "orbit_problem": "orbit_branches", "continue_orbits": "orbit_branches",
    "hopf_start": "orbit_branches", "hopf_branch": "orbit_branches", "orbit_branch": "orbit_branches",
    "switch_period_doubling": "orbit_branches", "homoclinic_limit": "orbit_branches",
    "manifold_return": "homoclinic", "manifold_branch": "homoclinic", "homoclinic_point": "homoclinic",
    "homoclinic_scan": "homoclinic", "homoclinic_curve": "homoclinic",
    "Shooting": "symmetric_families", "symmetric_family": "symmetric_families", "family_drift": "melnikov",
    "drift_at": "melnikov",
    "branch_dataset": "orbit_datasets", "orbits_dataset": "orbit_datasets", "orbit_from_dataset": "orbit_datasets",
    # Lyapunov exponents, Poincaré sections, attractors, sweeps
    "lyapunov_spectrum": "lyapunov", "poincare_section": "poincare", "basins": "attractors.system_basins",
    "Grid": "attractors.records", "Sweep": "sweeps", "run_sweep": "sweeps",
    # hybrid (event-driven) and Filippov systems
    "HybridSystem": "hybrid", "Guard": "hybrid", "Jump": "hybrid", "simulate_hybrid": "hybrid",
    "Leg": "hybrid_orbits", "find_hybrid_orbit": "hybrid_orbits", "legs_from_run": "hybrid_orbits",
    "filippov_system": "filippov",
    "fit": "fitting", "FitProblem": "fitting", "compare_fits": "fit_dataset",  # parameter estimation
}

__all__ = sorted(_PUBLIC)


def __getattr__(name: str):
    if name in _PUBLIC:
        value = getattr(importlib.import_module(f".{_PUBLIC[name]}", __name__), name)
        globals()[name] = value
        return value
    try:
        return importlib.import_module(f".{name}", __name__)
    except ModuleNotFoundError as exc:
        if exc.name != f"{__name__}.{name}":
            raise
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
