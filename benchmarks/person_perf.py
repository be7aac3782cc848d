"""Speed of the recommended path: the record-level person (``identify REC --mass M``, issue 23).

Simulated people bounce for 30 s at 100 Hz (``simulate_bouncing``, people drawn as in
``benchmarks/person_accuracy.py``: ``f_b`` 1.5-3.5 Hz, ``f_h`` 1.8-4.2 Hz, ``xi_h`` 0.1-0.5,
mass 50-90 kg, one :class:`numpy.random.SeedSequence` child per person), each person with
every generator of ``--generators`` (default ``jumps`` and ``smooth``). One run measures:

* **the library**: :func:`smd_statespace.person.identify_person` (its defaults) per record,
  median, min and max, split into the likelihood searches (``fit.fit_model``), the
  re-placement of the cycle starts (``fit.corrected_timing``: statsmodels' smoother), the
  information matrix (``fit.information``), the rest of the result object
  (``fit.person_result`` without the information) and everything else (checks, cycle
  timing, model building, start values); with the number of likelihood evaluations
  (``RecordModel.loglike`` calls) and their mean cost. The split comes from timers wrapped
  around those functions for the run (a few microseconds per call); a function that no
  longer exists is reported as "n/a". Then what the command does after the fit, in the
  same process: ``result.summary()`` (statsmodels' smoother and the residual tests) and
  ``write_person`` (person.json, results.csv and the figures);
* **the command line**, in fresh processes: the import of ``smd_statespace``, of
  ``smd_statespace.cli`` and of everything ``identify`` loads (wall time, fastest of
  ``--import-repeats``, next to a bare ``python -c pass``), ``python -X importtime``
  summarised by package; ``identify REC.csv --mass M --out DIR`` (wall, and the fit's own
  seconds as the command prints them) on the first ``--cli-records`` records;
  ``diagnose REC.csv --mass M`` (every built-in candidate effect, its default) on the
  first ``--diagnose-records``;
* **statsmodels side by side** (first ``--statsmodels-records`` records): the model
  ``identify_person`` ended with (``result.model``) fitted again from one start (the best
  of ``fit.START_F_H`` x ``fit.START_XI_H``, as ``fit_model`` chooses it) by our
  ``fit.fit_model`` and by statsmodels' ``MLEModel.fit`` (L-BFGS-B within the same
  bounds) of the twin ``RecordStateSpace(model, delta)``, ``delta`` from
  ``model.filter(result.params)`` (its log-likelihood is the profile likelihood at that
  ``delta``); time ratio, likelihood evaluations, and the difference of the ``f_h`` and
  ``xi_h`` estimates in units of their sd (inverse observed information at our estimate);
* with ``--study N``: N records written to a temporary folder with a manifest and
  identified by ``identify FOLDER --manifest M --estimator record --jobs J`` (wall); with
  ``--dask`` also by :func:`~smd_statespace.identify.batch.run_batch` on a
  ``distributed.LocalCluster`` of J worker processes (``executor=client.get_executor()``).

Usage::

    OPENBLAS_NUM_THREADS=1 python benchmarks/person_perf.py --out /tmp/person_perf.md   # about 5 min
    python benchmarks/person_perf.py --people 1 --diagnose-records 0 --statsmodels-records 0   # library + CLI only
    python benchmarks/person_perf.py --study 8 --jobs 2 --dask                            # + a batch study

The load average (1, 5, 15 min) is printed before and after: the machine is shared, and
every number here is wall-clock time of one process (BLAS single-threaded). Before the
timed records, one likelihood of each variation model is evaluated (numba loads its
compiled passes from the disk cache, or compiles them); that warm-up is reported apart.
"""

from __future__ import annotations

import os

# timings are per core: BLAS single-threaded before numpy is imported (children inherit it)
for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")
os.environ.setdefault("MPLBACKEND", "Agg")

import argparse  # noqa: E402
import importlib  # noqa: E402
import platform  # noqa: E402
import re  # noqa: E402
import shlex  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

import smd_statespace  # noqa: E402
from smd_statespace.io import write_record  # noqa: E402
from smd_statespace.person import fit as person_fit  # noqa: E402
from smd_statespace.person import search as person_search  # noqa: E402
from smd_statespace.person import identify_person  # noqa: E402
from smd_statespace.person import score as person_score  # noqa: E402
from smd_statespace.person.model import RecordModel  # noqa: E402
from smd_statespace.simulation import DEFAULT_BLF, simulate_bouncing  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
PACKAGE_ROOT = Path(smd_statespace.__file__).resolve().parents[1]

