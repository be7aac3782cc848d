"""``smd-statespace diagnose``: fit, residual tests and the ranked candidate effects of one record."""

from __future__ import annotations

import json
import shlex

import pandas as pd

from ..diagnostics.check import INITIAL_STATES
from ..estimators import ESTIMATORS
from .common import (add_model_arguments, add_rate_argument, add_record_arguments, add_run_arguments, build_model,
                     estimator_options, out_dir, prepare_record, rate_of)
from .identify import DEFAULT_ESTIMATOR


def add_diagnose(subparsers):
    """Declare ``smd-statespace diagnose``."""
    parser = subparsers.add_parser(
        "diagnose",
        help="compare the model with the measurement, test the residuals, rank missing effects",
        description=("Identify the record, compare the predicted GRF with the measured one (free simulation and "
                     "one-step-ahead prediction), test the residuals (whiteness, normality, variance change, "
                     "spectrum, phase, cross-correlation) and refit with every candidate effect to find the one "
                     "that is missing. With --effect, the fit without and with those effects is shown side by side."),
    )
    add_record_arguments(parser)
    parser.add_argument("--estimator", choices=["record"] + sorted(ESTIMATORS), default=DEFAULT_ESTIMATOR,
                        help=f"estimator for every fit (default {DEFAULT_ESTIMATOR}); record: the record-level model, "
                             "each candidate added with its record-level parameters and tested by likelihood ratio")
    add_rate_argument(parser)
    add_model_arguments(parser)
    add_run_arguments(parser)
    parser.add_argument("--json", metavar="FILE", help="write the report as JSON")
    parser.add_argument("--alpha", type=float, default=0.01, metavar="P",
                        help="significance level of the candidates' F-tests (default 0.01, Bonferroni-corrected)")
    parser.add_argument("--initial-state", choices=INITIAL_STATES, default=INITIAL_STATES[0],
                        help="where each cycle's free simulation starts: 'estimate' (least-squares fit to the "
                             "cycle, as MATLAB's compare) or 'filtered' (the filter at the first sample)")
    return parser


def _fit_line(check) -> str:
    return (f"fit {check.fit_percent:.1f} % (one-step {check.fit_percent_one_step:.1f} %), residual RMS "
            f"{check.residual_rms:.2f} N = {check.residual_rms_bw:.2f} % body weight, "
            f"residual serial correlation {check.serial_correlation_ratio():.2f} per df "
            f"(Ljung-Box p = {check.whiteness_pvalue(series='residual'):.3g})")


def before_after(before, after) -> pd.DataFrame:
    """The fit without and with the effects, side by side."""
    rows = {}
    for label, check in (("without", before), ("with", after)):
        rows[label] = {"fit_%": check.fit_percent, "one_step_fit_%": check.fit_percent_one_step,
                       "residual_rms_N": check.residual_rms, "residual_rms_%BW": check.residual_rms_bw,
                       "serial_ratio": check.serial_correlation_ratio(),
                       "whiteness_p": check.whiteness_pvalue(series="residual"), "log_likelihood": check.log_likelihood}
    return pd.DataFrame(rows)


def run_person_diagnose(args) -> int:
    """``diagnose --estimator record``: candidate effects on the record-level model."""
    from ..io import read_record
    from ..person import identify_person
    from ..person.diagnose import diagnose_person

    directory = out_dir(args.out)
    record = read_record(args.record, args.mass)
    base = identify_person(record, n_harmonics=args.harmonics, check=not args.ignore_checks, rate=rate_of(args),
                           progress=not args.quiet)
    print(f"{record.source}: record-level model")
    print(base.summary())
    result = diagnose_person(base, candidates=args.effect or None, alpha=args.alpha)
    print("\ncandidate effects added to the record-level model (likelihood ratio, best first):")
    columns = ["n_params", "lr", "p_value", "significant", "noise_change_%", "f_h_before", "f_h", "xi_h_before",
               "xi_h", "estimate", "estimate_sd"]
    with pd.option_context("display.float_format", "{:.4g}".format, "display.width", 160):
        print(result.table()[columns].to_string())
    if result.adequate:
        print("\nverdict: no candidate effect is a significant improvement at "
              f"alpha {args.alpha:g} (Bonferroni over {len(result.rows)})")
    else:
        best = result.table().loc[result.missing[0]]
        print(f"\nverdict: missing effect '{result.missing[0]}' (LR {best['lr']:.1f} on {int(best['n_params'])} "
              f"parameters, p {best['p_value']:.2g}); with it f_h {best['f_h_before']:.3f} -> {best['f_h']:.3f} Hz, "
              f"xi_h {best['xi_h_before']:.3f} -> {best['xi_h']:.3f}")
    for note in result.notes():
        print(f"note: {note}")
    written = [directory / "person_diagnostics.png"]
    base.plot_diagnostics(written[0])
    if args.json:
        with open(args.json, "w", encoding="utf-8") as handle:
            json.dump(result.report(), handle, indent=2, default=float)
        written.append(args.json)
    print("wrote " + ", ".join(str(path) for path in written))
    return 0


def run_diagnose(args) -> int:
    """Run ``smd-statespace diagnose``."""
    from ..diagnostics.check import check_model

    if args.estimator == "record":
        return run_person_diagnose(args)
    from ..diagnostics.missing import diagnose
    from ..plotting.cycles import plot_before_after

    directory = out_dir(args.out)
    model = build_model(args)
    record, preprocessed = prepare_record(args)
    options = dict(max_passes=args.max_passes, seed=args.seed, progress=not args.quiet,
                   initial_state=args.initial_state, **estimator_options(args.estimator, args))
    result = diagnose(preprocessed, model, estimator=args.estimator, alpha=args.alpha, **options)
    base = result.base
    print(f"{record.source}: {args.estimator} on {model}")
    print(_fit_line(base))
    print(base.summary())
    if model.effects:
        plain = check_model(preprocessed, type(model)(**model.options), estimator=args.estimator, **options)
        print("\nfit without and with " + ", ".join(e.name for e in model.effects) + ":")
        with pd.option_context("display.float_format", "{:.4g}".format):
            print(before_after(plain, base).to_string())
        plot_before_after(plain, base, directory / "before_after.png")
    print("\ncandidate effects, each refitted (best first):")
    table = result.table()
    if table.empty:
        print("  none left to try: every registered effect is in the model")
    else:
        with pd.option_context("display.float_format", "{:.3g}".format, "display.width", 140):
            print(table.to_string())
    if result.adequate:
        print("\nverdict: the model is adequate for this record (no candidate effect is a significant improvement)")
    else:
        best = result.missing[0]
        print(f"\nverdict: missing effect '{best.name}': {best.evidence}")
        print(f"next: smd-statespace diagnose {shlex.quote(str(args.record))} --mass {args.mass:g} "
              f"--effect {shlex.quote(best.effect.spec)}")
    for note in result.notes:
        print(f"note: {note}")
    base.plot_diagnostics(directory / "diagnostics.png")
    base.plot_fit(directory / "fit.png")
    written = [directory / "diagnostics.png", directory / "fit.png"]
    if model.effects:
        written.append(directory / "before_after.png")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as handle:
            json.dump(result.report(), handle, indent=2)
        written.append(args.json)
    print("wrote " + ", ".join(str(path) for path in written))
    return 0
