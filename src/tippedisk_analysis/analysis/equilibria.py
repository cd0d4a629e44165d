"""Moved to :mod:`tippedisk_analysis.dynamics.equilibria`; this old import path keeps working for now."""

from ..dynamics.equilibria import REAL_TOL, EquilibriumProblem, Parameter  # noqa: F401
