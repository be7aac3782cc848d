"""Every estimator works at about :data:`RECORD_RATE`: a faster record is low-pass filtered and decimated first."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..errors import OptionError
from ..io import Record

__all__ = ["RECORD_RATE", "GUARD_BAND", "RATE_SLACK", "check_rate", "decimation_factor", "decimate_record",
           "decimation_note"]


RECORD_RATE = 100.0
"""Sample rate (Hz) every estimator works at: faster records are decimated to between this and twice it.

Bouncing forces carry nothing above about 25 Hz (six harmonics of 3.5 Hz, floor modes of
Table 3 below 20 Hz). The article's per-sample noise levels and random walk (Eq. 6) were
set at its 100 Hz, and so was the calibration of the record-level intervals
(:data:`smd_statespace.person.calibration.CALIBRATION`); the cost grows with the samples (a 60 s
record, record-level: 13 s at 100 Hz, 114 s at 1000 Hz).
"""

GUARD_BAND = 0.1
"""Width (Hz) of the band just below the new Nyquist frequency that :func:`decimate_record` removes too.

Mains hum (50 Hz) sits on the Nyquist frequency of 100 Hz; a guard this narrow keeps it off
without colouring white noise (measured in :func:`decimate_record`'s notes).
"""


RATE_SLACK = 1e-3
"""A record up to this fraction slower than a multiple ``q`` of the fitting rate is decimated by ``q``
(:func:`decimation_factor`).

A phone's clock is measured, not nominal: set to 200 Hz, simulated phones measured 199.9996-200.0003 Hz (quartz
clocks are good to about 1e-4). ``floor(199.9996 / 100)`` is 1, and such a phone record, about every other one,
was fitted at 200 Hz with every sample (twice the samples and the noise of another rate; on one simulated record,
read alike, the innovations had a kurtosis of 13.5 there against 3.4 at 100 Hz)."""


def decimation_factor(fs: float, rate) -> int:
    """``q = floor(fs / rate)`` within :data:`RATE_SLACK` (at least 1; 1 when ``rate`` is None).

    Examples
    --------
    >>> decimation_factor(1000.0, 100.0), decimation_factor(199.9996, 100.0), decimation_factor(150.0, 100.0)
    (10, 2, 1)
    """
    if check_rate(rate) is None:
        return 1
    return max(int(math.floor(fs / rate * (1.0 + RATE_SLACK))), 1)


def check_rate(rate):
    """``rate`` if it is a positive number of Hz or None; otherwise an :class:`OptionError` naming it."""
    if rate is not None and not (isinstance(rate, (int, float)) and not isinstance(rate, bool)
                                 and math.isfinite(rate) and rate > 0):
        raise OptionError(f"rate={rate!r} must be a positive sample rate in Hz (or None to keep every sample)")
    return rate


def decimate_record(record: Record, rate=RECORD_RATE, extra=()):
    """The record at ``rate`` to ``2 rate`` Hz: an ideal low-pass just below the new Nyquist frequency, every ``q``-th sample.

    ``q = floor(fs / rate)`` (:func:`decimation_factor`, which lets a phone's clock run a little slow); with
    ``q < 2`` (or ``rate`` None) the record is returned as it
    is. The first ``q * floor(n / q)`` samples are kept (at most ``q - 1`` samples, under
    ``1 / rate``, are dropped at the end), extended by their mirror image (so the periodic
    extension has no jump) and filtered in the frequency domain: every component below the
    new Nyquist frequency less :data:`GUARD_BAND` comes through unchanged, every one above it
    is removed instead of folded onto the bouncing harmonics. An ideal filter keeps white
    measurement noise white, which the record-level model assumes and its Ljung-Box test
    checks; a FIR filter (:func:`scipy.signal.resample_poly`) droops below the new Nyquist
    frequency and made white noise fail that test on 4 of 10 records of 3000 samples (lag-1
    autocorrelation 0.04; this filter: 0 of 10, 0.002). Measured on noise-free simulated
    bouncing at 1000 Hz with a smooth force: within 0.2 N of the samples themselves, except
    the first and last three decimated samples (up to 10 N). A force that jumps (the
    simulator's ``"jumps"`` generator) rings at every jump under any anti-aliasing filter.

    The guard band keeps the new Nyquist frequency empty: 1000 Hz decimated to 100 Hz puts
    50 Hz mains hum on it, where an ideal filter at the Nyquist frequency itself
    (:func:`scipy.signal.resample`, used before) let it through (an RMS of 0.25 per unit
    amplitude 3 s in from the ends, alternating in sign every sample, ringing at three times the amplitude near the
    ends). Measured (``benchmarks/frontend_speed.py``, 400 white-noise records of 30 s): a
    guard of 0.1 Hz leaves 0.048 of an exact 50 Hz line and keeps the noise white (Ljung-Box,
    20 lags, rejected at 5 % on 5.0 % of records, 5.5 % without a guard; lag-1 0.001); wider
    guards colour it (0.5 Hz: 22 %, 1 Hz: 90 % rejected). It moves a smooth bouncing force by at
    most 0.09 N 0.3 s in from the ends (0.04 N without it). Hum is therefore removed before decimation
    (:func:`~smd_statespace.signals.remove_hum`); the guard only keeps what is left off the
    Nyquist frequency.

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
    factor = decimation_factor(record.fs, rate)
    if factor < 2:
        return record, 1, list(extra)

    kept = record.time.size // factor
    # keep the bins below the new Nyquist frequency less the guard (in cycles per original sample)
    frequencies = np.fft.rfftfreq(2 * kept * factor)[:kept + 1]
    passed = frequencies < 0.5 / factor - GUARD_BAND / record.fs

    def down(values):
        whole = np.asarray(values, dtype=float)[:kept * factor]
        spectrum = np.fft.rfft(np.concatenate([whole, whole[::-1]]))[:kept + 1]
        return np.fft.irfft(np.where(passed, spectrum, 0.0), 2 * kept)[:kept] / factor

    time = record.time[:kept * factor:factor]
    floor_acc = None if record.floor_acc is None else down(record.floor_acc)
    decimated = replace(record, time=time, force=down(record.force), floor_acc=floor_acc)
    return decimated, factor, [down(values) for values in extra]


def decimation_note(measured_rate: float, record: Record, factor: int, rate) -> list:
    """What :func:`decimate_record` did, in words for a result's notes (``[]`` when it kept every sample)."""
    if factor == 1:
        return []
    return [f"fitted at {record.fs:.4g} Hz: the record ({measured_rate:.4g} Hz) was low-pass filtered and one "
            f"sample in {factor} kept (the rate asked: {rate:g} Hz; to keep every sample, rate=None in Python or "
            "--rate 0 on the command line)"]
