"""Files of a record-level identification: person.json, results.csv, run.json and figures.

``person.json`` is written last and atomically (a temporary file renamed), so a
killed or failed run never leaves a half-written answer.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from .. import __version__

__all__ = ["write_person", "atomic_write_text"]


def atomic_write_text(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file in the same folder."""
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, path)


def _plain(value):
    """JSON-able version of numpy scalars and containers."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (np.floating, float)):
        return float(value) if np.isfinite(value) else None
    return value


def write_person(directory, result, options: dict, truth=None) -> list:
    """Write a :class:`~smd_statespace.person.results.PersonResult`'s files into ``directory``.

    Returns
    -------
    list of pathlib.Path
        ``person.json``, ``results.csv`` (one row per force cycle),
        ``run.json``, ``person_fit.png``, ``person_diagnostics.png``,
        ``person_spectrum.png`` (innovations' spectrum), ``person_compare.png``
        (free-run simulation against the measurement, with the fit without the
        effects when there is one) and, with a ``floor_acc`` column,
        ``person_floor.png`` (innovations against the floor acceleration), and ``person_record.png``
        (the record as read: its parts, the fitted span, its spectrum with the mains hum).
    """
    directory = Path(directory)
    person = result.to_dict()
    if truth:
        shown = ("f_h", "xi_h", *(f"blf_{i}" for i in range(1, result.model.n_harmonics + 1)),
                 *result.model.effect_parameters)
        person["truth"] = {k: truth[k] for k in shown if k in truth}
    cycles = directory / "results.csv"
    table = result.cycles.copy()
    table.insert(0, "status", np.where(table["whole"], "ok", "partial"))
    table.to_csv(cycles, index=False)
    run = directory / "run.json"
    atomic_write_text(run, json.dumps({"version": __version__, "command": "identify", "estimator": "record",
                                       "record": str(result.record.source),
                                       "mass": result.record.mass if result.mass_known else None,
                                       "sensor": person["sensor"],
                                       "options": options}, indent=2))
    from ..plotting.person import plot_compare, plot_floor_correlation, plot_spectrum

    figures = [directory / f"person_{name}.png" for name in ("fit", "diagnostics", "spectrum", "compare")]
    result.plot_fit(figures[0], truth=person.get("truth"))
    result.plot_diagnostics(figures[1])
    plot_spectrum(result, figures[2])
    plot_compare(result, figures[3])
    if getattr(result.record, "floor_acc", None) is not None:
        figures.append(directory / "person_floor.png")
        plot_floor_correlation(result, figures[-1])
    if result.prepared is not None:
        from ..plotting.record import plot_record_parts

        figures.append(directory / "person_record.png")
        plot_record_parts(result.prepared, figures[-1])
    path = directory / "person.json"
    atomic_write_text(path, json.dumps(_plain(person), indent=2))
    return [path, cycles, run, *figures]
