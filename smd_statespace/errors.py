"""The library's exception family.

Every problem with user input raises a subclass of :class:`SMDInputError`,
itself a :class:`ValueError`, with a one-line message that names the file,
column, row or option at fault and says what would be valid. The command line
prints that line on stderr and exits with status 2.

:func:`check_range` is the one check of a ``(low, high)`` option: the model's prior
ranges, the effects' ranges, the signal pipeline's ``fb_range``.
"""

import math

__all__ = ["SMDInputError", "RecordError", "MassError", "OptionError", "CycleError", "check_range"]


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


def check_range(value, label, *, minimum=None, positive=False) -> tuple:
    """``value`` as a pair of finite floats ``low < high``, or an :class:`OptionError` naming ``label``.

    Parameters
    ----------
    value : sequence of two numbers
    label : str
        How the message names the option (``"floor_mode: frequency_range"``).
    minimum : float, optional
        ``low`` may not go below it (``f_h_range`` from 0).
    positive : bool
        ``0 < low`` (frequencies, damping ratios, mass ratios).

    Returns
    -------
    tuple of float
        ``(low, high)``.
    """
    try:
        low, high = (float(v) for v in value)
    except (TypeError, ValueError):
        raise OptionError(f"{label} must be a pair (low, high), got {value!r}") from None
    if not (math.isfinite(low) and math.isfinite(high) and low < high):
        raise OptionError(f"{label} must satisfy low < high, got {value!r}")
    if positive and not low > 0.0:
        raise OptionError(f"{label} must satisfy 0 < low < high, got {value!r}")
    if minimum is not None and low < minimum:
        raise OptionError(f"{label} must not go below {minimum:g}, got {value!r}")
    return low, high
