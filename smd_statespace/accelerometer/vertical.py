"""The vertical COM acceleration without gravity from a uniform record: :func:`vertical_acceleration`.

Three axes
----------

The direction of gravity is estimated from the record itself. A zero-phase low-pass
of the three axes at ``cutoff`` (Butterworth, order :data:`GRAVITY_ORDER`, forwards
and backwards) keeps the slowly changing specific force of gravity ``g(t)`` in the
phone's frame, following slow tilt and sway of the phone while removing the
bouncing; its unit vector ``e(t) = g(t) / |g(t)|`` is "up" in the phone's frame.
Then

    a_v(t) = acc(t) . e(t) - |g|(e(t))

with ``|g|(e)`` the sensor's own reading of gravity in the direction ``e``, not
9.81 and not one number for the whole record: a sensor's bias and per-axis gain
errors make it depend on the phone's orientation (``|g| + b . e + g sum_i d_i e_i^2``),
so as the phone turns slowly its reading of gravity changes with it. It is fitted
over the record (:func:`gravity_level`): the low-passed magnitude ``|g(t)|``
regressed on the direction's turning. Until 2026-11-28 one number, the median of
``|g(t)|``, was subtracted: a tilt wander of 5 deg, or per-axis gains of 3 % with a
0.5 m/s^2 bias, left 0.015-0.06 m/s^2 rms below 0.5 Hz in ``a_v``, enough for the
"smooth" variation model to absorb it and ``f_h`` to be +35 to +71 % off on single
records (``benchmarks/phone_phenomena.py``, seed 4401). Subtracting ``|g(t)|``
itself would remove that too, but also put into ``a_v`` every slow bump of the
low-passed magnitude that is not gravity: the line interpolated across a gap of
the phone's stamps is up to 5 m/s^2 off a bouncing signal, and the low-pass spreads
it over seconds (0.38 m/s^2 at worst beside two 0.25 s gaps; a 0.25 s gap put
``f_h`` at the search's bound). A fit over the whole record, which follows the
orientation and leaves the gaps' samples out (``measured``), is moved by little.
The low-pass is computed as the complement of
:func:`smd_statespace.signals.highpass` (``acc - highpass(acc)``: for a zero-phase
Butterworth pair the two responses add up to one), whose ``"predict"`` padding keeps
the record's ends free of start-up transients.

One vertical channel
--------------------

``a_v = s acc - |g|`` with ``|g|`` the median of the channel's low-passed level and
``s`` its sign (+1 for an axis pointing up, -1 for one pointing down): one channel
cannot tell the phone's turning. The median of the raw channel would not do: a
bouncing acceleration is skewed (sharp peaks while the feet push, flat troughs), so
its median differs from its mean (0.7 m/s^2 for the harmonics 3, 2, 0.8, 0.3 m/s^2
of a 2.2 Hz bounce).

Why a sensor bias does not matter
---------------------------------

A bias ``b`` of the axes is constant: the low-pass passes it whole, so ``g(t)``
becomes ``g(t) + b``. Its component along ``e`` adds to both ``acc . e`` and ``|g|``
and cancels; its component across ``e`` tilts ``e`` by at most ``|b| / |g|`` (1.2
deg for 0.2 m/s^2), which scales the vertical signal by ``cos`` of that (0.99978)
and mixes in 2 % of the small horizontal acceleration. A constant has no content at
any bouncing frequency; all it could do is move the mean, which the fitted
``|g|(e)`` removes. A common scale error of the sensor scales ``a_v`` by the same factor (a few
tenths of a percent for a phone): it is not corrected, ``info["gravity"] / 9.80665``
shows it together with any bias.

Why the low-pass
----------------

The direction ``e(t)`` must not see the bouncing: a 2 % leak of it would modulate
the direction at the bouncing frequency. At :data:`GRAVITY_CUTOFF` the leak is 1e-5
(see there). Rotation of the pelvis *at* the bouncing frequency is not followed; a
+-5 deg rocking changes the projection by ``g (1 - cos 5 deg) = 0.04 m/s^2`` at
twice that frequency.

Stillness
---------

A stretch longer than :data:`STILL_DURATION` whose movement (RMS about its own mean)
is below :data:`STILL_FRACTION` of the record's dynamic RMS (``acc - g(t)``) is
reported (``still``; at either end also ``still_start``, ``still_end``), not refused:
a phone record is picked up, strapped on, worn standing, then bounced with, and the
person model's front end fits only the bouncing (until 2026-11-28 a still stretch
between movements was refused, which refused every record with handling before a
standing start).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import OptionError, RecordError
from ..io import G, SAMPLING_TOLERANCE
from .reading import GRAVITY_TOLERANCE
from .resampling import _check_arrays

__all__ = [
    "GRAVITY_CUTOFF",
    "GRAVITY_ORDER",
    "ORIENTATION_SPREAD",
    "STILL_DURATION",
    "STILL_FRACTION",
    "across_vertical",
    "gravity_level",
    "gravity_track",
    "vertical_acceleration",
]

GRAVITY_CUTOFF = 0.3
"""Cut-off (Hz) of the zero-phase low-pass that separates gravity from bouncing.

