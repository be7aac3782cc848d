"""A table of people (one record-level person per record) against the bouncing frequency.

``identify FOLDER --estimator record`` writes one row per record: ``f_h``, ``xi_h`` with
their interval ends (``f_h_low``, ``f_h_high``), the load factors with their sds. This
figure draws each person as one point with its interval, the way the article's Fig. 6-8
draw parameters against ``f_b``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from ..identify.plausibility import flagged
from .cycles import DPI, PARAMETER_LABELS
from .save import save

__all__ = ["plot_people"]

MAX_LABELLED = 12
"""Most people whose record names are written beside their points (in the first panel)."""


def _error_bars(ok: pd.DataFrame, name: str) -> tuple[np.ndarray, str]:
    """Asymmetric bars from the interval columns where the table has them, else ±1 sd (and which it is)."""
    low, high = f"{name}_low", f"{name}_high"
    values = ok[name].to_numpy(dtype=float)
    if low in ok and high in ok:
        below = np.clip(values - ok[low].to_numpy(dtype=float), 0, None)
        above = np.clip(ok[high].to_numpy(dtype=float) - values, 0, None)
        level = ok["interval_level"].iloc[0] if "interval_level" in ok and len(ok) else 0.9
        return np.vstack([below, above]), f"{float(level):.0%} interval"
    sd = ok.get(f"{name}_sd", pd.Series(np.zeros(len(ok)), index=ok.index)).to_numpy(dtype=float)
    return np.vstack([sd, sd]), "±1 sd"


def plot_people(table: pd.DataFrame, path=None, names=("f_h", "xi_h", "blf_1", "blf_2"), title=None) -> Figure:
    """Each identified person as one point with its interval, against its bouncing frequency.

    Parameters
    ----------
    table : pandas.DataFrame
        One row per record, as ``results.csv`` of ``identify FOLDER --estimator record``
        (columns ``status``, ``f_b`` (Hz), the parameters and ``<name>_low``/``<name>_high``
        or ``<name>_sd``, ``<name>_determined``, ``implausible``; ``label`` or ``record`` names the points when
        there are few). Rows whose status is not ``ok`` are left out.
    path : str or Path, optional
        PNG file to write.
    names : sequence of str
        Parameters drawn, one panel each (those the table lacks are skipped).
    title : str, optional
        The figure's title (default: one person per record, and how many).

    Returns
    -------
    matplotlib.figure.Figure
    """
    ok = table[table["status"] == "ok"]
    names = [n for n in names if n in ok]
    fig = Figure(figsize=(9.0, 1.9 * len(names) + 0.7))
    axes = fig.subplots(len(names), 1, sharex=True, squeeze=False)[:, 0]
    f_b = ok["f_b"].to_numpy(dtype=float)
    bad = flagged(ok)
    for ax, name in zip(axes, names):
        bars, kind = _error_bars(ok, name)
        determined = flagged(ok, f"{name}_determined") if f"{name}_determined" in ok else np.ones(len(ok), bool)
        for mask, style in ((determined & ~bad, dict(color="tab:blue", mfc="tab:blue", label=f"determined ({kind})")),
                            (~determined & ~bad, dict(color="0.55", mfc="white", label="not determined")),
                            (bad, dict(color="tab:red", mfc="tab:red", fmt="x", label="implausible"))):
            if mask.any():
                ax.errorbar(f_b[mask], ok[name].to_numpy(dtype=float)[mask], yerr=bars[:, mask], ms=5, capsize=3,
                            lw=0.9, **{"fmt": "o", **style})
        ax.set_ylabel(PARAMETER_LABELS.get(name, name))
        ax.grid(alpha=0.3)
        labels = "label" if "label" in ok else "record"
        if ax is axes[0] and labels in ok and len(ok) <= MAX_LABELLED:
            for x, y, record in zip(f_b, ok[name].to_numpy(dtype=float), ok[labels].astype(str)):
                ax.annotate(record, (x, y), xytext=(4, 3), textcoords="offset points", fontsize=7, color="0.3")
        if ax.get_legend_handles_labels()[1]:
            ax.legend(fontsize=7, loc="best", frameon=False)
    axes[-1].set_xlabel(r"bouncing frequency $f_b$ (Hz)")
    fig.suptitle(title or f"One person per record ({len(ok)} people, record-level model)", fontsize=11, x=0.02,
                 ha="left")
    fig.tight_layout()
    return save(fig, path, DPI)
