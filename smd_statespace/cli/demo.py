"""``smd-statespace demo``: the pipeline and the identification on the shipped sample, explained."""

from __future__ import annotations

import textwrap
import time
from collections import Counter
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import OptionError
from .common import MASS_HELP, demo_out_dir, load_record, load_sample


DEMO_OUT = "smd_demo_output"
"""Default output directory of ``smd-statespace demo`` (in the current directory)."""

DEMO_TABLE_ROWS = 6
"""Cycles shown in the demo's per-cycle table."""


def add_demo(subparsers):
    """Declare ``smd-statespace demo``."""
    parser = subparsers.add_parser(
        "demo",
        help="the person from the built-in sample record, then the article's per-cycle method on it, explained",
        description=(
            "Read the shipped sample record (synthetic, 70 kg, bouncing at 2 Hz) or your own, identify the "
            "person from the whole record (f_h, xi_h with intervals, against the sample's truth), then show how "
            "the article's per-cycle method sees it: the GRF turned into COM acceleration, velocity and "
            "displacement (Eq. 3), the cycles, the augmented model (Eq. 7-16) and every cycle identified."
        ),
    )
    parser.add_argument("--out", default=DEMO_OUT, metavar="DIR",
                        help=f"directory for the figure (default ./{DEMO_OUT})")
    parser.add_argument("--record", metavar="CSV",
                        help="your own record (time,force[,floor_acc]) instead of the built-in sample; needs --mass")
    parser.add_argument("--mass", type=float, metavar="KG", help=f"of --record: {MASS_HELP}")
    return parser


def _rms(x) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def _heading(title: str) -> str:
    return f"\n{title}\n{'-' * len(title)}"


def _rows(pairs) -> str:
    """Aligned ``label  value`` lines."""
    width = max(len(label) for label, _ in pairs)
    return "\n".join(f"  {label:<{width}}  {value}" for label, value in pairs)


def demo_record_section(record, truth, where=None) -> str:
    """What the record is: file, duration, sampling, mass, mean GRF, known truth (if any)."""
    from ..io import G

    weight = record.mass * G
    rows = [
        ("file", record.source),
        ("length", f"{record.duration:.2f} s, {record.time.size} samples at {record.fs:g} Hz"),
        ("body mass", f"{record.mass:g} kg (M_h g = {weight:.1f} N)"),
        ("mean GRF", f"{np.mean(record.force):.1f} N = {np.mean(record.force) / weight:.3f} body weights"),
        ("GRF range", f"{record.force.min() / weight:.2f}-{record.force.max() / weight:.2f} body weights"),
    ]
    if where is not None:
        rows.insert(1, ("location", where))
    if truth and all(key in truth for key in ("f_h", "xi_h", "f_b")):
        rows.append(("known truth", f"synthetic: f_h {truth['f_h']:g} Hz, xi_h {truth['xi_h']:g}, "
                                    f"f_b {truth['f_b']:g} Hz (what identification should recover)"))
    if record.floor_acc is not None:
        rows.append(("floor", f"floor acceleration recorded, RMS {_rms(record.floor_acc):.3g} m/s^2"))
    return _heading("Record") + "\n" + _rows(rows)


def demo_cycles_section(pre, rows: int = DEMO_TABLE_ROWS) -> str:
    """Cycles found: count, bouncing frequency, why some are invalid, a table head."""
    valid = pre.valid_cycles
    f_b = np.array([c.f_b for c in (valid or pre.cycles)])
    reasons = Counter(c.reason for c in pre.cycles if not c.valid)
    flagged = "; ".join(f"{n} {reason}" for reason, n in reasons.most_common()) or "none"
    lines = [
        _heading("Cycles (GRF peak to GRF peak, Section 4)"),
        _rows([
            ("cycles", f"{len(pre.cycles)} ({len(valid)} valid)"),
            ("bouncing freq.", f"median {np.median(f_b):.3f} Hz, range {f_b.min():.3f}-{f_b.max():.3f} Hz "
                               f"({'valid' if valid else 'all'} cycles)"),
            ("cycle length", f"median {np.median(1.0 / f_b):.3f} s"),
            ("flagged", flagged),
        ]),
        "",
        f"  {'cycle':>5}  {'start s':>7}  {'end s':>7}  {'samples':>7}  {'f_b Hz':>6}  status",
    ]
    for c in pre.cycles[:rows]:
        status = "valid" if c.valid else f"invalid: {c.reason}"
        lines.append(f"  {c.index:>5}  {c.t_start:>7.2f}  {c.t_end:>7.2f}  {c.n_samples:>7}  {c.f_b:>6.3f}  {status}")
    if len(pre.cycles) > rows:
        lines.append(f"  ... {len(pre.cycles) - rows} more (Preprocessed.cycle_table())")
    return "\n".join(lines)


