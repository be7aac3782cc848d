"""``smd-statespace compare``: several estimators side by side on the same cycles of one record."""

from __future__ import annotations

import pandas as pd

from ..errors import OptionError
from ..estimators import ESTIMATORS
from .common import (add_model_arguments, add_rate_argument, add_record_arguments, add_run_arguments, build_model,
                     load_truth, out_dir, prepare_record, rate_of, reading_options, truth_values)
from ..identify.plausibility import plausible_cycles
from .identify import identify

COMPARED = ("f_h", "xi_h", "blf_1", "blf_2", "blf_3")

INTERVALS = ("f_h", "xi_h")
"""Parameters whose interval and verdict (determined or not) every row shows."""

DEFAULT_ESTIMATORS = "record,ekf,grid"
"""What docs/benchmarks.md recommends: the person from the whole record, the cheapest per-cycle Kalman
filter (the UKF costs 7 times more for the same accuracy) and the exact grid, the only per-cycle
estimator whose intervals cover; the article's pf on request (its intervals cover 3 %)."""

RECORD_COVERAGE = 97
"""Coverage (%) of the record-level model's calibrated 90 % interval of ``f_h`` on fresh records, with the
shipped calibration (:data:`~smd_statespace.person.calibration.CALIBRATION`, the default covariance
:data:`~smd_statespace.person.search.WIDER_SANDWICH`): 150 of 154 records of seed 2029,
16 people per generator of force variation (five) and noise level (0.3 and 1 % BW), 6 failed fits left out
(docs/person-calibration.md, "On fresh records"; rows in ``benchmarks/results/person_accuracy_seed2029*.csv``,
which ``tests/test_person.py`` recomputes it from)."""

MEASURED_COVERAGE = {"pf": 3, "rbpf": 33, "ukf": 72, "ekf": 67, "grid": 97, "record": RECORD_COVERAGE}
"""Coverage (%) of the nominal 90 % interval of ``f_h`` measured on simulated records: per-cycle
estimators in docs/benchmarks.md (60 cycles, seed 2019), the record-level model in
docs/person-calibration.md (:data:`RECORD_COVERAGE`)."""

COVERAGE_OK = 85
"""Below this measured coverage (%) of a 90 % interval, a row is marked over-confident."""


def add_compare(subparsers):
    """Declare ``smd-statespace compare``."""
    parser = subparsers.add_parser(
        "compare",
        help="run several estimators on the same cycles and compare them",
        description=("Identify the same record with each estimator and print, per estimator, its answer for the "
                     "record in one vocabulary: the value of each parameter, the interval of f_h and xi_h and "
                     "whether the record determines them (per-cycle estimators: the cycles' median and the range "
                     "of the central 90 % of them, never determined), the share of cycles "
                     "that determine them on their own and the run time; with --truth also the answer's absolute "
                     "error. Writes DIR/compare_table.csv, DIR/compare.csv (every cycle) and DIR/compare.png."),
    )
    add_record_arguments(parser)
    parser.add_argument("--estimators", default=DEFAULT_ESTIMATORS, metavar="LIST",
                        help=f"comma-separated estimators among record,{','.join(sorted(ESTIMATORS))} (default "
                             f"{DEFAULT_ESTIMATORS}, as docs/benchmarks.md recommends; record: one f_h, xi_h for the "
                             "whole record; pf: the article's particle filter)")
    parser.add_argument("--truth", metavar="JSON", help="truth file of a synthetic record (simulate writes one)")
    add_model_arguments(parser)
    add_run_arguments(parser)
    add_rate_argument(parser)
    return parser


def parse_estimators(text: str) -> list:
    """Estimator names from ``--estimators``, checked."""
    names = [name.strip() for name in text.split(",") if name.strip()]
    unknown = [name for name in names if name not in ESTIMATORS and name != "record"]
    if unknown or not names:
        raise OptionError(f"--estimators {text!r}: unknown {unknown[0]!r}; choose among record, "
                          f"{', '.join(sorted(ESTIMATORS))}" if unknown else "--estimators: give at least one estimator")
    if len(set(names)) != len(names):
        raise OptionError(f"--estimators {text!r}: an estimator is listed twice")
    return names


def answer_row(estimator: str, answer: dict, seconds: float, truth: dict | None = None,
               table: pd.DataFrame | None = None) -> dict:
    """One estimator's answer for the record as a row of the comparison, in one vocabulary for all.

    ``answer`` holds the flat keys of the person's ``to_dict`` (``f_h``, ``f_h_low``, ``f_h_high``,
    ``f_h_determined``, ...; :func:`~smd_statespace.identify.pooled.pooled_row` gives them for a table of
    cycles: their median and central range, never determined). ``table``: the per-cycle results the answer
    was made from (its cycles counted, and the share of cycles that determine ``f_h`` and ``xi_h`` on their
    own); ``None`` for the record-level person.
    """
    row = {"estimator": estimator, "cycles": answer["n_cycles"], "implausible": 0, "failed": 0}
    for parameter in COMPARED:  # an estimator without a plausible cycle has no answer: NaN, not determined
        for key in ("", "_low", "_high"):
            row[f"{parameter}{key}"] = answer.get(f"{parameter}{key}", float("nan"))
        row[f"{parameter}_determined"] = bool(answer.get(f"{parameter}_determined", False))
    ok = None if table is None else plausible_cycles(table)
    if table is not None:
        row["implausible"] = int((table["status"] == "ok").sum()) - len(ok)
        row["failed"] = int((table["status"] == "failed").sum())
    for parameter in INTERVALS:  # one cycle at a time: the share that determine it (the person: all or none)
        row[f"{parameter}_det_%"] = 100.0 * (ok[f"{parameter}_determined"].mean() if ok is not None
                                             else row[f"{parameter}_determined"])
    for parameter in COMPARED:
        if truth and parameter in truth:
            row[f"|err| {parameter}"] = abs(row[parameter] - truth[parameter])
    row["s/cycle"] = seconds / max(row["cycles"], 1)
    row["f_h_cover_%"] = MEASURED_COVERAGE.get(estimator, float("nan"))
    return row


