"""A bouncing person seen by a body-worn accelerometer (a phone at the waist): reading the record.

A phone clipped to the belt or carried in a trouser pocket moves with the pelvis,
close to the body's centre of mass (COM). Its accelerometer measures the *specific
force* ``f = a - g_vec`` along the phone's own three axes, in m/s^2: the COM
acceleration ``a`` plus the reaction to gravity (``g_vec`` points down, so a phone at
rest reads 9.81 m/s^2 *upwards*). The person model needs one observation, the
vertical COM acceleration without gravity (upwards positive)::

    a_v = f . e_up - g        (m/s^2)

This module turns a phone's file into that signal in three steps, each a public
function that can be inspected on its own:

1. :func:`read_accelerometer` reads the file (phyphox's CSV export, a plain
   ``time,ax,ay,az`` CSV in m/s^2 or g, or a single vertical channel) into an
   :class:`AccelerometerRecord`, in m/s^2, with gravity; it refuses a record
   without gravity (phyphox's "Linear Acceleration" experiment).
2. :func:`resample_uniform` puts the phone's irregular time stamps (jitter, dropped
   samples, duplicates, samples out of order) onto a uniform grid by linear
   interpolation, and refuses a gap longer than :data:`MAX_GAP`.
3. :func:`vertical_acceleration` estimates the direction of gravity from the record
   itself (a zero-phase low-pass at :data:`GRAVITY_CUTOFF`), projects the three axes
   onto it and removes the record's own gravity magnitude; it refuses a record
   in which the phone lay still for more than :data:`STILL_DURATION` between
   stretches of bouncing.

Together::

    record = read_accelerometer("phone.csv")
    time, acc, clock = resample_uniform(record.time, record.acc, source=record.source)
    a_v, geometry = vertical_acceleration(time, acc, source=record.source)

Every problem with the input raises a :class:`~smd_statespace.errors.RecordError`
(the file or its data) or an :class:`~smd_statespace.errors.OptionError` (an
argument) with a one-line message naming the file, column or option and what is
valid, like :func:`smd_statespace.io.read_record`.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import OptionError, RecordError
from .io import G, SAMPLING_TOLERANCE, csv_rows, numeric_column

__all__ = [
    "UNITS",
    "FORMATS",
    "RATE_RANGE",
    "RATE_TOLERANCE",
    "MAX_GAP",
    "GRAVITY_CUTOFF",
    "GRAVITY_ORDER",
    "GRAVITY_TOLERANCE",
    "LINEAR_ACCELERATION_LIMIT",
    "STILL_DURATION",
    "STILL_FRACTION",
    "ACCEPTED_HEADERS",
    "AccelerometerRecord",
    "read_accelerometer",
    "resample_uniform",
    "vertical_acceleration",
    "UNKNOWN_MASS",
    "accelerometer_record",
]

UNITS = ("auto", "m/s^2", "g")
"""Values of ``units`` accepted by :func:`read_accelerometer`: ``"auto"`` decides from the data."""

FORMATS = ("phyphox", "plain", "vertical")
"""The file formats :func:`read_accelerometer` recognises from the header (see there)."""

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

GRAVITY_CUTOFF = 0.3
"""Cut-off (Hz) of the zero-phase low-pass that separates gravity from bouncing.

Well below the slowest bouncing (1.5 Hz in the article, 1.2 Hz supported): with
:data:`GRAVITY_ORDER` 4, run forwards and backwards, the gravity estimate keeps
``1 / (1 + (f / 0.3)^8)`` of a component at ``f``, i.e. 1.5e-5 at 1.2 Hz and
2.6e-6 at 1.5 Hz, while it follows the slow tilt and sway of the phone (a 0.1 Hz
sway is passed with a gain of 0.99985)."""

GRAVITY_ORDER = 4
"""Butterworth order of one pass of the gravity low-pass (:data:`GRAVITY_CUTOFF`)."""

GRAVITY_TOLERANCE = 0.3
"""Largest relative deviation of the record's gravity level from 1 g.