RANGES = {"f_b": (1.5, 3.5), "f_h": (1.8, 4.2), "xi_h": (0.1, 0.5), "mass": (50.0, 90.0)}
"""Uniform ranges of the simulated people (Hz, Hz, -, kg), as ``benchmarks/person_accuracy.py``."""

BLF_FACTOR = (0.7, 1.3)
"""Each ``BLF_i`` is the simulator's default times an independent uniform factor in this range."""

DURATION, FS = 30.0, 100.0
"""Record length (s) and sampling rate (Hz)."""

TIMED = (("searches", "fit", "fit_model"), ("searches", "search", "fit_model"), ("timing", "search", "corrected_timing"),
         ("information", "answer", "information"), ("result", "fit", "person_result"))
"""``(key, module of smd_statespace.person, function)`` timed during ``identify_person`` (a function is timed in
each module that calls it: ``fit_model`` makes the first fits in ``fit``, the others in ``search``)."""

IDENTIFY_IMPORTS = ("smd_statespace.cli", "smd_statespace.person", "smd_statespace.person.statespace",
                    "smd_statespace.cli.person_output", "smd_statespace.plotting.person")
"""What ``identify REC --mass M`` imports before its first figure (the command, the fit, statsmodels' twin,
the files and the figures)."""

PACKAGES = {"numpy": ("numpy",), "pandas": ("pandas",), "scipy": ("scipy",), "matplotlib": ("matplotlib", "mpl_toolkits",
            "PIL", "kiwisolver", "pyparsing", "cycler", "fontTools", "contourpy"), "numba": ("numba", "llvmlite"),
            "statsmodels": ("statsmodels", "patsy"), "filterpy": ("filterpy",), "dask": ("dask", "distributed"),
            "smd_statespace": ("smd_statespace",)}
"""Packages (and the top-level modules counted with them) of the ``-X importtime`` summary."""

WRITE_STEPS = (("data", "smd_statespace.person.results", "PersonResult", "to_dict"),
               ("fit", "smd_statespace.person.results", "PersonResult", "plot_fit"),
               ("diagnostics", "smd_statespace.person.results", "PersonResult", "plot_diagnostics"),
               ("spectrum", "smd_statespace.plotting.person", None, "plot_spectrum"),
               ("compare", "smd_statespace.plotting.person", None, "plot_compare"))
"""``(key, module, class or None, function)`` timed inside ``write_person`` (``result.cycles``, a cached property
that ``write_person`` reads, is timed before it)."""


# ---------------------------------------------------------------------------
# Records
# ---------------------------------------------------------------------------


def draw_people(n: int, seed: int) -> list[dict]:
    """``n`` people and their simulator seeds from ``SeedSequence(seed)``, one child per person."""
    people = []
    for k, child in enumerate(np.random.SeedSequence(seed).spawn(n)):
        people_ss, sim_ss = child.spawn(2)
        rng = np.random.default_rng(people_ss)
        person = {"person": k, **{name: float(rng.uniform(lo, hi)) for name, (lo, hi) in RANGES.items()}}
        person["blf"] = [float(b * f) for b, f in zip(DEFAULT_BLF, rng.uniform(*BLF_FACTOR, size=len(DEFAULT_BLF)))]
        person["sim_seed"] = int(sim_ss.generate_state(1, np.uint32)[0])
        people.append(person)
    return people


def simulate(person: dict, generator: str):
    """The person's 30 s, 100 Hz record with force variation ``generator``."""
    return simulate_bouncing(mass=person["mass"], f_b=person["f_b"], f_h=person["f_h"], xi_h=person["xi_h"],
                             duration=DURATION, fs=FS, blf=person["blf"], seed=person["sim_seed"],
                             variation=generator).record


# ---------------------------------------------------------------------------
# Timers around the library's functions
# ---------------------------------------------------------------------------


class Timers:
    """Wrap functions (module attributes or methods) with accumulating timers for the duration of a ``with``."""

    def __init__(self):
        self.seconds, self.calls, self._undo, self.missing = {}, {}, [], []

    def wrap(self, owner, name, key):
        original = owner.__dict__.get(name) if isinstance(owner, type) else getattr(owner, name, None)
        if original is None:
            self.missing.append(key)
            return
        self.seconds[key], self.calls[key] = 0.0, 0

        def timed(*args, **kwargs):
            started = time.perf_counter()
            try:
                return original(*args, **kwargs)
            finally:
                self.seconds[key] += time.perf_counter() - started
                self.calls[key] += 1

        setattr(owner, name, timed)
        self._undo.append((owner, name, original))

    def reset(self):
        for key in self.seconds:
            self.seconds[key], self.calls[key] = 0.0, 0

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        for owner, name, original in reversed(self._undo):
            setattr(owner, name, original)
        self._undo.clear()


