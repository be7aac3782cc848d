"""Reading a phone's accelerometer file: phyphox's CSV export, a plain ``time,ax,ay,az`` CSV or one vertical channel.

:func:`read_accelerometer` recognises the format from the header, reads the
numbers (decimal commas too, with a semicolon or tab delimiter), decides the units
(m/s^2 or g) and refuses a record without gravity; the result is an
:class:`AccelerometerRecord` in m/s^2, with gravity, time stamps as recorded.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import OptionError, RecordError
from ..io import G, csv_rows, numeric_column
from ..plate_exports import ACCELERATION_UNITS, split_name

__all__ = [
    "UNITS",
    "FORMATS",
    "GRAVITY_TOLERANCE",
    "LINEAR_ACCELERATION_LIMIT",
    "ACCEPTED_HEADERS",
    "AccelerometerRecord",
    "read_accelerometer",
]

UNITS = ("auto", "m/s^2", "g")
"""Values of ``units`` accepted by :func:`read_accelerometer`: ``"auto"`` decides from the data."""

FORMATS = ("phyphox", "plain", "vertical", "labelled", "physics toolbox")
"""The file formats :func:`read_accelerometer` recognises from the header (see there)."""

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

_PHYPHOX_TIME = "Time (s)"
_PHYPHOX_AXES = ("Acceleration x (m/s^2)", "Acceleration y (m/s^2)", "Acceleration z (m/s^2)")
_PHYPHOX_LINEAR_AXES = tuple(f"Linear {name}" for name in _PHYPHOX_AXES)
_PHYPHOX_ABSOLUTE = "Absolute acceleration (m/s^2)"
_TIME_NAMES = ("time", "t")
_DELIMITERS = (("tab", "\t"), ("semicolon", ";"), ("comma", ","))
_LABELLED_TIME = ("time", "t", "elapsed", "accelerometertimestamp sincereboot")  # the last: SensorLog's
_TIME_UNITS = {"s": 1.0, "ms": 1e-3}
_SECONDS_NAMES = ("seconds elapsed",)  # Sensor Logger's (its "time" is an epoch in ns, without a unit)
_LABELLED_AXIS = re.compile(r"^(?:(?:accelerometer)?acc(?:el(?:eration|erometer)?)?[\s_-]*)?([xyz])"
                            r"(?:[\s_-]*axis)?$")  # x, Accel_X, x-axis, SensorLog's accelerometerAccelerationX
_G_FORCE_AXES = ("gfx", "gfy", "gfz")
"""Physics Toolbox Sensor Suite's g-force meter: the specific force in g along the phone's axes (``time,gFx,gFy,gFz,
TgF``; its multi-record export adds ``wx``, ``Bx``, ...), its time in s or as a clock (``00:01.234``)."""
_CLOCK = re.compile(r"^(?:(\d+):)?(\d+):(\d+(?:[.,]\d*)?)(?::(\d{1,3}))?$")
"""A time written as a clock: ``MM:SS.fff``, ``HH:MM:SS.fff`` or ``HH:MM:SS:fff`` (milliseconds after a colon)."""

ACCEPTED_HEADERS = (
    '"Time (s)","Acceleration x (m/s^2)","Acceleration y (m/s^2)","Acceleration z (m/s^2)"'
    '[,"Absolute acceleration (m/s^2)"] (phyphox), time,ax,ay,az, time,acc or time,az '
    "(any case; t for time; separated by commas, semicolons or tabs), or a time in s or ms and x, y, z axes "
    'named with their unit, other columns left alone ("Time (s)","X (m/s^2)",... as phyphox exports a sensor; '
    "elapsed (s),x-axis (g),... as MetaWear does; seconds_elapsed,ACCELEROMETER X (m/s²),... as Sensor Logger "
    "does; accelerometerTimestamp_sinceReboot(s),accelerometerAccelerationX(G),... as SensorLog does; Accel_X "
    "(m/s^2)), or Physics Toolbox's g-force meter (time,gFx,gFy,gFz[,TgF])"
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
        One of :data:`FORMATS`: ``"phyphox"``, ``"plain"`` (``time,ax,ay,az``),
        ``"physics toolbox"`` (``time,gFx,gFy,gFz``),
        ``"vertical"`` (``time,acc`` or ``time,az``) or ``"labelled"`` (the time and
        the axes named with their units: :func:`read_accelerometer`).
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


def _delimiter(path, first_line: str) -> str:
    """The header's delimiter (tab, semicolon or comma), or a :class:`RecordError` naming what was found.

    phyphox exports with commas, semicolons and tabs.
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


