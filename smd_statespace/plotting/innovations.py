"""The innovations' four panels that every model's diagnostics figure begins with, drawn one way for all.

Whatever the estimator, a model that is right leaves one-step innovations that, divided by their predicted
sd, are white N(0, 1). Four panels show how far they are from it (statsmodels' ``plot_diagnostics``, with
the tests' p-values in the titles): (1) the standardised innovations over time, with the marks of the cycle
starts; (2) their histogram against N(0, 1) and against a normal of their own sd; (3) a normal Q-Q plot; (4)
their autocorrelation with the Ljung-Box p-value. The per-cycle check (``ModelCheck.plot_diagnostics``) and
the record-level person (``PersonResult.plot_diagnostics``) hand :func:`plot_innovation_panels` an
:class:`Innovations` of their own and add their own panels below.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats

__all__ = ["Innovations", "plot_innovation_panels"]


@dataclass(frozen=True)
class Innovations:
    """What the four panels draw: a model's standardised innovations and their tests.

    Attributes
    ----------
    time : ndarray
        Sample times (s).
    values : ndarray
        Standardised innovations (NaN where a sample has none: it is left out of every panel).
    acf : ndarray
        Their autocorrelation at lags 0..L (samples).
    ljung_box_p : float
        The Ljung-Box p-value at lag L.
    normality : dict
        ``pvalue`` (Jarque-Bera), ``skew`` and ``kurtosis`` (3 for a normal distribution).
    sample_interval : float
        Seconds per lag.
    marks : ndarray
        Times (s) of the vertical marks of panel (1): the cycle starts.
    acf_name : str
        Panel (4)'s name for the autocorrelation (``"ACF within cycles"`` where each cycle is filtered afresh).
    """

    time: np.ndarray
    values: np.ndarray
    acf: np.ndarray
    ljung_box_p: float
    normality: dict
    sample_interval: float
    marks: np.ndarray = ()
    acf_name: str = "ACF"


def plot_innovation_panels(innovations: Innovations, ax_time, ax_hist, ax_qq, ax_acf) -> None:
    """Draw panels (1)-(4) of the module docstring on the four axes given."""
    _plot_series(innovations, ax_time)
    z = np.asarray(innovations.values, dtype=float)
    z = z[np.isfinite(z)]
    _plot_histogram(z, innovations.normality, ax_hist)
    _plot_qq(z, innovations.normality, ax_qq)
    _plot_acf(innovations, z.size, ax_acf)


def _plot_series(innovations: Innovations, ax) -> None:
    """Panel (1): standardised innovations over time, with the marks."""
    time, z = innovations.time, np.asarray(innovations.values, dtype=float)
    ax.plot(time, z, color="tab:blue", lw=0.6)
    for level in (-2, 2):
        ax.axhline(level, color="tab:red", lw=0.8, ls="--")
    ax.axhline(0.0, color="0.3", lw=0.6)
    for mark in np.asarray(innovations.marks, dtype=float):
        if time[0] <= mark <= time[-1]:
            ax.axvline(mark, color="0.6", lw=0.5, zorder=0)
    ax.set_xlim(time[0], time[-1])
    finite = z[np.isfinite(z)]
    outside = float(np.mean(np.abs(finite) > 2.0)) if finite.size else float("nan")
    ax.set_title(f"(1) Standardised innovations of $\\ddot u$: sd {np.std(finite):.2f} (1 expected), "
                 f"{100 * outside:.1f} % beyond $\\pm$2 (4.6 % expected); grey lines: cycle starts",
                 loc="left", fontsize=10)
    ax.set_xlabel("time (s)")
    ax.grid(True, lw=0.4, alpha=0.5)


def _plot_histogram(z, normality: dict, ax) -> None:
    """Panel (2): histogram of the innovations against N(0, 1)."""
    span = max(4.0, float(np.max(np.abs(z))) if z.size else 4.0)
    ax.hist(z, bins=np.linspace(-span, span, 41), density=True, color="tab:blue", alpha=0.6, label="innovations")
    grid_x = np.linspace(-span, span, 200)
    ax.plot(grid_x, stats.norm.pdf(grid_x), color="k", lw=1.2, label="N(0, 1)")
    ax.plot(grid_x, stats.norm.pdf(grid_x, scale=max(np.std(z), 1e-12)), color="tab:green", lw=1.0, ls="--",
            label=f"N(0, {np.std(z):.2f}$^2$)")
    ax.set_title(f"(2) Histogram; Jarque-Bera p = {normality['pvalue']:.2g}", loc="left", fontsize=10)
    ax.legend(fontsize=7, loc="upper right")
    ax.set_xlabel("standardised innovation")


def _plot_qq(z, normality: dict, ax) -> None:
    """Panel (3): normal Q-Q plot of the innovations."""
    (theoretical, ordered), _ = stats.probplot(z, dist="norm")
    limit = max(float(np.max(np.abs(theoretical))), float(np.max(np.abs(ordered))))
    ax.plot(theoretical, ordered, ".", ms=2.5, color="tab:blue")
    ax.plot([-limit, limit], [-limit, limit], color="k", lw=1.0, label="N(0, 1)")
    ax.set_title(f"(3) Normal Q-Q: skew {normality['skew']:.2f}, kurtosis {normality['kurtosis']:.2f}",
                 loc="left", fontsize=10)
    ax.set_xlabel("normal quantile")
    ax.set_ylabel("innovation quantile")
    ax.legend(fontsize=7, loc="upper left")


def _plot_acf(innovations: Innovations, count: int, ax) -> None:
    """Panel (4): the autocorrelation with its band and the Ljung-Box p-value."""
    acf = np.asarray(innovations.acf, dtype=float)
    lags = np.arange(1, acf.size)
    ax.vlines(lags, 0.0, acf[1:], color="tab:blue", lw=2.0)
    ax.plot(lags, acf[1:], "o", color="tab:blue", ms=3)
    band = 1.96 / np.sqrt(max(count, 1))
    ax.axhspan(-band, band, color="tab:blue", alpha=0.15, lw=0, label="$\\pm 1.96/\\sqrt{n}$")
    ax.axhline(0.0, color="0.3", lw=0.6)
    ax.set_xlabel(f"lag (samples of {innovations.sample_interval:.4g} s)")
    ax.set_title(f"(4) {innovations.acf_name}; Ljung-Box p = {innovations.ljung_box_p:.2g}", loc="left", fontsize=10)
    ax.legend(fontsize=7, loc="upper right")
    ax.set_xlim(0.3, lags.size + 0.7)