def write_timers() -> Timers:
    import importlib

    timers = Timers()
    for key, module, cls, name in WRITE_STEPS:
        owner = importlib.import_module(module)
        owner = getattr(owner, cls) if cls else owner
        member = owner.__dict__.get(name) if isinstance(owner, type) else None
        if isinstance(member, property) or type(member).__name__ == "cached_property":
            timers.missing.append(key)  # a property: not wrapped (cached_property keeps its value on the object)
            continue
        timers.wrap(owner, name, key)
    return timers


def library_timers() -> Timers:
    timers = Timers()
    for key, module, name in TIMED:
        timers.wrap(importlib.import_module(f"smd_statespace.person.{module}"), name, key)
    timers.wrap(RecordModel, "filter", "loglike")  # every Kalman pass: a likelihood alone or under a score
    timers.wrap(person_score, "score", "score")  # passes with derivatives (each also one pass above)
    return timers


def warm_up(record) -> float:
    """One likelihood of each variation model ``identify_person`` compares (numba's cache or compiler); seconds."""
    from smd_statespace.io import G
    from smd_statespace.person.timing import estimate_timing

    started = time.perf_counter()
    try:
        timing = estimate_timing(record.time, record.force)
        y = record.force / record.mass - G
        for variation in person_fit.AUTO_VARIATIONS:
            model = RecordModel(record.time, y, timing, variation=variation)
            model.loglike(model.start_params(2.5, 0.3))
    except Exception as exc:  # the warm-up is a courtesy: an API change must not stop the benchmark
        print(f"warm-up skipped ({type(exc).__name__}: {exc})")
    return time.perf_counter() - started


def time_library(records, progress=print) -> list[dict]:
    """``identify_person`` on every record with the timers; then ``summary()`` and ``write_person``."""
    from smd_statespace.cli.person_output import write_person

    rows = []
    with library_timers() as timers, tempfile.TemporaryDirectory() as scratch:
        for k, item in enumerate(records):
            timers.reset()
            started = time.perf_counter()
            result = identify_person(item["record"])
            total = time.perf_counter() - started
            parts = {key: timers.seconds.get(key, np.nan) for key in dict.fromkeys(key for key, *_ in TIMED)}
            parts["result"] = parts["result"] - parts["information"]  # person_result calls information
            row = {**{k_: item[k_] for k_ in ("person", "generator", "f_b", "f_h_true", "xi_h_true")},
                   "seconds": total, **parts,
                   "other": total - np.nansum([parts[key] for key in dict.fromkeys(key for key, *_ in TIMED)]),
                   "loglike_calls": timers.calls.get("loglike", 0), "loglike_seconds": timers.seconds.get("loglike", np.nan),
                   "score_calls": timers.calls.get("score", 0), "score_seconds": timers.seconds.get("score", np.nan),
                   "searches_calls": timers.calls.get("searches", 0), "variation": result.model.variation,
                   "f_h": result.f_h, "xi_h": result.xi_h, "n_evaluations": result.n_evaluations,
                   "fitted": result}
            started = time.perf_counter()
            result.summary()
            row["summary_seconds"] = time.perf_counter() - started
            started = time.perf_counter()
            _ = result.cycles  # cached on the result: write_person reads it
            row["cycles_seconds"] = time.perf_counter() - started
            folder = Path(scratch) / f"r{k}"
            folder.mkdir()
            with write_timers() as writing:
                started = time.perf_counter()
                write_person(folder, result, {"benchmark": True})
                row["write_seconds"] = time.perf_counter() - started
            row["write_parts"] = {key: writing.seconds.get(key, np.nan) for key, *_ in WRITE_STEPS}
            rows.append(row)
            progress(f"  {item['name']}: identify_person {total:.1f} s ({row['loglike_calls']} Kalman passes, {row['score_calls']} with derivatives), "
                     f"summary {row['summary_seconds']:.1f} s, files {row['write_seconds']:.1f} s")
        missing = list(timers.missing)
    for row in rows:
        row["missing"] = missing
    return rows


# ---------------------------------------------------------------------------
# Fresh processes
# ---------------------------------------------------------------------------


def child_env() -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(PACKAGE_ROOT)] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep)
                                                              if p])
    return env


def run_child(argv, check=True) -> tuple[float, str]:
    """Run ``python argv...``; ``(wall seconds, stdout)``."""
    started = time.perf_counter()
    done = subprocess.run([sys.executable, *argv], capture_output=True, text=True, env=child_env())
    wall = time.perf_counter() - started
    if check and done.returncode != 0:
        raise RuntimeError(f"{shlex.join(argv)} exited {done.returncode}:\n{done.stderr[-2000:]}")
    return wall, done.stdout