def _labelled(names: list):
    """``([time, x, y, z columns], units, seconds per time unit)`` of a header that names one time column in s or
    ms (``time``, ``t``, ``elapsed``; or ``seconds_elapsed``) and one x, y and z acceleration column each with one
    acceleration unit (``X (m/s^2)``, ``Accel_X (m/s^2)``, ``x-axis (g)``, ``ACCELEROMETER X (m/s²)``), other
    columns left alone; None otherwise. An axis without its unit is not taken for an acceleration (a gyroscope's or
    a position's would read as well)."""
    times, axes, units = [], {}, set()
    for name in names:
        base, unit = split_name(name)  # lower case, "_-./:" read as spaces
        if base in _LABELLED_TIME and unit in _TIME_UNITS:
            times.append((name, _TIME_UNITS[unit]))
        elif base in _SECONDS_NAMES and not unit:
            times.append((name, 1.0))
        axis = _LABELLED_AXIS.match(base)
        if axis is not None and unit in ACCELERATION_UNITS:
            axes.setdefault(axis.group(1), []).append(name)
            units.add(ACCELERATION_UNITS[unit])
    if len(times) != 1 or sorted(axes) != ["x", "y", "z"] or any(len(v) != 1 for v in axes.values()) \
            or len(units) != 1:
        return None
    return [times[0][0], *(axes[axis][0] for axis in "xyz")], units.pop(), times[0][1]


def _layout(path, header: list) -> tuple:
    """``(format, [time column, acceleration columns...], units the header names or None, seconds per time
    unit)`` from the header's names."""
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
        return "phyphox", [names[position[name.lower()]] for name in columns], "m/s^2", 1.0
    time = [name for name in _TIME_NAMES if name in position]
    rest = set(lower) - set(time)
    if len(time) == 1:
        if set(_G_FORCE_AXES) <= rest:
            return "physics toolbox", [names[position[name]] for name in (time[0], *_G_FORCE_AXES)], "g", 1.0
        if rest in ({"ax", "ay", "az"}, {"ax", "ay", "az", "at"}):  # "at": Physics Toolbox's total, not read
            return "plain", [names[position[name]] for name in (time[0], "ax", "ay", "az")], None, 1.0
        if rest in ({"acc"}, {"az"}):
            return "vertical", [names[position[name]] for name in (time[0], *rest)], None, 1.0
    labelled = _labelled(names)
    if labelled is not None:
        return ("labelled", *labelled)
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


def _units(path, units: str, level: float, named, acc: np.ndarray) -> str:
    """The units of the file: those its header ``named``, else from the option and the data's gravity level (in
    the file's units)."""
    if named is not None:
        if units not in ("auto", named):
            raise OptionError(f"{path}: units={units!r}, but the header says {named}; use units='auto' or {named!r}")
        return named
    if units != "auto":
        return units
    if abs(level - 1.0) <= GRAVITY_TOLERANCE:
        return "g"
    if abs(level / G - 1.0) <= GRAVITY_TOLERANCE:
        return "m/s^2"
    for unit in (1.0, G):
        _refuse_turning(path, acc, level, unit)
    if level < LINEAR_ACCELERATION_LIMIT:
        return "m/s^2"  # no gravity in either unit: the check in read_accelerometer says so
    raise RecordError(
        f"{path}: cannot tell the units: the mean acceleration has magnitude {level:.4g}, neither about 1 (g) "
        f"nor about {G:.2f} (m/s^2); give units='g' or units='m/s^2'"
    )


