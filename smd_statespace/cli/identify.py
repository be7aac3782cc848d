"""``smd-statespace identify``: the person from a whole record (default), or every cycle with a per-cycle estimator."""

from __future__ import annotations

import json
import time
from pathlib import Path
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pandas as pd

from .. import __version__
from ..estimators import ESTIMATORS
from ..errors import OptionError, SMDInputError
from ..identify.plausibility import plausible_cycles
from .common import (FADE_CHOICES, MASS_HELP, PROG, _count, add_accelerometer_arguments, add_export_arguments,
                     add_fade_argument, add_model_arguments, add_noise_floor_argument, add_rate_argument,
                     add_run_arguments, add_span_argument, build_model, check_record_level_options, estimator_options,
                     load_truth, out_dir, person_effects, prepare_record, rate_of, read_person_record,
                     reading_options, truth_values)


SUMMARY_PARAMETERS = ("f_h", "xi_h", "blf_1", "blf_2", "blf_3", "k_h", "c_h")


def add_identify(subparsers):
    """Declare ``smd-statespace identify``."""
    parser = subparsers.add_parser(
        "identify",
        help="identify the person (f_h, xi_h, the force) from a record; --estimator for the per-cycle method",
        description=("One record: identify the person from the whole record (the record-level model, the default: "
                     "one f_h and xi_h with 90 % intervals, the force's load factors, noise levels by maximum "
                     "likelihood; --effect adds physical effects to it); write DIR/person.json, results.csv and "
                     "figures. With a per-cycle --estimator (pf, rbpf, ukf, ekf, grid), the article's method: split "
                     "the record into bouncing cycles (GRF peak to peak) and identify f_h, xi_h and the force "
                     "coefficients of every cycle with repeated passes (Wang et al. 2019, Section 3.2); write "
                     "DIR/results.csv, DIR/run.json and figures. Given a folder, a glob or --manifest, identify "
                     "every record (--estimator record: one person each), writing each finished one to DIR/parts/ "
                     "(see --resume); exit status 1 when some records failed (each is named on stderr), 0 when "
                     "none did."),
    )
    parser.add_argument("record", metavar="REC", nargs="?",
                        help="a record CSV (time,force[,floor_acc]) or a force plate's export (Vicon Nexus, Kistler "
                             "BioWare, Qualisys, OpenSim, C3D, ...), a folder of them, or a quoted glob "
                             "('data/*.csv'); may be omitted with --manifest")
    parser.add_argument("--mass", type=float, metavar="KG",
                        help=MASS_HELP + "; with many records, the mass of those the manifest does not list; "
                             "optional with --accelerometer (K_h, C_h need it)")
    add_export_arguments(parser)
    add_accelerometer_arguments(parser)
    parser.add_argument("--manifest", metavar="FILE",
                        help="CSV with columns file,mass: one body mass per record (files relative to it)")
    parser.add_argument("--resume", action="store_true",
                        help="continue a killed batch run in --out: finished records are kept, not recomputed")
    parser.add_argument("--estimator", choices=["record"] + sorted(ESTIMATORS), default=None,
                        help="record (default, for one record and for a batch: one f_h, xi_h per record, noise "
                             "levels by maximum likelihood; writes DIR/person.json, or one row per record) or a "
                             "per-cycle estimator, the article's method: pf (its particle filter), rbpf, ukf, ekf "
                             "or grid")
    parser.add_argument("--variation", choices=("auto", "independent", "smooth", "both", "random_walk"),
                        default="auto",
                        help="record estimator: how the force coefficients vary: independent (they jump at every "
                             "cycle start), smooth (they drift continuously), both, random_walk, or auto (default: "
                             "fits independent and smooth and keeps the lower AIC)")
    parser.add_argument("--timing", choices=("model", "template", "peaks"), default="model",
                        help="record estimator: force-cycle starts placed by the model's own phase errors (default), "
                             "aligned on the mean cycle (template), or at GRF peaks (the article's cycles)")
    parser.add_argument("--intervals", choices=("calibrated", "wald", "profile"), default="calibrated",
                        help="record estimator: 90 %% intervals of f_h, xi_h from the standard errors widened by "
                             "factors measured on simulated records, and as wide as the yardstick where the record "
                             "does not determine them or the model misfits it (calibrated, default), from the "
                             "standard errors alone (wald: too narrow) or from the profile likelihood (slower)")
    parser.add_argument("--no-floor", action="store_true",
                        help="record estimator: leave a record's measured floor (its floor_acc column) out of the "
                             "person's model; by default the person rides it (Eq. 2 relative to the floor, a known "
                             "input, no unknown added)")
    add_rate_argument(parser)
    add_span_argument(parser, each=True)
    add_noise_floor_argument(parser)
    add_fade_argument(parser)
    add_model_arguments(parser)
    add_run_arguments(parser)
    parser.add_argument("--jobs", type=_count, default=1, metavar="N", help="parallel processes (default 1)")
    parser.add_argument("--cycle", type=int, metavar="K",
                        help="cycle whose convergence over passes is drawn (default: the middle valid cycle)")
    parser.add_argument("--truth", metavar="JSON", help="truth file of a synthetic record, drawn in the figures")
    parser.add_argument("--verbose", action="store_true",
                        help="record estimator: also print how the intervals were made (always in person.json)")
    return parser