Well below the slowest bouncing (1.5 Hz in the article, 1.2 Hz supported): with
:data:`GRAVITY_ORDER` 4, run forwards and backwards, the gravity estimate keeps
``1 / (1 + (f / 0.3)^8)`` of a component at ``f``, i.e. 1.5e-5 at 1.2 Hz and
2.6e-6 at 1.5 Hz, while it follows the slow tilt and sway of the phone (a 0.1 Hz
sway is passed with a gain of 0.99985)."""

ORIENTATION_SPREAD = 0.5
"""Turning (degrees, sd over the record) of the gravity direction along an axis above which the sensor's gravity
reading is followed along it (:func:`gravity_level`). A bias of 0.5 m/s^2 or a gain error of 3 % changes the reading
by under 0.005 m/s^2 over a turn of 0.5 degrees."""

GRAVITY_ORDER = 4
"""Butterworth order of one pass of the gravity low-pass (:data:`GRAVITY_CUTOFF`)."""

STILL_DURATION = 2.0
"""Length (s) of a stretch of stillness that :func:`vertical_acceleration` refuses between bouncing."""

STILL_FRACTION = 0.05
"""A stretch is *still* when its dynamic acceleration's RMS is below this fraction of the record's.

Bouncing gives a dynamic RMS of 1-4 m/s^2; a phone lying on a table shows only
its noise (0.01-0.05 m/s^2 per axis); quiet standing about 0.02-0.1 m/s^2."""


def _still_stretches(acc: np.ndarray, dynamic_rms: float, fs: float) -> np.ndarray:
    """``(start, stop)`` sample ranges covered by :data:`STILL_DURATION` windows with little movement.

    A window of ``STILL_DURATION`` s is still when the RMS of ``acc`` about the
    window's own mean (summed over the axes) is below ``STILL_FRACTION *
    dynamic_rms``. Using the window's mean, not the gravity low-pass, keeps a
    change of orientation (the phone being put down or picked up) out of the
    windows that do not contain it, so a still stretch is found to within a
    sample. Running sums make it one pass.
    """
    n = acc.shape[0]
    width = int(round(STILL_DURATION * fs))
    if n < width:
        return np.empty((0, 2), dtype=int)
    centred = acc - acc.mean(axis=0)
    sums = np.vstack([np.zeros((1, acc.shape[1])), np.cumsum(centred, axis=0)])
    squares = np.concatenate([[0.0], np.cumsum((centred**2).sum(axis=1))])
    window_sum = sums[width:] - sums[:-width]
    variance = (squares[width:] - squares[:-width] - (window_sum**2).sum(axis=1) / width) / width
    still = np.sqrt(np.maximum(variance, 0.0)) < STILL_FRACTION * dynamic_rms
    covered = np.convolve(still.astype(float), np.ones(width))[:n] > 0.5
    edges = np.diff(np.concatenate([[0], covered.astype(np.int8), [0]]))
    return np.column_stack([np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)])


def _check_cutoff(cutoff, cutoff_max: float) -> None:
    """Refuse a gravity low-pass cut-off that is not a number of Hz in ``(0, cutoff_max]`` (an :class:`OptionError`)."""
    if isinstance(cutoff, bool) or not isinstance(cutoff, (int, float)) \
            or not (math.isfinite(cutoff) and 0.0 < cutoff <= cutoff_max):
        raise OptionError(
            f"cutoff={cutoff!r}: the gravity low-pass cut-off must be in (0, {cutoff_max:g}] Hz, well below "
            f"the bouncing frequency (default {GRAVITY_CUTOFF:g})"
        )


def _uniform_rate(time: np.ndarray, cutoff: float, source: str) -> float:
    """The sampling rate (Hz) of the uniform ``time``, or a :class:`RecordError`.

    Fewer than 3 samples, steps that are not uniform (within
    :data:`~smd_statespace.io.SAMPLING_TOLERANCE`) or a record shorter than
    ``1 / cutoff`` are refused.
    """
    if time.size < 3:
        raise RecordError(f"{source}: only {time.size} samples; a record needs at least one bouncing cycle")
    steps = np.diff(time)
    dt = float(np.median(steps))
    deviation = np.abs(steps / dt - 1.0) if dt > 0 else np.inf * np.ones_like(steps)
    if not dt > 0 or deviation.max() > SAMPLING_TOLERANCE:
        row = int(np.argmax(deviation)) + 2
        raise RecordError(
            f"{source}: time is not uniform at sample {row} (step {steps[row - 2]:.4g} s, median {dt:.4g} s); "
            "put the record on a uniform grid with resample_uniform first"
        )
    duration = float(time[-1] - time[0])
    if duration < 1.0 / cutoff:
        raise RecordError(
            f"{source}: the record lasts {duration:.3g} s; finding the direction of gravity with a "
            f"{cutoff:g} Hz low-pass needs at least {1.0 / cutoff:.3g} s"
        )
    return 1.0 / dt


def _gravity_magnitude(gravity_t: np.ndarray, source: str) -> tuple:
    """``(|g(t)|, |g|)``: the low-passed specific force's magnitude and its median (m/s^2), refused unless about 1 g."""
    magnitude = np.linalg.norm(gravity_t, axis=1)
    gravity = float(np.median(magnitude))
    if abs(gravity / G - 1.0) > GRAVITY_TOLERANCE:
        raise RecordError(
            f"{source}: gravity magnitude {gravity:.4g} m/s^2, expected about {G:.2f}; acc must be in m/s^2 and "
            "include gravity"
        )
    return magnitude, gravity


