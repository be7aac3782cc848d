"""Helpers shared by the command-line subcommands: argument types, effect specs, loading records."""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
from pathlib import Path

from ..errors import OptionError
from ..io import truth_values  # noqa: F401 - the commands import it from here

PROG = "smd-statespace"


def _one_line(text) -> str:
    """Collapse a message onto one line."""
    return " ".join(str(text).split())


def _fail(message) -> int:
    print(f"{PROG}: error: {_one_line(message)}", file=sys.stderr)
    return 2


def _number(text: str, accept, requirement: str) -> float:
    """A finite number for which ``accept(value)`` holds, or an argparse type error naming ``requirement``."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (math.isfinite(value) and accept(value)):
        raise argparse.ArgumentTypeError(f"must be {requirement}, got {text!r}")
    return value


def _positive(text: str) -> float:
    """argparse type: a finite number > 0."""
    return _number(text, lambda value: value > 0, "a positive number")


def _nonnegative(text: str) -> float:
    """argparse type: a finite number >= 0."""
    return _number(text, lambda value: value >= 0, "zero or a positive number")


def _whole(text: str, minimum: int, requirement: str) -> int:
    """A whole number >= ``minimum``, or an argparse type error naming ``requirement``."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be {requirement}, got {text!r}") from None
    if value < minimum:
        raise argparse.ArgumentTypeError(f"must be {requirement}, got {text!r}")
    return value


def _seed(text: str) -> int:
    """argparse type: a non-negative integer seed."""
    return _whole(text, 0, "a non-negative whole number")


