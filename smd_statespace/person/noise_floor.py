"""The noise floor: a record quieter than the model is trusted to is fitted with white noise added up to it.

The record-level model describes how the force varies from cycle to cycle by a few smooth
processes (:mod:`~smd_statespace.person.variation`). A real force varies in finer ways than
that, and so do the simulator's generators. On a record with the noise of a quiet force plate
(about 0.05-0.15 % of body weight per fitted sample) the likelihood reads ``f_h`` and ``xi_h``
from those details: the person's high-frequency roll-off (``|GRF| ~ 2 xi_h f_h / f`` above the
resonance) is the one part of the model that can suppress a misfit there, so ``xi_h`` comes out
low and ``f_h`` high, with white-looking innovations (``docs/person.md``, "A quiet record").

Measured (``benchmarks/person_noise.py`` and ``benchmarks/lab_records.py``, results in
``benchmarks/results/person_noise_floor_seed77.md`` and ``lab_records_standard_seed4343_noise_floor.md``):
on 96 quiet and fast simulated records ``xi_h``'s 90 % intervals covered 91 % as measured (50 % on the
quietest records of the ``matern`` generator, whose covariance is the model's) and 100 % with the floor,
and two answers called determined were more than 10 % off (none with it); on 16 lab exports ``f_h``'s
median error went from 4.7 % to 2.7 % and the confident misses from 2 to 0. On records simulated from
the model itself, 0.1 % BW gives unbiased ``xi_h``: the loss is the model's, not the estimator's. The
price: fewer answers called determined (7 to 4 of 16 lab records) and no power left in the halves' test
of a change (3 to 0 of 16).

So a record whose measured noise (:func:`measured_noise`) is below :data:`NOISE_FLOOR` of body
weight is fitted with independent normal noise added to make up the difference (the level at
which the intervals were calibrated, :data:`~smd_statespace.person.calibration.CALIBRATION`),
drawn from a generator seeded by the record's own samples (:func:`record_seed`, rounded: the same
record, also read back from a CSV, gives the same answer). The result says so in its notes;
``noise_floor=None`` (``--noise-floor 0``) fits the record as measured.
"""

from __future__ import annotations

import hashlib

import numpy as np

from ..errors import OptionError
from ..io import G

__all__ = ["NOISE_FLOOR", "MAX_NOISE_FLOOR", "NOISE_BAND", "SEED_BLOCKS", "check_noise_floor", "measured_noise",
           "record_seed", "raise_to_floor", "noise_added", "measured_label"]

NOISE_FLOOR = 0.01
"""Default noise floor: the sd of the fitted samples' noise, as a fraction of body weight (1 % BW)."""

MAX_NOISE_FLOOR = 0.05
"""Largest noise floor accepted (5 % BW)."""

NOISE_BAND = (25.0, 0.95)
"""The band the measurement noise is read from: above 25 Hz (a bouncing force carries nothing there: six harmonics
of 3.5 Hz, :data:`~smd_statespace.signals.RECORD_RATE`) and below 0.95 of the Nyquist frequency (the decimation's
guard band); from half the Nyquist frequency instead where that is lower than 25 Hz (a record fitted below 50 Hz)."""

NOTE_START = "the record is quieter ("
"""How :func:`raise_to_floor`'s note begins (:func:`noise_added` finds it in a result's notes)."""


def noise_added(notes) -> bool:
    """Whether a result's ``notes`` say the noise floor added noise to the samples fitted."""
    return any(note.startswith(NOTE_START) for note in notes)


def measured_label(notes) -> str:
    """The legend label of the samples fitted: "measured", or that with the noise floor's noise in it."""
    return "measured + the noise floor's noise" if noise_added(notes) else "measured"


def check_noise_floor(noise_floor):
    """``noise_floor`` as a float fraction of body weight (0 for None); an :class:`OptionError` naming it if invalid."""
    if noise_floor is None:
        return 0.0
    if isinstance(noise_floor, bool) or not isinstance(noise_floor, (int, float)) or not (
            0.0 <= noise_floor <= MAX_NOISE_FLOOR):
        raise OptionError(f"noise_floor={noise_floor!r} must be a fraction of body weight from 0 to "
                          f"{MAX_NOISE_FLOOR:g} (e.g. {NOISE_FLOOR:g} for 1 % BW), or None to fit the record as "
                          "measured")
    return float(noise_floor)


