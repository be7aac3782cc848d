"""How many fits the record-level person needs: each fit's estimate against the answer (issue 23).

``identify_person`` (its defaults: ``variation="auto"``, ``timing="model"``) fits each variation
model of :data:`~smd_statespace.person.fit.AUTO_VARIATIONS` at the first cycle timing, then
with a phase template at the cycle starts it re-places from its own fit
(:data:`~smd_statespace.person.search.TIMING_ITERATIONS` times), keeps its best fit and refits
it to full precision; the lowest AIC wins. This script runs it on simulated records
(``person_accuracy.py``'s people and generators) with every :func:`~smd_statespace.person.search.fit_model`
call and every re-placement of the cycle starts recorded (a wrapper for the run), and asks
which of those fits the answer needs:

* **stop re-placing early**: the estimate of ``f_h`` and ``xi_h`` after each re-placement,
  against the last one, in units of the answer's standard error (the raw one, from the
  observed information), beside how far that re-placement moved the cycle starts (RMS, %
  of the median period) and what it gained in log-likelihood: a stop rule on either is
  safe where the estimates it would keep are within a tenth of their sd;
* **choose before the final fits**: whether the AIC of the models' best quick fits (before
  the full-precision refits) chooses as the AIC after them; where it does, only the winner
  needs its final fit;
* the seconds of each kind of fit.

Rows (one per ``fit_model`` call, re-placement and answer) go to a JSON-lines journal that
a rerun resumes; ``--report`` reads it back and prints the tables.

::

    OPENBLAS_NUM_THREADS=1 python benchmarks/person_fits.py --records 8 --seed 77 --jobs 2 \\
        --journal benchmarks/results/person_fits_seed77.jsonl
"""

from __future__ import annotations

import os

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from smd_statespace.person import fit as person_fit  # noqa: E402
from smd_statespace.person import search  # noqa: E402
from smd_statespace.person.calibration import CALIBRATION  # noqa: E402
from smd_statespace.person import identify_person  # noqa: E402

import person_accuracy  # noqa: E402  (beside this script: its people and generators)

GENERATORS = ("jumps", "smooth", "coefficients", "pulses", "tempo")
TENTH = 0.1
"""A stop rule is safe where the estimates it keeps are within this many sds of the answer (the issue's bar)."""


def _rms_shift(old, new) -> float:
    """RMS move of the inner cycle starts, in % of the median period."""
    old, new = np.asarray(old.boundaries), np.asarray(new.boundaries)
    if old.size != new.size:
        return float("nan")
    return float(100.0 * np.sqrt(np.mean((new[1:-1] - old[1:-1]) ** 2)) / np.median(np.diff(old)))


