"""Identify many records in one run that loses nothing: a folder, a glob or a manifest, resumable.

A lab identifies hundreds of records overnight (the article: 173 records,
6800 cycles). :func:`run_batch` identifies them one record at a time and
writes each finished record to ``OUT/parts/`` at once, atomically (a
temporary file renamed into place, so a kill leaves either the whole part or
none of it). ``resume=True`` continues a killed run: records whose part
exists are not identified again, and the final ``OUT/results.csv`` is the
parts joined in the run's record order, identical to an uninterrupted run.

Nothing is lost to one bad record: a record that cannot be read or
segmented, or whose identification fails numerically, gets one row with
``status`` "failed" and the reason, and the batch goes on
(:class:`BatchSummary` counts them). Cycles whose estimates cannot be true
keep ``status`` "ok" but are flagged ``implausible`` with the reason (see
:mod:`smd_statespace.identify.plausibility`); the summary counts them too.

By default (``estimator="record"``, as for one record) every record gives one
row, the person from the whole record
(:func:`~smd_statespace.person.identify_person`; deterministic), with the
flags ``implausible`` and ``model_adequate`` that ``stats`` reads. A
per-cycle estimator (``"ekf"``, ``"pf"``, ...) gives the article's table
instead, one row per cycle.

Reproducible: every cycle's random stream is derived from the seed, the
record's name (:func:`record_key`) and the cycle's index, never from the
order in which records or cycles happen to run, so the results do not depend
on ``jobs`` or on where a run was interrupted.

Layout of ``OUT``::

    run.json          version, options, seed and the records (a resumed run must match it)
    parts/NAME.csv    one finished record each (its person, or all its cycles; a ``record`` column first)
    results.csv       every record's rows, in the run's record order (written at the end)
    pooled.csv        a per-cycle estimator's: each record's cycles pooled into one person's row
                      (:func:`~smd_statespace.identify.pooled.pooled_people`; ``stats`` reads it as people)
"""

from __future__ import annotations

import glob
import hashlib
import json
import os
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd

from .. import __version__
from ..errors import OptionError, RecordError, SMDInputError
from ..io import check_mass
from ..progress import tqdm
from .plausibility import implausible_ok

RECORD_ESTIMATOR = "record"
"""The estimator name of the record-level model (:func:`~smd_statespace.person.identify_person`):
one row per record (the person) instead of one per cycle."""

__all__ = ["BatchRecord", "BatchSummary", "collect_records", "read_manifest", "record_key", "run_batch",
           "atomic_write_csv"]

RECORD_SUFFIXES = (".csv", ".tsv", ".txt", ".c3d", ".mot", ".sto")
"""The files of a folder taken as its records: this library's CSV and a plate's exports
(:func:`~smd_statespace.io.read_record`: Qualisys' ``.tsv``, BioWare's and AMTI's ``.txt``, C3D, OpenSim's)."""

MANIFEST_COLUMNS = ("file", "mass")
"""Columns of a manifest: the record's CSV (relative to the manifest's folder, or absolute) and its body mass (kg)."""


@dataclass(frozen=True)
class BatchRecord:
    """One record of a batch: its file, body mass (kg), name in the results and seed key.

    ``sensor`` is ``"plate"`` (a force record, :func:`~smd_statespace.io.read_record`) or
    ``"accelerometer"`` (a phone's record, :func:`~smd_statespace.accelerometer.accelerometer_record`,
    read in ``units``); an accelerometer's ``mass`` may be None (then K_h, C_h are not given). ``fs`` and
    ``force_columns`` say how to read a plate's export (:func:`~smd_statespace.io.read_record`).
    """

    path: Path
    mass: float | None
    name: str
    sensor: str = "plate"
    units: str = "auto"
    fs: float | None = None
    force_columns: tuple | None = None

    def read(self):
        """The record as the person model reads it (:class:`~smd_statespace.io.Record`)."""
        if self.sensor == "accelerometer":
            from ..accelerometer import accelerometer_record

            return accelerometer_record(self.path, self.mass, units=self.units)
        from ..io import read_record

        return read_record(self.path, self.mass, fs=self.fs, force_columns=self.force_columns)

    @property
    def key(self) -> int:
        """Seed key of the record, see :func:`record_key`."""
        return record_key(self.name)

    @property
    def part(self) -> str:
        """File name of the record's part: its name made safe, plus the key so that names cannot collide."""
        safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in self.name.removesuffix(".csv"))
        return f"{safe}-{self.key:08x}.csv"