def demo_signals_section(pre) -> str:
    """The derived COM signals (Eq. 3, high-pass, integration) as RMS values in SI units."""
    rows = [
        ("acceleration u''", _rms(pre.acc), "m/s^2", f"(GRF - M_h g) / M_h (Eq. 3), high-passed at {pre.cutoff:g} Hz"),
        ("velocity u'", _rms(pre.vel), "m/s", "integrated once, high-passed"),
        ("displacement u", _rms(pre.disp), "m",
         f"integrated twice, high-passed; peak to peak {np.ptp(pre.disp):.3f} m"),
        ("removed by high-pass", _rms(pre.acc_raw - pre.acc), "m/s^2", "offset and drift below the cut-off"),
    ]
    width = max(len(name) for name, *_ in rows)
    lines = [_heading("COM motion from the GRF (Section 3.2)"), f"  {'signal':<{width}}  {'RMS':>7}  {'unit':<5}  how"]
    lines += [f"  {name:<{width}}  {value:>7.3g}  {unit:<5}  {how}" for name, value, unit, how in rows]
    return "\n".join(lines)


def demo_model_section(model, fs: float) -> str:
    """The augmented-state model an estimator will fit, cycle by cycle."""
    opts = model.options
    params = [n for n in model.state_names if n not in ("u", "u_dot", "f_h", "xi_h")]
    coefficients = f"{params[0]}, {params[1]}, {params[2]}, ..., {params[-2]}, {params[-1]}" if len(params) > 5 \
        else ", ".join(params)
    discretisation = {"rk4": "classical Runge-Kutta (rk4)", "euler": "forward Euler (Eq. 11-12)"}[model.discretisation]
    lo, hi = opts["coefficient_range"]
    return _heading("Model to identify per cycle (augmented state, Eq. 7-16)") + "\n" + _rows([
        ("model", repr(model)),
        ("state X", f"u, u_dot | f_h, xi_h | {coefficients}  ({model.n_state} entries, Eq. 7)"),
        ("dynamics", "u'' = -w_h^2 u - 2 xi_h w_h u' + g [a0 + sum a_i cos + b_i sin]  (Eq. 2, 4, 10)"),
        ("discretised", f"{discretisation}, dt = 1/fs = {1.0 / fs:g} s; the article uses Euler"),
        ("observed", f"{', '.join(model.channels)} (Eq. 13-16), noise {model.observation_noise:.0%} of each RMS"),
        ("priors", f"f_h {opts['f_h_range'][0]:g}-{opts['f_h_range'][1]:g} Hz, "
                   f"xi_h {opts['xi_h_range'][0]:g}-{opts['xi_h_range'][1]:g}, "
                   f"coefficients {lo:g} to {hi:g} g (uniform)"),
        ("process noise", f"{model.process_noise:.0%} of each quantity's nominal value per step (Eq. 6)"),
        ("derived", "K_h (Eq. 17), C_h (Eq. 18) and BLF_i (Eq. 5) from f_h, xi_h, a_i, b_i"),
    ])


def demo_figure(pre, out_dir) -> Path:
    """Draw the pre-processing figure into ``out_dir/pipeline.png`` (creating ``out_dir``); return its path."""
    out_dir = Path(out_dir)
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OptionError(f"--out {out_dir}: cannot create the directory ({exc.strerror or exc})") from None
    path = out_dir / "pipeline.png"
    pre.plot(path)
    return path


