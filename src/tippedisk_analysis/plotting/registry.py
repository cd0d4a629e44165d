"""The figure registry: each figure module registers one function per dataset kind with :func:`figure`."""

from __future__ import annotations

from collections.abc import Callable

from .style import styled

FIGURES: dict[str, Callable] = {}


def figure(kind: str):
    """Register the decorated ``function(ds) -> matplotlib Figure`` for datasets of ``kind``; it draws in the
    page's style (:func:`.style.styled`)."""

    def register(function: Callable) -> Callable:
        if kind in FIGURES:
            raise ValueError(f"figure for kind {kind!r} registered twice")
        FIGURES[kind] = styled(function)
        return FIGURES[kind]

    return register
