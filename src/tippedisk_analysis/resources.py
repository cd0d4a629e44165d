"""Memory and work estimates: refuse, before any work starts, a request that cannot fit.

The budget is ``MEMORY_FRACTION`` (defaults.py; the environment variable
``TIPPEDISK_MEMORY_FRACTION`` overrides it, e.g. 0.8 on a node of one's own) of the machine's
memory, or of the container's limit (cgroup ``memory.max``) if that is smaller. Estimates
are deliberately rough (a factor of two either way) and err on the large side.
"""

from __future__ import annotations

import functools
import math
import os
from pathlib import Path

from . import defaults
from .errors import ParameterError, ResourceError

GB = 1e9
WORKER_BYTES = 0.4e9
"""Memory of one dask worker process with a compiled heyoka integrator (measured ~0.3 GB)."""


@functools.lru_cache(maxsize=1)
def machine_memory() -> float:
    """Bytes of physical memory (or the cgroup limit, if lower); read once per process."""
    try:
        total = float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):  # pragma: no cover - not POSIX
        total = 8 * GB
    for limit_file in ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"):
        try:
            text = Path(limit_file).read_text().strip()
        except OSError:
            continue
        if text.isdigit() and 0 < int(text) < total:
            total = float(text)
    return total


def memory_fraction() -> float:
    text = os.environ.get("TIPPEDISK_MEMORY_FRACTION")
    if text is None:
        return defaults.MEMORY_FRACTION
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not 0 < value <= 1:
        raise ParameterError(f"TIPPEDISK_MEMORY_FRACTION = {text!r} must be a number in (0, 1]; e.g. 0.5")
    return value


def human(nbytes: float) -> str:
    """12.3 GB, 450 MB, 3.1 TB."""
    for unit, size in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6)):
        if nbytes >= size:
            value = nbytes / size
            return f"{value:,.0f} {unit}" if value >= 1000 else f"{value:.3g} {unit}"
    return f"{nbytes / 1e3:.3g} kB"


def human_time(seconds: float) -> str:
    """45 s, 12 min, 3.5 h, 20 days."""
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    if seconds < 2 * 86400:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:.3g} days"


def check_memory(needed: float, what: str, fix: str, cli_fix: str | None = None) -> None:
    """ResourceError if ``needed`` bytes exceed the budget: one line with the estimate, the machine's
    memory and ``fix`` (``cli_fix`` in the command line's wording, if different)."""
    total = machine_memory()
    fraction = memory_fraction()
    if not (needed <= fraction * total):  # also refuses NaN and inf
        head = (f"{what} needs about {human(needed)} of memory (estimate), more than {fraction:.0%} of this "
                f"machine's {human(total)}")
        raise ResourceError(f"{head}; {fix}", cli=f"{head}; {cli_fix or fix}")
