"""Accuracy benchmark of the record-level identification (:func:`smd_statespace.person.identify_person`).

Simulated people bounce for 30 s at 100 Hz across the article's range; each
record is identified once, as a user would (``identify_person`` with its
defaults but the interval method), and the estimates are compared with the
simulator's truth::

    python benchmarks/person_accuracy.py                  # the documented run (about 17 min on one core)
    python benchmarks/person_accuracy.py --quick          # 3 records per generator: to time things
    python benchmarks/person_accuracy.py --records 20 --generators jumps --intervals wald

Truth
-----
* People (:func:`draw_people`): ``f_b`` uniform 1.5-3.5 Hz, ``f_h`` uniform
  1.8-4.2 Hz, ``xi_h`` uniform 0.1-0.5, body mass uniform 50-90 kg, each
  ``BLF_i`` the simulator's default (0.25, 0.15, 0.05, 0.02) g times an
  independent uniform factor 0.7-1.3; force phases the simulator's default
  (a realistic GRF shape).
* Records: :func:`~smd_statespace.simulation.simulate_bouncing`, 30 s at
  100 Hz, GRF noise 1 % of body weight, the default cycle-to-cycle variation
  (``f_b`` 2 %, coefficients 10 %) with each generator of ``--generators``:
  ``jumps`` (the force's frequency and coefficients jump at the force-cycle
  boundaries, as the record-level model assumes) and ``smooth`` (they drift
  continuously; the model's piecewise-constant cycles are then an
  approximation).
* The same people (and simulator seeds) are used for every generator, so the
  generators are compared record by record.

What is measured
----------------
Per generator: the relative error of ``f_h`` (median and worst), the
absolute error of ``xi_h`` (median and worst), the coverage of the 90 %
intervals of ``f_h`` and ``xi_h``, the share of records whose innovations
pass the Ljung-Box test at 1 % (``ljung_box_p >= 0.01``), the median
kurtosis of the standardised innovations, the median seconds per
``identify_person`` call (``time.perf_counter``) and the failures (every
record's exceptions are caught and counted with their messages).

Timing experiment (``--no-timing-experiment`` to skip): the same records
fitted with (a) the simulator's true force-cycle boundaries
(``identify_person`` itself, ``timing="template"``, with its boundary
estimate replaced by the given
:class:`~smd_statespace.person.timing.CycleTiming`: every other step is the
library's), (b) the default ``timing`` (the main table's fits) and, for
``jumps`` records, every other ``timing`` of ``identify_person``
(``model``, ``template``, ``peaks``); with each estimated timing's boundary
jitter against the true boundaries
(:data:`EXPERIMENT_TIMINGS`); and the first ``--ablation-records`` smooth
records simulated again with only the frequency drift or only the
coefficient drift (:data:`ABLATIONS`), fitted with their true boundaries.

Everything random comes from one :class:`numpy.random.SeedSequence` (``--seed``),
spawned once per record, so the same seed gives the same tables (up to the
timings).
"""

from __future__ import annotations

import os

# Timings are per core: keep BLAS single-threaded unless the caller says otherwise.
for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

import argparse  # noqa: E402
import contextlib  # noqa: E402
import datetime  # noqa: E402
import inspect  # noqa: E402
import platform  # noqa: E402
import shlex  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from collections import Counter  # noqa: E402
from pathlib import Path  # noqa: E402

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import scipy  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from scipy import stats  # noqa: E402
from tqdm.auto import tqdm  # noqa: E402

import smd_statespace  # noqa: E402
from smd_statespace.person import fit as person_fit  # noqa: E402
from smd_statespace.person import identify_person  # noqa: E402
from smd_statespace.person.timing import TIMING_METHODS, CycleTiming  # noqa: E402
from smd_statespace.simulation import DEFAULT_BLF, simulate_bouncing  # noqa: E402
from smd_statespace.simulation.variation import VARIATIONS  # noqa: E402

import person_calibration  # noqa: E402  (beside this script: the held-out calibration)

REPO = Path(__file__).resolve().parents[1]

RANGES = {"f_b": (1.5, 3.5), "f_h": (1.8, 4.2), "xi_h": (0.1, 0.5), "mass": (50.0, 90.0)}
"""Uniform ranges of the simulated people (Hz, Hz, -, kg)."""

WIDE_RANGES = {"f_b": (1.5, 3.5), "f_h_over_f_b": (1.05, 1.6), "xi_h": (0.08, 0.6), "mass": (50.0, 90.0)}
"""``--people wide``: ``f_h`` drawn relative to ``f_b`` (the unseen-variation issue's spread, the hard
cases near ``f_b`` and near ``1.5 f_b`` included), ``xi_h`` wider."""

BLF_FACTOR = (0.7, 1.3)
"""Each ``BLF_i`` is :data:`DEFAULT_BLF` times an independent uniform factor in this range."""

DURATION, FS, NOISE = 30.0, 100.0, 0.01
"""Record length (s), sampling rate (Hz) and GRF noise (fraction of body weight)."""

LEVEL = 0.9
"""Confidence level of the intervals."""

N_HARMONICS = 4
GENERATORS = VARIATIONS
CALIBRATED_ON = ("jumps", "smooth", "coefficients", "pulses", "tempo")
"""The generators :data:`~smd_statespace.person.calibration.CALIBRATION` and the model-error floor were measured on (the
five of docs/person-calibration.md, on other people: seeds 2027-2028; before it ``jumps`` and ``smooth``), named,
so that a generator added to the simulator later is marked held out (the method never saw it). The table
*Calibrated on the others* holds each generator out in turn."""
_SIGNATURE = inspect.signature(identify_person).parameters
DEFAULT_TIMING = _SIGNATURE["timing"].default
"""``identify_person``'s default ``timing``: the main table's fits."""

DEFAULT_VARIATION = _SIGNATURE["variation"].default
"""``identify_person``'s default ``variation`` (``--variation``' default)."""

DEFAULT_INTERVALS = _SIGNATURE["intervals"].default
"""``identify_person``'s default interval method (``--intervals``' default)."""

TIMINGS = ("true",) + tuple(dict.fromkeys((DEFAULT_TIMING, "model") + tuple(TIMING_METHODS)))
"""Force-cycle boundaries of the timing experiment: the simulator's, then every ``timing`` of ``identify_person``."""

EXPERIMENT_TIMINGS = {"jumps": TIMINGS, "smooth": tuple(dict.fromkeys(("true", DEFAULT_TIMING, "template"))),
                      **{g: tuple(dict.fromkeys(("true", DEFAULT_TIMING))) for g in VARIATIONS
                         if g not in ("jumps", "smooth")}}
"""Fits per record of each generator in the timing experiment (the default timing is the main table's fit).

``smooth`` records are fitted with their true boundaries too (where the
phase passes a multiple of 2 pi): what is left is the model's
piecewise-constant force against a smoothly drifting one."""

TIMING_LABELS = {"true": "true force-cycle boundaries", "model": "`timing=\"model\"`",
                 "template": "`timing=\"template\"`", "peaks": "`timing=\"peaks\"`"}

