"""Moved to :mod:`tippedisk_analysis.dynamics.sweeps`; this old import path keeps working for now."""

from ..dynamics.sweeps import *  # noqa: F401,F403
from ..dynamics.sweeps import (MERGE_FACTOR, Grid, Sweep, check_resources, check_run_settings,  # noqa: F401
                               chunk_bounds, chunk_dir, discard_other_configuration, estimate, parse_scheduler,
                               run_sweep, stored_chunks)
