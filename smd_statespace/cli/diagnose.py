"""``smd-statespace diagnose``: fit, residual tests and the ranked candidate effects of one record."""

from __future__ import annotations

import json
import shlex

import numpy as np
import pandas as pd

from ..diagnostics.check import INITIAL_STATES
from ..estimators import ESTIMATORS
from .common import (FADE_CHOICES, add_fade_argument, add_model_arguments, add_noise_floor_argument,
                     add_rate_argument, add_record_arguments, add_run_arguments, add_span_argument, build_model,
                     check_record_level_options, estimator_options, out_dir, person_effects, prepare_record, rate_of,
                     read_person_record)
from ..identify.runner import DEFAULT_ESTIMATOR


def add_diagnose(subparsers):
    """Declare ``smd-statespace diagnose``."""
    parser = subparsers.add_parser(
        "diagnose",
        help="compare the model with the measurement, test the residuals, rank missing effects",
        description=("Identify the person from the whole record (the record-level model, as 'identify' does), "
                     "test its innovations, then identify it again with each candidate effect (every registered "
                     "effect, a user's too) and test each by likelihood ratio: the table shows f_h, xi_h, the "
                     "effect's parameters, the noise and the Ljung-Box p before and after, and the verdict prints "
                     "the 'identify --effect' command that adds the missing effect. --effect adds an effect to "
                     "the model (the candidates are then tried on top of it); --candidate names the candidates to "
                     "try. With a per-cycle --estimator (the article's method), each cycle is refitted with "
                     "every candidate and the fits compared (free simulation, residual tests)."),
    )
    add_record_arguments(parser, accelerometer=True)
    parser.add_argument("--estimator", choices=["record"] + sorted(ESTIMATORS), default="record",
                        help="estimator for every fit (default record: the record-level model, each candidate "
                             f"identified with the person); a per-cycle one ({DEFAULT_ESTIMATOR}, ...) refits "
                             "every cycle with each candidate")
    add_rate_argument(parser)
    add_span_argument(parser)
    add_noise_floor_argument(parser)
    add_fade_argument(parser)
    add_model_arguments(parser)
    add_run_arguments(parser)
    parser.add_argument("--candidate", action="append", default=[], metavar="NAME[:key=value,...]",
                        help="a candidate effect to try, repeatable (default: every registered effect not in the "
                             "model; the floor is the measured one with a floor_acc column, else an estimated mode)")
    parser.add_argument("--no-floor", action="store_true",
                        help="record estimator: leave a record's measured floor (floor_acc) out of the person's "
                             "model and try it as a candidate (by default the person rides it, as in identify)")
    parser.add_argument("--json", metavar="FILE", help="write the report as JSON")
    parser.add_argument("--alpha", type=float, default=0.01, metavar="P",
                        help="family-wise significance level (default 0.01, Bonferroni over the candidates): of "
                             "the likelihood-ratio tests (record level, the default; their held-out gain is asked "
                             "as clearly) or the F-tests (per cycle, --estimator)")
    parser.add_argument("--initial-state", choices=INITIAL_STATES, default=INITIAL_STATES[0],
                        help="where each cycle's free simulation starts: 'estimate' (least-squares fit to the "
                             "cycle, as MATLAB's compare) or 'filtered' (the filter at the first sample)")
    return parser


SHARED_COLUMNS = ("df", "lr", "p_value", "significant", "f_h_before", "f_h", "xi_h_before", "xi_h",
                  "ljung_box_p_before", "ljung_box_p", "parameters")
"""The candidates' table columns both diagnoses print (record-level and per-cycle: one vocabulary)."""


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


