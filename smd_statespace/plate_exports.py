"""A force plate's export as lab software writes it: its time and vertical force.

A C3D file (the motion-capture labs' binary format) is read with ezc3d, which computes each plate's
force from its analog channels and calibration (:func:`c3d_force`). In a text export, lab software
writes a plate's record with a block of settings above the table, a row of units under the header,
one group of columns per plate, and its own delimiter, decimal mark and sign.
:func:`find_layout` finds, in the rows of such a file,

- the table: the first three rows of numbers with as many cells as each other; its header is the
  row above them, or the row above that when the row between is a row of units (``N``, ``s``,
  ``mm``, ...). The table ends at the first empty row (a Vicon Nexus export's ``Trajectories``
  block follows its ``Devices`` block after one);
- the time: a column named ``time``, ``t`` or ``abs time`` in s or ms (``Time (s)``,
  ``TIME``, ``abs time (s)``, ``Time [ms]``), else the rows counted at the sampling rate the block
  above names (``FREQUENCY 1000`` as Qualisys writes it, ``Sampling rate: 1000``, or the rate under
  ``Devices`` in a Vicon Nexus export, whose rows are numbered by frame and sub-frame);
- the vertical force: every plate's vertical force column, summed (:data:`VERTICAL`: ``Fz``,
  ``Fz1``, ``FP1 Fz``, ``Force.Fz2``, ``FORCE_Z``, ``Fz (N)``, ``Vertical force``, ``vGRF``,
  OpenSim's ``ground_force1_vy``); a column named as a total (``Total Fz``, ``Combined Force``) is
  taken alone. A column whose unit is not a force's (``V``, a plate's raw channel) is not one.

The reading is said in words (:attr:`ExportLayout.notes`), and a file in which no table, time or
vertical force is found is refused in one line naming what was found. Numbers are not converted
here (:func:`smd_statespace.io.read_record` does it).
"""

from __future__ import annotations

import csv
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import RecordError

__all__ = ["ExportLayout", "check_file", "decode_rows", "find_layout", "split_name", "c3d_force", "VERTICAL",
           "FORCE_UNITS", "TIME_UNITS"]

VERTICAL = (
    re.compile(r"^(?:(?:fp|force ?plate|plate|platform|left|right|l|r|total|combined|net|force) ?\d* )*"
               r"(?:force )?f ?z ?\d*$"),
    re.compile(r"^(?:(?:fp|plate|left|right|total|combined|net) ?\d* )*(?:force|grf) ?z ?\d*$"),
    re.compile(r"^(?:(?:left|right|total|combined|net) )?(?:grf|force)(?: ?\d+)?$"),
    re.compile(r"^(?:[a-z]+ ?\d* )*(?:vertical (?:ground reaction )?force|fvert|f vert|fvertical|vgrf|vertical grf)"
               r"(?: ?\d+)?$"),  # a name that says vertical: any qualifier before it (dominant, paretic, ...)
    re.compile(r"^(?:\d+ )?ground force ?\d* vy$"),  # OpenSim's frame: y up
)
"""Names (lower case, without their unit, ``._-:/`` read as spaces) of a plate's vertical force column."""

SIDES = re.compile(r"^(?:left|right|combined|total|sum)(?: ?\d+)?$")
"""The columns of a jump plate that measures the vertical force alone, per side and in all (``Left (N)``,
``Right (N)``, ``Combined (N)``): vertical forces when they name a force's unit."""

TOTAL = re.compile(r"\b(?:total|combined|net|sum)\b")
"""A vertical force column named as the plates' total, taken alone when there is one."""

FORCE_UNITS = {"": 1.0, "n": 1.0, "newton": 1.0, "newtons": 1.0, "kn": 1000.0, "lbf": 4.4482216152605,
               "kgf": 9.80665}
"""Multipliers to N of the units a vertical force column may name (none: N)."""

ACCELERATION_UNITS = {"m/s^2": "m/s^2", "m/s²": "m/s^2", "m/s2": "m/s^2", "g": "g"}
"""Units of a column that holds an acceleration, as its header may write them, and their one spelling: what the
accelerometer reader reads, and what a plate's export read without force is told it holds (a phone's export)."""

TIME_UNITS = {"": 1.0, "s": 1.0, "sec": 1.0, "seconds": 1.0, "ms": 1e-3, "msec": 1e-3}
"""Multipliers to s of the units a time column may name (none: s)."""

