"""Reading, checking and writing GRF records.

A record is a CSV file with a header row and the columns

========== ======= ==================================================
column     unit    meaning
========== ======= ==================================================
time       s       sample times, increasing and uniformly spaced
force      N       vertical ground reaction force (GRF) of one person
floor_acc  m/s^2   optional: vertical floor acceleration under the person
========== ======= ==================================================

A force plate's export as lab software writes it is read too (:mod:`smd_statespace.plate_exports`):
a block of settings above the header, a row of units under it, commas, semicolons or tabs, decimal
commas, a time column in s or ms or the rows counted at the rate the block names (Vicon Nexus,
Qualisys), each plate's vertical force (``Fz``, ``FZ1``, ``FORCE_Z``, OpenSim's
``ground_force1_vy``, ...) summed into ``force``, turned to point up where it is negative under
the load; and a C3D file's force platforms, with the ezc3d package. The reading is said in
``record.extra["reading"]``.

The body mass is not in the file; it is given separately (``--mass KG`` on
the command line). :func:`read_record` and :func:`make_record` check
everything a later stage relies on and raise a :class:`~smd_statespace.errors.RecordError`
or :class:`~smd_statespace.errors.MassError` with a one-line message otherwise.
"""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .errors import MassError, RecordError
from .plate_exports import c3d_force, check_file, decode_rows, find_layout

if TYPE_CHECKING:  # pandas is imported where it is used: `import smd_statespace` needs numpy only
    import pandas as pd

G = 9.80665
"""Standard gravity (m/s^2)."""

CONTACT_FRACTION = 0.05
"""Force below this fraction of body weight means no contact (the plate's noise is about 1 %): the reader's unit
check, :mod:`smd_statespace.applicability` and the record front end read it."""

MASS_RANGE = (20.0, 250.0)
"""Plausible body masses (kg) accepted by :func:`check_mass`."""

SAMPLING_TOLERANCE = 0.01
"""Largest relative deviation of a time step from the median step."""

MIN_SAMPLING_RATE = 10.0
"""Lowest sampling rate (Hz) a record may have: below it even the slowest bouncing the model takes (1.2 Hz) has its
four harmonics folded onto each other. A time column in milliseconds reads as a rate 1000 times too low."""

REQUIRED_COLUMNS = ("time", "force")
OPTIONAL_COLUMNS = ("floor_acc",)

@dataclass(frozen=True)
class Record:
    """One person's GRF record, checked.

    Attributes
    ----------
    time : ndarray, shape (T,)
        Sample times (s), uniformly spaced.
    force : ndarray, shape (T,)
        Vertical ground reaction force (N).
    mass : float
        Body mass ``M_h`` (kg).
    floor_acc : ndarray or None, shape (T,)
        Measured floor acceleration under the person (m/s^2), if recorded.
    source : str
        Where the record came from (file name), used in error messages.
    """

    time: np.ndarray
    force: np.ndarray
    mass: float
    floor_acc: np.ndarray | None = None
    source: str = "<arrays>"
    extra: dict = field(default_factory=dict)

    @property
    def fs(self) -> float:
        """Sampling frequency (Hz)."""
        return 1.0 / float(np.median(np.diff(self.time)))

    @property
    def dt(self) -> float:
        """Sampling interval (s)."""
        return 1.0 / self.fs

    @property
    def duration(self) -> float:
        """Record length (s)."""
        return float(self.time[-1] - self.time[0])

    def to_frame(self) -> pd.DataFrame:
        """The record as a DataFrame with the CSV column names."""
        import pandas as pd  # here, not at the top: `import smd_statespace` needs numpy only (0.3 s less)

        data = {"time": self.time, "force": self.force}
        if self.floor_acc is not None:
            data["floor_acc"] = self.floor_acc
        return pd.DataFrame(data)


