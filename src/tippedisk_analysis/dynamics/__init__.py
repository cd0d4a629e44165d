"""A generic dynamics layer: declare a system once (:class:`System`), run every analysis on it.

Knows nothing of the disk (it imports nothing of models, solvers, parameters, kinematics or the tippedisk
analyses; tests/test_layering.py enforces it). The tippedisk's analyses (:mod:`tippedisk_analysis.analysis`)
are built on top of it.
"""

from .branches import equilibrium_branch, special_point_curve
from .continuation import Options
from .datasets import point_of, special_point
from .system import Event, System

__all__ = ["Event", "Options", "System", "equilibrium_branch", "point_of", "special_point", "special_point_curve"]