TIME_NAMES = ("time", "t", "abs time", "elapsed time", "time s")
RATE_NAMES = ("frequency", "sampling rate", "sample rate", "sampling frequency", "rate", "analog rate",
              "analog frequency", "sample frequency", "samplerate", "sampling rate hz", "frequency hz", "rate hz",
              "capture rate", "acquisition rate")
UNIT_WORDS = {"n", "kn", "lbf", "kgf", "s", "ms", "mm", "m", "cm", "n.mm", "nmm", "n.m", "nm", "n*m", "n·m", "mm.n",
              "v", "mv", "deg", "rad", "hz", "%", "kg", "m/s", "m/s^2", "m/s2", "g", "sec", "frame", "frames"}
HEADER_SEARCH_ROWS = 200
"""Rows in which the table's first rows of numbers are looked for."""

_SPACES = re.compile(r"[\s._\-:/]+")
_UNIT = re.compile(r"^(.*?)\s*[(\[]\s*([^()\[\]]*?)\s*[)\]]\s*$")


@dataclass(frozen=True)
class ExportLayout:
    """Where a record is in an export's rows.

    Attributes
    ----------
    header : list of str
        The table's column names, as written.
    header_line : int
        The header's line number in the file (1-based).
    body : list of list of str
        The table's rows of numbers (decimal commas already read as points).
    time : int or None
        The time column's index; None when the time is the rows counted at ``rate``.
    time_scale : float
        Seconds per unit of the time column.
    rate : float or None
        The sampling rate (Hz) the block above the header names, used when there is no time column.
    forces : list of int
        The vertical force columns' indices, summed.
    force_scale : float
        Newtons per unit of the force columns.
    notes : list of str
        How the export was read, in words.
    body_line : int or None
        The first row of numbers' line number in the file (1-based).
    """

    header: list
    header_line: int
    body: list
    time: int | None
    time_scale: float
    rate: float | None
    forces: list
    force_scale: float
    notes: list = field(default_factory=list)
    body_line: int | None = None


def check_file(path: Path, expected: str = "a CSV file") -> None:
    """A one-line :class:`RecordError` when ``path`` does not exist or is a directory (``expected``: what it should
    be, for the message)."""
    if not path.exists():
        raise RecordError(f"{path}: no such file")
    if path.is_dir():
        raise RecordError(f"{path}: is a directory, expected {expected}")


