"""Bouncing cycles: the record split at GRF peaks, one cycle from one peak to the next."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import CycleError, OptionError, RecordError, check_range

__all__ = ["SUPPORTED_FB", "PEAK_PROMINENCE", "PEAK_SPACING", "MIN_FORCE_RANGE", "PERIOD_RATIO_LIMITS", "Cycle", "find_cycles"]


SUPPORTED_FB = (1.2, 4.0)
"""Bouncing frequencies (Hz) the library supports; the article's metronome
covered 1.5-3.5 Hz (Section 2)."""


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