def measured_noise(y, fs) -> float:
    """Standard deviation (m/s^2) of the white measurement noise in ``y``, read from the band of :data:`NOISE_BAND`.

    A Hann-windowed periodogram of ``y`` (``GRF / M_h - g`` at the fitted rate ``fs``, Hz), its mean
    power over the band divided by the window's mean square: the variance of white noise. Power of
    the force itself in the band (a record sampled too slowly for the band to be free of it) makes
    the estimate larger, never smaller.

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> t = np.arange(3000) / 100.0
    >>> y = 3.0 * np.sin(2 * np.pi * 2.0 * t) + 0.02 * rng.standard_normal(t.size)
    >>> round(measured_noise(y, 100.0), 3)
    0.02
    """
    y = np.asarray(y, dtype=float)
    window = np.hanning(y.size)
    power = np.abs(np.fft.rfft((y - y.mean()) * window)) ** 2 / (y.size * np.mean(window**2))
    frequency = np.fft.rfftfreq(y.size, 1.0 / fs)
    nyquist = 0.5 * fs
    low = min(NOISE_BAND[0], 0.5 * nyquist)
    band = (frequency >= low) & (frequency <= NOISE_BAND[1] * nyquist)
    return float(np.sqrt(np.mean(power[band]))) if band.sum() >= 8 else float("nan")


SEED_BLOCKS = 16
"""Blocks of the record whose means (with its length and sd) seed the noise floor's draw (:func:`record_seed`)."""


def record_seed(samples) -> np.random.SeedSequence:
    """The seed of the noise floor's draw, from the record itself: its number of samples, sd and the means of
    :data:`SEED_BLOCKS` consecutive blocks of it, each rounded to 0.1 of the samples' unit.

    Rounded so that a copy of the record written with fewer digits draws the same noise: a CSV at 6 decimals (the
    library's own, :func:`~smd_statespace.io.write_record`) moves a block's mean by about 1e-7. Seeded by the
    samples' bytes, as it was until 2026-11-29, a lab export and its copy read back from the library's CSV gave
    2.64 and 2.48 Hz. Records that differ by less than the rounding draw the same noise, which is as good a draw
    for each.
    """
    x = np.asarray(samples, dtype=float)
    summary = [np.nanstd(x)] + [np.nanmean(block) for block in np.array_split(x, SEED_BLOCKS) if block.size]
    key = f"{x.size} " + " ".join(f"{value:.1f}" for value in summary)
    digest = hashlib.sha256(key.encode("ascii")).digest()
    return np.random.SeedSequence(int.from_bytes(digest[:16], "little"))


def raise_to_floor(y, observed, fs, noise_floor, seed_from=None) -> tuple:
    """``y`` with white noise added up to ``noise_floor`` g of sd, and the note that says so.

    Parameters
    ----------
    y : ndarray
        ``GRF / M_h - g`` (m/s^2) at the fitted rate.
    observed : ndarray of bool or None
        The samples the likelihood uses (the noise is read from them and added to all).
    fs : float
        The fitted rate (Hz).
    noise_floor : float
        Fraction of body weight (:func:`check_noise_floor`); 0 leaves ``y`` as it is.
    seed_from : ndarray, optional
        The samples that seed the draw (:func:`record_seed`; default ``y``): ``identify_person`` gives the
        force as read from the file, which is the same on every machine, where ``y`` has been through the
        front end's floating-point arithmetic.

    Returns
    -------
    y : ndarray
        The samples to fit (``y`` itself when its noise is at the floor or above it, or unknown).
    notes : list of str
        One note when noise was added: the measured and added levels and how to fit without it.
    """
    if noise_floor <= 0.0:
        return y, []
    used = y if observed is None else y[np.asarray(observed, dtype=bool)]
    measured = measured_noise(used, fs)
    target = noise_floor * G
    if not np.isfinite(measured) or measured >= target:
        return y, []
    added = float(np.sqrt(target**2 - measured**2))
    rng = np.random.default_rng(record_seed(y if seed_from is None else seed_from))
    note = (f"{NOTE_START}{100 * measured / G:.2g} % BW noise per fitted sample) than the "
            f"{100 * noise_floor:g} % BW the model is trusted to: white noise of {100 * added / G:.2g} % BW was added "
            "before the fit (drawn from the record's own samples, so the same record gives the same answer), so that "
            "f_h and xi_h are not read from details of the force's variation that no variation model describes "
            "(docs/person.md, 'A quiet record'); noise_floor=None in Python or --noise-floor 0 fits it as measured")
    return y + added * rng.standard_normal(y.size), [note]
