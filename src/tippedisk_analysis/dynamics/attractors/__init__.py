"""Attractors found by recurrences in a cell grid: a generic core that knows nothing of the disk.

Modules: :mod:`.records` (grid, settings, descriptions), :mod:`.problem` (the contract and the generic
description), :mod:`.mapping` (the state machine), :mod:`.tables` (merging, matching, columns), :mod:`.sets`
(attractors compared as sets), :mod:`.confirm` (assignments confirmed in the full state where the grid is a
projection), :mod:`.system_problem` (the problem of any
:class:`~tippedisk_analysis.dynamics.System`), :mod:`.system_basins` (its basins), :mod:`.conservative` (the volume test: conservative
flows have no attractors).

The method is the one of Datseris & Wagemakers (Chaos 32, 023104, 2022) used by Attractors.jl's
``AttractorsViaRecurrences``: integrate an initial condition, sample it every ``dt``, map each sample
(through an observation ``y = observe(x)``) to a cell of a grid, and run a small state machine on the
cells. No list of attractors is given beforehand; they are found on the fly, and once found they make
every later run that enters their cells stop early. Implemented here from the description of the
method (not from its code), on heyoka batch integrators (SIMD lanes) with lanes refilled as runs end.

State machine of one run (counts are consecutive samples; settings in :class:`RecurrenceSettings`):

1. *search*: a sample in a cell of a known attractor of the same parameter group counts towards
   ``consecutive_attractor_steps``; reached -> the run is assigned to that attractor (early stop), if its full
   state is near the attractor's (:mod:`.confirm`; checked where descriptions carry ``state_points``, i.e. the
   grid misses a state); if not, the run is doubted there: those samples count as ordinary ones.
   A sample in a cell this run visited before counts towards ``consecutive_recurrences``; reached ->
   *locate*. A new cell resets that count. Outside the grid for ``consecutive_lost_steps`` samples ->
   ``left_grid``.
2. *locate*: ``attractor_locate_steps`` more samples are recorded; their cells form the candidate.
   If most of them (``overlap``) already belong to one known attractor (and the last state is near it, as
   above) the run is assigned to it.
   Otherwise the problem describes the candidate (:meth:`Problem.describe`, by default
   :func:`describe`); a description makes it a new attractor whose cells join the table, ``None``
   rejects it (e.g. the amplitude grows) and the run returns to *search* with its visited cells
   forgotten. A description marked ``transient`` (a slowly evolving state that a problem can
   recognise, e.g. by a drifting energy) labels the run but keeps its cells out of the table, so it
   stops no other run. Both are additions to the published method: they keep slowly escaping or
   drifting transients from claiming cells that belong to an attractor's neighbourhood.
3. a terminal event of the integrator ends the run with the problem's label for it (e.g. ``fell``);
   a non-finite state with ``failed``, or with ``diverged`` if the problem's runs can escape
   (:attr:`Problem.escapes`) and it was outside the grid; the maximum horizon with ``undecided`` (the only
   way to get it), with the reason its last candidate was refused (:attr:`Problem.rejection_reasons`).

A candidate is a claim to verify, not a result: the problem of a :class:`~tippedisk_analysis.dynamics.System`
checks every kind by a criterion of its own (Newton and eigenvalues, shooting and multipliers, the largest
Lyapunov exponent: :meth:`.system_problem.SystemProblem.describe`), because a window of fixed length
mistakes the slow part of a relaxation cycle for an equilibrium.

Labels: attractors get ids 0, 1, ... (per call of :func:`map_points`); the others are negative:
:data:`SPECIAL_LABELS`, then the problem's terminal labels (-4, -5, ...), then ``diverged`` where it applies.

Kinds (:func:`describe`, from the recorded samples y_k, k = 1..L, in cell units): with a1, a2 the
largest peak-to-peak ranges over the first and the second half of the window,

* ``equilibrium``: a2 <= ``equilibrium_spread`` (cells) or a2 <= ``decay_ratio`` a1 (it converges);
  the representative state is the last sample, improved by :meth:`Problem.refine_equilibrium`;
* growing (a2 > ``growth_ratio`` a1): rejected;
* ``periodic``: the run returns to its last sample within ``return_distance`` cells; period and
  amplitude from a re-integration sampled ``refine_samples`` times per period (upward crossings of the
  first observed coordinate through its mean, located on the dense output to round-off);
* ``irregular``: otherwise.
Problems may add kinds (the tippedisk adds ``rolling``).

Parameter groups: runs with the same ``group`` number share their attractor cells (same parameters);
different groups never do. Attractors of different groups, chunks or parameter values are identified
afterwards by :func:`merge` (within one parameter point: the problem's ``same_attractor``, as sets where the
problem describes attractors by points, :attr:`Problem.set_points`; never by centre and kind alone) and
:func:`match` (across parameter values, "global continuation": nearest by the problem's distance,
within a threshold, each previous attractor used at most once; unmatched ones get new ids).
"""

from . import confirm, sets
from .mapping import MapResult, map_points
from .problem import (DescribeContext, Problem, circular_mean, combine, converging, describe,
                      equilibrium_description, growing, spreads)
from .records import BASE_KINDS, SPECIAL_LABELS, Candidate, Description, FirstTime, Found, Grid, RecurrenceSettings
from .tables import assemble_table, chunk_result, column_names, from_columns, match, merge, to_columns

__all__ = ["BASE_KINDS", "SPECIAL_LABELS", "Candidate", "DescribeContext", "Description", "FirstTime", "Found", "Grid",
           "MapResult", "Problem", "RecurrenceSettings", "assemble_table", "chunk_result", "circular_mean",
           "column_names", "combine",
           "converging", "describe", "equilibrium_description", "from_columns", "growing", "map_points", "match",
           "merge", "confirm", "sets", "spreads", "to_columns"]