def _effects_and_candidates(args) -> tuple:
    """``(effects added to the model, candidates or None)`` of ``--effect`` and ``--candidate``, checked: their specs
    (:func:`~smd_statespace.cli.common.person_effects`: a bare name configures itself for the record)."""
    from ..effects import make_effect
    from ..errors import OptionError

    added = person_effects(args)
    present = {make_effect(spec).key for spec in added}
    candidates = [spec.strip() for spec in args.candidate] or None
    both = [key for key in (make_effect(spec).key for spec in candidates or []) if key in present]  # bad: one line
    if both:
        raise OptionError(f"--candidate {both[0]!r} is also given as --effect: an effect is either in the model "
                          "(--effect) or a candidate to try on top of it (--candidate)")
    return added, candidates


def person_options(args) -> str:
    """The record-level options given away from their defaults, to repeat in the printed ``identify`` command
    (each ends with a space)."""
    from ..person.noise_floor import NOISE_FLOOR

    words = []
    if args.span != "auto":
        words.append("--span all" if args.span is None else f"--span {args.span[0]:g}:{args.span[1]:g}")
    if args.noise_floor != NOISE_FLOOR:
        words.append(f"--noise-floor {args.noise_floor:g}")
    if args.fade != "auto":
        words.append(f"--fade {args.fade}")
    if args.no_floor:
        words.append("--no-floor")
    return "".join(f"{word} " for word in words)


def _extra_effects(args) -> str:
    """``--effects FILE`` options to repeat in the printed next command (a user's effects file)."""
    return "".join(f"--effects {shlex.quote(str(path))} " for path in getattr(args, "effects", []))


def _print_verdict(result, command: str) -> None:
    """Either diagnosis's verdict, the command that adds what is missing (``command``, empty when adequate) and
    its notes, one line each."""
    print(f"\nverdict: {result.verdict()}")
    if command:
        print("next: " + command)
    for note in result.notes():
        print(f"note: {note}")


def _write_json(args, result, written: list) -> None:
    """``--json FILE``: the diagnosis's report (either path's ``report()``), added to ``written``."""
    if args.json:
        with open(args.json, "w", encoding="utf-8") as handle:
            json.dump(result.report(), handle, indent=2, default=float)
        written.append(args.json)


def screened_header(screened, alpha: float) -> str:
    """The line above the screened generic terms: how they were tested and how many of them are fitted above (those
    whose quick likelihood ratio is significant over the library at ``alpha``, at most
    :data:`~smd_statespace.person.diagnose.SCREENED`: :func:`~smd_statespace.person.diagnose.fitted_terms`)."""
    from ..person.diagnose import SCREENED, fitted_terms  # the fit's modules: imported when a person is diagnosed

    fitted = len(fitted_terms(screened, alpha))
    which = ("none is significant over the library (Holm), so none is fitted above" if fitted == 0 else
             f"the {fitted} largest quick likelihood ratio{'s' if fitted > 1 else ''} (over their misspecification "
             f"scale) significant over the library (Holm; at most {SCREENED}) {'are' if fitted > 1 else 'is'} "
             "fitted above")
    return f"generic terms, each score-tested at the fitted person, those not ruled out fitted quickly; {which}"


