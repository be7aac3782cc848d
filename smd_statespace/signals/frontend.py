"""A record as a lab exports it, made ready for the fit: mains hum, the bouncing bouts, trimming.

A lab's export is sampled at 500-2000 Hz; the person stands still, starts bouncing over a few cycles, bounces, stops
and stands again; the plate picks up mains hum (50 or 60 Hz and their harmonics) and its zero drifts slowly. Fitting
the whole record as bouncing pulls the answer off (standing fitted as bouncing: up to 75 %), and a 50 Hz hum
decimated to 100 Hz sits on the new Nyquist frequency (innovations alternating in sign at every lag). The steps:

1. :func:`mains_hum` finds hum: a line at a harmonic of 50 or 60 Hz (below the Nyquist frequency) whose power is
   :data:`LINE_RATIO` times its neighbourhood's in a Welch spectrum; it refines the fundamental and follows each
   line's amplitude and phase (a sinusoid fitted in a sliding Hann window of :data:`HUM_WINDOW`, by complex
   demodulation, to the force high-passed at :data:`HUM_HIGHPASS`, clear of the bouncing band); :func:`remove_hum`
   subtracts them.
2. :func:`find_bouts` splits the record into standing, bouncing, ramps, other movement and no contact, and reads
   the standing levels before and after (body weight, the drift of the plate's zero) and the noise while standing.
3. :func:`trim_record` restricts a record to a span (a steady bout).
4. :func:`front_end` runs them with :func:`~smd_statespace.signals.decimate_record` (whose guard band keeps the new
   Nyquist frequency empty).

``benchmarks/frontend_speed.py`` measures it (40 s at 1000 Hz: about 0.07 s in all), ``frontend_spans.py`` its spans.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..applicability import ACTIVE_SPREAD, CONTACT_FRACTION, RHYTHM_MIN, flights, repeating_period, runs
from ..errors import OptionError, RecordError
from ..io import G, Record
from .decimation import RECORD_RATE, decimate_record

__all__ = ["MAINS", "LINE_RATIO", "HUM_WINDOW", "HUM_HIGHPASS", "ACTIVE_LEVEL", "STEADY_SWING",
           "MIN_BOUT_CYCLES", "MAX_RAMP_CYCLES", "Hum", "Span", "Bout", "Bouts", "FrontEnd", "mains_hum",
           "remove_hum", "find_bouts", "trim_record", "front_end"]

MAINS = (50.0, 60.0)
"""Nominal mains frequencies (Hz) whose harmonics are searched for hum."""

LINE_RATIO = 10.0
"""A hum line's Welch power over the median of its neighbourhood (1.5-6 Hz away) at least this."""

HUM_WINDOW = 4.0
"""Length (s) of the Hann window over which each hum line's amplitude and phase are fitted."""

HUM_HIGHPASS = 35.0
"""Cut-off (Hz) of the zero-phase high-pass applied before the hum fit: the bouncing band stays out."""

ACTIVE_LEVEL = ACTIVE_SPREAD
"""RMS of the 0.7-10 Hz force over 1 s, as a fraction of body weight, above which the person moves: the applicability
check's :data:`~smd_statespace.applicability.ACTIVE_SPREAD` (0.03), so that a bout kept here is not counted as no
cycles there."""

STEADY_SWING = 0.9
"""An end cycle of a bout is steady when its swing reaches this fraction of its reference (:func:`find_bouts`)."""

MIN_BOUT_CYCLES = 4
"""Fewest steady cycles that make a rhythmic movement a bouncing bout."""

MAX_RAMP_CYCLES = 4
"""Most cycles at each end of a bout left out as ramp for a small swing. Starting and stopping grow the force from
nothing (or let it die) over 1-3 cycles; a decline over many is the person tiring, and bouncing: against the bout's
median alone, a person tiring by 20-35 % lost the last third of the bout (``benchmarks/frontend_spans.py``)."""

