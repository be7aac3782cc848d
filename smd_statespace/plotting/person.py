"""Figures of a record-level person: how it fits, where the model fails, and what an added effect changed.

- :func:`plot_person_fit`: measured against one-step predicted COM acceleration where the fit
  is best and worst, and every cycle's load factors (``PersonResult.plot_fit``);
- :func:`plot_person_diagnostics`: the innovations' four panels, as a per-cycle check's
  (``PersonResult.plot_diagnostics``, :mod:`~smd_statespace.plotting.innovations`);
- :func:`plot_spectrum`: the innovations' spectrum with the multiples of the
  bouncing frequency marked, without and with the effects;
- :func:`plot_compare`: measured against free-run simulated COM acceleration
  with a fit percentage (MATLAB's ``compare``), without and with the effects;
- :func:`plot_floor_correlation`: the innovations' cross-correlation with the
  measured floor acceleration, when the record has one;
- :func:`plot_candidates`: what ``diagnose`` found, the generic terms' score tests and the
  candidates' likelihood ratios against their levels.

Every function builds a :class:`matplotlib.figure.Figure` without pyplot,
saves it when given a ``path`` and returns it. Times are in seconds.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from scipy import signal

from ..measures import fit_percent
from ..person.supremum import critical_value
from ..person.noise_floor import measured_label
from .innovations import Innovations, plot_innovation_panels
from .save import save

__all__ = ["plot_person_fit", "plot_person_diagnostics", "plot_spectrum", "plot_compare",
           "plot_held_out", "plot_floor_correlation", "plot_candidates", "plot_step_scan"]

COLORS = {"without": "tab:red", "with": "tab:blue"}


DPI = 110
"""Dots per inch of this module's figures."""


def _name(result) -> str:
    return Path(str(result.record.source)).name


def _label(result) -> str:
    from ..effects.generic import label

    return ("with " + ", ".join(label(e) for e in result.effects)) if result.effects else "without effects"


def _pairs(result) -> list:
    """``[(label, result)]``: the fit without the effects first when there is one."""
    if result.before is None:
        return [("model", result)]
    return [("without", result.before), ("with", result)]


def plot_spectrum(result, path=None) -> Figure:
    """Welch spectrum of the standardised innovations (8 s segments), multiples of ``f_b`` dashed.

    White innovations are flat at 1/(fs/2); a line left at a multiple of ``f_b``
    is a harmonic the model lacks (extra force harmonics, a nonlinear spring),
    a line elsewhere a resonance it lacks (a floor mode).
    """
    fig = Figure(figsize=(9.5, 4.2))
    fig.subplots_adjust(left=0.105, right=0.985, bottom=0.12, top=0.91)  # fixed: a layout engine costs 0.15 s here
    ax = fig.subplots()
    fs = result.record.fs
    f_b = float(np.median(result.model.timing.f_b))
    for label, fitted in _pairs(result):
        innov = fitted.standardized_innovations()
        frequency, power = signal.welch(innov, fs=fs, nperseg=min(innov.size, int(8 * fs)))
        p = fitted.test_pvalues()["ljung_box_p"]
        ax.semilogy(frequency, power, color=COLORS.get(label, "tab:blue"), lw=1.1,
                    label=f"{_label(fitted)}: Ljung-Box p {p:.2g}")
    for k in range(1, int(0.5 * fs / f_b) + 1):
        ax.axvline(k * f_b, color="0.6", ls="--", lw=0.7, zorder=0)
    ax.axhline(2.0 / fs, color="k", lw=0.8, ls=":", label="white noise")
    ax.set(xlabel="frequency (Hz)", ylabel="innovation PSD (1/Hz)", xlim=(0, min(0.5 * fs, 12 * f_b)))
    ax.legend(fontsize=8, loc="upper right")
    ax.set_title(f"{_name(result)}: innovations' spectrum; dashed: multiples of f_b = {f_b:.2f} Hz", fontsize=10)
    return save(fig, path, DPI)


