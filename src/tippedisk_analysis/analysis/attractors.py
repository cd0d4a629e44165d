"""Moved to :mod:`tippedisk_analysis.dynamics.attractors`; this old import path keeps working for now."""

from ..dynamics.attractors import *  # noqa: F401,F403
from ..dynamics.attractors import _circular_mean  # noqa: F401