TARGETS = {"f_h_med": 3.0, "f_h_worst": 8.0, "xi_h_med": 0.04, "coverage": (85.0, 95.0), "white": 85.0}
"""Targets: f_h relative error (%) median and worst, xi_h absolute error median, coverage (%), white share (%)."""

ABLATIONS = {"smooth, f_b drift only": {"coef_variation": 0.0}, "smooth, coefficient drift only": {"fb_variation": 0.0}}
"""Smooth records with one of the two drifts switched off (simulator arguments), fitted with their true boundaries."""

SHIFT_LIMIT = 10.0
"""Estimated boundaries count as shifted when their common shift exceeds this many % of the period."""

COUNT_TOLERANCE = 0.1
"""An estimated timing has the wrong number of cycles when it differs from the true count by more than this fraction."""

WHITE_P = 0.01
"""A record's innovations count as white when the Ljung-Box p-value is at least this."""

ANALYSIS_BEGIN, ANALYSIS_END = "<!-- analysis:begin -->", "<!-- analysis:end -->"


# ---------------------------------------------------------------------------
# Truth
# ---------------------------------------------------------------------------


def draw_people(n: int, seed: int, spread: str = "article") -> pd.DataFrame:
    """Draw ``n`` people and their simulator seeds from one ``SeedSequence(seed)`` (one child per record).

    ``spread`` "article" draws from :data:`RANGES`, "wide" from :data:`WIDE_RANGES`.

    Returns
    -------
    pandas.DataFrame
        ``record, f_b, f_h, xi_h, mass, blf1..blf4, sim_seed``.
    """
    return pd.DataFrame([{"record": k, **draw_person(child, spread)}
                         for k, child in enumerate(np.random.SeedSequence(seed).spawn(n))])


def draw_person(child: np.random.SeedSequence, spread: str = "article") -> dict:
    """One person of :func:`draw_people` from its record's ``child`` SeedSequence: ``f_b, f_h, xi_h, mass,
    blf1..blf4, sim_seed``.

    The child spawns the person's draw and the simulator's seed; the ranges are drawn in their order, then one
    factor per BLF (:data:`BLF_FACTOR`).
    """
    people_ss, sim_ss = child.spawn(2)
    rng = np.random.default_rng(people_ss)
    row = {name: float(rng.uniform(lo, hi)) for name, (lo, hi) in (RANGES if spread == "article"
                                                                    else WIDE_RANGES).items()}
    if "f_h_over_f_b" in row:
        row["f_h"] = row.pop("f_h_over_f_b") * row["f_b"]
    factors = rng.uniform(*BLF_FACTOR, size=len(DEFAULT_BLF))
    for i, (base, factor) in enumerate(zip(DEFAULT_BLF, factors), start=1):
        row[f"blf{i}"] = float(base * factor)
    row["sim_seed"] = int(sim_ss.generate_state(1, np.uint32)[0])
    return row


def simulate(person, generator: str, noise=NOISE, **overrides):
    """The person's 30 s record with the given variation generator and GRF noise (fraction of body weight;
    ``overrides``: other simulator arguments)."""
    blf = [person[f"blf{i}"] for i in range(1, len(DEFAULT_BLF) + 1)]
    return simulate_bouncing(mass=person["mass"], f_b=person["f_b"], f_h=person["f_h"], xi_h=person["xi_h"],
                             duration=DURATION, fs=FS, blf=blf, noise=noise, seed=int(person["sim_seed"]),
                             variation=generator, **overrides)


def true_boundaries(sim) -> np.ndarray:
    """The simulator's force-cycle boundaries (s), covering the record."""
    return np.append(sim.cycles.t_start.values, sim.cycles.t_end.values[-1])


# ---------------------------------------------------------------------------
# Fits
# ---------------------------------------------------------------------------


@contextlib.contextmanager
def given_boundaries(boundaries):
    """Make ``identify_person`` use ``boundaries`` instead of estimating them (every other step unchanged)."""
    timing = CycleTiming(np.asarray(boundaries, dtype=float), "given")
    original = person_fit.estimate_timing
    person_fit.estimate_timing = lambda *args, **kwargs: timing
    try:
        yield
    finally:
        person_fit.estimate_timing = original


def identify_with_boundaries(record, boundaries, intervals, variation, level=LEVEL):
    """:func:`identify_person` with given force-cycle boundaries (held fixed: ``timing="template"``)."""
    with given_boundaries(boundaries):
        return identify_person(record, n_harmonics=N_HARMONICS, variation=variation, timing="template",
                               intervals=intervals, level=level)


def boundary_jitter(estimated, truth, record_time) -> dict:
    """Where estimated boundaries inside the record fall in the true force cycles.

    Each estimated boundary is located in the true cycles as a phase
    ``2 pi (t - b_j) / (b_{j+1} - b_j)``. Their circular mean is the common
    *shift* (in % of the period, -50 to 50) and their circular standard
    deviation ``sqrt(-2 ln R)`` (``R`` the mean resultant length) the
    *jitter* (in % of the period and in ms at the mean period). A shift
    leaves the periodic part of the force alone (the template absorbs a
    phase origin) but puts the force's cycle-to-cycle changes inside the
    model's cycles; jitter moves every boundary differently.
    """
    inner = estimated[(estimated > record_time[0]) & (estimated < record_time[-1])]
    n_true = int(np.sum((truth > record_time[0]) & (truth < record_time[-1])) - 1)
    if inner.size < 2:
        return {"jitter_ms": np.nan, "jitter_pct": np.nan, "shift_pct": np.nan,
                "cycles_found": max(inner.size - 1, 0), "cycles_true": n_true}
    j = np.clip(np.searchsorted(truth, inner, side="right") - 1, 0, truth.size - 2)
    angle = 2.0 * np.pi * (inner - truth[j]) / (truth[j + 1] - truth[j])
    mean = complex(np.mean(np.exp(1j * angle)))
    fraction = np.sqrt(-2.0 * np.log(max(abs(mean), 1e-12))) / (2.0 * np.pi)
    period = float(np.mean(np.diff(truth)))
    return {"jitter_ms": 1e3 * fraction * period, "jitter_pct": 100.0 * fraction,
            "shift_pct": 100.0 * float(np.angle(mean)) / (2.0 * np.pi), "cycles_found": int(inner.size - 1),
            "cycles_true": n_true}