def _worst_window(time, residual, seconds) -> float:
    """Start (s) of the ``seconds`` window with the largest residual energy."""
    dt = time[1] - time[0]
    width = max(int(round(seconds / dt)), 1)
    energy = np.convolve(np.nan_to_num(residual) ** 2, np.ones(width), mode="valid")  # NaN: not predicted
    return float(time[int(np.argmax(energy))])


def _longest_run(time, mask) -> np.ndarray:
    """The times of the longest run of consecutive samples where ``mask`` holds (the held-out parts a run predicts:
    the middle of the record is not one where two folds hold out its ends)."""
    edges = np.flatnonzero(np.diff(np.r_[0, mask.astype(int), 0]))
    starts, ends = edges[::2], edges[1::2]
    longest = int(np.argmax(ends - starts))
    return time[starts[longest]:ends[longest]]


def _compare_figure(time, y, runs, title, seconds, cuts=(), one_step=None, measured="measured") -> Figure:
    """Measured against simulated runs ``[(color key, label, run)]``: the residuals, the worst window, the middle.

    ``measured``: the legend label of ``y`` (:func:`~smd_statespace.person.noise_floor.measured_label`).

    ``one_step``: one-step predictions ``[(color key, label, prediction)]`` drawn as their errors in a first panel.
    Samples a run does not predict (NaN) are left out of its fit % and of the middle window.
    """
    fig = Figure(figsize=(10.0, 7.5 if one_step is None else 9.6))
    top = 0.955 if "\n" not in title else 0.94
    fig.subplots_adjust(left=0.08, right=0.985, bottom=0.07, top=top, hspace=0.42)  # fixed: no layout engine
    axes = list(fig.subplots(3 if one_step is None else 4, 1))
    panels = [(axes.pop(0), one_step, "one-step prediction error (m/s$^2$)")] if one_step is not None else []
    panels.append((axes[0], runs, "measured - simulated (m/s$^2$)"))
    for ax, series, ylabel in panels:
        for key, label, predicted in series:
            known = np.isfinite(predicted)
            ax.plot(time, y - predicted, color=COLORS.get(key, "tab:blue"), lw=0.6, alpha=0.85,
                    label=f"{label}: fit {fit_percent(y[known], predicted[known]):.1f} %")
        for number, cut in enumerate(cuts):  # where the fitted and held-out parts meet
            ax.axvline(cut, color="k", lw=1.0, ls="--", label="fitted | held out" if number == 0 else None)
        ax.set(xlabel="time (s)", ylabel=ylabel)
        ax.legend(fontsize=8, loc="upper right")
    panels[0][0].set_title(title, fontsize=10)
    worst, middle = axes[1:]
    covered = _longest_run(time, np.isfinite(runs[0][2]))  # the longest stretch the runs predict
    starts = (_worst_window(time, y - runs[0][2], seconds), covered[0] + 0.5 * (covered[-1] - covered[0]) - seconds / 2)
    for ax, start, what in ((worst, starts[0], "free run, where the model without misses most"),
                            (middle, starts[1], "free run, middle")):
        shown = (time >= start) & (time <= start + seconds)
        ax.plot(time[shown], y[shown], color="k", lw=1.4, label=measured)
        for key, label, run in runs:
            ax.plot(time[shown], run[shown], color=COLORS.get(key, "tab:blue"), lw=1.0, label=label)
        ax.set(xlabel="time (s)", ylabel="GRF/M - g (m/s$^2$)")
        ax.set_title(what, fontsize=9, loc="left")
        ax.legend(fontsize=8, loc="upper right", ncol=3)
    return fig


def plot_compare(result, path=None, seconds: float = 3.0) -> Figure:
    """Measured against free-run simulated ``GRF / M_h - g``, with the fit % (MATLAB ``compare``).

    The simulation is ``PersonResult.free_run`` (the template force in every cycle), so
    the fit % counts the cycles' own variation as misfit for every model alike;
    what an effect changes is the part of the response the template cannot
    make. Top: the whole record's residual (measured - simulated) without and
    with the effects. Below: the window of ``seconds`` where the model without
    the effects misses most, and the middle of the record.
    """
    runs = [(key, _label(fitted), fitted.free_run()) for key, fitted in _pairs(result)]
    title = f"{_name(result)}: free-run simulation against the measurement"
    return save(_compare_figure(result.model.time, result.model.y, runs, title, seconds,
                                measured=measured_label(result.notes)), path, DPI)