``units="auto"`` reads a record whose level is within 1 +- 0.3 as g and within
9.81 +- 30 % as m/s^2, and :func:`vertical_acceleration` refuses a gravity
magnitude outside 9.81 m/s^2 +- 30 % (a record in g, or without gravity). Phone
accelerometers are within a few percent of 1 g at rest."""

LINEAR_ACCELERATION_LIMIT = 0.5
"""A record whose gravity level is below this many g never saw gravity.

The gravity level is the magnitude of the record's mean acceleration vector
``|mean(a)|``: about 1 g whenever the axes include gravity (slightly less if the
phone turns during the record: ``cos`` of the turn), about 0 for a
linear-acceleration export, whose mean is the mean COM acceleration. The mean of
the magnitude, ``mean(|a|)``, would not separate the two as well: for vigorous
bouncing the linear acceleration's magnitude averages 0.3-0.6 g."""

STILL_DURATION = 2.0
"""Length (s) of a stretch of stillness that :func:`vertical_acceleration` refuses between bouncing."""

STILL_FRACTION = 0.05
"""A stretch is *still* when its dynamic acceleration's RMS is below this fraction of the record's.

Bouncing gives a dynamic RMS of 1-4 m/s^2; a phone lying on a table shows only
its noise (0.01-0.05 m/s^2 per axis); quiet standing about 0.02-0.1 m/s^2."""

_PHYPHOX_TIME = "Time (s)"
_PHYPHOX_AXES = ("Acceleration x (m/s^2)", "Acceleration y (m/s^2)", "Acceleration z (m/s^2)")
_PHYPHOX_LINEAR_AXES = tuple(f"Linear {name}" for name in _PHYPHOX_AXES)
_PHYPHOX_ABSOLUTE = "Absolute acceleration (m/s^2)"
_TIME_NAMES = ("time", "t")
_DELIMITERS = (("tab", "\t"), ("semicolon", ";"), ("comma", ","))

ACCEPTED_HEADERS = (
    '"Time (s)","Acceleration x (m/s^2)","Acceleration y (m/s^2)","Acceleration z (m/s^2)"'
    '[,"Absolute acceleration (m/s^2)"] (phyphox), time,ax,ay,az, time,acc or time,az '
    "(any case; t for time; separated by commas, semicolons or tabs)"
)
"""The headers :func:`read_accelerometer` accepts, as its error messages list them."""


@dataclass(frozen=True)
class AccelerometerRecord:
    """An accelerometer record as read from a file: in m/s^2, with gravity, time stamps as recorded.

    Attributes
    ----------
    time : ndarray, shape (T,)
        Time stamps (s) as recorded: possibly irregular, with gaps, duplicates or
        samples out of order (:func:`resample_uniform` puts them on a grid).
    acc : ndarray, shape (T, 3) or (T, 1)
        Specific force (m/s^2) including gravity: the phone's x, y, z axes, or a
        single channel along a vertical axis.
    source : str
        Where the record came from (the file name), used in error messages.
    units_read : str
        The units of the file: ``"m/s^2"`` or ``"g"`` (``acc`` is in m/s^2 either way).
    format : str
        One of :data:`FORMATS`: ``"phyphox"``, ``"plain"`` (``time,ax,ay,az``) or
        ``"vertical"`` (``time,acc`` or ``time,az``).
    """

    time: np.ndarray
    acc: np.ndarray
    source: str
    units_read: str
    format: str

    @property
    def duration(self) -> float:
        """Time from the first to the last time stamp (s)."""
        return float(np.max(self.time) - np.min(self.time))


# ---------------------------------------------------------------------------
# 1. Reading
# ---------------------------------------------------------------------------


def _delimiter(path, first_line: str) -> str:
    """The header's delimiter (tab, semicolon or comma), or a :class:`RecordError` naming what was found.

    :func:`smd_statespace.io._sniff_delimiter` insists on commas (a GRF record is
    written by this library); phyphox also exports with semicolons and tabs.
    """
    line = first_line.strip()
    for _, delimiter in _DELIMITERS:
        if delimiter in line:
            return delimiter
    for name, delimiter in (("space", " "), ("'|'", "|")):
        if delimiter in line and not line.startswith('"'):
            raise RecordError(
                f"{path}: header {line!r} is {name}-separated; accelerometer records are separated by commas, "
                "semicolons or tabs"
            )
    raise RecordError(f"{path}: header {line!r} has a single column; accepted headers: {ACCEPTED_HEADERS}")


