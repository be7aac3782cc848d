"""An accelerometer file as the person model reads it: :func:`accelerometer_record`.
"""

from __future__ import annotations

import numpy as np

from ..io import G
from .reading import read_accelerometer
from .resampling import resample_uniform
from .vertical import across_vertical, gravity_track, vertical_acceleration

__all__ = ["GAP_SAMPLES", "UNKNOWN_MASS", "accelerometer_record", "unmeasured"]

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