def plot_held_out(diagnosis, name, path=None, seconds: float = 3.0) -> Figure:
    """The held-out free run without and with the candidate ``name`` (MATLAB ``compare`` on validation data).

    Each half of the record is simulated by the person fitted on the other half
    (:func:`~smd_statespace.person.validation.cross_validated_loglike`: its template in every cycle, the
    half's own initial state estimated), so every sample drawn was held out of the fit that predicts it. First
    panel: the one-step prediction errors, with the held-out log-likelihood (what ``diagnose`` judges by); then
    the free run as :func:`plot_compare` draws it. Each legend gives the fit %.
    """
    before, after = diagnosis.held_out_pair(name)
    pairs = (("without", "without", before), ("with", f"with {name}", after))
    runs = [(key, label, check["free_run"]) for key, label, check in pairs]
    one_step = [(key, f"{label} (held-out log-likelihood {check['loglike']:.1f})", check["one_step"])
                for key, label, check in pairs]
    title = f"{_name(diagnosis.base)}: each half predicted by the person fitted on the other half"
    if len(after["cuts"]) != 1 or len(after["folds"]) == 1:  # a change in time: parts that hold it were fitted
        first, last = float(after["time"][0]), float(after["time"][-1])
        held = [(fold["end"], last) if fold["start"] <= first else (first, fold["start"]) for fold in after["folds"]]
        title = (f"{_name(diagnosis.base)}: each part held out predicted by the person fitted across the change\n"
                 + "; ".join(f"{low:.1f}-{high:.1f} s by the fit on {fold['start']:.1f}-{fold['end']:.1f} s"
                             for (low, high), fold in zip(held, after["folds"])))
    return save(_compare_figure(before["time"], before["measured"], runs, title, seconds, cuts=before["cuts"],
                                one_step=one_step, measured=measured_label(diagnosis.base.notes)), path, DPI)


def plot_floor_correlation(result, path=None, max_lag: float = 1.0) -> Figure:
    """Cross-correlation of the standardised innovations with the measured floor acceleration, lags ±``max_lag`` s.

    Outside the ±1.96/sqrt(N) band the floor explains part of what the model
    misses: the leg acts on the motion relative to the floor (``--effect floor_mode``).
    """
    floor = getattr(result.record, "floor_acc", None)
    if floor is None:
        raise ValueError(f"{result.record.source}: no floor_acc column to correlate with")
    fs = result.record.fs
    lags = np.arange(-int(max_lag * fs), int(max_lag * fs) + 1)
    fig = Figure(figsize=(9.0, 3.8), layout="constrained")
    ax = fig.subplots()
    floor = (np.asarray(floor) - np.mean(floor)) / np.std(floor)
    for label, fitted in _pairs(result):
        innov = fitted.standardized_innovations()
        innov = (innov - innov.mean()) / innov.std()
        n = innov.size
        values = [np.mean(innov[max(0, -k):n - max(0, k)] * floor[max(0, k):n - max(0, -k)]) for k in lags]
        ax.plot(lags / fs, values, color=COLORS.get(label, "tab:blue"), lw=1.0, label=_label(fitted))
    band = 1.96 / np.sqrt(floor.size)
    ax.axhspan(-band, band, color="0.85", label="±1.96/sqrt(N)")
    ax.set(xlabel="lag of the floor acceleration (s)", ylabel="correlation")
    ax.legend(fontsize=8, loc="upper right")
    ax.set_title(f"{_name(result)}: innovations against the measured floor acceleration", fontsize=10)
    return save(fig, path, DPI)


