"""A generic dynamics layer: declare a system once (:class:`System`), run every analysis on it.

Knows nothing of the disk (it imports nothing of models, solvers, parameters, kinematics or the tippedisk
analyses; tests/test_layering.py enforces it). The tippedisk's analyses (:mod:`tippedisk_analysis.analysis`)
are built on top of it.
"""

from .branches import equilibrium_branch, special_point_curve
from .continuation import Options
from .datasets import point_of, special_point
from .lyapunov import lyapunov_spectrum
from .orbit_branches import orbit_branch
from .orbit_datasets import orbit_from_dataset
from .orbits import find_orbit
from .system import Event, System
from .systems import textbook_system

__all__ = ["Event", "Options", "System", "equilibrium_branch", "find_orbit", "lyapunov_spectrum", "orbit_branch",
           "orbit_from_dataset", "point_of", "special_point", "special_point_curve", "textbook_system"]