def comparison_table(tables: dict, seconds: dict, truth: dict | None = None, level: float = 0.9) -> pd.DataFrame:
    """One row per per-cycle estimator (:func:`answer_row`): its cycles' answer for the record
    (:func:`~smd_statespace.identify.pooled.pool_cycles`), the errors of that answer, time per cycle."""
    from ..identify.pooled import pooled_row

    rows = [answer_row(name, pooled_row(table, level, COMPARED), seconds[name], truth, table)
            for name, table in tables.items()]
    return pd.DataFrame(rows).set_index("estimator")


def printed_view(result: pd.DataFrame) -> pd.DataFrame:
    """The comparison as printed: each interval in one column (``low-high``), its verdict beside it, the cycles'
    losses only where there are any; ``compare_table.csv`` keeps every column."""
    view = pd.DataFrame(index=result.index)
    view["cycles"] = result["cycles"]
    for column in ("implausible", "failed"):
        if result[column].sum() > 0:
            view[column] = result[column]
    for parameter in INTERVALS:
        view[parameter] = result[parameter].map("{:.3g}".format)
        view[f"{parameter} 90 %"] = [f"{low:.3g}-{high:.3g}" for low, high in
                                    zip(result[f"{parameter}_low"], result[f"{parameter}_high"])]
        view[f"{parameter} det"] = result[f"{parameter}_determined"].map({True: "yes", False: "no"})
    for column in [c for c in COMPARED if c not in INTERVALS and c in result] + [f"{p}_det_%" for p in INTERVALS]:
        view[column] = result[column]
    for column in [c for c in result.columns if c in ("|err| f_h", "|err| xi_h")] + ["s/cycle", "f_h_cover_%"]:
        view[column] = result[column]
    return view


def coverage_warnings(names) -> list:
    """A ``warning:`` line for every estimator whose measured 90 % coverage of ``f_h`` is below :data:`COVERAGE_OK`."""
    out = []
    for name in names:
        cover = MEASURED_COVERAGE.get(name)
        if cover is not None and cover < COVERAGE_OK:
            where = "docs/person-calibration.md" if name == "record" else "docs/benchmarks.md"
            out.append(f"warning: {name}: intervals over-confident: its 90 % intervals of f_h covered the truth on "
                       f"{cover} % of simulated records ({where}); read its sd as a lower bound")
    return out


def run_compare(args) -> int:
    """Run ``smd-statespace compare``."""
    from ..plotting.cycles import plot_comparison

    names = parse_estimators(args.estimators)
    directory = out_dir(args.out)
    model = build_model(args)
    truth = truth_values(load_truth(args.truth))
    record, preprocessed = prepare_record(args)
    tables, seconds = {}, {}
    person = None
    for name in names:
        if name == "record":
            import time

            from ..io import read_record
            from ..person import identify_person

            started = time.perf_counter()
            # the record as read, as identify fits it: the front end needs the measured rate (the mains hum is
            # found and subtracted there, and the fitting rate chosen off its multiples); the per-cycle rows
            # take the record decimated to --rate
            as_read = read_record(args.record, args.mass, **reading_options(args))
            person = identify_person(as_read, n_harmonics=args.harmonics,
                                     check=not args.ignore_checks, rate=rate_of(args),
                                     progress=not args.quiet)
            person_seconds = time.perf_counter() - started
            continue
        _, tables[name], seconds[name] = identify(args, model, preprocessed, name)
    result = comparison_table(tables, seconds, truth) if tables else pd.DataFrame()
    if person is not None:
        row = pd.DataFrame([answer_row("record", person.to_dict(), person_seconds, truth)]).set_index(
            "estimator")
        result = pd.concat([row, result])
    print(f"{record.source}: {len(preprocessed.valid_cycles)} cycles, {model}")
    with pd.option_context("display.float_format", "{:.3g}".format, "display.width", 160,
                           "display.max_columns", 30):
        print(printed_view(result).to_string())
    if truth:
        print("truth: " + ", ".join(f"{k} {v:.4g}" for k, v in truth.items() if k in COMPARED))
    print("f_h_cover_%: how often one cycle's 90 % interval of f_h (record: the person's) held the truth on "
          "simulated records (measured in the docs, not on this record)")
    if tables:
        print("per-cycle rows: the cycles' median and the range of the central 90 % of them, never determined: the "
              "cycles share the estimator's error, which no pooling removes (docs/benchmarks.md)")
    for line in coverage_warnings(names):
        print(line)
    if result.get("implausible", pd.Series(dtype=float)).sum() > 0:
        print("warning: implausible cycles (xi_h < 0, a parameter on its prior bound, ...) are left out of the "
              "per-cycle answers and counted in the column 'implausible'")
    if person is not None:
        print("record: the person from the whole record (its 90 % interval of f_h "
              f"{person.intervals['f_h'][0]:.3f}-{person.intervals['f_h'][1]:.3f} Hz; docs/person.md says how far "
              "its intervals can be trusted)")
    written = [directory / "compare_table.csv"]
    result.to_csv(written[0])
    if tables:
        combined = pd.concat(tables.values(), ignore_index=True)
        combined.to_csv(directory / "compare.csv", index=False)
        plot_comparison(tables, directory / "compare.png", truth=truth, answers=result)
        written += [directory / "compare.csv", directory / "compare.png"]
    print("wrote " + ", ".join(str(path) for path in written))
    return 0
