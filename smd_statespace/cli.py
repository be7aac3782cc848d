"""The ``smd-statespace`` command line (also ``python -m smd_statespace``).

Every subcommand is a pair of functions: ``add_NAME(subparsers)`` declares
its options and returns the subparser, ``run_NAME(args) -> int`` runs it.
The pairs are listed in :data:`COMMANDS`; a new subcommand is one more pair
appended there, nothing else changes.

Errors: every :class:`~smd_statespace.errors.SMDInputError` and every usage
error becomes one line on stderr, ``smd-statespace: error: <message>``, and
exit status 2; success is 0.

============ ================================================================
command      what it does
============ ================================================================
``simulate`` write a synthetic GRF record (Eq. 2-4) and the truth behind it
``demo``     the pipeline on the shipped sample: record, cycles, COM signals
             (Eq. 3), the augmented-state model (Eq. 7-16) and a figure
============ ================================================================
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import sys
from collections import Counter
from pathlib import Path

import numpy as np

from . import __version__
from .errors import OptionError, SMDInputError

PROG = "smd-statespace"


# ---------------------------------------------------------------------------
# Parser plumbing: usage errors are exceptions, not exits
# ---------------------------------------------------------------------------


class UsageError(Exception):
    """A command-line usage error (unknown option, missing argument, bad value)."""

    def __init__(self, message: str, command: str):
        super().__init__(message)
        self.command = command


class _Parser(argparse.ArgumentParser):
    """ArgumentParser that raises :class:`UsageError` instead of printing usage and exiting."""

    def error(self, message):
        raise UsageError(message, self.prog)


def _one_line(text) -> str:
    """Collapse a message onto one line."""
    return " ".join(str(text).split())


def _fail(message) -> int:
    print(f"{PROG}: error: {_one_line(message)}", file=sys.stderr)
    return 2


def _positive(text: str) -> float:
    """argparse type: a finite number > 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a positive number, got {text!r}")
    return value


def _nonnegative(text: str) -> float:
    """argparse type: a finite number >= 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"must be zero or a positive number, got {text!r}")
    return value


def _seed(text: str) -> int:
    """argparse type: a non-negative integer seed."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a non-negative whole number, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be a non-negative whole number, got {text!r}")
    return value


