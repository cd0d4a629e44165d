"""Parameter ranges: ``START:STOP:N`` on the command line, ``(start, stop, n)`` in Python.

N evenly spaced values, both ends included. One rule for every command and function:
finite ends, an integer N >= 1, START < STOP for N > 1 (ranges run upwards: swap the ends
for a descending grid, the results do not depend on the order), START = STOP for N = 1.
"""

from __future__ import annotations

import math
import numbers
from typing import TYPE_CHECKING

from .errors import ParameterError

if TYPE_CHECKING:
    import numpy as np


def _rule(start: float, stop: float, n: int) -> str | None:
    """What is wrong with (start, stop, n), as '... ; give ...', or None."""
    if not (math.isfinite(start) and math.isfinite(stop)):
        return "has a non-finite end; give finite START and STOP"
    if n < 1:
        return f"has N = {n}; give N >= 1"
    if n == 1 and start != stop:
        return "has N = 1 but START != STOP; give one number for one value"
    if n > 1 and start == stop:
        return f"repeats one value {n} times; give START < STOP or N = 1"
    if start > stop:
        return "has STOP < START; give START < STOP (swap the ends: ranges run upwards)"
    return None


def parse_range(text: str, name: str | None = None) -> tuple[float, float, int]:
    """``START:STOP:N`` -> (start, stop, n); one number ``X`` -> (X, X, 1).

    Raises ParameterError naming the option ``--name`` (if given) and the fix.
    """
    option = f"--{name}" if name else "--OPTION"
    example = f"e.g. {option} 10:80:64 (write {option}=-1:1:3 for a negative START)"
    label = f"{option} {text!r}" if name else f"range {text!r}"
    parts = str(text).split(":")
    try:
        if len(parts) == 1:
            start = stop = float(parts[0])
            n = 1
        elif len(parts) == 3:
            start, stop, n = float(parts[0]), float(parts[1]), int(parts[2])
        else:
            raise ValueError
    except ValueError:
        raise ParameterError(f"{label} is not START:STOP:N with numbers and an integer N; "
                             f"give {example}") from None
    problem = _rule(start, stop, n)
    if problem:
        raise ParameterError(f"{label} {problem}")
    return start, stop, n


def check_range(value, name: str) -> tuple[float, float, int]:
    """A Python range ``(start, stop, n)`` (or one number) checked by the same rule; API wording."""
    label = f"{name} = {value!r}"
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        value = (value, value, 1)
    try:
        start, stop, n = value
        ok = all(isinstance(v, numbers.Real) and not isinstance(v, bool) for v in (start, stop, n))
        ok = ok and float(n) == int(n)
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ParameterError(f"{label} is not (start, stop, n) with numbers and an integer n; give e.g. "
                             f"{name}=(10, 80, 64)")
    start, stop, n = float(start), float(stop), int(n)
    problem = _rule(start, stop, n)
    if problem:
        raise ParameterError(f"{label} {problem.replace('START', 'start').replace('STOP', 'stop').replace('N ', 'n ')}")
    return start, stop, n


def check_axis(values, name: str) -> np.ndarray:
    """A 1-D grid of finite, strictly increasing values (the same rule for arrays)."""
    import numpy as np  # imported here: the command line parses ranges before it needs numpy

    try:
        arr = np.atleast_1d(np.asarray(values, dtype=float))
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a 1-D array of numbers; give e.g. numpy.linspace(10, 80, 64)") from None
    if arr.ndim != 1 or arr.size == 0 or not np.all(np.isfinite(arr)):
        raise ParameterError(f"{name} must be a non-empty 1-D array of finite numbers; give e.g. "
                             "numpy.linspace(10, 80, 64)")
    if arr.size > 1 and np.any(np.diff(arr) <= 0):
        raise ParameterError(f"{name} values must increase strictly; give start < stop (sort them)")
    return arr


def range_values(text: str, name: str | None = None) -> np.ndarray:
    """The values of ``START:STOP:N`` (or of one number) as an array."""
    import numpy as np

    return np.linspace(*parse_range(text, name))