def import_times(repeats: int) -> list[dict]:
    """Wall time of fresh interpreters importing the package, the command line and what ``identify`` loads."""
    cases = [("`python -c pass` (the interpreter alone)", "pass"),
             ("`import smd_statespace`", "import smd_statespace"),
             ("`import smd_statespace.person`", "import smd_statespace.person"),
             ("`import smd_statespace.cli`", "import smd_statespace.cli"),
             ("what `identify` imports (" + ", ".join(m.removeprefix("smd_statespace.") for m in IDENTIFY_IMPORTS[1:])
              + " too)", "import " + ", ".join(IDENTIFY_IMPORTS))]
    rows = []
    for label, code in cases:
        walls = [run_child(["-c", code])[0] for _ in range(repeats)]
        rows.append({"what": label, "min": min(walls), "median": float(np.median(walls))})
    return rows


def importtime(code: str) -> dict:
    """``python -X importtime -c code``: the total and the modules' own (self) times summed by package (ms).

    Self times add up to the total, so each package's share is what importing its own modules cost
    (a package imported inside another one is counted as itself).
    """
    done = subprocess.run([sys.executable, "-X", "importtime", "-c", code], capture_output=True, text=True,
                          env=child_env())
    owner = {top: package for package, tops in PACKAGES.items() for top in tops}
    total, packages = 0.0, {}
    for line in done.stderr.splitlines():
        match = re.match(r"import time:\s+(\d+) \|\s+(\d+) \|( *)(\S+)", line)
        if not match:
            continue
        own, name = int(match[1]) / 1000.0, match[4]
        total += own
        package = owner.get(name.split(".")[0], "other (Python's own, small packages)")
        packages[package] = packages.get(package, 0.0) + own
    return {"total": total, "packages": packages}


def time_cli(item, folder: Path) -> dict:
    """``identify REC.csv --mass M --out DIR`` in a fresh process: wall, and the fit's seconds as printed."""
    path = folder / f"{item['name']}.csv"
    write_record(path, item["record"])
    wall, out = run_child(["-m", "smd_statespace", "identify", str(path), "--mass", f"{item['record'].mass:.6g}",
                           "--out", str(folder / f"{item['name']}_out"), "--quiet"])
    match = re.search(r"record-level model \(([\d.]+) s\)", out)
    return {"name": item["name"], "wall": wall, "fit": float(match[1]) if match else np.nan, "path": path}


def time_diagnose(item, folder: Path) -> dict:
    """``diagnose REC.csv --mass M`` (every built-in candidate) in a fresh process: wall, and the candidates tried."""
    path = folder / f"{item['name']}.csv"
    if not path.exists():
        write_record(path, item["record"])
    wall, out = run_child(["-m", "smd_statespace", "diagnose", str(path), "--mass", f"{item['record'].mass:.6g}",
                           "--out", str(folder / f"{item['name']}_diagnose"), "--quiet"])
    verdict = next((line for line in out.splitlines() if line.startswith("verdict:")), "")
    match = re.search(r"Bonferroni over (\d+)", verdict)
    candidates = int(match[1]) if match else None
    return {"name": item["name"], "wall": wall, "candidates": candidates, "verdict": verdict}


# ---------------------------------------------------------------------------
# statsmodels side by side
# ---------------------------------------------------------------------------


def coarse_start(model):
    """The start ``fit_model`` picks by itself: the best of ``START_F_H`` x ``START_XI_H``."""
    grid = [model.start_params(f, x) for f in person_search.START_F_H
            for x in person_search.START_XI_H]
    return max(grid, key=model.loglike)


def per_evaluation(function, params, repeats=5) -> float:
    function(params)
    started = time.perf_counter()
    for _ in range(repeats):
        function(params)
    return (time.perf_counter() - started) / repeats


