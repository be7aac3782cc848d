"""Accuracy benchmark: every estimator and the exact grid reference against known truth.

Simulated people bounce across the article's bouncing frequencies
(1.5-3.5 Hz); their records are identified cycle by cycle exactly as a user
would (``preprocess`` then ``CycleRunner`` with the library's defaults), and
every reported value is compared with the simulator's truth::

    python benchmarks/accuracy.py                       # the documented run (about 17 min on one core)
    python benchmarks/accuracy.py --quick               # 5 cycles, 3 per experiment: to time things
    python benchmarks/accuracy.py --estimators ekf,grid --records 5 --experiment none

What is measured (per estimator): the median absolute error of ``f_h``,
``xi_h`` and ``BLF1-3``; the coverage of the reported ``±1.645 sd`` intervals
(a calibrated 90 % interval covers the truth 90 % of the time); the fraction
of cycles the runner flags as determining ``f_h`` and ``xi_h``; passes,
seconds per cycle and failures; the distance of every estimate from the grid
reference (the exact posterior under the model's own assumptions); the
correlation of estimates with the truth; two data-free guesses for scale
(the prior mean, and the population median at the record's ``f_b``); and
the grid posteriors of a record's cycles pooled into one per person.

Truth
-----
* People: ``f_b`` cycles through :data:`FB_LEVELS`; ``f_h``, ``xi_h``,
  ``BLF1-3`` and the mass come from :func:`~smd_statespace.simulation.sample_population`
  (the article's Table 2) with ``f_h`` redrawn into the estimators' prior range
  and ``BLF`` redrawn below the largest coefficient of the prior box (see
  :func:`draw_people`); ``BLF4`` is the simulator's default.
* Records: :func:`~smd_statespace.simulation.simulate_bouncing` with its default
  cycle-to-cycle variation and GRF noise of 1 % body weight.
* ``f_h`` and ``xi_h`` are constant per record. ``BLF_i`` is per force cycle
  (the simulator's ``.cycles``); an identified cycle (GRF peak to GRF peak)
  takes the force cycle whose start is nearest its own, provided they are
  closer than :data:`MATCH_TOLERANCE` of that force cycle's period
  (:func:`match_truth`). ``BLF`` is an amplitude, so it does not depend on the
  small shift between the two time origins.

Experiments (``--experiment``)
------------------------------
``ladder``
    The grid reference on a subset of cycles while one thing at a time is
    made ideal: the simulator's exact ``u, u', u''`` instead of the
    pipeline's, the true force-cycle boundaries and ``f_b`` instead of the
    GRF peaks, lower observation / process noise, Euler instead of RK4.
``pf-ess``
    One pass of the article's particle filter from the prior: effective
    sample size after the first observations, and how narrow the cloud ends
    up compared with the grid posterior; also with 10 times more particles.
``single-pass``
    Every estimator limited to one pass, against the (one-pass) grid
    reference: what the article's repeated passes do to the intervals.

Everything random comes from one :class:`numpy.random.SeedSequence`, so the
same ``--seed`` gives the same tables (up to the timings).
"""

from __future__ import annotations

import os

# Timings are per core: keep BLAS single-threaded unless the caller says otherwise.
for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import platform  # noqa: E402
import shlex  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import scipy  # noqa: E402
from tqdm.auto import tqdm  # noqa: E402

import smd_statespace  # noqa: E402
from smd_statespace import article  # noqa: E402
from smd_statespace.estimators import ESTIMATORS, cycle_data, get_estimator  # noqa: E402
from smd_statespace.model import DISCRETISATIONS, SMDModel  # noqa: E402
from smd_statespace.determined import DETERMINED_FRACTION  # noqa: E402
from smd_statespace.identify.runner import CycleRunner  # noqa: E402
from smd_statespace.signals import Cycle, preprocess  # noqa: E402
from smd_statespace.simulation import DEFAULT_BLF, sample_population, simulate_bouncing  # noqa: E402

REPO = Path(__file__).resolve().parents[1]

FB_LEVELS = (1.5, 2.0, 2.5, 3.0, 3.5)
"""Nominal bouncing frequencies (Hz) of the simulated records, one per article band they fall in."""

Z90 = 1.645
"""Half-width of a central 90 % normal interval, in standard deviations."""

MATCH_TOLERANCE = 0.2
"""An identified cycle matches a force cycle when their starts differ by less than this fraction of its period."""

N_BLF = 3
"""Load factors compared with the truth (Table 2 has BLF1-3)."""

DEFAULT_ESTIMATORS = ("pf", "rbpf", "ukf", "ekf", "grid")
EXPERIMENTS = ("ladder", "pf-ess", "single-pass")
ANALYSIS_BEGIN, ANALYSIS_END = "<!-- analysis:begin -->", "<!-- analysis:end -->"

METRICS = ["f_h", "xi_h"] + [f"blf_{i}" for i in range(1, N_BLF + 1)]
LABELS = {"f_h": "f_h", "xi_h": "xi_h", "blf_1": "BLF1", "blf_2": "BLF2", "blf_3": "BLF3"}
UNITS = {"f_h": "Hz", "xi_h": "-", "blf_1": "g", "blf_2": "g", "blf_3": "g"}


# ---------------------------------------------------------------------------
# Truth: people, records, cycles
# ---------------------------------------------------------------------------


@dataclasses.dataclass
class Case:
    """One simulated person and record, ready to identify.

    Attributes
    ----------
    key : int
        Record number (the runner's ``record_key``).
    person : dict
        Drawn parameters: ``f_b, f_h, xi_h, blf1..3, mass``.
    synthetic : SyntheticRecord
        The simulator's output (record, states, per-cycle force table).
    preprocessed : Preprocessed
        The pipeline output with only the selected cycles left valid.
    truth : pandas.DataFrame
        One row per selected cycle (see :func:`match_truth`).
    """

    key: int
    person: dict
    synthetic: object
    preprocessed: object
    truth: pd.DataFrame


def draw_people(n: int, seeds, model: SMDModel, f_b: float | None = None, seed=None) -> pd.DataFrame:
    """Draw ``n`` people, ``f_b`` cycling through :data:`FB_LEVELS`.

    ``sample_population`` (Table 2, independent skew-normal marginals) with two
    bounds tightened so that the truth lies inside the estimators' prior:
    ``f_h`` is redrawn into ``model``'s ``f_h_range`` (Table 2 puts a large
    share of the 3-3.5 Hz bands above 4 Hz) and every ``BLF`` is redrawn below
    the largest coefficient of the prior box (then ``|a_i|, |b_i| <= BLF_i``
    fit at any phase, before the simulator's cycle-to-cycle variation).

    Parameters
    ----------
    n : int
        Number of people.
    seeds : sequence of numpy.random.SeedSequence
        One per person (ignored with ``f_b``).
    model : SMDModel
        Supplies the prior ranges.
    f_b, seed : float and SeedSequence, optional
        Draw all ``n`` people at this one level from ``seed`` instead (in one call).
    """
    coefficient_high = max(abs(v) for v in model.options["coefficient_range"])
    bounds = {"f_h": model.options["f_h_range"], "blf": (0.0, coefficient_high)}
    if f_b is not None:
        return sample_population(n, f_b, seed=seed, bounds=bounds)
    rows = [sample_population(1, FB_LEVELS[i % len(FB_LEVELS)], seed=seeds[i], bounds=bounds).iloc[0]
            for i in range(n)]
    return pd.DataFrame(rows).reset_index(drop=True)


