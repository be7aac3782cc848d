"""Figures of a record-level person: where the model fails, and what an added effect changed.

- :func:`plot_spectrum`: the innovations' spectrum with the multiples of the
  bouncing frequency marked, without and with the effects;
- :func:`plot_compare`: measured against free-run simulated COM acceleration
  with a fit percentage (MATLAB's ``compare``), without and with the effects;
- :func:`plot_floor_correlation`: the innovations' cross-correlation with the
  measured floor acceleration, when the record has one.

Every function builds a :class:`matplotlib.figure.Figure` without pyplot,
saves it when given a ``path`` and returns it. Times are in seconds.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from scipy import signal

__all__ = ["free_run", "fit_percent", "plot_spectrum", "plot_compare", "plot_floor_correlation"]

COLORS = {"without": "tab:red", "with": "tab:blue"}


def _save(fig: Figure, path):
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig


def _name(result) -> str:
    return Path(str(result.record.source)).name


def _label(result) -> str:
    return ("with " + ", ".join(e.name for e in result.effects)) if result.effects else "without effects"


def _pairs(result) -> list:
    """``[(label, result)]``: the fit without the effects first when there is one."""
    if result.before is None:
        return [("model", result)]
    return [("without", result.before), ("with", result)]


def free_run(result) -> np.ndarray:
    """The COM acceleration ``GRF / M_h - g`` (m/s^2) the model gives when simulated freely over the record.

    The force is the record's template in every cycle (the cycles' own
    variation is what the model leaves to chance; a smoothed per-cycle force
    would absorb the model's misfit too), on the model's cycle timing; the
    dynamics start from the estimated initial state and run without any
    correction by the measurement. For a nonlinear effect the run uses the
    model linearised about its fitted path.
    """
    model = result.model
    system = model.system(result.params)
    nx, p = model.n_dynamic, system["H"].shape[1]
    delta = result.filtered["delta"]
    force = np.zeros((model.y.size, p))
    force[:, :model.n_coefficients] = delta[nx:nx + model.n_coefficients]  # the template (phase errors 0)
    beta = delta[nx + model.n_coefficients:]
    n = model.y.size
    phi = np.broadcast_to(system["Phi"], (n, nx, nx))
    hx = np.broadcast_to(system["hx"], (n, nx))
    drive = np.einsum("kij,kj->ki", system["Gam"], force) + system["offset"]
    if beta.size:
        drive = drive + system["X_tr"] @ beta
    states = np.empty((n, nx))
    states[0] = delta[:nx]
    for k in range(1, n):
        states[k] = phi[k - 1] @ states[k - 1] + drive[k - 1]
    out = np.einsum("ki,ki->k", hx, states) + np.einsum("kj,kj->k", system["H"], force) + system["y_known"]
    return out + (system["X_obs"] @ beta if beta.size else 0.0)


def fit_percent(measured, predicted) -> float:
    """MATLAB's ``compare`` fit: ``100 (1 - |y - y_hat| / |y - mean(y)|)`` (%)."""
    measured = np.asarray(measured, dtype=float)
    return float(100.0 * (1.0 - np.linalg.norm(measured - predicted) / np.linalg.norm(measured - measured.mean())))


def plot_spectrum(result, path=None) -> Figure:
    """Welch spectrum of the standardised innovations (8 s segments), multiples of ``f_b`` dashed.

    White innovations are flat at 1/(fs/2); a line left at a multiple of ``f_b``
    is a harmonic the model lacks (extra force harmonics, a nonlinear spring),
    a line elsewhere a resonance it lacks (a floor mode).
    """
    fig = Figure(figsize=(9.5, 4.2), layout="constrained")
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
    return _save(fig, path)


def _worst_window(time, residual, seconds) -> float:
    """Start (s) of the ``seconds`` window with the largest residual energy."""
    dt = time[1] - time[0]
    width = max(int(round(seconds / dt)), 1)
    energy = np.convolve(residual**2, np.ones(width), mode="valid")
    return float(time[int(np.argmax(energy))])


def plot_compare(result, path=None, seconds: float = 3.0) -> Figure:
    """Measured against free-run simulated ``GRF / M_h - g``, with the fit % (MATLAB ``compare``).

    The simulation is :func:`free_run` (the template force in every cycle), so
    the fit % counts the cycles' own variation as misfit for every model alike;
    what an effect changes is the part of the response the template cannot
    make. Top: the whole record's residual (measured - simulated) without and
    with the effects. Below: the window of ``seconds`` where the model without
    the effects misses most, and the middle of the record.
    """
    time, y = result.model.time, result.model.y
    pairs = [(label, fitted, free_run(fitted)) for label, fitted in _pairs(result)]
    fig = Figure(figsize=(10.0, 7.5), layout="constrained")
    top, worst, middle = fig.subplots(3, 1)
    for label, fitted, run in pairs:
        top.plot(time, y - run, color=COLORS.get(label, "tab:blue"), lw=0.6, alpha=0.85,
                 label=f"{_label(fitted)}: fit {fit_percent(y, run):.1f} %")
    top.set(xlabel="time (s)", ylabel="measured - simulated (m/s$^2$)")
    top.legend(fontsize=8, loc="upper right")
    top.set_title(f"{_name(result)}: free-run simulation against the measurement", fontsize=10)
    first = pairs[0]
    starts = (_worst_window(time, y - first[2], seconds), time[0] + 0.5 * (time[-1] - time[0]) - seconds / 2)
    for ax, start, what in ((worst, starts[0], "where the model misses most"), (middle, starts[1], "middle")):
        shown = (time >= start) & (time <= start + seconds)
        ax.plot(time[shown], y[shown], color="k", lw=1.4, label="measured")
        for label, fitted, run in pairs:
            ax.plot(time[shown], run[shown], color=COLORS.get(label, "tab:blue"), lw=1.0, label=_label(fitted))
        ax.set(xlabel="time (s)", ylabel="GRF/M - g (m/s$^2$)")
        ax.set_title(what, fontsize=9, loc="left")
        ax.legend(fontsize=8, loc="upper right", ncol=3)
    return _save(fig, path)


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
    return _save(fig, path)
