"""Figures of identification results, written as PNG files.

Every function builds a :class:`matplotlib.figure.Figure` without touching
pyplot's global state (safe in scripts, tests and worker processes), saves it
when given a ``path`` and returns it.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from ..io import truth_values
from ..identify.plausibility import flagged
from .save import save

PARAMETER_LABELS = {
    "f_h": r"$f_h$ (Hz)",
    "xi_h": r"$\xi_h$ (-)",
    "blf_1": r"BLF$_1$ (g)",
    "blf_2": r"BLF$_2$ (g)",
    "blf_3": r"BLF$_3$ (g)",
    "blf_4": r"BLF$_4$ (g)",
    "k_h": r"$K_h$ (N/m)",
    "c_h": r"$C_h$ (N s/m)",
}


DPI = 110
"""Dots per inch of this module's figures."""


def plot_convergence(history, cycle: int, tolerance: float = 0.05, path=None, names=("f_h", "xi_h", "blf_1",
                                                                                     "blf_2", "blf_3")) -> Figure:
    """Parameter estimates of one cycle against the pass number (like the article's Fig. 4).

    Parameters
    ----------
    history : list of dict
        ``CycleRunner.history_[cycle]``: one dict of estimates per pass.
    cycle : int
        Cycle number (for the title).
    tolerance : float
        The convergence band drawn around the final value (±tolerance).
    """
    frame = pd.DataFrame(history)
    names = [n for n in names if n in frame]
    fig = Figure(figsize=(2.6 * len(names), 3.0))
    axes = fig.subplots(1, len(names), squeeze=False)[0]
    passes = frame["pass_number"].to_numpy()
    for ax, name in zip(axes, names):
        values = frame[name].to_numpy()
        sd = frame.get(f"{name}_sd")
        if sd is not None:
            ax.fill_between(passes, values - sd, values + sd, color="tab:blue", alpha=0.2, label="±1 sd")
        ax.plot(passes, values, "o-", color="tab:blue", label="estimate")
        final = values[-1]
        ax.axhspan(final * (1 - tolerance), final * (1 + tolerance), color="tab:green", alpha=0.15,
                   label=f"±{tolerance:.0%} of final")
        ax.set_xlabel("pass")
        ax.set_title(PARAMETER_LABELS.get(name, name), fontsize=10)
        ax.set_xticks(passes)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7, loc="best")
    fig.suptitle(f"Convergence over repeated passes, cycle {cycle}", fontsize=11)
    fig.tight_layout()
    return save(fig, path, DPI)


def plot_parameters(table: pd.DataFrame, path=None, truth: dict | None = None,
                    names=("f_h", "xi_h", "blf_1", "blf_2", "blf_3"), against: str = "time") -> Figure:
    """Identified parameters of every cycle over the record (or against ``f_b``), with ±1 sd bars.

    Cycles that did not determine a parameter (posterior not much narrower
    than the prior, the ``*_determined`` columns) are drawn hollow and grey,
    so a confident-looking number is never shown for them; cycles flagged
    ``implausible`` (estimates that cannot be true, :mod:`.plausibility`) are red crosses.

    Parameters
    ----------
    table : DataFrame
        ``CycleRunner.run`` output (one row per cycle).
    truth : dict, optional
        Known values (e.g. of a synthetic record) drawn as dashed lines: flat
        keys or a simulation's truth, as :func:`~smd_statespace.io.truth_values` reads it.
    against : {"time", "f_b"}
        Horizontal axis: the cycle's middle time (s; one record) or its
        bouncing frequency (Hz; many records, as the article's Fig. 6-8).
    """
    if against not in ("time", "f_b"):
        raise ValueError(f"against must be 'time' or 'f_b', got {against!r}")
    truth = truth_values(truth)
    ok = table[table["status"] == "ok"]
    names = [n for n in names if n in ok]
    fig = Figure(figsize=(9.0, 1.9 * len(names) + 0.6))
    axes = fig.subplots(len(names), 1, sharex=True, squeeze=False)[:, 0]
    middle = 0.5 * (ok["t_start"] + ok["t_end"]) if against == "time" else ok["f_b"]
    for ax, name in zip(axes, names):
        sd = ok.get(f"{name}_sd", pd.Series(np.zeros(len(ok)), index=ok.index))
        flag = ok.get(f"{name}_determined", pd.Series(np.ones(len(ok), dtype=bool), index=ok.index)).astype(bool)
        bad = pd.Series(flagged(ok), index=ok.index)
        for mask, style in ((flag & ~bad, dict(color="tab:blue", mfc="tab:blue", label="determined")),
                            (~flag & ~bad, dict(color="0.6", mfc="white", label="not determined")),
                            (bad, dict(color="tab:red", mfc="tab:red", fmt="x", label="implausible"))):
            if mask.any():
                ax.errorbar(middle[mask], ok[name][mask], yerr=sd[mask], ms=4, capsize=2, lw=0.8,
                            **{"fmt": "o", **style})
        if truth and name in truth:
            ax.axhline(truth[name], color="tab:red", ls="--", lw=1, label="truth")
        ax.set_ylabel(PARAMETER_LABELS.get(name, name))
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7, ncol=3, loc="lower right", bbox_to_anchor=(1.0, 1.0), frameon=False)
    axes[-1].set_xlabel("time (s)" if against == "time" else r"bouncing frequency $f_b$ (Hz)")
    estimator = ok["estimator"].iloc[0] if len(ok) else "?"
    records = f"{ok['record'].nunique()} records, " if "record" in ok else ""
    fig.suptitle(f"Parameters per cycle ({records}{estimator}; bars ±1 sd)", fontsize=11, x=0.02, ha="left")
    fig.tight_layout()
    return save(fig, path, DPI)


