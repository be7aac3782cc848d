"""The library's exception family.

Every problem with user input raises a subclass of :class:`SMDInputError`,
itself a :class:`ValueError`, with a one-line message that names the file,
column, row or option at fault and says what would be valid. The command line
prints that line on stderr and exits with status 2.
"""


class SMDInputError(ValueError):
    """Base class of every input error raised by smd_statespace."""


class RecordError(SMDInputError):
    """A record (CSV file or arrays) is unreadable, incomplete or inconsistent."""


class MassError(SMDInputError):
    """The body mass is missing, non-positive or implausible."""


class OptionError(SMDInputError):
    """An option value (estimator, effect, count, range, ...) is not valid."""


class CycleError(SMDInputError):
    """A record or cycle is too short, has no peaks, or its bouncing frequency is unsupported."""