def select_cycles(preprocessed, count: int):
    """Keep ``count`` valid cycles, evenly spread over the record; flag the others invalid.

    Returns a copy of ``preprocessed`` (the runner then reports the others as skipped).
    """
    valid = [cycle.index for cycle in preprocessed.valid_cycles]
    if count <= 0 or count >= len(valid):
        return preprocessed
    return only_cycles(preprocessed, [valid[int(i)] for i in np.round(np.linspace(0, len(valid) - 1, count))])


def match_truth(preprocessed, synthetic, person: dict, coefficient_high: float) -> pd.DataFrame:
    """Truth of every valid identified cycle, by the nearest force-cycle start.

    ``coefficient_high`` is the largest ``|a_i|, |b_i|`` of the estimators' prior.

    Returns
    -------
    pandas.DataFrame
        Columns ``cycle`` (identified), ``force_cycle`` (matched, -1 if none),
        ``offset`` (identified start minus force start, s), ``matched``,
        ``f_h``, ``xi_h`` (record truth), ``blf_1..3`` (force cycle, NaN if
        unmatched), ``f_b_true`` (force cycle), ``outside_prior`` (a true
        coefficient of the cycle lies outside the prior box), and the relative
        RMS error of the pipeline's ``u, u', u''`` against the simulator's
        exact states over the cycle (``err_u``, ``err_u_dot``, ``err_u_ddot``).
    """
    force = synthetic.cycles
    starts = force["t_start"].to_numpy()
    periods = (force["t_end"] - force["t_start"]).to_numpy()
    cycles = preprocessed.valid_cycles
    t0 = np.array([c.t_start for c in cycles])
    nearest = np.argmin(np.abs(t0[:, None] - starts[None, :]), axis=1)
    offset = t0 - starts[nearest]
    matched = np.abs(offset) < MATCH_TOLERANCE * periods[nearest]
    table = pd.DataFrame({"cycle": [c.index for c in cycles], "force_cycle": np.where(matched, nearest, -1),
                          "offset": offset, "matched": matched, "f_h": person["f_h"], "xi_h": person["xi_h"]})
    for i in range(1, N_BLF + 1):
        table[f"blf_{i}"] = np.where(matched, force[f"blf{i}"].to_numpy()[nearest], np.nan)
    table["f_b_true"] = np.where(matched, force["f_b"].to_numpy()[nearest], np.nan)
    coefficients = force.filter(regex=r"^[ab]\d+$").to_numpy()[nearest]
    table["outside_prior"] = np.any(np.abs(coefficients) > coefficient_high, axis=1) & matched
    exact = {"u": synthetic.states["u"].to_numpy(), "u_dot": synthetic.states["u_dot"].to_numpy(),
             "u_ddot": synthetic.states["u_ddot"].to_numpy()}
    pipeline = {"u": preprocessed.disp, "u_dot": preprocessed.vel, "u_ddot": preprocessed.acc}
    for name in exact:
        table[f"err_{name}"] = [
            float(np.sqrt(np.mean((pipeline[name][c.samples] - exact[name][c.samples]) ** 2))
                  / np.sqrt(np.mean(exact[name][c.samples] ** 2))) for c in cycles]
    return table


def build_cases(people: pd.DataFrame, seeds, duration: float, cycles_per_record: int, model: SMDModel,
                noise: float = 0.01) -> list[Case]:
    """Simulate and preprocess every person's record; select cycles; match the truth.

    ``noise`` is the GRF noise (fraction of body weight); the simulator's
    other settings (cycle-to-cycle variation, 100 Hz) are its defaults.
    """
    coefficient_high = max(abs(v) for v in model.options["coefficient_range"])
    cases = []
    for key, person in people.iterrows():
        synthetic = simulate_bouncing(mass=person["mass"], f_b=person["f_b"], f_h=person["f_h"],
                                      xi_h=person["xi_h"], duration=duration, noise=noise,
                                      blf=[person[f"blf{i}"] for i in range(1, N_BLF + 1)] + list(DEFAULT_BLF[N_BLF:]),
                                      seed=seeds[key])
        preprocessed = select_cycles(preprocess(synthetic.record), cycles_per_record)
        truth = match_truth(preprocessed, synthetic, person.to_dict(), coefficient_high)
        cases.append(Case(int(key), person.to_dict(), synthetic, preprocessed, truth))
    return cases


def truth_table(cases: list[Case]) -> pd.DataFrame:
    """All cases' truth rows with ``record`` and the nominal ``f_b`` of the record."""
    return pd.concat([case.truth.assign(record=case.key, f_b_nominal=case.person["f_b"]) for case in cases],
                     ignore_index=True)


# ---------------------------------------------------------------------------
# Data variants for the experiments
# ---------------------------------------------------------------------------


def exact_states(case: Case):
    """The case's pipeline output with the simulator's exact ``u, u', u''`` swapped in."""
    states = case.synthetic.states
    return dataclasses.replace(case.preprocessed, disp=states["u"].to_numpy(), vel=states["u_dot"].to_numpy(),
                               acc=states["u_ddot"].to_numpy())


def force_cycles(preprocessed, case: Case):
    """``preprocessed`` with every matched cycle replaced by its true force cycle.

    Samples strictly inside the force cycle (no sample of a neighbouring
    cycle, whose coefficients differ) and the force cycle's own ``f_b``; the
    cycle keeps its identified index so that seeds and truth still match.
    """
    fs, time_ = preprocessed.fs, preprocessed.time
    force = case.synthetic.cycles
    cycles = []
    for row in case.truth.itertuples():
        if not row.matched:
            continue
        start = int(np.ceil(force["t_start"].iloc[row.force_cycle] * fs - 1e-9))
        stop = int(np.floor(force["t_end"].iloc[row.force_cycle] * fs + 1e-9))
        cycles.append(Cycle(index=row.cycle, start=start, stop=stop, t_start=float(time_[start]),
                            t_end=float(time_[stop]), f_b=float(force["f_b"].iloc[row.force_cycle])))
    return dataclasses.replace(preprocessed, cycles=cycles)


def true_bouncing_frequency(preprocessed, case: Case):
    """``preprocessed`` with every matched cycle's ``f_b`` set to its force cycle's (span unchanged)."""
    true_fb = dict(zip(case.truth["cycle"], case.truth["f_b_true"]))
    return dataclasses.replace(preprocessed, cycles=[
        dataclasses.replace(c, f_b=float(true_fb[c.index])) if c.index in true_fb and np.isfinite(true_fb[c.index])
        else c for c in preprocessed.cycles])


def only_cycles(preprocessed, indices):
    """``preprocessed`` with only the cycles ``indices`` valid."""
    keep = set(indices)
    return dataclasses.replace(preprocessed, cycles=[
        c if c.index in keep else dataclasses.replace(c, valid=False, reason="not selected")
        for c in preprocessed.cycles])


# ---------------------------------------------------------------------------
# Identification and scoring
# ---------------------------------------------------------------------------


