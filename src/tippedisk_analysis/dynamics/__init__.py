"""A generic dynamics layer: declare a system once (:class:`System`), run every analysis on it.

Knows nothing of the disk (it imports nothing of models, solvers, parameters, kinematics or the tippedisk
analyses; tests/test_layering.py enforces it). The tippedisk's analyses (:mod:`tippedisk_analysis.analysis`)
are built on top of it. The names below are imported on first use.
"""

from __future__ import annotations

import importlib

_PUBLIC = {
    "System": "system", "Event": "system", "Options": "continuation",
    "equilibrium_branch": "branches", "special_point_curve": "branches",
    "point_of": "datasets", "special_point": "datasets",
    "find_orbit": "orbits", "orbit_branch": "orbit_branches", "hopf_branch": "orbit_branches",
    "orbit_from_dataset": "orbit_datasets",
    "lyapunov_spectrum": "lyapunov", "poincare_section": "poincare", "textbook_system": "systems",
    "basins": "attractors.system_problem", "Grid": "attractors.records",
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
