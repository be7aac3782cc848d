"""The benchmarks' resumable result CSVs: one row per record, each appended in one write, resumed after a kill.

``lab_records.py`` and ``phone_phenomena.py`` keep their rows this way: a killed run loses at most the records in
flight, and ``--resume`` fits only the rows missing (or failed) from the CSV.
"""

from __future__ import annotations

import csv
import io
import os
from pathlib import Path

import pandas as pd


def line(values: dict, columns) -> bytes:
    """One CSV line of ``values`` in the order of ``columns``."""
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerow([values[c] for c in columns])
    return buffer.getvalue().encode("utf-8")


def append_row(path: Path, values: dict, columns):
    """Append one row in a single ``write`` (O_APPEND), then fsync."""
    fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    try:
        os.write(fd, line(values, columns))
        os.fsync(fd)
    finally:
        os.close(fd)


def open_csv(path: Path, resume: bool, columns, keys) -> set:
    """Make the CSV ready (its header written when new); the rows already fitted without error (``resume``).

    ``keys``: ``(column, type)`` pairs; each fitted row is returned as the tuple of its keys' values, so converted.
    A row whose ``error`` is set is tried again (its new row is the one read). A last line cut by a kill is dropped;
    a CSV with other columns, or an existing one without ``resume``, stops the run with one line.
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.exists() and path.stat().st_size > 0:
        if not resume:
            raise SystemExit(f"{path} exists: give --resume to go on with it, or another --csv")
        data = path.read_bytes()
        if not data.endswith(b"\n"):  # a line cut by a kill: drop it
            with open(path, "r+b") as handle:
                handle.truncate(data.rfind(b"\n") + 1)
        if tuple(data.split(b"\n", 1)[0].decode("utf-8").split(",")) != tuple(columns):
            raise SystemExit(f"{path}: its columns are not this script's; give another --csv")
        names = [name for name, _ in keys]
        done = pd.read_csv(path, usecols=names + ["error"],
                           dtype={"error": str, **{n: str for n, kind in keys if kind is str}})
        done = done[done["error"].isna()]
        return {tuple(kind(v) for (_, kind), v in zip(keys, row)) for row in done[names].itertuples(index=False)}
    path.write_bytes(line({c: c for c in columns}, columns))
    return set()