@dataclass
class BatchSummary:
    """What a batch run did: records identified now, taken from an earlier run, failed; cycles by status.

    ``failures`` maps each record that could not be identified at all to the reason; ``table`` is
    what ``results`` holds (every record's cycles, in the run's record order); ``implausible``
    counts the ``ok`` cycles flagged implausible, ``implausible_reasons`` how often each reason
    was given; ``pooled``: a per-cycle estimator's ``pooled.csv``, each record's cycles pooled into
    one row in the person's columns (:func:`~smd_statespace.identify.pooled.pooled_people`).
    """

    records: int
    identified: int
    resumed: int
    failures: dict = field(default_factory=dict)
    cycles: dict = field(default_factory=dict)
    results: Path | None = None
    table: pd.DataFrame | None = None
    implausible: int = 0
    implausible_reasons: dict = field(default_factory=dict)
    pooled: Path | None = None

    @property
    def failed_records(self) -> list:
        """Names of the records that could not be identified at all, sorted."""
        return sorted(self.failures)

    def line(self) -> str:
        """One line for the terminal."""
        counts = ", ".join(f"{n} {status}" + (f" ({self.implausible} of them implausible)"
                                               if status == "ok" and self.implausible else "")
                           for status, n in sorted(self.cycles.items()))
        unit = "cycles" if self.table is None or "cycle" in self.table else (
            "rows (one person per bout)" if "bout" in self.table else "rows (one person per record)")
        return (f"{self.records} records: {self.identified} identified now, {self.resumed} taken from the earlier "
                f"run, {len(self.failed_records)} failed; {unit}: {counts or 'none'}")


def record_key(name: str) -> int:
    """A stable 32-bit key of a record's name (SHA-256), part of every cycle's seed.

    It depends on the name alone, so a record gets the same random numbers
    whatever else is in the batch, its position, or the number of jobs.
    """
    return int.from_bytes(hashlib.sha256(name.encode("utf-8")).digest()[:4], "big")


