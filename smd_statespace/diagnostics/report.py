"""The model check as readable text (:meth:`smd_statespace.diagnostics.check.ModelCheck.summary`)."""

from __future__ import annotations

import numpy as np

__all__ = ["summary_text"]


def summary_text(check, n_peaks=5, n_signals=5) -> str:
    """Readable report of a model check: fit, residual size, tests, spectral peaks, strongest correlations.

    Parameters
    ----------
    check : ModelCheck
        The model check (:func:`~smd_statespace.diagnostics.check.check_model`).
    n_peaks : int
        Largest number of residual spectrum peaks listed.
    n_signals : int
        Largest number of candidate correlations listed.

    Returns
    -------
    str
        78 characters wide; forces in N and % of body weight, frequencies in Hz.
    """
    pre = check.preprocessed
    lb = check.test_serial_correlation()
    combined = lb.loc["combined"]
    normal = check.test_normality()
    hetero = check.test_heteroskedasticity()
    _, _, peaks = check.residual_spectrum()
    corr = check.cross_correlation()
    estimator = check.table["estimator"].iloc[0] if "estimator" in check.table and len(check.table) else "?"
    width = 78
    lines = [
        "Model check".center(width),
        "=" * width,
        f"record: {getattr(pre, 'source', '?')}    model: {check.model!r}",
        f"estimator: {estimator}    cycles checked: {check.n_cycles}    samples: {check.residual.size}"
        f"    median f_b: {check.f_b:.3f} Hz",
        f"log-likelihood: {check.log_likelihood:.1f}    parameters: {check.n_parameters}"
        f"    AIC: {check.aic:.1f}    BIC: {check.bic:.1f}",
        "-" * width,
        f"fit, free simulation:        {check.fit_percent:6.2f} %",
        f"fit, one-step prediction:    {check.fit_percent_one_step:6.2f} %",
        f"residual RMS (free sim.):    {check.residual_rms:8.2f} N = {check.residual_rms_bw:.2f} % of body weight"
        f" ({check.weight:.0f} N)",
        f"  of which no re-fit of the cycles could remove: {check.residual_unabsorbed_rms_bw:.2f} % of body weight",
        f"innovation variance:         {check.innovation_variance:6.3f}   (1 if the filter's noise levels fit)",
        "-" * width,
        "Tests on the standardised innovations of u''",
        f"  Ljung-Box (per cycle, {int(combined['lags'])} dof):  Q = {combined['lb_stat']:.1f},"
        f"  p = {combined['lb_pvalue']:.3g}",
        f"  Jarque-Bera:  JB = {normal['statistic']:.1f},  p = {normal['pvalue']:.3g},"
        f"  skew = {normal['skew']:.2f},  kurtosis = {normal['kurtosis']:.2f}",
        f"  Heteroskedasticity (last/first third):  H = {hetero['statistic']:.2f},  p = {hetero['pvalue']:.3g}"
        f"  (residual ratio {hetero['residual_ratio']:.2f})",
        "-" * width,
        f"Residual spectrum peaks (noise floor {peaks.attrs['noise_floor']:.3g} N^2/Hz, threshold "
        f"x{peaks.attrs['threshold'] / peaks.attrs['noise_floor']:.1f}):",
    ]
    if len(peaks):
        for _, row in peaks.head(n_peaks).iterrows():
            lines.append(f"  {row['frequency']:6.2f} Hz  ({row['f_over_fb']:.2f} f_b)  x{row['ratio_to_floor']:7.1f}"
                         f"  {row['label']}")
    else:
        lines.append("  none above the threshold")
    lines.append("-" * width)
    lines.append("Strongest correlations of the residual with candidate terms (force-basis fit removed):")
    for _, row in corr.head(n_signals).iterrows():
        signed = f"{row['corr']:+.3f}" if np.isfinite(row["corr"]) else f"R={row['max_abs_corr']:.3f}"
        lines.append(f"  {row['signal']:<16s} {signed}")
    lines.append("=" * width)
    return "\n".join(lines)