def fit_row(person, generator, timing, sim, intervals, variation) -> dict:
    """Fit one record with one timing; never raises (failures are recorded)."""
    row = {"generator": generator, "timing": timing, **{k: person[k] for k in ("record", "f_b", "f_h", "xi_h",
                                                                               "mass")}}
    start = time.perf_counter()
    try:
        if timing == "true":
            result = identify_with_boundaries(sim.record, true_boundaries(sim), intervals, variation)
        else:
            result = identify_person(sim.record, n_harmonics=N_HARMONICS, variation=variation, timing=timing,
                                     intervals=intervals, level=LEVEL)
        row["seconds"] = time.perf_counter() - start
        d = result.to_dict()
    except Exception as exc:  # noqa: BLE001 - one record must never kill the run
        row["seconds"] = time.perf_counter() - start
        row["error"] = f"{type(exc).__name__}: {str(exc).splitlines()[0][:160]}"
        return row
    from smd_statespace.person.calibration import CALIBRATION  # here: person_before_after.py imports this script
    # to simulate records for trees older than the module

    (f_lo, f_hi), (x_lo, x_hi) = result.intervals["f_h"], result.intervals["xi_h"]
    row.update({
        "error": "",
        "f_h_est": result.f_h, "xi_h_est": result.xi_h, "f_h_se": float(result.se[0]), "xi_h_se": float(result.se[1]),
        # the sds before the calibration's factor (person_calibration.py measures factors on them)
        **{f"{name}_raw_se": float(result.se[i]) / (CALIBRATION[result.model.variation][name]
                                                    if intervals == "calibrated" else 1.0)
           for i, name in enumerate(("f_h", "xi_h"))},
        "f_h_low": float(f_lo), "f_h_high": float(f_hi), "xi_h_low": float(x_lo), "xi_h_high": float(x_hi),
        "ljung_box_p": d["ljung_box_p"], "kurtosis": d["kurtosis"], "noise_bw": d["noise_bw"],
        "n_cycles": d["n_cycles"], "f_b_est": d["f_b"], "warnings": len(d["warnings"]),
        "variation": result.model.variation, "f_h_determined": bool(d["f_h_determined"]),
        "xi_h_determined": bool(d["xi_h_determined"]), "f_h_artefact": bool(result.artefact("f_h")),
        "variations_disagree": bool(result.variation_disagreement()), "misfit_share": float(d["misfit_share"]),
        "f_h_low_narrow": float(result.narrow_intervals.get("f_h", (f_lo, f_hi))[0]),
        "f_h_high_narrow": float(result.narrow_intervals.get("f_h", (f_lo, f_hi))[1]),
        "xi_h_low_narrow": float(result.narrow_intervals.get("xi_h", (x_lo, x_hi))[0]),
        "xi_h_high_narrow": float(result.narrow_intervals.get("xi_h", (x_lo, x_hi))[1]),
        "blf1_true": float(sim.truth["blf"][0]), "blf1_est": d["blf_1"], "blf1_low": d["blf_1_low"],
        "blf1_high": d["blf_1_high"],
    })
    if timing == "true":
        b = true_boundaries(sim)
        inner = int(np.sum((b > sim.record.time[0]) & (b < sim.record.time[-1])) - 1)
        row.update({"jitter_ms": 0.0, "jitter_pct": 0.0, "shift_pct": 0.0, "cycles_found": inner,
                    "cycles_true": inner})
    elif sim is not None:
        row.update(boundary_jitter(result.model.timing.boundaries, true_boundaries(sim), sim.record.time))
    return row


def _simulation_failed(person, generator, timing, exc) -> dict:
    return {"generator": generator, "timing": timing, "record": int(person["record"]), "f_b": person["f_b"],
            "f_h": person["f_h"], "xi_h": person["xi_h"], "mass": person["mass"], "seconds": np.nan,
            "error": f"simulation: {type(exc).__name__}: {str(exc).splitlines()[0][:160]}"}


def _task_rows(task) -> list:
    """The rows of one task ``(person, generator, timings, overrides, intervals, variation, noise)``: simulate, fit
    each timing; every row carries the record's GRF noise (``noise``, fraction of body weight)."""
    person, generator, timings, overrides, intervals, variation, noise = task
    try:
        sim = simulate(person, "smooth" if overrides else generator, noise=noise, **overrides)
        rows = [fit_row(person, generator, timing, sim, intervals, variation) for timing in timings]
    except Exception as exc:  # noqa: BLE001 - one record must never kill the run
        rows = [_simulation_failed(person, generator, timing, exc) for timing in timings]
    return [{**row, "noise": noise} for row in rows]


def run(people: pd.DataFrame, generators, intervals, timing_experiment, ablation_records=0,
        variation=DEFAULT_VARIATION, jobs=1, noise=NOISE) -> pd.DataFrame:
    """Simulate and fit every record (``jobs`` processes; the rows do not depend on it); one progress bar."""
    def timings_of(generator):
        return EXPERIMENT_TIMINGS[generator] if timing_experiment else (DEFAULT_TIMING,)

    ablation = people.iloc[:ablation_records] if "smooth" in generators else people.iloc[:0]
    tasks = [(person, generator, timings_of(generator), {}, intervals, variation, noise)
             for generator in generators for _, person in people.iterrows()]
    tasks += [(person, name, ("true",), overrides, intervals, variation, noise)
              for name, overrides in ABLATIONS.items() for _, person in ablation.iterrows()]
    rows = []
    with tqdm(total=sum(len(t[2]) for t in tasks), desc="fits", unit="fit", file=sys.stderr,
              dynamic_ncols=True) as bar:
        with contextlib.ExitStack() as stack:
            if jobs > 1:
                from concurrent.futures import ProcessPoolExecutor

                results = stack.enter_context(ProcessPoolExecutor(jobs)).map(_task_rows, tasks)
            else:
                results = map(_task_rows, tasks)
            for task, task_rows in zip(tasks, results):  # in task order, whatever the number of jobs
                rows += task_rows
                bar.set_postfix_str(f"{task[1]} record {int(task[0]['record'])}")
                bar.update(len(task_rows))
    frame = pd.DataFrame(rows)
    for column in ("f_h_est", "xi_h_est", "f_h_low", "f_h_high", "xi_h_low", "xi_h_high", "ljung_box_p", "kurtosis",
                   "jitter_ms", "jitter_pct", "shift_pct", "cycles_found", "cycles_true", "blf1_true", "blf1_est",
                   "blf1_low", "blf1_high"):
        if column not in frame:
            frame[column] = np.nan
    frame["record"] = frame["record"].astype(int)
    frame["f_h_err_pct"] = 100.0 * (frame["f_h_est"] - frame["f_h"]) / frame["f_h"]
    frame["xi_h_err"] = frame["xi_h_est"] - frame["xi_h"]
    frame["f_h_covered"] = (frame["f_h_low"] <= frame["f_h"]) & (frame["f_h"] <= frame["f_h_high"])
    frame["xi_h_covered"] = (frame["xi_h_low"] <= frame["xi_h"]) & (frame["xi_h"] <= frame["xi_h_high"])
    frame["blf1_err_pct"] = 100.0 * (frame["blf1_est"] - frame["blf1_true"]) / frame["blf1_true"]
    frame["blf1_covered"] = (frame["blf1_low"] <= frame["blf1_true"]) & (frame["blf1_true"] <= frame["blf1_high"])
    return frame


# ---------------------------------------------------------------------------
# Summaries
# ---------------------------------------------------------------------------


