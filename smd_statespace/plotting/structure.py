"""Figures of a crowd on a structure (:mod:`smd_statespace.structure`): frequency response empty vs occupied,
running RMS coupled vs force-only, and the Monte Carlo distribution."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from ..structure.analysis import StructureResult
from ..structure.limits import ROUTE2, Limits
from ..structure.response import accelerance, running_rms
from .save import save

__all__ = ["plot_frequency_response", "plot_running_rms", "plot_draws"]


def plot_frequency_response(result: StructureResult, path=None) -> Figure:
    """Driving-point accelerance at the worst response point, empty and occupied structure.

    Parameters
    ----------
    result : StructureResult
    path : str or path-like, optional
        PNG to write.

    Returns
    -------
    matplotlib.figure.Figure
    """
    point = result.points[result.worst()]
    model = result.model
    top = min(result.fs / 2.0, 1.6 * float(model.frequency.max()), 40.0)
    frequency = np.linspace(0.05, top, 4000)
    fig = Figure(figsize=(8.0, 4.6))
    ax = fig.subplots()
    ax.semilogy(frequency, np.abs(accelerance(result.coupling, point, frequency, occupied=False)), lw=1.2,
                label="empty structure")
    ax.semilogy(frequency, np.abs(accelerance(result.coupling, point, frequency)), lw=1.2,
                label=f"occupied: {result.coupling.n_people} people (SMD, Eq. 2)")
    f_b = result.occupants.settings["f_b"]
    for k in range(1, 4):
        if k * f_b < top:
            ax.axvline(k * f_b, color="0.6", lw=0.8, ls=":")
            ax.text(k * f_b, ax.get_ylim()[1], f" {k} $f_b$", fontsize=8, va="top", color="0.4")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("accelerance |a / F| (m/s$^2$ per N)")
    ax.set_title(f"{model.name}: driving-point frequency response at {model.points[point]}", fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return save(fig, path)


def plot_running_rms(result: StructureResult, path=None, limits: Limits = ROUTE2) -> Figure:
    """1 s running RMS acceleration over time at the worst response point, coupled and force-only, with the
    criteria of ``limits`` (each drawn when below the plotted maximum, and the first above it).

    Parameters
    ----------
    result : StructureResult
    path : str or path-like, optional
        PNG to write.
    limits : Limits
        Criteria on the unweighted ``rms_1s_max`` (default :data:`~smd_statespace.structure.limits.ROUTE2`);
        None for none.

    Returns
    -------
    matplotlib.figure.Figure
    """
    k = result.worst()
    coupled, force_only = (a[k] for a in result.accelerations())
    fs, time = result.fs, result.solution.time
    fig = Figure(figsize=(8.0, 5.6))
    ax_time, ax_rms = fig.subplots(2, 1, sharex=True)
    ax_time.plot(time, force_only, lw=0.5, color="tab:red", label="force-only (people as forces, empty structure)")
    ax_time.plot(time, coupled, lw=0.5, color="tab:blue", label="coupled (people as SMD systems)")
    ax_time.set_ylabel("acceleration (m/s$^2$)")
    ax_time.legend(fontsize=7, loc="lower left", framealpha=0.9)
    name = result.model.points[result.points[k]]
    ax_time.set_title(f"{result.model.name}: vertical acceleration at {name} (unweighted)", fontsize=10)
    for values, color, label in ((force_only, "tab:red", "force-only"), (coupled, "tab:blue", "coupled")):
        rms = running_rms(values, fs)
        ax_rms.plot(time[time.size - rms.size:], rms, lw=1.2, color=color,
                    label=f"{label}: max {rms.max() if rms.size else np.nan:.3f} m/s$^2$")
    if limits is not None and limits.measure == "rms_1s_max":
        ax_rms.set_title(_criteria(ax_rms, limits), fontsize=8, loc="right")
    ax_rms.set_xlabel("time (s)")
    ax_rms.set_ylabel("1 s running RMS (m/s$^2$)")
    ax_rms.legend(fontsize=8, loc="upper left", framealpha=0.9)
    fig.tight_layout()
    return save(fig, path)


def _criteria(ax, limits: Limits, vertical=False):
    """Lines at the criteria of ``limits`` up to the first above the plotted data, each labelled: horizontal on the
    y axis (a running RMS), vertical on the x axis (a histogram of maxima). Returns a caption naming the source."""
    top = (ax.get_xlim() if vertical else ax.get_ylim())[1]
    shown = [c for c in limits.criteria if c.limit <= top]
    shown += [c for c in limits.criteria if c.limit > top][:1]
    box = {"facecolor": "white", "alpha": 0.75, "edgecolor": "none", "pad": 0.5}
    for criterion in shown:
        label = f"{limits.kind} {criterion.name}: {criterion.stated} "
        if vertical:
            ax.axvline(criterion.limit, color="0.35", lw=0.9, ls="--")
            ax.text(criterion.limit, 0.6, label, fontsize=7, color="0.25", rotation=90, ha="right", va="center",
                    bbox=box, transform=ax.get_xaxis_transform())
        else:
            ax.axhline(criterion.limit, color="0.35", lw=0.9, ls="--")
            ax.text(ax.get_xlim()[1], criterion.limit, label, fontsize=7, color="0.25", ha="right", va="bottom",
                    bbox=box)
    bound = max(top, 1.12 * shown[-1].limit) if shown else top
    (ax.set_xlim if vertical else ax.set_ylim)(0.0, bound)
    return f"dashed: {limits.label}"


def plot_draws(frame, point, path=None, q=95.0, limits: Limits = ROUTE2) -> Figure:
    """Histograms over Monte Carlo draws of the maximum 1 s running RMS at ``point``, coupled and force-only, with
    the criteria of ``limits``.

    Parameters
    ----------
    frame : pandas.DataFrame
        :func:`~smd_statespace.structure.montecarlo.monte_carlo`'s table.
    point : str
        Response point shown.
    path : str or path-like, optional
        PNG to write.
    q : float
        Percentile marked (default the 95th).
    limits : Limits
        Criteria on the unweighted ``rms_1s_max`` (default :data:`~smd_statespace.structure.limits.ROUTE2`);
        None for none.

    Returns
    -------
    matplotlib.figure.Figure
    """
    rows = frame[frame["point"] == point]
    fig = Figure(figsize=(8.0, 4.4))
    ax = fig.subplots()
    columns = (("force_only_rms_1s_max", "tab:red", "force-only"), ("coupled_rms_1s_max", "tab:blue", "coupled"))
    top = max(float(rows[column].max()) for column, _, _ in columns)
    bins = np.linspace(0.0, 1.05 * top if top > 0 else 1.0, 41)  # the same bins for both models
    for column, color, label in columns:
        values = rows[column].to_numpy(dtype=float)
        ax.hist(values, bins=bins, color=color, alpha=0.5,
                label=f"{label}: {q:g}th percentile {np.percentile(values, q):.3f} m/s$^2$")
        ax.axvline(np.percentile(values, q), color=color, lw=1.2, ls="--")
    ax.set_xlabel("maximum 1 s running RMS acceleration (m/s$^2$, unweighted)")
    ax.set_ylabel("draws")
    title = f"{len(rows)} random crowds: response at {point}"
    if limits is not None and limits.measure == "rms_1s_max":
        title += "\n" + _criteria(ax, limits, vertical=True)
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=8, loc="upper right", framealpha=0.9)
    fig.tight_layout()
    return save(fig, path)