def _layout(path, header: list) -> tuple:
    """``(format, [time column, acceleration columns...])`` from the header's names (exact spelling)."""
    names = [name.strip() for name in header]
    lower = [name.lower() for name in names]
    if len(set(lower)) != len(lower):
        raise RecordError(f"{path}: header {','.join(names)!r} repeats a column; accepted headers: {ACCEPTED_HEADERS}")
    position = {name: i for i, name in enumerate(lower)}
    found = set(lower) - {_PHYPHOX_ABSOLUTE.lower()}
    phyphox = {_PHYPHOX_TIME.lower(), *(name.lower() for name in _PHYPHOX_AXES)}
    if found == {_PHYPHOX_TIME.lower(), *(name.lower() for name in _PHYPHOX_LINEAR_AXES)}:
        raise RecordError(
            f"{path}: header names {_PHYPHOX_LINEAR_AXES[0]!r}: a linear-acceleration export, without gravity; "
            "record with phyphox's 'Acceleration with g'"
        )
    if found == phyphox:
        columns = [_PHYPHOX_TIME, *_PHYPHOX_AXES]
        return "phyphox", [names[position[name.lower()]] for name in columns]
    time = [name for name in _TIME_NAMES if name in position]
    rest = set(lower) - set(time)
    if len(time) == 1:
        if rest == {"ax", "ay", "az"}:
            return "plain", [names[position[name]] for name in (time[0], "ax", "ay", "az")]
        if rest in ({"acc"}, {"az"}):
            return "vertical", [names[position[name]] for name in (time[0], *rest)]
    raise RecordError(f"{path}: header {','.join(names)!r} is not an accelerometer record; accepted headers: "
                      f"{ACCEPTED_HEADERS}")


def _read_rows(path: Path) -> tuple:
    """The file's header, data rows and delimiter, or a :class:`RecordError`."""
    rows, delimiter = csv_rows(path, f"a header ({ACCEPTED_HEADERS})", _delimiter)
    body = [row for row in rows[1:] if any(cell.strip() for cell in row)]
    return rows[0], body, delimiter


def _gravity_level(acc: np.ndarray) -> float:
    """``|mean(a)|``: the magnitude of the record's mean acceleration vector (see :data:`LINEAR_ACCELERATION_LIMIT`)."""
    return float(np.linalg.norm(acc.mean(axis=0)))


def _units(path, units: str, level: float, fmt: str) -> str:
    """The units of the file, from the option and the data's gravity level (in the file's units)."""
    if fmt == "phyphox":
        if units == "g":
            raise OptionError(f"{path}: units='g', but phyphox's header says m/s^2; use units='auto' or 'm/s^2'")
        return "m/s^2"
    if units != "auto":
        return units
    if abs(level - 1.0) <= GRAVITY_TOLERANCE:
        return "g"
    if abs(level / G - 1.0) <= GRAVITY_TOLERANCE:
        return "m/s^2"
    if level < LINEAR_ACCELERATION_LIMIT:
        return "m/s^2"  # no gravity in either unit: the check in read_accelerometer says so
    raise RecordError(
        f"{path}: cannot tell the units: the mean acceleration has magnitude {level:.4g}, neither about 1 (g) "
        f"nor about {G:.2f} (m/s^2); give units='g' or units='m/s^2'"
    )


