"""The progress bar every long run shows: on a terminal or in a notebook, never into a log or a pipe.

``tqdm.auto`` picks the notebook widget inside Jupyter, but without ipywidgets
installed it warns ("IProgress not found") on every bar. This module gives the
widget bar only when ipywidgets is importable, else the plain text bar, which
Jupyter shows as well; no warning either way.

A bar asked for (``disable=False``) is drawn only where someone watches it: when
its stream (standard error by default) is a terminal, or inside a Jupyter
kernel. Written into a log file or a pipe, a bar is hundreds of carriage-return
lines that bury the messages; there it is left out (tqdm's own ``disable=None``
rule, applied to every bar of the package).
"""

from __future__ import annotations

import importlib.util
import sys

if importlib.util.find_spec("ipywidgets") is not None:
    from tqdm.auto import tqdm as _tqdm
else:
    from tqdm.std import tqdm as _tqdm

__all__ = ["tqdm", "watched"]


def watched(stream=None) -> bool:
    """Whether a bar written to ``stream`` (default standard error) is seen: a terminal, or a Jupyter kernel."""
    if "ipykernel" in sys.modules:
        return True
    stream = sys.stderr if stream is None else stream
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False


class tqdm(_tqdm):
    """tqdm's bar, drawn only where it is watched (:func:`watched`); otherwise as tqdm's ``disable=True``."""

    def __init__(self, *args, disable=False, file=None, **kwargs):
        super().__init__(*args, disable=disable or not watched(file), file=file, **kwargs)
