"""Eq. 3 and the zero-phase filters: COM acceleration from the GRF, the 0.5 Hz high-pass and the integration to
velocity and displacement (with the record ends padded by linear prediction)."""

from __future__ import annotations

import math

import numpy as np

from ..errors import MassError, OptionError, RecordError
from ..io import G

__all__ = ["PADDINGS", "com_acceleration", "highpass", "integrate", "motion"]


PADDINGS = ("predict", "odd", "even")
"""Ways :func:`highpass` can extend a signal beyond its ends."""


_PAD_CUTOFF_PERIODS = 3.0  # prediction length, in periods of the cut-off frequency


_FIT_CUTOFF_PERIODS = 5.0  # length of the stretch an AR model is fitted to


_AR_CUTOFF_PERIODS = 0.5  # AR memory (model order), in periods of the cut-off


_MAX_AR_ORDER = 1024


_AR_LOADING = 1e-9  # relative diagonal loading of the Toeplitz system


def com_acceleration(force, mass):
    """Centre-of-mass acceleration from the ground reaction force (Eq. 3).

    ``u_ddot = (GRF - M_h g) / M_h``, with ``g`` = :data:`smd_statespace.io.G`.

    Parameters
    ----------
    force : array_like
        Vertical ground reaction force (N), any shape.
    mass : float or array_like
        Body mass ``M_h`` (kg), positive; broadcast against ``force``.

    Returns
    -------
    ndarray
        COM acceleration (m/s^2), upwards positive, shape of the broadcast of
        ``force`` and ``mass``.

    Raises
    ------
    MassError
        A mass is not a positive finite number.
    """
    mass_arr = np.asarray(mass, dtype=float)
    if not np.all(np.isfinite(mass_arr) & (mass_arr > 0)):
        raise MassError(f"body mass must be a positive number of kg, got {mass!r}")
    force_arr = np.asarray(force, dtype=float)
    return (force_arr - mass_arr * G) / mass_arr  # Eq. 3


def _check_filter_options(n_samples: int, fs: float, cutoff: float, order: int, padding: str) -> np.ndarray:
    """Validate the high-pass options and return the filter's second-order sections."""
    try:
        fs = float(fs)
    except (TypeError, ValueError):
        raise OptionError(f"fs={fs!r} is not a number; give the sampling frequency in Hz") from None
    if not (math.isfinite(fs) and fs > 0):
        raise OptionError(f"fs={fs!r} Hz: the sampling frequency must be a positive number")
    try:
        cutoff = float(cutoff)
    except (TypeError, ValueError):
        raise OptionError(f"cutoff={cutoff!r} is not a number; give the high-pass cut-off in Hz") from None
    nyquist = fs / 2.0
    if not (math.isfinite(cutoff) and 0.0 < cutoff < nyquist):
        raise OptionError(
            f"cutoff={cutoff:g} Hz is outside (0, {nyquist:g}) Hz, i.e. above zero and below fs/2; "
            "the article uses 0.5 Hz"
        )
    if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or not 1 <= order <= 12:
        raise OptionError(f"order={order!r}: the Butterworth order must be an integer from 1 to 12 (default 4)")
    if padding not in PADDINGS:
        raise OptionError(f"padding={padding!r} is not one of {', '.join(PADDINGS)}")
    from scipy import signal  # imported here: with scipy.stats, ~1 s (not needed to start)

    sos = signal.butter(int(order), cutoff, btype="highpass", fs=fs, output="sos")
    # The padding sosfiltfilt itself needs (its default padlen).
    padlen = 3 * (2 * len(sos) + 1 - min(int((sos[:, 2] == 0).sum()), int((sos[:, 5] == 0).sum())))
    if n_samples <= padlen:
        raise OptionError(
            f"signal has {n_samples} samples; the order-{order} high-pass (cutoff={cutoff:g} Hz) "
            f"needs more than {padlen} for its padding"
        )
    return sos


