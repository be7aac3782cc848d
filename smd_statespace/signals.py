"""From a measured ground reaction force to centre-of-mass motion, cycle by cycle.

This module is the pre-processing stage of Wang, Chen & Nagayama (2019),
Sections 3.2 and 4. It turns one person's vertical ground reaction force (GRF)
into the observations the estimators need, ``Y = [u, u_dot, u_ddot]`` (Eq. 13),
and splits the record into bouncing cycles:

1. **COM acceleration** (Eq. 3): ``u_ddot = (GRF - M_h g) / M_h`` with the body
   mass ``M_h`` measured beforehand (:func:`com_acceleration`).
2. **High-pass** the acceleration at 0.5 Hz with a zero-phase Butterworth filter
   (:func:`highpass`), removing the offset left by an imprecise mass or a
   drifting insole.
3. **Integrate** once for the velocity ``u_dot`` and again for the displacement
   ``u``: cumulative trapezoidal rule, each followed by the same zero-phase
   high-pass to remove the integration constants and drift (:func:`integrate`).
   Pipeline: ``acc --highpass--> acc_hp --integrate--> vel --integrate--> disp``.
4. **Cycles**: the record is split at GRF peaks, one cycle from one peak to the
   next (:func:`find_cycles`); consecutive cycles share their boundary sample.

Every estimator works at most at about :data:`RECORD_RATE`: a faster record is
low-pass filtered and decimated first (:func:`decimate_record`). The record-level
model (:mod:`smd_statespace.person`) then takes the force itself.

:func:`preprocess` runs all four steps on a :class:`~smd_statespace.io.Record`
and returns a :class:`Preprocessed` holding every intermediate signal, so that
each step can be inspected, tabulated and plotted. A floor acceleration, when
the record has one, is high-passed and integrated the same way (it drives the
moving-floor model of Section 6).

Two numerical facts worth knowing, both measured on synthetic records:

* **Record ends.** ``scipy.signal.sosfiltfilt`` with its default padding (odd
  reflection of 15 samples) leaves start-up transients that decay with the
  filter's slowest pole (time constant about 0.8 s at a 0.5 Hz cut-off). On
  synthetic bouncing records at 1.5-3.5 Hz, 2 s from either end, that left
  velocity errors of 15-45 % and displacement errors of 60-200 % of their RMS
  (still 6-25 % for the displacement 5 s in). The default
  ``padding="predict"`` instead removes the linear trend and extends each end
  by linear prediction (a Yule-Walker autoregressive model fitted to the
  nearest 10 s), which brings these to at most 0.4 % and 2.2 % at 2 s, and
  1.2 % and 4.6 % at 1 s. :func:`preprocess` flags the cycles closer than
  ``edge_margin`` (default 2 s) to either end.
* **Trapezoidal integration** scales a component of frequency ``f`` by
  ``x / tan(x)``, ``x = pi f / fs``: at 100 Hz sampling it loses 0.4 % at
  3.5 Hz and 6.6 % at 14 Hz per integration (the phase is exact).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from .errors import CycleError, MassError, OptionError, RecordError, check_range
from .io import G, Record

__all__ = [
    "SUPPORTED_FB",
    "RECORD_RATE",
    "check_rate",
    "decimate_record",
    "decimation_note",
    "OBSERVATION_CHANNELS",
    "PADDINGS",
    "Cycle",
    "Preprocessed",
    "com_acceleration",
    "highpass",
    "integrate",
    "find_cycles",
    "preprocess",
]

SUPPORTED_FB = (1.2, 4.0)
"""Bouncing frequencies (Hz) the library supports; the article's metronome
covered 1.5-3.5 Hz (Section 2)."""

OBSERVATION_CHANNELS = ("u", "u_dot", "u_ddot")
"""Names of the observation channels of Eq. 13: COM displacement (m),
velocity (m/s) and acceleration (m/s^2)."""

PADDINGS = ("predict", "odd", "even")
"""Ways :func:`highpass` can extend a signal beyond its ends."""

PEAK_PROMINENCE = 0.2
"""Default minimum prominence of a GRF peak, as a fraction of the force's
robust dynamic range (1st to 99th percentile)."""

PEAK_SPACING = 0.6
"""Minimum spacing of GRF peaks as a fraction of the estimated bouncing period.
Any secondary hump lies within half a period of a main peak, so a spacing above
0.5 keeps only the highest peak of each cycle while allowing for cycle-to-cycle
jitter of up to 40 %."""

MIN_FORCE_RANGE = 0.05
"""Smallest peak-to-peak GRF variation, as a fraction of the mean force, that
counts as bouncing (a person standing still sways by about 1 %)."""

PERIOD_RATIO_LIMITS = (0.7, 1.4)
"""A cycle whose duration divided by the median duration falls outside these
limits is flagged invalid (a missed peak doubles a cycle, an extra one halves it)."""

_AUTOCORR_REPEAT = 0.75
"""The bouncing period is the shortest lag whose autocorrelation reaches this
fraction of the highest autocorrelation peak (guards against octave errors)."""

_PAD_CUTOFF_PERIODS = 3.0  # prediction length, in periods of the cut-off frequency
_FIT_CUTOFF_PERIODS = 5.0  # length of the stretch an AR model is fitted to
_AR_CUTOFF_PERIODS = 0.5  # AR memory (model order), in periods of the cut-off
_MAX_AR_ORDER = 1024
_AR_LOADING = 1e-9  # relative diagonal loading of the Toeplitz system


# ---------------------------------------------------------------------------
# Step 1: Eq. 3
# ---------------------------------------------------------------------------


RECORD_RATE = 100.0
"""Sample rate (Hz) every estimator works at: faster records are decimated to between this and twice it.