def check_mass(mass, source: str = "--mass") -> float:
    """Return ``mass`` as a float (kg), or raise :class:`MassError`.

    Accepts finite masses in :data:`MASS_RANGE`.
    """
    try:
        value = float(mass)
    except (TypeError, ValueError):
        raise MassError(f"{source}: body mass {mass!r} is not a number; give it in kg, e.g. 70") from None
    if not np.isfinite(value) or value <= 0:
        raise MassError(f"{source}: body mass must be a positive number of kg, got {mass!r}")
    lo, hi = MASS_RANGE
    if not lo <= value <= hi:
        raise MassError(
            f"{source}: body mass {value:g} kg is implausible; expected {lo:g}-{hi:g} kg (is it in kg?)"
        )
    return value


def numeric_column(values: np.ndarray, column: str, source: str, first_line=None) -> np.ndarray:
    """Convert one column of a file to float64, naming the first bad row (1-based data row).

    Parameters
    ----------
    values : ndarray
        The column as read (strings or numbers).
    column, source : str
        Its name and the file's, for the error message.
    first_line : int or sequence of int, optional
        The file's line number (1-based) of the first value, or of every value (a file with blank lines between
        its rows), when known: the message then names the bad value's line too, as an editor shows it.

    Raises
    ------
    RecordError
        When a value is not a finite number.
    """
    import pandas as pd  # here, not at the top: `import smd_statespace` needs numpy only

    numeric = pd.to_numeric(pd.Series(values), errors="coerce").to_numpy(dtype=float)
    bad = ~np.isfinite(numeric)
    if bad.any():
        row = int(np.argmax(bad))
        line = _line_text(first_line, row)
        raise RecordError(
            f"{source}: column '{column}' row {row + 1}{line} holds {values[row]!r}; "
            "every value must be a finite number"
        )
    return numeric


def _line_text(lines, row: int) -> str:
    """``" (line 12)"``: the file line of data row ``row`` (0-based), from the first line's number or every row's;
    "" when not known."""
    if lines is None:
        return ""
    return f" (line {lines + row if np.isscalar(lines) else lines[row]})"


