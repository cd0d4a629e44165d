"""tippedisk_analysis: models, simulations and nonlinear-dynamics analysis of the tippedisk.

Sailer, Eugster, Leine, "The Tippedisk: a Tippetop Without Rotational Symmetry",
Regul. Chaotic Dyn. 25 (2020) 553-580.
"""

from .version import __version__
from .errors import DatasetError, IntegrationError, ParameterError, TippediskError, UnknownModelError
from .parameters import Disk, Friction, InitialState, Setup
from .results import load, save
from .solvers import model_names, simulate

__all__ = [
    "DatasetError", "Disk", "Friction", "InitialState", "IntegrationError", "ParameterError", "Setup",
    "TippediskError", "UnknownModelError", "__version__", "load", "model_names", "save", "simulate",
]
