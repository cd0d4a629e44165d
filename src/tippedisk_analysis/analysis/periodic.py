"""Moved: periodic orbits of any system to :mod:`tippedisk_analysis.dynamics` (flows, shooting, orbits,
orbit_branches, orbit_datasets, systems), the tippedisk's to :mod:`.orbits`; this old import path keeps
working for now."""

from ..dynamics.flows import MULTIPLIER_TOL, STABILITY, TAYLOR_TOL, Flow, FlowError, classify, deflate, floquet  # noqa
from ..dynamics.orbit_branches import (continue_orbits, homoclinic_limit, hopf_start, orbit_branch,  # noqa: F401
                                       orbit_problem, switch_period_doubling)
from ..dynamics.orbit_datasets import SPECIAL_KINDS, branch_dataset, branch_orbits, orbits_dataset  # noqa: F401
from ..dynamics.orbits import (AMPLITUDE_TOL, NEWTON_MAX_ITER, NEWTON_TOL, STATUS, HopfGuess, find_orbit,  # noqa
                               hopf_guess, integral_levels, monodromy_fd, orbit_from_hopf, simulation_guess)
from ..dynamics.shooting import N_SAMPLES, PeriodicOrbit, ShootingProblem  # noqa: F401
from ..dynamics.system import System as OdeSystem  # noqa: F401
from ..dynamics.systems import TEXTBOOK, Textbook, textbook_system  # noqa: F401
from .orbits import (TIPPEDISK_SCALE, orbit_from_dataset, system_of, tippedisk_branch_dataset,  # noqa: F401
                     tippedisk_full_model_check, tippedisk_lyapunov_family, tippedisk_lyapunov_orbit,
                     tippedisk_orbits_from_hopf, tippedisk_orbits_from_run, tippedisk_returns, tippedisk_system)
from ..parameters import to_dict as _to_dict  # noqa: F401
