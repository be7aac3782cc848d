"""Option checks and spec text shared by the built-in effects (numbers, ranges, ``key=value`` values)."""

from __future__ import annotations

import numpy as np

from ..errors import OptionError


def with_values_spec(spec: str, effect) -> str:
    """``spec`` with the effect's known values appended (``key=value`` in the same spec)."""
    values = effect.values
    if not values:
        return spec
    glue = "," if ":" in spec else ":"
    return spec + glue + ",".join(f"{key}={spec_value(value)}" for key, value in values.items())


def numbers(value, label, where, pair=False):
    """``value`` (a number or a sequence of numbers) as floats; ``pair``: exactly two."""
    try:
        numbers = tuple(float(v) for v in np.atleast_1d(value))
    except (TypeError, ValueError):
        raise OptionError(f"{where}: {label} must be {'a pair low/high' if pair else 'numbers'}, got {value!r}") from None
    if not all(np.isfinite(numbers)) or (pair and len(numbers) != 2):
        raise OptionError(f"{where}: {label} must be {'a pair low/high' if pair else 'finite numbers'}, got {value!r}")
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


def spec_value(value) -> str:
    """An option value as ``make_effect`` reads it (pairs as ``low/high``)."""
    if isinstance(value, (tuple, list)):
        return "/".join(spec_value(v) for v in value)
    return f"{value:g}" if isinstance(value, float) else str(value)


def positive(value, label, where):
    """``value`` as a finite float > 0, or an :class:`OptionError` naming ``label`` in ``where``."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise OptionError(f"{where}: {label} must be a number, got {value!r}") from None
    if not (np.isfinite(number) and number > 0):
        raise OptionError(f"{where}: {label} must be a positive number, got {value!r}")
    return number


def positive_range(value, label, where):
    """``value`` as a pair ``0 < low < high`` of floats, or an :class:`OptionError` naming ``label``."""
    try:
        low, high = (float(v) for v in value)
    except (TypeError, ValueError):
        raise OptionError(f"{where}: {label} must be a pair low/high, got {value!r}") from None
    if not (np.isfinite(low) and np.isfinite(high) and 0 < low < high):
        raise OptionError(f"{where}: {label} must satisfy 0 < low < high, got {value!r}")
    return low, high