def gravity_track(acc: np.ndarray, fs: float, cutoff: float = GRAVITY_CUTOFF) -> np.ndarray:
    """``g(t)``, shape (T, k): the zero-phase low-pass of the axes ``acc`` (m/s^2, shape (T, k)) at ``cutoff`` (Hz),
    computed as ``acc - highpass(acc)`` (the module's description)."""
    from ..signals import highpass  # here: signals imports pandas and scipy (not needed to read)

    return acc - highpass(acc, fs, cutoff, GRAVITY_ORDER, axis=0)


def across_vertical(acc: np.ndarray, gravity_t: np.ndarray) -> np.ndarray:
    """The magnitude (m/s^2) of the movement across the vertical: ``acc - g(t)`` less its component along ``e(t)``.

    A phone fixed at the waist of a bouncing person moves mostly along the vertical (the horizontal COM
    acceleration is a tenth of the vertical's); one that swings loose, or rocks, reads gravity across it."""
    direction = gravity_t / np.linalg.norm(gravity_t, axis=1, keepdims=True)
    dynamic = acc - gravity_t
    return np.linalg.norm(dynamic - np.einsum("ij,ij->i", dynamic, direction)[:, None] * direction, axis=1)


def gravity_level(direction: np.ndarray, magnitude: np.ndarray, measured=None) -> np.ndarray:
    """The sensor's gravity reading ``|g|(e(t))`` (m/s^2) as the phone turns: :data:`ORIENTATION_SPREAD`.

    ``|g(t)|`` (``magnitude``, the low-passed magnitude) regressed by least squares,
    over the ``measured`` samples (default all), on a constant and the components
    of the direction's change ``e(t) - mean(e)`` along which it turns by more than
    :data:`ORIENTATION_SPREAD` (sd); the fitted values are returned. A bias ``b``
    and per-axis gains ``1 + d_i`` make the reading ``|g| + b . e + g sum_i d_i
    e_i^2``, to first order in the turn linear in it. Fitted over the whole record,
    a burst of missing samples, whose interpolation bumps the low-passed magnitude
    for a few seconds, moves the fit by little, where subtracting ``|g(t)|`` itself
    would put the bump into ``a_v``.
    """
    measured = np.ones(magnitude.size, bool) if measured is None else np.asarray(measured, bool)
    change = direction - direction[measured].mean(axis=0)
    _, spread, axes = np.linalg.svd(change[measured], full_matrices=False)
    turning = spread / math.sqrt(max(int(measured.sum()), 1)) > math.radians(ORIENTATION_SPREAD)
    design = np.column_stack([np.ones(magnitude.size), change @ axes[turning].T])
    coefficients = np.linalg.lstsq(design[measured], magnitude[measured], rcond=None)[0]
    return design @ coefficients


