"""heyoka compilation as users meet it: a one-line notice when a first compile is slow.

heyoka JIT-compiles every integrator and compiled function. It keeps the machine code in memory and
in its disk cache (``~/.cache/heyoka``, on by default since heyoka 7.10), so only the first use on a
machine pays the compile: seconds for an ODE model, up to about a minute for third-order derivative
tensors. :func:`compiling` wraps such a compile and says what is being compiled once it has taken
longer than :data:`NOTICE_AFTER`, so a cold start never looks like a hang; a cache hit says nothing.
"""

from __future__ import annotations

import contextlib
import threading
import warnings

from .errors import TippediskWarning

NOTICE_AFTER = 2.0
"""[s] a compile still running after this long is announced (loading from the disk cache takes < 1 s)."""


class CompileNotice(TippediskWarning):
    """A compilation is taking long: the first use of this code on this machine (heyoka caches it)."""


@contextlib.contextmanager
def compiling(what: str):
    """Announce (a :class:`CompileNotice` warning, one line on the command line) that ``what`` is being
    compiled if the block takes longer than NOTICE_AFTER seconds."""

    def notice():
        warnings.warn(f"compiling {what} (first use on this machine; heyoka caches it on disk, later runs "
                      "start at once)", CompileNotice, stacklevel=1)

    timer = threading.Timer(NOTICE_AFTER, notice)
    timer.daemon = True
    timer.start()
    try:
        yield
    finally:
        timer.cancel()