def plot_person_fit(result, path=None, seconds=3.0, truth=None) -> Figure:
    """Measured against one-step predicted ``GRF / M_h - g`` where the fit is best and worst, and every cycle's BLFs.

    The two windows of ``seconds`` are those with the smallest and the largest RMS innovation
    (at 100 Hz a one-step prediction looks good almost everywhere: the worst window shows where
    it does not). The template's BLFs are drawn with their intervals at the result's ``level`` (sds with the person's uncertainty,
    :meth:`~smd_statespace.person.results.PersonResult.template_blf`). ``truth`` (flat keys ``f_h``, ``xi_h``,
    ``blf_1``, ..., as :func:`~smd_statespace.io.truth_values` gives them) is drawn as dashed
    lines and named in the title.
    """
    truth = dict(truth or {})
    _, raw = result.model.innovations(result.params, result.filtered)
    t, y = result.model.time, result.model.y
    width = max(1, min(int(round(seconds * result.record.fs)), t.size))
    power = np.convolve(raw**2, np.ones(width) / width, mode="valid")  # mean square over each window
    worst = int(np.argmax(power))
    apart = np.abs(np.arange(power.size) - worst) >= width  # the best window does not overlap the worst
    best = int(np.argmin(np.where(apart, power, np.inf))) if apart.any() else int(np.argmin(power))
    fig = Figure(figsize=(11, 6.8))
    grid = fig.add_gridspec(2, 2, left=0.065, right=0.985, bottom=0.08, top=0.89, hspace=0.38, wspace=0.12)
    known = (f" (truth {truth['f_h']:.2f} Hz, {truth['xi_h']:.2f})" if {"f_h", "xi_h"} <= set(truth) else "")
    fig.suptitle(f"{_name(result)}: f_h {result.f_h:.2f} Hz, xi_h {result.xi_h:.2f}{known}")
    for column, (first, label) in enumerate(((best, "best"), (worst, "worst"))):
        ax = fig.add_subplot(grid[0, column])
        window = slice(first, first + width)
        ax.plot(t[window], y[window], color="0.3", lw=1.2, label=measured_label(result.notes))
        ax.plot(t[window], (y - raw)[window], color="C1", lw=1.0, label="predicted one step ahead")
        ax.plot(t[window], raw[window], color="C3", lw=0.8, label="innovation")
        for b in result.model.timing.boundaries:
            if t[window][0] <= b <= t[window][-1]:
                ax.axvline(b, color="0.8", lw=0.6, zorder=0)
        rms = float(np.sqrt(power[first]))
        ax.set(xlabel="time (s)", ylabel="GRF/M - g (m/s$^2$)" if column == 0 else None,
               title=f"{label} {seconds:g} s: RMS innovation {rms:.3f} m/s$^2$ (grey: cycle starts)")
        if column == 0:
            ax.legend(loc="upper right", fontsize=7, ncol=3)
    bx = fig.add_subplot(grid[1, :])
    cycles = result.cycles
    blf = result.template_blf()
    for i in range(1, result.model.n_harmonics + 1):
        bx.errorbar(cycles["t_start"], cycles[f"blf_{i}"], yerr=cycles[f"blf_{i}_sd"], fmt="o", ms=3,
                    color=f"C{i - 1}", label=f"BLF{i}")
        bx.axhline(blf.loc[i, "blf"], color=f"C{i - 1}", lw=0.8)
        bx.axhspan(blf.loc[i, "low"], blf.loc[i, "high"], color=f"C{i - 1}", alpha=0.12, lw=0)
        if f"blf_{i}" in truth:
            bx.axhline(truth[f"blf_{i}"], color=f"C{i - 1}", lw=1.0, ls="--")
    bx.set(xlabel="cycle start (s)", ylabel="BLF (g)",
           title=f"every cycle's load factors (smoother); lines and bands: template, {result.level:.0%} interval"
           + ("; dashed: truth" if any(k.startswith("blf_") for k in truth) else ""))
    bx.legend(loc="upper right", fontsize=8, ncol=4)
    return save(fig, path, DPI)