def identify(args, model, preprocessed, estimator: str):
    """Run the cycle runner as the options say; returns ``(runner, table, seconds)``."""
    from ..identify.runner import CycleRunner

    options = dict(estimator=estimator, max_passes=args.max_passes, seed=args.seed, progress=not args.quiet,
                   **estimator_options(estimator, args))
    started = time.perf_counter()
    if getattr(args, "jobs", 1) > 1:
        with ProcessPoolExecutor(max_workers=args.jobs) as pool:
            runner = CycleRunner(model, executor=pool, **options)
            table = runner.run(preprocessed)
    else:
        runner = CycleRunner(model, **options)
        table = runner.run(preprocessed)
    return runner, table, time.perf_counter() - started


def summary_table(table: pd.DataFrame, truth: dict | None = None) -> pd.DataFrame:
    """Median, interquartile range and share of determining cycles of each reported parameter.

    Over the plausible ``ok`` cycles only: cycles flagged ``implausible`` (see
    :mod:`smd_statespace.identify.plausibility`) are left out, :func:`implausible_warning` says how many.
    Empty (no rows) when no cycle is left.
    """
    ok = plausible_cycles(table)
    rows = []
    for name in SUMMARY_PARAMETERS:
        if name not in ok:
            continue
        values = ok[name]
        row = {"parameter": name, "median": values.median(), "q25": values.quantile(0.25),
               "q75": values.quantile(0.75), "median_sd": ok[f"{name}_sd"].median() if f"{name}_sd" in ok else np.nan}
        flag = f"{name}_determined"
        row["determined_%"] = 100.0 * ok[flag].mean() if flag in ok else np.nan
        if truth and name in truth:
            row["truth"] = truth[name]
        rows.append(row)
    if not rows or ok.empty:
        return pd.DataFrame(columns=["median", "q25", "q75", "median_sd", "determined_%"],
                            index=pd.Index([], name="parameter"))
    return pd.DataFrame(rows).set_index("parameter")


def implausible_warning(table: pd.DataFrame) -> str:
    """A ``warning:`` line counting the cycles flagged ``implausible`` and why; ``""`` when there are none."""
    from ..identify.plausibility import implausible_ok

    ok, bad, counts = implausible_ok(table)
    if not bad.any():
        return ""
    why = ", ".join(f"{reason}: {n}" for reason, n in counts.items())
    return (f"warning: {int(bad.sum())} of {int(ok.sum())} identified cycles gave estimates that cannot be true "
            f"({why}); they are marked implausible and undetermined in results.csv and left out of the summary")


