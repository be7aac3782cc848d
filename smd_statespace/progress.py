"""The progress bar every long run shows: tqdm's notebook bar where it can draw, its plain bar elsewhere.

``tqdm.auto`` picks the notebook widget inside Jupyter, but without ipywidgets
installed it warns ("IProgress not found") on every bar. This module gives the
widget bar only when ipywidgets is importable, else the plain text bar, which
Jupyter shows as well; no warning either way.
"""

from __future__ import annotations

import importlib.util

__all__ = ["tqdm"]

if importlib.util.find_spec("ipywidgets") is not None:
    from tqdm.auto import tqdm
else:
    from tqdm.std import tqdm