def _ar_forecast(segment: np.ndarray, n_ahead: int, order: int) -> np.ndarray:
    """Continue ``segment`` by ``n_ahead`` samples with a Yule-Walker AR(order) model.

    The biased autocovariance with a little diagonal loading is positive
    definite, so the fitted model is stable and its forecast decays towards
    the segment mean instead of growing. Falls back to the mean when the
    segment is constant or the fit fails.
    """
    from scipy import linalg, signal  # imported here: with scipy.stats, ~1 s (not needed to start)

    mean = float(segment.mean())
    fallback = np.full(n_ahead, mean)
    centred = segment - mean
    n = centred.size
    acov = signal.correlate(centred, centred, mode="full", method="fft")[n - 1 : n + order] / n
    if not acov[0] > 0:
        return fallback
    column = acov[:order].copy()
    column[0] *= 1.0 + _AR_LOADING
    try:
        coef = linalg.solve_toeplitz(column, acov[1 : order + 1])
    except (np.linalg.LinAlgError, ValueError):
        return fallback
    denominator = np.concatenate(([1.0], -coef))
    state = signal.lfiltic([1.0], denominator, y=centred[::-1][:order])
    forecast, _ = signal.lfilter([1.0], denominator, np.zeros(n_ahead), zi=state)
    bound = 10.0 * np.abs(centred).max()
    if not np.all(np.isfinite(forecast)) or np.abs(forecast).max() > bound:
        return fallback
    return forecast + mean


