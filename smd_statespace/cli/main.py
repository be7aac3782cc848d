"""The ``smd-statespace`` command line (also ``python -m smd_statespace``).

Every subcommand is a pair of functions: ``add_NAME(subparsers)`` declares
its options and returns the subparser, ``run_NAME(args) -> int`` runs it.
The pairs are listed in :data:`COMMANDS`; a new subcommand is one more pair
appended there, nothing else changes.

Errors: every :class:`~smd_statespace.errors.SMDInputError` and every usage
error becomes one line on stderr, ``smd-statespace: error: <message>``, and
exit status 2; success is 0.

============= ================================================================
command       what it does
============= ================================================================
``simulate``  write a synthetic GRF record (Eq. 2-4) and the truth behind it
``demo``      the pipeline on the shipped sample: record, cycles, COM signals
              (Eq. 3), the augmented-state model (Eq. 7-16) and a figure
``stats``     population statistics of many identified cycles: bands, Eq. 19
              skew-normal fits in the layout of Table 2, trends (Section 5)
``crowd``     crowd load: N people drawn from Table 2, each one's GRF (SMD
              model, rigid floor) and the total force, spectrum, figure
``hsi``       human-structure interaction (Section 6): one person on the
              Table 3 plate vs a rigid floor, identified, against Table 4
``structure`` a crowd of SMD people on a structure's modes (modes.csv,
              shapes.csv): occupied modes, responses coupled vs force-only
============= ================================================================
"""

from __future__ import annotations

import argparse
import os
import sys

from .. import __version__
from . import compare, crowd, demo, diagnose, hsi, identify, simulate, stats, structure
from .common import CREATED, PROG, remove_empty_outputs
from ..effects import load_effects_file, load_installed_effects
from ..errors import SMDInputError


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


# ---------------------------------------------------------------------------
# Registry and entry point
# ---------------------------------------------------------------------------

COMMANDS = [
    (simulate.add_simulate, simulate.run_simulate),
    (demo.add_demo, demo.run_demo),
    (identify.add_identify, identify.run_identify),
    (compare.add_compare, compare.run_compare),
    (diagnose.add_diagnose, diagnose.run_diagnose),
    (stats.add_stats, stats.run_stats),
    (crowd.add_crowd, crowd.run_crowd),
    (hsi.add_hsi, hsi.run_hsi),
    (structure.add_structure, structure.run_structure),
]
"""``(add, run)`` pairs, one per subcommand, in the order ``--help`` lists them."""


EFFECTS_HELP = ("a Python file that registers physical effects (@register_effect), repeatable, before or after the "
                "command; the command then knows them by name")


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser with every subcommand of :data:`COMMANDS`."""
    parser = _Parser(
        prog=PROG,
        description="Identify the spring-mass-damper model of a bouncing person from ground reaction forces "
                    "(Wang, Chen & Nagayama, J. Sound Vib. 456, 2019).",
    )
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    parser.add_argument("--effects", action="append", default=[], metavar="FILE.py", help=EFFECTS_HELP)
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for add, run in COMMANDS:
        command = add(subparsers)
        # the same option after the command (its own destination: a subcommand's default would overwrite the
        # value given before the command); main joins the two lists
        command.add_argument("--effects", action="append", default=[], dest="command_effects", metavar="FILE.py",
                             help=EFFECTS_HELP)
        command.set_defaults(run=run)
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
    args.effects = [*args.effects, *getattr(args, "command_effects", [])]
    CREATED.clear()
    try:
        load_installed_effects()
        for path in args.effects:
            load_effects_file(path)
        return args.run(args)
    except SMDInputError as exc:
        remove_empty_outputs()
        return _fail(exc)
    except KeyboardInterrupt:
        remove_empty_outputs()
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
