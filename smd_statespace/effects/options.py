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