def identify(jobs, estimator: str, model: SMDModel, seed: int, bar, options=None, max_passes=8, tolerance=0.05,
             results: dict | None = None):
    """Run one estimator over ``jobs`` (pairs ``(record_key, preprocessed)``); return the cycle rows.

    Uses :class:`~smd_statespace.identify.runner.CycleRunner` unchanged; skipped
    (unselected) cycles are dropped; ``wall`` is the wall time of the whole
    estimator run. With ``results`` (a dict), every cycle's final
    :class:`~smd_statespace.estimators.FilterResult` is stored in it under
    ``(record_key, cycle)``.
    """
    frames = []
    started = time.perf_counter()
    for key, preprocessed in jobs:
        runner = CycleRunner(model, estimator=estimator, max_passes=max_passes, tolerance=tolerance, seed=seed,
                             progress=False, keep_results=results is not None, **(options or {}))
        table = runner.run(preprocessed, record_key=key)
        if results is not None:
            results.update({(key, cycle): result for cycle, result in runner.results_.items()})
        table = table[table["status"] != "skipped"].assign(record=key)
        frames.append(table)
        bar.update(len(table))
    rows = pd.concat(frames, ignore_index=True)
    rows.attrs["wall"] = time.perf_counter() - started
    return rows


def score(rows: pd.DataFrame, truth: pd.DataFrame) -> pd.DataFrame:
    """Attach the truth to identified rows; add ``err_*`` (estimate - truth) and ``cover_*`` columns."""
    merged = rows.merge(truth, on=["record", "cycle"], how="left", suffixes=("", "_true"))
    for name in METRICS:
        merged[f"err_{name}"] = merged[name] - merged[f"{name}_true"]
        inside = np.abs(merged[f"err_{name}"]) <= Z90 * merged[f"{name}_sd"]
        merged[f"cover_{name}"] = inside.where(merged[f"err_{name}"].notna())
    return merged


def summary_row(scored: pd.DataFrame) -> dict:
    """One estimator's row of the main table."""
    ok = scored[scored["status"] == "ok"]
    row = {"cycles": len(scored), "failed": int((scored["status"] == "failed").sum())}
    for name in METRICS:
        row[f"mae_{name}"] = float(np.nanmedian(np.abs(ok[f"err_{name}"]))) if len(ok) else np.nan
    for name in METRICS:
        row[f"cov_{name}"] = 100.0 * float(ok[f"cover_{name}"].astype(float).mean()) if len(ok) else np.nan
    row["det_f_h"] = 100.0 * float(ok["f_h_determined"].astype(float).mean()) if len(ok) else np.nan
    row["det_xi_h"] = 100.0 * float(ok["xi_h_determined"].astype(float).mean()) if len(ok) else np.nan
    row["passes"] = float(ok["passes"].mean()) if len(ok) else np.nan
    row["seconds"] = float(scored["seconds"].mean())
    row["median_sd_f_h"] = float(ok["f_h_sd"].median()) if len(ok) else np.nan
    row["median_sd_xi_h"] = float(ok["xi_h_sd"].median()) if len(ok) else np.nan
    return row


def prior_mean_row(truth: pd.DataFrame, model: SMDModel) -> dict:
    """Errors of guessing the prior mean of ``f_h`` and ``xi_h`` for every cycle (no data at all)."""
    mean = {name: float(np.mean(model.options[f"{name}_range"])) for name in ("f_h", "xi_h")}
    return {f"mae_{name}": float(np.median(np.abs(truth[name] - value))) for name, value in mean.items()}


def population_median_row(truth: pd.DataFrame, model: SMDModel, seed, draws: int = 20000) -> dict:
    """Errors of guessing, for every cycle, the population median of its record's ``f_b`` level (no data).

    The medians come from ``draws`` people of the same distribution the truth
    was drawn from (:func:`draw_people`): the best data-free guess of a
    reader who knows the bouncing frequency and Table 2.
    """
    seeds = seed.spawn(len(FB_LEVELS))
    columns = {"f_h": "f_h", "xi_h": "xi_h", **{f"blf_{i}": f"blf{i}" for i in range(1, N_BLF + 1)}}
    medians = {}
    for f_b, level_seed in zip(FB_LEVELS, seeds):
        people = draw_people(draws, None, model, f_b=f_b, seed=level_seed)
        medians[f_b] = {name: float(people[column].median()) for name, column in columns.items()}
    guess = {name: truth["f_b_nominal"].map(lambda f, n=name: medians[f][n]) for name in columns}
    return {f"mae_{name}": float(np.nanmedian(np.abs(truth[name] - guess[name]))) for name in columns}


def correlation_table(scored: dict) -> pd.DataFrame:
    """Pearson correlation of estimates with the truth: over all cycles, and within each ``f_b`` level (mean).

    The population's ``f_h`` rises with ``f_b`` (Table 2), so the overall
    correlation partly reflects the bouncing frequency; the within-level
    correlation does not.
    """
    rows = {}
    for name, table in scored.items():
        ok = table[table["status"] == "ok"]
        row = {f"r {LABELS[m]}": ok[m].corr(ok[f"{m}_true"]) for m in METRICS}
        for m in ("f_h", "xi_h"):
            within = [group[m].corr(group[f"{m}_true"]) for _, group in ok.groupby("f_b_nominal")]
            row[f"r {LABELS[m]} within f_b"] = float(np.nanmean(within))
        rows[name] = row
    return pd.DataFrame(rows).T


def pooled_grid(results: dict, people: pd.DataFrame) -> pd.DataFrame:
    """Record-level ``(f_h, xi_h)`` from the grid reference: the cycles' posteriors multiplied.

    Each cycle's grid posterior is its likelihood times the uniform prior on
    the grid, so the normalised product over a record's cycles is the
    posterior given all of them, if ``f_h`` and ``xi_h`` are the same in every
    cycle (true of the simulated records) and the cycles are independent
    given them (approximately: each cycle restarts from the prior).

    Returns one row per record: ``record, f_b_nominal, cycles`` and, for
    ``f_h`` and ``xi_h``, the truth, pooled mean and sd, error and coverage.
    """
    log_posterior, counts = {}, {}
    for (record, _), result in results.items():
        log_posterior[record] = log_posterior.get(record, 0.0) + np.log(np.maximum(result.diagnostics["posterior"], 1e-300))
        counts[record] = counts.get(record, 0) + 1
        axes = {"f_h": result.diagnostics["f_h_grid"], "xi_h": result.diagnostics["xi_h_grid"]}
    rows = []
    for record, total in log_posterior.items():
        posterior = np.exp(total - total.max())
        posterior /= posterior.sum()
        row = {"record": record, "f_b_nominal": people.loc[record, "f_b"], "cycles": counts[record]}
        for name, marginal in (("f_h", posterior.sum(axis=1)), ("xi_h", posterior.sum(axis=0))):
            mean = float(marginal @ axes[name])
            sd = float(np.sqrt(marginal @ (axes[name] - mean) ** 2))
            truth = float(people.loc[record, name])
            row.update({f"{name}_true": truth, name: mean, f"{name}_sd": sd, f"err_{name}": mean - truth,
                        f"cover_{name}": abs(mean - truth) <= Z90 * sd})
        rows.append(row)
    return pd.DataFrame(rows)