def read_accelerometer(path, units: str = "auto") -> AccelerometerRecord:
    """Read a phone's accelerometer record (CSV) and check that it includes gravity.

    The format is recognised from the header (names in any case and order,
    surrounding quotes and spaces ignored):

    ``"Time (s)","Acceleration x (m/s^2)","Acceleration y (m/s^2)","Acceleration z (m/s^2)"``
        **phyphox**, experiment "Acceleration with g", as exported by the app
        (quoted names, numbers like ``9.806650000E0``), optionally with a fifth
        column ``"Absolute acceleration (m/s^2)"``, which is not read (it is
        ``|a|``, derivable, and phyphox pads it with ``NaN``). Always m/s^2.
    ``time,ax,ay,az`` (or ``t,ax,ay,az``)
        **plain**: the phone's three axes in m/s^2 or g.
    ``time,acc`` or ``time,az``
        **vertical**: one channel along a vertical axis (up or down), with gravity,
        in m/s^2 or g.

    Columns may be separated by commas, semicolons or tabs (the delimiter is
    taken from the header). With semicolons or tabs a decimal comma
    (``9,81``, phyphox's "decimal comma" exports) is read as a decimal point; with
    commas it cannot be told from a delimiter.

    Parameters
    ----------
    path : str or path-like
        The CSV file.
    units : {"auto", "m/s^2", "g"}, default "auto"
        Units of the acceleration columns. ``"auto"`` reads phyphox files as m/s^2
        (their header says so) and decides for the others from the record's
        gravity level ``|mean(a)|``: within 1 +- :data:`GRAVITY_TOLERANCE` it is g,
        within 9.81 m/s^2 +- 30 % it is m/s^2, anything else is an error.

    Returns
    -------
    AccelerometerRecord
        Time stamps as recorded (s) and the specific force in m/s^2, gravity
        included, shape (T, 3) or (T, 1).

    Raises
    ------
    RecordError
        The file is missing, unreadable, empty or has an unknown header; a row has
        the wrong number of fields or a cell is not a finite number (naming column
        and row); the units cannot be told; or the record never saw gravity (its
        gravity level is below :data:`LINEAR_ACCELERATION_LIMIT` g: phyphox's
        "Linear Acceleration" experiment, or any gravity-removed export).
    OptionError
        ``units`` is not one of :data:`UNITS`, or is ``"g"`` for a phyphox file.

    Notes
    -----
    A record without gravity cannot be used: the direction of gravity is what
    :func:`vertical_acceleration` finds the vertical from, and phones compute the
    linear acceleration by subtracting their own gravity estimate (a sensor-fusion
    filter whose errors at the bouncing frequencies are unknown).
    """
    if units not in UNITS:
        raise OptionError(f"units={units!r} is not one of {', '.join(UNITS)}")
    path = Path(path)
    source = os.fspath(path)
    header, body, delimiter = _read_rows(path)
    fmt, columns = _layout(path, header)
    if not body:
        raise RecordError(f"{path}: header only, no data rows")
    width = len(header)
    lengths = np.fromiter((len(row) for row in body), dtype=int, count=len(body))
    if (lengths != width).any():
        number = int(np.argmax(lengths != width)) + 1
        extra = delimiter == "," and lengths[number - 1] > width
        hint = "; decimal commas need a semicolon or tab delimiter" if extra else ""
        raise RecordError(f"{path}: data row {number} has {lengths[number - 1]} fields, the header has {width}{hint}")
    if len(body) < 3:
        raise RecordError(f"{path}: only {len(body)} data rows; a record needs at least one bouncing cycle")
    cells = np.array(body, dtype=object)
    names = [name.strip() for name in header]
    texts = [np.char.strip(cells[:, names.index(name)].astype(str)) for name in columns]  # 2 or 4 columns
    decimal_comma = delimiter != "," and any((np.char.find(text, ",") >= 0).any() for text in texts)
    numbers = []
    for name, column in zip(columns, texts):
        if decimal_comma:
            column = np.char.replace(column, ",", ".")
        try:
            numbers.append(numeric_column(column.astype(object), name, source))
        except RecordError as exc:
            raise RecordError(f"{exc} (decimal commas read as points)" if decimal_comma else str(exc)) from None
    time = numbers[0]
    acc = np.column_stack(numbers[1:])
    units_read = _units(path, units, _gravity_level(acc), fmt)
    if units_read == "g":
        acc = acc * G
    level = _gravity_level(acc) / G
    if fmt != "phyphox" and units_read == "m/s^2" and abs(level * G - 1.0) <= GRAVITY_TOLERANCE:
        raise RecordError(
            f"{path}: the mean acceleration has magnitude {level:.3g} g with units='m/s^2'; it looks like g: "
            "give units='g' or 'auto'"
        )
    if level < LINEAR_ACCELERATION_LIMIT:
        hint = ("record with phyphox's 'Acceleration with g'" if fmt == "phyphox"
                else "export the acceleration including gravity")
        raise RecordError(
            f"{path}: the axes never see gravity (|mean a| {level:.2f} g): a linear-acceleration export; {hint}"
        )
    if abs(level - 1.0) > GRAVITY_TOLERANCE:
        raise RecordError(
            f"{path}: the mean acceleration has magnitude {level:.3g} g with units={units_read!r}; "
            f"a record with gravity has about 1 g: check the units ({', '.join(UNITS[1:])})"
        )
    return AccelerometerRecord(time=time, acc=acc, source=source, units_read=units_read, format=fmt)


