"""Option checks shared by the built-in effects (numbers, ranges, non-negative and positive values)."""

from __future__ import annotations

import numpy as np

from ..errors import OptionError


def numbers(value, label, where):
    """``value`` (a number or numbers) as finite floats; a range: :func:`~smd_statespace.errors.check_range`."""
    try:
        numbers = tuple(float(v) for v in np.atleast_1d(value))
    except (TypeError, ValueError):
        raise OptionError(f"{where}: {label} must be numbers, got {value!r}") from None
    if not all(np.isfinite(numbers)):
        raise OptionError(f"{where}: {label} must be finite numbers, got {value!r}")
    return numbers


def nonnegative(value, label, where):
    """``value`` as a finite float >= 0, or an :class:`OptionError` naming ``label`` in ``where``."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise OptionError(f"{where}: {label} must be a number, got {value!r}") from None
    if not (np.isfinite(number) and number >= 0):
        raise OptionError(f"{where}: {label} must be a number >= 0, got {value!r}")
    return number


def positive(value, label, where):
    """``value`` as a finite float > 0, or an :class:`OptionError` naming ``label`` in ``where``."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise OptionError(f"{where}: {label} must be a number, got {value!r}") from None
    if not (np.isfinite(number) and number > 0):
        raise OptionError(f"{where}: {label} must be a positive number, got {value!r}")
    return number