def make_record(time, force, mass, floor_acc=None, source: str = "<arrays>", lines=None) -> Record:
    """Check arrays and return a :class:`Record`.

    Parameters
    ----------
    time : array_like, shape (T,)
        Sample times (s), strictly increasing and uniformly spaced
        (within :data:`SAMPLING_TOLERANCE`), at :data:`MIN_SAMPLING_RATE` or faster.
    force : array_like, shape (T,)
        GRF (N). Its mean must be near ``mass * g``: a record in body weights
        or kilonewtons is rejected.
    mass : float
        Body mass (kg).
    floor_acc : array_like, optional
        Floor acceleration (m/s^2).
    source : str
        Name used in error messages.
    lines : int or sequence of int, optional
        The file line (1-based) of the first sample, or of every sample, when read from a file: the messages
        name a bad sample's line beside its data row, as an editor shows it.
    """
    mass = check_mass(mass)
    time = numeric_column(np.asarray(time).ravel(), "time", source, lines)
    force = numeric_column(np.asarray(force).ravel(), "force", source, lines)
    if floor_acc is not None:
        floor_acc = numeric_column(np.asarray(floor_acc).ravel(), "floor_acc", source, lines)
        if floor_acc.size != time.size:
            raise RecordError(f"{source}: column 'floor_acc' has {floor_acc.size} rows, 'time' has {time.size}")
    if force.size != time.size:
        raise RecordError(f"{source}: column 'force' has {force.size} rows, 'time' has {time.size}")
    if time.size < 3:
        raise RecordError(f"{source}: only {time.size} data rows; a record needs at least one bouncing cycle")
    steps = np.diff(time)
    if (steps <= 0).any():
        row = int(np.argmax(steps <= 0)) + 2
        what = "repeats" if steps[row - 2] == 0 else "decreases"
        raise RecordError(f"{source}: column 'time' {what} at row {row}{_line_text(lines, row - 1)}; time must "
                          "strictly increase")
    median = float(np.median(steps))
    deviation = np.abs(steps / median - 1.0)
    if deviation.max() > SAMPLING_TOLERANCE:
        row = int(np.argmax(deviation)) + 2
        raise RecordError(
            f"{source}: non-uniform sampling at row {row}{_line_text(lines, row - 1)} (step {steps[row - 2]:.6g} s, "
            f"median {median:.6g} s); "
            f"resample to a uniform rate (tolerance {SAMPLING_TOLERANCE:.0%})"
        )
    rate = 1.0 / median
    if rate < MIN_SAMPLING_RATE:
        hint = ("; is 'time' in milliseconds? divide it by 1000 to get s" if rate * 1000.0 >= MIN_SAMPLING_RATE
                else "")
        raise RecordError(f"{source}: column 'time' has samples {median:.6g} s apart ({rate:.3g} Hz); a record "
                          f"needs at least {MIN_SAMPLING_RATE:g} Hz (time in s){hint}")
    weight = mass * G
    # the whole record's mean is M g for any movement that ends as it starts (jumping included); a lab's export
    # that reads 0 before stepping on and after stepping off has that mean while someone is on the plate (the
    # samples above the no-contact fraction of the record's largest value, in its own units)
    mean = float(np.mean(force))
    loaded = force > CONTACT_FRACTION * float(np.max(force))
    means = (mean, float(np.mean(force[loaded])) if loaded.any() else mean)
    if not any(0.7 <= value / weight <= 1.3 for value in means):
        if any(abs(value - 1.0) < 0.3 for value in means):
            hint = "it looks like body weights; multiply by mass*g to get N"
        elif any(abs(value * 1000.0 / weight - 1.0) < 0.3 for value in means):
            hint = "it looks like kN; multiply by 1000 to get N"
        elif 0.7 <= -mean / weight <= 1.3:  # a plate whose vertical axis points down (Fz negative under a load)
            hint = "it looks like the plate's vertical axis points down; multiply by -1 to get the upward force"
        elif abs(mean) < 0.1 * weight and np.std(force) > 0.05 * weight:  # a plate zeroed with the person on it
            hint = (f"it looks like the body weight was subtracted (the plate zeroed with the person on it); add "
                    f"mass*g = {weight:.1f} N to get the force")
        else:
            hint = "check the units (N) and the --mass value"
        raise RecordError(
            f"{source}: mean of column 'force' is {mean:.4g}, expected about mass*g = {weight:.1f} N; {hint}"
        )
    return Record(time=time, force=force, mass=mass, floor_acc=floor_acc, source=source)


def csv_rows(path: Path, expected: str, delimiter_of) -> tuple:
    """``(rows, delimiter)`` of a CSV file, or a one-line :class:`RecordError`.

    Missing, a directory, empty, not UTF-8 text or unreadable: said so, with ``expected`` (what the
    header should be) for an empty file. ``delimiter_of(path, first_line)`` returns the delimiter or
    raises :class:`RecordError` naming the one found.
    """
    check_file(path)
    try:
        with open(path, newline="", encoding="utf-8-sig") as handle:
            first_line = handle.readline()
            if not first_line.strip():
                raise RecordError(f"{path}: file is empty; expected {expected} and data rows")
            delimiter = delimiter_of(path, first_line)
            handle.seek(0)
            rows = list(csv.reader(handle, delimiter=delimiter))
    except UnicodeDecodeError:
        raise RecordError(f"{path}: not a text CSV file (could not decode as UTF-8)") from None
    except OSError as exc:
        raise RecordError(f"{path}: cannot read ({exc.strerror or exc})") from None
    return rows, delimiter