def distance_from_grid(scored: dict) -> pd.DataFrame:
    """Per estimator: median ``|estimate - grid|`` and median ``sd / grid sd`` of ``f_h`` and ``xi_h``."""
    grid = scored["grid"][["record", "cycle", "f_h", "f_h_sd", "xi_h", "xi_h_sd"]]
    rows = {}
    for name, table in scored.items():
        if name == "grid":
            continue
        both = table[table["status"] == "ok"].merge(grid, on=["record", "cycle"], suffixes=("", "_grid"))
        rows[name] = {
            "f_h": np.median(np.abs(both["f_h"] - both["f_h_grid"])),
            "f_h_sd": np.median(both["f_h_sd"] / both["f_h_sd_grid"]),
            "xi_h": np.median(np.abs(both["xi_h"] - both["xi_h_grid"])),
            "xi_h_sd": np.median(both["xi_h_sd"] / both["xi_h_sd_grid"]),
        }
    return pd.DataFrame(rows).T


def band_breakdown(scored: dict, truth: pd.DataFrame, model: SMDModel) -> pd.DataFrame:
    """Median ``|f_h error|`` (Hz) per nominal bouncing frequency and estimator, with the prior-mean guess."""
    prior_mean = float(np.mean(model.options["f_h_range"]))
    out = []
    for f_b, group in truth.groupby("f_b_nominal"):
        low, high = article.BANDS[article.band_of(f_b)]
        row = {"f_b (Hz)": f"{f_b:g}", "article band": f"{low:g}-{high:g}", "cycles": len(group),
               "true f_h (Hz)": f"{group['f_h'].min():.2f}-{group['f_h'].max():.2f}"}
        for name, table in scored.items():
            ok = table[(table["status"] == "ok") & (table["f_b_nominal"] == f_b)]
            row[name] = np.nanmedian(np.abs(ok["err_f_h"])) if len(ok) else np.nan
        row["prior mean"] = np.median(np.abs(group["f_h"] - prior_mean))
        out.append(row)
    return pd.DataFrame(out)


# ---------------------------------------------------------------------------
# Experiments
# ---------------------------------------------------------------------------


def ladder_variants(model: SMDModel) -> list:
    """``(label, states, boundaries, model)`` of the ladder: one thing made ideal at a time."""
    options = dict(model.options)

    def variant(**changes):
        return SMDModel(**{**options, **changes})

    low = dict(observation_noise=0.01, process_noise=1e-4)
    return [
        ("main-table settings", "pipeline", "GRF peaks", model),
        ("Euler (article's discretisation)", "pipeline", "GRF peaks", variant(discretisation="euler")),
        ("observation noise 3 %", "pipeline", "GRF peaks", variant(observation_noise=0.03)),
        ("process noise 0.1 %", "pipeline", "GRF peaks", variant(process_noise=1e-3)),
        ("obs. 3 %, process 0.1 %", "pipeline", "GRF peaks", variant(observation_noise=0.03, process_noise=1e-3)),
        ("obs. 1 %, process 0.01 %", "pipeline", "GRF peaks", variant(**low)),
        ("exact states, obs. 1 %, process 0.01 %", "exact", "GRF peaks", variant(**low)),
        ("exact states, GRF-peak span but true f_b, obs. 1 %, process 0.01 %", "exact", "GRF peaks, true f_b",
         variant(**low)),
        ("force cycles, obs. 1 %, process 0.01 %", "pipeline", "force cycles", variant(**low)),
        ("exact states + force cycles", "exact", "force cycles", model),
        ("exact states + force cycles, obs. 1 %, process 0.01 %", "exact", "force cycles", variant(**low)),
    ]


def experiment_subset(cases: list[Case], count: int) -> list[tuple[Case, int]]:
    """``count`` matched cycles for the experiments: the first selected cycle of successive records."""
    chosen = []
    for case in cases:
        matched = case.truth[case.truth["matched"]]
        if len(matched):
            chosen.append((case, int(matched["cycle"].iloc[0])))
        if len(chosen) == count:
            break
    return chosen


def subset_rows(scored: pd.DataFrame, subset) -> pd.DataFrame:
    """The rows of ``scored`` that belong to the experiment cycles ``subset``."""
    keys = pd.DataFrame([(case.key, cycle) for case, cycle in subset], columns=["record", "cycle"])
    return scored.merge(keys, on=["record", "cycle"])


def run_ladder(subset, model: SMDModel, truth: pd.DataFrame, seed: int, bar, main_grid=None) -> pd.DataFrame:
    """The grid reference under every :func:`ladder_variants` entry; one summary row each.

    ``main_grid``: the main run's scored grid rows, reused for the first
    variant (the same computation; the grid is deterministic).
    """
    rows = []
    for label, states, boundaries, variant in ladder_variants(model):
        if variant is model and (states, boundaries) == ("pipeline", "GRF peaks") and main_grid is not None:
            summary = summary_row(subset_rows(main_grid, subset))
            rows.append(ladder_row(label, states, boundaries, variant, summary))
            continue
        jobs = []
        for case, cycle in subset:
            data = exact_states(case) if states == "exact" else case.preprocessed
            data = force_cycles(data, case) if boundaries == "force cycles" else data
            data = true_bouncing_frequency(data, case) if boundaries == "GRF peaks, true f_b" else data
            jobs.append((case.key, only_cycles(data, [cycle])))
        summary = summary_row(score(identify(jobs, "grid", variant, seed, bar), truth))
        rows.append(ladder_row(label, states, boundaries, variant, summary))
    return pd.DataFrame(rows)


def ladder_row(label, states, boundaries, variant: SMDModel, summary: dict) -> dict:
    """One row of the ladder table."""
    return {"variant": label, "states": states, "cycles from": boundaries,
            "obs. noise": f"{variant.observation_noise:.0%}",
            "process noise": f"{variant.process_noise:.2%}".replace(".00%", "%"),
            **{k: summary[k] for k in ("mae_f_h", "cov_f_h", "median_sd_f_h", "det_f_h",
                                       "mae_xi_h", "cov_xi_h", "median_sd_xi_h", "det_xi_h")}}


def run_pf_ess(subset, model: SMDModel, seed: int, particles: int, bar, grid_rows: pd.DataFrame) -> pd.DataFrame:
    """One pass of the particle filter from the prior per cycle: ESS and width against the grid.

    Also runs the Rao-Blackwellised filter (its default particles) the same way, for comparison.
    """
    rows = []
    settings = [("pf", {"n_particles": particles}), ("pf", {"n_particles": 10 * particles}), ("rbpf", {})]
    for name, options in settings:
        estimator = get_estimator(name, **options)
        for case, cycle in subset:
            data = cycle_data(model, case.preprocessed, case.preprocessed.cycles[cycle])
            rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(case.key, cycle, 7)))
            result = estimator.run(model, data, rng=rng)
            ess = result.diagnostics["ess"] / result.diagnostics["n_particles"]
            i_f, i_xi = model.index("f_h"), model.index("xi_h")
            grid = grid_rows[(grid_rows["record"] == case.key) & (grid_rows["cycle"] == cycle)].iloc[0]
            rows.append({"estimator": f"{name} ({result.diagnostics['n_particles']} particles)",
                         "ess_0": ess[0], "ess_1": ess[1], "ess_median": np.median(ess),
                         "ess_min_particles": ess.min() * result.diagnostics["n_particles"],
                         "resamples": result.diagnostics["resamples"], "samples": len(ess),
                         "f_h_sd_ratio": result.final_std[i_f] / grid["f_h_sd"],
                         "xi_h_sd_ratio": result.final_std[i_xi] / grid["xi_h_sd"],
                         "f_h_vs_grid": abs(result.final_mean[i_f] - grid["f_h"]),
                         "f_h_error": abs(result.final_mean[i_f] - case.person["f_h"]),
                         "f_h_covered": abs(result.final_mean[i_f] - case.person["f_h"]) <= Z90 * result.final_std[i_f]})
            bar.update()
    frame = pd.DataFrame(rows)
    return frame.groupby("estimator", sort=False).agg(
        cycles=("ess_0", "size"), ess_0=("ess_0", "median"), ess_1=("ess_1", "median"),
        ess_median=("ess_median", "median"), ess_min_particles=("ess_min_particles", "median"), resamples=("resamples", "median"), samples=("samples", "median"),
        f_h_sd_ratio=("f_h_sd_ratio", "median"), xi_h_sd_ratio=("xi_h_sd_ratio", "median"),
        f_h_vs_grid=("f_h_vs_grid", "median"), f_h_error=("f_h_error", "median"),
        f_h_covered=("f_h_covered", "mean")).reset_index()