def _numbers(text: str) -> tuple[float, ...]:
    """argparse type: comma-separated numbers, e.g. ``0.25,0.15,0.05,0.02``."""
    try:
        return tuple(float(part) for part in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be comma-separated numbers, got {text!r}") from None


# ---------------------------------------------------------------------------
# simulate
# ---------------------------------------------------------------------------


def parse_effect(spec: str) -> tuple[str, dict]:
    """Parse ``NAME[:key=value,key=value]`` into ``(name, {key: value})``.

    Values are numbers; a tuple is written ``a/b`` (e.g. ``blf=0.04/0.03``).
    Names and keys are checked by the simulator, not here.

    Examples
    --------
    >>> parse_effect("floor_mode:frequency=3.48,modal_mass=8583")
    ('floor_mode', {'frequency': 3.48, 'modal_mass': 8583.0})
    >>> parse_effect("harmonics:blf=0.04/0.03")
    ('harmonics', {'blf': (0.04, 0.03)})
    """
    name, _, rest = spec.partition(":")
    name = name.strip()
    if not name:
        raise OptionError(f"--effect {spec!r}: give an effect name, e.g. floor_mode or harmonics:blf=0.04/0.03")
    params = {}
    for item in filter(None, (part.strip() for part in rest.split(","))):
        key, eq, value = item.partition("=")
        key = key.strip()
        if not eq or not key:
            raise OptionError(f"--effect {spec!r}: {item!r} must look like key=value")
        try:
            numbers = tuple(float(part) for part in value.split("/"))
        except ValueError:
            raise OptionError(
                f"--effect {spec!r}: value {value.strip()!r} of {key!r} is not a number (write a tuple as a/b)"
            ) from None
        params[key] = numbers if "/" in value else numbers[0]
    return name, params


def add_simulate(subparsers):
    """Declare ``smd-statespace simulate``."""
    parser = subparsers.add_parser(
        "simulate",
        help="write a synthetic GRF record with known truth",
        description=(
            "Simulate one person bouncing (SMD model, Eq. 2; Fourier force, Eq. 4; GRF by Eq. 3 plus noise) "
            "and write the record as CSV (time,force[,floor_acc]) and the truth as JSON."
        ),
    )
    parser.add_argument("--out", required=True, metavar="CSV", help="record file to write")
    parser.add_argument("--truth", metavar="JSON", help="truth file (default: <out stem>_truth.json beside it)")
    parser.add_argument("--mass", required=True, type=float, metavar="KG", help="body mass M_h (kg)")
    parser.add_argument("--fb", required=True, type=_positive, metavar="HZ", help="bouncing frequency f_b (Hz)")
    parser.add_argument("--fh", required=True, type=_positive, metavar="HZ", help="SMD natural frequency f_h (Hz)")
    parser.add_argument("--xi", required=True, type=_positive, metavar="RATIO", help="SMD damping ratio xi_h")
    parser.add_argument("--duration", required=True, type=_positive, metavar="S", help="record length (s)")
    parser.add_argument("--fs", type=_positive, default=100.0, metavar="HZ", help="sampling frequency (default 100)")
    parser.add_argument("--noise", type=_nonnegative, default=0.01, metavar="BW",
                        help="GRF noise SD as a fraction of body weight (default 0.01)")
    parser.add_argument("--seed", type=_seed, metavar="N",
                        help="random seed (default: fresh entropy, recorded in the truth file)")
    parser.add_argument("--blf", type=_numbers, metavar="G,G,...",
                        help="harmonic amplitudes BLF_1..BLF_n in g (default 0.25,0.15,0.05,0.02)")
    parser.add_argument("--fb-variation", type=_nonnegative, default=0.02, metavar="FRAC",
                        help="cycle-to-cycle relative SD of f_b (default 0.02)")
    parser.add_argument("--coef-variation", type=_nonnegative, default=0.10, metavar="FRAC",
                        help="cycle-to-cycle relative SD of the force harmonics (default 0.10)")
    parser.add_argument("--effect", action="append", default=[], metavar="NAME[:key=value,...]",
                        help="physical effect, repeatable: floor_mode, harmonics, cubic_stiffness "
                             "(e.g. floor_mode:frequency=3.48 or harmonics:blf=0.04/0.03)")
    return parser


def run_simulate(args) -> int:
    """Run ``smd-statespace simulate``."""
    from .io import check_mass
    from .simulate import DEFAULT_BLF, simulate_bouncing

    mass = check_mass(args.mass, source="--mass")
    effects = {}
    for spec in args.effect:
        name, params = parse_effect(spec)
        if name in effects:
            raise OptionError(f"--effect {name!r} is given twice; give each effect once")
        effects[name] = params
    out = Path(args.out)
    truth = None if args.truth is None else Path(args.truth)
    for label, path in (("--out", out), ("--truth", truth)):
        if path is not None and not path.parent.is_dir():
            raise OptionError(f"{label} {path}: directory {path.parent} does not exist")
    try:
        synthetic = simulate_bouncing(
            mass=mass,
            f_b=args.fb,
            f_h=args.fh,
            xi_h=args.xi,
            duration=args.duration,
            fs=args.fs,
            blf=DEFAULT_BLF if args.blf is None else args.blf,
            fb_variation=args.fb_variation,
            coef_variation=args.coef_variation,
            noise=args.noise,
            effects=effects or None,
            seed=args.seed,
        )
    except SMDInputError as exc:
        # The simulator names itself ("simulate_bouncing: ..."); on the command line that is noise.
        raise type(exc)(str(exc).replace("simulate_bouncing: ", "", 1)) from None
    csv_path, truth_path = synthetic.write(out, truth)
    record, info = synthetic.record, synthetic.truth
    extra = f", effects {', '.join(effects)}" if effects else ""
    seed = f"seed {info['seed']}" if args.seed is not None else "random seed (in the truth file)"
    print(
        f"wrote {csv_path}: {record.duration:.2f} s at {record.fs:g} Hz, {info['n_cycles']} force cycles "
        f"(f_b {args.fb:g} Hz, f_h {args.fh:g} Hz, xi_h {args.xi:g}, {seed}{extra}); truth in {truth_path}"
    )
    return 0


# ---------------------------------------------------------------------------
# demo
# ---------------------------------------------------------------------------

DEMO_OUT = "smd_demo_output"
"""Default output directory of ``smd-statespace demo`` (in the current directory)."""

DEMO_TABLE_ROWS = 6
"""Cycles shown in the demo's per-cycle table."""


def add_demo(subparsers):
    """Declare ``smd-statespace demo``."""
    parser = subparsers.add_parser(
        "demo",
        help="run the pipeline on the built-in sample record and explain each step",
        description=(
            "Read the shipped sample record (synthetic, 70 kg, bouncing at 2 Hz) or your own, turn its GRF "
            "into COM acceleration, velocity and displacement (Eq. 3), split it into cycles, show the model "
            "to be identified (Eq. 7-16) and draw the pipeline figure."
        ),
    )
    parser.add_argument("--out", default=DEMO_OUT, metavar="DIR",
                        help=f"directory for the figure (default ./{DEMO_OUT})")
    parser.add_argument("--record", metavar="CSV",
                        help="your own record (time,force[,floor_acc]) instead of the built-in sample; needs --mass")
    parser.add_argument("--mass", type=float, metavar="KG", help="body mass (kg) of --record")
    return parser


def demo_out_dir(out) -> Path:
    """Check the demo's output directory before any work, so a bad ``--out`` fails fast.

    The directory is created only when the figure is written (:func:`demo_figure`).
    """
    out_dir = Path(out)
    if out_dir.exists() and not out_dir.is_dir():
        raise OptionError(f"--out {out_dir}: exists and is not a directory")
    return out_dir


def load_sample():
    """The shipped sample record and its truth: ``(Record, dict)``.

    The record's ``source`` is shortened to the file name for titles; the
    mass comes from ``sample_truth.json``.
    """
    from .io import read_record
    from .simulate import sample_path, sample_truth_path

    truth = json.loads(sample_truth_path().read_text(encoding="utf-8"))
    record = read_record(sample_path(), truth["mass"])
    return dataclasses.replace(record, source=sample_path().name), truth


def load_record(path, mass):
    """A user's record and, if ``<stem>_truth.json`` lies beside it (``simulate`` writes one), its truth."""
    from .io import read_record

    if mass is None:
        raise OptionError(f"--record {path}: give the body mass with --mass KG")
    record = read_record(path, mass)
    beside = Path(path).with_name(f"{Path(path).stem}_truth.json")
    try:
        truth = json.loads(beside.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        truth = None
    return record, truth


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
    from .io import G

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


def demo_next_steps() -> str:
    """What comes after pre-processing."""
    return _heading("Next stages") + "\n" + "\n".join([
        "  Identification runs an estimator over every valid cycle, repeating passes until",
        "  f_h, xi_h and the force coefficients change by less than 5 % (Section 4):",
        "  particle filter (the article's, 5000 particles), UKF, EKF, or an exact grid",
        "  reference (`smd-statespace identify`). Model diagnosis then checks the fitted",
        "  model against the measurement (residuals, spectra, missing effects such as a",
        "  vibrating floor or a nonlinear leg spring).",
    ])


def run_demo(args) -> int:
    """Run ``smd-statespace demo``."""
    from .model import SMDModel
    from .signals import preprocess
    from .simulate import sample_path

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
    print(demo_cycles_section(pre))
    print(demo_signals_section(pre))
    print(demo_model_section(SMDModel(), record.fs))
    figure = demo_figure(pre, out_dir)
    print(_heading("Figure") + f"\n  {figure}\n  GRF and cycles, COM acceleration, velocity and displacement: "
          "whole record and a 3-cycle zoom")
    print(demo_next_steps())
    return 0


# ---------------------------------------------------------------------------
# Registry and entry point
# ---------------------------------------------------------------------------

COMMANDS = [
    (add_simulate, run_simulate),
    (add_demo, run_demo),
]
"""``(add, run)`` pairs, one per subcommand, in the order ``--help`` lists them."""


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser with every subcommand of :data:`COMMANDS`."""
    parser = _Parser(
        prog=PROG,
        description="Identify the spring-mass-damper model of a bouncing person from ground reaction forces "
                    "(Wang, Chen & Nagayama, J. Sound Vib. 456, 2019).",
    )
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for add, run in COMMANDS:
        add(subparsers).set_defaults(run=run)
    return parser


def main(argv=None) -> int:
    """Run the command line with ``argv`` (default ``sys.argv[1:]``); return the exit status."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except UsageError as exc:
        hint = f" (see '{exc.command} --help')"
        return _fail(f"{exc}{hint}")
    except SystemExit as exc:  # --help and --version
        return exc.code if isinstance(exc.code, int) else 0
    if args.command is None:
        names = ", ".join(choice for choice in parser._subparsers._group_actions[0].choices)
        return _fail(f"choose a command: {names} (see '{PROG} --help')")
    try:
        return args.run(args)
    except SMDInputError as exc:
        return _fail(exc)
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # output piped into e.g. `head`, which stopped reading
        try:
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        except (OSError, ValueError, AttributeError):
            pass
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
