"""``smd-statespace compare``: several estimators side by side on the same cycles of one record."""

from __future__ import annotations

import pandas as pd

from ..errors import OptionError
from ..estimators import ESTIMATORS
from .common import (add_model_arguments, add_rate_argument, add_record_arguments, add_run_arguments, build_model,
                     load_truth, out_dir, prepare_record, truth_values)
from .identify import identify, plausible_cycles

COMPARED = ("f_h", "xi_h", "blf_1", "blf_2", "blf_3")

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
        description=("Identify the same cycles with each estimator and print, per estimator, the median estimates, "
                     "their spread over cycles, the share of cycles that determine each parameter and the run time; "
                     "with --truth also the median absolute error. Writes DIR/compare.csv and DIR/compare.png."),
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


def comparison_table(tables: dict, seconds: dict, truth: dict | None = None) -> pd.DataFrame:
    """One row per estimator: medians, interquartile range of f_h, determined shares, errors, time."""
    rows = []
    for name, table in tables.items():
        ok = plausible_cycles(table)  # impossible estimates are not summarised (counted instead)
        implausible = int((table["status"] == "ok").sum()) - len(ok)
        row = {"estimator": name, "cycles": len(ok), "implausible": implausible,
               "failed": int((table["status"] == "failed").sum())}
        for parameter in COMPARED:
            row[parameter] = ok[parameter].median()
        row["f_h_iqr"] = ok["f_h"].quantile(0.75) - ok["f_h"].quantile(0.25)
        row["f_h_det_%"] = 100.0 * ok["f_h_determined"].mean()
        row["xi_h_det_%"] = 100.0 * ok["xi_h_determined"].mean()
        for parameter in COMPARED:
            if truth and parameter in truth:
                row[f"|err| {parameter}"] = (ok[parameter] - truth[parameter]).abs().median()
        row["s/cycle"] = seconds[name] / max(len(ok), 1)
        row["f_h_cover_%"] = MEASURED_COVERAGE.get(name, float("nan"))
        rows.append(row)
    return pd.DataFrame(rows).set_index("estimator")


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


def person_row(person, seconds: float, truth: dict | None = None) -> dict:
    """The record-level estimate as a row of the comparison: the person's values, not medians of cycles."""
    d = person.to_dict()
    row = {"estimator": "record", "cycles": d["n_cycles"], "implausible": 0, "failed": 0}
    for parameter in COMPARED:
        row[parameter] = d[parameter]
    row["f_h_iqr"] = float("nan")
    row["f_h_det_%"] = 100.0 * d["f_h_determined"]
    row["xi_h_det_%"] = 100.0 * d["xi_h_determined"]
    for parameter in COMPARED:
        if truth and parameter in truth:
            row[f"|err| {parameter}"] = abs(d[parameter] - truth[parameter])
    row["s/cycle"] = seconds / max(d["n_cycles"], 1)
    row["f_h_cover_%"] = MEASURED_COVERAGE["record"]
    return row


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

            from ..person import identify_person

            started = time.perf_counter()
            person = identify_person(record, n_harmonics=args.harmonics, check=False, rate=None,  # checked, decimated
                                     progress=not args.quiet)
            person_seconds = time.perf_counter() - started
            continue
        _, tables[name], seconds[name] = identify(args, model, preprocessed, name)
    result = comparison_table(tables, seconds, truth) if tables else pd.DataFrame()
    if person is not None:
        row = pd.DataFrame([person_row(person, person_seconds, truth)]).set_index("estimator")
        result = pd.concat([row, result])
    print(f"{record.source}: {len(preprocessed.valid_cycles)} cycles, {model}")
    with pd.option_context("display.float_format", "{:.3g}".format, "display.width", 160,
                           "display.max_columns", 30):
        print(result.to_string())
    if truth:
        print("truth: " + ", ".join(f"{k} {v:.4g}" for k, v in truth.items() if k in COMPARED))
    print("f_h_cover_%: how often each estimator's 90 % interval of f_h held the truth on simulated records "
          "(measured in the docs, not on this record)")
    for line in coverage_warnings(names):
        print(line)
    if result.get("implausible", pd.Series(dtype=float)).sum() > 0:
        print("warning: implausible cycles (xi_h < 0, a parameter on its prior bound, ...) are left out of the "
              "medians and counted in the column 'implausible'")
    if person is not None:
        print("record: the person from the whole record (its 90 % interval of f_h "
              f"{person.intervals['f_h'][0]:.3f}-{person.intervals['f_h'][1]:.3f} Hz; docs/person.md says how far "
              "its intervals can be trusted); the other rows are medians over cycles")
    written = [directory / "compare_table.csv"]
    result.to_csv(written[0])
    if tables:
        combined = pd.concat(tables.values(), ignore_index=True)
        combined.to_csv(directory / "compare.csv", index=False)
        plot_comparison(tables, directory / "compare.png", truth=truth)
        written += [directory / "compare.csv", directory / "compare.png"]
    print("wrote " + ", ".join(str(path) for path in written))
    return 0
