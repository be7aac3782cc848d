"""Putting a phone's irregular clock onto a uniform time grid: :func:`resample_uniform`.

Phones stamp each sample with the time the sensor delivered it: the intervals
jitter by a fraction of a millisecond, samples get dropped (often when the
phone is busy), the same stamp can appear twice and a sample can arrive out
of order.

The steps
---------

:func:`resample_uniform` repairs the clock in five steps:

1. **Order**: the samples are sorted by time (stable sort); a step backwards
   larger than ``max_gap`` is refused (the clock was reset, or two records
   were concatenated), smaller ones are counted in ``n_backwards``; a clock
   whose steps go back more often than forwards (a reversed file) is refused.
2. **Duplicates**: samples with the same time stamp are merged into their mean;
   more than :data:`REPEATED_STAMPS` of them (a stuck or coarse clock) is refused.
3. **Rate**: the nominal interval is first the one near the median of the
   intervals at which the first stamps' phases agree best, robust to jitter and
   to dropped samples, then refined by a least-squares
   line through the time stamps against their sample numbers (dropped
   samples keep their numbers). The median of jittered intervals can be off
   the phone's true rate by 0.04-1 %, enough for a grid at that rate to slide
   by several samples across a record; the line is good to about 1e-5 and
   keeps the grid on the samples (see below). ``fs_nominal`` is the
   refined rate; the grid's rate is ``fs`` if given, else ``fs_nominal``. The
   record's rate must lie in :data:`RATE_RANGE` (within
   :data:`RATE_TOLERANCE`), ``fs`` in :data:`RATE_RANGE`.
4. **Gaps**: an interval longer than ``max_gap`` is refused (interpolating
   through it would invent the better part of a bouncing cycle); shorter ones
   (dropped samples) are bridged.
5. **Interpolation**: each grid time ``t0 + n / fs`` up to the last stamp gets
   the straight line between the two samples around it (vectorised: one
   ``searchsorted`` and one weighted sum for all axes).

When were the samples taken?
----------------------------

A stamp that scatters about the phone's clock says one of two things: the
sensor sampled at irregular instants and stamped them truly (the interpolation
above reads each value at its instant), or it sampled on its regular clock and
the stamps came late or early (the time the system took the sample from the
sensor's queue). Read at their stamps, such samples are each read at the wrong
instant: a value off by the acceleration's rate of change times the stamp's
error (about 0.03 m/s^2 rms for 1 ms at 200 Hz on a bounce of 2.2 Hz, more than
half the sensor's noise). The record says which: each sample is predicted by
the straight line between its two neighbours, once at the stamps and once on a
regular clock (the samples in the file's order, numbered with the ones dropped,
:func:`_regular_clock`), and the clock with the smaller mean square error is
taken when it is clearly smaller (:data:`CLOCK_MARGIN`), and tried only when
the stamps scatter by less than a quarter interval (:data:`REGULAR_SCATTER`). On
130 simulated phones (``benchmarks/phone_clock.py``) the regular clock was chosen
on every record whose stamps scattered by 0.3-2 ms about regular samples and on
none whose samples were taken at the scattered stamps (``info["samples_at"]``:
``"stamps"`` or ``"regular clock"``).

Why linear interpolation
------------------------

Linear interpolation is local (a dropped sample or a glitch affects one
interval only), never overshoots, needs no assumption about the band of the
signal, and costs one weighted sum per sample; a band-limited (sinc or spline)
interpolator would spread an irregularity over many samples and ring at gaps.
Its price is a small, known low-pass. A grid point a fraction ``mu`` of an
interval after a sample receives ``(1 - mu) x[k] + mu x[k+1]``,
whose response to a component at ``f`` is ``H_mu(f) = 1 - mu + mu exp(2j pi f / fs)``
against an ideal delay of ``exp(2j pi mu f / fs)``. Averaged over all positions
of the grid relative to the samples this is the triangle kernel's response

    H(f) = sinc^2(f / fs) = (sin(pi f / fs) / (pi f / fs))^2

real (no phase error), ``~ 1 - (pi f / fs)^2 / 3``; the worst position,
``mu = 1/2``, gives ``cos(pi f / fs)``. Amplitude lost (%), average / worst:

======= ============ ============ ============ ============= =============
fs (Hz) 1.5 Hz       3.5 Hz       7 Hz         10.5 Hz       15 Hz
======= ============ ============ ============ ============= =============
50      0.30 / 0.44  1.6 / 2.4    6.3 / 9.5    13.7 / 21.0   26.3 / 41.2
100     0.07 / 0.11  0.40 / 0.60  1.6 / 2.4    3.6 / 5.4     7.2 / 10.9
200     0.02 / 0.03  0.10 / 0.15  0.40 / 0.60  0.90 / 1.4    1.8 / 2.8
500     0.00 / 0.00  0.02 / 0.02  0.06 / 0.10  0.14 / 0.22   0.30 / 0.44
======= ============ ============ ============ ============= =============

So at the bouncing frequencies (1.5-3.5 Hz) the loss is below 2 % at 50 Hz and
below 0.5 % from 100 Hz; harmonics up to 15 Hz lose less than 3 % from 200 Hz
but a quarter at 50 Hz (record at 100 Hz or more if they matter). These are
the figures when the grid slides across the samples, as it does when ``fs``
differs from the record's rate. On the default grid, at the refined rate of
the record, ``mu`` stays near 0, moved by the jitter alone, and the loss is
a fraction of them: on a synthetic 20 s, 50 Hz record with 0.3 ms jitter
(four harmonics of 2.2 Hz, to 8.8 Hz) the vertical acceleration came out
within 0.18 % of its RMS, against 2.3 % on a grid at the median rate. The
variation of ``mu`` along the record also modulates the loss, which leaks a
comparably small part of each component to other frequencies.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import OptionError, RecordError

__all__ = [
    "RATE_RANGE",
    "RATE_TOLERANCE",
    "MAX_GAP",
    "REPEATED_STAMPS",
    "CLOCK_MARGIN",
    "REGULAR_SCATTER",
    "RATE_SEARCH",
    "resample_uniform",
]

RATE_RANGE = (50.0, 500.0)
"""Sampling rates (Hz) accepted by :func:`resample_uniform`, for the record and for ``fs``.