def read_record(path, mass=None, *, fs=None, force_columns=None) -> Record:
    """Read a CSV record and check it (see the module docstring for the format).

    Parameters
    ----------
    path : str or path-like
        CSV file with header ``time,force[,floor_acc]``, or a force plate's export
        (:mod:`smd_statespace.plate_exports`: a block of settings above the header, a row
        of units, each plate's vertical force, commas, semicolons or tabs, decimal commas,
        OpenSim's ground-reaction files; a ``.c3d`` file with the ezc3d package).
    mass : float, optional
        Body mass (kg). None: the plate weighs the person; the record then carries a provisional mass (its
        loaded force's median over ``g``) and ``extra["weigh"]``, and
        :func:`~smd_statespace.signals.weighing.weigh_record` (which ``identify_person`` and the front end call)
        takes the mass from its standing parts or its whole bouncing cycles.
    fs : float, optional
        An export's sampling rate (Hz), for one without a time column or a rate above its
        header: the time is then its rows counted at ``fs``.
    force_columns : sequence of str or int, optional
        An export's vertical force columns, by name or number (1: the first), summed; for a
        table without a header, or whose columns are named otherwise.

    Returns
    -------
    Record
        An export's reading is said in words in ``record.extra["reading"]``.

    Raises
    ------
    RecordError
        The file is missing, unreadable, empty, lacks a column or holds bad values.
    MassError
        The mass is not plausible.
    """
    path, source = Path(path), os.fspath(path)
    if mass is not None:
        check_mass(mass)
    floor_acc = None
    if path.suffix.lower() == ".c3d":
        time, force, notes = c3d_force(path)
    else:
        rows, delimiter = decode_rows(path)
        header = [name.strip().lower() for name in rows[0]] if rows else []
        if delimiter == "," and "time" in header and "force" in header and fs is None and force_columns is None:
            return _read_plain(path, rows, header, mass)  # this library's own format, read strictly
        time, force, notes, floor_acc = _read_export(rows, delimiter, source, fs, force_columns)
    loaded = np.abs(force) > CONTACT_FRACTION * float(np.max(np.abs(force)))
    if loaded.any() and float(np.mean(force[loaded])) < 0.0:
        force = -force
        notes.append("the vertical force is negative under the load (the force on the plate with z up, as Vicon "
                     "Nexus gives it, or a plate whose z axis points down): read with its sign turned")
    given = mass is not None
    mass = mass if given else provisional_mass(force, source)
    return replace(make_record(time, force, mass, floor_acc=floor_acc, source=source),
                   extra={"reading": notes, "weigh": not given})


def provisional_mass(force, source: str) -> float:
    """The mass (kg) a record read without one carries until the plate weighs the person
    (:func:`~smd_statespace.signals.weighing.weigh_record`): the median of its loaded force (above
    :data:`CONTACT_FRACTION` of its largest) over ``g``; a :class:`MassError` naming the reading when that is no
    person's weight."""
    force = np.asarray(force, dtype=float)
    finite = force[np.isfinite(force)]
    loaded = finite[np.abs(finite) > CONTACT_FRACTION * float(np.max(np.abs(finite)))] if finite.size else finite
    level = float(np.median(loaded)) if loaded.size else float("nan")
    lo, hi = MASS_RANGE
    if not (np.isfinite(level) and lo <= level / G <= hi):
        swing = float(np.std(finite)) if finite.size else 0.0
        zeroed = swing > 0.0 and abs(float(np.mean(finite))) < swing  # it swings about 0, not about a weight
        hint = (f"it swings about 0 (sd {swing:.4g} N): the body weight looks subtracted (the plate zeroed with the "
                "person on it), so the plate cannot weigh the person; add the weight back, or " if zeroed else "")
        raise MassError(f"{source}: no body mass given, and the plate's force (median {level:.4g} N = "
                        f"{level / G:.4g} kg at g) is no person's weight ({lo:g}-{hi:g} kg); {hint}give it with "
                        "--mass KG (mass=KG), and check the force's units (N)")
    return level / G