# ---------------------------------------------------------------------------
# 2. Clock
# ---------------------------------------------------------------------------


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
    """The phone's clock: ``(interval, jitter sd, sample numbers)`` from a line through the stamps.

    The stamps are numbered ``round((t - t0 - offset) / dt)``, dropped samples and
    all, and a least-squares line through stamps against numbers gives the
    interval. The numbering is right while the drift of the current ``dt`` over
    the stretch, plus the jitter, stays within half an interval; so it starts on
    the first 64 intervals with the median ``dt`` and doubles the stretch with
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
            residual = used - used.mean() - dt * centred
            return dt, float(np.std(residual)), number
        span *= 2.0


def resample_uniform(time, acc, fs=None, *, max_gap: float = MAX_GAP, source: str = "<arrays>") -> tuple:
    """Put an accelerometer record with a phone's irregular clock onto a uniform time grid.

    Phones stamp each sample with the time the sensor delivered it: the intervals
    jitter by a fraction of a millisecond, samples get dropped (often when the
    phone is busy), the same stamp can appear twice and a sample can arrive out
    of order. The steps:

    1. **Order**: the samples are sorted by time (stable sort); a step backwards
       larger than ``max_gap`` is refused (the clock was reset, or two records
       were concatenated), smaller ones are counted in ``n_backwards``.
    2. **Duplicates**: samples with the same time stamp are merged into their mean.
    3. **Rate**: the nominal interval is first the median of the intervals,
       robust to jitter and to dropped samples, then refined by a least-squares
       line through the time stamps against their sample numbers (dropped
       samples keep their numbers). The median of jittered intervals can be off
       the phone's true rate by 0.04-1 %, enough for a grid at that rate to slide
       by several samples across a record; the line is good to about 1e-5 and
       keeps the grid on the samples (see the Notes). ``fs_nominal`` is the
       refined rate; the grid's rate is ``fs`` if given, else ``fs_nominal``. The
       record's rate must lie in :data:`RATE_RANGE` (within
       :data:`RATE_TOLERANCE`), ``fs`` in :data:`RATE_RANGE`.
    4. **Gaps**: an interval longer than ``max_gap`` is refused (interpolating
       through it would invent the better part of a bouncing cycle); shorter ones
       (dropped samples) are bridged.
    5. **Interpolation**: each grid time ``t0 + n / fs`` up to the last stamp gets
       the straight line between the two samples around it (vectorised: one
       ``searchsorted`` and one weighted sum for all axes).

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
        stamps about the fitted uniform clock).

    Raises
    ------
    RecordError
        Arrays of mismatched shapes or with non-finite values, fewer than 3
        distinct time stamps, a record rate outside :data:`RATE_RANGE`, a gap
        longer than ``max_gap`` (naming its time and length) or a jump back in
        time longer than ``max_gap``.
    OptionError
        ``fs`` outside :data:`RATE_RANGE` or ``max_gap`` not a positive number.

    Notes
    -----
    **Why linear interpolation.** It is local (a dropped sample or a glitch
    affects one interval only), never overshoots, needs no assumption about
    the band of the signal, and costs one weighted sum per sample; a band-limited
    (sinc or spline) interpolator would spread an irregularity over many samples
    and ring at gaps. Its price is a small, known low-pass. A grid point a fraction
    ``mu`` of an interval after a sample receives ``(1 - mu) x[k] + mu x[k+1]``,
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
    lo, hi = RATE_RANGE
    if fs is not None:
        fs = _check_rate_option("fs", fs)
    if isinstance(max_gap, bool) or not isinstance(max_gap, (int, float)) or not (math.isfinite(max_gap)
                                                                                 and max_gap > 0):
        raise OptionError(f"max_gap={max_gap!r}: give the longest gap to interpolate across in s, e.g. {MAX_GAP:g}")
    squeeze = np.ndim(acc) == 1
    time, acc2 = _check_arrays(time, acc, source)
    steps = np.diff(time)
    if steps.size and steps.min() < -max_gap:
        k = int(np.argmin(steps))
        raise RecordError(
            f"{source}: time jumps back by {-steps[k]:.4g} s at row {k + 2} (t = {time[k + 1]:.4g} s); "
            "a record must come from one clock without resets"
        )
    n_backwards = int(np.count_nonzero(steps < 0))
    order = np.argsort(time, kind="stable")
    stamps, first, counts = np.unique(time[order], return_index=True, return_counts=True)
    merged = np.add.reduceat(acc2[order], first, axis=0) / counts[:, None]
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
    k = int(np.argmax(steps))
    if steps[k] > max_gap:
        raise RecordError(
            f"{source}: no samples for {steps[k]:.3g} s after t = {stamps[k]:.4g} s; gaps longer than "
            f"{max_gap:g} s cannot be interpolated: use the record on either side"
        )
    dt, jitter, number = _fit_clock(stamps, dt)
    fs_nominal = 1.0 / dt
    rate = fs_nominal if fs is None else fs
    n_out = int(math.floor((stamps[-1] - stamps[0]) * rate + 1e-9)) + 1
    grid = stamps[0] + np.arange(n_out) / rate
    left = np.clip(np.searchsorted(stamps, grid, side="right") - 1, 0, stamps.size - 2)
    weight = np.clip((grid - stamps[left]) / steps[left], 0.0, 1.0)[:, None]
    values = merged[left] * (1.0 - weight) + merged[left + 1] * weight
    info = {
        "fs": float(rate),
        "fs_nominal": float(fs_nominal),
        "n_samples_in": int(time.size),
        "n_samples_out": int(n_out),
        "n_duplicates": int(time.size - stamps.size),
        "n_backwards": n_backwards,
        "n_dropped": int(max(number.max() - number.min() + 1 - stamps.size, 0)),
        "largest_gap": float(steps[k]),
        "largest_gap_at": float(stamps[k]),
        "jitter_sd": jitter,
    }
    return grid, (values[:, 0] if squeeze else values), info