def decode_rows(path: Path) -> tuple:
    """``(rows, delimiter)`` of a text export: UTF-8, UTF-16 (with its byte order mark) or Windows' code page 1252;
    comma-, semicolon-, tab- or space-separated (the delimiter of most of its first lines; a tab before a semicolon
    before a comma, which may be a decimal comma); ``delimiter`` None for spaces."""
    check_file(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise RecordError(f"{path}: cannot read ({exc.strerror or exc})") from None
    if data[:2] in (b"\xff\xfe", b"\xfe\xff"):
        text = data.decode("utf-16", errors="replace")
    elif b"\x00" in data[:4096]:
        raise RecordError(f"{path}: not a text CSV file (binary data); a C3D file's name ends in .c3d")
    else:
        try:
            text = data.decode("utf-8-sig")
        except UnicodeDecodeError:
            text = data.decode("cp1252", errors="replace")
    lines = text.splitlines()
    if not any(line.strip() for line in lines):
        raise RecordError(f"{path}: file is empty; expected a header (time,force[,floor_acc]) and data rows")
    sample = [line for line in lines[:HEADER_SEARCH_ROWS] if line.strip()]
    counts = {delimiter: sum(delimiter in line for line in sample) for delimiter in ("\t", ";", ",")}
    delimiter = max(counts, key=lambda d: (counts[d], -("\t", ";", ",").index(d)))
    if counts[delimiter] == 0:
        return [line.split() for line in lines], None
    return list(csv.reader(lines, delimiter=delimiter)), delimiter


def _number(cell: str, decimal_comma: bool) -> bool:
    """Whether ``cell`` reads as a number."""
    try:
        float(cell.replace(",", ".") if decimal_comma else cell)
    except ValueError:
        return False
    return True


def _numbers(row: list, decimal_comma: bool) -> int:
    """How many cells of ``row`` are numbers, or 0 when a non-empty cell is not one (or none is)."""
    cells = [cell.strip() for cell in row if cell.strip()]
    if not cells or not all(_number(cell, decimal_comma) for cell in cells):
        return 0
    return len(cells)


def _table_start(rows: list, decimal_comma: bool) -> int | None:
    """The index of the first of three rows of numbers with as many cells as each other.

    Rows of numbers just above those, as wide but with blank cells (a centre of pressure left blank while the
    plate is unloaded, a marker not yet seen), belong to the table too: a header is not a row of numbers. (The
    first data row of such an export was taken for the header, and the file refused as having no time column.)
    """
    counts = [_numbers(row, decimal_comma) for row in rows[:HEADER_SEARCH_ROWS + 3]]
    for index in range(len(counts) - 2):
        if counts[index] and counts[index] == counts[index + 1] == counts[index + 2]:
            while index > 0 and counts[index - 1] and len(rows[index - 1]) == len(rows[index]):
                index -= 1
            return index
    return None


def _is_units(row: list) -> bool:
    """A row of units under the header: every non-empty cell a unit (one of them a common one)."""
    cells = [cell.strip().strip("()[]").lower() for cell in row if cell.strip()]
    return bool(cells) and all(len(cell) <= 8 and not any(ch.isdigit() and ch != "2" for ch in cell)
                               for cell in cells) and any(cell in UNIT_WORDS for cell in cells)


def split_name(name: str, unit_below: str = "") -> tuple:
    """``(base, unit)`` of a column name: lower case, ``._-:/`` as spaces, the unit from ``(unit)`` or ``[unit]``
    after it, else from the row of units."""
    match = _UNIT.match(name.strip())
    base, unit = (match.group(1), match.group(2)) if match else (name, unit_below)
    return _SPACES.sub(" ", base.strip().lower()).strip(), unit.strip().lower()


def _rate(block: list) -> float | None:
    """The sampling rate (Hz) the rows above the header name: ``FREQUENCY 1000``, ``Sampling rate: 1000 Hz``,
    ``Rate (Hz),1000``, or a Vicon Nexus export's rate on the row under ``Devices``."""
    for index, row in enumerate(block):
        cells = [cell.strip() for cell in row if cell.strip()]
        if len(cells) == 1 and ":" in cells[0]:
            cells = [part.strip() for part in cells[0].split(":", 1)]
        if not cells:
            continue
        name, _ = split_name(cells[0].rstrip(":="))
        if name in ("devices", "analog") and index + 1 < len(block):
            values = [cell.strip() for cell in block[index + 1] if cell.strip()][:1]
        elif name in RATE_NAMES:
            values = cells[1:2]
        else:
            continue
        value = values[0].lower().removesuffix("hz").strip().replace(",", ".") if values else ""
        if _number(value, False) and float(value) > 0:
            return float(value)
    return None


def _vertical(base: str, unit: str) -> bool:
    """Whether a column of this name and unit is a plate's vertical force: a name :data:`VERTICAL` knows, or a
    vertical-only plate's ``Left``, ``Right``, ``Combined`` with a force's unit (``Left (N)``)."""
    return any(pattern.match(base) for pattern in VERTICAL) or (SIDES.match(base) is not None and unit != ""
                                                                  and unit in FORCE_UNITS)


def _software(block: list, header: list) -> str:
    """The software that wrote the export, where the rows say so ("" otherwise)."""
    first = [row[0].strip().lower() for row in block if row and row[0].strip()]
    names = [name.strip().lower() for name in header]
    if "devices" in first:
        return "Vicon Nexus"
    if "no_of_samples" in first or "force_x" in names:
        return "Qualisys"
    if "endheader" in first:
        return "OpenSim"
    if "abs time (s)" in names:
        return "Kistler BioWare"
    return ""


def find_layout(rows: list, delimiter: str | None, source: str, fs: float | None = None,
                force_columns=None) -> ExportLayout:
    """Find the table, its time and its vertical force columns in an export's ``rows`` (:func:`decode_rows`).

    Parameters
    ----------
    rows : list of list of str
        The file's rows, split at ``delimiter`` (None: spaces).
    source : str
        The file's name, for messages.
    fs : float, optional
        The sampling rate (Hz): the time is then the rows counted at it, whatever the file holds. Needed for a
        table without a time column and without a rate above its header.
    force_columns : sequence of str or int, optional
        The vertical force columns, by name (every column of that name, case aside, or of that name before its
        unit) or by number (1 for the first column); summed. Needed for a table without a header, or whose
        columns are not named as :data:`VERTICAL` knows.

    Raises
    ------
    RecordError
        No table of numbers, no header above it, no time column and no rate, or no vertical force column, or a
        force or time unit not understood; the message names the header and its line.
    """
    decimal_comma = delimiter in ("\t", ";") and any(
        "," in cell for row in rows[:HEADER_SEARCH_ROWS] for cell in row if _number(cell.strip(), True)
        and not _number(cell.strip(), False))
    start = _table_start(rows, decimal_comma)
    if start is None:
        raise RecordError(f"{source}: no table of numbers in its first {HEADER_SEARCH_ROWS} rows; expected a header "
                          "time,force[,floor_acc] and data rows, or a force plate's export")
    header_at, header, names = _header(rows, start, source, force_columns)
    where = f"the header is {(delimiter or ' ').join(header)!r} (line {header_at + 1})" if header_at >= 0 else \
        "the table has no header"
    end = next((i for i in range(start, len(rows)) if not any(cell.strip() for cell in rows[i])), len(rows))
    body = rows[start:end]
    if decimal_comma:
        body = [[cell.replace(",", ".") for cell in row] for row in body]
    block = rows[:max(header_at, 0)]
    times = [] if fs else [i for i, (base, unit) in enumerate(names) if base in TIME_NAMES and unit in TIME_UNITS]
    rate = fs or (None if times else _rate(block))
    if not times and rate is None:
        raise RecordError(f"{source}: missing column 'time' (in s or ms), and no sampling rate above the header; "
                          f"{where}; give the rate with --fs HZ (fs=HZ)")
    groups = _groups(rows, header_at, len(header), decimal_comma)
    forces = _force_columns(header, names, times, force_columns, source, where, groups)
    units = {names[i][1] for i in forces}
    if len(units) > 1 or not units <= set(FORCE_UNITS):
        raise RecordError(f"{source}: vertical force columns in {', '.join(sorted(repr(u) for u in units))}; "
                          f"expected N, kN, lbf or kgf ({where})")
    time_unit = names[times[0]][1] if times else "s"
    notes = _notes(_software(block, header), header, times, rate, forces, header_at, bool(fs), groups)
    return ExportLayout(header, header_at + 1, body, times[0] if times else None, TIME_UNITS[time_unit], rate,
                        forces, FORCE_UNITS[units.pop()], notes, start + 1)


def _header(rows: list, start: int, source: str, force_columns) -> tuple:
    """``(index, cells, [(base, unit), ...])`` of the header above the table that starts at ``start`` (index -1 and
    names ``column 1``, ... for a table without one, when the force columns are given by number)."""
    units_row = [""] * len(rows[start])
    header_at = start - 1
    if header_at >= 1 and _is_units(rows[header_at]):
        units_row, header_at = rows[header_at], header_at - 1
    if header_at >= 0 and not any(cell.strip() for cell in rows[header_at]):
        header_at = -1  # an empty line above the numbers (AMTI NetForce's text files)
    if header_at < 0:
        if force_columns is None or not all(_column_number(column) for column in force_columns):
            raise RecordError(f"{source}: no header row above the numbers (line 1 holds numbers); give the vertical "
                              "force's columns by number with --force-columns 3 (force_columns=[3]) and the rate "
                              "with --fs HZ")
        header = [f"column {i + 1}" for i in range(max(len(row) for row in rows[start:start + 3]))]
        return -1, header, [(name, "") for name in header]
    header = [cell.strip() for cell in rows[header_at]]
    return header_at, header, [split_name(name, units_row[i] if i < len(units_row) else "")
                               for i, name in enumerate(header)]


def _groups(rows: list, header_at: int, width: int, decimal_comma: bool) -> list:
    """Each column's group, from a row of group names right above the header (a Vicon Nexus export names its
    devices there, ``FP1 - Force``, ``Combined Force``, over each device's first column): the name last written at
    or left of the column; all "" when the row above is not such a row (its first cell written, or a
    number in it)."""
    above = rows[header_at - 1] if header_at >= 1 else []
    cells = [cell.strip() for cell in above]
    if not cells or cells[0] or not any(cells) or any(_number(cell, decimal_comma) for cell in cells if cell):
        return [""] * width
    groups, current = [], ""
    for i in range(width):
        current = cells[i] if i < len(cells) and cells[i] else current
        groups.append(current)
    return groups


def _column_number(column) -> int | None:
    """``column`` as a 1-based column number, or None when it is a name."""
    text = str(column).strip()
    return int(text) if text.isdigit() and int(text) >= 1 else None


def _force_columns(header: list, names: list, times: list, force_columns, source: str, where: str,
                   groups: list) -> list:
    """The indices of the vertical force columns: those given, else those :data:`VERTICAL` names (a total alone:
    named so, or under a group named so, ``groups``)."""
    if force_columns is not None:
        chosen = []
        for column in force_columns:
            number = _column_number(column)
            found = ([number - 1] if number and number <= len(header) else []) if number else [
                i for i, name in enumerate(header) if name.lower() == str(column).strip().lower()
                or names[i][0] == split_name(str(column))[0]]
            if not found:
                raise RecordError(f"{source}: --force-columns {column!r} is not a column; {where}")
            chosen += [i for i in found if i not in chosen]
        return chosen
    forces = [i for i, (base, unit) in enumerate(names) if _vertical(base, unit) and i not in times]
    forces = [i for i in forces if names[i][1] in FORCE_UNITS] or forces
    totals = [i for i in forces if TOTAL.search(names[i][0]) or TOTAL.search(groups[i].lower())]
    if len(totals) == 1:
        return totals
    if not forces:
        accelerations = [header[i] for i, (base, unit) in enumerate(names) if unit in ACCELERATION_UNITS
                         or base.startswith(("acc", "linear acc"))]
        hint = (f"; it holds accelerations ({', '.join(repr(a) for a in accelerations[:3])}): a phone's or "
                "accelerometer's record is read with --accelerometer") if accelerations else \
            "; name them with --force-columns NAME,NAME"
        raise RecordError(f"{source}: missing column 'force' (or each plate's vertical force: Fz, FZ1, FORCE_Z, "
                          f"'Fz (N)', ground_force1_vy, ...); {where}{hint}")
    return forces


def _notes(software: str, header: list, times: list, rate, forces: list, header_at: int, given: bool,
           groups: list) -> list:
    """The reading in words."""
    what = f"a {software} export" if software else "an export"
    what += f", header on line {header_at + 1}" if header_at >= 0 else ", without a header"
    time = f"time from '{header[times[0]]}'" if times else \
        f"time from the rows counted at {rate:g} Hz{' (as given)' if given else ''}"
    columns = ", ".join(f"column {i + 1}" if header_at < 0 else
                        f"'{header[i]}' (column {i + 1}{', ' + groups[i] if groups[i] else ''})" for i in forces)
    force = f"force the sum of {len(forces)} plates' vertical columns {columns}" if len(forces) > 1 else \
        f"force from {columns}"
    return [f"read as {what}: {time}, {force}"]


def c3d_force(path: Path) -> tuple:
    """``(time, force, notes)`` of a C3D file: the analog rate's clock (s) and the sum of its force platforms'
    vertical forces (N, in the lab's frame, as ezc3d computes them from each plate's channels, calibration and
    type), with the reading in words.

    Raises
    ------
    RecordError
        ezc3d is not installed, the file is not a C3D file, or it holds no force platform's data.
    """
    try:
        import ezc3d
    except ImportError:
        raise RecordError(f"{path}: a C3D file is read with the ezc3d package: pip install ezc3d (or "
                          "'smd_statespace[c3d]'), or export the plates' forces as text (CSV)") from None
    check_file(path, "a file")
    try:
        c3d = ezc3d.c3d(str(path), extract_forceplat_data=True)
    except Exception as exc:  # ezc3d raises plain RuntimeErrors and IndexErrors on files it cannot parse
        raise RecordError(f"{path}: not a C3D file ezc3d can read ({' '.join(str(exc).split()) or type(exc).__name__})"
                          ) from None
    plates = [plate for plate in c3d["data"]["platform"] if plate["force"].shape[1] > 0]
    rate = float(np.ravel(c3d["parameters"]["ANALOG"]["RATE"]["value"])[0]) if "ANALOG" in c3d["parameters"] else 0.0
    if not plates or rate <= 0.0:
        raise RecordError(f"{path}: the C3D file holds no force platform's data (analog rate {rate:g} Hz, "
                          f"{len(c3d['data']['platform'])} platforms described)")
    scale = {plate["unit_force"].strip().lower() for plate in plates}
    if len(scale) > 1 or not scale <= set(FORCE_UNITS):
        raise RecordError(f"{path}: force platforms in {', '.join(sorted(scale))}; expected N, kN, lbf or kgf")
    force = FORCE_UNITS[scale.pop()] * np.sum([plate["force"][2] for plate in plates], axis=0)
    notes = [f"read as a C3D file (ezc3d): time from the analog rate {rate:g} Hz, force the sum of "
             f"{len(plates)} force platforms' vertical forces" if len(plates) > 1 else
             f"read as a C3D file (ezc3d): time from the analog rate {rate:g} Hz, force from its force platform"]
    return np.arange(force.size) / rate, force, notes
