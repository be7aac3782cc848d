"""The figure of the signal pipeline (:func:`smd_statespace.signals.preprocess`): every pre-processing step of
a record, the whole record and a zoom on a few cycles."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure

from ..io import G
from .save import save

__all__ = ["plot_preprocessed"]


def plot_preprocessed(pre, path=None, zoom_cycles=3) -> Figure:
    """Every pre-processing step of ``pre`` (a :class:`~smd_statespace.signals.Preprocessed`), one row of panels each.

    Rows: GRF with detected peaks and cycles (invalid cycles shaded red);
    raw (Eq. 3) and high-passed COM acceleration; the part the high-pass
    removed (raw minus high-passed, on its own small scale); velocity;
    displacement; and, with a floor signal, the floor acceleration. The
    left column shows the whole record (the zoomed span shaded in the GRF
    panel), the wider right column a few cycles from its middle.

    Parameters
    ----------
    pre : Preprocessed
    path : str or path-like, optional
        Where to save the figure as PNG (100 dpi).
    zoom_cycles : int, default 3
        Number of cycles in the right-hand zoom (0: no zoom column).

    Returns
    -------
    matplotlib.figure.Figure
        The figure (made without pyplot, so no GUI backend is needed).
    """
    rows = _rows(pre)
    zoom = _zoom_window(pre, zoom_cycles)
    fig, axes = _figure(rows, zoom is not None)
    name = Path(str(pre.source)).name or str(pre.source)
    fig.suptitle(
        f"{name}: pre-processing, {len(pre.cycles)} cycles ({len(pre.valid_cycles)} valid), "
        f"fs {pre.fs:g} Hz, high-pass {pre.cutoff:g} Hz",
        fontsize=11, y=1.0 - 0.12 / fig.get_figheight(), va="top",
    )
    n_cols = axes.shape[1]
    for col in range(n_cols):
        _draw_steps(pre, axes[:, col], full=(col == 0), dense=(col == 0 and zoom is not None))
    for ax, (ylabel, title, _) in zip(axes[:, 0], rows):
        ax.set_title(title, fontsize=10, loc="left", pad=4, y=1.0)  # fixed y: no costly auto-placement
        ax.set_ylabel(ylabel)
    axes[0, 0].set_xlim(pre.time[0], pre.time[-1])
    if zoom is not None:
        _zoom_column(pre, axes, zoom, zoom_cycles)
    else:
        axes[-1, 0].set_xlabel("time (s)")
    for ax_text, ax_lines in zip(axes[:, -1], axes[:, 0]):
        handles, labels = ax_lines.get_legend_handles_labels()
        ax_text.legend(handles, labels, loc="lower right", bbox_to_anchor=(1.0, 1.0), ncol=3, fontsize=8,
                       frameon=False, borderaxespad=0.15, handlelength=1.6, columnspacing=1.2)
    return save(fig, path, 100)


def _rows(pre) -> list:
    """``(y label, title, height ratio)`` of each row of panels: the steps, and the floor's with a floor signal."""
    rows = [
        ("GRF (N)", "Ground reaction force and cycles", 1.0),
        (r"$\ddot u$ (m/s$^2$)", r"COM acceleration $\ddot u = (GRF - M_h g)/M_h$ (Eq. 3)", 1.0),
        ("removed\n" r"(m/s$^2$)", "Removed by the high-pass: raw minus high-passed (own scale)", 0.55),
        (r"$\dot u$ (m/s)", "COM velocity: integrated, high-passed", 0.8),
        (r"$u$ (mm)", "COM displacement: integrated twice, high-passed", 0.8),
    ]
    if pre.floor_acc is not None:
        rows.append((r"$\ddot z$ (m/s$^2$)", "Floor acceleration, high-passed", 0.8))
    return rows


def _figure(rows: list, zoomed: bool) -> tuple:
    """``(figure, axes)``: one row of axes per step, a second (wider) column for the zoom, fixed margins."""
    n_cols = 2 if zoomed else 1
    ratios = [row[2] for row in rows]
    gap = 0.62  # inches between rows: title or legend above each axis
    unit = 1.65  # inches of a row of ratio 1
    top, bottom = 0.75, 0.55
    height = top + bottom + unit * sum(ratios) + gap * (len(rows) - 1)
    width = 13.0 if zoomed else 9.0
    left, right = 0.95, 0.2
    fig = Figure(figsize=(width, height))
    # Fixed margins (in inches): with this many labels the constrained and
    # tight layout engines cost seconds per draw.
    axes = fig.subplots(
        len(rows), n_cols, sharex="col", squeeze=False,
        gridspec_kw={
            "width_ratios": [1.0, 1.3][:n_cols],
            "height_ratios": ratios,
            "left": left / width,
            "right": 1.0 - right / width,
            "top": 1.0 - top / height,
            "bottom": bottom / height,
            "hspace": gap / (unit * float(np.mean(ratios))),
            "wspace": 0.12,
        },
    )
    return fig, axes