def plot_person_diagnostics(result, path=None, lags=None) -> Figure:
    """The standardised innovations over time, their histogram, normal Q-Q plot and autocorrelation with the
    residual tests' p-values (:func:`~smd_statespace.plotting.innovations.plot_innovation_panels`, as a per-cycle
    check's first four panels); saved as PNG if ``path``.

    ``lags``: of the autocorrelation and the Ljung-Box test (default: the result's, whose p-value the summary and
    ``test_pvalues`` give).
    """
    from statsmodels.tsa.stattools import acf

    lags = int(lags or result.default_lags())
    values = np.where(result.model.observed, result.standardized_innovations(), np.nan)
    normality = result.test_normality()[0]  # statsmodels' (statistic, p-value, skew, kurtosis)
    innovations = Innovations(time=result.model.time, values=values, acf=acf(values, nlags=lags, missing="drop"),
                              ljung_box_p=float(result.test_serial_correlation(lags)[0, 1, lags - 1]),
                              normality={"pvalue": normality[1], "skew": normality[2], "kurtosis": normality[3]},
                              sample_interval=result.model.dt, marks=result.model.timing.boundaries)
    fig = Figure(figsize=(11.0, 7.5))
    grid = fig.add_gridspec(2, 3, height_ratios=[0.8, 1.0], hspace=0.45, wspace=0.28, left=0.07, right=0.98,
                            top=0.9, bottom=0.08)
    plot_innovation_panels(innovations, fig.add_subplot(grid[0, :]), *(fig.add_subplot(grid[1, i]) for i in range(3)))
    fig.suptitle(f"{_name(result)}: innovations of GRF/M - g (record-level model, {_label(result)})", x=0.07,
                 ha="left")
    return save(fig, path, DPI)


def plot_candidates(diagnosis, path=None) -> Figure:
    """What ``diagnose`` found: the generic terms' score tests and the fitted candidates' likelihood ratios.

    Left: every generic term's robust score statistic (chi-square(1) under "absent"; a step a scan placed, the
    largest of the scan's: its own level as a tick), with Holm's first level over the library (``alpha / terms``),
    in blue the terms fitted as candidates (those whose quick fit passed over the library, at most
    :data:`~smd_statespace.person.diagnose.SCREENED`: the screened table's ``fitted``), in light
    blue any others that passed; right: each fitted candidate's likelihood
    ratio over its misspecification scale (:func:`~smd_statespace.person.robust.robust_scale`) against the level
    of its own test (Bonferroni over every test, and over a floor mode's frequency grid): the proposal in blue (the
    first of :meth:`~smd_statespace.person.diagnose.PersonDiagnosis.table`), the others that pass in light blue.
    """
    fig = Figure(figsize=(11, 4.4), layout="constrained")
    left, right = fig.subplots(1, 2, width_ratios=(1.15, 1))
    screened = diagnosis.screened
    if len(screened):
        names = [name.replace("term:", "") for name in screened["label"]][::-1]
        values = screened["lm_robust"].to_numpy()[::-1]
        gate = "p_quick_holm" if "p_quick_holm" in screened else "p_holm"  # what decided the fit (screen's stages)
        passed = (screened[gate] < diagnosis.alpha).to_numpy()
        # the terms diagnose fitted: those passed, at most SCREENED (a third that passed is not fitted)
        fitted = screened["fitted"].to_numpy(dtype=bool) if "fitted" in screened else passed
        colours = np.where(fitted, "tab:blue", np.where(passed, "lightsteelblue", "0.6"))[::-1]
        left.barh(names, values, color=colours)
        first_level = diagnosis.alpha / len(screened)
        left.axvline(critical_value(first_level), color="k", ls="--", lw=0.8,
                     label=f"Holm's first level (alpha {diagnosis.alpha:g} over {len(screened)})")
        trims = screened["scan_trim"].to_numpy(dtype=float)[::-1] if "scan_trim" in screened else []
        for y, trim in enumerate(trims):  # a step a scan placed: its level as the largest of the scan's
            if np.isfinite(trim):
                left.plot([critical_value(first_level, 1, trim)] * 2, [y - 0.4, y + 0.4], color="k", lw=1.2)
        left.set_xscale("symlog", linthresh=10.0)
        left.legend(fontsize=8, loc="lower right")
    left.set(xlabel="robust score statistic (no fit)",
             title="generic terms at the fitted person\n(blue: fitted; light blue: passed by a quick fit, not fitted)")
    table = diagnosis.table()
    if not table.empty:
        level = diagnosis.level
        names = list(table.index)[::-1]
        ratios = np.maximum(table["lr_robust"].to_numpy(dtype=float), 0.0)[::-1]
        passes = table["significant"].to_numpy(dtype=bool)
        proposed = np.arange(len(table)) == 0  # the table's order: the proposal first, when any passes
        colours = np.where(passes & proposed, "tab:blue", np.where(passes, "lightsteelblue", "0.6"))[::-1]
        right.barh(names, ratios, color=colours)
        degrees = table["df"].to_numpy(dtype=int)[::-1]
        trials = table["trials"].to_numpy(dtype=float)[::-1]  # a floor mode's frequency grid: tested as that many
        trims = table["scan_trim"].to_numpy(dtype=float)[::-1]  # a step a scan placed: the largest of the scan's
        for y, (df, tried, trim) in enumerate(zip(degrees, trials, trims)):
            right.plot([critical_value(level / tried, df, trim)] * 2, [y - 0.4, y + 0.4], color="k", lw=1.2)
        right.set_xscale("symlog", linthresh=10.0)
    right.set(xlabel="likelihood ratio / its scale (black: its test's level)",
              title="candidates fitted with the person\n(blue: proposed; light blue: also passes its test)")
    fig.suptitle(f"{_name(diagnosis.base)}: is an effect missing?", fontsize=10)
    return save(fig, path, DPI)


