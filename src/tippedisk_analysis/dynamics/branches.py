"""Branches of equilibria of a :class:`.system.System` and curves of their special points, as datasets.

    import heyoka as hy
    from tippedisk_analysis import dynamics as dy
    u1, u2 = hy.make_vars("u1", "u2"); D, B, beta = hy.par[0], hy.par[1], hy.par[2]
    ab = dy.System("ab", [u1, u2], [-u1 + D*(1-u1)*hy.exp(u2), -u2 + D*B*(1-u1)*hy.exp(u2) - beta*u2],
                   parameters={"D": 0.0, "B": 14.0, "beta": 2.0})
    eq = dy.equilibrium_branch(ab, [0.0, 0.0], "D", bounds=(0.0, 0.2))        # folds LP1, LP2, Hopf HOPF1
    hc = dy.special_point_curve(ab, eq, "HOPF1", ("D", "beta"), bounds={"beta": (1.0, 3.0)})

Both return datasets of kind ``continuation`` (:mod:`.datasets`). Special points are located by the
continuation core (:mod:`.continuation`): folds, branch points, Hopf points (a neutral saddle, where two
real eigenvalues s, -s sum to zero, is not one), and on curves the codimension-two points.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from ..errors import ParameterError
from .continuation import Options, continue_both_ways, continue_branch
from .datasets import continuation_dataset, point_of, special_point
from .equilibria import EquilibriumProblem, Parameter
from .system import System


def _options(options: Options | None, overrides: dict) -> Options:
    if options is not None and overrides:
        raise ParameterError("give either options=Options(...) or the option keywords (ds, ds_max, ...), not both")
    return options or Options(**overrides)


def bounds_pair(bounds, name: str) -> tuple[float, float]:
    try:
        if isinstance(bounds, str | bytes):
            raise TypeError
        low, high = (float(b) for b in bounds)
    except (TypeError, ValueError):
        raise ParameterError(f"bounds of {name} = {bounds!r}: give a pair (low, high), e.g. (0.0, 0.2)") from None
    if not (math.isfinite(low) and math.isfinite(high) and low < high):
        raise ParameterError(f"bounds of {name} = ({low:g}, {high:g}): give finite low < high")
    return low, high


def equilibrium_branch(system: System, state, parameter: str, *, bounds, pars=None, direction: int = 1,
                       scale: float = 1.0, marks=(), options: Options | None = None,
                       **option_keywords) -> xr.Dataset:
    """The branch of equilibria through ``state`` (corrected first) at ``pars`` (default: the system's
    values), continued in ``parameter`` within ``bounds`` = (low, high), starting towards increasing
    (``direction`` = 1) or decreasing (-1) values, or both ways (0: one branch ordered from one end to the
    other). A start strictly inside ``bounds`` continued one way covers one side only: the dataset's message
    says so and names ``direction=0``. ``scale``: the parameter's typical size (arclength metric);
    ``marks``: parameter values where the branch's points are computed exactly (user points UZ1, ...).
    Options: :class:`.continuation.Options` or its fields as keywords (ds, ds_max, max_points, ...)."""
    pars = system.with_pars(pars)
    index = system.parameter_index(parameter)
    low, high = bounds_pair(bounds, parameter)
    if not low <= pars[index] <= high:
        raise ParameterError(f"the start {parameter} = {pars[index]:g} lies outside the bounds [{low:g}, {high:g}]")
    state = np.asarray(state, dtype=float)
    if state.shape != (system.n,):
        raise ParameterError(f"the state needs {system.n} values ({', '.join(system.state_names)})")
    if direction not in (-1, 0, 1):
        raise ParameterError(f"direction = {direction!r}: give 1 (increasing {parameter}), -1 (decreasing) or 0 (both)")
    prob = EquilibriumProblem(system, [Parameter.of(system, parameter, scale)], pars=pars, bounds={0: (low, high)})
    u0, opts = np.append(state, pars[index]), _options(options, option_keywords)
    if direction == 0:
        br = continue_both_ways(prob, u0, opts, marks=marks)
    else:
        br = continue_branch(prob, u0, opts, direction=direction, marks=marks)
        if low < pars[index] < high:
            br.message += (f"; one side of the start {parameter} = {pars[index]:g} only (direction=0 continues both "
                           "ways)")
    return continuation_dataset(br, prob, {"start": list(map(float, state)), "parameter": parameter})


def special_point_curve(system: System, branch: xr.Dataset, label: str, parameters, *, bounds: dict | None = None,
                        scales: dict | None = None, options: Options | None = None,
                        **option_keywords) -> xr.Dataset:
    """The curve through special point ``label`` (a Hopf point, or a fold or branch point: a zero eigenvalue) of
    ``branch`` (a dataset of :func:`equilibrium_branch` for ``system``) in two ``parameters``, in both
    directions, with its codimension-two points (Bogdanov-Takens, zero-Hopf, double Hopf, Bautin, cusp).
    ``bounds`` {name: (low, high)} boxes the curve; ``scales`` {name: typical size}. Of a ``periodic_orbits``
    dataset (collocation orbits) the curve through its fold of cycles, period doubling or Neimark-Sacker point
    ``label`` (LP1, PD1, NS1, ...): a dataset of kind ``cycle_curve`` (:func:`.cycle_curves.cycle_curve`; option
    keywords as there: ntst, ncol)."""
    if branch.attrs.get("kind") == "periodic_orbits":  # imported here: cycle_curves builds on the orbit modules
        from .cycle_curves import cycle_curve
        return cycle_curve(system, branch, label, parameters, bounds=bounds or {}, scales=scales,
                                options=options, **option_keywords)
    index, kind = special_point(branch, label)
    if kind not in ("hopf", "fold", "branch_point"):
        raise ParameterError(f"{label} is a {kind} point; curves start at a Hopf point or a zero eigenvalue")
    parameters = list(parameters)
    if len(parameters) != 2 or len(set(parameters)) != 2:
        raise ParameterError(f"give two different parameters for a curve, not {parameters}")
    state, pars = point_of(branch, system, index)
    bounds = dict(bounds or {})
    for name in bounds:
        if name not in parameters:
            raise ParameterError(f"bound on {name!r}, which is not one of the curve's parameters {parameters}")
    box = {parameters.index(name): bounds_pair(b, name) for name, b in bounds.items()}
    free = [Parameter.of(system, name, (scales or {}).get(name, 1.0)) for name in parameters]
    prob = EquilibriumProblem(system, free, pars=pars, bounds=box, critical="hopf" if kind == "hopf" else "zero")
    u0 = np.append(state, [pars[system.parameter_index(name)] for name in parameters])
    br = continue_both_ways(prob, u0, _options(options, option_keywords or {"ds": 0.02, "ds_max": 0.05}))
    return continuation_dataset(br, prob, {"source_label": label, "parameters": parameters})
