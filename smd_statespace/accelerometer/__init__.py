"""A bouncing person seen by a body-worn accelerometer (a phone at the waist): reading the record.

A phone clipped to the belt or carried in a trouser pocket moves with the pelvis,
close to the body's centre of mass (COM). Its accelerometer measures the *specific
force* ``f = a - g_vec`` along the phone's own three axes, in m/s^2: the COM
acceleration ``a`` plus the reaction to gravity (``g_vec`` points down, so a phone at
rest reads 9.81 m/s^2 *upwards*). The person model needs one observation, the
vertical COM acceleration without gravity (upwards positive)::

    a_v = f . e_up - g        (m/s^2)

This package turns a phone's file into that signal in three steps, each a public
function that can be inspected on its own:

1. :func:`read_accelerometer` reads the file (phyphox's CSV export, a plain
   ``time,ax,ay,az`` CSV in m/s^2 or g, or a single vertical channel) into an
   :class:`AccelerometerRecord`, in m/s^2, with gravity; it refuses a record
   without gravity (phyphox's "Linear Acceleration" experiment).
2. :func:`resample_uniform` puts the phone's irregular time stamps (jitter, dropped
   samples, duplicates, samples out of order) onto a uniform grid by linear
   interpolation, at their stamps or, when the record shows the samples were taken
   on the phone's clock and stamped late or early, on that clock; it refuses a gap
   longer than :data:`MAX_GAP`.
3. :func:`vertical_acceleration` estimates the direction of gravity from the record
   itself (a zero-phase low-pass at :data:`GRAVITY_CUTOFF`), projects the three axes
   onto it and removes the sensor's own reading of gravity in that direction
   (bias and gains make it turn with the phone); it reports stretches in which the
   phone lay still for more than :data:`STILL_DURATION` (standing, or put down).

Together::

    record = read_accelerometer("phone.csv")
    time, acc, clock = resample_uniform(record.time, record.acc, source=record.source)
    a_v, geometry = vertical_acceleration(time, acc, source=record.source)

The steps live in :mod:`~smd_statespace.accelerometer.reading`,
:mod:`~smd_statespace.accelerometer.resampling` and
:mod:`~smd_statespace.accelerometer.vertical`; :func:`accelerometer_record`
(:mod:`~smd_statespace.accelerometer.record`) chains them into the record the
person model reads. Every name is importable from the package itself.

Every problem with the input raises a :class:`~smd_statespace.errors.RecordError`
(the file or its data) or an :class:`~smd_statespace.errors.OptionError` (an
argument) with a one-line message naming the file, column or option and what is
valid, like :func:`smd_statespace.io.read_record`.
"""

from .reading import (
    ACCEPTED_HEADERS,
    FORMATS,
    GRAVITY_TOLERANCE,
    LINEAR_ACCELERATION_LIMIT,
    UNITS,
    AccelerometerRecord,
    read_accelerometer,
)
from .record import UNKNOWN_MASS, accelerometer_record
from .resampling import MAX_GAP, RATE_RANGE, RATE_TOLERANCE, resample_uniform
from .vertical import (
    GRAVITY_CUTOFF,
    GRAVITY_ORDER,
    ORIENTATION_SPREAD,
    STILL_DURATION,
    STILL_FRACTION,
    across_vertical,
    gravity_level,
    gravity_track,
    vertical_acceleration,
)

__all__ = [
    "UNITS",
    "FORMATS",
    "RATE_RANGE",
    "RATE_TOLERANCE",
    "MAX_GAP",
    "GRAVITY_CUTOFF",
    "GRAVITY_ORDER",
    "GRAVITY_TOLERANCE",
    "ORIENTATION_SPREAD",
    "LINEAR_ACCELERATION_LIMIT",
    "STILL_DURATION",
    "STILL_FRACTION",
    "ACCEPTED_HEADERS",
    "AccelerometerRecord",
    "read_accelerometer",
    "resample_uniform",
    "vertical_acceleration",
    "gravity_level",
    "gravity_track",
    "across_vertical",
    "UNKNOWN_MASS",
    "accelerometer_record",
]