_REFERENCE_CYCLES = 5  # an end cycle's reference: the median swing of the next 5 inward (ramp ones a minority)
_MIN_STANDING = 0.5  # s: quieter gaps inside movement are movement
_MARGIN = 0.25  # s of standing next to movement left out of the levels


def _signal():
    from scipy import signal  # imported here: scipy.signal takes ~0.5 s (not needed to start)

    return signal


@dataclass(frozen=True)
class Hum:
    """Mains hum found in a record.

    Attributes
    ----------
    found : bool
        True when at least one harmonic of 50 or 60 Hz is a line.
    frequency : float
        The refined fundamental (Hz); nan when nothing was found.
    harmonics : ndarray
        Frequencies (Hz) of the fundamental's harmonics below the Nyquist frequency.
    amplitudes : ndarray
        Their amplitudes (N, of a sinusoid; the median over time of the sliding fit).
    lines : ndarray of bool
        Which harmonics are lines (only these are removed).
    waveform : ndarray, shape (T,)
        The fitted hum of the lines (N), sample by sample: what :func:`remove_hum` subtracts.
    """

    found: bool
    frequency: float
    harmonics: np.ndarray
    amplitudes: np.ndarray
    lines: np.ndarray
    waveform: np.ndarray = field(repr=False)

    def describe(self) -> str:
        """One line: the hum found, or that there is none."""
        if not self.found:
            return "no mains hum (no line at a harmonic of 50 or 60 Hz)"
        parts = ", ".join(f"{f:.0f} Hz {a:.2g} N" for f, a, line in
                          zip(self.harmonics, self.amplitudes, self.lines) if line)
        return f"mains hum at {self.frequency:.3f} Hz: {parts}"


def _highpass(x, fs):
    sos = _signal().butter(6, HUM_HIGHPASS, btype="highpass", fs=fs, output="sos")
    return _signal().sosfiltfilt(sos, x), sos


def _line_ratios(freq, power, centres):
    """Power at each centre (the highest bin within the tolerance) over its neighbourhood's median."""
    k = np.maximum(np.round(centres / MAINS[0]), 1.0)
    tolerance = np.minimum(0.3 * k, 1.0)[:, None] + (freq[1] - freq[0])
    d = np.abs(freq[None, :] - centres[:, None])
    peak = np.where(d <= tolerance, power[None, :], 0.0).max(axis=1)
    around = np.where((d > tolerance + 1.0) & (d <= tolerance + 6.0), power[None, :], np.nan)
    return peak / np.nanmedian(around, axis=1)


def _refine(x, fs, base, harmonics, lines):
    """The fundamental from the lines' peaks in a zero-padded Hann spectrum (parabola on the log)."""
    n, size = x.size, 4 * x.size
    spectrum = np.abs(np.fft.rfft(x * np.hanning(n), size))
    step = fs / size
    estimates, weights = [], []
    for k, centre in zip(np.round(harmonics / base).astype(int)[lines], harmonics[lines]):
        lo, hi = int((centre - min(0.3 * k, 1.0)) / step), int((centre + min(0.3 * k, 1.0)) / step) + 1
        i = lo + int(np.argmax(spectrum[lo:hi]))
        a, b, c = np.log(spectrum[i - 1:i + 2] + 1e-300)
        shift = 0.5 * (a - c) / (a - 2 * b + c) if a - 2 * b + c < 0 else 0.0
        estimates.append((i + float(np.clip(shift, -0.5, 0.5))) * step / k)
        weights.append((k * spectrum[i]) ** 2)
    return float(np.average(estimates, weights=weights))


def _envelopes(x, fs, freqs, window, sos):
    """Complex amplitudes ``a_k(t)`` with ``x ~ sum 2 Re(a_k e^{2 pi i f_k t})``: a Hann-weighted local fit."""
    signal = _signal()
    length = max(int(round(window * fs)) | 1, 3)
    kernel = np.hanning(length + 2)[1:-1]
    phase = np.exp(-2j * np.pi * np.outer(freqs, np.arange(x.size) / fs))
    local = signal.oaconvolve(phase * x[None, :], kernel[None, :], mode="same", axes=1)
    norm = signal.oaconvolve(np.ones(x.size), kernel, mode="same")
    gain = np.abs(signal.sosfreqz(sos, worN=freqs, fs=fs)[1]) ** 2  # sosfiltfilt's gain
    return local / norm[None, :] / gain[:, None], phase


