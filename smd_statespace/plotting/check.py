"""Figures of a model check (:class:`~smd_statespace.diagnostics.ModelCheck`): the fit and the residual diagnostics.

:func:`plot_fit` puts the measured GRF beside the free simulation and the
one-step prediction; :func:`plot_diagnostics` shows on one page where and how
the model fails (innovations, their distribution and autocorrelation, the
residual spectrum, the phase profile and the correlations with each
candidate effect's terms). ``ModelCheck.plot_fit`` and
``ModelCheck.plot_diagnostics`` call them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from ..diagnostics.check import PEAK_FALSE_ALARM
from ..errors import OptionError
from .innovations import Innovations, plot_innovation_panels
from .save import save

__all__ = ["plot_fit", "plot_diagnostics"]


def plot_fit(check, path=None, cycles=None):
    """Measured GRF against the free simulation and the one-step prediction, residual underneath.

    Top: a stretch of a few cycles (measured, free simulation, one-step
    prediction) with the residual below it; bottom: the whole checked
    record, the stretch shaded.

    Parameters
    ----------
    check : ModelCheck
        The model check to draw (:func:`~smd_statespace.diagnostics.check_model`).
    path : str or path-like, optional
        Where to save the figure (PNG).
    cycles : int or sequence of int, optional
        Cycles in the zoom: their numbers, or how many from the first
        checked one (default 4).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    numbers = check._cycle_numbers()
    if cycles is None:
        cycles = 4
    if np.isscalar(cycles):
        chosen = numbers[: max(1, int(cycles))]
    else:
        chosen = [int(c) for c in cycles]
        missing = [c for c in chosen if c not in numbers]
        if missing:
            raise OptionError(f"cycles {missing} were not identified; checked cycles: {numbers}")
    zoom = np.isin(check.cycle_index, chosen)
    fig = Figure(figsize=(12.0, 9.0))
    axes = fig.subplots(4, 1, gridspec_kw={"height_ratios": [1.3, 0.7, 1.0, 0.7], "hspace": 0.55,
                                           "left": 0.08, "right": 0.98, "top": 0.92, "bottom": 0.06})
    pct = f"{check.fit_percent:.1f} %"
    for ax_fit, ax_res, mask, lw in ((axes[0], axes[1], zoom, 1.4), (axes[2], axes[3], slice(None), 0.7)):
        t = check.time[mask]
        ax_fit.plot(t, check.measured[mask], color="0.15", lw=lw + 0.6, alpha=0.55, label="measured $M_h\\ddot u$")
        ax_fit.plot(t, check.simulated[mask], color="tab:blue", lw=lw, label=f"free simulation (fit {pct})")
        ax_fit.plot(t, check.one_step[mask], color="tab:orange", lw=lw * 0.8, ls="--",
                    label=f"one-step prediction (fit {check.fit_percent_one_step:.1f} %)")
        ax_res.plot(t, check.residual[mask], color="tab:red", lw=lw * 0.8,
                    label=f"measured - free simulation (RMS {check.residual_rms:.1f} N = "
                          f"{check.residual_rms_bw:.2f} % BW)")
        ax_res.axhline(0.0, color="0.3", lw=0.6)
        ax_res.axhspan(-0.01 * check.weight, 0.01 * check.weight, color="0.5", alpha=0.15, lw=0,
                       label="$\\pm$1 % body weight")
        for ax in (ax_fit, ax_res):
            _cycle_marks(check, ax, t)
            ax.grid(True, lw=0.4, alpha=0.5)
            ax.set_xlim(t[0], t[-1])
        ax_fit.set_ylabel("dynamic GRF (N)")
        ax_res.set_ylabel("residual (N)")
        limit = 1.1 * np.max(np.abs(check.residual)) if check.residual.size else 1.0
        ax_res.set_ylim(-limit, limit)
    axes[0].set_title(f"Cycles {chosen[0]}-{chosen[-1]}", loc="left", fontsize=10)
    axes[2].set_title("All checked cycles", loc="left", fontsize=10)
    t_zoom = check.time[zoom]
    axes[2].axvspan(t_zoom[0], t_zoom[-1], color="tab:olive", alpha=0.2, lw=0, label="zoomed span (top)")
    for ax in axes:
        ax.legend(loc="lower right", bbox_to_anchor=(1.0, 1.0), ncol=4, fontsize=8, frameon=False,
                  borderaxespad=0.1)
    axes[1].set_xlabel("time (s)")
    axes[3].set_xlabel("time (s)")
    fig.suptitle(f"{Path(str(getattr(check.preprocessed, 'source', ''))).name}: identified model vs measurement "
                 f"({check.n_cycles} cycles, median $f_b$ {check.f_b:.2f} Hz)", fontsize=12, x=0.08, ha="left")
    return save(fig, path, 100)

