"""The figure registry: each figure module registers one function per dataset kind with :func:`figure`."""

from __future__ import annotations

from collections.abc import Callable

FIGURES: dict[str, Callable] = {}


def figure(kind: str):
    """Register the decorated ``function(ds) -> matplotlib Figure`` for datasets of ``kind``."""

    def register(function: Callable) -> Callable:
        if kind in FIGURES:
            raise ValueError(f"figure for kind {kind!r} registered twice")
        FIGURES[kind] = function
        return function

    return register