def read_manifest(path) -> list[BatchRecord]:
    """Records and body masses from a manifest CSV with columns ``file,mass``.

    ``file`` is relative to the manifest's folder (or absolute). Errors name
    the manifest, the row and what is valid.
    """
    path = Path(path)
    if not path.is_file():
        raise RecordError(f"--manifest {path}: no such file")
    try:
        table = pd.read_csv(path, dtype=str, keep_default_na=False)
    except (pd.errors.EmptyDataError, pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise RecordError(
            f"--manifest {path}: not a readable CSV with columns file,mass ({type(exc).__name__})") from None
    table.columns = [str(c).strip() for c in table.columns]
    missing = [c for c in MANIFEST_COLUMNS if c not in table.columns]
    if missing:
        raise RecordError(f"--manifest {path}: missing column {missing[0]!r}; the header is "
                          f"{','.join(table.columns)!r}, expected file,mass")
    if table.empty:
        raise RecordError(f"--manifest {path}: no records listed under the header file,mass")
    records, seen = [], set()
    for row, (name, mass) in enumerate(zip(table["file"], table["mass"]), start=2):
        name = name.strip()
        if not name:
            raise RecordError(f"--manifest {path}: row {row} has an empty file name")
        if name in seen:
            raise RecordError(f"--manifest {path}: row {row} lists {name!r} a second time")
        seen.add(name)
        try:
            value = float(mass)
        except ValueError:
            raise RecordError(
                f"--manifest {path}: row {row} ({name}) has mass {mass!r}; expected a number of kg") from None
        records.append(BatchRecord(path.parent / name, check_mass(value, f"--manifest {path} row {row} ({name})"),
                                   name))
    return records


def collect_records(source, mass=None, manifest=None, accelerometer=False, units="auto",
                    reading=None) -> list[BatchRecord]:
    """The records of a batch, in a fixed order.

    Parameters
    ----------
    source : str or path, optional
        A folder (every file of :data:`RECORD_SUFFIXES` in it, sorted by name,
        except the manifest), a glob pattern (``"data/*/rec*.csv"``) or one file. May be
        None with a manifest, which then lists the records.
    mass : float, optional
        Body mass (kg) of every record; needed unless a manifest gives them.
    manifest : path, optional
        CSV ``file,mass``: per-record masses (and, without ``source``, the records).
    accelerometer : bool, optional
        The records are phones' (:mod:`smd_statespace.accelerometer`): the mass
        may be left out, and ``units`` (``"auto"``, ``"g"``, ``"m/s^2"``) says
        how to read them.
    reading : dict, optional
        ``fs`` and ``force_columns`` of every plate's export
        (:func:`~smd_statespace.io.read_record`).

    Returns
    -------
    list of BatchRecord
    """
    records = _collect(source, mass, manifest, accelerometer)
    if accelerometer:
        records = [replace(r, sensor="accelerometer", units=units) for r in records]
    reading = {key: value for key, value in (reading or {}).items() if value is not None}
    if "force_columns" in reading:
        reading["force_columns"] = tuple(reading["force_columns"])
    return [replace(r, **reading) for r in records]


def _collect(source, mass, manifest, accelerometer) -> list[BatchRecord]:
    listed = read_manifest(manifest) if manifest is not None else None
    if source is None:
        if listed is None:
            raise OptionError("give records (a file, folder or glob) or --manifest FILE with columns file,mass")
        return listed
    text = str(source)
    if Path(text).is_dir():
        paths = sorted(p for p in Path(text).iterdir() if p.is_file() and p.suffix.lower() in RECORD_SUFFIXES
                       and (manifest is None or p.resolve() != Path(manifest).resolve()))
        base = Path(text)
        where = f"folder {text}"
    else:
        paths = sorted(Path(p) for p in glob.glob(text))
        base = None
        where = f"pattern {text!r}" if glob.has_magic(text) else text
    if not paths:
        raise RecordError(f"{where}: no record files ({', '.join('*' + x for x in RECORD_SUFFIXES)}) found")
    names = [str(p.relative_to(base)) if base is not None else str(p) for p in paths]
    if listed is None:
        value = None if mass is None else check_mass(mass)  # None: each plate's record weighs its person
        return [BatchRecord(p, value, n) for p, n in zip(paths, names)]
    by_file = {r.path.resolve(): r for r in listed}
    records = []
    for p, n in zip(paths, names):
        entry = by_file.get(p.resolve())
        if entry is None:
            if mass is None and not accelerometer:
                raise RecordError(f"--manifest {manifest}: no mass for {n}; add a row '{n},KG' or give --mass")
            records.append(BatchRecord(p, None if mass is None else check_mass(mass), n))
        else:
            records.append(BatchRecord(p, entry.mass, n))
    return records


def atomic_write_csv(table: pd.DataFrame, path) -> None:
    """Write ``table`` to ``path`` through a temporary file and a rename: all of it or nothing."""
    path = Path(path)
    temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    table.to_csv(temporary, index=False)
    with open(temporary, "rb+") as handle:
        os.fsync(handle.fileno())
    os.replace(temporary, path)


def identify_record(record: BatchRecord, model, estimator, runner_options: dict, check=True) -> pd.DataFrame:
    """Identify every cycle of one record; a record that fails gives one "failed" row with the reason.

    With ``estimator="record"`` the record gives one row: the person
    (:meth:`~smd_statespace.person.results.PersonResult.table_row`). With
    ``check`` a record that is not bouncing
    (:func:`~smd_statespace.applicability.check_bouncing`) fails with the reason.
    """
    from ..applicability import check_bouncing
    from ..signals import RECORD_RATE
    from ..signals.weighing import weigh_record
    from .runner import CycleRunner

    mass = record.mass
    try:
        measured = weigh_record(record.read())  # no mass given: the plate weighs the person
        mass = measured.mass if record.sensor != "accelerometer" else mass
        if estimator == RECORD_ESTIMATOR:  # the person from the whole record: one row (a row per bout: "each")
            from ..person import identify_bouts, identify_person
            from ..person.noise_floor import NOISE_FLOOR

            options = dict(n_harmonics=model.n_harmonics, check=check, rate=runner_options.get("rate", RECORD_RATE),
                           effects=model.effects, measured_floor=runner_options.get("measured_floor", True),
                           noise_floor=runner_options.get("noise_floor", NOISE_FLOOR),
                           fade=runner_options.get("fade", "auto"))
            if runner_options.get("span") == "each":
                table = pd.DataFrame([a.row() for a in identify_bouts(measured, **options)])
                table["label"] = record.name + ": " + table["label"]
            else:
                person = identify_person(measured, **options)
                table = pd.DataFrame([{"status": "ok", "reason": "", **person.table_row()}])
        else:
            runner = CycleRunner(model, estimator=estimator, progress=False, **runner_options)
            check_bouncing(measured).raise_if_refused(override=not check)
            table = runner.run(measured, record_key=record.key)  # decimated to runner_options["rate"], preprocessed
    except SMDInputError as exc:
        table = pd.DataFrame([{"status": "failed", "reason": " ".join(str(exc).split())}])
    except (ArithmeticError, np.linalg.LinAlgError) as exc:  # numerical failure outside a filter: contained
        table = pd.DataFrame([{"status": "failed", "reason": f"{type(exc).__name__}: {exc}"}])
    table.insert(0, "record", record.name)
    table.insert(1, "mass", mass)
    return table


def _settings(records, model, estimator, runner_options) -> dict:
    return {"version": __version__, "command": "identify", "model": repr(model), "estimator": str(estimator),
            "options": {k: v for k, v in sorted(runner_options.items())},
            "records": [{"name": r.name, "mass": r.mass, **({"sensor": r.sensor, "units": r.units}
                                                             if r.sensor != "plate" else {}),
                         **({"fs": r.fs} if r.fs is not None else {}),
                         **({"force_columns": list(r.force_columns)} if r.force_columns is not None else {})}
                        for r in records]}


def _check_settings(sidecar: Path, settings: dict, resume: bool, parts: Path):
    earlier = json.loads(sidecar.read_text(encoding="utf-8")) if sidecar.exists() else None
    if not resume:
        if any(parts.glob("*.csv")):
            raise OptionError(f"--out {sidecar.parent}: holds a previous batch run; add --resume to continue it "
                              "or choose another --out")
        return
    if earlier is None:
        raise OptionError(f"--resume: {sidecar} not found; there is no run in {sidecar.parent} to continue")
    for key in ("model", "estimator", "options", "records"):
        if earlier.get(key) != settings.get(key):
            raise OptionError(f"--resume: the {key} differ from the run in {sidecar.parent} "
                              f"({sidecar.name}); resume with the same records and options, or choose another --out")


def _run_on(executor, pending, model, estimator, runner_options, check, parts: Path, bar) -> None:
    """Identify the ``pending`` records on ``executor``, writing each record's part as soon as it is done."""
    futures = {executor.submit(identify_record, r, model, estimator, runner_options, check): r for r in pending}
    for future in as_completed(futures):
        atomic_write_csv(future.result(), parts / futures[future].part)
        bar.update()


def _prepare_folder(out: Path, settings: dict, resume: bool) -> Path:
    """The run's ``parts`` folder in ``out``, made ready for the records' parts.

    The settings are checked against ``run.json`` (``resume``) or written to it, and
    any part left half-written by a killed run is removed.
    """
    parts = out / "parts"
    parts.mkdir(parents=True, exist_ok=True)
    sidecar = out / "run.json"
    settings = json.loads(json.dumps(settings))  # as stored
    _check_settings(sidecar, settings, resume, parts)
    if not resume:
        temporary = sidecar.with_name(".run.json.tmp")
        temporary.write_text(json.dumps(settings, indent=2), encoding="utf-8")
        os.replace(temporary, sidecar)
    for stale in parts.glob(".*.tmp"):  # a part being written when the run was killed
        stale.unlink()
    return parts


def _one_search_thread():
    """A batch's worker process runs one record's searches in one thread: the processes keep the cores busy
    (:mod:`~smd_statespace.person.threads`)."""
    from ..person.threads import THREADS_VARIABLE

    os.environ[THREADS_VARIABLE] = "1"


def run_batch(records, out, model=None, estimator=RECORD_ESTIMATOR, runner_options=None, jobs: int = 1,
              resume: bool = False, progress: bool = True, check: bool = True, executor=None) -> BatchSummary:
    """Identify every record, writing each finished one at once; see the module docstring.

    Parameters
    ----------
    records : list of BatchRecord
        From :func:`collect_records`.
    out : path
        Output folder (created).
    model : SMDModel, optional
        Default ``SMDModel()``.
    estimator : str
        ``"record"`` (default: the person from each whole record, one row each, as ``identify`` gives for one
        record) or a per-cycle estimator (``"ekf"``, ``"pf"``, ...: the article's method, one row per cycle).
    runner_options : dict, optional
        A per-cycle estimator's :class:`~smd_statespace.identify.runner.CycleRunner` options (``max_passes``,
        ``seed``, ``rate``, ``n_particles``, ...); with ``estimator="record"`` only ``rate`` (default
        :data:`~smd_statespace.signals.RECORD_RATE`), ``measured_floor`` (default True), ``noise_floor``
        (default :data:`~smd_statespace.person.noise_floor.NOISE_FLOOR`) and ``fade`` (default "auto") are used (see
        :func:`~smd_statespace.person.fit.identify_person`).
    jobs : int
        Records identified in parallel processes (results do not depend on it); ignored with ``executor``.
    resume : bool
        Continue the run in ``out``: keep its finished records.
    progress : bool
        Show a progress bar over records.
    check : bool
        Refuse records that are not bouncing (each fails with its reason; the others go on).
    executor : concurrent.futures.Executor, optional
        Identifies the records, one task per record, instead of ``jobs`` local processes: any
        executor (processes, threads, or a Dask cluster's ``client.get_executor()``), for either
        estimator (``"record"`` too). Each part is written by this process as its record
        finishes, so a killed run resumes as usual, and the results do not depend on the
        number of workers. The executor is not shut down here.

    Returns
    -------
    BatchSummary
    """
    from ..model import SMDModel

    model = SMDModel() if model is None else model
    runner_options = dict(runner_options or {})
    out = Path(out)
    parts = _prepare_folder(out, _settings(records, model, estimator, runner_options), resume)
    pending = [r for r in records if not (parts / r.part).exists()]
    bar = tqdm(total=len(records), initial=len(records) - len(pending), desc=f"identify ({estimator})",
               unit="record", disable=not progress)
    try:
        if executor is not None and pending:
            _run_on(executor, pending, model, estimator, runner_options, check, parts, bar)
        elif jobs > 1 and len(pending) > 1:
            with ProcessPoolExecutor(max_workers=jobs, initializer=_one_search_thread) as pool:
                _run_on(pool, pending, model, estimator, runner_options, check, parts, bar)
        else:
            for record in pending:
                atomic_write_csv(identify_record(record, model, estimator, runner_options, check),
                                 parts / record.part)
                bar.update()
    finally:
        bar.close()
    table = pd.concat([pd.read_csv(parts / r.part, keep_default_na=False, na_values=[""]) for r in records],
                      ignore_index=True)
    results = out / "results.csv"
    atomic_write_csv(table, results)
    pooled = None
    if estimator != RECORD_ESTIMATOR:  # the per-cycle method's person of each record, in the person's columns
        from .pooled import pooled_people

        pooled = out / "pooled.csv"
        atomic_write_csv(pooled_people(table), pooled)
    part = next((table[c] for c in ("cycle", "bout") if c in table), pd.Series(np.nan, index=table.index))
    failed = table[(table["status"] == "failed") & part.isna()]  # a record's one row: it was not identified
    _, bad, reasons = implausible_ok(table)
    return BatchSummary(records=len(records), identified=len(pending), resumed=len(records) - len(pending),
                        failures=dict(zip(failed["record"], failed["reason"])),
                        cycles=table["status"].value_counts().to_dict(), results=results, table=table,
                        implausible=int(bad.sum()), implausible_reasons=reasons, pooled=pooled)