def mains_hum(record: Record, window: float = HUM_WINDOW) -> Hum:
    """Find mains hum (50 or 60 Hz and their harmonics up to the Nyquist frequency) in the force.

    Parameters
    ----------
    record : Record
        The measurement (force in N), sampled fast enough to hold 50 Hz (above 102 Hz).
    window : float
        Length (s) of the sliding Hann window over which each line's amplitude and phase are fitted (slowly varying
        amplitude and a mains frequency that wanders are followed).

    Returns
    -------
    Hum
        Whether hum was found, its fundamental (Hz), the harmonics' amplitudes (N), which are lines, and the fitted
        hum waveform.

    Notes
    -----
    A harmonic is a line when its Welch power (4 s Hann segments) is :data:`LINE_RATIO` times the median of the bins
    1.5-6 Hz away. Of 50 and 60 Hz the base with more lines wins (300 Hz is a harmonic of both). The fundamental is
    refined from the lines' peaks in a zero-padded spectrum of the whole record; each harmonic's amplitude is the
    median over time of the sliding fit's ``2 |a_k(t)|``.
    """
    if not (isinstance(window, (int, float)) and math.isfinite(window) and window > 0):
        raise OptionError(f"window={window!r} must be a positive duration in s")
    fs = record.fs
    x = np.asarray(record.force, float) - float(np.mean(record.force))
    empty = Hum(False, float("nan"), np.zeros(0), np.zeros(0), np.zeros(0, bool), np.zeros(x.size))
    if fs / 2 <= MAINS[0] + 1.0 or x.size < 2 * fs:
        return empty
    filtered, sos = _highpass(x, fs)
    freq, power = _signal().welch(filtered, fs, nperseg=min(x.size, int(2 ** np.ceil(np.log2(4 * fs)))))
    best = None
    for base in MAINS:
        harmonics = base * np.arange(1, int((fs / 2 - 7.0) // base) + 1)
        if harmonics.size == 0:
            continue
        ratios = _line_ratios(freq, power, harmonics)
        lines = ratios > LINE_RATIO
        score = (int(lines.sum()), float(np.sum(np.log(ratios[lines]))))
        if lines.any() and (best is None or score > best[0]):
            best = (score, base, harmonics, lines)
    if best is None:
        return empty
    _, base, harmonics, lines = best
    f0 = _refine(filtered, fs, base, harmonics, lines)
    harmonics = f0 * np.round(harmonics / base)
    amplitude, phase = _envelopes(filtered, fs, harmonics, window, sos)
    waveform = 2.0 * np.real(np.sum(amplitude[lines] * np.conj(phase[lines]), axis=0))
    return Hum(True, f0, harmonics, np.median(2.0 * np.abs(amplitude), axis=1), lines, waveform)


def remove_hum(record: Record, hum: Hum | None = None) -> Record:
    """The record with its mains hum's lines subtracted (``record`` itself when there is none).

    Parameters
    ----------
    record : Record
    hum : Hum, optional
        From :func:`mains_hum` on this record (found again when not given).

    Returns
    -------
    Record
        The force less :attr:`Hum.waveform`; time, floor acceleration and the rest unchanged.

    Notes
    -----
    A sliding Hann-weighted least-squares sinusoid at each line (complex demodulation), chosen over zero-phase
    notches (``iirnotch``) by ``benchmarks/frontend_speed.py``: at a 4 s window it leaves 2 % of a wandering hum,
    changes the band below 30 Hz by under 0.001 N and takes less of the noise than notches of Q 25-100 (which leave
    2-5 % and change it by up to 0.01 N).
    """
    hum = mains_hum(record) if hum is None else hum
    if not hum.found:
        return record
    if hum.waveform.size != record.force.size:
        raise RecordError(f"{record.source}: the hum has {hum.waveform.size} samples, the record "
                          f"{record.force.size}; find it on this record (mains_hum)")
    return replace(record, force=np.asarray(record.force, float) - hum.waveform)


@dataclass(frozen=True)
class Span:
    """One part of a record.

    Attributes
    ----------
    kind : str
        ``standing``, ``bouncing`` (the steady part of a bout), ``ramp`` (starting or stopping), ``movement``
        (stepping on or off, a jump, a squat) or ``no_contact`` (under
        :data:`~smd_statespace.applicability.CONTACT_FRACTION` of body weight).
    start, end : float
        Times (s) of its first and last sample, on the record's own time axis.
    """

    kind: str
    start: float
    end: float


@dataclass(frozen=True)
class Bout:
    """One bout of bouncing: its steady part, trimmed to whole cycles, and its ramps.

    Attributes
    ----------
    start, end : float
        The steady part (s): from the force peak opening the first steady cycle to the peak closing the last one.
    period : float
        The bouncing period (s), from the autocorrelation of the bout.
    cycles : int
        Steady cycles (peak to peak) between ``start`` and ``end``.
    ramp_in, ramp_out : tuple of float or None
        ``(start, end)`` (s) of the movement before and after the steady part (starting and stopping to bounce:
        :func:`find_bouts`), left out of the span.
    """

    start: float
    end: float
    period: float
    cycles: int
    ramp_in: tuple | None = None
    ramp_out: tuple | None = None

    @property
    def span(self) -> tuple:
        """``(start, end)`` (s) of the steady part, for :func:`trim_record`."""
        return (self.start, self.end)


@dataclass(frozen=True)
class Bouts:
    """A record split into its parts by :func:`find_bouts`.

    Attributes
    ----------
    source : str
        The record's name.
    segments : tuple of Span
        Every part of the record, in time order.
    bouts : tuple of Bout
        The bouncing bouts (empty when the person never bounces).
    level_before, level_after : float
        Mean force (N) while standing before the first bout and after the last one (nan when there is no such
        standing; with no bout, ``level_before`` is the mean of all standing).
    noise_sd : float
        Standard deviation (N) of the force's white noise per sample while standing (at the record's rate; from
        successive differences, robust to sway).
    """

    source: str
    segments: tuple
    bouts: tuple
    level_before: float
    level_after: float
    noise_sd: float

    @property
    def found(self) -> bool:
        """True when there is at least one bout of bouncing."""
        return bool(self.bouts)

    @property
    def mass(self) -> float:
        """Body mass (kg) from the standing level before bouncing (``level / g``; nan without one)."""
        return self.level_before / G

    @property
    def drift(self) -> float:
        """Drift of the plate's zero (N): standing level after less before (nan without both)."""
        return self.level_after - self.level_before

    def _spans(self, kind) -> str:
        spans = [s for s in self.segments if s.kind == kind]
        return " and ".join(f"{s.start:.1f}-{s.end:.1f} s" for s in spans[:3]) + (" ..." if len(spans) > 3 else "")

    def describe(self) -> str:
        """One line: where the person bounces, and what standing says."""
        stand = self._spans("standing") or "none"
        if not self.found:
            other = [s.kind for s in self.segments if s.kind not in ("standing",)]
            rest = f"; also {', '.join(sorted(set(other)))}" if other else ""
            return f"{self.source}: no bouncing found; standing {stand}{rest}"
        bouts = ", ".join(f"{b.start:.1f}-{b.end:.1f} s ({b.cycles} cycles of {b.period:.2f} s)" for b in self.bouts)
        levels = [f"{name} {value:.1f} N" for name, value in (("before", self.level_before),
                                                                ("after", self.level_after)) if np.isfinite(value)]
        extra = f"; mass {self.mass:.1f} kg" if np.isfinite(self.mass) else ""
        extra += f", zero drift {self.drift:+.1f} N" if np.isfinite(self.drift) else ""
        ramps = self._spans("ramp")
        return (f"{self.source}: bouncing {bouts}" + (f" (ramps {ramps} left out)" if ramps else "")
                + f"; standing {stand}" + (f" ({', '.join(levels)}{extra}; noise sd {self.noise_sd:.2g} N)"
                                           if levels else ""))

    def require(self) -> Bouts:
        """``self`` when a bout was found; else a one-line :class:`~smd_statespace.errors.RecordError` saying why."""
        if not self.found:
            raise RecordError(f"{self.describe()}: nothing to identify the person from")
        return self


def _moving_mean(x, n):
    c = np.cumsum(np.r_[0.0, x])
    lo = np.clip(np.arange(x.size) - n // 2, 0, x.size)
    hi = np.clip(np.arange(x.size) + n - n // 2, 0, x.size)
    return (c[hi] - c[lo]) / (hi - lo)


def _states(force, fs, weight):
    """Per sample: 0 no contact, 1 standing, 2 moving; and the 20 Hz low-passed force."""
    signal = _signal()
    low = signal.sosfiltfilt(signal.butter(4, min(20.0, 0.4 * fs), fs=fs, output="sos"), force)
    band = signal.sosfiltfilt(signal.butter(2, [0.7, min(10.0, 0.4 * fs)], "bandpass", fs=fs, output="sos"), force)
    rms = np.sqrt(_moving_mean(band ** 2, max(int(round(fs)), 3)))
    state = np.where(rms > ACTIVE_LEVEL * weight, 2, 1)
    starts, stops = runs(low < CONTACT_FRACTION * weight)
    for a, b in zip(starts, stops):  # a dip that is not a flight (applicability.flights) is movement
        state[a:b] = 2
    for a, b in zip(*flights(low / weight, 1.0 / fs)):
        state[a:b] = 0
    starts, stops = runs(state == 1)  # short quiet gaps inside movement are movement
    for a, b in zip(starts, stops):
        if (b - a) / fs < _MIN_STANDING and a > 0 and b < state.size:
            state[a:b] = 2
    return state, low


def _ramp(swings, regular):
    """Cycles opening ``swings`` that are ramp: off the period, or among the first MAX_RAMP_CYCLES low ones."""
    n = low = 0  # low: the cycles taken for their swing alone
    typical = np.median(swings)
    while n + 1 < swings.size and not (regular[n] and (low >= MAX_RAMP_CYCLES or swings[n] >= STEADY_SWING * min(
            typical, np.median(swings[n + 1:n + 1 + _REFERENCE_CYCLES])))):
        low, n = low + bool(regular[n]), n + 1
    return n


def _bout(time, low, a, b, fs):
    """The bout in samples ``a:b`` of the low-passed force, or None when it is no bouncing."""
    period, rhythm = repeating_period(low[a:b], 1.0 / fs)  # the applicability check's period and rhythm
    if not (np.isfinite(period) and rhythm >= RHYTHM_MIN):
        return None
    x = low[a:b]
    swing_all = np.subtract(*np.percentile(x, [99, 1]))
    peaks, _ = _signal().find_peaks(x, distance=max(int(0.6 * period * fs), 1), prominence=0.2 * swing_all)
    if peaks.size < MIN_BOUT_CYCLES + 1:
        return None
    swings = 0.5 * (x[peaks[:-1]] + x[peaks[1:]]) - np.minimum.reduceat(x, peaks)[:-1]
    regular = np.abs(np.diff(peaks) / fs / period - 1.0) < 0.3
    first, last = _ramp(swings, regular), swings.size - 1 - _ramp(swings[::-1], regular[::-1])
    if last < first or regular[first:last + 1].sum() < MIN_BOUT_CYCLES:
        return None
    start, end = time[a + peaks[first]], time[a + peaks[last + 1]]
    ramp_in = (float(time[a]), float(start)) if peaks[first] > 0 else None
    ramp_out = (float(end), float(time[b - 1])) if a + peaks[last + 1] < b - 1 else None
    return Bout(float(start), float(end), period, last - first + 1, ramp_in, ramp_out)


def _levels(force, state, bouts, time, fs):
    """Mean standing force before the first bout and after the last (N), and the noise sd (N)."""
    standing = state == 1
    starts, stops = runs(standing)
    margin = int(round(_MARGIN * fs))
    used = np.zeros_like(standing)
    for a, b in zip(starts, stops):
        used[a + (margin if a > 0 else 0):b - (margin if b < standing.size else 0)] = True
    steps = np.diff(force)[used[1:] & used[:-1]]
    noise = float(1.4826 * np.median(np.abs(steps - np.median(steps))) / np.sqrt(2)) if steps.size > 10 else np.nan
    if not bouts:
        return (float(force[used].mean()) if used.any() else np.nan), np.nan, noise
    before, after = used & (time < bouts[0].start), used & (time > bouts[-1].end)
    mean = (lambda m: float(force[m].mean()) if m.sum() >= fs * 0.5 else np.nan)
    return mean(before), mean(after), noise


def find_bouts(record: Record) -> Bouts:
    """Split a record into standing, bouncing (steady and ramps), other movement and no contact.

    Parameters
    ----------
    record : Record
        The measurement (force in N; ``record.mass`` in kg scales the thresholds), best with its mains hum removed
        (:func:`remove_hum`).

    Returns
    -------
    Bouts
        The parts in time order, the bouts of bouncing (none: :meth:`Bouts.require` refuses in words), the standing
        levels before and after (N) and the noise sd while standing.

    Notes
    -----
    Per sample, the force low-passed at 20 Hz under
    :data:`~smd_statespace.applicability.CONTACT_FRACTION` of ``M g`` for
    :data:`~smd_statespace.applicability.CONTACT_MIN_DURATION` or more, at about zero
    (:func:`~smd_statespace.applicability.flights`), is no contact; the RMS over 1 s of the force band-passed to
    0.7-10 Hz above :data:`ACTIVE_LEVEL` of ``M g`` is
    movement (quiet gaps under 0.5 s inside movement too); the rest is standing. A movement is a bout of bouncing
    when its force repeats (autocorrelation >= 0.5 at a period of 0.2-1.25 s) over at least :data:`MIN_BOUT_CYCLES`
    steady cycles. A bout is cut at force peaks: from each end inwards, cycles off the period by 30 % or more, and
    up to :data:`MAX_RAMP_CYCLES` cycles whose swing is under :data:`STEADY_SWING` of both the median of the next 5
    inward and the bout's median, are ramp (starting and stopping: the force growing from nothing over 1-3 cycles,
    or dying) and left out of the span (not steady bouncing); a slow decline (tiring) or a swell is bouncing, and
    the interior is kept whole. The standing levels leave out 0.25 s next to any movement.

    Examples
    --------
    >>> import numpy as np
    >>> from smd_statespace.io import make_record
    >>> t = np.arange(0.0, 20.0, 0.001)
    >>> force = 686.5 * (1 + 0.4 * ((t > 5) & (t < 15)) * np.sin(2 * np.pi * 2.0 * (t - 5)))
    >>> bouts = find_bouts(make_record(t, force, 70.0))
    >>> [(s.kind, round(s.start, 1), round(s.end, 1)) for s in bouts.segments if s.kind != "ramp"]
    [('standing', 0.0, 4.5), ('bouncing', 5.1, 14.6), ('standing', 15.5, 20.0)]
    """
    time, force, fs = np.asarray(record.time, float), np.asarray(record.force, float), record.fs
    state, low = _states(force, fs, record.mass * G)
    segments, bouts = [], []
    starts = np.flatnonzero(np.r_[True, state[1:] != state[:-1]])
    for a, b in zip(starts, np.r_[starts[1:], state.size]):
        kind = {0: "no_contact", 1: "standing", 2: "movement"}[int(state[a])]
        bout = _bout(time, low, a, b, fs) if kind == "movement" else None
        if bout is None:
            segments.append(Span(kind, float(time[a]), float(time[b - 1])))
            continue
        bouts.append(bout)
        segments += ([Span("ramp", *bout.ramp_in)] if bout.ramp_in else []) + [Span("bouncing", *bout.span)]
        segments += [Span("ramp", *bout.ramp_out)] if bout.ramp_out else []
    before, after, noise = _levels(force, state, bouts, time, fs)
    return Bouts(str(record.source), tuple(segments), tuple(bouts), before, after, noise)


def trim_record(record: Record, span) -> Record:
    """The record restricted to ``span``, on its own time axis (times are not re-based).

    Parameters
    ----------
    record : Record
    span : (float, float), Span or Bout
        Start and end (s) on the record's time axis; samples with ``start <= t <= end`` (to half a sample) are kept.

    Returns
    -------
    Record
        Time, force, floor acceleration and any array in ``record.extra`` of the record's length cut alike; times
        keep their values, so spans, findings and figures of the trimmed record read as on the whole one.

    Raises
    ------
    OptionError
        ``span`` is not two numbers ``start < end``.
    RecordError
        ``span`` reaches outside the record, or holds fewer than 3 samples.
    """
    try:
        start, end = (float(v) for v in ((span.start, span.end) if hasattr(span, "start") else span))
    except (TypeError, ValueError):
        raise OptionError(f"span={span!r} must be a pair (start, end) of times in s") from None
    if not (math.isfinite(start) and math.isfinite(end) and start < end):
        raise OptionError(f"span={span!r} must satisfy start < end (s)")
    time = np.asarray(record.time, float)
    half = 0.5 * record.dt
    if start < time[0] - half or end > time[-1] + half:
        raise RecordError(f"{record.source}: span=({start:g}, {end:g}) s reaches outside the record "
                          f"({time[0]:g}-{time[-1]:g} s)")
    keep = (time >= start - half) & (time <= end + half)
    if keep.sum() < 3:
        raise RecordError(f"{record.source}: span=({start:g}, {end:g}) s holds {int(keep.sum())} samples; "
                          "at least 3 are needed")
    extra = {k: (v[keep] if isinstance(v, np.ndarray) and v.shape[:1] == (time.size,) else v)
             for k, v in (record.extra or {}).items()}
    floor_acc = None if record.floor_acc is None else np.asarray(record.floor_acc)[keep]
    return replace(record, time=time[keep], force=np.asarray(record.force)[keep], floor_acc=floor_acc, extra=extra)


@dataclass(frozen=True)
class FrontEnd:
    """What :func:`front_end` found and made.

    Attributes
    ----------
    hum : Hum
    bouts : Bouts
        Found on ``clean``, the record with its hum removed (at its own rate).
    clean : Record
    decimated : Record
        ``clean`` decimated whole (:func:`~smd_statespace.signals.decimate_record`).
    factor : int
        The decimation factor (1: unchanged).
    """

    hum: Hum
    bouts: Bouts
    clean: Record
    decimated: Record
    factor: int

    def steady(self, index: int = 0) -> Record:
        """The decimated record trimmed to bout ``index``'s steady part (a :class:`RecordError` without bouts)."""
        bouts = self.bouts.require().bouts
        if not -len(bouts) <= index < len(bouts):
            raise OptionError(f"index={index!r}: the record has {len(bouts)} bout(s) of bouncing")
        return trim_record(self.decimated, bouts[index].span)


def front_end(record: Record, rate=RECORD_RATE) -> FrontEnd:
    """Hum found and removed, bouts found, the whole record decimated: a lab export made ready.

    Parameters
    ----------
    record : Record
    rate : float or None
        As :func:`~smd_statespace.signals.decimate_record` (Hz; None keeps every sample).

    Returns
    -------
    FrontEnd
        ``front_end(record).steady()`` is the first bout's steady part, hum-free and decimated (decimated whole
        before trimming, so the decimation's end effects stay outside the bout).
    """
    hum = mains_hum(record)
    clean = remove_hum(record, hum)
    bouts = find_bouts(clean)
    decimated, factor, _ = decimate_record(clean, rate)
    return FrontEnd(hum, bouts, clean, decimated, factor)