def compare_statsmodels(row) -> dict:
    """Our ``fit_model`` and statsmodels' ``MLEModel.fit`` on the final model of one record, from one start."""
    from smd_statespace.person.statespace import RecordStateSpace

    result = row["fitted"]
    model, params = result.model, np.asarray(result.params, dtype=float)
    start = coarse_start(model)
    calls = [0]
    original = model.loglike

    def counted(p, *args, **kwargs):
        calls[0] += 1
        return original(p, *args, **kwargs)

    model.loglike = counted  # an instance attribute: this model only, removed below
    try:
        started = time.perf_counter()
        ours = person_search.fit_model(model, start)
        ours_seconds = time.perf_counter() - started
        ours_calls = max(calls[0], ours["n_evaluations"])  # scoring's passes carry derivatives (score), not loglike
    finally:
        del model.loglike
    ours_eval = per_evaluation(model.loglike, params)

    twin = RecordStateSpace(model, model.filter(params)["delta"])
    sm_eval = per_evaluation(twin.loglike, params, repeats=3)
    calls[0] = 0
    plain = twin.loglike

    def sm_counted(p, *args, **kwargs):
        calls[0] += 1
        return plain(p, *args, **kwargs)

    twin.loglike = sm_counted
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        started = time.perf_counter()
        fitted = twin.fit(start_params=start, method="lbfgs", maxiter=1000, disp=False, approx_complex_step=False,
                          bounds=[tuple(b) for b in model.bounds])
        sm_seconds = time.perf_counter() - started
    sm_params = np.asarray(fitted.params, dtype=float)
    try:
        cov, _ = person_search.information(model, params, "oim")
        sd = np.sqrt(np.diag(cov))[:2]
        sd_source = "inverse observed information"
    except Exception:  # noqa: BLE001 - the calibrated sds of the result, if the information changed its form
        sd = np.asarray(result.se, dtype=float)[:2]
        sd_source = "result.se"
    ours_params = np.asarray(ours["params"], dtype=float)
    return {"name": row["name"], "variation": model.variation, "k": len(params),
            "ours_seconds": ours_seconds, "ours_calls": ours_calls, "ours_eval": ours_eval,
            "ours_loglike": ours["loglike"], "ours_params": ours_params,
            "sm_seconds": sm_seconds, "sm_calls": calls[0], "sm_eval": sm_eval,
            "sm_converged": bool(fitted.mle_retvals.get("converged", False)),
            "sm_profile_loglike": float(model.loglike(sm_params)), "sm_params": sm_params, "sd": sd,
            "sd_source": sd_source}


# ---------------------------------------------------------------------------
# A batch study
# ---------------------------------------------------------------------------


def write_study(n: int, seed: int, generators, folder: Path) -> list:
    people = draw_people(n, seed + 1)
    lines = ["file,mass"]
    names = []
    for k, person in enumerate(people):
        generator = generators[k % len(generators)]
        name = f"p{k:03d}_{generator}.csv"
        record = simulate(person, generator)
        write_record(folder / name, record)
        lines.append(f"{name},{record.mass:.6g}")
        names.append(name)
    (folder / "manifest.csv").write_text("\n".join(lines) + "\n")
    return names


def time_study(n: int, jobs: int, seed: int, generators, dask: bool) -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch) / "records"
        folder.mkdir()
        started = time.perf_counter()
        write_study(n, seed, generators, folder)
        print(f"  {n} records written in {time.perf_counter() - started:.1f} s")
        argv = ["-m", "smd_statespace", "identify", str(folder), "--manifest", str(folder / "manifest.csv"),
                "--estimator", "record", "--jobs", str(jobs), "--out", str(Path(scratch) / "cli"), "--quiet"]
        wall, out = run_child(argv, check=False)
        line = next((x for x in out.splitlines() if " records: " in x), out.strip()[-200:])
        rows.append({"how": f"`identify FOLDER --manifest M --estimator record --jobs {jobs}`", "records": n,
                     "workers": jobs, "wall": wall, "line": line})
        print(f"  command line: {wall:.1f} s; {line}")
        if dask:
            try:
                import distributed
            except ImportError:
                print("  --dask: distributed is not installed; skipped")
                return rows
            from smd_statespace.identify.batch import collect_records, run_batch

            records = collect_records(folder, manifest=folder / "manifest.csv")
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                started = time.perf_counter()
                with distributed.LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True,
                                              host="127.0.0.1", dashboard_address=None) as cluster, \
                        distributed.Client(cluster) as client:
                    up = time.perf_counter() - started
                    summary = run_batch(records, Path(scratch) / "dask", estimator="record", progress=False,
                                        executor=client.get_executor())
                wall = time.perf_counter() - started
            rows.append({"how": f"`run_batch(..., executor=client.get_executor())`, LocalCluster of {jobs} "
                                f"processes (start-up {up:.1f} s included)", "records": n, "workers": jobs,
                         "wall": wall, "line": summary.line()})
            print(f"  dask: {wall:.1f} s; {summary.line()}")
    return rows


# ---------------------------------------------------------------------------
# Report
# ---------------------------------------------------------------------------


def spread(values) -> str:
    values = np.asarray([v for v in values if np.isfinite(v)], dtype=float)
    if values.size == 0:
        return "n/a"
    return f"{np.median(values):.2f} [{values.min():.2f}, {values.max():.2f}]"