def run_single_pass(subset, estimators, model: SMDModel, truth: pd.DataFrame, seed: int, bar, options,
                    main_grid=None) -> pd.DataFrame:
    """Every estimator with one pass against the grid (also one pass) on the experiment cycles.

    ``main_grid``: the main run's scored grid rows, reused (the grid always makes one pass).
    """
    jobs = [(case.key, only_cycles(case.preprocessed, [cycle])) for case, cycle in subset]
    scored = {}
    for name in estimators:
        if name == "grid" and main_grid is not None:
            scored[name] = subset_rows(main_grid, subset)
            continue
        scored[name] = score(identify(jobs, name, model, seed, bar, options.get(name), max_passes=1), truth)
    summary = pd.DataFrame({name: summary_row(table) for name, table in scored.items()}).T
    distance = distance_from_grid(scored) if "grid" in scored else pd.DataFrame()
    return summary.join(distance.add_prefix("grid_dist_"), how="left")


# ---------------------------------------------------------------------------
# Figure
# ---------------------------------------------------------------------------


def draw_figure(scored: dict, model: SMDModel, path: Path):
    """Estimated vs true ``f_h`` and ``xi_h`` per estimator, with the reported 90 % intervals."""
    names = list(scored)
    fig, axes = plt.subplots(2, len(names), figsize=(3.1 * len(names) + 0.8, 6.9), squeeze=False)
    colours = dict(zip(FB_LEVELS, plt.cm.viridis(np.linspace(0.0, 0.9, len(FB_LEVELS)))))
    true_xi = pd.concat([table["xi_h_true"] for table in scored.values()])
    x_max = min(1.0, max(0.6, float(np.ceil(10 * true_xi.max() + 0.5)) / 10))
    for column, name in enumerate(names):
        table = scored[name][scored[name]["status"] == "ok"]
        for row, parameter in enumerate(("f_h", "xi_h")):
            ax = axes[row, column]
            low, high = model.options[f"{parameter}_range"]
            ax.plot([low, high], [low, high], color="0.4", lw=0.8, ls="--", zorder=1)
            ax.axhline(0.5 * (low + high), color="tab:red", lw=0.7, ls=":", zorder=1)
            for f_b, group in table.groupby("f_b_nominal"):
                # Small jitter along x: the truth is one value per record, shared by its cycles.
                jitter = (group["cycle"] % 5 - 2) * 0.006 * (high - low)
                ax.errorbar(group[f"{parameter}_true"] + jitter, group[parameter], yerr=Z90 * group[f"{parameter}_sd"],
                            fmt="o", ms=3.2, lw=0.7, elinewidth=0.6, alpha=0.75, color=colours[f_b],
                            label=f"f_b {f_b:g} Hz", zorder=2)
            right = high if parameter == "f_h" else x_max
            ax.set_xlim(low - 0.02 * (right - low), right + 0.02 * (right - low))
            ax.set_ylim(low, high)
            ax.grid(True, lw=0.4, alpha=0.5)
            coverage = 100.0 * table[f"cover_{parameter}"].astype(float).mean()
            mae = np.nanmedian(np.abs(table[f"err_{parameter}"]))
            ax.set_title(f"{name}: {LABELS[parameter]}\nmedian |err| {mae:.2f}, 90 % cover {coverage:.0f} %",
                         fontsize=9.5)
            ax.set_xlabel(f"true {LABELS[parameter]} ({UNITS[parameter]})", fontsize=9)
            if column == 0:
                ax.set_ylabel(f"estimate ± 1.645 sd ({UNITS[parameter]})", fontsize=9)
            ax.tick_params(labelsize=8)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(FB_LEVELS), fontsize=9, frameon=False)
    fig.suptitle("Per-cycle estimates against the truth (dashed: estimate = truth; dotted red: prior mean); "
                 f"x axis of xi_h cut at {x_max:g} (every true xi_h is below)", fontsize=10.5)
    fig.tight_layout(rect=(0, 0.04, 1, 0.97))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ---------------------------------------------------------------------------
# Report
# ---------------------------------------------------------------------------


def markdown_table(frame: pd.DataFrame, formats: dict | None = None) -> str:
    """A pipe table; ``formats`` maps columns to format strings (others ``str``); NaN prints as a dash."""
    formats = formats or {}

    def cell(column, value):
        if isinstance(value, float) and np.isnan(value):
            return "–"
        return format(value, formats[column]) if column in formats else str(value)

    lines = ["| " + " | ".join(map(str, frame.columns)) + " |", "|" + "---|" * len(frame.columns)]
    lines += ["| " + " | ".join(cell(c, v) for c, v in zip(frame.columns, row)) + " |"
              for row in frame.itertuples(index=False)]
    return "\n".join(lines)


def markdown_report(title: str, script: str, argv, started: float, body: list, out: Path | None) -> str:
    """A benchmark's markdown report: ``# title``, the command that made it (``script`` with ``argv``, default the
    process's arguments) and its minutes since ``started`` (``time.perf_counter()``), then ``body``'s lines; printed,
    and written to ``out`` when given. Returns the text."""
    arguments = list(sys.argv[1:] if argv is None else argv)
    command = " ".join(["python", f"benchmarks/{script}"] + arguments)
    minutes = (time.perf_counter() - started) / 60
    text = "\n".join([f"# {title}", "", f"`{command}` ({minutes:.1f} min)", "", *body]) + "\n"
    print(text)
    if out:
        Path(out).write_text(text, encoding="utf-8")
    return text


def main_table(summaries: dict, baselines: dict) -> str:
    """The main table: one row per estimator plus the data-free guesses."""
    rows = []
    for name, s in summaries.items():
        rows.append({"estimator": name, **{f"\\|err\\| {LABELS[m]}": s[f"mae_{m}"] for m in METRICS},
                     **{f"cover {LABELS[m]} %": s[f"cov_{m}"] for m in METRICS},
                     "det. f_h %": s["det_f_h"], "det. xi_h %": s["det_xi_h"], "passes": s["passes"],
                     "s/cycle": s["seconds"], "failed": f"{s['failed']}/{s['cycles']}"})
    for label, guess in baselines.items():
        rows.append({"estimator": label, **{f"\\|err\\| {LABELS[m]}": guess[f"mae_{m}"] for m in METRICS
                                            if f"mae_{m}" in guess}})
    frame = pd.DataFrame(rows)
    formats = {c: ".3f" for c in frame.columns if c.startswith("\\|err")}
    formats.update({c: ".0f" for c in frame.columns if c.startswith(("cover", "det"))})
    formats.update({"passes": ".1f", "s/cycle": ".2f"})
    return markdown_table(frame.astype(object).where(frame.notna(), np.nan), formats)


