"""The notice of a slow first compile (tippedisk_analysis.compilation)."""

import time
import warnings

from tippedisk_analysis import compilation
from tippedisk_analysis.compilation import CompileNotice, compiling


def test_a_compile_that_takes_long_is_announced_once(monkeypatch):
    """A CompileNotice is a TippediskWarning: the command line prints it as one 'note:' line."""
    monkeypatch.setattr(compilation, "NOTICE_AFTER", 0.0)  # every compile counts as slow
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        with compiling("the test integrator"):
            deadline = time.monotonic() + 600  # a safety net only: the block ends when the notice has come
            while not seen and time.monotonic() < deadline:
                time.sleep(0.01)
    assert len(seen) == 1 and issubclass(seen[0].category, CompileNotice)
    assert str(seen[0].message).startswith("compiling the test integrator (first use on this machine")


def test_a_quick_compile_says_nothing():
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        with compiling("a cached integrator"):
            pass
    assert not seen

