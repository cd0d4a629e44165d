"""Moved to :mod:`tippedisk_analysis.dynamics.continuation` (and branch switching to
:mod:`tippedisk_analysis.dynamics.switching`); this old import path keeps working for now."""

from ..dynamics.continuation import *  # noqa: F401,F403
from ..dynamics.continuation import (LABELS, REJECTED, Branch, Options, Point, Problem, SpecialPoint,  # noqa: F401
                                     _eigenvalues, _tangent, hopf_test, label_points, nearest_pair, nearest_real,
                                     zero_test,
                                     continue_both_ways, continue_branch, correct, solve_at)
from ..dynamics.switching import Switch, branch_directions, switch_branch  # noqa: F401