def run_record(task) -> list:
    """Identify one record with every fit and re-placement recorded; rows as dicts. ``task``: ``(person,
    generator, quick_gain)``, ``quick_gain`` None for the library's :data:`~smd_statespace.person.search.QUICK_GAIN`
    (an experiment's stop rule of the intermediate fits otherwise)."""
    person, generator, quick_gain = task
    if quick_gain is not None:
        search.QUICK_GAIN = quick_gain
    key = {"generator": generator, "record": int(person["record"])}
    try:
        record = person_accuracy.simulate(person, generator).record
    except Exception as exc:  # a simulation the simulator refuses (the person would leave the plate)
        return [{**key, "kind": "failed", "error": f"{type(exc).__name__}: {exc}"}]
    rows = []
    fit_model, corrected_timing = search.fit_model, search.corrected_timing

    def recorded_fit(model, start=None, quick=False, method="scoring"):
        began = time.perf_counter()
        out = fit_model(model, start, quick, method)
        rows.append({**key, "kind": "fit", "variation": model.variation,
                     "template": model.phase_template is not None, "quick": bool(quick),
                     "loglike": float(out["loglike"]), "n_params": len(out["params"]),
                     "f_h": float(out["params"][0]), "xi_h": float(out["params"][1]),
                     "on_bound": bool(model.person_at_bound(out["params"])), "converged": bool(out["converged"]),
                     "evaluations": int(out["n_evaluations"]), "seconds": time.perf_counter() - began})
        return out

    def recorded_timing(model, params):
        began = time.perf_counter()
        new = corrected_timing(model, params)
        rows.append({**key, "kind": "timing", "variation": model.variation, "shift": _rms_shift(model.timing, new),
                     "seconds": time.perf_counter() - began})
        return new

    # identify_person makes the first fits (person.fit), the search the others (person.search): both recorded
    person_fit.fit_model = search.fit_model = recorded_fit
    search.corrected_timing = recorded_timing
    began = time.perf_counter()
    try:
        result = identify_person(record)
    except Exception as exc:  # a refusal is an answer too: recorded, the run goes on
        return rows + [{**key, "kind": "failed", "error": f"{type(exc).__name__}: {exc}"}]
    finally:
        person_fit.fit_model = search.fit_model = fit_model
        search.corrected_timing = corrected_timing
    seconds = time.perf_counter() - began
    # the sds before the calibration's factor (stricter than the reported ones)
    raw = result.se[:2] / np.array([CALIBRATION[result.model.variation][n] for n in ("f_h", "xi_h")])
    rows.append({**key, "kind": "answer", "variation": result.model.variation, "f_h": result.f_h,
                 "xi_h": result.xi_h, "f_h_se": float(raw[0]), "xi_h_se": float(raw[1]),
                 "f_h_true": float(person["f_h"]), "xi_h_true": float(person["xi_h"]), "seconds": seconds})
    return rows


def journal_rows(path: Path) -> list:
    if path is None or not path.is_file():
        return []
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def fits_per_model(rows: pd.DataFrame) -> pd.DataFrame:
    """Per record and variation model: its template fits in order (iteration 0..), with the re-placement that
    preceded each (iteration 0: none), and its final fit."""
    out = []
    for (generator, record), group in rows.groupby(["generator", "record"], sort=False):
        for variation, own in group[group["kind"].isin(["fit", "timing"])].groupby("variation", sort=False):
            iteration, shift = -1, np.nan
            for row in own.itertuples():
                if row.kind == "timing":
                    shift = row.shift
                    continue
                stage = "first" if not row.template else ("final" if not row.quick else "template")
                if stage == "template":
                    iteration += 1
                out.append({"generator": generator, "record": record, "variation": variation, "stage": stage,
                            "iteration": iteration if stage == "template" else np.nan,
                            "shift": shift if stage == "template" and iteration > 0 else np.nan,
                            "loglike": row.loglike, "n_params": row.n_params, "f_h": row.f_h, "xi_h": row.xi_h,
                            "on_bound": row.on_bound, "converged": row.converged, "seconds": row.seconds,
                            "evaluations": row.evaluations})
    return pd.DataFrame(out)


def _winner(best: pd.DataFrame) -> str:
    """The variation model ``identify_person`` would choose among these fits (one per model): lowest AIC among
    those not on a search bound (all, if every one is)."""
    ok = ~best["on_bound"] & best["converged"]
    eligible = best[ok] if ok.any() else best
    return eligible.loc[(2 * eligible["n_params"] - 2 * eligible["loglike"]).idxmin(), "variation"]