def _project(acc: np.ndarray, gravity_t: np.ndarray, magnitude: np.ndarray, gravity: float, measured) -> tuple:
    """``(a_v, tilt_deg, direction_change_deg)``: ``acc`` along the gravity direction ``e(t)``, less the sensor's
    gravity reading in that direction (:func:`gravity_level`).

    One channel: ``a_v = s acc - |g|`` with ``s`` the sign of its low-passed level,
    and no angles (None).
    """
    if acc.shape[1] == 1:
        sign = 1.0 if np.median(gravity_t[:, 0]) > 0 else -1.0
        return sign * acc[:, 0] - gravity, None, None
    direction = gravity_t / np.maximum(magnitude, 1e-12)[:, None]
    a_v = np.einsum("ij,ij->i", acc, direction) - gravity_level(direction, magnitude, measured)
    mean_direction = gravity_t.mean(axis=0)
    mean_direction /= np.linalg.norm(mean_direction)
    tilt = float(np.degrees(np.arccos(np.clip(mean_direction[2], -1.0, 1.0))))
    change = float(np.degrees(np.arccos(np.clip(direction @ mean_direction, -1.0, 1.0))).max())
    return a_v, tilt, change


def _still_parts(time: np.ndarray, acc: np.ndarray, gravity_t: np.ndarray, fs: float) -> tuple:
    """``(still_start, still_end, still)``: the lengths (s) of still stretches at the record's ends and the
    ``[start, end]`` times (s) of every still stretch."""
    dynamic_rms = float(np.sqrt(np.mean(((acc - gravity_t) ** 2).sum(axis=1))))
    stretches = _still_stretches(acc, dynamic_rms, fs)
    n = time.size
    still_start = still_end = 0.0
    for start, stop in stretches:  # a handful of stretches, not samples
        if start == 0:
            still_start = (stop - start) / fs
        if stop == n:
            still_end = (stop - start) / fs
    still = [[float(time[start]), float(time[stop - 1])] for start, stop in stretches]
    return still_start, still_end, still