def _predictive_highpass(rows: np.ndarray, fs: float, cutoff: float, sos: np.ndarray) -> np.ndarray:
    """High-pass each row after detrending and extending both ends by linear prediction."""
    from scipy import signal  # imported here: with scipy.stats, ~1 s (not needed to start)

    n = rows.shape[-1]
    rows = signal.detrend(rows, axis=-1, type="linear")
    n_pad = int(math.ceil(_PAD_CUTOFF_PERIODS / cutoff * fs))
    fit_len = min(n, int(math.ceil(_FIT_CUTOFF_PERIODS / cutoff * fs)))
    ar_order = min(int(math.ceil(_AR_CUTOFF_PERIODS / cutoff * fs)), fit_len // 3, _MAX_AR_ORDER)
    if ar_order < 2:
        return signal.sosfiltfilt(sos, rows, axis=-1)
    extended = np.empty(rows.shape[:-1] + (n + 2 * n_pad,))
    for i, row in enumerate(rows):
        before = _ar_forecast(row[:fit_len][::-1], n_pad, ar_order)[::-1]
        after = _ar_forecast(row[-fit_len:], n_pad, ar_order)
        extended[i] = np.concatenate((before, row, after))
    filtered = signal.sosfiltfilt(sos, extended, axis=-1)
    return filtered[:, n_pad : n_pad + n]


def highpass(x, fs, cutoff=0.5, order=4, *, axis=-1, padding="predict"):
    """Zero-phase Butterworth high-pass filter.

    A Butterworth design (``scipy.signal.butter``, second-order sections) run
    forwards and backwards (``scipy.signal.sosfiltfilt``): no phase lag, and a
    magnitude response equal to the square of the Butterworth one, i.e. an
    attenuation of 1/2 (-6 dB) at ``cutoff``.

    Parameters
    ----------
    x : array_like
        Signal sampled at ``fs``, any unit; filtered along ``axis``.
    fs : float
        Sampling frequency (Hz).
    cutoff : float, default 0.5
        Cut-off frequency (Hz), in the open interval (0, fs/2). The article
        uses 0.5 Hz (Section 3.2).
    order : int, default 4
        Butterworth order of one pass (1 to 12).
    axis : int, default -1
        Time axis of ``x``.
    padding : {"predict", "odd", "even"}, default "predict"
        How the signal is continued beyond its ends. ``"predict"`` removes
        the linear trend, then extends each end by ``3 / cutoff`` seconds of
        linear prediction from an autoregressive model fitted to the nearest
        ``5 / cutoff`` seconds; this suppresses most of the start-up transient
        at the record ends. ``"odd"`` and ``"even"`` are the plain
        ``sosfiltfilt`` reflections (``"odd"`` is SciPy's default).

    Returns
    -------
    ndarray
        Filtered signal, same shape and unit as ``x``.

    Raises
    ------
    OptionError
        ``fs``, ``cutoff``, ``order`` or ``padding`` is invalid, or the signal
        is too short for the filter's padding.
    RecordError
        ``x`` holds NaN or infinite values.
    """
    x = np.asarray(x, dtype=float)
    if x.ndim == 0:
        raise OptionError("x is a scalar; highpass needs a signal (an array of samples)")
    sos = _check_filter_options(x.shape[axis], fs, cutoff, order, padding)
    if not np.all(np.isfinite(x)):
        raise RecordError("signal holds NaN or infinite values; the high-pass needs finite samples")
    if padding != "predict":
        from scipy import signal  # imported here: with scipy.stats, ~1 s (not needed to start)

        return signal.sosfiltfilt(sos, x, axis=axis, padtype=padding)
    moved = np.moveaxis(x, axis, -1)
    rows = moved.reshape(-1, moved.shape[-1])
    filtered = _predictive_highpass(rows, float(fs), float(cutoff), sos)
    return np.moveaxis(filtered.reshape(moved.shape), -1, axis)


def integrate(x, fs, cutoff=0.5, order=4, *, axis=-1, padding="predict"):
    """Integrate a signal in time and remove the drift with a zero-phase high-pass.

    Cumulative trapezoidal rule starting from zero
    (``scipy.integrate.cumulative_trapezoid(..., initial=0)``), followed by
    :func:`highpass` with the same options, which removes the unknown
    integration constant and low-frequency drift. Used twice in the pipeline:
    acceleration to velocity, velocity to displacement (Section 3.2).

    Parameters
    ----------
    x : array_like
        Signal sampled at ``fs`` (e.g. m/s^2); integrated along ``axis``.
    fs : float
        Sampling frequency (Hz).
    cutoff : float, default 0.5
        High-pass cut-off frequency (Hz).
    order : int, default 4
        Butterworth order of one pass.
    axis : int, default -1
        Time axis of ``x``.
    padding : {"predict", "odd", "even"}, default "predict"
        End treatment of the high-pass; see :func:`highpass`.

    Returns
    -------
    ndarray
        Integral of ``x`` (unit of ``x`` times s, e.g. m/s), same shape as
        ``x``, with no content below ``cutoff``.

    Raises
    ------
    OptionError
        See :func:`highpass`.

    Notes
    -----
    The trapezoidal rule scales a component of frequency ``f`` by
    ``(pi f / fs) / tan(pi f / fs)`` and leaves its phase exact: about
    -0.4 % at 3.5 Hz and -6.6 % at 14 Hz for ``fs`` = 100 Hz.
    """
    x = np.asarray(x, dtype=float)
    if x.ndim == 0:
        raise OptionError("x is a scalar; integrate needs a signal (an array of samples)")
    _check_filter_options(x.shape[axis], fs, cutoff, order, padding)
    from scipy.integrate import cumulative_trapezoid  # here, not at the top, as scipy.signal

    integral = cumulative_trapezoid(x, dx=1.0 / float(fs), axis=axis, initial=0.0)
    return highpass(integral, fs, cutoff, order, axis=axis, padding=padding)


def motion(acceleration, fs, cutoff=0.5, order=4, *, padding="predict") -> tuple:
    """High-passed acceleration, velocity and displacement of a measured acceleration (SI units).

    The acceleration is high-passed and integrated twice by :func:`highpass`
    and :func:`integrate` with the same filter, as :func:`preprocess` does for
    the COM (Eq. 3) and for a floor accelerometer.
    """
    acc = highpass(acceleration, fs, cutoff, order, padding=padding)
    vel = integrate(acc, fs, cutoff, order, padding=padding)
    return acc, vel, integrate(vel, fs, cutoff, order, padding=padding)
