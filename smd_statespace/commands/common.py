"""Helpers shared by the command-line subcommands: argument types, effect specs, loading records."""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
from pathlib import Path

from ..errors import OptionError

PROG = "smd-statespace"


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
    from ..simulate import sample_path, sample_truth_path

    truth = json.loads(sample_truth_path().read_text(encoding="utf-8"))
    record = read_record(sample_path(), truth["mass"])
    return dataclasses.replace(record, source=sample_path().name), truth



def load_record(path, mass):
    """A user's record and, if ``<stem>_truth.json`` lies beside it (``simulate`` writes one), its truth."""
    from ..io import read_record

    if mass is None:
        raise OptionError(f"--record {path}: give the body mass with --mass KG")
    record = read_record(path, mass)
    beside = Path(path).with_name(f"{Path(path).stem}_truth.json")
    try:
        truth = json.loads(beside.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        truth = None
    return record, truth