def share(part, total) -> str:
    part, total = np.asarray(part, float), np.asarray(total, float)
    if not np.isfinite(part).any():
        return "n/a"
    return f"{np.nanmedian(part):.2f} ({100 * np.nansum(part) / np.nansum(total):.0f} %)"


def machine_line() -> str:
    import numba
    import scipy
    import statsmodels

    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True, text=True,
                              check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--", "smd_statespace"], cwd=REPO,
                               capture_output=True, text=True, check=True).stdout.strip()
        commit = f"commit {head}" + (" + uncommitted changes" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        commit = "commit unknown"
    return (f"Python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}, numba "
            f"{numba.__version__}, statsmodels {statsmodels.__version__}; smd_statespace {commit}; "
            f"{platform.machine()}, {os.cpu_count()} CPUs; OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}")


def library_section(rows, warm) -> list[str]:
    lines = ["## Library: `identify_person(record)` (one process, its defaults)", ""]
    missing = rows[0]["missing"] if rows else []
    if missing:
        lines += [f"Not found in the library, so not split out: {', '.join(missing)}.", ""]
    lines += ["Seconds per record, median [min, max]; each part: median seconds (share of all records' time).", "",
              "| records | identify_person (s) | likelihood searches (`fit_model`) | cycle-start re-placement "
              "(`corrected_timing`) | information matrix (`information`) | rest of the result (`person_result`) "
              "| other | Kalman passes per record | of them with derivatives (`score`) | ms per pass "
              "(`filter`) | ms per `score` (its pass included) |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    groups = [(g, [r for r in rows if r["generator"] == g]) for g in dict.fromkeys(r["generator"] for r in rows)]
    groups.append(("all", rows))
    for label, group in groups:
        if not group:
            continue
        total = [r["seconds"] for r in group]
        per = [1e3 * r["loglike_seconds"] / r["loglike_calls"] for r in group if r["loglike_calls"]]
        per_score = [1e3 * r["score_seconds"] / r["score_calls"] for r in group if r["score_calls"]]
        lines.append(f"| {label} ({len(group)}) | {spread(total)} | "
                     + " | ".join(share([r[key] for r in group], total) for key in
                                  ("searches", "timing", "information", "result", "other"))
                     + f" | {np.median([r['loglike_calls'] for r in group]):.0f} | "
                       f"{np.median([r['score_calls'] for r in group]):.0f} | "
                       f"{np.median(per) if per else float('nan'):.2f} | "
                       f"{np.median(per_score) if per_score else float('nan'):.1f} |")
    lines += ["", f"Warm-up before the timed records (numba's compiled passes loaded or compiled): {warm:.1f} s.", "",
              "| record | generator | f_b (Hz) | f_h true / est. (Hz) | xi_h true / est. | variation chosen | s | "
              "searches (`fit_model` calls) | Kalman passes | summary (s) | files and figures (s) |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['name']} | {r['generator']} | {r['f_b']:.2f} | {r['f_h_true']:.2f} / {r['f_h']:.2f} | "
                     f"{r['xi_h_true']:.2f} / {r['xi_h']:.2f} | {r['variation']} | {r['seconds']:.1f} | "
                     f"{r['searches']:.1f} ({r['searches_calls']}) | {r['loglike_calls']} | "
                     f"{r['summary_seconds']:.1f} | {r['write_seconds']:.1f} |")
    labels = {"data": "`to_dict` (person.json's numbers)", "fit": "`plot_fit`", "diagnostics": "`plot_diagnostics`",
              "spectrum": "`plot_spectrum`", "compare": "`plot_compare` (free-run simulation)"}
    lines += ["", "After the fit, in the same process (what the command does next), seconds per record, median "
              "[min, max]:", "", "| step | s |", "|---|---|",
              f"| `result.summary()` (statsmodels' smoother at the estimate, residual tests) | "
              f"{spread([r['summary_seconds'] for r in rows])} |",
              f"| `result.cycles` (per-cycle table from the smoother; cached) | "
              f"{spread([r['cycles_seconds'] for r in rows])} |",
              f"| `write_person` (person.json, results.csv, run.json, 4 figures) | "
              f"{spread([r['write_seconds'] for r in rows])} |"]
    for key, label in labels.items():
        lines.append(f"| - of which {label} | {spread([r['write_parts'].get(key, np.nan) for r in rows])} |")
    return lines + [""]


def cli_section(imports, profile, cli, diagnose) -> list[str]:
    lines = ["## Command line (fresh processes)", ""]
    if imports:
        lines += ["| import | wall s, fastest | median |", "|---|---|---|"]
        lines += [f"| {r['what']} | {r['min']:.2f} | {r['median']:.2f} |" for r in imports]
        lines.append("")
    if profile:
        names = [p for p in list(PACKAGES) + ["other (Python's own, small packages)"]
                 if any(p in prof["packages"] for prof in profile.values())]
        lines += ["`python -X importtime -c CODE`: ms of the modules' own import times, summed by package (they add "
                  "up to the total; `-X importtime` itself slows imports a little).", "",
                  "| CODE | total ms | " + " | ".join(names) + " |", "|---|---|" + "---|" * len(names)]
        for code, prof in profile.items():
            lines.append(f"| `{code}` | {prof['total']:.0f} | "
                         + " | ".join(f"{prof['packages'][n]:.0f}" if n in prof["packages"] else "-" for n in names)
                         + " |")
        lines.append("")
    if cli:
        lines += ["| command | record | wall s | fit s (as printed) | the rest: start, imports, reading, summary, "
                  "files, figures |", "|---|---|---|---|---|"]
        for r in cli:
            lines.append(f"| `identify REC.csv --mass M --out DIR` | {r['name']} | {r['wall']:.1f} | {r['fit']:.1f} | "
                         f"{r['wall'] - r['fit']:.1f} |")
        for r in diagnose:
            lines.append(f"| `diagnose REC.csv --mass M` ({r['candidates']} candidates) | {r['name']} | "
                         f"{r['wall']:.1f} | | |")
        lines.append("")
    elif diagnose:
        lines += ["| command | record | wall s |", "|---|---|---|"]
        lines += [f"| `diagnose REC.csv --mass M` ({r['candidates']} candidates) | {r['name']} | {r['wall']:.1f} |"
                  for r in diagnose]
        lines.append("")
    for r in diagnose:
        lines.append(f"- {r['name']}: {r['verdict']}")
    if diagnose:
        lines.append("")
    return lines


def statsmodels_section(rows) -> list[str]:
    lines = ["## statsmodels side by side", "",
             "The model `identify_person` ended with, fitted again from the start `fit_model` picks by itself, by "
             "our `fit_model` (compiled likelihood, Fisher scoring with the exact gradient) and by statsmodels' `MLEModel.fit` of the twin "
             "`RecordStateSpace(model, delta)` (`method='lbfgs'`, the same bounds, numerical gradients). "
             "Differences of the estimates in units of their sd "
             f"({rows[0]['sd_source'] if rows else ''}).", "",
             "| record | variation, parameters | ours: s (passes, most with derivatives; ms per likelihood) | statsmodels: s (likelihoods, ms each) "
             "| time ratio | per likelihood | f_h ours / sm (diff in sd) | xi_h ours / sm (diff in sd) | "
             "profile log-lik. ours - sm |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        diff = (r["ours_params"][:2] - r["sm_params"][:2]) / r["sd"]
        lines.append(
            f"| {r['name']} | {r['variation']}, {r['k']} | {r['ours_seconds']:.1f} ({r['ours_calls']}, "
            f"{1e3 * r['ours_eval']:.1f}) | {r['sm_seconds']:.1f} ({r['sm_calls']}, {1e3 * r['sm_eval']:.1f})"
            f"{'' if r['sm_converged'] else ', not converged'} | {r['sm_seconds'] / r['ours_seconds']:.1f}x | "
            f"{r['sm_eval'] / r['ours_eval']:.1f}x | {r['ours_params'][0]:.4f} / {r['sm_params'][0]:.4f} "
            f"({diff[0]:+.3f}) | {r['ours_params'][1]:.4f} / {r['sm_params'][1]:.4f} ({diff[1]:+.3f}) | "
            f"{r['ours_loglike'] - r['sm_profile_loglike']:+.4f} |")
    lines.append("")
    return lines


def study_section(rows) -> list[str]:
    lines = ["## A batch study", "", "| how | records | workers | wall s | s per record | summary line |",
             "|---|---|---|---|---|---|"]
    lines += [f"| {r['how']} | {r['records']} | {r['workers']} | {r['wall']:.1f} | {r['wall'] / r['records']:.1f} | "
              f"{r['line']} |" for r in rows]
    return lines + [""]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--people", type=int, default=2,
                        help="simulated people (default 2; 0 with --study times the batch alone)")
    parser.add_argument("--generators", default="jumps,smooth",
                        help="force-variation generators of simulate_bouncing, comma-separated (default jumps,smooth)")
    parser.add_argument("--seed", type=int, default=2023, help="SeedSequence seed of the people (default 2023)")
    parser.add_argument("--cli-records", type=int, default=1,
                        help="records run through 'identify REC --mass M --out DIR' (default 1)")
    parser.add_argument("--diagnose-records", type=int, default=1,
                        help="records run through 'diagnose REC --mass M' (default 1; 0 skips)")
    parser.add_argument("--statsmodels-records", type=int, default=1,
                        help="records fitted again by statsmodels' MLEModel.fit (default 1; 0 skips; about 40 s each)")
    parser.add_argument("--import-repeats", type=int, default=3,
                        help="fresh interpreters per import timing (default 3; 0 skips the import timings)")
    parser.add_argument("--study", type=int, default=0, metavar="N",
                        help="also time a batch of N records through 'identify FOLDER --manifest M --estimator "
                             "record' (default 0: off)")
    parser.add_argument("--jobs", type=int, default=2, metavar="J", help="processes of the --study batch (default 2)")
    parser.add_argument("--dask", action="store_true",
                        help="with --study: also run the batch on a distributed.LocalCluster of J workers")
    parser.add_argument("--out", metavar="FILE.md", help="write the tables (markdown) to this file too")
    args = parser.parse_args(argv)

    wall_started = time.perf_counter()
    load_before = os.getloadavg()
    print(f"Load average (1, 5, 15 min) before: {', '.join(f'{x:.2f}' for x in load_before)}", flush=True)
    generators = [g.strip() for g in args.generators.split(",") if g.strip()]
    records = []
    for person in draw_people(args.people, args.seed):
        for generator in generators:
            records.append({"name": f"p{person['person']}_{generator}", "person": person["person"],
                            "generator": generator, "f_b": person["f_b"], "f_h_true": person["f_h"],
                            "xi_h_true": person["xi_h"], "record": simulate(person, generator)})
    print(f"{len(records)} records simulated ({DURATION:g} s at {FS:g} Hz)", flush=True)

    warm = warm_up(records[0]["record"]) if records else 0.0
    print(f"library (warm-up {warm:.1f} s):", flush=True)
    library = time_library(records, progress=lambda text: print(text, flush=True))
    for row, item in zip(library, records):
        row["name"] = item["name"]

    imports, profile = [], {}
    if args.import_repeats > 0:
        print("imports ...", flush=True)
        imports = import_times(args.import_repeats)
        for code in ("import smd_statespace", "import smd_statespace.cli", "import " + ", ".join(IDENTIFY_IMPORTS)):
            profile[code] = importtime(code)

    cli, diagnose = [], []
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        for item in records[:args.cli_records]:
            cli.append(time_cli(item, folder))
            print(f"  identify {item['name']}: {cli[-1]['wall']:.1f} s wall, fit {cli[-1]['fit']:.1f} s", flush=True)
        for item in records[:args.diagnose_records]:
            diagnose.append(time_diagnose(item, folder))
            print(f"  diagnose {item['name']}: {diagnose[-1]['wall']:.1f} s wall", flush=True)

    side = []
    for row in library[:args.statsmodels_records]:
        side.append(compare_statsmodels(row))
        s = side[-1]
        print(f"  statsmodels {s['name']}: ours {s['ours_seconds']:.1f} s, statsmodels {s['sm_seconds']:.1f} s",
              flush=True)

    study = []
    if args.study > 0:
        print(f"study of {args.study} records, {args.jobs} jobs ...", flush=True)
        study = time_study(args.study, args.jobs, args.seed, generators, args.dask)

    load_after = os.getloadavg()
    took = time.perf_counter() - wall_started
    command = "python benchmarks/person_perf.py" + ("" if argv is None and len(sys.argv) == 1 else
                                                     " " + shlex.join(sys.argv[1:] if argv is None else argv))
    lines = ["# The record-level person: where the time goes (`benchmarks/person_perf.py`)", "",
             "```text", f"$ OPENBLAS_NUM_THREADS=1 {command}",
             f"Load average (1, 5, 15 min) before: {', '.join(f'{x:.2f}' for x in load_before)}; after: "
             f"{', '.join(f'{x:.2f}' for x in load_after)}; {os.cpu_count()} CPUs; run took {took:.0f} s.", "```", "",
             f"- {machine_line()}.",
             f"- {len(records)} records: {args.people} simulated people (seed {args.seed}) x generators "
             f"{', '.join(generators)}; {DURATION:g} s at {FS:g} Hz each.", ""]
    if library:
        lines += library_section(library, warm)
    if imports or profile or cli or diagnose:
        lines += cli_section(imports, profile, cli, diagnose)
    if side:
        lines += statsmodels_section(side)
    if study:
        lines += study_section(study)
    text = "\n".join(lines)
    print()
    print(text)
    if args.out:
        Path(args.out).write_text(text + "\n", encoding="utf-8")
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