def demo_person_section(record, out_dir, truth):
    """The answer first: the person from the whole record, with intervals, against the truth when known.

    Returns the text; writes ``person.json`` and the person's figures into ``out_dir/person``.
    """
    from ..person import identify_person
    from .person_output import write_person
    from .common import truth_values

    known = truth_values(truth)
    started = time.perf_counter()
    result = identify_person(record, progress=True)
    seconds = time.perf_counter() - started
    d = result.to_dict()
    pct = int(round(100 * result.level))

    def against(name, value):
        if name not in known:
            return ""
        truth_value = known[name]
        inside = "inside" if d[f"{name}_low"] <= truth_value <= d[f"{name}_high"] else "OUTSIDE"
        error = f"{100 * (value / truth_value - 1):+.1f} %" if name == "f_h" else f"{value - truth_value:+.3f}"
        return f"   truth {truth_value:.3g} ({error}, {inside} the interval)"

    rows = [
        ("f_h", f"{d['f_h']:.3f} Hz, {pct} % interval {d['f_h_low']:.2f}-{d['f_h_high']:.2f} Hz"
                + ("" if d["f_h_determined"] else " (not determined)") + against("f_h", d["f_h"])),
        ("xi_h", f"{d['xi_h']:.3f}, {pct} % interval {d['xi_h_low']:.2f}-{d['xi_h_high']:.2f}"
                 + ("" if d["xi_h_determined"] else " (not determined)") + against("xi_h", d["xi_h"])),
        ("K_h, C_h", f"{d['k_h']:.0f} N/m, {d['c_h']:.0f} N s/m (Eq. 17, 18)"),
        ("BLF (g)", ", ".join(f"{d[f'blf_{i}']:.3f} ± {d[f'blf_{i}_sd']:.3f}" for i in range(1, 5))),
        *([("BLF truth", ", ".join(f"{known[f'blf_{i}']:.3f}" for i in range(1, 5)))] if "blf_4" in known else []),
        ("innovations", f"Ljung-Box p {d['ljung_box_p']:.2g}: "
                        + ("white, the model explains the record" if d["ljung_box_p"] >= 0.01 else
                           "serially correlated: the model misses something (run diagnose)")),
    ]
    directory = Path(out_dir) / "person"
    directory.mkdir(parents=True, exist_ok=True)
    written = write_person(directory, result, {"variation": "auto", "timing": "model"}, truth=known or None)
    lines = [f"  identify_person(record): one f_h and xi_h from the whole record, {result.n_cycles} force cycles in "
             f"{result.record.duration:.0f} s, fitted in {seconds:.0f} s", _rows(rows)]
    lines += [f"  warning: {text}" for text in d["warnings"]]
    lines += [f"  wrote {directory / 'person.json'} and {len(written) - 1} more files (person_fit.png, ...)"]
    return _heading("The person, from the whole record (identify's default)") + "\n" + "\n".join(lines)


