"""Figures of population statistics (Section 5), like the article's Fig. 6-8.

Every function takes a :class:`smd_statespace.population.PopulationStats`, builds a
:class:`matplotlib.figure.Figure` without pyplot's global state (as
:mod:`smd_statespace.plotting.cycles`), saves it when given a ``path`` and returns it.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import MaxNLocator

from .. import article
from .cycles import PARAMETER_LABELS
from ..population import PARAMETERS, TrendResult
from .save import save

MAX_POINTS = 1500
"""Most cycles drawn as dots per panel of :func:`plot_trends` (an even subsample beyond that)."""


def _label(parameter: str) -> str:
    return PARAMETER_LABELS.get(PARAMETERS[parameter].column, parameter)


def _collect_legend(axes, handles: list, labels: list):
    """Append each axes' legend entries to ``handles``/``labels`` once per label; return both."""
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            if label not in labels:
                handles.append(handle)
                labels.append(label)
    return handles, labels


DPI = 100
"""Dots per inch of this module's figures."""


def _band_range(stats) -> tuple:
    """``(low, high)``: the lowest and highest band edge (Hz)."""
    return stats.bands.intervals[0][0], stats.bands.intervals[-1][1]


def _draw_trend(ax, trend, low: float, high: float, noun: str):
    """A parameter's trend on its panel: the OLS line and its band, a quadratic's vertex, or why there is none."""
    if isinstance(trend, TrendResult):
        fitted = np.linspace(*trend.f_b_range, 200)  # no extrapolation beyond the cycles fitted
        mean, lo, hi = trend.predict(fitted)
        ax.fill_between(fitted, lo, hi, color="tab:red", alpha=0.25, lw=0, zorder=3)
        ax.plot(fitted, mean, color="tab:red", lw=1.6, zorder=3,
                label=f"OLS trend, {trend.confidence:.0%} band of its mean")
        if trend.vertex is not None and low <= trend.vertex <= high:
            ax.axvline(trend.vertex, color="tab:blue", ls="--", lw=1.0, zorder=2)
            ax.axvspan(max(trend.vertex_ci_delta[0], low), min(trend.vertex_ci_delta[1], high), color="tab:blue",
                       alpha=0.15, lw=0, zorder=1, label="vertex f* and its delta-method interval")
            ax.text(0.98, 0.95, f"{trend.vertex_kind} at f* = {trend.vertex:.2f} Hz", transform=ax.transAxes,
                    ha="right", va="top", fontsize=8, color="tab:blue")
        elif trend.vertex is not None:
            ax.text(0.98, 0.95, f"{trend.vertex_kind} at {trend.vertex:.2f} Hz\n(outside the bands)",
                    transform=ax.transAxes, ha="right", va="top", fontsize=7, color="tab:blue")
    elif trend is not None:  # "no trend (too few cycles: ...)" or "no trend (no spread: ...)"
        why = str(trend).partition("(")[2].partition(":")[0] or f"too few {noun}"
        ax.text(0.5, 0.06, f"no trend: {why}", transform=ax.transAxes, ha="center", va="bottom",
                fontsize=8, color="tab:red")


def _trend_panel(ax, stats, parameter: str):
    """One parameter against ``f_b``: the cycles used, band means ± 1 sd, the trend; y-range from the bulk."""
    cycles, noun = stats.cycles, stats.noun
    low, high = _band_range(stats)
    used = cycles[cycles[f"used_{parameter}"]]
    points = used.iloc[:: max(1, math.ceil(len(used) / MAX_POINTS))]
    ax.plot(points["f_b"], points[PARAMETERS[parameter].column], ".", color="0.55", ms=2, alpha=0.35,
            rasterized=True)
    cells = [stats.cells[parameter, b] for b in range(len(stats.bands))]
    means = np.array([c.mean for c in cells])
    sds = np.array([c.sd if c.n > 1 else 0.0 for c in cells])
    shown = np.isfinite(means)
    ax.errorbar(stats.bands.centres[shown], means[shown], yerr=sds[shown], fmt="o", color="k", ms=4, capsize=3,
                lw=1.2, label="band mean ± sd", zorder=4)
    _draw_trend(ax, stats.trends.get(parameter), low, high, noun)
    # y-range from the bulk of the cycles, so that a few outliers do not flatten the panel
    values = used[PARAMETERS[parameter].column].to_numpy()
    if not values.size:
        ax.set_yticks([])
        missing = f"no {noun}" + ("" if stats.options["include_undetermined"] else " that determined it")
        ax.text(0.5, 0.55, missing, transform=ax.transAxes, ha="center", va="center", fontsize=9, color="tab:red")
    if values.size:
        q_lo, q_hi = np.percentile(values, [0.5, 99.5])
        span = max(q_hi - q_lo, 1e-3 * max(abs(q_hi), abs(q_lo)), 1e-12)  # one value: a readable range
        ax.set_ylim(min(q_lo, np.nanmin(means - sds)) - 0.05 * span,
                    max(q_hi, np.nanmax(means + sds)) + 0.05 * span)
    ax.set_title(_label(parameter), fontsize=10)
    ax.set_xlim(low - 0.05, high + 0.05)
    ax.grid(alpha=0.3)


