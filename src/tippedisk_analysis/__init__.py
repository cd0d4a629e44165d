"""tippedisk_analysis: models, simulations and nonlinear-dynamics analysis of the tippedisk.

Sailer, Eugster, Leine, "The Tippedisk: a Tippetop Without Rotational Symmetry",
Regul. Chaotic Dyn. 25 (2020) 553-580.

The names below are imported on first use (PEP 562), so that ``import tippedisk_analysis`` and
``tippedisk --help`` do not pay for xarray, heyoka and numba until a command needs them.
"""

from __future__ import annotations

import importlib

from .errors import DatasetError, IntegrationError, ParameterError, TippediskError, UnknownModelError
from .version import __version__

_LAZY = {"Disk": "parameters", "Friction": "parameters", "InitialState": "parameters", "Setup": "parameters",
         "load": "results", "save": "results", "model_names": "solvers", "simulate": "solvers", "fit": "analysis.fit",
         "compare_fits": "analysis.fit"}

__all__ = [
    "DatasetError", "Disk", "Friction", "InitialState", "IntegrationError", "ParameterError", "Setup",
    "TippediskError", "UnknownModelError", "__version__", "compare_fits", "fit", "load", "model_names", "save",
    "simulate",
]


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    try:  # a submodule, e.g. td.results or td.errors
        return importlib.import_module(f".{name}", __name__)
    except ModuleNotFoundError as exc:
        if exc.name != f"{__name__}.{name}":
            raise
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