def run_person_diagnose(args) -> int:
    """``diagnose`` with the record-level model: identify with each candidate effect, test, print the command."""
    from ..person import identify_person
    from ..person.diagnose import diagnose_person
    from ..plotting.person import plot_candidates, plot_compare, plot_held_out, plot_spectrum, plot_step_scan
    from ..person.extend import check_effects

    added, candidates = _effects_and_candidates(args)  # a bad --effect or --candidate: one line, nothing read
    record = read_person_record(args)
    check_effects(added + (candidates or []), record)
    directory = out_dir(args.out)
    base = identify_person(record, n_harmonics=args.harmonics, check=not args.ignore_checks, rate=rate_of(args),
                           span=args.span, progress=not args.quiet, effects=added, measured_floor=not args.no_floor,
                           noise_floor=args.noise_floor, fade=FADE_CHOICES[args.fade])
    print(f"{record.source}: record-level model" + (f" with {', '.join(e.spec for e in base.effects)}"
                                                    if base.effects else ""))
    print(base.summary())
    result = diagnose_person(base, candidates=candidates, alpha=args.alpha, progress=not args.quiet)
    table = result.table()
    print("\ncandidate effects, each identified with the person (likelihood ratio, best first):")
    if table.empty:
        print("  none could be fitted")
    else:
        columns = (list(SHARED_COLUMNS[:2]) + ["lr_scale"] + list(SHARED_COLUMNS[2:-1])
                   + ["noise_change_%", "held_out_before", "held_out", "held_out_free_run_fit_before",
                      "held_out_free_run_fit", "parameters"])
        with pd.option_context("display.float_format", "{:.4g}".format, "display.width", 200,
                               "display.max_colwidth", 60):
            print(table[columns].to_string())
    if len(result.screened):
        print(f"\n{screened_header(result.screened, args.alpha)}:")
        for _, row in result.screened.head(5).iterrows():
            quick = (f"quick LR {row['lr_quick']:7.1f} / {row['lr_scale']:<4.2g} (Holm p {row['p_quick_holm']:<7.2g})"
                     if np.isfinite(row.get("lr_quick", np.nan)) else "not fitted" + " " * 28)
            print(f"  {row['label']:<17} robust LM {row['lm_robust']:7.1f}  {quick}  {row['physics']}")
    _print_verdict(result, result.command(args.record, args.mass, _extra_effects(args), person_options(args)))
    written = [directory / "person_diagnostics.png", directory / "person_candidates.png"]
    base.plot_diagnostics(written[0])
    plot_candidates(result, written[1])
    if result.scans:  # when does the person change: the steps' scans
        written.append(directory / "person_step_scan.png")
        plot_step_scan(result, written[-1])
    if not result.adequate:  # the proposed effect: the innovations' spectrum and the free run, without and with it
        proposed = result.fits[result.missing[0]]
        written += [directory / "person_spectrum.png", directory / "person_compare.png"]
        plot_spectrum(proposed, written[-2])
        plot_compare(proposed, written[-1])
    validated = [name for name in result.table().index if result.held_out_pair(name) is not None]
    if validated:  # the proposed one, else the best that was judged on held-out data
        written.append(directory / "person_held_out.png")
        plot_held_out(result, (result.missing or validated)[0], written[-1])
    _write_json(args, result, written)
    print("wrote " + ", ".join(str(path) for path in written))
    return 0


def run_diagnose(args) -> int:
    """Run ``smd-statespace diagnose``."""
    from ..diagnostics.check import check_model

    if args.estimator == "record":
        return run_person_diagnose(args)
    check_record_level_options(args, "tries it as a candidate anyway")
    from ..diagnostics.missing import diagnose
    from ..effects import make_effect
    from ..plotting.cycles import plot_before_after

    directory = out_dir(args.out)
    _, candidates = _effects_and_candidates(args)
    candidates = [make_effect(spec) for spec in candidates] if candidates else None
    model = build_model(args)
    record, preprocessed = prepare_record(args)
    options = dict(max_passes=args.max_passes, seed=args.seed, progress=not args.quiet,
                   initial_state=args.initial_state, **estimator_options(args.estimator, args))
    result = diagnose(preprocessed, model, estimator=args.estimator, candidates=candidates, alpha=args.alpha,
                      **options)
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
        with pd.option_context("display.float_format", "{:.3g}".format, "display.width", 200,
                               "display.max_colwidth", 60):
            print(table[list(SHARED_COLUMNS[:-1]) + ["score", "rms_fall_%", "parameters"]].to_string())
    _print_verdict(result, result.command(args.record, args.mass, args.estimator, _extra_effects(args)))
    base.plot_diagnostics(directory / "diagnostics.png")
    base.plot_fit(directory / "fit.png")
    written = [directory / "diagnostics.png", directory / "fit.png"]
    if model.effects:
        written.append(directory / "before_after.png")
    _write_json(args, result, written)
    print("wrote " + ", ".join(str(path) for path in written))
    return 0