def machine() -> str:
    """Python, library and machine versions, and the repository commit (read only)."""
    try:
        commit = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"], capture_output=True,
                                text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(REPO), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, check=True).stdout.strip()
        commit += " (with uncommitted changes)" if dirty else ""
    except (OSError, subprocess.CalledProcessError):
        commit = "unknown"
    import filterpy
    return (f"Python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}, "
            f"pandas {pd.__version__}, filterpy {filterpy.__version__}, smd_statespace {smd_statespace.__version__} "
            f"(commit {commit}); {platform.system()} {platform.machine()}, {os.cpu_count()} CPUs; "
            f"single-threaded BLAS (OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}), one process")


def preserved_analysis(path: Path) -> str:
    """The hand-written analysis between the markers of an existing report (kept when re-run)."""
    if not path.exists():
        return "_(not written yet)_"
    text = path.read_text(encoding="utf-8")
    if ANALYSIS_BEGIN in text and ANALYSIS_END in text:
        return text.split(ANALYSIS_BEGIN, 1)[1].split(ANALYSIS_END, 1)[0].strip("\n")
    return "_(not written yet)_"


def write_report(path: Path, args, command: str, people: pd.DataFrame, truth: pd.DataFrame, summaries: dict,
                 baselines: dict, correlations: pd.DataFrame, distance: pd.DataFrame, bands: pd.DataFrame, pooled: pd.DataFrame, failures: dict, experiments: dict,
                 figure: Path, model: SMDModel, elapsed: tuple, estimator_wall: dict, variations: dict):
    """Write the Markdown report (keeps an existing hand-written analysis section)."""
    analysis = preserved_analysis(path)
    figure_link = os.path.relpath(figure, path.parent)
    n_matched = int(truth["matched"].sum())
    offsets_ms = 1e3 * truth.loc[truth["matched"], "offset"].abs()
    err = truth[["err_u", "err_u_dot", "err_u_ddot"]].median() * 100
    lines = [
        "# Accuracy benchmark: the estimators against known truth",
        "",
        "Generated by `benchmarks/accuracy.py`; the tables below are rewritten by every run, the analysis "
        "section is hand-written and kept.",
        "",
        "```",
        command,
        "```",
        "",
        f"- Machine: {machine()}.",
        f"- Run time: {elapsed[0] / 60:.1f} min wall clock, {elapsed[1] / 60:.1f} min CPU (the difference is "
        "time spent waiting for a core shared with other processes); per estimator (main table, wall clock): "
        + ", ".join(f"{name} {wall / 60:.1f} min" for name, wall in estimator_wall.items()) + ".",
        "",
        "## Settings",
        "",
        f"- {len(people)} simulated records, `f_b` cycling through {', '.join(f'{f:g}' for f in FB_LEVELS)} Hz "
        f"({len(people) // len(FB_LEVELS)} per level), {args.duration:g} s each at 100 Hz, seed {args.seed}. "
        "People from `sample_population` (Table 2 skew-normals, independent marginals) with `f_h` redrawn into "
        f"the prior range {model.options['f_h_range'][0]:g}-{model.options['f_h_range'][1]:g} Hz "
        f"and every BLF redrawn below {max(abs(v) for v in model.options['coefficient_range']):g} g "
        f"(the largest coefficient of the prior box); BLF4 = {DEFAULT_BLF[N_BLF]:g} g. "
        f"Drawn: `f_h` {people['f_h'].min():.2f}-{people['f_h'].max():.2f} Hz, `xi_h` "
        f"{people['xi_h'].min():.2f}-{people['xi_h'].max():.2f}, BLF1 {people['blf1'].min():.2f}-"
        f"{people['blf1'].max():.2f} g, mass {people['mass'].min():.0f}-{people['mass'].max():.0f} kg.",
        f"- Simulator: default cycle-to-cycle variation (`fb_variation` {variations['fb_variation']:g}, "
        f"`coef_variation` {variations['coef_variation']:g}: amplitudes ±{variations['coef_variation']:.0%}, "
        f"phases ±{variations['coef_variation']:g} rad per cycle), GRF noise {args.noise:.0%} of body weight. "
        f"{int(truth['outside_prior'].sum())} of {len(truth)} cycles have a true coefficient outside the "
        f"±{max(abs(v) for v in model.options['coefficient_range']):g} g prior box (cycle variation on a large BLF).",
        f"- Cycles: `preprocess` defaults (0.5 Hz high-pass, GRF peak to GRF peak, 2 s edge margin); "
        f"{args.cycles_per_record} valid cycles per record, evenly spread, {len(truth)} in all.",
        f"- Truth matching: an identified cycle takes the force cycle (simulator `.cycles`) whose start is "
        f"nearest its own, if closer than {MATCH_TOLERANCE:.0%} of that cycle's period: {n_matched} of "
        f"{len(truth)} matched, start offsets median {offsets_ms.median():.1f} ms, max {offsets_ms.max():.1f} ms. "
        "`f_h`, `xi_h` truth per record, BLF truth per matched force cycle.",
        f"- Pipeline vs simulator states over the selected cycles (relative RMS error, median): "
        f"`u` {err['err_u']:.1f} %, `u'` {err['err_u_dot']:.1f} %, `u''` {err['err_u_ddot']:.1f} %.",
        f"- Model: `{model!r}`, observation noise {model.observation_noise:.0%} of each channel's RMS, process "
        f"noise {model.process_noise:.0%} of each slot's nominal value per step, coefficient prior "
        f"{model.options['coefficient_range']}.",
        f"- Runner: `CycleRunner(max_passes={args.max_passes}, tolerance={args.tolerance:g})`; estimator "
        f"options: pf {args.particles} particles, others at their defaults. A parameter is 'determined' when its "
        f"posterior sd is below {DETERMINED_FRACTION:g} of its prior sd (`f_h`: "
        f"{DETERMINED_FRACTION * np.diff(model.options['f_h_range'])[0] / np.sqrt(12):.3f} Hz, `xi_h`: "
        f"{DETERMINED_FRACTION * np.diff(model.options['xi_h_range'])[0] / np.sqrt(12):.3f}).",
        "",
        "## Main table",
        "",
        "Median absolute error against the truth, coverage of the reported ±1.645 sd interval (90 % if "
        "calibrated), cycles flagged 'determined', mean passes, seconds per cycle, failed cycles. "
        "Two data-free guesses for scale: 'prior mean' is the centre of the estimators' prior (2.5 Hz, 0.5) "
        "for every cycle; 'population median at f_b' is the median of the simulated population at the "
        "record's bouncing frequency (what Table 2 alone predicts; it knows the distribution the truth was "
        "drawn from, so it is an optimistic yardstick).",
        "",
        main_table(summaries, baselines),
        "",
        "Median posterior sd reported: " + ", ".join(
            f"{name} `f_h` {s['median_sd_f_h']:.3f} Hz / `xi_h` {s['median_sd_xi_h']:.3f}" for name, s in summaries.items())
        + ".",
        "",
    ]
    lines += [
        "### Correlation with the truth",
        "",
        "Pearson correlation of per-cycle estimates with the truth over all cycles, and the mean of the "
        "correlations within each `f_b` level (the population's `f_h` rises with `f_b`, so the overall value "
        "partly reflects `f_b`; within a level it does not).",
        "",
        markdown_table(correlations.reset_index().rename(columns={"index": "estimator"}),
                       {c: ".2f" for c in correlations.columns}),
        "",
    ]
    if len(distance):
        lines += [
            "### Distance from the grid reference",
            "",
            "Per cycle, against the grid's posterior mean and sd of the same cycle (median over cycles). "
            "The grid is the exact posterior under the model's own assumptions (one pass).",
            "",
            markdown_table(distance.reset_index().rename(columns={
                "index": "estimator", "f_h": "\\|f_h − grid\\| (Hz)", "f_h_sd": "sd f_h / grid sd",
                "xi_h": "\\|xi_h − grid\\|", "xi_h_sd": "sd xi_h / grid sd"}),
                {"\\|f_h − grid\\| (Hz)": ".3f", "sd f_h / grid sd": ".2f", "\\|xi_h − grid\\|": ".3f",
                 "sd xi_h / grid sd": ".2f"}),
            "",
        ]
    lines += [
        "### f_h error by bouncing frequency",
        "",
        "Median |f_h error| (Hz) per nominal bouncing frequency.",
        "",
        markdown_table(bands, {c: ".3f" for c in list(summaries) + ["prior mean"]}),
        "",
        "'prior mean': the error of guessing 2.5 Hz. The top two levels have their true `f_h` crowded against "
        "the prior's upper edge (Table 2 puts most of them above 4 Hz; they were redrawn into 1-4 Hz).",
        "",
        f"![estimated vs true f_h and xi_h]({figure_link})",
        "",
    ]
    if pooled is not None:
        per_cycle = summaries["grid"]
        frame = pd.DataFrame([
            {"estimate": "grid, per cycle (main table)", "\\|err\\| f_h": per_cycle["mae_f_h"],
             "cover f_h %": per_cycle["cov_f_h"], "sd f_h": per_cycle["median_sd_f_h"],
             "\\|err\\| xi_h": per_cycle["mae_xi_h"], "cover xi_h %": per_cycle["cov_xi_h"],
             "sd xi_h": per_cycle["median_sd_xi_h"]},
            {"estimate": f"grid, {args.cycles_per_record} cycles of a record pooled",
             "\\|err\\| f_h": np.median(np.abs(pooled["err_f_h"])), "cover f_h %": 100 * pooled["cover_f_h"].mean(),
             "sd f_h": pooled["f_h_sd"].median(), "\\|err\\| xi_h": np.median(np.abs(pooled["err_xi_h"])),
             "cover xi_h %": 100 * pooled["cover_xi_h"].mean(), "sd xi_h": pooled["xi_h_sd"].median()},
            {"estimate": "population median at f_b (no data)", "\\|err\\| f_h": baselines[
                "population median at f_b (no data)"]["mae_f_h"], "\\|err\\| xi_h": baselines[
                "population median at f_b (no data)"]["mae_xi_h"]},
        ])
        lines += [
            "### Pooling the cycles of a record",
            "",
            f"The grid reference's per-cycle posteriors multiplied over the {args.cycles_per_record} identified "
            "cycles of each record (one posterior of `f_h`, `xi_h` per person; valid because the simulated "
            "person's `f_h`, `xi_h` do not change between cycles). Medians over the "
            f"{len(pooled)} records; errors in Hz and -.",
            "",
            markdown_table(frame.astype(object).where(frame.notna(), np.nan),
                           {"\\|err\\| f_h": ".3f", "cover f_h %": ".0f", "sd f_h": ".3f", "\\|err\\| xi_h": ".3f",
                            "cover xi_h %": ".0f", "sd xi_h": ".3f"}),
            "",
        ]
    if any(failures.values()):
        lines += ["Failed cycles:", ""]
        lines += [f"- {name}: {reason} ({count}×)" for name, reasons in failures.items()
                  for reason, count in reasons.items()]
        lines.append("")
    if experiments:
        lines += ["## Experiments", ""]
    if "ladder" in experiments:
        frame = experiments["ladder"]
        lines += [
            "### Ladder: the grid reference as one thing at a time is made ideal",
            "",
            f"The grid reference (exact under the model) on {experiments['subset_size']} cycles (the first "
            "selected cycle of successive records, every `f_b` level). 'exact states' feeds the simulator's "
            "`u, u', u''` instead of the pipeline's; 'force cycles' cuts the cycles at the true force-cycle "
            "boundaries (samples strictly inside) with the true `f_b`, instead of GRF peak to peak; the noise "
            "columns are the model's assumed observation and process noise.",
            "",
            markdown_table(frame.rename(columns={
                "mae_f_h": "\\|err\\| f_h", "cov_f_h": "cover f_h %", "median_sd_f_h": "sd f_h",
                "det_f_h": "det. f_h %", "mae_xi_h": "\\|err\\| xi_h", "cov_xi_h": "cover xi_h %",
                "median_sd_xi_h": "sd xi_h", "det_xi_h": "det. xi_h %"}),
                {"\\|err\\| f_h": ".3f", "cover f_h %": ".0f", "sd f_h": ".3f", "det. f_h %": ".0f",
                 "\\|err\\| xi_h": ".3f", "cover xi_h %": ".0f", "sd xi_h": ".3f", "det. xi_h %": ".0f"}),
            "",
        ]
    if "pf-ess" in experiments:
        frame = experiments["pf-ess"]
        lines += [
            "### Particle filter: effective sample size in one pass from the prior",
            "",
            f"Same {experiments['subset_size']} cycles, one pass each, medians over cycles. ESS as a fraction of "
            "the particles after the first (`ess_0`) and second (`ess_1`) observation and its median over the "
            "pass; its minimum over the pass in particles; posterior sd of `f_h`, `xi_h` over the grid's; |f_h − grid f_h| and |f_h error| (Hz); "
            "fraction of cycles whose 90 % interval covers the true `f_h`.",
            "",
            markdown_table(frame, {"ess_0": ".3f", "ess_1": ".3f", "ess_min_particles": ".1f", "ess_median": ".3f",
                                   "resamples": ".0f", "samples": ".0f", "f_h_sd_ratio": ".2f",
                                   "xi_h_sd_ratio": ".2f", "f_h_vs_grid": ".3f", "f_h_error": ".3f",
                                   "f_h_covered": ".2f"}),
            "",
        ]
    if "single-pass" in experiments:
        frame = experiments["single-pass"].reset_index().rename(columns={"index": "estimator"})
        keep = ["estimator", "mae_f_h", "cov_f_h", "median_sd_f_h", "mae_xi_h", "cov_xi_h", "median_sd_xi_h",
                "mae_blf_1", "cov_blf_1", "seconds"] + [c for c in frame.columns if c.startswith("grid_dist_")]
        lines += [
            "### One pass only (no repeated passes)",
            "",
            f"Same {experiments['subset_size']} cycles, `max_passes=1` for every estimator. `grid_dist_*`: "
            "median |estimate − grid| and median sd / grid sd.",
            "",
            markdown_table(frame[keep], {c: ".3f" for c in keep if c.startswith(("mae", "median", "grid_dist"))}
                           | {c: ".0f" for c in keep if c.startswith("cov")} | {"seconds": ".2f"}),
            "",
        ]
    lines += ["## Analysis", "", ANALYSIS_BEGIN, analysis, ANALYSIS_END, ""]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines), encoding="utf-8")