def _cycle_marks(check, ax, t):
    starts = [c.t_start for c in check.cycles if t[0] <= c.t_start <= t[-1]]
    for start in starts:
        ax.axvline(start, color="0.6", lw=0.5, zorder=0)

def plot_diagnostics(check, path=None, lags=None):
    """One figure to read at a glance where and how the model fails.

    Panels: (1) standardised innovations over time; (2) their histogram
    against N(0, 1) and (3) a normal Q-Q plot; (4) their autocorrelation
    within cycles, with the combined Ljung-Box p-value; (5) the residual
    spectrum (Welch, log scale) with the measured GRF's faint behind it,
    the noise floor and peak threshold, lines at ``k f_b`` and labelled
    peaks; (6) the residual against the cycle phase (binned mean +- sd);
    (7) cross-correlations of the residual with candidate signals.

    Parameters
    ----------
    check : ModelCheck
        The model check to draw (:func:`~smd_statespace.diagnostics.check_model`).
    path : str or path-like, optional
        Where to save the figure (PNG).
    lags : int, optional
        Lags of the autocorrelation and Ljung-Box test.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    lags = check.default_lags() if lags is None else int(lags)
    fig = Figure(figsize=(13.0, 15.0))
    grid = fig.add_gridspec(4, 3, height_ratios=[0.8, 1.0, 1.25, 1.05], hspace=0.5, wspace=0.28,
                            left=0.07, right=0.98, top=0.93, bottom=0.04)
    ax_time = fig.add_subplot(grid[0, :])
    ax_hist = fig.add_subplot(grid[1, 0])
    ax_qq = fig.add_subplot(grid[1, 1])
    ax_acf = fig.add_subplot(grid[1, 2])
    ax_spec = fig.add_subplot(grid[2, :])
    bottom = grid[3, :].subgridspec(1, 2, width_ratios=[1.9, 1.0], wspace=0.42)
    ax_phase = fig.add_subplot(bottom[0, 0])
    ax_corr = fig.add_subplot(bottom[0, 1])
    plot_innovation_panels(_innovations(check, lags), ax_time, ax_hist, ax_qq, ax_acf)
    _plot_spectrum(check, ax_spec)
    _plot_phase_profile(check, ax_phase)
    _plot_correlations(check, ax_corr)

    name = Path(str(getattr(check.preprocessed, "source", ""))).name
    fig.suptitle(f"{name}: model diagnostics. Free-simulation fit {check.fit_percent:.1f} %, residual RMS "
                 f"{check.residual_rms_bw:.2f} % BW, {check.n_cycles} cycles", fontsize=12, x=0.07, ha="left")
    return save(fig, path, 100)


def _innovations(check, lags: int) -> Innovations:
    """The check's standardised innovations and their tests, for the four panels every diagnostics figure begins
    with (:mod:`~smd_statespace.plotting.innovations`): the filter starts afresh in every cycle, so the
    autocorrelation and the Ljung-Box test are within cycles."""
    return Innovations(time=check.time, values=check.innovations, acf=check.pooled_acf(lags),
                       ljung_box_p=check.whiteness_pvalue(lags), normality=check.test_normality(),
                       sample_interval=1.0 / check.fs, marks=np.array([c.t_start for c in check.cycles]),
                       acf_name="ACF within cycles")


def _plot_spectrum(check, ax):
    """Panel (5): residual spectrum with the noise floor, k f_b lines and labelled peaks."""
    freq, psd, peaks = check.residual_spectrum()
    f_m, p_m = check.measured_spectrum()
    ax.semilogy(f_m, p_m, color="0.6", lw=1.0, alpha=0.6, label="measured GRF")
    ax.semilogy(freq, psd, color="tab:red", lw=1.2, label="residual (measured - free simulation)")
    ax.axhline(peaks.attrs["noise_floor"], color="k", lw=0.8, ls=":", label="noise floor (median)")
    ax.axhline(peaks.attrs["threshold"], color="k", lw=0.8, ls="--",
                    label=f"peak threshold (false alarm {PEAK_FALSE_ALARM:.0%})")
    top = min(check.fs / 2.0, max(8.5 * check.f_b, 1.3 * float(peaks["frequency"].max()) if len(peaks) else 0.0))
    for k in range(1, int(top / check.f_b) + 1):
        ax.axvline(k * check.f_b, color="tab:green", lw=0.6, alpha=0.6, zorder=0)
        ax.text(k * check.f_b, 1.0, f"{k}$f_b$", transform=ax.get_xaxis_transform(), ha="center",
                     va="bottom", fontsize=7, color="tab:green")
    shown = peaks[peaks["frequency"] <= top].head(8)
    for _, row in shown.iterrows():
        ax.plot(row["frequency"], row["power"], "v", color="k", ms=5)
        text = row["label"].replace("harmonic ", "h") if row["label"] != "non-harmonic" else "non-harm."
        ax.annotate(f"{text}\n{row['frequency']:.2f} Hz", (row["frequency"], row["power"]),
                         xytext=(0, 6), textcoords="offset points", ha="center", va="bottom", fontsize=7)
    ax.set_xlim(0.0, top)
    visible = (freq <= top) & (freq > 0)
    low = min(float(np.min(psd[visible])), peaks.attrs["noise_floor"]) if visible.any() else 1e-6
    high = max(float(np.max(p_m[(f_m <= top) & (f_m > 0)])), float(np.max(psd[visible]))) if visible.any() else 1.0
    ax.set_ylim(low / 3.0, high * 8.0)
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("PSD (N$^2$/Hz)")
    ax.set_title(f"(5) Residual spectrum (Welch, resolution {peaks.attrs['resolution']:.2f} Hz); green: "
                      f"multiples of median $f_b$ = {check.f_b:.2f} Hz", loc="left", fontsize=10, pad=14)
    ax.legend(fontsize=7, loc="upper right", ncol=2)
    ax.grid(True, which="major", lw=0.4, alpha=0.5)

def _plot_phase_profile(check, ax):
    """Panel (6): residual against the cycle phase."""
    profile = check.phase_profile()
    ax.fill_between(profile["phase"], profile["mean"] - profile["sd"], profile["mean"] + profile["sd"],
                          step="mid", color="tab:red", alpha=0.2, lw=0, label="$\\pm$1 sd")
    ax.step(profile["phase"], profile["mean"], where="mid", color="tab:red", lw=1.5, label="mean residual")
    ax.errorbar(profile["phase"], profile["mean"], yerr=2 * profile["sem"], fmt="none", color="tab:red",
                      lw=0.8, capsize=2, label="$\\pm$2 standard errors")
    ax.axhline(0.0, color="0.3", lw=0.6)
    ax.set_xlim(0.0, 1.0)
    ax.set_xlabel("cycle phase $(t - t_{start}) / (t_{end} - t_{start})$  (0, 1: GRF peaks)")
    ax.set_ylabel("residual (N)")
    scale = 100.0 / check.weight
    secondary = ax.secondary_yaxis("right", functions=(lambda x: x * scale, lambda x: x / scale))
    secondary.set_ylabel("% BW")
    ax.set_title("(6) Residual against cycle phase", loc="left", fontsize=10)
    ax.legend(fontsize=7, loc="upper left", ncol=3)
    ax.grid(True, lw=0.4, alpha=0.5)

def _plot_correlations(check, ax):
    """Panel (7): correlations of the residual with candidate terms."""
    corr = check.cross_correlation().iloc[::-1]
    signed = np.isfinite(corr["corr"].to_numpy())
    colours = np.where(~signed, "0.55", np.where(corr["corr"].fillna(0) >= 0, "tab:blue", "tab:orange"))
    ax.barh(np.arange(len(corr)), corr["max_abs_corr"], color=colours)
    ax.set_yticks(np.arange(len(corr)))
    ax.set_yticklabels(corr["signal"], fontsize=8)
    for y, (_, row), has_sign in zip(range(len(corr)), corr.iterrows(), signed):
        text = f" {row['corr']:+.2f}" if has_sign else f" R {row['max_abs_corr']:.2f}"
        if row["lag_s"] != 0:
            text += f" @ {1e3 * row['lag_s']:+.0f} ms"
        ax.text(row["max_abs_corr"], y, text, va="center", fontsize=7)
    ax.set_xlim(0.0, min(1.15, max(0.3, 1.3 * float(np.nan_to_num(corr["max_abs_corr"]).max()))))
    ax.set_xlabel("|correlation| with the residual")
    ax.set_title("(7) Residual vs candidate terms, force-basis\nfit removed (blue +, orange -, grey: multiple R)",
                      loc="left", fontsize=10)
    ax.grid(True, axis="x", lw=0.4, alpha=0.5)