def _numbers(text: str) -> tuple[float, ...]:
    """argparse type: comma-separated numbers, e.g. ``0.25,0.15,0.05,0.02``."""
    try:
        return tuple(float(part) for part in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be comma-separated numbers, got {text!r}") from None




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
    from ..io import read_record
    from ..simulation.bouncing import sample_path, sample_truth_path

    truth = json.loads(sample_truth_path().read_text(encoding="utf-8"))
    record = read_record(sample_path(), truth["mass"])
    return dataclasses.replace(record, source=sample_path().name), truth



def load_record(path, mass):
    """A user's record and, if ``<stem>_truth.json`` lies beside it (``simulate`` writes one), its truth."""
    from ..io import read_record

    from ..signals.weighing import weigh_record

    record = weigh_record(read_record(path, mass))  # no --mass: the plate weighs the person
    beside = Path(path).with_name(f"{Path(path).stem}_truth.json")
    if not beside.is_file():
        return record, None
    try:
        truth = json.loads(beside.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) else f"not valid JSON ({exc})"
        print(f"warning: {beside}: {reason}; the record is shown without its truth", file=sys.stderr)
        return record, None
    if not isinstance(truth, dict):
        print(f"warning: {beside}: not a truth file (a JSON object as simulate writes); the record is shown without "
              "its truth", file=sys.stderr)
        return record, None
    return record, truth


def _count(text: str) -> int:
    """argparse type: a whole number >= 1."""
    return _whole(text, 1, "a whole number >= 1")


def add_rate_argument(parser):
    """``--rate HZ``: the sample rate every estimator works at (0 keeps every sample)."""
    from ..signals import RECORD_RATE

    parser.add_argument("--rate", type=_nonnegative, default=RECORD_RATE, metavar="HZ",
                        help=f"a record sampled at twice this rate or faster is low-pass filtered and decimated to "
                             f"between HZ and 2 HZ before the fit (default {RECORD_RATE:g}: the article's rate, at "
                             "which the per-cycle noise settings and the record estimator's calibrated intervals "
                             "were set; 0 keeps every sample, slower)")


def add_noise_floor_argument(parser):
    """``--noise-floor FRACTION``: a quieter record is fitted with white noise added up to this share of body weight."""
    from ..person.noise_floor import MAX_NOISE_FLOOR, NOISE_FLOOR

    parser.add_argument("--noise-floor", type=_noise_floor, default=NOISE_FLOOR, metavar="FRACTION",
                        help=f"record estimator: a record whose noise per fitted sample is below this fraction of "
                             f"body weight (default {NOISE_FLOOR:g}: 1 %% BW, where the intervals were calibrated; "
                             f"0-{MAX_NOISE_FLOOR:g}) is fitted with white noise added up to it, seeded by the record, "
                             "so that a quiet plate does not let details of the force's variation that no model "
                             "describes set f_h and xi_h; 0 fits the record as measured")


FADE_CHOICES = {"auto": "auto", "on": True, "off": False}
"""``--fade``'s words and ``identify_person``'s ``fade`` values."""


def add_fade_argument(parser):
    """``--fade auto|on|off``: let the force's harmonics fade linearly over the record with the person."""
    parser.add_argument("--fade", choices=list(FADE_CHOICES), default="auto",
                        help="record estimator: let the force's harmonics fade (or grow) linearly over the "
                             "record by one factor (a person who tires; no search dimension is added): auto "
                             "(default) where the record was trimmed to a bout of bouncing (standing before and "
                             "after), on for any record, off never")


def _noise_floor(text):
    """argparse type of ``--noise-floor`` (:func:`~smd_statespace.person.noise_floor.check_noise_floor`)."""
    from ..person.noise_floor import MAX_NOISE_FLOOR, check_noise_floor

    try:
        return check_noise_floor(float(text))
    except (ValueError, OptionError):
        raise argparse.ArgumentTypeError(f"{text!r} is not a fraction of body weight from 0 to {MAX_NOISE_FLOOR:g} "
                                         "(e.g. 0.01 for 1 % BW; 0 fits the record as measured)") from None


def add_span_argument(parser, each=False):
    """``--span START:END|auto|all`` (``each``: also ``each``, every bout): the part of the record the person is
    identified from."""
    parser.add_argument("--span", type=_span_or_each if each else _span, default="auto", metavar="START:END",
                        help="record estimator: the part of the record to identify the person from, in s on the "
                             "record's time axis (e.g. 4.5:33); auto (default) finds the steady bouncing of a lab's "
                             "export (standing before and after, ramps, mains hum) and says what it kept; all: the "
                             "whole record as it is" + ("; each: every bout of bouncing, a person each (a session "
                                                        "at several tempos: DIR/bouts.csv, person_bouts.png and "
                                                        "DIR/bout_N/)" if each else ""))


def _span_or_each(text):
    """argparse type of ``identify --span``: :func:`_span`'s, or ``each``."""
    return "each" if str(text).strip().lower() == "each" else _span(text)


def _span(text):
    """argparse type of ``--span`` (:func:`~smd_statespace.signals.parse_span`)."""
    from ..signals import parse_span

    try:
        return parse_span(text)
    except OptionError as exc:
        raise argparse.ArgumentTypeError(str(exc).replace("--span ", "", 1)) from None


def rate_of(args):
    """``--rate`` as :func:`~smd_statespace.person.identify_person` takes it: None for 0."""
    return args.rate or None


MASS_HELP = ("body mass M_h (kg); without it a force plate's record weighs the person: the mean force while "
             "standing still before bouncing, else over its whole bouncing cycles, over g")


def add_record_arguments(parser, accelerometer=False):
    """``REC.csv --mass KG``: the record to identify (``accelerometer``: also ``--accelerometer``, ``--units``), and
    how to read a plate's export (:func:`add_export_arguments`)."""
    parser.add_argument("record", metavar="REC.csv", help="record with columns time,force[,floor_acc], or a force "
                        "plate's export (Vicon Nexus, Kistler BioWare, Qualisys, OpenSim, C3D, ...)")
    parser.add_argument("--mass", type=float, metavar="KG", help=MASS_HELP + (
        "; optional with --accelerometer (K_h, C_h need it)" if accelerometer else ""))
    add_export_arguments(parser)
    if accelerometer:
        add_accelerometer_arguments(parser)


def add_export_arguments(parser):
    """``--fs`` and ``--force-columns``: how to read a force plate's export that does not say it all itself."""
    parser.add_argument("--fs", type=float, metavar="HZ",
                        help="a plate export's sampling rate, for one without a time column or a rate above its "
                             "header (AMTI NetForce's text files): its rows are counted at HZ")
    parser.add_argument("--force-columns", metavar="NAME,...",
                        help="a plate export's vertical force columns, by name or number (1: the first), summed "
                             "(default: the columns named as a plate's vertical force: Fz, FZ1, Force_Z, ...)")


def reading_options(args) -> dict:
    """``fs`` and ``force_columns`` of :func:`~smd_statespace.io.read_record` from ``--fs`` and ``--force-columns``,
    or a one-line :class:`OptionError`."""
    fs, columns = getattr(args, "fs", None), getattr(args, "force_columns", None)
    if fs is not None and not (math.isfinite(fs) and fs > 0):
        raise OptionError(f"--fs {fs:g}: a sampling rate must be a positive number of Hz")
    if columns is not None:
        columns = [name.strip() for name in columns.split(",")]
        if not all(columns):
            raise OptionError(f"--force-columns {args.force_columns!r}: expected names or numbers separated by commas")
    if (fs is not None or columns is not None) and getattr(args, "accelerometer", False):
        raise OptionError(f"{'--fs' if fs is not None else '--force-columns'} reads a force plate's export, not a "
                          "phone's (--accelerometer)")
    return {"fs": fs, "force_columns": columns}


def add_accelerometer_arguments(parser):
    """``--accelerometer`` and ``--units``: the record is a body-worn accelerometer's (record-level model)."""
    parser.add_argument("--accelerometer", action="store_true",
                        help="REC is a body-worn accelerometer's CSV (phyphox's export, time,ax,ay,az or time,acc, "
                             "gravity included) instead of a force plate's: the vertical is taken from the record's "
                             "own gravity, the clock made uniform (record-level model only; --mass optional, K_h "
                             "and C_h need it; a folder, glob or manifest of phones' records is a batch)")
    parser.add_argument("--units", choices=("auto", "m/s^2", "g"), default=None,
                        help="with --accelerometer: units of a plain CSV (default auto: from gravity's size)")


def check_record_level_options(args, floor_elsewhere: str):
    """One-line errors for the record-level model's own options given with a per-cycle ``--estimator``.

    ``--accelerometer`` and ``--units`` read a phone's record, which only the record-level model takes;
    ``--no-floor`` leaves out the measured floor that only it adds by default (``floor_elsewhere``: what the
    command's per-cycle estimators do with a floor instead).
    """
    if args.estimator in (None, "record"):
        return
    accelerometer, units = getattr(args, "accelerometer", False), getattr(args, "units", None)
    if accelerometer or units is not None:
        option = "--accelerometer" if accelerometer else "--units"
        raise OptionError(f"{option} works with the record-level model (--estimator record), not "
                          f"--estimator {args.estimator}")
    if getattr(args, "fade", "auto") != "auto":
        raise OptionError(f"--fade {args.fade} applies to the record-level model (--estimator record); --estimator "
                          f"{args.estimator} fits every cycle's own force")
    if getattr(args, "no_floor", False):
        raise OptionError(f"--no-floor applies to the record-level model (--estimator record), which adds a record's "
                          f"measured floor by default; --estimator {args.estimator} {floor_elsewhere}")


def read_person_record(args):
    """The record of ``args``: a force plate's (``--mass`` needed) or, with ``--accelerometer``, a phone's."""
    from ..io import read_record

    if args.units is not None and not args.accelerometer:
        raise OptionError("--units applies to an accelerometer record (--accelerometer)")
    options = reading_options(args)
    if args.accelerometer:
        from ..accelerometer import accelerometer_record

        return accelerometer_record(args.record, args.mass, units=args.units or "auto")
    from ..signals.weighing import weigh_record

    return weigh_record(read_record(args.record, args.mass, **options))  # no --mass: the plate weighs the person


def add_check_argument(parser):
    """``--ignore-checks``: identify a record that the bouncing checks refuse."""
    parser.add_argument("--ignore-checks", action="store_true",
                        help="identify even a record that is not bouncing (contact lost, clipped, not rhythmic, "
                             "walking); the checks' findings are printed as warnings")


def checked(record, args) -> list:
    """Check that ``record`` is bouncing (:func:`~smd_statespace.applicability.check_bouncing`); print warnings.

    Raises :class:`~smd_statespace.applicability.NotBouncingError` (exit 2)
    for a refusal unless ``--ignore-checks``; returns the warnings.
    """
    import sys

    from ..applicability import check_bouncing

    warnings = check_bouncing(record).raise_if_refused(override=getattr(args, "ignore_checks", False))
    for text in warnings:
        print(f"warning: {text}", file=sys.stderr)
    return warnings


def add_model_arguments(parser):
    """Options that build the :class:`~smd_statespace.model.SMDModel`."""
    parser.add_argument("--harmonics", type=_count, default=4, metavar="N",
                        help="Fourier harmonics of the biomechanical force (default 4, as the article)")
    parser.add_argument("--discretisation", choices=("rk4", "euler"), default="rk4",
                        help="transition: rk4 (default) or euler (the article's Eq. 11-12)")
    parser.add_argument("--effect", action="append", default=[], metavar="NAME[:key=value,...]",
                        help="physical effect added to the model, repeatable (e.g. harmonics:count=2, cubic_stiffness)")


def add_run_arguments(parser):
    """Options of the cycle runner shared by ``identify`` and ``compare``."""
    parser.add_argument("--particles", type=_count, metavar="N",
                        help="particles of pf (default 5000, as the article) or rbpf (default 300)")
    parser.add_argument("--max-passes", type=_count, default=8, metavar="N",
                        help="largest number of repeated passes per cycle (default 8)")
    parser.add_argument("--seed", type=_seed, default=0, metavar="S", help="random seed (default 0)")
    parser.add_argument("--out", default="smd_output", metavar="DIR", help="output directory (default ./smd_output)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    add_check_argument(parser)


def person_effects(args) -> list:
    """``--effect`` as the record-level person takes it: the specs themselves, each checked first (one line before
    anything is read).

    A bare registered name then configures itself for the record
    (:func:`~smd_statespace.person.extend.configured_for_record`: a cubic spring's range scaled to the record's
    displacement), as ``identify FOLDER`` and the library have it. An effect made here would keep its class's
    default (a cubic spring's +-1000 1/m^2, on which a strong spring ends): until 2026-12-01 ``identify REC
    --effect cubic_stiffness`` and ``diagnose REC --effect cubic_stiffness`` searched that default range.
    """
    build_model(args)
    return [spec.strip() for spec in args.effect]


def build_model(args):
    """The model the options describe."""
    from ..effects import make_effect
    from ..model import SMDModel

    effects = [make_effect(spec) for spec in args.effect]
    return SMDModel(n_harmonics=args.harmonics, discretisation=args.discretisation, effects=effects)


def estimator_options(name: str, args) -> dict:
    """Estimator keyword options from the command line (only those the estimator takes)."""
    if args.particles is not None and name in ("pf", "rbpf"):
        return {"n_particles": args.particles}
    return {}


def prepare_record(args):
    """Read, check, decimate (``--rate``) and preprocess ``args.record``; returns ``(Record, Preprocessed)``.

    How an export was read and the decimation are said on standard output in ``note:`` lines.
    """
    from ..io import read_record
    from ..signals import decimate_record, decimation_note, preprocess
    from ..signals.weighing import weigh_record

    record = weigh_record(read_record(args.record, args.mass, **reading_options(args)))
    checked(record, args)
    measured_rate = record.fs
    record, factor, _ = decimate_record(record, rate_of(args))
    for note in (*record.extra.get("reading", ()), *decimation_note(measured_rate, record, factor, rate_of(args))):
        print(f"note: {note}")
    return record, preprocess(record)


CREATED: list = []
"""Output directories (and their parents) this command created: :func:`remove_empty_outputs` takes back those still
empty when the command stops on bad input."""


def out_dir(path) -> Path:
    """Create (if needed) and return the output directory, failing clearly when it cannot be one."""
    directory = Path(path)
    if directory.exists() and not directory.is_dir():
        raise OptionError(f"--out {directory}: exists and is not a directory")
    missing = [folder for folder in (directory, *directory.parents) if not folder.exists()]
    directory.mkdir(parents=True, exist_ok=True)
    CREATED.extend(missing)  # the deepest first
    return directory


def remove_empty_outputs() -> None:
    """Remove the output directories this command created and left empty (a command stopped by bad input after
    making its ``--out`` folder, e.g. an option that only the fit can refuse): nothing written is touched."""
    for directory in CREATED:
        try:
            directory.rmdir()  # only an empty directory
        except OSError:
            pass
    CREATED.clear()


def load_truth(path):
    """A truth JSON (as ``simulate`` writes) or ``None``."""
    if path is None:
        return None
    try:
        return json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as exc:
        raise OptionError(f"--truth {path}: cannot read ({exc.strerror or exc})") from None
    except ValueError:
        raise OptionError(f"--truth {path}: not a JSON file") from None
