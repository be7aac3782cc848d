"""When does each force cycle start? The phase of the biomechanical force over a record.

The record-level model (:mod:`smd_statespace.person.model`) writes the force
of Eq. 4 with a bouncing phase ``theta(t)`` that advances by ``2 pi`` per force
cycle and is linear within a cycle (each cycle has its own bouncing frequency
``f_b``). The cycle boundaries are not observed. A GRF peak is not a force-cycle
boundary: the peak moves within the cycle when the force's shape or the
person's response changes from cycle to cycle. Two estimates are offered:

``"peaks"``
    GRF peak to GRF peak, as the article cuts its cycles (Section 4).
``"template"``
    Start from the peaks, then move every boundary to where the measured
    acceleration best matches the record's own mean cycle (a Fourier template
    of the acceleration against the phase), alternating template fits and
    boundary moves. Each boundary is moved by a grid search over a quarter of
    a period either way, every other boundary at a time so that the two
    cycles a boundary touches are refitted together.

The cost of each choice, on simulated records with known force cycles, is in
docs/benchmarks.md ("record-level identification").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import CycleError, OptionError
from ..signals import SUPPORTED_FB, find_cycles

__all__ = ["TIMING_METHODS", "CycleTiming", "estimate_timing", "floor_share"]

TIMING_METHODS = ("template", "peaks")
"""Ways :func:`estimate_timing` places the force-cycle boundaries."""

SEARCH_FRACTION = 0.25
"""How far (fraction of the local period) the template alignment moves a boundary either way."""

SEARCH_POINTS = 41
"""Candidate positions per boundary and alignment sweep."""

ALIGN_ITERATIONS = 4
"""Template fits and boundary sweeps of the template alignment."""

EDGE_TOLERANCE = 0.25
"""A record's first (last) whole cycle whose length is off the median period by more than this fraction is not
trusted: its outer boundary is placed one neighbouring period away instead (:func:`align_boundaries`).

At a record's edge a boundary has one real neighbour only, and a first cycle of another shape (a person starting
from rest) pulled it by a third of a period: on six records of the ``coefficients`` generator, which start from
rest, ``f_h`` was 4-14 % off with the innovations' predictable part at 0.3-0.9 %; without the first 0.3 s of
each record, 0.1-1.8 % and 0 %."""

PEAK_TOLERANCE = 0.3
"""GRF peaks one of whose inner intervals is off the running median period by more than this fraction are not
trusted to count the cycles: the boundaries are placed by the phase of the force's fundamental instead
(:func:`_phase_boundaries`).