def _read_export(rows: list, delimiter, source: str, fs, force_columns) -> tuple:
    """``(time, force, notes, floor_acc)`` of a text export's ``rows``
    (:func:`~smd_statespace.plate_exports.find_layout`; ``floor_acc`` a column of that name, or None)."""
    layout = find_layout(rows, delimiter, source, fs=fs, force_columns=force_columns)

    def column(index):
        cells = np.array([row[index].strip() if index < len(row) else "" for row in layout.body], dtype=object)
        return numeric_column(cells, layout.header[index], source, layout.body_line)

    force = layout.force_scale * sum(column(index) for index in layout.forces)
    time = (layout.time_scale * column(layout.time) if layout.time is not None
            else np.arange(len(layout.body)) / layout.rate)
    named = [name.strip().lower() for name in layout.header]
    floor_acc = column(named.index("floor_acc")) if "floor_acc" in named else None
    return time, force, list(layout.notes), floor_acc


def _read_plain(path: Path, rows: list, header: list, mass) -> Record:
    """A record in this library's own format (``time,force[,floor_acc]``, commas), every row checked; ``mass``
    None: a provisional one, to be weighed (:func:`read_record`)."""
    # rows[i] is the file's line i + 1 (csv_rows reads from the first line, the header)
    lines = [i + 1 for i, row in enumerate(rows) if i > 0 and any(cell.strip() for cell in row)]
    body = [rows[line - 1] for line in lines]
    if not body:
        raise RecordError(f"{path}: header only, no data rows")
    for number, (line, row) in enumerate(zip(lines, body), start=1):
        if len(row) != len(header):
            raise RecordError(f"{path}: data row {number} (line {line}) has {len(row)} fields, the header has "
                              f"{len(header)}")
    columns = {name: np.array([row[i].strip() for row in body], dtype=object) for i, name in enumerate(header)}
    source = os.fspath(path)
    given = (mass if mass is not None
             else provisional_mass(numeric_column(columns["force"], "force", source, lines), source))
    record = make_record(columns["time"], columns["force"], given, floor_acc=columns.get("floor_acc"), source=source,
                         lines=lines)
    return record if mass is not None else replace(record, extra={"weigh": True})


def write_record(path, record: Record) -> None:
    """Write ``record`` as CSV (columns ``time, force[, floor_acc]``)."""
    record.to_frame().to_csv(path, index=False, float_format="%.6f")


def truth_values(truth) -> dict:
    """The reported quantities of a truth (``SyntheticRecord.truth`` or a truth file): flat keys.

    ``f_h``, ``xi_h`` as given, ``blf`` (a list) as ``blf_1, blf_2, ...``,
    ``K_h``, ``C_h`` as ``k_h``, ``c_h``; keys already flat (``blf_1``) are kept; a
    simulation's effects' parameters by their estimated names (``beta_3``; a floor's
    ``frequency``, ``damping`` as ``f_f``, ``xi_f``).
    """
    if not truth:
        return {}
    values = {name: float(truth[name]) for name in ("f_h", "xi_h") if name in truth}
    for i, value in enumerate(truth.get("blf", []), start=1):
        values[f"blf_{i}"] = float(value)
    for source, name in (("K_h", "k_h"), ("C_h", "c_h")):
        if source in truth:
            values[name] = float(truth[source])
    for name, value in truth.items():  # numbers only: a lab record's truth has lists (blf_start, blf_end)
        if (name.startswith("blf_") or name in ("k_h", "c_h")) and isinstance(value, (int, float)):
            values.setdefault(name, float(value))
    for effect in dict(truth.get("effects") or {}).values():  # a simulation's effects: their parameters
        for name, value in dict(effect or {}).items():
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                values.setdefault(_EFFECT_TRUTH_NAMES.get(name, name), float(value))
    return values


_EFFECT_TRUTH_NAMES = {"frequency": "f_f", "damping": "xi_f"}
"""A simulated floor mode's truth keys and the names of the parameters it is estimated as."""
