"""The ``smd-statespace`` command line (also ``python -m smd_statespace``).

:mod:`.main` holds the parser and the entry point; every command is a module of its own
(:mod:`.simulate`, :mod:`.demo`, :mod:`.identify`, :mod:`.compare`, :mod:`.diagnose`,
:mod:`.stats`, :mod:`.crowd`, :mod:`.hsi`) with an ``add_NAME`` and a ``run_NAME``;
:mod:`.common` holds what they share.
"""

from .main import COMMANDS, UsageError, build_parser, main

__all__ = ["COMMANDS", "UsageError", "build_parser", "main"]