def summarise(rows: pd.DataFrame) -> dict:
    """The table's numbers for one generator and timing."""
    ok = rows[rows["error"] == ""]
    n = len(ok)
    out = {"records": len(rows), "fitted": n, "failures": len(rows) - n}
    if n == 0:
        return out
    f_err = ok["f_h_err_pct"].abs()
    x_err = ok["xi_h_err"].abs()
    out.update({
        "f_h_med": float(f_err.median()), "f_h_worst": float(f_err.max()),
        "f_h_bias": float(ok["f_h_err_pct"].median()),
        "xi_h_med": float(x_err.median()), "xi_h_worst": float(x_err.max()),
        "xi_h_bias": float(ok["xi_h_err"].median()),
        "f_h_cov": 100.0 * float(ok["f_h_covered"].mean()), "xi_h_cov": 100.0 * float(ok["xi_h_covered"].mean()),
        "blf1_med": float(ok["blf1_err_pct"].abs().median()), "blf1_cov": 100.0 * float(ok["blf1_covered"].mean()),
        "white": 100.0 * float((ok["ljung_box_p"] >= WHITE_P).mean()), "kurtosis": float(ok["kurtosis"].median()),
        "seconds": float(ok["seconds"].median()), "jitter_pct": float(ok["jitter_pct"].median()),
        "jitter_ms": float(ok["jitter_ms"].median()),
        "f_h_within_8": 100.0 * float((f_err <= TARGETS["f_h_worst"]).mean()),
        "count_off": int(np.sum(np.abs(ok["cycles_found"] / ok["cycles_true"] - 1.0) > COUNT_TOLERANCE)),
        "shifted": int(np.sum(ok["shift_pct"].abs() > SHIFT_LIMIT)),
        "variations": ", ".join(f"{name} {count}" for name, count in Counter(ok["variation"]).most_common()),
    })
    return out


def coverage_interval(p_pct, n, level=0.95):
    """Wilson interval (%) of a coverage estimated from ``n`` records."""
    if n == 0 or not np.isfinite(p_pct):
        return (np.nan, np.nan)
    p = p_pct / 100.0
    z = stats.norm.ppf(0.5 + level / 2.0)
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (100.0 * (centre - half), 100.0 * (centre + half))


def mark(value, ok):
    """A number followed by a pass/miss sign."""
    return f"{value} ✓" if ok else f"{value} ✗"


def main_table(frame: pd.DataFrame, generators) -> list:
    """Markdown rows of the main table (default timing, one row per generator)."""
    lo_cov, hi_cov = TARGETS["coverage"]
    lines = [
        "| generator | records (failed) | f_h rel. error median | f_h worst | xi_h abs. error median | xi_h worst | "
        "f_h 90 % coverage | xi_h 90 % coverage | BLF1 rel. error median | BLF1 90 % coverage | Ljung-Box p ≥ 0.01 "
        "| median kurtosis | s / record |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
        f"| *target* | | ≤ {TARGETS['f_h_med']:g} % | ≤ {TARGETS['f_h_worst']:g} % | ≤ {TARGETS['xi_h_med']:g} | | "
        f"{lo_cov:g}-{hi_cov:g} % | {lo_cov:g}-{hi_cov:g} % | | {lo_cov:g}-{hi_cov:g} % | ≥ {TARGETS['white']:g} % "
        "| (3 if normal) | |",
    ]
    for generator in generators:
        s = summarise(frame[(frame["generator"] == generator) & (frame["timing"] == DEFAULT_TIMING)])
        if s["fitted"] == 0:
            lines.append(f"| {generator} | {s['records']} ({s['failures']}) | - | - | - | - | - | - | - | - | - | - "
                         "| - |")
            continue
        cells = [
            mark(f"{s['f_h_med']:.1f} %", s["f_h_med"] <= TARGETS["f_h_med"]),
            mark(f"{s['f_h_worst']:.1f} %", s["f_h_worst"] <= TARGETS["f_h_worst"]),
            mark(f"{s['xi_h_med']:.3f}", s["xi_h_med"] <= TARGETS["xi_h_med"]),
            f"{s['xi_h_worst']:.3f}",
            mark(f"{s['f_h_cov']:.0f} %", lo_cov <= s["f_h_cov"] <= hi_cov),
            mark(f"{s['xi_h_cov']:.0f} %", lo_cov <= s["xi_h_cov"] <= hi_cov),
            f"{s['blf1_med']:.1f} %",
            mark(f"{s['blf1_cov']:.0f} %", lo_cov <= s["blf1_cov"] <= hi_cov),
            mark(f"{s['white']:.0f} %", s["white"] >= TARGETS["white"]),
            f"{s['kurtosis']:.2f}",
            f"{s['seconds']:.1f}",
        ]
        label = generator if generator in CALIBRATED_ON else f"{generator} (held out)"
        lines.append(f"| {label} | {s['records']} ({s['failures']}) | " + " | ".join(cells) + " |")
    return lines


def extra_table(frame: pd.DataFrame, generators) -> list:
    """Bias, share within the worst-case target, and the coverages' sampling uncertainty."""
    lines = ["| generator | f_h median signed error | xi_h median signed error | records with f_h error ≤ 8 % "
             "| f_h coverage, 95 % Wilson interval | xi_h coverage, 95 % Wilson interval "
             "| timing with the cycle count off by > 10 % | variation model chosen (records) |",
             "|---|---|---|---|---|---|---|---|"]
    for generator in generators:
        s = summarise(frame[(frame["generator"] == generator) & (frame["timing"] == DEFAULT_TIMING)])
        if s["fitted"] == 0:
            continue
        fc = coverage_interval(s["f_h_cov"], s["fitted"])
        xc = coverage_interval(s["xi_h_cov"], s["fitted"])
        lines.append(f"| {generator} | {s['f_h_bias']:+.1f} % | {s['xi_h_bias']:+.3f} | {s['f_h_within_8']:.0f} % "
                     f"| {fc[0]:.0f}-{fc[1]:.0f} % | {xc[0]:.0f}-{xc[1]:.0f} % | {s['count_off']} "
                     f"| {s['variations']} |")
    return lines


def held_out_table(frame: pd.DataFrame, generators) -> list:
    """Markdown rows: every generator held out in turn, its coverage with the intervals calibrated on the others.

    The calibration is rebuilt by ``person_calibration.py`` (:func:`person_calibration.held_out`) as the library's
    was made: factors per variation model on the raw sds of the other generators' records, a model-error floor per
    variation model sized on them by leaving each of them out in turn, the "determined" rule on the new sds.
    """
    rows = person_calibration.prepare(frame)
    if rows["generator"].nunique() < 2:
        return []
    schemes = ("as fitted", "by variation, floors held out", "by variation, no floor")
    lines = ["| held out | f_h factor from the others (by variation model, on the raw sd) | f_h coverage: shipped, "
             "calibrated on the others, same without the floor | xi_h factor from the others | xi_h coverage: "
             "shipped, calibrated on the others, same without the floor |", "|---|---|---|---|---|"]
    results = {name: person_calibration.held_out(rows, name, schemes) for name in ("f_h", "xi_h")}
    for held in generators:
        if held not in set(rows["generator"]):
            continue
        cells = []
        for name, result in results.items():
            train = rows[rows["generator"] != held]
            factors, _ = person_calibration.measure_factors(train, name, ("variation",))
            mine = result[result["held out"] == held]
            coverage = [100.0 * float(np.average(mine.loc[mine["scheme"] == scheme, "coverage"] / 100.0,
                                                 weights=mine.loc[mine["scheme"] == scheme, "records"]))
                        for scheme in schemes]
            cells += [", ".join(f"{v[0]} {f:.2f}" for v, f in sorted(factors.items())) or "-",
                      ", ".join(f"{c:.0f} %" for c in coverage)]
        lines.append(f"| {held} | " + " | ".join(cells) + " |")
    return lines