def early_stop_table(fits: pd.DataFrame, answers: pd.DataFrame) -> list:
    """Markdown: stopping the re-placements after iteration ``i``: the chosen model's best quick fit so far
    against the one of all iterations (in sds of the answer), the re-placement's move and gain, and whether the
    models' best fits so far choose the same variation model."""
    template = fits[fits["stage"] == "template"]
    per_record = {}
    for key, group in template.groupby(["generator", "record"]):
        if key not in answers.index:
            continue
        answer = answers.loc[key]
        mine = group[group["variation"] == answer["variation"]].sort_values("iteration").reset_index(drop=True)
        last = mine.loc[mine["loglike"].idxmax()]
        entries = []
        for i in range(len(mine)):
            so_far = group[group["iteration"] <= i]
            best = so_far.loc[so_far.groupby("variation")["loglike"].idxmax()]
            pick = mine.loc[mine.loc[:i, "loglike"].idxmax()]
            entries.append({"shift": mine.loc[i, "shift"],
                            "gain": mine.loc[i, "loglike"] - mine.loc[i - 1, "loglike"] if i else np.nan,
                            "df": abs(pick.f_h - last.f_h) / answer.f_h_se,
                            "dx": abs(pick.xi_h - last.xi_h) / answer.xi_h_se,
                            "same choice": _winner(best) == answer["variation"]})
        per_record[key] = entries
    lines = ["| stop after re-placement | records | RMS move of the starts by it (% of period), median [max] "
             "| log-likelihood it gained, median [max] | f_h: best fit so far - best of all, max (sd) "
             "| xi_h: same (sd) | records within 0.1 sd of both | records choosing another variation model |",
             "|---|---|---|---|---|---|---|---|"]
    iterations = max((len(v) for v in per_record.values()), default=0)
    for i in range(iterations - 1):
        at = pd.DataFrame([v[i] for v in per_record.values() if len(v) > i])
        within = int(((at["df"] <= TENTH) & (at["dx"] <= TENTH)).sum())
        moved = "-" if i == 0 else f"{at['shift'].median():.2f} [{at['shift'].max():.2f}]"
        gained = "-" if i == 0 else f"{at['gain'].median():.2f} [{at['gain'].max():.1f}]"
        lines.append(f"| {i} | {len(at)} | {moved} | {gained} | {at['df'].max():.2f} | {at['dx'].max():.2f} "
                     f"| {within}/{len(at)} | {int((~at['same choice']).sum())} |")
    return lines


def choice_table(fits: pd.DataFrame, answers: pd.DataFrame) -> list:
    """Markdown: does the AIC of each model's best quick template fit choose as the one after the final fits?"""
    same, differ, saved, total = 0, [], 0.0, 0.0
    for key, group in fits.groupby(["generator", "record"]):
        if key not in answers.index:
            continue
        quick = group[group["stage"] == "template"]
        final = group[group["stage"] == "final"]
        total += group["seconds"].sum()

        quick_choice = _winner(quick.loc[quick.groupby("variation")["loglike"].idxmax()])
        final_choice = _winner(final)
        if quick_choice == final_choice:
            same += 1
            saved += final.loc[final["variation"] != final_choice, "seconds"].sum()
        else:
            differ.append(f"{key[0]} {key[1]}")
    return [f"- The AIC of the best quick fits chose as after the final fits on {same} of {same + len(differ)} "
            f"records" + (f" (not on: {', '.join(differ)})" if differ else "") + f"; the losers' final fits took "
            f"{saved:.1f} s of the {total:.1f} s of all fits."]


def seconds_table(fits: pd.DataFrame, rows: pd.DataFrame) -> list:
    timing = rows[rows["kind"] == "timing"]
    answers = rows[rows["kind"] == "answer"]
    lines = ["| part | s per record, median | share of identify_person |", "|---|---|---|"]
    total = answers.groupby(["generator", "record"])["seconds"].sum()
    for label, frame in (("first fits (coarse start + quick search)", fits[fits["stage"] == "first"]),
                         ("template fits (quick)", fits[fits["stage"] == "template"]),
                         ("final fits (full precision)", fits[fits["stage"] == "final"]),
                         ("re-placements of the cycle starts", timing)):
        per = frame.groupby(["generator", "record"])["seconds"].sum().reindex(total.index).fillna(0.0)
        lines.append(f"| {label} | {per.median():.2f} | {100 * per.sum() / total.sum():.0f} % |")
    lines.append(f"| identify_person | {total.median():.2f} | 100 % |")
    return lines