def plot_comparison(tables: dict, path=None, truth: dict | None = None, names=("f_h", "xi_h", "blf_1", "blf_2"),
                    title: str = "Estimators compared on the same cycles", answers=None) -> Figure:
    """Per-cycle estimates of several runs side by side (one marker style per run), and each run's answer.

    Parameters
    ----------
    tables : dict of str to DataFrame
        ``CycleRunner.run`` outputs keyed by a label (estimators, or models), on the same cycles.
    truth : dict, optional
        Known values drawn as dashed lines: flat keys (``blf_1``) or a
        simulation's truth (``blf`` as a list), as :func:`~smd_statespace.io.truth_values` reads it.
    title : str
        The figure's title (say "Models compared ..." when the tables come from two models).
    answers : DataFrame, optional
        Each estimator's answer for the record (``compare``'s table: index the estimator, columns ``name``,
        ``name_low``, ``name_high``, ``name_determined``), drawn in a panel beside the cycles: the value with
        its 90 % interval, filled where the record determines it, hollow where not (a per-cycle estimator's
        bar is then the range of the central 90 % of its cycles). An estimator without cycles (the
        record-level person) appears there only.
    """
    truth = truth_values(truth)
    answers = None if answers is None or not len(answers) else answers
    fig = Figure(figsize=(9.0 + (1.6 if answers is not None else 0.0), 1.9 * len(names) + 0.6))
    grid = {"width_ratios": [5.0, 1.0], "wspace": 0.04} if answers is not None else {}
    panels = fig.subplots(len(names), 2 if answers is not None else 1, sharex="col", sharey="row", squeeze=False,
                          gridspec_kw=grid)
    axes = panels[:, 0]
    markers = "osD^v<>"
    only_answers = [] if answers is None else [label for label in answers.index if label not in tables]
    colors = {label: f"C{k}" for k, label in enumerate([*tables, *only_answers])}
    width = 0.8 / max(len(tables), 1)
    for k, (label, table) in enumerate(tables.items()):
        ok = table[table["status"] == "ok"]
        # Spread the estimators a little along the time axis so their bars do not overlap.
        middle = 0.5 * (ok["t_start"] + ok["t_end"]) + (k - (len(tables) - 1) / 2) * width * 0.1
        for ax, name in zip(axes, names):
            if name in ok:
                sd = ok.get(f"{name}_sd")
                ax.errorbar(middle, ok[name], yerr=sd, fmt=markers[k % len(markers)], ms=3.5, lw=0.7, capsize=1.5,
                            label=label, alpha=0.85, color=colors[label])
    for ax, name in zip(axes, names):
        if truth and name in truth:
            ax.axhline(truth[name], color="k", ls="--", lw=1, label="truth")
        ax.set_ylabel(PARAMETER_LABELS.get(name, name))
        ax.grid(alpha=0.3)
    if answers is not None:
        _draw_answers(panels[:, 1], answers, names, colors, truth)
    handles, labels = axes[0].get_legend_handles_labels()
    axes[0].legend(handles, labels, fontsize=7, ncol=len(labels), loc="lower right", bbox_to_anchor=(1.0, 1.0),
                   frameon=False)
    axes[-1].set_xlabel("time (s)")
    fig.suptitle(f"{title} (bars ±1 sd)", fontsize=11, x=0.02, ha="left")
    if answers is None:
        fig.tight_layout()
    else:  # tight_layout cannot place the shared rows of two columns
        fig.subplots_adjust(left=0.08, right=0.985, top=0.9, bottom=0.1, hspace=0.15)
    return save(fig, path, DPI)