def _count_panel(count_ax, stats):
    """The last panel of :func:`plot_trends`: ok cycles per band and those used for ``f_h`` and ``xi_h``."""
    cycles, noun, centres = stats.cycles, stats.noun, stats.bands.centres
    low, high = _band_range(stats)
    in_band = np.array([int((cycles["band"] == b).sum()) for b in range(len(stats.bands))])
    width = 0.8 * np.min(np.diff([lo for lo, _ in stats.bands] + [high])) / 3.0
    count_ax.bar(centres - width, in_band, width, color="0.7", label=f"ok {noun}")
    for k, (parameter, color) in enumerate((("f_h", "tab:blue"), ("xi_h", "tab:orange"))):
        if parameter in stats.parameters:
            used_n = [stats.cells[parameter, b].n for b in range(len(stats.bands))]
            count_ax.bar(centres + k * width, used_n, width, color=color, label=f"used for {_label(parameter)}")
    count_ax.set_title(f"{noun} per band", fontsize=10)
    count_ax.set_ylim(0, 1.75 * max(int(in_band.max()), 1))
    count_ax.legend(fontsize=7, loc="upper left", frameon=False, ncol=1)
    count_ax.grid(alpha=0.3, axis="y")
    count_ax.set_xlim(low - 0.05, high + 0.05)


def _trends_legend_and_title(fig: Figure, parameter_axes, stats):
    """The figure's shared legend (cycles, trend, band means, vertex) and its title (which cycles are shown)."""
    cycles, noun = stats.cycles, stats.noun
    handles = [Line2D([], [], marker=".", ls="", color="0.55", ms=7)]
    labels = [noun + (f" (an even subsample of {MAX_POINTS} per panel)" if len(cycles) > MAX_POINTS else "")]
    _collect_legend(parameter_axes, handles, labels)
    fig.legend(handles, labels, loc="upper center", ncol=len(labels), fontsize=8, frameon=False,
               bbox_to_anchor=(0.5, 1.0 - 0.36 / fig.get_figheight()))
    included = f"all {noun}" if stats.options["include_undetermined"] else f"{noun} that determined each parameter"
    impossible = stats.counts.get("implausible", 0) + stats.counts.get("inadequate", 0)
    if impossible:
        included += (f", {impossible} implausible kept" if stats.options.get("include_implausible")
                     else f", {impossible} implausible left out")
    fig.suptitle(f"Parameters against bouncing frequency ({included}; {stats.counts['in_bands']} ok {noun} in the "
                 "bands)", fontsize=11, x=0.01, ha="left", y=1.0 - 0.08 / fig.get_figheight(), va="top")


def plot_trends(stats, path=None) -> Figure:
    """Every parameter against the bouncing frequency: cycles, band means ± sd, trend with its band.

    One panel per parameter: the cycles used (grey dots), the mean ± 1 sd of each band (black),
    the OLS trend with the confidence band of its mean (red), and for a quadratic the vertex
    ("preferred frequency", dashed) with its delta-method interval (shaded). The last panel
    counts the cycles per band and how many determined ``f_h`` and ``xi_h``.

    Parameters
    ----------
    stats : PopulationStats
    path : str or Path, optional
        PNG file to write.
    """
    parameters = list(stats.parameters)
    n_panels = len(parameters) + 1
    ncols = min(4, n_panels)
    nrows = math.ceil(n_panels / ncols)
    fig = Figure(figsize=(3.3 * ncols, 2.9 * nrows))
    axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
    for ax, parameter in zip(axes, parameters):
        _trend_panel(ax, stats, parameter)
    _count_panel(axes[len(parameters)], stats)
    for ax in axes[n_panels:]:
        ax.set_visible(False)
    for ax in axes[-ncols:]:
        ax.set_xlabel("bouncing frequency $f_b$ (Hz)")
    _trends_legend_and_title(fig, axes[:len(parameters)], stats)
    fig.tight_layout(rect=(0, 0, 1, 1.0 - 0.52 / fig.get_figheight()))
    return save(fig, path, DPI)