def run_summary(table: pd.DataFrame, seconds: float) -> str:
    """One line: cycles identified (implausible among them), converged, failed, skipped, and time."""
    from ..identify.plausibility import flagged

    counts = table["status"].value_counts()
    ok = table[table["status"] == "ok"]
    implausible = int(flagged(ok).sum())
    return (f"{counts.get('ok', 0)} cycles identified ({int(ok['converged'].sum())} converged within the pass limit, "
            f"mean {ok['passes'].mean():.1f} passes, {implausible} implausible), {counts.get('failed', 0)} failed, "
            f"{counts.get('skipped', 0)} skipped near the record ends; {seconds:.1f} s "
            f"({seconds / max(len(ok), 1):.2f} s per cycle)")


def write_outputs(directory, runner, table, args, estimator, truth=None) -> list:
    """results.csv, run.json (version, options, seed) and the figures; returns the paths written."""
    from ..plotting.cycles import plot_convergence, plot_parameters

    results = directory / "results.csv"
    table.to_csv(results, index=False)
    sidecar = directory / "run.json"
    sidecar.write_text(json.dumps({
        "version": __version__, "command": "identify", "record": str(args.record), "mass": args.mass,
        "estimator": estimator, "options": estimator_options(estimator, args), "harmonics": args.harmonics,
        "discretisation": args.discretisation, "effects": list(args.effect), "max_passes": args.max_passes,
        "seed": args.seed, "rate": rate_of(args),
    }, indent=2))
    written = [results, sidecar]
    ok = table[table["status"] == "ok"]
    if len(ok):
        written.append(directory / "parameters.png")
        plot_parameters(table, written[-1], truth=truth)
        cycles = [c for c in ok["cycle"] if runner.history_.get(c)]
        cycle = args.cycle if args.cycle in cycles else (cycles[len(cycles) // 2] if cycles else None)
        if cycle is not None:
            written.append(directory / "convergence.png")
            plot_convergence(runner.history_[cycle], cycle, tolerance=runner.tolerance, path=written[-1])
    return written


def is_batch(args) -> bool:
    """Whether the options ask for many records (a folder, a glob, a manifest or --resume)."""
    import glob

    from pathlib import Path

    record = args.record
    return (args.manifest is not None or args.resume or record is None or Path(record).is_dir()
            or (glob.has_magic(record) and not Path(record).exists()))


def run_batch_identify(args) -> int:
    """Identify many records (see :mod:`smd_statespace.identify.batch`); 1 when some failed, else 0."""
    import sys

    from ..identify.batch import collect_records, run_batch
    from ..plotting.cycles import plot_parameters
    from ..plotting.people import plot_people

    if args.truth is not None:
        raise OptionError("--truth applies to one record, not to a batch")
    if args.span != "auto" and (args.span != "each" or args.estimator != "record"):
        raise OptionError("--span applies to one record; with many, only --span each (a person per bout of every "
                          "record, the record-level model)")
    directory = out_dir(args.out)
    model = build_model(args)
    records = collect_records(args.record, args.mass, args.manifest, accelerometer=args.accelerometer,
                              units=args.units or "auto", reading=reading_options(args))
    options = dict(max_passes=args.max_passes, seed=args.seed, rate=rate_of(args),
                   **estimator_options(args.estimator, args))
    if args.no_floor:
        options["measured_floor"] = False
    if args.estimator == "record":
        options["noise_floor"], options["fade"] = args.noise_floor, FADE_CHOICES[args.fade]
        if args.span == "each":
            options["span"] = "each"
    started = time.perf_counter()
    summary = run_batch(records, directory, model, args.estimator, options, jobs=args.jobs, resume=args.resume,
                        progress=not args.quiet, check=not args.ignore_checks)
    written = [summary.results] + ([summary.pooled] if summary.pooled else []) + [directory / "run.json"]
    if (summary.table["status"] == "ok").any():
        if args.estimator == "record":
            written.append(directory / "people.png")
            plot_people(summary.table, written[-1], title="A person per bout of every record" if
                        args.span == "each" else None)
        else:
            written.append(directory / "parameters.png")
            plot_parameters(summary.table, written[-1], against="f_b")
    print(f"{summary.line()}; {time.perf_counter() - started:.1f} s")
    warning = implausible_warning(summary.table)
    if warning:
        print(warning)
    for reason in summary.failures.values():
        print(f"{PROG}: error: {reason}", file=sys.stderr)
    print("wrote " + ", ".join(str(path) for path in written) + f" and {len(records)} parts in {directory / 'parts'}")
    return 1 if summary.failed_records else 0


def run_person(args) -> int:
    """``identify --estimator record``: the person from the whole record; person.json, results.csv, figures
    (``--span each``: a person per bout, :func:`run_bouts`)."""
    from ..person import identify_person
    from ..person.extend import check_effects
    from .person_output import write_person

    effects = person_effects(args)  # an unknown effect or option: one line before anything is read
    record = read_person_record(args)
    check_effects(effects, record)  # a column the record lacks (floor_acc): one line, nothing written
    truth = truth_values(load_truth(args.truth))  # a bad --truth fails before the fit, not after
    directory = out_dir(args.out)
    fit_options = dict(n_harmonics=args.harmonics, variation=args.variation, timing=args.timing,
                       intervals=args.intervals, check=not args.ignore_checks, rate=rate_of(args),
                       progress=not args.quiet, effects=effects, measured_floor=not args.no_floor,
                       noise_floor=args.noise_floor, fade=FADE_CHOICES[args.fade])
    options = {"variation": args.variation, "timing": args.timing, "intervals": args.intervals,
               "harmonics": args.harmonics, "rate": rate_of(args), "span": args.span,
               "noise_floor": args.noise_floor, "fade": args.fade, "effects": list(effects)}
    if args.span == "each":
        return run_bouts(record, directory, fit_options, options, truth)
    started = time.perf_counter()
    result = identify_person(record, span=args.span, **fit_options)
    seconds = time.perf_counter() - started
    print(f"{record.source}: record-level model ({seconds:.1f} s)")
    print(result.summary(verbose=args.verbose))
    options["effects"] = [e.spec for e in result.effects]
    written = write_person(directory, result, options, truth=truth)
    print("wrote " + ", ".join(str(path) for path in written))
    return 0


def run_bouts(record, directory, fit_options: dict, options: dict, truth) -> int:
    """``identify REC --span each``: a person per bout of bouncing (:func:`~smd_statespace.person.identify_bouts`);
    DIR/bouts.csv (one row per bout), DIR/person_bouts.png (each against its ``f_b``) and each bout's files in
    DIR/bout_N/. 1 when some bout could not be identified (each named on stderr), else 0."""
    import sys

    from ..person import identify_bouts
    from ..plotting.people import plot_people
    from .person_output import atomic_write_text, write_person

    started = time.perf_counter()
    answers = identify_bouts(record, **fit_options)
    bouts = f"{len(answers)} bouts of bouncing, a person each" if len(answers) > 1 else "1 bout of bouncing"
    print(f"{record.source}: {bouts} ({time.perf_counter() - started:.1f} s)")
    written = [directory / "bouts.csv", directory / "run.json"]
    for answer in answers:
        print(answer.line())
        if answer.result is not None:
            written += write_person(out_dir(directory / f"bout_{answer.number}"), answer.result, options,
                                    truth=truth)[:1]
    table = pd.DataFrame([answer.row() for answer in answers])
    table.insert(0, "record", str(record.source))
    table.to_csv(written[0], index=False)
    atomic_write_text(written[1], json.dumps({"version": __version__, "command": "identify", "estimator": "record",
                                              "record": str(record.source), "options": options,
                                              "mass": record.mass if record.extra.get("mass_known", True) else None,
                                              "bouts": [[a.start, a.end] for a in answers]}, indent=2))
    if (table["status"] == "ok").any():
        written.append(directory / "person_bouts.png")
        plot_people(table, written[-1], title=f"{record.source}: a person per bout of bouncing "
                                              f"({int((table['status'] == 'ok').sum())} of {len(table)} identified)")
    for answer in answers:
        if answer.result is None:
            print(f"{PROG}: error: {record.source}: {answer.name}: {answer.error}", file=sys.stderr)
    print("wrote " + ", ".join(str(path) for path in written) + " and each bout's figures beside its person.json")
    return 1 if any(answer.result is None for answer in answers) else 0


def run_identify(args) -> int:
    """Run ``smd-statespace identify``."""
    if args.units is not None and not args.accelerometer:
        raise OptionError("--units applies to an accelerometer record (--accelerometer)")
    floor = "adds a floor only with --effect"
    args.estimator = args.estimator or "record"  # one record or many: the person, the per-cycle method by name
    check_record_level_options(args, floor)
    if is_batch(args):
        return run_batch_identify(args)
    if args.estimator == "record":
        return run_person(args)
    directory = out_dir(args.out)
    model = build_model(args)
    truth = truth_values(load_truth(args.truth))
    record, preprocessed = prepare_record(args)
    runner, table, seconds = identify(args, model, preprocessed, args.estimator)
    written = write_outputs(directory, runner, table, args, args.estimator, truth)
    print(f"{record.source}: {args.estimator} on {model}")
    print(run_summary(table, seconds))
    warning = implausible_warning(table)
    if warning:
        print(warning)
    summary = summary_table(table, truth)
    if summary.empty:
        print("no plausible identified cycle to summarise")
    else:
        with pd.option_context("display.float_format", "{:.4g}".format, "display.width", 120):
            print(summary.to_string())
        print("'determined_%': plausible cycles whose posterior sd is under a quarter of the prior sd; "
              "the others do not pin the parameter down.")
        written.append(print_pooled(table, directory))
        written += print_check(runner, directory)
    print("wrote " + ", ".join(str(path) for path in written))
    return 0


def print_pooled(table: pd.DataFrame, directory) -> Path:
    """Print the record's answer from its cycles (:func:`~smd_statespace.identify.pooled.pool_cycles`, the
    person's vocabulary) and write it to ``DIR/pooled.csv``; returns the path."""
    from ..identify.pooled import pool_cycles

    pooled = pool_cycles(table)
    shown = pd.DataFrame({"value": pooled["value"].map("{:.4g}".format),
                          "central 90 % of cycles": [f"{low:.4g}-{high:.4g}" for low, high in
                                                     zip(pooled["low"], pooled["high"])],
                          "determined": "no",
                          "cycles determining": [f"{d} of {n}" for d, n in
                                                 zip(pooled["determining"], pooled["cycles"])]},
                         index=pooled.index)
    print("the record's answer from its cycles: their median and the range of the central 90 % of them; the "
          "per-cycle method determines no parameter of the person, since its cycles share the estimator's error "
          "(docs/benchmarks.md); the person from the whole record does: drop --estimator")
    print(shown.to_string())
    path = Path(directory) / "pooled.csv"
    pooled.to_csv(path)
    return path


def print_check(runner, directory) -> list:
    """Print how the cycles' model meets the record (:func:`~smd_statespace.diagnostics.check_model`: the tests
    and the free run every estimator's answer carries, :mod:`smd_statespace.answers`) and draw its diagnostics as
    ``DIR/diagnostics.png``; returns the paths written (none where the check cannot be made, which is said)."""
    from ..diagnostics import check_model

    try:
        check = check_model(runner=runner)
    except (SMDInputError, ArithmeticError, np.linalg.LinAlgError) as exc:
        print(f"note: the cycles were not checked against the record: {' '.join(str(exc).split())}")
        return []
    tests = check.test_pvalues()
    print(f"the cycles against the record: free-run fit {check.fit_percent:.1f} % (each cycle with its own person "
          f"and force); innovations within cycles: Ljung-Box p {tests['ljung_box_p']:.2g}, Jarque-Bera p "
          f"{tests['jarque_bera_p']:.2g}, kurtosis {tests['kurtosis']:.2f} (the article's filter restarts every "
          "cycle and its innovations are correlated even where the model is right: 'diagnose --estimator "
          f"{runner.estimator.name}' tests the free run's residual for a missing effect)")
    path = Path(directory) / "diagnostics.png"
    check.plot_diagnostics(path)
    return [path]