def _zoom_column(pre, axes, zoom: tuple, zoom_cycles: int):
    """The zoom column: its span shaded in the GRF panel, x labels, and y-ranges fitted to the zoomed span."""
    first, last = _zoom_cycles(pre, zoom_cycles)
    axes[0, 0].axvspan(*zoom, color="tab:olive", alpha=0.3, lw=0, zorder=0.5)
    axes[0, 0].fill_between([], [], color="tab:olive", alpha=0.3, label="zoomed span (right)")
    axes[-1, 0].set_xlabel("time (s): whole record")
    axes[-1, 1].set_xlabel(f"time (s): zoom on cycles {first}-{last}, shaded olive in the GRF panel")
    axes[0, 1].set_xlim(*zoom)
    inside = (pre.time >= zoom[0]) & (pre.time <= zoom[1])
    for row, ax_zoom in enumerate(axes[:, 1]):
        if row == 2:  # the removed part: same scale as the whole record
            ax_zoom.set_ylim(axes[2, 0].get_ylim())
            continue
        values = [np.asarray(line.get_ydata())[inside] for line in ax_zoom.get_lines()
                  if np.size(line.get_ydata()) == inside.size]
        low = min(float(v.min()) for v in values)
        high = max(float(v.max()) for v in values)
        pad = 0.1 * (high - low) if high > low else 1.0
        ax_zoom.set_ylim(low - pad, high + pad)


def _zoom_cycles(pre, zoom_cycles):
    """Indices ``(first, last)`` of the cycles shown in the zoom column."""
    first = max(0, len(pre.cycles) // 2 - zoom_cycles // 2)
    return first, first + int(zoom_cycles) - 1


def _zoom_window(pre, zoom_cycles):
    """Time span (s) of ``zoom_cycles`` cycles from the middle of the record, or None."""
    if not zoom_cycles or len(pre.cycles) <= zoom_cycles:
        return None
    first, last = _zoom_cycles(pre, zoom_cycles)
    chosen = pre.cycles[first : last + 1]
    margin = 0.05 * (chosen[-1].t_end - chosen[0].t_start)
    return chosen[0].t_start - margin, chosen[-1].t_end + margin


def _draw_steps(pre, axes, full, dense):
    """Draw the pre-processing steps, one per axis.

    ``full``: the whole-record column (legend entries of the cycle
    shading); ``dense``: many cycles in it (thinner lines).
    """
    ax = axes[0]
    lw = 0.7 if dense else 1.2
    starts = np.array([c.t_start for c in pre.cycles])
    ends = np.array([c.t_end for c in pre.cycles])
    valid = np.array([c.valid for c in pre.cycles], dtype=bool)
    alternate = valid & (np.arange(len(pre.cycles)) % 2 == 0)
    span = ax.get_xaxis_transform()  # x in data, y in axes fraction
    for mask, style in ((alternate, {"color": "0.88"}), (~valid, {"color": "tab:red", "alpha": 0.15})):
        if mask.any():
            boxes = [[(t0, 0.0), (t1, 0.0), (t1, 1.0), (t0, 1.0)] for t0, t1 in zip(starts[mask], ends[mask])]
            ax.add_collection(PolyCollection(boxes, transform=span, lw=0, zorder=0, **style), autolim=False)
    ax.plot(pre.time, pre.force, color="tab:blue", lw=lw, label="GRF")
    ax.plot(pre.time[pre.peaks], pre.force[pre.peaks], "v", color="tab:orange", ms=4 if dense else 6,
            label="peak = cycle boundary")
    ax.axhline(pre.mass * G, color="0.3", lw=0.8, ls="--", label=r"$M_h g$")
    if full:
        ax.fill_between([], [], color="0.88", label="cycle (alternate shading)")
        ax.fill_between([], [], color="tab:red", alpha=0.15, label="invalid cycle")
    axes[1].plot(pre.time, pre.acc_raw, color="tab:orange", lw=2.2 if dense else 4.5, alpha=0.5,
                 solid_capstyle="butt", label="raw (Eq. 3)")
    axes[1].plot(pre.time, pre.acc, color="tab:blue", lw=lw, label=f"high-passed {pre.cutoff:g} Hz")
    removed = pre.acc_raw - pre.acc
    rms = float(np.sqrt(np.mean(np.square(removed))))
    axes[2].plot(pre.time, removed, color="tab:red", lw=1.0, label=f"raw - high-passed (RMS {rms:.2g} m/s$^2$)")
    axes[2].axhline(0.0, color="0.3", lw=0.6)
    axes[3].plot(pre.time, pre.vel, color="tab:green", lw=lw, label=r"$\dot u$")
    axes[4].plot(pre.time, pre.disp * 1e3, color="tab:purple", lw=lw, label=r"$u$")
    if pre.floor_acc is not None:
        axes[5].plot(pre.time, pre.floor_acc, color="tab:brown", lw=lw, label="floor")
    for ax in axes:
        ax.grid(True, lw=0.4, alpha=0.5)