def report(rows: list) -> str:
    frame = pd.DataFrame(rows)
    failed = frame[frame["kind"] == "failed"]
    answers = frame[frame["kind"] == "answer"].set_index(["generator", "record"])
    fits = fits_per_model(frame)
    out = [f"{len(answers)} records identified, {len(failed)} failed "
           + (f"({'; '.join(sorted(set(failed['error'].str.slice(0, 80))))})" if len(failed) else ""), "",
           *seconds_table(fits, frame), "", *early_stop_table(fits, answers), "", *choice_table(fits, answers)]
    return "\n".join(out)


def against_table(rows: list, before: list) -> list:
    """Markdown: the answers of this run against another journal's on the same records (a change's before)."""
    now = pd.DataFrame(rows)
    old = pd.DataFrame(before)
    now, old = (f[f["kind"] == "answer"].set_index(["generator", "record"]) for f in (now, old))
    both = now.index.intersection(old.index)
    if both.empty:
        return ["(no record in both journals)"]
    now, old = now.loc[both], old.loc[both]
    df = ((now["f_h"] - old["f_h"]) / old["f_h_se"]).abs()
    dx = ((now["xi_h"] - old["xi_h"]) / old["xi_h_se"]).abs()
    return [f"Against the other journal, {len(both)} records: variation model chosen the same on "
            f"{int((now['variation'] == old['variation']).sum())}; |f_h| moved by at most {df.max():.3f} sd "
            f"(median {df.median():.3f}), |xi_h| by at most {dx.max():.3f} sd; records within {TENTH} sd of both: "
            f"{int(((df <= TENTH) & (dx <= TENTH)).sum())}; seconds per record, median "
            f"{old['seconds'].median():.2f} -> {now['seconds'].median():.2f} (total {old['seconds'].sum():.0f} -> "
            f"{now['seconds'].sum():.0f} s)."]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=8, help="people per generator (default 8)")
    parser.add_argument("--seed", type=int, default=77, help="SeedSequence root of the people (default 77)")
    parser.add_argument("--generators", default=",".join(GENERATORS))
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--journal", type=Path, default=None, help="JSON lines of the rows; a rerun resumes it")
    parser.add_argument("--quick-gain", type=float, default=None, metavar="GAIN",
                        help="an experiment: the intermediate fits' stop rule (log-likelihood gained by the last "
                             f"step; the library's: {search.QUICK_GAIN:g})")
    parser.add_argument("--report", action="store_true", help="only print the tables of --journal")
    parser.add_argument("--against", type=Path, default=None, metavar="JOURNAL",
                        help="another run's journal (e.g. before a change): compare the answers on the same records")
    args = parser.parse_args(argv)
    generators = [g.strip() for g in args.generators.split(",") if g.strip()]
    unknown = sorted(set(generators) - set(person_accuracy.GENERATORS))
    if unknown:
        parser.error(f"--generators: {', '.join(unknown)} not one of {', '.join(person_accuracy.GENERATORS)}")
    rows = journal_rows(args.journal)
    if not args.report:
        done = {(r["generator"], r["record"]) for r in rows if r["kind"] in ("answer", "failed")}
        people = person_accuracy.draw_people(args.records, args.seed)
        tasks = [(person, g, args.quick_gain) for g in generators for _, person in people.iterrows()
                 if (g, int(person["record"])) not in done]
        with ProcessPoolExecutor(args.jobs) as pool:
            for k, new in enumerate(pool.map(run_record, tasks), start=1):
                rows += new
                if args.journal is not None:
                    with args.journal.open("a") as handle:
                        handle.writelines(json.dumps(r) + "\n" for r in new)
                print(f"{k}/{len(tasks)} {tasks[k - 1][1]} {int(tasks[k - 1][0]['record'])}", file=sys.stderr)
    print(report(rows))
    if args.against is not None:
        print("\n" + "\n".join(against_table(rows, journal_rows(args.against))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