def demo_identification_section(pre, out_dir, truth, estimator: str = "ekf") -> str:
    """Identify every valid cycle (repeated passes, Section 3.2), compare with the truth, draw the figures."""
    from ..plotting.cycles import plot_convergence, plot_parameters
    from ..identify.runner import CycleRunner
    from .common import truth_values
    from .identify import run_summary, summary_table

    runner = CycleRunner(estimator=estimator, progress=True)
    started = time.perf_counter()
    table = runner.run(pre)
    seconds = time.perf_counter() - started
    known = truth_values(truth)
    out_dir.mkdir(parents=True, exist_ok=True)
    table.to_csv(out_dir / "results.csv", index=False)
    plot_parameters(table, out_dir / "parameters.png", truth=known)
    ok = table[table["status"] == "ok"]
    cycle = int(ok["cycle"].iloc[len(ok) // 2])
    plot_convergence(runner.history_[cycle], cycle, tolerance=runner.tolerance, path=out_dir / "convergence.png")
    summary = summary_table(table, known)
    lines = [f"  every cycle on its own, with its own force; estimator {estimator} (--estimator pf is the article's)",
             textwrap.fill(run_summary(table, seconds), width=96, initial_indent="  ", subsequent_indent="  "), ""]
    with pd.option_context("display.float_format", "{:.4g}".format, "display.width", 120):
        lines += ["  " + line for line in summary.to_string().splitlines()]
    lines += ["",
              "  determined_%: share of cycles whose posterior sd is under a quarter of the prior sd.",
              "  A nearly periodic cycle with a free Fourier force fits many f_h: most cycles do not",
              "  pin f_h down, and the table says so instead of printing a confident number. That is",
              "  why the person above is identified from the whole record.",
              f"  wrote {out_dir / 'results.csv'}, {out_dir / 'parameters.png'}, {out_dir / 'convergence.png'}"]
    return _heading("Per cycle, the article's method (Section 3.2), for comparison") + "\n" + "\n".join(lines)


DEMO_RECORD = "rec.csv"
"""Record that the first of the demo's next steps writes and the others read (in the current directory)."""


def demo_next_steps(out_dir=DEMO_OUT) -> str:
    """What to do next: commands that run exactly as printed, in order, from the current directory.

    The first writes a short synthetic record (8 s, so that each step takes
    seconds) that the next ones read; ``stats`` reads the demo's own
    ``results.csv`` in ``out_dir``. ``tests/test_suggestions.py`` runs every
    one of them.

    Parameters
    ----------
    out_dir : str or path-like
        The demo's output directory.

    Returns
    -------
    str
    """
    import shlex

    results = shlex.quote(str(Path(out_dir) / "results.csv"))
    rec, truth = DEMO_RECORD, DEMO_RECORD.replace(".csv", "_truth.json")
    steps = [
        (f"smd-statespace simulate --out {rec} --mass 70 --fb 2 --fh 2.5 --xi 0.3 --duration 8 --seed 1",
         f"a record with known truth ({truth})"),
        (f"smd-statespace identify {rec} --mass 70", "the person (person.json)"),
        (f"smd-statespace compare {rec} --mass 70 --truth {truth} --estimators record,ekf,ukf",
         "estimators side by side, the person beside the article's per-cycle filters"),
        (f"smd-statespace diagnose {rec} --mass 70 --candidate harmonics",
         "is an effect missing? (the person identified with it, tested by likelihood ratio)"),
        (f"smd-statespace stats {results} --bootstrap 20", "Section 5 on the demo's cycles"),
        ("smd-statespace crowd --people 50 --fb 2.5 --out crowd.csv", "crowd loads drawn from Table 2 (30 s)"),
        ("smd-statespace hsi --repeats 1 --duration 8 --max-passes 2", "Section 6, small (defaults: 10 x 30 s)"),
    ]
    lines = [line for command, what in steps for line in (f"  {what}:", f"    {command}")]
    lines.append("  your own record (a CSV or a force plate's export): identify REC --mass KG, or without --mass to "
                 "weigh the person on the plate; a whole study: identify FOLDER --manifest M.csv (docs/batch.md)")
    return (_heading("Next (each command runs as printed, in order, from this directory)") + "\n"
            + "\n".join(lines))


def run_demo(args) -> int:
    """Run ``smd-statespace demo``."""
    from ..model import SMDModel
    from ..signals import preprocess
    from ..simulation.bouncing import sample_path

    out_dir = demo_out_dir(args.out)
    if args.record is None:
        if args.mass is not None:
            raise OptionError("--mass is the mass of --record; the built-in sample's mass (70 kg) is known")
        record, truth = load_sample()
        where = f"{sample_path()} (built-in sample)"
    else:
        record, truth = load_record(args.record, args.mass)
        where = None
    pre = preprocess(record)
    print("smd-statespace demo: the SMD model of a bouncing person (Wang, Chen & Nagayama 2019), step by step")
    print(demo_record_section(record, truth, where))
    print("\n" + demo_person_section(record, out_dir, truth))
    print(_heading("How the article's per-cycle method sees the same record") + "\n  "
          "(the pre-processing, the augmented model and the identification of every cycle)")
    print(demo_cycles_section(pre))
    print(demo_signals_section(pre))
    print(demo_model_section(SMDModel(), record.fs))
    figure = demo_figure(pre, out_dir)
    print(_heading("Figure") + f"\n  {figure}\n  GRF and cycles, COM acceleration, velocity and displacement: "
          "whole record and a 3-cycle zoom")
    print(demo_identification_section(pre, out_dir, truth))
    print(demo_next_steps(out_dir))
    return 0