def plot_step_scan(diagnosis, path=None) -> Figure:
    """When does the person change? The score statistics of a step of ``f_h`` and of ``xi_h`` at every time
    ``diagnose``'s scan tested (:func:`~smd_statespace.person.breaks.step_scan`), against the record's time.

    Per kind of step a panel: the robust (cycle-clustered) statistic in blue and the plain one in grey, the
    level of the largest of them at ``diagnose``'s level (Andrews' distribution,
    :func:`~smd_statespace.person.breaks.critical_value`) dashed, and where the step was placed (the plain
    statistic's largest) as a vertical line. A person who changes once shows one peak above the line; a drift,
    a broad hump; a person who does not change, nothing above it.
    """
    scans = diagnosis.scans
    fig = Figure(figsize=(10, 2.6 * max(len(scans), 1)), layout="constrained")
    axes = np.atleast_1d(fig.subplots(max(len(scans), 1), 1, sharex=True, squeeze=False)[:, 0])
    parameter = {"f_step": "f_h (stiffness)", "xi_step": "xi_h (damping)"}
    for ax, (kind, scan) in zip(axes, scans.items()):
        table = scan["table"]
        ax.plot(table["time_s"], table["lm"], color="0.6", lw=0.7, label="score statistic")
        ax.plot(table["time_s"], table["lm_robust"], color="tab:blue", lw=0.9, label="robust (cycles as clusters)")
        ax.axhline(critical_value(diagnosis.level, 1, scan["trim"]), color="k", ls="--", lw=0.8,
                   label=f"level of the largest (p {diagnosis.level:.2g})")
        ax.axvline(scan["time_s"], color="tab:red", lw=0.8, label=f"placed at {scan['time_s']:.2f} s")
        ax.set_yscale("symlog", linthresh=10.0)
        ax.set_ylim(bottom=0.0)
        ax.set(ylabel="statistic", title=f"a step of {parameter.get(kind, kind)}: largest robust "
                                          f"{scan['lm_robust']:.1f}, p {scan['p']:.2g} as the largest of the scan")
        ax.legend(fontsize=7, loc="upper right")
    axes[-1].set_xlabel("time (s, the record's)")
    fig.suptitle(f"{_name(diagnosis.base)}: when does the person change? a step tested at every sample",
                 fontsize=10)
    return save(fig, path, DPI)
