"""One exception family. Every message names the problem and how to fix it."""


class TippediskError(Exception):
    """Base class of all errors raised by tippedisk_analysis."""


class ParameterError(TippediskError, ValueError):
    """A physical or numerical parameter is out of its admissible range."""


class UnknownModelError(TippediskError, KeyError):
    """A model name is not registered."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0])


class DatasetError(TippediskError):
    """A file is not a dataset written by tippedisk_analysis (or is damaged)."""


class IntegrationError(TippediskError):
    """The integrator failed (non-finite state, step limit)."""