A GRF with two humps per cycle has its highest peak jump from one hump to the other: on a person on a resonant
floor (``f_b`` 3.35 Hz, floor 3.48 Hz) the peaks' intervals were 0.18-0.47 s about a period of 0.30 s, 94 peaks for
100 cycles, and the record-level model, given 96 cycles, put ``f_h`` at 3.36 Hz (truth 3.07) with ``xi_h`` 0.08
(0.48)."""

RUNNING_WINDOW = 9
"""Peak intervals in the running median period :data:`PEAK_TOLERANCE` is measured against."""

FUNDAMENTAL_BAND = (0.6, 1.4)
"""Pass band of the fundamental whose phase counts the cycles, relative to the mean bouncing frequency."""

SUBHARMONIC_RATIO = 30.0
"""A spectral line at ``f_b / 2`` or ``f_b / 3`` of the GRF this many times above the
median power near it means the peaks found half or a third of the force cycle (a
dominant 2nd or 3rd harmonic, e.g. ``f_h`` near ``2 f_b``): the cycles are regrouped."""

SUBHARMONIC_OFFSET = 0.02
"""...provided that line peaks within this fraction of ``f_b / 2`` (``f_b / 3``): half-cycle peaks put the force's
own fundamental exactly there (measured: within 1 % on 12 records of ``f_h`` near ``2 f_b``, lines 1150-14700 times
their neighbourhood). On two quiet lab records (noise 0.7 N) a bump 4-6 % off ``f_b / 2``, 31-33 times its
neighbourhood, regrouped the cycles in pairs and the person came out on the search bound (f_b read as 1.34 Hz,
truth 2.67 Hz; f_h +79 %)."""

SUBHARMONIC_STRONG = (300.0, 0.05)
"""A line this many times above its neighbourhood (ten times :data:`SUBHARMONIC_RATIO`) may lie up to this fraction
off ``f_b / 2`` (``f_b / 3``): where the GRF's humps are not locked to the force cycle (a person whose ``f_h``
drifts towards ``2 f_b`` shows humps at 4.37 Hz over a fundamental at 2.25 Hz, 2958 times its neighbourhood:
``benchmarks/lab_records.py --people lab``, seed 4361, change row, record 12), the peaks' rate is not twice the
fundamental's, and that record was refused as "median bouncing frequency 4.39 Hz is outside the supported range".
The spurious bumps above were 31-33 times their neighbourhood."""


@dataclass(frozen=True)
class CycleTiming:
    """Force-cycle boundaries over a record and the phase they imply.

    Attributes
    ----------
    boundaries : ndarray, shape (J + 1,)
        Start times (s) of the force cycles, increasing; the first lies at or
        before the record's first sample and the last at or after its last
        sample (the partial end cycles are extrapolated from their neighbours).
    method : str
        How they were estimated (:data:`TIMING_METHODS`, or ``"given"``).
    """

    boundaries: np.ndarray
    method: str = "given"

    @property
    def n_cycles(self) -> int:
        """Number of force cycles ``J`` (partial end cycles included)."""
        return self.boundaries.size - 1

    @property
    def f_b(self) -> np.ndarray:
        """Bouncing frequency of each cycle (Hz), shape (J,)."""
        return 1.0 / np.diff(self.boundaries)

    def locate(self, t):
        """Cycle index, phase and phase rate at times ``t``.

        Parameters
        ----------
        t : array_like, shape (N,)
            Times (s) within the boundaries.

        Returns
        -------
        cycle : ndarray of int, shape (N,)
            Index ``j`` of the cycle that contains each time.
        theta : ndarray, shape (N,)
            Bouncing phase ``2 pi (j + (t - b_j) / (b_{j+1} - b_j))`` (rad).
        rate : ndarray, shape (N,)
            Its rate ``2 pi f_b`` of the cycle (rad/s).
        """
        t = np.asarray(t, dtype=float)
        b = self.boundaries
        cycle = np.clip(np.searchsorted(b, t, side="right") - 1, 0, b.size - 2)
        period = b[cycle + 1] - b[cycle]
        theta = 2.0 * np.pi * (cycle + (t - b[cycle]) / period)
        return cycle, theta, 2.0 * np.pi / period


def _extend(boundaries, t_first, t_last):
    """Add extrapolated boundaries so that ``[t_first, t_last]`` is covered."""
    b = list(boundaries)
    while b[0] > t_first:
        b.insert(0, b[0] - (b[1] - b[0]))
    while b[-1] < t_last:
        b.append(b[-1] + (b[-1] - b[-2]))
    return np.asarray(b, dtype=float)


def _basis(theta, n):
    """Fourier basis ``[1, cos(i theta), sin(i theta)]``, shape theta.shape + (2 n + 1,)."""
    orders = np.arange(1, n + 1)
    angle = theta[..., None] * orders
    return np.concatenate([np.ones(theta.shape + (1,)), np.cos(angle), np.sin(angle)], axis=-1)


def _series(theta, coef, n):
    """``_basis(theta, n) @ coef`` without the basis: ``cos(i theta), sin(i theta)`` by rotation from the first."""
    turn = np.exp(1j * theta)
    power = turn.copy()
    total = np.full(theta.shape, coef[0])
    for i in range(1, n + 1):
        total += coef[i] * power.real + coef[n + i] * power.imag
        power *= turn
    return total


def _template(time, y, boundaries, n):
    """Least-squares Fourier template of ``y`` against the phase; returns its coefficients."""
    _, theta, _ = CycleTiming(boundaries).locate(time)
    coef, *_ = np.linalg.lstsq(_basis(theta, n), y, rcond=None)
    return coef


def _sweep(time, y, b, movable, coef, n):
    """Move the boundaries ``b[movable]`` to their best candidate positions (in place)."""
    dt = time[1] - time[0]
    left, right = b[movable - 1], b[movable + 1]
    lo = np.searchsorted(time, left, side="left")
    hi = np.searchsorted(time, right, side="right")
    length = int(np.max(hi - lo))
    if length < 2:
        return
    index = lo[:, None] + np.arange(length)
    inside = index < hi[:, None]
    index = np.minimum(index, time.size - 1)
    t_win, y_win = time[index], y[index]  # (W, L)
    period = 0.5 * (right - left)
    shift = np.linspace(-SEARCH_FRACTION, SEARCH_FRACTION, SEARCH_POINTS)
    candidate = b[movable][:, None] + shift[None, :] * period[:, None]  # (W, C)
    candidate = np.clip(candidate, left[:, None] + 2 * dt, right[:, None] - 2 * dt)
    c = candidate[:, :, None]
    tw = t_win[:, None, :]
    first = tw < c
    theta = np.where(first, (tw - left[:, None, None]) / (c - left[:, None, None]),
                     (tw - c) / (right[:, None, None] - c))
    model = _series(2.0 * np.pi * theta, coef, n)
    cost = np.sum(np.where(inside[:, None, :], (y_win[:, None, :] - model) ** 2, 0.0), axis=-1)
    b[movable] = candidate[np.arange(movable.size), np.argmin(cost, axis=1)]


def estimate_timing(time, force, n_harmonics=4, method="template", *, fb_range=SUPPORTED_FB, source=None):
    """Estimate the force-cycle boundaries of a bouncing record.

    Parameters
    ----------
    time : array_like, shape (N,)
        Sample times (s), uniformly spaced.
    force : array_like, shape (N,)
        Vertical ground reaction force (N) or anything affine in it (the COM
        acceleration of Eq. 3).
    n_harmonics : int
        Harmonics of the force model; the alignment template uses two more.
    method : {"template", "peaks"}
        See the module docstring.
    fb_range : tuple of float
        Accepted bouncing frequencies (Hz), passed to :func:`~smd_statespace.signals.find_cycles`.
    source : str, optional
        Record name for error messages.

    Returns
    -------
    CycleTiming

    Raises
    ------
    CycleError
        No bouncing cycles in the record (from :func:`~smd_statespace.signals.find_cycles`).
    OptionError
        Unknown ``method``.
    """
    if method not in TIMING_METHODS:
        raise OptionError(f"timing method {method!r} is not one of: {', '.join(TIMING_METHODS)}")
    time = np.asarray(time, dtype=float)
    force = np.asarray(force, dtype=float)
    lo, hi = fb_range
    try:  # a dominant 2nd or 3rd harmonic puts GRF peaks up to three times per force cycle
        peaks, _ = find_cycles(time, force, (lo, 3.0 * hi), source=source)
    except CycleError:
        peaks, _ = find_cycles(time, force, fb_range, source=source)  # its own message
    group = _cycles_per_peak(time, force, peaks, fb_range)
    peaks = _main_peaks(force, peaks, group)
    f_b = (peaks.size - 1) / (time[peaks[-1]] - time[peaks[0]]) if peaks.size > 1 else 0.0
    if not lo <= f_b <= hi:
        peaks, _ = find_cycles(time, force, fb_range, source=source)  # raises the library's own one-line error
    boundaries = time[peaks]
    if not _regular(boundaries):
        boundaries = _phase_boundaries(time, force, f_b, boundaries)
    boundaries = _extend(boundaries, time[0], time[-1])
    if method == "peaks":
        return CycleTiming(boundaries, "peaks")
    return align_boundaries(time, force, boundaries, n_harmonics + 2, method="template")


def _regular(peak_times) -> bool:
    """Whether every inner interval of ``peak_times`` is within :data:`PEAK_TOLERANCE` of its running median.

    The first and last interval are not judged (a record that starts from rest has an irregular first cycle,
    which :func:`_regular_edges` handles).
    """
    interval = np.diff(peak_times)
    if interval.size < 5:
        return True
    half = RUNNING_WINDOW // 2
    padded = np.pad(interval, half, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(padded, RUNNING_WINDOW)
    ratio = interval / np.median(windows, axis=1)
    return bool(np.all(np.abs(ratio[1:-1] - 1.0) <= PEAK_TOLERANCE))


def _phase_boundaries(time, force, f_b, peak_times) -> np.ndarray:
    """Boundaries one per turn of the phase of the force's fundamental, at the peaks' mean phase.

    The GRF is band-passed about ``f_b`` (:data:`FUNDAMENTAL_BAND`, zero phase) and its analytic signal's
    unwrapped phase advances by ``2 pi`` per force cycle whatever the cycle's shape; a boundary is put where it
    passes the circular mean of its values at the GRF peaks, so that the boundaries lie where the peaks lie
    when these are regular and the template alignment starts from the same place.
    """
    from scipy.signal import butter, hilbert, sosfiltfilt

    fs = 1.0 / (time[1] - time[0])
    low, high = FUNDAMENTAL_BAND
    sos = butter(4, [low * f_b, min(high * f_b, 0.45 * fs)], btype="bandpass", fs=fs, output="sos")
    phase = np.unwrap(np.angle(hilbert(sosfiltfilt(sos, force - np.mean(force)))))
    phase = np.maximum.accumulate(phase)  # noise may turn it back by a hair: a boundary is crossed once
    origin = float(np.angle(np.mean(np.exp(1j * np.interp(peak_times, time, phase)))))
    turns = np.arange(np.ceil((phase[0] - origin) / (2.0 * np.pi)), np.floor((phase[-1] - origin) / (2.0 * np.pi)) + 1)
    crossings = np.interp(origin + 2.0 * np.pi * turns, phase, time)
    inner = crossings[(crossings > time[0]) & (crossings < time[-1])]
    return np.unique(inner) if inner.size >= 2 else peak_times


def _cycles_per_peak(time, force, peaks, fb_range):
    """1, 2 or 3: how many GRF-peak intervals make one force cycle (a subharmonic line in the GRF says so)."""
    if peaks.size < 7:
        return 1
    span = slice(int(peaks[0]), int(peaks[-1]) + 1)
    x = force[span] - np.mean(force[span])
    fs = 1.0 / (time[1] - time[0])
    n = 4 * x.size
    power = np.abs(np.fft.rfft(x * np.hanning(x.size), n)) ** 2
    freq = np.fft.rfftfreq(n, 1.0 / fs)
    # the peaks' rate from their usual intervals: a hump too low to be found as a peak leaves a long interval, which
    # a count over the record's length would spread over every cycle
    interval = np.diff(time[peaks])
    f_peak = 1.0 / float(np.mean(interval[np.abs(interval / np.median(interval) - 1.0) < PEAK_TOLERANCE]))
    best, best_ratio = 1, SUBHARMONIC_RATIO
    for group in (2, 3):
        f_sub = f_peak / group
        if f_sub < fb_range[0] or (peaks.size - 1) // group < 3:
            continue
        line = (freq > f_sub * 0.93) & (freq < f_sub * 1.07)
        near = (freq > f_sub * 0.6) & (freq < f_sub * 1.4) & ~((freq > f_sub * 0.85) & (freq < f_sub * 1.15))
        ratio = power[line].max() / max(float(np.median(power[near])), 1e-300)
        at = freq[line][np.argmax(power[line])]
        offset = SUBHARMONIC_STRONG[1] if ratio >= SUBHARMONIC_STRONG[0] else SUBHARMONIC_OFFSET
        if ratio > best_ratio and abs(at / f_sub - 1.0) <= offset:
            best, best_ratio = group, ratio
    return best


def _main_peaks(force, peaks, group):
    """Every ``group``-th peak, starting where the kept peaks are highest (the main peak of each force cycle)."""
    if group == 1:
        return peaks
    offset = max(range(group), key=lambda k: float(np.mean(force[peaks[k::group]])))
    return peaks[offset::group]


def align_boundaries(time, signal, boundaries, n_fit, method="template"):
    """Move cycle boundaries to where ``signal`` best matches its own mean cycle.

    Parameters
    ----------
    time : ndarray, shape (N,)
        Sample times (s).
    signal : ndarray, shape (N,)
        A periodic-looking signal of the record: the GRF, or the force
        reconstructed by a fitted model.
    boundaries : ndarray, shape (J + 1,)
        Starting boundaries covering the record (s).
    n_fit : int
        Harmonics of the template (capped below the Nyquist frequency).
    method : str
        Label stored in the returned timing.

    Returns
    -------
    CycleTiming
    """
    fs = 1.0 / (time[1] - time[0])
    n_fit = int(max(1, min(n_fit, np.floor(0.4 * fs * np.median(np.diff(boundaries))))))
    y = (signal - signal.mean()) / max(float(signal.std()), 1e-12)
    b = np.asarray(boundaries, dtype=float).copy()
    for _ in range(ALIGN_ITERATIONS):
        coef = _template(time, y, b, n_fit)
        for parity in (1, 2):
            movable = np.arange(parity, b.size - 1, 2)
            if movable.size:
                _sweep(time, y, b, movable, coef, n_fit)
        inner = _regular_edges(b[(b > time[0]) & (b < time[-1])])
        if inner.size >= 2:
            b = _extend(inner, time[0], time[-1])
    return CycleTiming(b, method)


def _regular_edges(inner):
    """``inner`` boundaries with an irregular first or last whole cycle (:data:`EDGE_TOLERANCE`) replaced: the
    outer boundary is put one neighbouring period away from the next one in."""
    if inner.size < 4:
        return inner
    b = inner.copy()
    period = float(np.median(np.diff(b)))
    if abs(b[1] - b[0] - period) > EDGE_TOLERANCE * period:
        b[0] = b[1] - (b[2] - b[1])
    if abs(b[-1] - b[-2] - period) > EDGE_TOLERANCE * period:
        b[-1] = b[-2] + (b[-2] - b[-3])
    return b


def floor_share(time, floor_acc, f_h, xi_h) -> np.ndarray:
    """The body's acceleration (m/s^2) that a measured floor drives through the person's leg, shape (N,).

    A person on a moving floor obeys ``u'' = -w_h^2 (u - z) - 2 xi_h w_h (u' - z') + F`` (Eq. 2 relative to the
    floor: ``u`` the body's and ``z`` the floor's vertical displacement, upward, m; ``w_h = 2 pi f_h``; ``F`` the
    biomechanical force per unit mass). The part of ``u''`` that ``z`` drives alone (``F = 0``, the person at rest
    at the record's start) is the floor's acceleration ``z''`` (``floor_acc``) through
    ``H(s) = (2 xi_h w_h s + w_h^2) / (s^2 + 2 xi_h w_h s + w_h^2)``. The force less ``M_h`` times this is what
    the person's own force makes; its peaks are where the cycle starts lie, where a floor near resonance moves
    the GRF's (:func:`~smd_statespace.person.fit.identify_person` places the starts on it again).

    Parameters
    ----------
    time : array_like, shape (N,)
        Sample times (s), uniformly spaced.
    floor_acc : array_like, shape (N,)
        The floor's vertical acceleration (m/s^2, upward).
    f_h : float
        Natural frequency of the person (Hz).
    xi_h : float
        Damping ratio of the person.
    """
    from scipy.signal import lsim

    w = 2.0 * np.pi * f_h
    time = np.asarray(time, dtype=float)
    _, share, _ = lsim(([2.0 * xi_h * w, w * w], [1.0, 2.0 * xi_h * w, w * w]), np.asarray(floor_acc, dtype=float),
                       time - time[0])
    return np.asarray(share, dtype=float)
