"""An accelerometer file as the person model reads it: :func:`accelerometer_record`.
"""

from __future__ import annotations

import numpy as np

from ..errors import RecordError
from ..io import G
from .reading import read_accelerometer
from .resampling import resample_uniform
from .vertical import across_vertical, gravity_track, vertical_acceleration

__all__ = ["GAP_SAMPLES", "UNKNOWN_MASS", "accelerometer_record", "fill_gaps", "unmeasured"]

GAP_SAMPLES = 3.0
"""An interval between time stamps longer than this many of the phone's nominal intervals is a gap: the samples of
the uniform grid inside it are interpolated, not measured, and the person model leaves them out of its likelihood
(``record.extra["unmeasured"]``). Four gaps of up to 0.25 s, interpolated and fitted as measurements, put errors of
5-8 m/s^2 into the vertical (kurtosis 82-217) and ``f_h`` 67 % off at the median (12 simulated people,
``benchmarks/phone_phenomena.py``)."""

UNKNOWN_MASS = 70.0
"""Nominal mass (kg) an accelerometer record carries when no body mass is given (a value the records'
checks accept; nothing below depends on it).

The record-level model observes ``GRF / M - g`` (Eq. 3), which for an
accelerometer is ``a_v`` whatever ``M``: ``f_h``, ``xi_h``, the load factors (in g)
and the noise do not depend on it. ``K_h``, ``C_h`` (Eq. 17-18) and forces in
newtons do; they are left out (``record.extra["mass_known"]`` is False)."""


def accelerometer_record(path, mass=None, units: str = "auto", fs=None):
    """An accelerometer file as the person model reads it: a :class:`~smd_statespace.io.Record`.

    Reads the file (:func:`read_accelerometer`), puts it on a uniform clock
    (:func:`resample_uniform`), takes the vertical (:func:`vertical_acceleration`)
    and returns a record whose "force" is ``M (g + a_v)``: what a force plate under
    a rigid body of mass ``M`` moving like the phone would measure (Eq. 3 read
    backwards), so every check, estimator and output of a force-plate record applies
    (a record of jumping, whose vertical specific force falls to 0 in flight, is
    refused like a plate's whose force does).

    Parameters
    ----------
    path : str or Path
        The accelerometer CSV.
    mass : float, optional
        Body mass (kg). Without it, :data:`UNKNOWN_MASS` is used and marked unknown:
        ``K_h`` and ``C_h`` are then left out of the results.
    units : {"auto", "m/s^2", "g"}
        Units of a plain or vertical file (:func:`read_accelerometer`).
    fs : float, optional
        Rate of the uniform grid (Hz); default the phone's own nominal rate.

    Returns
    -------
    Record
        With ``extra``: ``sensor`` ("accelerometer"), ``mass_known``, ``format``,
        ``units_read``, ``clock`` (:func:`resample_uniform`'s info), ``geometry``
        (:func:`vertical_acceleration`'s info), and per sample ``unmeasured`` (bool,
        inside a gap of the stamps, :func:`unmeasured`), ``direction`` (the unit
        vector of gravity ``e(t)`` in the phone's frame, shape (T, 3)) and ``across``
        (m/s^2, :func:`~smd_statespace.accelerometer.vertical.across_vertical`), from
        which the person model's front end tells a phone fixed to the body from a
        loose one over the part it fits.
    """
    from dataclasses import replace

    from ..io import check_mass, make_record

    mass_known = mass is not None
    body = check_mass(mass) if mass_known else UNKNOWN_MASS
    raw = read_accelerometer(path, units=units)
    time, acc, clock = resample_uniform(raw.time, raw.acc, fs=fs, source=raw.source)
    missing = unmeasured(raw.time, time, clock["fs_nominal"])
    lag = _period_samples(acc, ~missing, clock["fs"]) if missing.any() else 0
    _refuse_a_gap_over_a_cycle(missing, lag, clock, raw.source)
    acc = fill_gaps(acc, missing, clock["fs"], lag=lag)
    a_v, geometry = vertical_acceleration(time, acc, source=raw.source, measured=~missing)
    record = make_record(time - time[0], body * (G + a_v), body, source=raw.source)
    gravity_t = gravity_track(acc, clock["fs"])
    return replace(record, extra={"sensor": "accelerometer", "mass_known": mass_known, "format": raw.format,
                                  "units_read": raw.units_read, "clock": clock, "geometry": geometry,
                                  "unmeasured": missing,
                                  "direction": gravity_t / np.linalg.norm(gravity_t, axis=1, keepdims=True),
                                  "across": across_vertical(acc, gravity_t)})


