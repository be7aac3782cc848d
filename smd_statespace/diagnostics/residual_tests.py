"""Tests of a residual series made of independent pieces (cycles): serial correlation, normality, variance change.

Functions over arrays, used by :meth:`ModelCheck.test_serial_correlation
<smd_statespace.diagnostics.check.ModelCheck.test_serial_correlation>`,
:meth:`~smd_statespace.diagnostics.check.ModelCheck.test_normality`,
:meth:`~smd_statespace.diagnostics.check.ModelCheck.test_heteroskedasticity` and
:meth:`~smd_statespace.diagnostics.check.ModelCheck.pooled_acf`:

- :func:`split_cycles`, :func:`cycle_numbers`: a series on consecutive cycles' samples, cut into the cycles;
- :func:`default_lags`: a quarter of the median piece length, at most 20;
- :func:`ljung_box_table`: Ljung-Box per piece, combined by adding the statistics;
- :func:`pooled_acf`: the autocorrelation pooled within pieces;
- :func:`jarque_bera_test`, :func:`variance_change_test`: statsmodels' tests as dictionaries.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..errors import OptionError

__all__ = ["split_cycles", "cycle_numbers", "default_lags", "ljung_box_table", "pooled_acf", "jarque_bera_test",
           "variance_change_test"]


def split_cycles(values, cycle_index) -> list:
    """Split a series into the pieces of consecutive equal ``cycle_index``.

    Parameters
    ----------
    values : array_like, shape (T,)
    cycle_index : ndarray of int, shape (T,)
        Cycle number of each sample (each cycle's samples consecutive).

    Returns
    -------
    list of ndarray
        One piece per cycle, in order.
    """
    breaks = np.flatnonzero(np.diff(cycle_index)) + 1
    return np.split(np.asarray(values), breaks)


def cycle_numbers(cycle_index) -> list:
    """The cycle number of each piece of :func:`split_cycles`, as ints."""
    breaks = np.flatnonzero(np.diff(cycle_index)) + 1
    return [int(cycle_index[i]) for i in np.r_[0, breaks]]


def default_lags(pieces) -> int:
    """Default Ljung-Box lag within a cycle: a quarter of the median piece length (samples), between 1 and 20."""
    lengths = np.array([piece.size for piece in pieces])
    return int(max(1, min(np.median(lengths) // 4, 20)))


def ljung_box_table(pieces, numbers, lags) -> pd.DataFrame:
    """Ljung-Box test of each piece, and of all together.

    Each piece is tested on its own
    (:func:`statsmodels.stats.diagnostic.acorr_ljungbox`) at lag ``min(lags,
    n // 2)``; constant pieces and pieces shorter than 2 samples are left
    out. Under the null hypothesis (white, independent pieces) the
    statistics add: ``Q = sum_c Q_c`` is chi-square with ``sum_c lags_c``
    degrees of freedom, which gives the combined p-value.

    Parameters
    ----------
    pieces : list of ndarray
        The pieces (:func:`split_cycles`).
    numbers : list
        A label for each piece (the cycle number).
    lags : int
        Largest lag (samples), at least 1.

    Returns
    -------
    pandas.DataFrame
        One row per tested piece (index ``cycle``) with ``nobs``, ``lags``,
        ``lb_stat``, ``lb_pvalue``, and a last row ``"combined"`` with the
        summed statistic and degrees of freedom and the chi-square p-value
        (NaN with no degree of freedom).
    """
    from scipy import stats  # imported here: scipy.signal, scipy.stats take ~1 s (not needed to start)
    from statsmodels.stats.diagnostic import acorr_ljungbox

    if int(lags) < 1:
        raise OptionError(f"lags must be a whole number >= 1, got {lags!r}")
    rows = []
    for number, piece in zip(numbers, pieces):
        h = min(lags, piece.size // 2)
        if h < 1 or np.var(piece) == 0:
            continue
        test = acorr_ljungbox(piece, lags=[h])
        rows.append({"cycle": number, "nobs": piece.size, "lags": h, "lb_stat": float(test["lb_stat"].iloc[0]),
                     "lb_pvalue": float(test["lb_pvalue"].iloc[0])})
    frame = pd.DataFrame(rows, columns=["cycle", "nobs", "lags", "lb_stat", "lb_pvalue"])
    q, dof = float(frame["lb_stat"].sum()), int(frame["lags"].sum())
    combined = {"cycle": "combined", "nobs": int(frame["nobs"].sum()), "lags": dof, "lb_stat": q,
                "lb_pvalue": float(stats.chi2.sf(q, dof)) if dof > 0 else float("nan")}
    frame = pd.concat([frame, pd.DataFrame([combined])], ignore_index=True)
    return frame.set_index("cycle")


def pooled_acf(pieces, nlags) -> np.ndarray:
    """Autocorrelation pooled within pieces, lags 0 .. ``nlags`` (samples).

    ``sum_c sum_t z_t z_{t-k} / sum_c sum_t z_t^2``, each piece ``z`` centred
    on its own mean, with both samples in the same piece.

    Returns
    -------
    ndarray, shape (nlags + 1,)
        1 at lag 0.
    """
    pieces = [p - p.mean() for p in pieces]
    denominator = sum(float(np.dot(p, p)) for p in pieces)
    out = np.empty(nlags + 1)
    for k in range(nlags + 1):
        out[k] = sum(float(np.dot(p[k:], p[: p.size - k])) for p in pieces if p.size > k) / denominator
    return out


def jarque_bera_test(values) -> dict:
    """Jarque-Bera test of normality (:func:`statsmodels.stats.stattools.jarque_bera`).

    Returns
    -------
    dict
        ``statistic``, ``pvalue``, ``skew`` and ``kurtosis`` (3 for a normal distribution).
    """
    from statsmodels.stats.stattools import jarque_bera

    statistic, pvalue, skew, kurtosis = jarque_bera(values)
    return {"statistic": float(statistic), "pvalue": float(pvalue), "skew": float(skew),
            "kurtosis": float(kurtosis)}


def variance_change_test(innovations, residual, subset_length=1.0 / 3.0) -> dict:
    """Does the variance change over the record? (statsmodels' breakvar test).

    The statistic is the sum of squares of ``innovations`` in the last
    ``subset_length`` of the samples over that in the first, F-distributed
    with ``(h, h)`` degrees of freedom under the null hypothesis of constant
    variance (two-sided),
    :func:`statsmodels.tsa.stattools.breakvar_heteroskedasticity_test`. The
    F distribution needs independent samples, hence the innovations; the
    ``residual``'s own ratio is reported beside it as a description.

    Parameters
    ----------
    innovations : ndarray, shape (T,)
        Standardised innovations.
    residual : ndarray, shape (T2,)
        A residual (any unit).
    subset_length : float
        Fraction of the samples in each of the two compared parts.

    Returns
    -------
    dict
        ``statistic``, ``pvalue`` (innovations), ``residual_ratio``: the
        mean square of ``residual`` in the last part over that in the first
        part (NaN when a part is empty).
    """
    from statsmodels.tsa.stattools import breakvar_heteroskedasticity_test

    statistic, pvalue = breakvar_heteroskedasticity_test(innovations, subset_length=subset_length)
    h = int(np.round(subset_length * residual.size))
    ratio = float(np.mean(residual[-h:] ** 2) / np.mean(residual[:h] ** 2)) if h > 0 else float("nan")
    return {"statistic": float(statistic), "pvalue": float(pvalue), "residual_ratio": ratio}
