"""Every numerical default of the package, in one place, each with its reason.

Physical defaults (Tables 1-3, Sect. 6) live in the dataclasses of :mod:`.parameters`;
this module holds the numerical ones: tolerances, step sizes, fall angles, smoothing,
chunk sizes. Front ends (CLI help, studies) read them from here, so a default is stated once.
"""

from __future__ import annotations

# --- ODE models (heyoka Taylor integration), models/ode.py, solvers/taylor.py ---
TAYLOR_TOL = 1e-13
"""Taylor tolerance of single runs: order 16; over the 5-s Table 3 run gamma is within 7e-13 rad of a
machine-epsilon run (scipy's DOP853 at rtol = atol = 1e-12: 9e-12 rad) and the energy balance holds to 3e-15 J;
1e-14 costs 1.3x the time for 1.5e-14 rad (benchmarks/bench_ode.py). The contact needs no tolerance: it is
built into the coordinates (models/ode.py). Compiles in about 3 s, once per machine."""

MAP_TOL = 1e-10
"""Taylor tolerance of outcome maps: classifications are identical to 1e-14 on the benchmark map,
at about half the steps (tests/test_outcome_map.py compares batch and scalar runs)."""

BIFURCATION_TOL = 1e-12
"""Taylor tolerance of brute-force bifurcation diagrams (crossings after 5-10 s of transient)."""

SLIP_SMOOTHING = 1e-12
"""delta [m/s] of |gamma_T| = sqrt(|gamma_T|^2 + delta^2) - delta (models/ode.py): makes the
regularised law (2.29) analytic at zero slip; changes the force by mu lambda_N delta / eps."""

FALL_ANGLE = 0.1
"""Tilt above the table [rad] at which a run of an Euler-angle model ends with status ``fell``:
sin(beta) = 0 is the singularity of the Euler angles (3.1) and of the contact point C1. 0.1 rad
(5.7 deg) is well past the point of no return of every run seen (the disk is down)."""

FALL_ANGLE_QUATERNION_MOREAU = 0.0
"""Quaternion Moreau models have no singularity at a flat disk (three contacts close, Sect. 2.1):
by default they run through it (0 switches the fall check off)."""

# --- Moreau time stepping (Sect. 4), solvers/moreau ---
MOREAU_DT = 1e-5
"""Time step [s] of the paper's simulations (Sect. 6)."""

MOREAU_MAX_DT = 1e-3
"""Largest accepted time step [s]: the midpoint rule resolves the spin (40 rad/s) with < 0.04 rad per step."""

MOREAU_TOL = 1e-8
"""Stopping tolerance [N s] of the prox fixed-point iteration: summed impulse change per sweep."""

MOREAU_NORMALIZE_QUATERNION = True
"""Quaternion Moreau models (2, 4, 6, 8, 10) normalise p after each step: the paper, Sect. 3.2 after (3.67),
"the quaternion has to be normalized after each time step" (the midpoint half steps grow |p| by
dt^2 |Omega|^2 / 8 per step). Unnormalised, Model 6 differs from ODE Model 2 by 1.6e-2 rad in gamma on
[0, 1] s, normalised by 1.0e-3 rad, the paper's +-1e-3 rad (Sect. 6.5). ``normalize_quaternion=False``
keeps the unnormalised scheme for drift studies."""

MOREAU_MAX_ITER = 1000
"""Prox sweeps per step before the step counts as a convergence failure (reported, never silent)."""

MOREAU_GAINS = {"r_N": 0.1, "r_T": 0.1, "r_tau": 0.1, "r_R": 1e-4}
"""Prox gains r of (4.4)-(4.7). Each is capped per step at 1.5 / G_jj of the Delassus matrix
(solvers/moreau/step.py), so the sweep of a single column contracts where a force direction grows
large; the solution does not depend on r."""

CONTOUR_REGULARISATION = 1e-2
"""s_reg of the contour friction direction (3.64), 1/sin^2(beta) -> 1/(sin^2(beta) + s_reg^2)
(models/moreau_geometry.contour_direction): bounds the contour torque of a nearly flat disk
(tilt below ~0.6 deg, where the thin-disk rim contact has no physical meaning: the 10-mm-thick
disk lies on its face); changes (3.64) by (s_reg / sin(beta))^2 relative, 1e-4 for an upright disk."""

MOREAU_STORE_INTERVAL = 1e-3
"""Output sampling [s] of Moreau runs: 5000 samples for a 5-s run."""

MOREAU_CHUNK_STEPS = 20_000
"""Steps per call of the numba loop: progress and checkpoints happen between calls (~10 ms each)."""

CHECKPOINT_SECONDS = 10.0
"""Wall time [s] between checkpoints of a long Moreau run (at most this much work is lost)."""

# --- Stationary solutions, stability, maps (analysis/) ---
NEWTON_TOL = 1e-12
"""Relative step size at which Newton iterations for equilibria stop."""

NEWTON_MAX_ITER = 30
"""Newton steps before an equilibrium search reports ``max_iter``."""

EIG_ATOL = 1e-9
"""Absolute tolerance [1/s] on eigenvalue real parts for the stable / marginal / unstable classification."""

EIG_RTOL = 1e-9
"""Relative tolerance (times max |eigenvalue|) of the same classification."""

CRITICAL_RTOL = 1e-10
"""brentq relative tolerance on critical spin speeds Omega_c (1e-6 rad/s is required)."""

# --- Sweeps (outcome maps and other chunked grids), dynamics/sweeps.py ---
CHUNK_SIZE = 128
"""Grid points per stored chunk: ~1 s of work, so an interrupted sweep loses little."""

BATCH_SIZE = 4
"""heyoka SIMD lanes per batch integrator: 4 measured 1.2-1.5x faster per run than
``hy.recommended_simd_size()`` = 8 on the development machine (benchmarks/bench_outcome_map.py)."""

OUTCOME_WINDOW_FRACTION = 0.2
"""Classification window of outcome maps as a fraction of t_end."""

OUTCOME_THRESHOLD = 0.9
"""|mean sin(gamma)| over the window above which a run counts as (not) inverted."""

MEMORY_FRACTION = 0.5
"""Largest share of the machine's memory a single request may plan to allocate."""
