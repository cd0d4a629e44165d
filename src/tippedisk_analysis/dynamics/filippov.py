"""Filippov systems: two smooth fields on either side of a switching surface h(x) = 0, and the sliding motion on
it, as a :class:`~.hybrid.HybridSystem`.

With sigma_- = grad h . f_- and sigma_+ = grad h . f_+ (the fields' rates across the surface), a trajectory
reaching h = 0 crosses where both point the same way (sigma_- sigma_+ > 0) and slides where both point into the
surface (sigma_- > 0 > sigma_+), along Filippov's convex combination

    f_s = (1 - a) f_- + a f_+,   a = sigma_- / (sigma_- - sigma_+),   so grad h . f_s = 0,

that is f_s = (sigma_+ f_- - sigma_- f_+) / (sigma_+ - sigma_-). The sliding motion leaves the surface where
sigma_- falls through 0 (into the side h < 0) or sigma_+ rises through 0 (into h > 0): there f_s equals the
field it leaves into, so the saltation matrix of the exit is the identity. The user declares the two sides only.
"""

from __future__ import annotations

import heyoka as hy

from ..errors import ParameterError
from .hybrid import Guard, HybridSystem, Jump
from .system import System

MODES = ("minus", "plus", "sliding")


def _rate(system: System, h) -> object:
    """grad h . f of ``system``."""
    return hy.sum([hy.diff(h, v) * f for v, f in zip(system.variables, system.declared_rhs)])


def filippov_system(name: str, minus: System, plus: System, surface, description: str = "") -> HybridSystem:
    """The Filippov system of ``minus`` (the field where ``surface`` < 0) and ``plus`` (where it is > 0): modes
    ``minus``, ``plus`` and ``sliding`` (module docstring), guards ``cross`` (h = 0 reached from either side),
    ``leave_minus``/``leave_plus`` (the sliding motion's exits)."""
    if tuple(map(str, minus.variables)) != tuple(map(str, plus.variables)):
        raise ParameterError(f"{name}: the two sides need the same state variables (got {minus.state_names} and "
                             f"{plus.state_names})")
    if minus.parameter_names != plus.parameter_names:
        raise ParameterError(f"{name}: the two sides need the same parameters, in the same order")
    s_minus, s_plus = _rate(minus, surface), _rate(plus, surface)
    sliding_rhs = [(s_plus * fm - s_minus * fp) / (s_plus - s_minus)
                   for fm, fp in zip(minus.declared_rhs, plus.declared_rhs)]
    observables = {**minus.observables, "sigma_minus": s_minus, "sigma_plus": s_plus}
    sliding = System(f"{name}.sliding", minus.variables, sliding_rhs, minus.parameters,
                     state_names=minus.state_names, state_scale=minus.state_scale, observables=observables,
                     n_trivial=minus.n_trivial, units=minus.units, time_units=minus.time_units,
                     description=f"Filippov's sliding motion on {surface} = 0", strict_parameters=False)
    guards = [
        Guard("cross", "minus", surface, (Jump("plus", when=s_plus), Jump("sliding")), direction="positive"),
        Guard("cross", "plus", surface, (Jump("minus", when=-s_minus), Jump("sliding")), direction="negative"),
        Guard("leave_minus", "sliding", s_minus, Jump("minus"), direction="negative"),
        Guard("leave_plus", "sliding", s_plus, Jump("plus"), direction="positive"),
    ]
    return HybridSystem(name, {"minus": minus, "plus": plus, "sliding": sliding}, guards,
                        description=description or f"Filippov system on {surface} = 0")