# ---------------------------------------------------------------------------
# 3. The vertical
# ---------------------------------------------------------------------------


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


def vertical_acceleration(time, acc, *, cutoff: float = GRAVITY_CUTOFF, source: str = "<arrays>") -> tuple:
    """The vertical COM acceleration without gravity, ``a_v`` (m/s^2, up positive), from a uniform record.

    **Three axes.** The direction of gravity is estimated from the record itself.
    A zero-phase low-pass of the three axes at ``cutoff`` (Butterworth, order
    :data:`GRAVITY_ORDER`, forwards and backwards) keeps the slowly changing
    specific force of gravity ``g(t)`` in the phone's frame, following slow tilt
    and sway of the phone while removing the bouncing; its unit vector
    ``e(t) = g(t) / |g(t)|`` is "up" in the phone's frame. Then

        a_v(t) = acc(t) . e(t) - |g|

    with ``|g|`` the record's own gravity magnitude, the median of ``|g(t)|``, not
    9.81: a sensor's bias or scale error changes ``|g|`` and would otherwise leave
    a constant offset in ``a_v``. The low-pass is computed as the complement of
    :func:`smd_statespace.signals.highpass` (``acc - highpass(acc)``: for a
    zero-phase Butterworth pair the two responses add up to one), whose
    ``"predict"`` padding keeps the record's ends free of start-up transients.

    **One vertical channel.** ``a_v = s acc - |g|`` with ``|g|`` the median of the
    channel's low-passed level and ``s`` its sign (+1 for an axis pointing up,
    -1 for one pointing down). The median of the raw channel would not do: a
    bouncing acceleration is skewed (sharp peaks while the feet push, flat
    troughs), so its median differs from its mean (0.7 m/s^2 for the harmonics
    3, 2, 0.8, 0.3 m/s^2 of a 2.2 Hz bounce).

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

    Returns
    -------
    a_v : ndarray, shape (T,)
        Vertical acceleration of the phone (~ the COM) without gravity (m/s^2),
        up positive; its mean over the record is about zero.
    info : dict
        ``gravity`` (m/s^2, the record's ``|g|``); ``tilt_deg``, the angle between
        the mean gravity direction and the phone's z axis (0 = lying screen up,
        90 = upright, as in a pocket, 180 = screen down); ``direction_change_deg``,
        the largest angle between ``e(t)`` and its mean direction over the record
        (the phone's slow sway; both None for one channel); ``cutoff`` (Hz);
        ``still_start`` and ``still_end`` (s), the length of a still stretch at the
        start or end of the record (e.g. before the bouncing began), 0 if none;
        they are not refused, trim them if the model should not see them.

    Raises
    ------
    RecordError
        Arrays of mismatched shapes or with non-finite values; time not uniform
        (within :data:`~smd_statespace.io.SAMPLING_TOLERANCE`); a record shorter
        than ``1 / cutoff``; a gravity magnitude not about 9.81 m/s^2 (a record in
        g, or without gravity); or a still stretch longer than
        :data:`STILL_DURATION` between stretches of bouncing (the phone put down
        halfway, or the bouncing stopped), naming its time and length.
    OptionError
        ``cutoff`` is not in (0, 0.6] Hz.

    Notes
    -----
    **Why a sensor bias does not matter.** A bias ``b`` of the axes is constant:
    the low-pass passes it whole, so ``g(t)`` becomes ``g(t) + b``. Its component
    along ``e`` adds to both ``acc . e`` and ``|g|`` and cancels; its component
    across ``e`` tilts ``e`` by at most ``|b| / |g|`` (1.2 deg for 0.2 m/s^2),
    which scales the vertical signal by ``cos`` of that (0.99978) and mixes in
    2 % of the small horizontal acceleration. A constant has no content at any
    bouncing frequency; all it could do is move the mean, which the median
    ``|g|`` removes. A common scale error of the sensor scales ``a_v`` by the
    same factor (a few tenths of a percent for a phone): it is not corrected,
    ``info["gravity"] / 9.80665`` shows it together with any bias.

    **Why the low-pass.** The direction ``e(t)`` must not see the bouncing: a
    2 % leak of it would modulate the direction at the bouncing frequency. At
    :data:`GRAVITY_CUTOFF` the leak is 1e-5 (see there). Rotation of the pelvis
    *at* the bouncing frequency is not followed; a +-5 deg rocking changes the
    projection by ``g (1 - cos 5 deg) = 0.04 m/s^2`` at twice that frequency.

    **Stillness.** A stretch longer than :data:`STILL_DURATION` whose movement
    (RMS about its own mean) is below :data:`STILL_FRACTION` of the record's
    dynamic RMS (``acc - g(t)``) with bouncing on both sides is refused: the
    model would see a person who stopped. At either end such a stretch is
    reported (``still_start``, ``still_end``), not refused.
    """
    from .signals import SUPPORTED_FB, highpass  # here: signals imports pandas and scipy (not needed to read)

    time, acc2 = _check_arrays(time, acc, source)
    if acc2.shape[1] not in (1, 3):
        raise RecordError(f"{source}: acc has {acc2.shape[1]} columns; expected 3 axes or 1 vertical channel")
    cutoff_max = SUPPORTED_FB[0] / 2.0
    if isinstance(cutoff, bool) or not isinstance(cutoff, (int, float)) or not (math.isfinite(cutoff)
                                                                               and 0.0 < cutoff <= cutoff_max):
        raise OptionError(
            f"cutoff={cutoff!r}: the gravity low-pass cut-off must be in (0, {cutoff_max:g}] Hz, well below "
            f"the bouncing frequency (default {GRAVITY_CUTOFF:g})"
        )
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
    fs = 1.0 / dt
    duration = float(time[-1] - time[0])
    if duration < 1.0 / cutoff:
        raise RecordError(
            f"{source}: the record lasts {duration:.3g} s; finding the direction of gravity with a "
            f"{cutoff:g} Hz low-pass needs at least {1.0 / cutoff:.3g} s"
        )
    gravity_t = acc2 - highpass(acc2, fs, cutoff, GRAVITY_ORDER, axis=0)
    magnitude = np.linalg.norm(gravity_t, axis=1)
    gravity = float(np.median(magnitude))
    if abs(gravity / G - 1.0) > GRAVITY_TOLERANCE:
        raise RecordError(
            f"{source}: gravity magnitude {gravity:.4g} m/s^2, expected about {G:.2f}; acc must be in m/s^2 and "
            "include gravity"
        )
    if acc2.shape[1] == 1:
        sign = 1.0 if np.median(gravity_t[:, 0]) > 0 else -1.0
        a_v = sign * acc2[:, 0] - gravity
        tilt = change = None
    else:
        direction = gravity_t / np.maximum(magnitude, 1e-12)[:, None]
        a_v = np.einsum("ij,ij->i", acc2, direction) - gravity
        mean_direction = gravity_t.mean(axis=0)
        mean_direction /= np.linalg.norm(mean_direction)
        tilt = float(np.degrees(np.arccos(np.clip(mean_direction[2], -1.0, 1.0))))
        change = float(np.degrees(np.arccos(np.clip(direction @ mean_direction, -1.0, 1.0))).max())
    dynamic_rms = float(np.sqrt(np.mean(((acc2 - gravity_t) ** 2).sum(axis=1))))
    stretches = _still_stretches(acc2, dynamic_rms, fs)
    n = time.size
    still_start = still_end = 0.0
    for start, stop in stretches:  # a handful of stretches, not samples
        if start == 0:
            still_start = (stop - start) / fs
        elif stop == n:
            still_end = (stop - start) / fs
        else:
            raise RecordError(
                f"{source}: no movement from t = {time[start]:.1f} s for {(stop - start) / fs:.1f} s "
                f"(RMS below {STILL_FRACTION:.0%} of the record's) while the rest moves: was the phone put down? "
                "use a record of continuous bouncing"
            )
    info = {
        "gravity": gravity,
        "tilt_deg": tilt,
        "direction_change_deg": change,
        "cutoff": float(cutoff),
        "still_start": float(still_start),
        "still_end": float(still_end),
    }
    return a_v, info


# ---------------------------------------------------------------------------
# 4. The record the person model reads
# ---------------------------------------------------------------------------

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
        ``units_read``, ``clock`` (:func:`resample_uniform`'s info) and ``geometry``
        (:func:`vertical_acceleration`'s info).
    """
    from dataclasses import replace

    from .io import check_mass, make_record

    mass_known = mass is not None
    body = check_mass(mass) if mass_known else UNKNOWN_MASS
    raw = read_accelerometer(path, units=units)
    time, acc, clock = resample_uniform(raw.time, raw.acc, fs=fs, source=raw.source)
    a_v, geometry = vertical_acceleration(time, acc, source=raw.source)
    record = make_record(time - time[0], body * (G + a_v), body, source=raw.source)
    return replace(record, extra={"sensor": "accelerometer", "mass_known": mass_known, "format": raw.format,
                                  "units_read": raw.units_read, "clock": clock, "geometry": geometry})
