"""Moved to :mod:`tippedisk_analysis.dynamics.normal_forms`; this old import path keeps working for now."""

from ..dynamics.normal_forms import *  # noqa: F401,F403
from ..dynamics.normal_forms import (first_lyapunov_coefficient, fold_coefficient, line_hopf,  # noqa: F401
                                     line_transcritical)