def timing_table(frame: pd.DataFrame, generators) -> list:
    """Markdown rows of the timing experiment."""
    labels = {t: TIMING_LABELS[t] + (" (default)" if t == DEFAULT_TIMING else "") for t in TIMINGS}
    lines = ["| generator | boundaries | records (failed) | boundary jitter, median (% of period / ms) "
             f"| records with the boundaries shifted > {SHIFT_LIMIT:g} % of a period "
             "| records with the cycle count off by > 10 % | f_h rel. error median "
             "| f_h worst | xi_h abs. error median | xi_h worst | f_h coverage | xi_h coverage | Ljung-Box p ≥ 0.01 "
             "| median kurtosis | s / record |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for generator in generators:
        for timing in EXPERIMENT_TIMINGS[generator]:
            rows = frame[(frame["generator"] == generator) & (frame["timing"] == timing)]
            if rows.empty:
                continue
            s = summarise(rows)
            if s["fitted"] == 0:
                lines.append(f"| {generator} | {labels[timing]} | {s['records']} ({s['failures']}) | - | - | - | - | - "
                             "| - | - | - | - | - | - | - |")
                continue
            jitter = "0" if timing == "true" else f"{s['jitter_pct']:.1f} % / {s['jitter_ms']:.1f} ms"
            lines.append(f"| {generator} | {labels[timing]} | {s['records']} ({s['failures']}) | {jitter} "
                         f"| {s['shifted']} | {s['count_off']} "
                         f"| {s['f_h_med']:.1f} % "
                         f"| {s['f_h_worst']:.1f} % | {s['xi_h_med']:.3f} | {s['xi_h_worst']:.3f} "
                         f"| {s['f_h_cov']:.0f} % | {s['xi_h_cov']:.0f} % | {s['white']:.0f} % | {s['kurtosis']:.2f} "
                         f"| {s['seconds']:.1f} |")
    return lines


def ablation_table(frame: pd.DataFrame) -> list:
    """Smooth records with one drift at a time, true boundaries, against both drifts on the same records."""
    names = [n for n in ABLATIONS if (frame["generator"] == n).any()]
    if not names:
        return []
    records = sorted(set(frame.loc[frame["generator"].isin(names), "record"]))
    lines = ["| smooth records, true boundaries | records (failed) | f_h rel. error median | f_h worst "
             "| f_h median signed error | xi_h abs. error median | xi_h worst | f_h coverage | xi_h coverage "
             "| Ljung-Box p ≥ 0.01 |", "|---|---|---|---|---|---|---|---|---|---|"]
    for name in ["smooth"] + names:
        rows = frame[(frame["generator"] == name) & (frame["timing"] == "true") & frame["record"].isin(records)]
        if rows.empty:
            continue
        s = summarise(rows)
        if s["fitted"] == 0:
            continue
        label = "both drifts (the `smooth` generator)" if name == "smooth" else name.split(", ", 1)[1]
        lines.append(f"| {label} | {s['records']} ({s['failures']}) | {s['f_h_med']:.1f} % | {s['f_h_worst']:.1f} % "
                     f"| {s['f_h_bias']:+.1f} % | {s['xi_h_med']:.3f} | {s['xi_h_worst']:.3f} | {s['f_h_cov']:.0f} % "
                     f"| {s['xi_h_cov']:.0f} % | {s['white']:.0f} % |")
    return lines


def worst_table(frame: pd.DataFrame, generators, count=6) -> list:
    """The records with the largest f_h errors (default timing), with the same record's other fits."""
    main = frame[(frame["timing"] == DEFAULT_TIMING) & (frame["error"] == "")]
    others = frame.set_index(["generator", "timing", "record"])
    other_timings = [t for t in TIMINGS if t != DEFAULT_TIMING]
    lines = ["| generator | record | f_b (Hz) | f_h (Hz) | f_h / f_b | xi_h | f_h estimate (error) | xi_h estimate "
             "| Ljung-Box p | cycles found / true | boundary shift / jitter (% of period) | "
             + " | ".join(f"f_h error, {TIMING_LABELS[t]}" for t in other_timings) + " | f_h error, other generator |",
             "|" + "---|" * (12 + len(other_timings))]

    def lookup(generator, timing, record):
        key = (generator, timing, record)
        if key not in others.index:
            return "-"
        value = others.loc[key, "f_h_err_pct"]
        return f"{value:+.1f} %" if np.isfinite(value) else "failed"

    for generator in generators:
        rows = main[main["generator"] == generator]
        rows = rows.reindex(rows["f_h_err_pct"].abs().sort_values(ascending=False).index)[:count]
        other = [g for g in generators if g != generator]
        for _, r in rows.iterrows():
            k = int(r["record"])
            found = r.get("cycles_found", np.nan)
            counts = f"{int(found)} / {int(r['cycles_true'])}" if np.isfinite(found) else "-"
            lines.append(
                f"| {generator} | {k} | {r['f_b']:.2f} | {r['f_h']:.2f} | {r['f_h'] / r['f_b']:.2f} | {r['xi_h']:.2f} "
                f"| {r['f_h_est']:.2f} ({r['f_h_err_pct']:+.1f} %) | {r['xi_h_est']:.3f} | {r['ljung_box_p']:.2g} "
                f"| {counts} | {r['shift_pct']:+.0f} / {r['jitter_pct']:.1f} | "
                + " | ".join(lookup(generator, t, k) for t in other_timings)
                + f" | {lookup(other[0], DEFAULT_TIMING, k) if other else '-'} |")
    return lines


def failure_lines(frame: pd.DataFrame) -> list:
    """Failures grouped by generator, timing and message."""
    failed = frame[frame["error"] != ""]
    if failed.empty:
        return ["No record failed."]
    lines = []
    for (generator, timing), group in failed.groupby(["generator", "timing"]):
        for message, count in Counter(group["error"]).most_common():
            records = ", ".join(str(k) for k in group.loc[group["error"] == message, "record"])
            lines.append(f"- {generator}, {timing} timing: {count} × `{message}` (records {records})")
    return lines


def correlation_lines(frame: pd.DataFrame, generators) -> list:
    """Where the errors come from: correlations of |f_h error| with the record's features."""
    lines = ["| generator, timing | Spearman ρ of abs. f_h error with: boundary jitter | f_h / f_b | xi_h | f_b |",
             "|---|---|---|---|---|"]
    for generator in generators:
        for timing in EXPERIMENT_TIMINGS[generator]:
            ok = frame[(frame["generator"] == generator) & (frame["timing"] == timing) & (frame["error"] == "")]
            if len(ok) < 5:
                continue
            err = ok["f_h_err_pct"].abs()
            cells = []
            for feature in (ok["jitter_pct"], ok["f_h"] / ok["f_b"], ok["xi_h"], ok["f_b"]):
                if feature.nunique() < 2:
                    cells.append("-")
                else:
                    cells.append(f"{stats.spearmanr(err, feature).statistic:+.2f}")
            lines.append(f"| {generator}, {timing} | " + " | ".join(cells) + " |")
    return lines


# ---------------------------------------------------------------------------
# Figures
# ---------------------------------------------------------------------------

COLOURS = {"jumps": "tab:blue", "smooth": "tab:orange", "coefficients": "tab:green", "pulses": "tab:red",
           "tempo": "tab:purple"}
TIMING_COLOURS = {"true": "tab:green", "model": "tab:purple", "template": "tab:blue", "peaks": "tab:red"}


def accuracy_figure(frame: pd.DataFrame, generators, path: Path, intervals: str):
    """Estimated against true f_h and xi_h with the 90 % intervals as error bars, one colour per generator."""
    fig = Figure(figsize=(11, 6.0), layout="constrained")
    axes = fig.subplots(1, 2)
    offsets = {g: (i - (len(generators) - 1) / 2) for i, g in enumerate(generators)}
    truth_range = {name: (float(frame[name].min()), float(frame[name].max())) for name in ("f_h", "xi_h")}
    for ax, name, unit, spread in ((axes[0], "f_h", " (Hz)", truth_range["f_h"]),
                                   (axes[1], "xi_h", "", truth_range["xi_h"])):
        width = spread[1] - spread[0]
        for generator in generators:
            ok = frame[(frame["generator"] == generator) & (frame["timing"] == DEFAULT_TIMING) & (frame["error"] == "")]
            if ok.empty:
                continue
            x = ok[name].to_numpy() + offsets[generator] * 0.006 * width  # side by side when they share a truth
            est = ok[f"{name}_est"].to_numpy()
            yerr = np.vstack([np.maximum(est - ok[f"{name}_low"], 0), np.maximum(ok[f"{name}_high"] - est, 0)])
            covered = ok[f"{name}_covered"].to_numpy()
            ax.errorbar(x, est, yerr=yerr, fmt="none", ecolor=COLOURS.get(generator, "k"), alpha=0.45, lw=1.0)
            ax.plot(x[covered], est[covered], "o", ms=4, color=COLOURS.get(generator, "k"),
                    label=f"{generator}: {covered.mean() * 100:.0f} % cover")
            ax.plot(x[~covered], est[~covered], "o", ms=5, mfc="white", mec=COLOURS.get(generator, "k"))
        ax.plot([], [], "o", ms=5, mfc="white", mec="k", label="open: interval misses the truth")
        lims = (spread[0] - 0.08 * width, spread[1] + 0.08 * width)
        ax.plot(lims, lims, "k-", lw=0.8)
        if name == "f_h":
            for rel in (0.03, 0.08):
                ax.plot(lims, np.multiply(lims, 1 + rel), "k:", lw=0.6)
                ax.plot(lims, np.multiply(lims, 1 - rel), "k:", lw=0.6)
            ax.plot([], [], "k:", lw=0.6, label="dotted: ±3 %, ±8 %")  # in the legend: a label on the lines hid points
        else:
            for delta in (0.04,):
                ax.plot(lims, np.add(lims, delta), "k:", lw=0.6)
                ax.plot(lims, np.subtract(lims, delta), "k:", lw=0.6)
            ax.plot([], [], "k:", lw=0.6, label="dotted: ±0.04")
        ax.set_xlim(lims)
        # the estimates' range, not the widest interval's: a bar cut at the frame runs on beyond it
        estimates = frame.loc[(frame["timing"] == DEFAULT_TIMING) & (frame["error"] == ""), f"{name}_est"]
        low = min(lims[0], float(estimates.min()) - 0.05 * width) if len(estimates) else lims[0]
        high = max(lims[1], float(estimates.max()) + 0.05 * width) if len(estimates) else lims[1]
        ax.set_ylim(low, high)
        ax.set_xlabel(f"true {name}{unit}")
        ax.set_ylabel(f"estimated {name}{unit}")
        ax.set_title(f"{name}: estimate and {LEVEL:.0%} {intervals} interval\n(timing={DEFAULT_TIMING}; "
                     "bars cut at the frame)", fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2)  # below: off the points
    noise = float(frame["noise"].iloc[0]) if "noise" in frame else NOISE  # rows of older runs: the default
    fig.suptitle(f"Record-level identification on simulated {DURATION:g} s records at {FS:g} Hz "
                 f"(f_b {RANGES['f_b'][0]}-{RANGES['f_b'][1]} Hz, noise {noise:.1%} BW)")
    fig.savefig(path, dpi=110, bbox_inches="tight")  # the legends sit below the axes


def timing_figure(frame: pd.DataFrame, generators, path: Path):
    """f_h and xi_h errors against f_h / f_b for each generator's fits of the timing experiment."""
    rows = [g for g in generators if (frame["generator"].eq(g) & frame["timing"].eq("true")).any()]
    if not rows:
        return False
    fig = Figure(figsize=(11, 4.2 * len(rows)), layout="constrained")
    axes = np.atleast_2d(fig.subplots(len(rows), 2))
    labels = {"true": "true boundaries", "model": "model", "template": "template", "peaks": "GRF peaks"}
    labels[DEFAULT_TIMING] += " (default)"
    for row, generator in zip(axes, rows):
        ok_all = frame[(frame["generator"] == generator) & (frame["error"] == "")]
        for timing in EXPERIMENT_TIMINGS[generator]:
            ok = ok_all[ok_all["timing"] == timing]
            if ok.empty:
                continue
            ratio = ok["f_h"] / ok["f_b"]
            for ax, column in zip(row, ("f_h_err_pct", "xi_h_err")):
                ax.plot(ratio, ok[column], "o", ms=4, color=TIMING_COLOURS[timing], alpha=0.75,
                        label=f"{labels[timing]} ({len(ok)})")
        low, high = row[0].get_ylim()
        ratio = np.linspace(0.55, 2.6, 300)
        row[0].plot(ratio, 100.0 * (1.0 / ratio - 1.0), color="0.5", lw=0.9, ls="-.", label="estimate = f_b")
        row[0].set_ylim(low, high)
        for ax, target, ylabel, name in ((row[0], TARGETS["f_h_worst"], "f_h error (%)", "f_h"),
                                         (row[1], TARGETS["xi_h_med"], "xi_h error (estimate - truth)", "xi_h")):
            ax.axhline(0, color="k", lw=0.8)
            ax.axhspan(-target, target, color="0.85", alpha=0.6, lw=0)
            for harmonic in (1, 2):
                ax.axvline(harmonic, color="0.4", ls="--", lw=0.7)
            ax.set_xlabel("f_h / f_b (dashed: the force's first and second harmonics)")
            ax.set_ylabel(ylabel)
            ax.set_title(f"{generator}: {name} error by force-cycle boundaries (grey: ±{target:g}"
                         f"{' %' if name == 'f_h' else ''})")
            ax.grid(alpha=0.3)
            ax.legend(fontsize=8)
    fig.savefig(path, dpi=110)
    return True


# ---------------------------------------------------------------------------
# Report
# ---------------------------------------------------------------------------


def machine_line(intervals: str) -> str:
    """Python, libraries, commit, CPU."""
    package = Path(smd_statespace.__file__).resolve().parent
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True, text=True,
                              check=True).stdout.strip()
        if package == REPO / "smd_statespace":
            dirty = subprocess.run(["git", "status", "--porcelain", "--", "smd_statespace"], cwd=REPO,
                                   capture_output=True, text=True, check=True).stdout.strip()
            commit = f"commit {head}" + (" + uncommitted changes in smd_statespace/" if dirty else "")
        else:
            commit = f"imported from {package}; repository HEAD {head}"
    except (OSError, subprocess.CalledProcessError):
        commit = "commit unknown"
    cpu = platform.processor() or "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (f"Python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}, "
            f"smd_statespace {smd_statespace.__version__} ({commit}); {cpu}, {os.cpu_count()} CPUs, "
            f"single-threaded BLAS, one process; intervals: {intervals}")