Below 50 Hz the fifth harmonic of a 3.5 Hz bounce (17.5 Hz) nears the Nyquist
frequency and linear interpolation loses more than a quarter of it; phones
deliver 100-500 Hz, and nothing a bouncing person does needs more."""

RATE_TOLERANCE = 0.05
"""Relative margin at the ends of :data:`RATE_RANGE` for a record's *measured* rate.

A phone set to 50 Hz may deliver 49.8 Hz (its clock, dropped samples); such a record
is accepted (47.5-525 Hz). A requested ``fs`` must lie in :data:`RATE_RANGE` itself."""

MAX_GAP = 0.3
"""Longest interval (s) without samples that :func:`resample_uniform` bridges by interpolation.

About half of the slowest bouncing cycle (1/1.5 Hz = 0.67 s): a longer gap would
replace the better part of a cycle by a straight line."""

REPEATED_STAMPS = 0.1
"""Largest share of a record's rows that may repeat another row's time stamp (merged into their mean).

A phone delivers a duplicate now and then (batched delivery); a clock stuck for several samples, or one
coarser than the sampling (each stamp twice), repeats most of them, and merging would halve the rate and
average away the signal. Above this share the record is refused."""


CLOCK_MARGIN = 0.98
"""The samples are read on a regular clock when, so read, each is predicted from its two neighbours with at most
this fraction of the mean square error of the samples read at their stamps (the module's "When were the samples
taken?"). On 6000-sample phone records whose samples were taken at their stamps (0.3-1 ms of jitter) the ratio was
1.02-1.32; on records sampled on time whose stamps scattered by 0.3, 0.5, 1 and 2 ms, 0.97, 0.89, 0.73 and 0.51."""

REGULAR_SCATTER = 0.25
"""A regular clock is tried only when the stamps scatter about the fitted clock by less than this fraction of an
interval: beyond it the samples cannot be numbered from their stamps (1 ms at 400 Hz, 0.4 of an interval: the
clock's rate came out 0.1-3 % off, and the samples read on it were worse than at their stamps)."""

RATE_SEARCH = (0.03, 256)
"""Where the phone's interval is first looked for: within this fraction of the median interval, at which the phases
``2 pi t / dt`` of this many first stamps agree best (:func:`_coherent_interval`)."""


def _check_rate_option(name: str, value) -> float:
    """A rate option (Hz) within :data:`RATE_RANGE`, or an :class:`OptionError`."""
    lo, hi = RATE_RANGE
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
            or not math.isfinite(value) or not lo <= value <= hi:
        raise OptionError(f"{name}={value!r}: the sampling rate must be a number of Hz from {lo:g} to {hi:g}")
    return float(value)


def _check_arrays(time, acc, source: str) -> tuple:
    """``time`` (T,) and ``acc`` (T, k) as finite float arrays, or a :class:`RecordError`."""
    time = np.asarray(time, dtype=float)
    acc = np.asarray(acc, dtype=float)
    if time.ndim != 1 or acc.ndim not in (1, 2) or acc.shape[0] != time.size:
        raise RecordError(
            f"{source}: time has shape {time.shape} and acc {acc.shape}; expected (T,) and (T,), (T, 1) or (T, 3)"
        )
    acc2 = acc.reshape(time.size, -1)
    for name, values in (("time", time), ("acc", acc2)):
        bad = ~np.isfinite(values.reshape(time.size, -1)).all(axis=1)
        if bad.any():
            raise RecordError(f"{source}: {name} sample {int(np.argmax(bad)) + 1} is not a finite number")
    return time, acc2


def _fit_clock(stamps: np.ndarray, dt: float) -> tuple:
    """The phone's clock: ``(interval, sample numbers)`` from a line through the stamps.

    The stamps are numbered ``round((t - t0 - offset) / dt)``, dropped samples and
    all, and a least-squares line through stamps against numbers gives the
    interval. The numbering is right while the drift of the current ``dt`` over
    the stretch, plus the jitter, stays within half an interval; so it starts on
    the first 64 intervals with the given ``dt`` (:func:`_coherent_interval`'s) and doubles the stretch with
    each refined ``dt`` until it is the whole record (the slope of a line through
    ``M`` samples of jitter ``sd`` is good to ``sqrt(12) sd / M^1.5``, so the drift
    over the doubled stretch shrinks as ``1 / sqrt(M)``). The offset is the
    circular mean of the stamps' phases ``2 pi t / dt``, which centres the
    numbering on the jitter instead of on the first stamp's. On synthetic 20 s
    records with 0.5 % dropped samples this recovered the rate to 3e-5 for jitter
    up to 20 % of the interval (the median: 0.04-1 %).
    """
    elapsed = stamps - stamps[0]
    median = dt
    span = 64.0 * dt
    while True:  # about log2(T / 64) rounds, each vectorised, 2 T samples in all
        used = elapsed[elapsed <= span]
        offset = dt / (2.0 * np.pi) * np.angle(np.mean(np.exp(2j * np.pi * used / dt)))
        number = np.rint((used - offset) / dt)
        centred = number - number.mean()
        if centred @ centred > 0:
            dt = float(centred @ (used - used.mean()) / (centred @ centred))
        if not 0.9 * median < dt < 1.1 * median:  # no single clock (the rate changed midway): keep the median
            dt = median
            number = np.rint(used / dt)
            centred = number - number.mean()
        if used.size == elapsed.size:
            return dt, number
        span *= 2.0


def _coherent_interval(stamps: np.ndarray, dt: float) -> float:
    """The interval within ``RATE_SEARCH[0]`` of ``dt`` (s) at which the phases ``2 pi t / dt`` of the first
    ``RATE_SEARCH[1]`` stamps agree best (the length of their mean unit vector), as :func:`_fit_clock`'s start.

    The median of the intervals is pulled long by dropped samples (3 % dropped, stamps scattered by 1 ms at
    200 Hz: 1 % long), and a clock started 1 % off drifts by more than half an interval over the 64 samples
    :func:`_fit_clock` numbers first; the phases do not count the samples, so dropped ones do not move them. The
    trial intervals are spaced so that neighbours drift apart by a quarter interval over the stamps used. Where
    no trial's phases agree clearly better than chance (three times the sd of random phases' agreement: stamps
    scattered by a third of an interval or more), ``dt`` is returned.
    """
    share, count = RATE_SEARCH
    elapsed = stamps[:count + 1] - stamps[0]
    trials = dt * (1.0 + np.linspace(-share, share, int(np.ceil(8.0 * share * elapsed.size)) + 1))
    agreement = np.abs(np.mean(np.exp(2j * np.pi * elapsed[None, :] / trials[:, None]), axis=1))
    best = int(np.argmax(agreement))
    # stamps scattered by a third of an interval or more agree hardly better than chance (sd 1 / sqrt(n)): the median
    return float(trials[best]) if agreement[best] > 3.0 / np.sqrt(elapsed.size) else dt


def _regular_clock(time: np.ndarray, dt: float) -> tuple:
    """``(instants, numbers, interval)``: the samples in the file's order taken on a regular clock.

    Sample ``k`` (in the file's order) is number ``k`` plus the samples dropped before it. Those are where the
    stamps' lag behind ``k dt`` (in intervals) steps up by whole intervals: the steps of its isotonic
    (non-decreasing) regression, rounded about the lag's circular mean, which a stamp's scatter alone does not
    make (a numbering by rounding each stamp, as :func:`_fit_clock`'s, goes wrong on a stamp half an interval
    off). A least-squares line through the stamps against the numbers is the clock; the numbering is made
    again with its interval.
    """
    from scipy.optimize import isotonic_regression  # the clock is fitted only when a phone record is read

    k = np.arange(time.size)
    for _ in range(2):
        lag = (time - time[0]) / dt - k
        offset = np.angle(np.mean(np.exp(2j * np.pi * lag))) / (2.0 * np.pi)
        dropped = np.maximum.accumulate(np.rint(isotonic_regression(lag).x - offset))
        number = k + dropped - dropped[0]
        centred = number - number.mean()
        dt = float(centred @ (time - time.mean()) / (centred @ centred))
    return time.mean() + dt * centred, number, dt


def _local_scatter(stamps: np.ndarray, number: np.ndarray, dt: float) -> float:
    """The stamps' scatter (s, an sd) about the phone's clock where they are, not about one line through the record.

    The stamps' residuals about the line (``stamps - dt number``) are differenced twice along the samples: a
    white scatter of sd ``s`` gives second differences of sd ``sqrt(6) s``, taken robustly (1.4826 times their
    median absolute deviation, so that a sample numbered wrong does not count). A clock whose rate drifts slowly
    bends the residuals without scattering them: a real phyphox record of 300 s at 99.5 Hz, its intervals
    10.046 ms in the first quarter and 10.045 in the last, lay up to 5 ms about one line (sd 2.1 ms, which was
    reported as its scatter) and 0.0006 ms about its own clock.
    """
    residual = stamps - dt * number
    if residual.size < 3:
        return 0.0
    second = np.diff(residual, 2)
    return float(1.4826 * np.median(np.abs(second - np.median(second))) / np.sqrt(6.0))


def _neighbour_error(instants: np.ndarray, values: np.ndarray) -> float:
    """Mean square error of each sample but the ends predicted by the straight line between its two neighbours,
    the samples taken at ``instants`` (s, increasing)."""
    weight = ((instants[1:-1] - instants[:-2]) / (instants[2:] - instants[:-2]))[:, None]
    return float(np.mean((values[1:-1] - values[:-2] * (1.0 - weight) - values[2:] * weight) ** 2))


def _check_max_gap(max_gap) -> None:
    """Refuse a ``max_gap`` that is not a positive, finite number of seconds (an :class:`OptionError`)."""
    if isinstance(max_gap, bool) or not isinstance(max_gap, (int, float)) \
            or not (math.isfinite(max_gap) and max_gap > 0):
        raise OptionError(f"max_gap={max_gap!r}: give the longest gap to interpolate across in s, e.g. {MAX_GAP:g}")


def _count_backwards(time: np.ndarray, max_gap: float, source: str) -> int:
    """The number of steps back in time in the record's order; a step back longer than ``max_gap`` is refused."""
    steps = np.diff(time)
    if steps.size and steps.min() < -max_gap:
        k = int(np.argmin(steps))
        raise RecordError(
            f"{source}: time jumps back by {-steps[k]:.4g} s at row {k + 2} (t = {time[k + 1]:.4g} s); "
            "a record must come from one clock without resets"
        )
    return int(np.count_nonzero(steps < 0))


def _check_clock_runs(time: np.ndarray, n_backwards: int, source: str) -> None:
    """Refuse a clock that runs backwards (most steps back) or repeats its stamps (over :data:`REPEATED_STAMPS`)."""
    steps = time.size - 1
    if n_backwards > steps / 2:
        raise RecordError(
            f"{source}: time runs backwards ({n_backwards} of {steps} steps go back; a phone's samples out of order "
            "are a few in a thousand): the time column must increase (is the file's order reversed?)"
        )
    repeated = time.size - np.unique(time).size
    if repeated > REPEATED_STAMPS * time.size:
        raise RecordError(
            f"{source}: time stamps repeat ({repeated} of {time.size} rows, {100 * repeated / time.size:.0f} %, "
            f"share the stamp of another; over {100 * REPEATED_STAMPS:g} % is not a phone's clock): the clock is "
            "stuck or coarser than the samples; export the sensor's own time stamps"
        )


def _merge_duplicates(time: np.ndarray, acc: np.ndarray) -> tuple:
    """``(stamps, values)``: the distinct time stamps in order, each with the mean of its samples (stable sort)."""
    order = np.argsort(time, kind="stable")
    stamps, first, counts = np.unique(time[order], return_index=True, return_counts=True)
    return stamps, np.add.reduceat(acc[order], first, axis=0) / counts[:, None]


def _median_interval(stamps: np.ndarray, source: str) -> tuple:
    """``(steps, dt)``: the intervals between the stamps and their median (s), or a :class:`RecordError`.

    Fewer than 3 stamps, or a rate outside :data:`RATE_RANGE` (within
    :data:`RATE_TOLERANCE`), is refused.
    """
    lo, hi = RATE_RANGE
    if stamps.size < 3:
        raise RecordError(
            f"{source}: only {stamps.size} distinct time stamps; a record needs at least one bouncing cycle"
        )
    steps = np.diff(stamps)
    dt = float(np.median(steps))
    if not lo * (1.0 - RATE_TOLERANCE) <= 1.0 / dt <= hi * (1.0 + RATE_TOLERANCE):
        raise RecordError(
            f"{source}: sampled at {1.0 / dt:.4g} Hz (median step {dt:.4g} s); accepted rates are {lo:g}-{hi:g} Hz"
        )
    return steps, dt


def _largest_gap(stamps: np.ndarray, steps: np.ndarray, max_gap: float, source: str) -> int:
    """The index of the longest interval; one longer than ``max_gap`` is refused, naming its time and length."""
    k = int(np.argmax(steps))
    if steps[k] > max_gap:
        raise RecordError(
            f"{source}: no samples for {steps[k]:.3g} s after t = {stamps[k]:.4g} s; gaps longer than "
            f"{max_gap:g} s cannot be interpolated: use the record on either side"
        )
    return k


def _interpolate(stamps: np.ndarray, values: np.ndarray, steps: np.ndarray, rate: float) -> tuple:
    """``(grid, values on it)``: the grid ``t0 + n / rate`` up to the last stamp, linearly interpolated.

    One ``searchsorted`` and one weighted sum for all axes (step 5 of the module's
    description).
    """
    n_out = int(math.floor((stamps[-1] - stamps[0]) * rate + 1e-9)) + 1
    grid = stamps[0] + np.arange(n_out) / rate
    left = np.clip(np.searchsorted(stamps, grid, side="right") - 1, 0, stamps.size - 2)
    weight = np.clip((grid - stamps[left]) / steps[left], 0.0, 1.0)[:, None]
    return grid, values[left] * (1.0 - weight) + values[left + 1] * weight


def resample_uniform(time, acc, fs=None, *, max_gap: float = MAX_GAP, source: str = "<arrays>") -> tuple:
    """Put an accelerometer record with a phone's irregular clock onto a uniform time grid.

    Orders the samples, merges duplicate time stamps, finds the phone's rate
    (a least-squares line through the stamps), refuses gaps longer than
    ``max_gap``, tells whether the samples were taken at their stamps or on the
    phone's regular clock and interpolates linearly onto the grid: the steps, and
    what linear interpolation loses at each rate, are set out in the module's
    description (:mod:`smd_statespace.accelerometer.resampling`).

    Parameters
    ----------
    time : array_like, shape (T,)
        Time stamps (s), as recorded.
    acc : array_like, shape (T,), (T, 1) or (T, 3)
        Accelerations at those times (any unit; m/s^2 in this library).
    fs : float, optional
        Rate of the uniform grid (Hz), within :data:`RATE_RANGE`; default: the
        record's own nominal rate. A grid much coarser than the record aliases its
        content above ``fs / 2`` (linear interpolation is no anti-aliasing filter):
        resample at the record's rate and decimate
        (:func:`smd_statespace.signals.decimate_record`) instead.
    max_gap : float, default :data:`MAX_GAP`
        Longest interval without samples that is interpolated across (s).
    source : str, default "<arrays>"
        Name used in error messages (the file name).

    Returns
    -------
    time : ndarray, shape (N,)
        Uniform grid (s) from the first time stamp, at ``fs``.
    acc : ndarray, same trailing shape as the input
        The accelerations on the grid.
    info : dict
        What was done: ``fs`` (Hz, the grid's rate), ``fs_nominal`` (Hz, the
        record's), ``n_samples_in`` and ``n_samples_out``, ``n_duplicates``
        (samples merged into another with the same stamp), ``n_backwards``
        (steps back in time in the record's order), ``n_dropped`` (samples missing
        at the nominal rate: the span of the sample numbers minus the samples),
        ``largest_gap`` (s, the longest interval) and ``largest_gap_at`` (s, the
        time stamp it starts at), ``jitter_sd`` (s, standard deviation of the time
        stamps about the phone's clock where they are: :func:`_local_scatter`), ``samples_at`` (``"stamps"``: each
        sample read at its stamp; ``"regular clock"``: the samples, in the file's
        order, taken on the phone's regular clock and the stamps' scatter left out;
        the module's "When were the samples taken?"), ``start`` (s, the grid's first
        time on the stamps' scale: the first stamp, or the regular clock's first instant).

    Raises
    ------
    RecordError
        Arrays of mismatched shapes or with non-finite values, fewer than 3
        distinct time stamps, a record rate outside :data:`RATE_RANGE`, a gap
        longer than ``max_gap`` (naming its time and length), a jump back in
        time longer than ``max_gap``, a clock that runs backwards (most steps
        back) or repeats its stamps (over :data:`REPEATED_STAMPS` of the rows).
    OptionError
        ``fs`` outside :data:`RATE_RANGE` or ``max_gap`` not a positive number.
    """
    if fs is not None:
        fs = _check_rate_option("fs", fs)
    _check_max_gap(max_gap)
    squeeze = np.ndim(acc) == 1
    time, acc2 = _check_arrays(time, acc, source)
    n_backwards = _count_backwards(time, max_gap, source)
    _check_clock_runs(time, n_backwards, source)
    stamps, merged = _merge_duplicates(time, acc2)
    steps, dt = _median_interval(stamps, source)
    k = _largest_gap(stamps, steps, max_gap, source)
    dt, number = _fit_clock(stamps, _coherent_interval(stamps, dt))
    jitter = _local_scatter(stamps, number, dt)
    instants, values, samples_at = stamps, merged, "stamps"
    regular = _regular_clock(time, dt) if jitter < REGULAR_SCATTER * dt else None
    if regular is not None and _neighbour_error(regular[0], acc2) < CLOCK_MARGIN * _neighbour_error(stamps, merged):
        (instants, number, dt), values, samples_at = regular, acc2, "regular clock"
    fs_nominal = 1.0 / dt
    rate = fs_nominal if fs is None else fs
    grid, values = _interpolate(instants, values, np.diff(instants), rate)
    info = {
        "fs": float(rate),
        "fs_nominal": float(fs_nominal),
        "n_samples_in": int(time.size),
        "n_samples_out": int(grid.size),
        "n_duplicates": int(time.size - stamps.size),
        "n_backwards": n_backwards,
        "n_dropped": int(max(number.max() - number.min() + 1 - stamps.size, 0)),
        "largest_gap": float(steps[k]),
        "largest_gap_at": float(stamps[k]),
        "jitter_sd": jitter,
        "samples_at": samples_at,
        "start": float(grid[0]),
    }
    return grid, (values[:, 0] if squeeze else values), info