Bouncing forces carry nothing above about 25 Hz (six harmonics of 3.5 Hz, floor modes of
Table 3 below 20 Hz). The article's per-sample noise levels and random walk (Eq. 6) were
set at its 100 Hz, and so was the calibration of the record-level intervals
(:data:`smd_statespace.person.calibration.CALIBRATION`); the cost grows with the samples (a 60 s
record, record-level: 13 s at 100 Hz, 114 s at 1000 Hz).
"""


def check_rate(rate):
    """``rate`` if it is a positive number of Hz or None; otherwise an :class:`OptionError` naming it."""
    if rate is not None and not (isinstance(rate, (int, float)) and not isinstance(rate, bool)
                                 and math.isfinite(rate) and rate > 0):
        raise OptionError(f"rate={rate!r} must be a positive sample rate in Hz (or None to keep every sample)")
    return rate


def decimate_record(record: Record, rate=RECORD_RATE, extra=()):
    """The record at ``rate`` to ``2 rate`` Hz: an ideal low-pass at the new Nyquist frequency, every ``q``-th sample.

    ``q = floor(fs / rate)``; with ``q < 2`` (or ``rate`` None) the record is returned as it
    is. The first ``q * floor(n / q)`` samples are kept (at most ``q - 1`` samples, under
    ``1 / rate``, are dropped at the end), extended by their mirror image (so the periodic
    extension has no jump) and resampled in the frequency domain
    (:func:`scipy.signal.resample`): every component below the new Nyquist frequency comes
    through unchanged, every one above it is removed instead of folded onto the bouncing
    harmonics. An ideal filter keeps white measurement noise white, which the record-level
    model assumes and its Ljung-Box test checks; a FIR filter
    (:func:`scipy.signal.resample_poly`) droops below the new Nyquist frequency and made
    white noise fail that test on 4 of 10 records of 3000 samples (lag-1 autocorrelation
    0.04; this filter: 0 of 10, 0.002). Measured on noise-free simulated bouncing at
    1000 Hz with a smooth force: within 0.2 N of the samples themselves, except the first and
    last three decimated samples (up to 10 N). A force that jumps (the simulator's
    ``"jumps"`` generator) rings at every jump under any anti-aliasing filter.

    Parameters
    ----------
    record : Record
    rate : float or None
        Lowest sample rate to keep (Hz); None keeps every sample.
    extra : sequence of ndarray
        Other signals sampled with the record (the same length), decimated alike.

    Returns
    -------
    record : Record
        The decimated record, or ``record`` itself.
    factor : int
        ``q`` (1: unchanged).
    extra : list of ndarray
        The ``extra`` signals, decimated alike.
    """
    if check_rate(rate) is None:
        return record, 1, list(extra)
    factor = int(math.floor(record.fs / rate + 1e-9))
    if factor < 2:
        return record, 1, list(extra)

    kept = record.time.size // factor
    from scipy import signal  # imported here: with scipy.stats, ~1 s (not needed to start)

    def down(values):
        whole = np.asarray(values, dtype=float)[:kept * factor]
        return signal.resample(np.concatenate([whole, whole[::-1]]), 2 * kept)[:kept]

    time = record.time[:kept * factor:factor]
    floor_acc = None if record.floor_acc is None else down(record.floor_acc)
    decimated = replace(record, time=time, force=down(record.force), floor_acc=floor_acc)
    return decimated, factor, [down(values) for values in extra]


def decimation_note(measured_rate: float, record: Record, factor: int, rate) -> list:
    """What :func:`decimate_record` did, in words for a result's notes (``[]`` when it kept every sample)."""
    if factor == 1:
        return []
    return [f"fitted at {record.fs:.4g} Hz: the record ({measured_rate:.4g} Hz) was low-pass filtered and every "
            f"{factor}th sample kept (rate {rate:g} Hz; rate=None or --rate 0 keeps every sample)"]


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