def _check_rows(path, header: list, body: list, delimiter: str) -> None:
    """Refuse a file without data rows, a row with more or fewer fields than the header, or fewer than 3 rows."""
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


def _read_columns(source: str, header: list, body: list, delimiter: str, columns: list) -> tuple:
    """``(time, acc)`` from the ``columns`` of the data rows, as finite floats, or a :class:`RecordError`.

    With a semicolon or tab delimiter, decimal commas in any of these columns are
    read as points (and a message about a bad cell says so).
    """
    cells = np.array(body, dtype=object)
    names = [name.strip() for name in header]
    texts = [np.char.strip(cells[:, names.index(name)].astype(str)) for name in columns]  # 2 or 4 columns
    decimal_comma = delimiter != "," and any((np.char.find(text, ",") >= 0).any() for text in texts)
    numbers = []
    if texts[0].size and _CLOCK.match(str(texts[0][0])):  # a time written as a clock (Physics Toolbox)
        numbers.append(_clock_seconds(texts[0], columns[0], source))
    for name, column in zip(columns[len(numbers):], texts[len(numbers):]):
        if decimal_comma:
            column = np.char.replace(column, ",", ".")
        try:
            numbers.append(numeric_column(column.astype(object), name, source))
        except RecordError as exc:
            raise RecordError(f"{exc} (decimal commas read as points)" if decimal_comma else str(exc)) from None
    return numbers[0], np.column_stack(numbers[1:])


def _clock_seconds(cells: np.ndarray, column: str, source: str) -> np.ndarray:
    """A time column written as a clock (``MM:SS.fff``, ``HH:MM:SS.fff``, ``HH:MM:SS:fff``) in seconds; a one-line
    :class:`RecordError` naming the first cell that is no clock."""
    parts = np.char.partition(np.char.replace(cells.astype(str), ",", "."), " ")[:, 0]  # no date or zone after it
    fields = [_CLOCK.match(cell) for cell in parts.tolist()]
    bad = [row for row, match in enumerate(fields) if match is None]
    if bad:
        raise RecordError(f"{source}: column {column!r} row {bad[0] + 1} holds {str(cells[bad[0]])!r}; its first "
                          "row is a clock time (MM:SS.fff or HH:MM:SS.fff), so every row must be one")
    hours, minutes, secs, millis = (np.array([float(group or 0) for group in groups]) for groups in
                                    zip(*(match.groups() for match in fields)))
    return 3600.0 * hours + 60.0 * minutes + secs + millis / 1000.0


def _refuse_turning(path, acc: np.ndarray, level: float, unit: float) -> None:
    """Refuse a record whose axes' mean is off 1 g while each sample reads about 1 g (in ``unit``): the phone turned.

    A phone fixed to the body keeps its orientation: the mean of its axes is gravity. In a bag or a hand it
    turns, the mean shrinks (0.63 g for a slow tumble of 80 degrees sd about each axis, 0.46 g for 180) while every
    sample's magnitude still reads gravity plus the movement."""
    sample = float(np.median(np.linalg.norm(acc, axis=1))) / unit
    if abs(level / unit - 1.0) > GRAVITY_TOLERANCE and abs(sample - 1.0) <= GRAVITY_TOLERANCE:
        raise RecordError(
            f"{path}: the axes' mean reads {level / unit:.2f} g while each sample reads {sample:.2f} g: the phone "
            "turned over the record (loose in a bag or a hand); fix it to the body at the waist and record again"
        )