# ---------------------------------------------------------------------------
# Command line
# ---------------------------------------------------------------------------


def parse_args(argv=None):
    """Command-line options (see the module docstring)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--records", type=int, default=15, help="simulated records (people)")
    parser.add_argument("--duration", type=float, default=9.0, help="record length (s)")
    parser.add_argument("--cycles-per-record", type=int, default=4, help="valid cycles identified per record")
    parser.add_argument("--estimators", default=",".join(DEFAULT_ESTIMATORS), help="comma-separated estimator names")
    parser.add_argument("--particles", type=int, default=5000, help="particles of the article's PF ('pf')")
    parser.add_argument("--max-passes", type=int, default=8, help="largest number of passes per cycle")
    parser.add_argument("--tolerance", type=float, default=0.05, help="relative change that ends the passes")
    parser.add_argument("--noise", type=float, default=0.01, help="GRF noise, fraction of body weight")
    parser.add_argument("--observation-noise", type=float, default=None, help="model observation noise (default: the model's)")
    parser.add_argument("--process-noise", type=float, default=None, help="model process noise (default: the model's)")
    parser.add_argument("--discretisation", default=None, choices=DISCRETISATIONS,
                        help="model discretisation (default: the model's)")
    parser.add_argument("--experiment", default="all",
                        help=f"comma-separated experiments from {', '.join(EXPERIMENTS)}, or 'all' or 'none'")
    parser.add_argument("--experiment-cycles", type=int, default=10, help="cycles used by each experiment")
    parser.add_argument("--seed", type=int, default=2019, help="root of every random number")
    parser.add_argument("--out", type=Path, default=REPO / "docs" / "benchmarks.md", help="Markdown report")
    parser.add_argument("--figure", type=Path, default=REPO / "docs" / "figures" / "accuracy.png", help="PNG figure")
    parser.add_argument("--cycles-csv", type=Path, default=None, help="also write every scored cycle row here")
    parser.add_argument("--quick", action="store_true",
                        help="5 records x 1 cycle, 3 experiment cycles: to time a run, not to judge")
    args = parser.parse_args(argv)
    if args.quick:
        args.records, args.cycles_per_record, args.experiment_cycles = 5, 1, 3
    args.estimators = [name.strip() for name in args.estimators.split(",") if name.strip()]
    unknown = [name for name in args.estimators if name not in ESTIMATORS]
    if unknown:
        parser.error(f"unknown estimator(s) {', '.join(unknown)}; choose from {', '.join(sorted(ESTIMATORS))}")
    chosen = {"all": list(EXPERIMENTS), "none": []}.get(args.experiment, args.experiment.split(","))
    bad = [name for name in chosen if name not in EXPERIMENTS]
    if bad:
        parser.error(f"unknown experiment(s) {', '.join(bad)}; choose from {', '.join(EXPERIMENTS)}, all, none")
    args.experiments = chosen
    return args


def main(argv=None):
    """Run the benchmark and write the report and figure."""
    args = parse_args(argv)
    given = sys.argv[1:] if argv is None else list(argv)
    command = " ".join(["python benchmarks/accuracy.py"] + ([shlex.join(given)] if given else []))
    started, cpu_started = time.perf_counter(), time.process_time()
    changes = {k: v for k, v in (("observation_noise", args.observation_noise), ("process_noise", args.process_noise),
                                 ("discretisation", args.discretisation)) if v is not None}
    model = SMDModel(**changes)
    root = np.random.SeedSequence(args.seed)
    people_seeds, record_seeds, runner_seed, population_seed = root.spawn(4)
    runner_seed = int(runner_seed.generate_state(1)[0])

    people = draw_people(args.records, people_seeds.spawn(args.records), model)
    cases = build_cases(people, record_seeds.spawn(args.records), args.duration, args.cycles_per_record, model,
                        args.noise)
    truth = truth_table(cases)
    variations = cases[0].synthetic.truth["variations"]
    subset = experiment_subset(cases, args.experiment_cycles)

    per_estimator = {"pf": {"n_particles": args.particles}}
    total = len(truth) * len(args.estimators)
    reuse = "grid" in args.estimators
    if "ladder" in args.experiments:
        total += len(subset) * (len(ladder_variants(model)) - reuse)
    if "pf-ess" in args.experiments:
        total += 3 * len(subset) + (0 if reuse else len(subset))
    if "single-pass" in args.experiments:
        total += len(subset) * (len(set(args.estimators) | {"grid"}) - reuse)
    bar = tqdm(total=total, desc="benchmark", unit="cycle", mininterval=1.0 if sys.stderr.isatty() else 30.0)

    jobs = [(case.key, case.preprocessed) for case in cases]
    scored, wall, grid_results = {}, {}, {}
    for name in args.estimators:
        bar.set_postfix_str(name)
        rows = identify(jobs, name, model, runner_seed, bar, per_estimator.get(name), args.max_passes, args.tolerance,
                        results=grid_results if name == "grid" else None)
        wall[name] = rows.attrs["wall"]
        scored[name] = score(rows, truth)
    summaries = {name: summary_row(table) for name, table in scored.items()}
    failures = {name: table.loc[table["status"] == "failed", "reason"].str.replace(r"cycle \d+: ", "", regex=True)
                .str.replace(r"sample \d+.*", "sample …", regex=True).value_counts().to_dict()
                for name, table in scored.items()}
    distance = distance_from_grid(scored) if "grid" in scored else pd.DataFrame()
    bands = band_breakdown(scored, truth, model)
    pooled = pooled_grid(grid_results, people) if grid_results else None

    experiments = {"subset_size": len(subset)} if args.experiments else {}
    if "ladder" in args.experiments:
        bar.set_postfix_str("ladder")
        experiments["ladder"] = run_ladder(subset, model, truth, runner_seed, bar, scored.get("grid"))
    if "pf-ess" in args.experiments:
        bar.set_postfix_str("pf-ess")
        grid_rows = scored["grid"] if "grid" in scored else score(identify(
            [(case.key, only_cycles(case.preprocessed, [cycle])) for case, cycle in subset], "grid", model,
            runner_seed, bar), truth)
        experiments["pf-ess"] = run_pf_ess(subset, model, runner_seed, args.particles, bar, grid_rows)
    if "single-pass" in args.experiments:
        bar.set_postfix_str("single pass")
        names = list(dict.fromkeys(args.estimators + ["grid"]))
        experiments["single-pass"] = run_single_pass(subset, names, model, truth, runner_seed, bar, per_estimator,
                                                     scored.get("grid"))
    bar.close()

    draw_figure(scored, model, args.figure)
    if args.cycles_csv is not None:
        pd.concat(scored.values(), ignore_index=True).to_csv(args.cycles_csv, index=False)
    baselines = {"prior mean (no data)": prior_mean_row(truth, model),
                 "population median at f_b (no data)": population_median_row(truth, model, population_seed)}
    write_report(args.out, args, command, people, truth, summaries, baselines, correlation_table(scored), distance,
                 bands, pooled,
                 failures, experiments, args.figure, model, (time.perf_counter() - started,
                                                             time.process_time() - cpu_started), wall, variations)
    print(f"wrote {args.out} and {args.figure} in {(time.perf_counter() - started) / 60:.1f} min")


if __name__ == "__main__":
    main()