def plot_histograms(stats, parameter: str, path=None, published: bool = True) -> Figure:
    """Per-band histograms of one parameter with the fitted skew-normal densities (Eq. 19).

    Parameters
    ----------
    stats : PopulationStats
    parameter : str
        One of ``stats.parameters`` (e.g. ``"f_h"``).
    path : str or Path, optional
        PNG file to write.
    published : bool
        Also draw the published Table 2 density (dashed) when the bands are the article's.
    """
    if parameter not in stats.parameters:
        from ..errors import OptionError

        raise OptionError(f"plot_histograms: {parameter!r} is not among {', '.join(stats.parameters)}")
    column = PARAMETERS[parameter].column
    cycles = stats.cycles
    used = cycles[cycles[f"used_{parameter}"]]
    n_bands = len(stats.bands)
    ncols = min(3, n_bands)
    nrows = math.ceil(n_bands / ncols)
    fig = Figure(figsize=(3.4 * ncols, 2.5 * nrows + 0.5))
    axes = fig.subplots(nrows, ncols, squeeze=False, sharex=True).ravel()
    values = used[column].to_numpy()
    if values.size:
        x_lo, x_hi = np.percentile(values, [0.5, 99.5])
    else:
        x_lo, x_hi = 0.0, 1.0
    show_published = published and stats.bands.is_article and parameter in article.TABLE2
    if show_published:
        for fit in article.TABLE2[parameter]:
            dist = fit.dist()
            x_lo = min(x_lo, dist.mean() - 2.5 * dist.std())
            x_hi = max(x_hi, dist.mean() + 3.5 * dist.std())
    pad = 0.03 * (x_hi - x_lo)
    x = np.linspace(x_lo - pad, x_hi + pad, 400)
    for band, ax in enumerate(axes[:n_bands]):
        cell = stats.cells[parameter, band]
        here = used.loc[used["band"] == band, column].to_numpy()
        if here.size:
            inside = here[(here >= x[0]) & (here <= x[-1])]
            if inside.size:
                # density over the whole sample (values beyond the drawn range count in the total)
                counts, edges = np.histogram(inside, bins=int(np.clip(np.sqrt(here.size), 5, 40)))
                density = counts / (here.size * np.diff(edges))
                ax.stairs(density, edges, fill=True, color="0.82", label=stats.noun)
                ax.stairs(density, edges, color="0.55", lw=0.6)
        if cell.fit is not None:
            ax.plot(x, cell.fit.dist().pdf(x), color="tab:red", lw=1.6, label="fit (Eq. 19)")
            text, color = f"n = {cell.n}\nm, s, a = {cell.cell(3)}", "k"
        else:
            text, color = f"n = {cell.n}\n{cell.note}\n(not fitted)", "tab:red"
        if show_published:
            ax.plot(x, article.TABLE2[parameter][band].dist().pdf(x), "k--", lw=1.1, label="Table 2 (article)")
        ax.text(0.98, 0.95, text, transform=ax.transAxes, ha="right", va="top", fontsize=7.5, color=color)
        ax.set_title(f"$f_b$ {stats.bands.labels[band]} Hz", fontsize=9)
        ax.set_yticks([])
        ax.xaxis.set_major_locator(MaxNLocator(nbins=5, prune="both"))
        ax.ticklabel_format(axis="x", style="sci", scilimits=(-3, 4))
        ax.grid(alpha=0.3, axis="x")
    for ax in axes[n_bands:]:
        ax.set_visible(False)
    for ax in axes[max(0, n_bands - ncols):n_bands]:
        ax.set_xlabel(_label(parameter))
    handles, labels = _collect_legend(axes[:n_bands], [], [])
    fig.legend(handles, labels, loc="upper right", ncol=len(labels), fontsize=8, frameon=False,
               bbox_to_anchor=(0.995, 1.0 - 0.04 / fig.get_figheight()))
    excluded = sum(c.excluded for (p, _), c in stats.cells.items() if p == parameter)
    note = f", {excluded} undetermined cycles left out" if excluded else ""
    fig.suptitle(f"{_label(parameter)} per bouncing-frequency band{note}", fontsize=11, x=0.01, ha="left",
                 y=1.0 - 0.06 / fig.get_figheight(), va="top")
    fig.tight_layout(rect=(0, 0, 1, 1.0 - 0.32 / fig.get_figheight()))
    return save(fig, path, DPI)
