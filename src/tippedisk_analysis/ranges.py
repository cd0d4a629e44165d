"""Parameter ranges written ``START:STOP:N``: N evenly spaced values, both ends included."""

from __future__ import annotations

import math

import numpy as np

from .errors import ParameterError


def parse_range(text: str, name: str | None = None) -> tuple[float, float, int]:
    """``START:STOP:N`` -> (start, stop, n); one number ``X`` -> (X, X, 1).

    Raises ParameterError naming the option ``--name`` (if given) and the fix.
    """
    option = f"--{name}" if name else "--OPTION"
    example = f"e.g. {option} 10:80:64 (write {option}=-1:1:3 for a negative START)"
    label = f"--{name} {text!r}" if name else f"range {text!r}"
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
    if not (math.isfinite(start) and math.isfinite(stop)):
        raise ParameterError(f"{label} has a non-finite end; give finite START and STOP")
    if n < 1:
        raise ParameterError(f"{label} has N = {n}; give N >= 1")
    if n == 1 and start != stop:
        raise ParameterError(f"{label} has N = 1 but START != STOP; give one number for one value")
    if n > 1 and start == stop:
        raise ParameterError(f"{label} repeats one value {n} times; give START != STOP or N = 1")
    return start, stop, n


def range_values(text: str, name: str | None = None) -> np.ndarray:
    """The values of ``START:STOP:N`` (or of one number) as an array."""
    return np.linspace(*parse_range(text, name))