# ---------------------------------------------------------------------------
# Steps 2 and 3: zero-phase high-pass and drift-free integration
# ---------------------------------------------------------------------------


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


# ---------------------------------------------------------------------------
# Step 4: cycles
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Cycle:
    """One bouncing cycle, from one GRF peak to the next.

    The cycle's samples are ``start:stop + 1``; consecutive cycles share their
    boundary sample (``cycles[k].stop == cycles[k + 1].start``).

    Attributes
    ----------
    index : int
        Position of the cycle in the record, from 0.
    start, stop : int
        Sample indices of the opening and closing GRF peaks.
    t_start, t_end : float
        Times of those peaks (s).
    f_b : float
        Bouncing frequency of this cycle, ``1 / (t_end - t_start)`` (Hz).
    valid : bool
        False when the cycle looks wrong (bouncing frequency out of the
        supported range, duration far from the median, too close to a record
        end); it is kept so that nothing disappears silently.
    reason : str
        Why the cycle is invalid (empty when valid).
    """

    index: int
    start: int
    stop: int
    t_start: float
    t_end: float
    f_b: float
    valid: bool = True
    reason: str = ""

    @property
    def n_samples(self) -> int:
        """Number of samples in the cycle, both boundary peaks included."""
        return self.stop - self.start + 1

    @property
    def duration(self) -> float:
        """Cycle duration ``t_end - t_start`` (s)."""
        return self.t_end - self.t_start

    @property
    def samples(self) -> slice:
        """The cycle's samples as a slice, ``start:stop + 1``."""
        return slice(self.start, self.stop + 1)