def vertical_acceleration(time, acc, *, cutoff: float = GRAVITY_CUTOFF, source: str = "<arrays>",
                          measured=None) -> tuple:
    """The vertical COM acceleration without gravity, ``a_v`` (m/s^2, up positive), from a uniform record.

    The direction of gravity ``e(t)`` is the unit vector of a zero-phase low-pass
    of the three axes at ``cutoff`` (Butterworth, order :data:`GRAVITY_ORDER`,
    forwards and backwards), and

        a_v(t) = acc(t) . e(t) - |g|(e(t))

    with ``|g|(e)`` the sensor's reading of gravity in the direction ``e``, fitted
    over the record (:func:`gravity_level`): a bias or gain error that differs
    between the axes then leaves no slow drift in ``a_v`` as the phone turns. One
    vertical channel gives ``a_v = s acc - |g|``, ``s`` its sign and ``|g|`` the
    median of its low-passed level.
    The method, why a sensor's bias does not matter and how stillness is found are
    set out in the module's description (:mod:`smd_statespace.accelerometer.vertical`).

    Parameters
    ----------
    time : array_like, shape (T,)
        Uniform sample times (s), e.g. from :func:`resample_uniform`.
    acc : array_like, shape (T, 3), (T, 1) or (T,)
        Specific force including gravity (m/s^2): the phone's three axes, or one
        channel along a vertical axis.
    cutoff : float, default :data:`GRAVITY_CUTOFF`
        Cut-off of the gravity low-pass (Hz), in (0, 0.6]: well below the lowest
        supported bouncing frequency (1.2 Hz), above the phone's slow sway.
    source : str, default "<arrays>"
        Name used in error messages (the file name).
    measured : array_like of bool, shape (T,), optional
        Which samples were measured (default all); the others (interpolated across a
        gap of the phone's stamps, :func:`~smd_statespace.accelerometer.record.unmeasured`)
        are left out of the fit of the sensor's gravity reading (:func:`gravity_level`).

    Returns
    -------
    a_v : ndarray, shape (T,)
        Vertical acceleration of the phone (~ the COM) without gravity (m/s^2),
        up positive; its mean over the record is about zero.
    info : dict
        ``gravity`` (m/s^2, the median of ``|g(t)|``); ``tilt_deg``, the angle between
        the mean gravity direction and the phone's z axis (0 = lying screen up,
        90 = upright, as in a pocket, 180 = screen down); ``direction_change_deg``,
        the largest angle between ``e(t)`` and its mean direction over the record
        (the phone's slow sway; both None for one channel); ``cutoff`` (Hz);
        ``still_start`` and ``still_end`` (s), the length of a still stretch at the
        start or end of the record (e.g. before the bouncing began), 0 if none;
        ``still``, the ``[start, end]`` times (s) of every still stretch (standing
        with the phone worn, or the phone put down). None is refused: the person
        model's front end (:func:`~smd_statespace.signals.prepare_record`) fits the
        longest bout of bouncing and says what it left out.

    Raises
    ------
    RecordError
        Arrays of mismatched shapes or with non-finite values; time not uniform
        (within :data:`~smd_statespace.io.SAMPLING_TOLERANCE`); a record shorter
        than ``1 / cutoff``; a gravity magnitude not about 9.81 m/s^2 (a record in
        g, or without gravity).
    OptionError
        ``cutoff`` is not in (0, 0.6] Hz.
    """
    from ..signals import SUPPORTED_FB  # here: signals imports pandas and scipy (not needed to read)

    time, acc2 = _check_arrays(time, acc, source)
    if acc2.shape[1] not in (1, 3):
        raise RecordError(f"{source}: acc has {acc2.shape[1]} columns; expected 3 axes or 1 vertical channel")
    _check_cutoff(cutoff, SUPPORTED_FB[0] / 2.0)
    fs = _uniform_rate(time, cutoff, source)
    measured = np.ones(time.size, bool) if measured is None else np.asarray(measured, bool)
    if measured.shape != time.shape or measured.sum() < 3:
        raise OptionError(f"measured: {measured.shape} flags with {int(measured.sum())} set; expected one per "
                          f"sample ({time.size}), at least 3 set")
    gravity_t = gravity_track(acc2, fs, cutoff)
    magnitude, gravity = _gravity_magnitude(gravity_t, source)
    a_v, tilt, change = _project(acc2, gravity_t, magnitude, gravity, measured)
    still_start, still_end, still = _still_parts(time, acc2, gravity_t, fs)
    info = {
        "gravity": gravity,
        "tilt_deg": tilt,
        "direction_change_deg": change,
        "cutoff": float(cutoff),
        "still_start": float(still_start),
        "still_end": float(still_end),
        "still": still,
    }
    return a_v, info