def _check_gravity(path, acc: np.ndarray, units_read: str, fmt: str) -> None:
    """Refuse a record (``acc`` in m/s^2) whose gravity level says it is in g, never saw gravity, is off 1 g, or
    whose orientation was not fixed."""
    _refuse_turning(path, acc, _gravity_level(acc), G)
    level = _gravity_level(acc) / G
    if fmt not in ("phyphox", "labelled") and units_read == "m/s^2" and abs(level * G - 1.0) <= GRAVITY_TOLERANCE:
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


def read_accelerometer(path, units: str = "auto") -> AccelerometerRecord:
    """Read a phone's accelerometer record (CSV) and check that it includes gravity.

    The format is recognised from the header (names in any case and order,
    surrounding quotes and spaces ignored):

    ``"Time (s)","Acceleration x (m/s^2)","Acceleration y (m/s^2)","Acceleration z (m/s^2)"``
        **phyphox**, experiment "Acceleration with g", as exported by the app
        (quoted names, numbers like ``9.806650000E0``), optionally with a fifth
        column ``"Absolute acceleration (m/s^2)"``, which is not read (it is
        ``|a|``, derivable, and phyphox pads it with ``NaN``). Always m/s^2.
    ``time,ax,ay,az`` (or ``t,ax,ay,az``; a fourth ``aT``, their magnitude, not read)
        **plain**: the phone's three axes in m/s^2 or g. (Physics Toolbox's linear accelerometer writes
        ``time;ax;ay;az;aT`` without gravity: it is read, and refused as a linear-acceleration export.)
    ``time,acc`` or ``time,az``
        **vertical**: one channel along a vertical axis (up or down), with gravity,
        in m/s^2 or g.
    ``"Time (s)","X (m/s^2)","Y (m/s^2)","Z (m/s^2)"``, ``elapsed (s),x-axis (g),y-axis (g),z-axis (g)``, ...
        **labelled**: one time column in s or ms (``time``, ``t`` or ``elapsed``)
        and one x, y and z acceleration column each, named with their unit
        (``m/s^2`` or ``g``; ``X``, ``Accel_X``, ``Acceleration x``, ``x-axis``),
        as phyphox exports a sensor's data, MetaWear sensors export theirs and the
        Sensor Logger app does (``seconds_elapsed``, ``ACCELEROMETER X (m/s²)``);
        other columns (an epoch, a date) are not read. The units are the header's.
        SensorLog's (iOS) ``accelerometerTimestamp_sinceReboot(s)`` and ``accelerometerAccelerationX(G)``, ... are
        read so (its ``motionUserAcceleration`` columns, without gravity, are not).
    ``time,gFx,gFy,gFz[,TgF]``
        **physics toolbox**: Physics Toolbox Sensor Suite's g-force meter, the specific force in g (other columns of
        its multi-record export left alone); the time in s, or as a clock (``00:01.234``, ``12:00:01.234``,
        ``12:00:01:234``), read as seconds.

    Columns may be separated by commas, semicolons or tabs (the delimiter is
    taken from the header). With semicolons or tabs a decimal comma
    (``9,81``, phyphox's "decimal comma" exports) is read as a decimal point; with
    commas it cannot be told from a delimiter.

    Parameters
    ----------
    path : str or path-like
        The CSV file.
    units : {"auto", "m/s^2", "g"}, default "auto"
        Units of the acceleration columns. ``"auto"`` reads phyphox and labelled files
        in the units their header names and decides for the others from the record's
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
        ``units`` is not one of :data:`UNITS`, or differs from the units a header names.

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
    fmt, columns, named, seconds = _layout(path, header)
    _check_rows(path, header, body, delimiter)
    time, acc = _read_columns(source, header, body, delimiter, columns)
    time = time * seconds
    units_read = _units(path, units, _gravity_level(acc), named, acc)
    if units_read == "g":
        acc = acc * G
    _check_gravity(path, acc, units_read, fmt)
    return AccelerometerRecord(time=time, acc=acc, source=source, units_read=units_read, format=fmt)