def _bouncing_period(force: np.ndarray, fs: float, fb_hi: float) -> float | None:
    """Dominant repetition period (s) of the force from its autocorrelation, or None.

    Lags from a quarter of the shortest supported period up to half the record
    are searched; the period is the shortest lag whose autocorrelation peak
    reaches :data:`_AUTOCORR_REPEAT` of the highest one, so that a multiple of
    the period is not taken for the period itself.
    """
    from scipy import signal  # imported here: with scipy.stats, ~1 s (not needed to start)

    centred = signal.detrend(force, type="linear")
    n = centred.size
    acf = signal.correlate(centred, centred, mode="full", method="fft")[n - 1 :]
    if not acf[0] > 0:
        return None
    acf = acf[: n // 2 + 1] / acf[0]
    min_lag = max(2, int(fs / (4.0 * fb_hi)))
    lags, props = signal.find_peaks(acf, height=0.1)
    keep = lags >= min_lag
    lags, heights = lags[keep], props["peak_heights"][keep]
    if lags.size == 0:
        return None
    first = int(np.argmax(heights >= _AUTOCORR_REPEAT * heights.max()))
    return float(lags[first]) / fs


def find_cycles(time, force, fb_range=SUPPORTED_FB, *, source=None, prominence=PEAK_PROMINENCE):
    """Split a GRF record into bouncing cycles at its peaks.

    A cycle runs from one GRF peak to the next (Section 4). Peaks are found in
    two stages, robust to the secondary humps that the 2nd and 3rd harmonics
    put into a bouncing GRF:

    1. the bouncing period ``T`` is estimated from the autocorrelation of the
       force (the shortest lag that repeats the waveform);
    2. ``scipy.signal.find_peaks`` keeps only peaks at least
       :data:`PEAK_SPACING` ``* T`` apart (the highest peak of each cycle wins)
       and with a prominence of at least ``prominence`` times the force's
       dynamic range (1st to 99th percentile).

    Parameters
    ----------
    time : array_like, shape (T,)
        Sample times (s), uniformly spaced.
    force : array_like, shape (T,)
        Vertical ground reaction force (N).
    fb_range : tuple of float, default :data:`SUPPORTED_FB`
        Accepted bouncing frequencies ``(low, high)`` (Hz).
    source : str, optional
        Name of the record, used in error messages.
    prominence : float, default :data:`PEAK_PROMINENCE`
        Minimum peak prominence as a fraction of the force's dynamic range.

    Returns
    -------
    peaks : ndarray of int, shape (P,)
        Sample indices of the GRF peaks.
    cycles : list of Cycle
        The ``P - 1`` cycles between consecutive peaks. Cycles whose bouncing
        frequency lies outside ``fb_range`` or whose duration is far from the
        median (:data:`PERIOD_RATIO_LIMITS`) have ``valid=False`` and a
        ``reason``.

    Raises
    ------
    CycleError
        No GRF peaks are found (flat force, or a force that does not vary
        enough to be bouncing); fewer than two peaks (record shorter than one
        cycle); the median bouncing frequency is outside ``fb_range``.
    OptionError
        ``fb_range`` or ``prominence`` is invalid, or ``time`` and ``force``
        do not match.
    RecordError
        ``time`` or ``force`` holds NaN or infinite values.

    Notes
    -----
    The peak spacing comes from the estimated period rather than from the
    highest supported frequency: at 1.5 Hz a second-harmonic hump sits
    0.33 s after the main peak, further than the 0.25 s period at 4 Hz, and a
    spacing fixed at 0.25 s would also let a 6 Hz record pass as 3 Hz instead
    of being rejected. A cycle whose peak is lower than a neighbouring
    secondary hump cannot be told apart from it; the duration check then
    flags the cycles around it.
    """
    label = f"{source}: " if source else ""
    lo, hi = check_range(fb_range, "fb_range (Hz)", positive=True)
    if not (isinstance(prominence, (int, float)) and 0.0 < prominence < 1.0):
        raise OptionError(f"prominence={prominence!r} must be a fraction of the force range in (0, 1)")
    time, force = _checked_signals(time, force, label)
    peaks = _grf_peaks(time, force, hi, prominence, label)
    return peaks, _cycles_between(time, peaks, lo, hi, label)


def _checked_signals(time, force, label):
    """``time`` and ``force`` as flat float arrays, or an error in words (sizes, NaN, too short)."""
    time = np.asarray(time, dtype=float).ravel()
    force = np.asarray(force, dtype=float).ravel()
    if time.size != force.size:
        raise OptionError(f"{label}time has {time.size} samples but force has {force.size}")
    if time.size < 3:
        raise CycleError(f"{label}record has only {time.size} samples; no bouncing cycle can be found")
    if not (np.all(np.isfinite(time)) and np.all(np.isfinite(force))):
        raise RecordError(f"{label}time or force holds NaN or infinite values")
    return time, force


def _grf_peaks(time, force, highest_fb, prominence, label):
    """Sample indices of the GRF peaks (at least two), at most one per :data:`PEAK_SPACING` of a period."""
    fs = 1.0 / float(np.median(np.diff(time)))
    low_pct, high_pct = np.percentile(force, [1.0, 99.0])
    span = float(high_pct - low_pct)
    level = abs(float(np.mean(force)))
    if span <= 1e-9 * max(level, 1.0):
        raise CycleError(f"{label}no GRF peaks found: the force is flat; is the person bouncing?")
    if span < MIN_FORCE_RANGE * level:
        raise CycleError(
            f"{label}no GRF peaks found: the force varies by only {span:.3g} N "
            f"({span / level:.1%} of its mean {level:.4g} N); bouncing needs at least {MIN_FORCE_RANGE:.0%}"
        )
    period = _bouncing_period(force, fs, highest_fb)
    if period is None:
        period = 1.0 / highest_fb  # no repetition visible (e.g. under two cycles): shortest supported period
    distance = max(1, int(PEAK_SPACING * period * fs))
    from scipy import signal  # imported here: with scipy.stats, ~1 s (not needed to start)

    peaks, _ = signal.find_peaks(force, distance=distance, prominence=prominence * span)
    duration = float(time[-1] - time[0])
    if peaks.size == 0:
        raise CycleError(f"{label}no GRF peaks found in {duration:.2f} s of record")
    if peaks.size < 2:
        raise CycleError(
            f"{label}record is shorter than one bouncing cycle: only 1 GRF peak in {duration:.2f} s; "
            "a cycle runs from one peak to the next"
        )
    return peaks


def _cycles_between(time, peaks, lo, hi, label):
    """One :class:`Cycle` from each peak to the next, invalid (with the reason) when its length is odd."""
    starts, stops = peaks[:-1], peaks[1:]
    durations = time[stops] - time[starts]
    f_b = 1.0 / durations
    median_fb = float(np.median(f_b))
    if not lo <= median_fb <= hi:
        raise CycleError(
            f"{label}median bouncing frequency {median_fb:.2f} Hz is outside the supported range "
            f"{lo:g}-{hi:g} Hz"
        )
    ratio = durations / float(np.median(durations))
    cycles = []
    for k in range(starts.size):
        reasons = []
        if not lo <= f_b[k] <= hi:
            reasons.append(f"f_b {f_b[k]:.2f} Hz outside the supported range {lo:g}-{hi:g} Hz")
        if ratio[k] > PERIOD_RATIO_LIMITS[1]:
            reasons.append(f"duration {ratio[k]:.2f} x the median (missed peak?)")
        elif ratio[k] < PERIOD_RATIO_LIMITS[0]:
            reasons.append(f"duration {ratio[k]:.2f} x the median (extra peak?)")
        cycles.append(
            Cycle(
                index=k,
                start=int(starts[k]),
                stop=int(stops[k]),
                t_start=float(time[starts[k]]),
                t_end=float(time[stops[k]]),
                f_b=float(f_b[k]),
                valid=not reasons,
                reason="; ".join(reasons),
            )
        )
    return cycles


# ---------------------------------------------------------------------------
# The whole pipeline
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Preprocessed:
    """Every intermediate signal of the pre-processing of one record.

    Attributes
    ----------
    time : ndarray, shape (T,)
        Sample times (s).
    force : ndarray, shape (T,)
        Measured GRF (N).
    mass : float
        Body mass ``M_h`` (kg).
    fs : float
        Sampling frequency (Hz).
    acc_raw : ndarray, shape (T,)
        COM acceleration from Eq. 3 (m/s^2), unfiltered.
    acc : ndarray, shape (T,)
        High-passed COM acceleration ``u_ddot`` (m/s^2).
    vel : ndarray, shape (T,)
        COM velocity ``u_dot`` (m/s).
    disp : ndarray, shape (T,)
        COM displacement ``u`` from static equilibrium (m).
    peaks : ndarray of int, shape (P,)
        Sample indices of the GRF peaks.
    cycles : list of Cycle
        The ``P - 1`` cycles between consecutive peaks.
    cutoff : float
        High-pass cut-off frequency (Hz).
    floor_acc, floor_vel, floor_disp : ndarray or None, shape (T,)
        High-passed floor acceleration (m/s^2), its velocity (m/s) and
        displacement (m), when the record has a floor acceleration.
    source : str
        Name of the record.
    """

    time: np.ndarray
    force: np.ndarray
    mass: float
    fs: float
    acc_raw: np.ndarray
    acc: np.ndarray
    vel: np.ndarray
    disp: np.ndarray
    peaks: np.ndarray
    cycles: list = field(default_factory=list)
    cutoff: float = 0.5
    floor_acc: np.ndarray | None = None
    floor_vel: np.ndarray | None = None
    floor_disp: np.ndarray | None = None
    source: str = "<arrays>"

    @property
    def duration(self) -> float:
        """Record length (s)."""
        return float(self.time[-1] - self.time[0])

    @property
    def valid_cycles(self) -> list:
        """The cycles flagged valid."""
        return [cycle for cycle in self.cycles if cycle.valid]

    def _cycle(self, cycle) -> Cycle:
        """Accept a :class:`Cycle` or its index and return the Cycle."""
        if isinstance(cycle, Cycle):
            return cycle
        if isinstance(cycle, (int, np.integer)) and not isinstance(cycle, bool):
            if 0 <= cycle < len(self.cycles):
                return self.cycles[int(cycle)]
            raise OptionError(
                f"{self.source}: cycle {cycle} does not exist; the record has {len(self.cycles)} cycles "
                f"(0-{len(self.cycles) - 1})"
            )
        raise OptionError(f"cycle must be a Cycle or a cycle index, got {cycle!r}")

    def to_frame(self) -> pd.DataFrame:
        """The per-sample signals as a DataFrame.

        Returns
        -------
        pandas.DataFrame
            Columns ``time`` (s), ``force`` (N), ``acc_raw``, ``acc``
            (m/s^2), ``vel`` (m/s), ``disp`` (m) and, with a floor signal,
            ``floor_acc`` (m/s^2), ``floor_vel`` (m/s), ``floor_disp`` (m).
        """
        data = {
            "time": self.time,
            "force": self.force,
            "acc_raw": self.acc_raw,
            "acc": self.acc,
            "vel": self.vel,
            "disp": self.disp,
        }
        if self.floor_acc is not None:
            data.update(floor_acc=self.floor_acc, floor_vel=self.floor_vel, floor_disp=self.floor_disp)
        return pd.DataFrame(data)

    def cycle_table(self) -> pd.DataFrame:
        """One row per cycle.

        Returns
        -------
        pandas.DataFrame
            Columns ``cycle`` (index), ``t_start``, ``t_end`` (s),
            ``n_samples``, ``f_b`` (Hz), ``valid`` and ``reason``.
        """
        columns = ["cycle", "t_start", "t_end", "n_samples", "f_b", "valid", "reason"]
        rows = [
            (c.index, c.t_start, c.t_end, c.n_samples, c.f_b, c.valid, c.reason) for c in self.cycles
        ]
        return pd.DataFrame(rows, columns=columns)

    def observations(self, cycle, channels=OBSERVATION_CHANNELS):
        """Observation vectors ``Y_k`` (Eq. 13) over one cycle.

        Parameters
        ----------
        cycle : Cycle or int
            The cycle, or its index.
        channels : sequence of str, default ("u", "u_dot", "u_ddot")
            Channels in the wanted column order: ``"u"`` displacement (m),
            ``"u_dot"`` velocity (m/s), ``"u_ddot"`` high-passed acceleration
            (m/s^2).

        Returns
        -------
        t : ndarray, shape (m,)
            Absolute sample times of the cycle (s), boundary peaks included.
        y : ndarray, shape (m, len(channels))
            The channels, one column each.

        Raises
        ------
        OptionError
            Unknown channel name, empty channel list or unknown cycle.
        """
        if isinstance(channels, str):
            channels = (channels,)
        channels = tuple(channels)
        signals = {"u": self.disp, "u_dot": self.vel, "u_ddot": self.acc}
        if not channels:
            raise OptionError(f"channels is empty; choose from {', '.join(OBSERVATION_CHANNELS)}")
        for name in channels:
            if name not in signals:
                raise OptionError(f"unknown channel {name!r}; choose from {', '.join(OBSERVATION_CHANNELS)}")
        span = self._cycle(cycle).samples
        y = np.column_stack([signals[name][span] for name in channels])
        return self.time[span].copy(), y

    def exogenous(self, cycle) -> dict:
        """Floor motion over one cycle (inputs of the moving-floor model, Section 6).

        Parameters
        ----------
        cycle : Cycle or int
            The cycle, or its index.

        Returns
        -------
        dict of str to ndarray
            ``floor_disp`` (m), ``floor_vel`` (m/s) and ``floor_acc``
            (m/s^2) over the cycle's samples, shape (m,) each; an empty dict
            when the record has no floor acceleration.
        """
        span = self._cycle(cycle).samples
        if self.floor_acc is None:
            return {}
        return {
            "floor_disp": self.floor_disp[span].copy(),
            "floor_vel": self.floor_vel[span].copy(),
            "floor_acc": self.floor_acc[span].copy(),
        }

    def summary(self) -> str:
        """One paragraph describing the pre-processed record.

        Returns
        -------
        str
            Number of cycles (valid ones), median bouncing frequency and its
            range over the valid cycles (Hz), sampling frequency (Hz),
            duration (s), high-pass cut-off (Hz) and RMS of the COM
            acceleration (m/s^2), velocity (m/s) and displacement (m).
        """
        valid = self.valid_cycles
        basis = valid if valid else self.cycles
        f_b = np.array([c.f_b for c in basis])
        which = "valid cycles" if valid else "all cycles, none valid"

        def rms(x):
            return float(np.sqrt(np.mean(np.square(x))))

        text = (
            f"{self.source}: {len(self.cycles)} bouncing cycles ({len(valid)} valid) in "
            f"{self.duration:.2f} s sampled at {self.fs:g} Hz, body mass {self.mass:g} kg. "
            f"Bouncing frequency median {np.median(f_b):.3f} Hz, range {f_b.min():.3f}-{f_b.max():.3f} Hz "
            f"({which}). High-pass cut-off {self.cutoff:g} Hz. RMS of the COM acceleration "
            f"{rms(self.acc):.3g} m/s^2, velocity {rms(self.vel):.3g} m/s, displacement {rms(self.disp):.3g} m."
        )
        if self.floor_acc is not None:
            text += (
                f" Floor RMS acceleration {rms(self.floor_acc):.3g} m/s^2, "
                f"displacement {rms(self.floor_disp):.3g} m."
            )
        return text

    def plot(self, path=None, zoom_cycles=3):
        """Plot every pre-processing step, one row of panels each
        (:func:`~smd_statespace.plotting.pipeline.plot_preprocessed`); saved as PNG (100 dpi) if ``path``."""
        from .plotting.pipeline import plot_preprocessed  # the pipeline's own figure: matplotlib when drawn

        return plot_preprocessed(self, path, zoom_cycles)


def motion(acceleration, fs, cutoff=0.5, order=4, *, padding="predict") -> tuple:
    """High-passed acceleration, velocity and displacement of a measured acceleration (SI units).

    The acceleration is high-passed and integrated twice by :func:`highpass`
    and :func:`integrate` with the same filter, as :func:`preprocess` does for
    the COM (Eq. 3) and for a floor accelerometer.
    """
    acc = highpass(acceleration, fs, cutoff, order, padding=padding)
    vel = integrate(acc, fs, cutoff, order, padding=padding)
    return acc, vel, integrate(vel, fs, cutoff, order, padding=padding)


def preprocess(record: Record, cutoff=0.5, fb_range=SUPPORTED_FB, *, order=4, padding="predict",
               edge_margin=2.0) -> Preprocessed:
    """Run the whole pre-processing pipeline on one record.

    ``acc_raw`` (Eq. 3) ``--highpass--> acc --integrate--> vel --integrate-->
    disp``, the same for the floor acceleration when present, and the cycles
    from the GRF peaks.

    Parameters
    ----------
    record : Record
        A checked record (see :func:`smd_statespace.io.make_record`).
    cutoff : float, default 0.5
        High-pass cut-off frequency (Hz).
    fb_range : tuple of float, default :data:`SUPPORTED_FB`
        Accepted bouncing frequencies (Hz).
    order : int, default 4
        Butterworth order of one filter pass.
    padding : {"predict", "odd", "even"}, default "predict"
        End treatment of the high-pass; see :func:`highpass`.
    edge_margin : float, default 2.0
        Cycles that start within this time (s) of the record start, or end
        within it of the record end, are flagged invalid: the filtered and
        integrated signals are least accurate there. 0 disables the flag.

    Returns
    -------
    Preprocessed

    Raises
    ------
    CycleError
        No peaks, fewer than two peaks, or median bouncing frequency outside
        ``fb_range`` (the message names ``record.source``).
    OptionError
        An invalid option, or a record too short for the filter.
    """
    source = record.source
    try:
        edge_margin = float(edge_margin)
    except (TypeError, ValueError):
        raise OptionError(f"edge_margin={edge_margin!r} must be a time in s") from None
    if not (math.isfinite(edge_margin) and edge_margin >= 0):
        raise OptionError(f"edge_margin={edge_margin!r} must be a non-negative time in s")
    time = np.asarray(record.time, dtype=float)
    force = np.asarray(record.force, dtype=float)
    fs = float(record.fs)
    peaks, cycles = find_cycles(time, force, fb_range, source=source)
    try:
        acc_raw = com_acceleration(force, record.mass)  # Eq. 3
        acc, vel, disp = motion(acc_raw, fs, cutoff, order, padding=padding)
        floor_acc = floor_vel = floor_disp = None
        if record.floor_acc is not None:
            floor_acc, floor_vel, floor_disp = motion(record.floor_acc, fs, cutoff, order, padding=padding)
    except (OptionError, MassError, RecordError) as exc:
        raise type(exc)(f"{source}: {exc}") from None

    if edge_margin > 0:
        t_first, t_last = float(time[0]), float(time[-1])
        flagged = []
        for cycle in cycles:
            near = cycle.t_start - t_first < edge_margin or t_last - cycle.t_end < edge_margin
            if near:
                note = f"within {edge_margin:g} s of a record end (filter edge effects)"
                reason = f"{cycle.reason}; {note}" if cycle.reason else note
                cycle = replace(cycle, valid=False, reason=reason)
            flagged.append(cycle)
        cycles = flagged

    return Preprocessed(
        time=time,
        force=force,
        mass=float(record.mass),
        fs=fs,
        acc_raw=acc_raw,
        acc=acc,
        vel=vel,
        disp=disp,
        peaks=peaks,
        cycles=cycles,
        cutoff=float(cutoff),
        floor_acc=floor_acc,
        floor_vel=floor_vel,
        floor_disp=floor_disp,
        source=source,
    )