def preserved_analysis(path: Path) -> str:
    """The hand-written analysis between the markers of an existing report (kept when re-run)."""
    if path.exists():
        text = path.read_text(encoding="utf-8")
        if ANALYSIS_BEGIN in text and ANALYSIS_END in text:
            return text.split(ANALYSIS_BEGIN, 1)[1].split(ANALYSIS_END, 1)[0].strip("\n")
    return "_(not written yet)_"


def write_report(path: Path, frame: pd.DataFrame, args, generators, command: str, wall: float, figures: dict):
    """Write the Markdown page (keeps an existing hand-written analysis)."""
    analysis = preserved_analysis(path)
    rel = {k: os.path.relpath(v, path.parent) for k, v in figures.items() if v is not None}
    n = args.records
    lines = [
        "# Record-level identification: accuracy on simulated records",
        "",
        "Generated by `benchmarks/person_accuracy.py`; the tables are rewritten by every run, the analysis at the "
        "end is kept.",
        "",
        f"- Command: `{command}` ({datetime.date.today().isoformat()}, {wall / 60:.1f} min wall time, "
        f"load average {os.getloadavg()[0]:.1f} at the end)",
        f"- Machine: {machine_line(args.intervals)}",
        f"- Records: {n} people per generator (the same people and simulator seeds for every generator), "
        f"seed {args.seed}; {DURATION:g} s at {FS:g} Hz, GRF noise {args.noise:.1%} of body weight; f_b uniform "
        f"{RANGES['f_b'][0]}-{RANGES['f_b'][1]} Hz, "
        + (f"f_h uniform {RANGES['f_h'][0]}-{RANGES['f_h'][1]} Hz, xi_h uniform {RANGES['xi_h'][0]}-{RANGES['xi_h'][1]}"
           if args.people == "article" else
           f"f_h / f_b uniform {WIDE_RANGES['f_h_over_f_b'][0]}-{WIDE_RANGES['f_h_over_f_b'][1]}, xi_h uniform "
           f"{WIDE_RANGES['xi_h'][0]}-{WIDE_RANGES['xi_h'][1]}")
        + f", mass uniform {RANGES['mass'][0]:g}-{RANGES['mass'][1]:g} "
        f"kg, BLF_i = ({', '.join(f'{b:g}' for b in DEFAULT_BLF)}) g times uniform {BLF_FACTOR[0]}-{BLF_FACTOR[1]}, "
        "the simulator's default cycle-to-cycle variation (f_b 2 %, coefficients 10 %) and force phases.",
        f"- Identification: `identify_person(record, n_harmonics={N_HARMONICS}, variation=\"{args.variation}\", "
        f"timing=\"{DEFAULT_TIMING}\", intervals=\"{args.intervals}\", level={LEVEL})` (the library's default "
        f"timing); {args.jobs} process(es); seconds are per call "
        "(`time.perf_counter`), the simulation excluded.",
        "",
        "## Accuracy per generator",
        "",
        "Errors are |estimate - truth| (relative for f_h); coverage is the share of records whose 90 % interval "
        f"holds the truth; a record's innovations are white when its Ljung-Box p ≥ {WHITE_P}. ✓/✗: target met or "
        "missed.",
        "",
        *main_table(frame, generators),
        "",
        *extra_table(frame, generators),
        "",
        "### Calibrated on the others",
        "",
        "Each generator held out in turn, the intervals rebuilt as the library's were made "
        "(`benchmarks/person_calibration.py`, [person-calibration.md](person-calibration.md)), but from the "
        "*other* generators' records only: factors per variation model chosen on the raw sds (the 90th "
        "percentile of |error| / sd over 1.645), a model-error floor per variation model sized on the others by "
        "leaving each of them out in turn, the \"determined\" rule on the new sds and the library's widening of "
        "artefacts kept. Their coverage on the held-out generator's records, beside the shipped intervals' and "
        "the same without the floor.",
        "",
        *held_out_table(frame, generators),
        "",
    ]
    if "figure" in rel:
        lines += [f"![estimated against true f_h and xi_h]({rel['figure']})", ""]
    if (frame["timing"] == "true").any():
        lines += [
            "## Timing experiment: the force-cycle boundaries as the error source",
            "",
            "The same records fitted again, changing only the force-cycle boundaries: the simulator's true ones "
            "(`identify_person` itself with `timing=\"template\"` and its boundary estimate replaced by the given "
            "`CycleTiming`, so every other step is the library's), the default "
            f"`timing=\"{DEFAULT_TIMING}\"` (the fits of the table above) and, on `jumps` records, every other "
            "`timing` of `identify_person`: `model` (start from the template alignment, then per-cycle phase and "
            "phase-rate errors as model states move the starts), `template` (the GRF's own mean cycle aligned to "
            "each cycle) and `peaks` (GRF peak to GRF peak). On `jumps` records the true boundaries are where the "
            "force jumps, so that fit is the model exactly as simulated; on `smooth` records they are where the "
            "force's phase passes a multiple of 2 pi, and what is left is the model's piecewise-constant force "
            "against a smoothly drifting one. Each estimated boundary is located by its phase in the true "
            "cycles; the boundary jitter is the circular standard deviation of these phases within a record (in % "
            "of the period and in ms, median over records), the shift their circular mean. A common shift leaves "
            "the periodic part of the force alone (the template absorbs a phase origin) but puts the force's "
            "cycle-to-cycle changes inside the model's cycles.",
            "",
            *timing_table(frame, generators),
            "",
        ]
        if "timing" in rel:
            lines += [f"![f_h and xi_h errors by boundaries]({rel['timing']})", ""]
    ablation = ablation_table(frame)
    if ablation:
        n_ab = frame.loc[frame["generator"].isin(list(ABLATIONS)), "record"].nunique()
        lines += [
            "## Smooth generator: which drift",
            "",
            f"The first {n_ab} `smooth` records simulated again with one of the two drifts switched off "
            "(`coef_variation=0`: only the bouncing frequency drifts; `fb_variation=0`: only the harmonics' "
            "amplitudes and phases drift), all fitted with their true boundaries; the first row is the same "
            "records with both drifts (from the timing experiment).",
            "",
            *ablation,
            "",
        ]
    lines += ["## Where the errors are", "",
              "Spearman rank correlations over records of |f_h error| with features of the record:", "",
              *correlation_lines(frame, generators), "",
              f"Largest f_h errors (`timing=\"{DEFAULT_TIMING}\"`), with the same record's other fits:", "",
              *worst_table(frame, generators), "",
              "## Failures", "", *failure_lines(frame), "",
              "## Analysis", "", ANALYSIS_BEGIN, analysis, ANALYSIS_END, ""]
    path.write_text("\n".join(lines), encoding="utf-8")


