"""One exception family. Every message names the problem and how to fix it.

A message is written for the Python API (``overwrite=True``, ``output=...``); where the
command line needs other words (``--overwrite``, ``--output``), the error carries them in
``cli`` and the ``tippedisk`` command prints :meth:`TippediskError.cli_message`.
"""


class TippediskError(Exception):
    """Base class of all errors raised by tippedisk_analysis."""

    def __init__(self, *args, cli: str | None = None):
        super().__init__(*args)
        self.cli = cli

    def cli_message(self) -> str:
        """The message in command-line wording (options instead of keyword arguments)."""
        return self.cli or str(self)


class ParameterError(TippediskError, ValueError):
    """A physical or numerical parameter is out of its admissible range."""


class UnknownModelError(TippediskError, KeyError):
    """A model name is not registered."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0])


class DatasetError(TippediskError):
    """A file is not a dataset written by tippedisk_analysis (or is damaged)."""


class OutputError(TippediskError):
    """An output path cannot be written (a directory, a device, an unwritable directory, an existing file)."""


class ResourceError(TippediskError):
    """A request would need more memory than the machine may give it (estimated before any work starts)."""


class IntegrationError(TippediskError):
    """The integrator failed (non-finite state, step limit)."""


class TippediskWarning(UserWarning):
    """Something was repaired on the way (e.g. a damaged chunk recomputed); the result is still right."""


class Interrupted(KeyboardInterrupt):
    """Ctrl-C stopped the work; the message says what was kept (e.g. chunks stored for a resume).

    A KeyboardInterrupt, so code that handles Ctrl-C keeps working; the ``tippedisk`` command
    prints the message as its one line and exits with status 130.
    """

    def __init__(self, message: str, *, stored: int = 0, total: int = 0):
        super().__init__(message)
        self.stored = stored
        self.total = total

    def __str__(self) -> str:
        return str(self.args[0])