def _draw_answers(axes, answers, names, colors, truth) -> None:
    """The answers' panel of :func:`plot_comparison`: one column per estimator, its value and 90 % bar."""
    positions = np.arange(len(answers))
    for ax, name in zip(axes, names):
        for x, (label, row) in zip(positions, answers.iterrows()):
            value, low, high = (row.get(key, np.nan) for key in (name, f"{name}_low", f"{name}_high"))
            if not np.isfinite(value):
                continue
            determined = bool(row.get(f"{name}_determined", False))
            below, above = max(value - low, 0.0), max(high - value, 0.0)
            ax.errorbar([x], [value], yerr=[[below], [above]] if np.isfinite(low + high) else None, fmt="o", ms=6,
                        lw=1.6, capsize=3, color=colors.get(label, "k"),
                        mfc=colors.get(label, "k") if determined else "white")
        if truth and name in truth:
            ax.axhline(truth[name], color="k", ls="--", lw=1)
        ax.grid(alpha=0.3, axis="y")
        ax.tick_params(labelleft=False)
    axes[0].set_title("answer (90 %);\nhollow: not determined", fontsize=8)
    axes[-1].set_xticks(positions, list(answers.index), rotation=45, fontsize=8)
    axes[-1].set_xlim(-0.7, len(answers) - 0.3)


def plot_before_after(before, after, path=None, seconds: float = 2.0) -> Figure:
    """The fit of two models of one record side by side: GRF, residual and residual spectrum.

    Parameters
    ----------
    before, after : ModelCheck
        :func:`smd_statespace.diagnostics.check_model` results without and with the added effects.
    seconds : float
        Length of the stretch of record shown in the time panels (s).
    """
    fig = Figure(figsize=(10.0, 7.2))
    axes = fig.subplots(3, 1)
    start = before.time[0]
    window = before.time <= start + seconds
    axes[0].plot(before.time[window], before.measured[window], color="k", lw=1.4, label="measured")
    for check, label, color in ((before, "without", "tab:red"), (after, "with", "tab:blue")):
        shown = check.time <= start + seconds
        names = ", ".join(e.name for e in check.model.effects) or "base model"
        axes[0].plot(check.time[shown], check.simulated[shown], color=color, lw=1.0,
                     label=f"{label}: {names} (fit {check.fit_percent:.1f} %)")
        axes[1].plot(check.time, check.residual, color=color, lw=0.6, alpha=0.8,
                     label=f"{label}: RMS {check.residual_rms_bw:.2f} % BW")
        frequency, power, _ = check.residual_spectrum()
        axes[2].semilogy(frequency, power, color=color, lw=1.0, label=label)
    axes[0].set_ylabel("dynamic GRF (N)")
    axes[0].set_xlabel("time (s)")
    axes[1].set_ylabel("residual (N)")
    axes[1].set_xlabel("time (s)")
    axes[2].set_ylabel("residual PSD (N²/Hz)")
    axes[2].set_xlabel("frequency (Hz)")
    axes[2].set_xlim(0, min(25.0, frequency[-1]))
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
    fig.suptitle("Free simulation without and with the added effect(s)", fontsize=11, x=0.02, ha="left")
    fig.tight_layout()
    return save(fig, path, DPI)