# ---------------------------------------------------------------------------
# Command line
# ---------------------------------------------------------------------------


def parse_args(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--records", type=int, default=None,
                        help="records (people) per generator (default 50; 3 with --quick)")
    parser.add_argument("--generators", default=",".join(GENERATORS),
                        help="comma-separated variation generators of simulate_bouncing (default all: "
                             f"{','.join(GENERATORS)}; the intervals were calibrated on "
                             f"{', '.join(CALIBRATED_ON)} at other seeds)")
    parser.add_argument("--seed", type=int, default=2024, help="root of the SeedSequence (default 2024)")
    parser.add_argument("--intervals", choices=("calibrated", "wald", "profile"), default=DEFAULT_INTERVALS,
                        help=f"interval method of identify_person (default {DEFAULT_INTERVALS}, the library's)")
    parser.add_argument("--out", type=Path, default=None,
                        help="Markdown page (default docs/person-benchmark.md; with --quick a temporary directory); "
                             "figures go to figures/ beside it")
    parser.add_argument("--csv", type=Path, default=None, help="also write every fit's row to this CSV")
    parser.add_argument("--rows", type=Path, default=None,
                        help="write the page from the rows of an earlier run (its --csv, run with the same options) "
                             "instead of fitting again")
    parser.add_argument("--no-timing-experiment", action="store_true",
                        help="fit every record with the default timing only (no true-boundary, other-timing or "
                             "one-drift fits)")
    parser.add_argument("--ablation-records", type=int, default=10,
                        help="smooth records refitted with one drift at a time (true boundaries; default the first 10)")
    parser.add_argument("--variation", default=DEFAULT_VARIATION,
                        help=f"variation model of identify_person (default {DEFAULT_VARIATION}, the library's)")
    parser.add_argument("--jobs", type=int, default=1,
                        help="processes (default 1); each record is seeded on its own, so the rows do not change")
    parser.add_argument("--quick", action="store_true", help="3 records per generator: a smoke run")
    parser.add_argument("--noise", type=float, default=NOISE,
                        help=f"GRF noise as a fraction of body weight (default {NOISE:g}, the calibration's; "
                             "real plates are often quieter: 0.003)")
    parser.add_argument("--people", choices=("article", "wide"), default="article",
                        help="article: f_h 1.8-4.2 Hz, xi_h 0.1-0.5 (default); wide: f_h/f_b 1.05-1.6, xi_h 0.08-0.6")
    args = parser.parse_args(argv)
    if args.records is None:
        args.records = 3 if args.quick else 50
    if args.records < 1:
        parser.error("--records must be at least 1")
    if not 0.0 <= args.noise < 0.2:
        parser.error(f"--noise {args.noise:g}: give the GRF noise as a fraction of body weight, 0 to 0.2")
    if args.rows is not None and not args.rows.is_file():
        parser.error(f"--rows {args.rows}: no such file (the --csv of an earlier run)")
    generators = tuple(g.strip() for g in args.generators.split(",") if g.strip())
    unknown = [g for g in generators if g not in GENERATORS]
    if unknown or not generators:
        parser.error(f"unknown generator(s) {unknown}; choose from {', '.join(GENERATORS)}")
    if args.out is None:
        args.out = (Path(tempfile.mkdtemp(prefix="person-benchmark-")) / "person-benchmark.md" if args.quick
                    else REPO / "docs" / "person-benchmark.md")
    return args, generators