def unmeasured(stamps, grid, fs_nominal) -> np.ndarray:
    """Which samples of the uniform ``grid`` (s) lie inside a gap of the ``stamps`` (s): an interval longer than
    :data:`GAP_SAMPLES` nominal intervals (``1 / fs_nominal``), more than half an interval from both its ends (a
    grid sample that close to a stamp is read off it); bool, shape of ``grid``."""
    stamps = np.unique(np.asarray(stamps, dtype=float))
    grid = np.asarray(grid, dtype=float)
    dt = 1.0 / float(fs_nominal)
    after = np.clip(np.searchsorted(stamps, grid, side="right"), 1, stamps.size - 1)
    before = stamps[after - 1]
    inside = (grid - before > 0.5 * dt) & (stamps[after] - grid > 0.5 * dt)
    return inside & (stamps[after] - before > (GAP_SAMPLES + 1e-6) * dt)


def _period_samples(acc: np.ndarray, measured: np.ndarray, fs: float) -> int:
    """The bouncing period in samples: the highest autocorrelation of the measured samples' specific-force
    magnitude at lags of one cycle of the supported bouncing frequencies (normalised by the number of measured
    pairs at each lag, so the gaps do not bias it)."""
    from ..signals import SUPPORTED_FB  # here: signals imports pandas and scipy (not needed to read)

    magnitude = np.linalg.norm(acc.reshape(acc.shape[0], -1), axis=1)
    centred = np.where(measured, magnitude - magnitude[measured].mean(), 0.0)
    n = centred.size
    products = np.fft.irfft(np.abs(np.fft.rfft(centred, 2 * n)) ** 2)[:n]
    pairs = np.fft.irfft(np.abs(np.fft.rfft(measured.astype(float), 2 * n)) ** 2)[:n]
    shortest, longest = int(fs / SUPPORTED_FB[1]), min(int(np.ceil(fs / SUPPORTED_FB[0])), n // 2)
    if longest <= shortest:
        return 0
    correlation = products[shortest:longest + 1] / np.maximum(pairs[shortest:longest + 1], 1.0)
    return shortest + int(np.argmax(correlation))


def _gaps(missing: np.ndarray) -> tuple:
    """``(starts, stops)``: the sample ranges of the runs of ``missing``."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], missing.astype(np.int8), [0]])))
    return edges[::2], edges[1::2]


def _refuse_a_gap_over_a_cycle(missing: np.ndarray, lag: int, clock: dict, source: str) -> None:
    """A one-line :class:`RecordError` when the longest gap of the stamps is as long as a bouncing cycle (``lag``
    samples, 0: unknown) or longer: nothing of that cycle was measured (gaps up to
    :data:`~smd_statespace.accelerometer.MAX_GAP` are otherwise read across)."""
    if not missing.any() or not lag:
        return
    starts, stops = _gaps(missing)
    if int((stops - starts).max()) >= lag:
        raise RecordError(f"{source}: no samples for {clock['largest_gap']:.3g} s after t = "
                          f"{clock['largest_gap_at']:.4g} s, as long as a bouncing cycle ({lag / clock['fs']:.3g} s) "
                          "or longer: a whole cycle is missing; use the record on either side")


def fill_gaps(acc, missing, fs: float, lag=None) -> np.ndarray:
    """``acc`` (m/s^2, shape (T, k)) with the samples inside the stamps' gaps (``missing``) taken one bouncing
    period earlier (later at the record's start), shifted to meet the measured samples at both ends.

    The samples stay unmeasured (the person model's likelihood leaves them out); the fill is what the filters
    downstream (the gravity low-pass, the decimation's low-pass, the cycle timing's peaks) see there instead of
    a straight line across the gap, which is up to 5 m/s^2 off a bouncing signal and which an ideal low-pass
    spreads over the measured samples around it. On a phone with every artefact of ``benchmarks/phone_phenomena.py``
    (four gaps of up to 0.25 s among them; seed 4460) the line took ``smooth`` and ``f_h`` +56 to +82 % off on six
    of eight people checked, the fill +0.4 to +8.7 % (``independent``). ``lag``: the period in samples when
    already found (default: found here from the measured samples)."""
    acc = np.array(acc, dtype=float)
    missing = np.asarray(missing, dtype=bool)
    if not missing.any() or missing.all():
        return acc
    values = acc if acc.ndim == 2 else acc[:, None]
    lag = _period_samples(values, ~missing, fs) if lag is None else int(lag)
    if lag == 0:
        return acc
    n = values.shape[0]
    for start, stop in zip(*_gaps(missing)):  # a few gaps per record, each filled at once
        inside = np.arange(start, stop)
        source = inside - lag if start - lag >= 0 else inside + lag
        source = np.clip(source, 0, n - 1)
        chained = missing[source] & (source >= start) & (source < stop)  # a gap longer than the period
        source[chained] = np.clip(source[chained] - lag, 0, n - 1)
        fill = values[source]
        left = values[start - 1] - values[max(source[0] - 1, 0)] if start > 0 else None
        right = values[stop] - values[min(source[-1] + 1, n - 1)] if stop < n else None
        left = right if left is None else left
        right = left if right is None else right
        weight = (np.arange(1, stop - start + 1) / (stop - start + 1))[:, None]
        values[start:stop] = fill + left + (right - left) * weight
    return acc