def main(argv=None):
    args, generators = parse_args(argv)
    command = "python benchmarks/person_accuracy.py " + shlex.join(sys.argv[1:] if argv is None else argv)
    start = time.perf_counter()
    if args.rows is not None:  # the page again from an earlier run's rows (same options), nothing refitted
        frame = pd.read_csv(args.rows, keep_default_na=True)
        frame["error"] = frame["error"].fillna("").astype(str)
        wall = float(frame["seconds"].sum())
        command += f" (tables rebuilt from the rows of {args.rows.name}; wall time: the fits' seconds summed)"
    else:
        people = draw_people(args.records, args.seed, args.people)
        frame = run(people, generators, args.intervals, not args.no_timing_experiment,
                    0 if args.no_timing_experiment else min(args.ablation_records, args.records), args.variation,
                    args.jobs, args.noise)
        wall = time.perf_counter() - start
    if args.csv is not None and args.rows is None:
        frame.to_csv(args.csv, index=False)
    figure_dir = args.out.parent / "figures"
    figure_dir.mkdir(parents=True, exist_ok=True)
    # the documented page keeps its figures' names; any other page gets its own (named after the page)
    stem = "person_accuracy" if args.out.name == "person-benchmark.md" else f"{args.out.stem}_accuracy"
    figures = {"figure": figure_dir / f"{stem}.png", "timing": figure_dir / f"{stem}_timing.png"}
    accuracy_figure(frame, generators, figures["figure"], args.intervals)
    if not timing_figure(frame, generators, figures["timing"]):
        figures["timing"] = None
    write_report(args.out, frame, args, generators, command.strip(), wall, figures)
    print("\n".join(main_table(frame, generators)))
    if not args.no_timing_experiment:
        print("\n".join(timing_table(frame, generators)))
        print("\n".join(ablation_table(frame)))
    print("\n".join(failure_lines(frame)))
    print(f"wrote {args.out} and {', '.join(str(p) for p in figures.values() if p is not None)} "
          f"({wall / 60:.1f} min)", file=sys.stderr)


if __name__ == "__main__":
    main()
