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
- :func:`jarque_bera_test`, :func:`variance_change_test`: statsmodels' tests as dictionaries;
- :class:`CycleResidualTests`: those tests as the methods of a per-cycle check, named as a statsmodels
  results object names them (and as the record-level person's are).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..errors import OptionError

__all__ = ["split_cycles", "cycle_numbers", "default_lags", "ljung_box_table", "pooled_acf", "jarque_bera_test",
           "variance_change_test", "CycleResidualTests"]


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


class CycleResidualTests:
    """The residual tests of a per-cycle check (:class:`~smd_statespace.diagnostics.check.ModelCheck`), as methods.

    A mixin: the class provides ``innovations`` (the filter's standardised innovations, (T,)), ``residual``
    (measured minus free simulation, N, (T,)) and ``cycle_index`` (each sample's cycle, consecutive).
    """

    def _per_cycle(self, values):
        """Split a (T,) array into the cycles' pieces."""
        return split_cycles(values, self.cycle_index)

    # -- tests on the standardised innovations ------------------------------

    def default_lags(self) -> int:
        """Default Ljung-Box lag within a cycle: a quarter of the median cycle length, at most 20 (samples)."""
        return default_lags(self._per_cycle(self.innovations))

    def test_serial_correlation(self, lags=None, series="innovations") -> pd.DataFrame:
        """Ljung-Box test of the standardised innovations (or of the residual), per cycle and combined.

        The filter starts afresh in every cycle, so each cycle is tested
        separately and the statistics add (:func:`residual_tests.ljung_box_table`).

        Parameters
        ----------
        lags : int, optional
            Largest lag in samples within a cycle; default :meth:`default_lags`
            (:func:`residual_tests.default_lags`). Cycles shorter than ``2 lags`` use ``n // 2``.
        series : {"innovations", "residual"}
            The filter's standardised innovations (default, as statsmodels) or the
            free-simulation :attr:`residual`. The article filter's innovations are
            serially correlated even when the model is right (its ``u``, ``u_dot``
            channels integrate the measured acceleration; its observation noise is
            10 % of the RMS), so a missing effect is judged on the residual:
            ``lb_stat / lags`` about 1.2-1.9 without a missing effect, 7-10 with one
            (measured, see :mod:`smd_statespace.diagnostics.missing`).

        Returns
        -------
        pandas.DataFrame
            One row per cycle (index ``cycle``): ``nobs``, ``lags``, ``lb_stat``,
            ``lb_pvalue``; a last row ``"combined"`` (summed statistic and degrees of freedom, chi-square p-value).
        """
        lags = self.default_lags() if lags is None else int(lags)
        if lags < 1:
            raise OptionError(f"lags must be a whole number >= 1, got {lags!r}")
        if series not in ("innovations", "residual"):
            raise OptionError(f"series must be 'innovations' or 'residual', got {series!r}")
        values = self.innovations if series == "innovations" else self.residual
        return ljung_box_table(self._per_cycle(values), self._cycle_numbers(), lags)

    def whiteness_pvalue(self, lags=None, series="innovations") -> float:
        """Combined Ljung-Box p-value of :meth:`test_serial_correlation`."""
        return float(self.test_serial_correlation(lags, series).loc["combined", "lb_pvalue"])

    def serial_correlation_ratio(self, lags=None, series="residual") -> float:
        """Combined Ljung-Box statistic per degree of freedom: about 1 for a white series (default: the residual).

        Unlike the p-value it does not grow with the record length, so it compares records and models.
        """
        combined = self.test_serial_correlation(lags, series).loc["combined"]
        return float(combined["lb_stat"] / combined["lags"]) if combined["lags"] > 0 else float("nan")

    def _cycle_numbers(self):
        return cycle_numbers(self.cycle_index)

    def test_normality(self) -> dict:
        """Jarque-Bera test of the standardised innovations, all cycles pooled: a dict of ``statistic``, ``pvalue``,
        ``skew`` and ``kurtosis`` (3 for a normal distribution)."""
        return jarque_bera_test(self.innovations)

    def test_heteroskedasticity(self, subset_length=1.0 / 3.0) -> dict:
        """Does the residual variance change over the record? (:func:`residual_tests.variance_change_test`).

        ``subset_length`` is the fraction of the record in each of the two compared
        parts. Returns a dict of ``statistic``, ``pvalue`` (statsmodels' breakvar test
        of the standardised innovations) and ``residual_ratio`` (the free-simulation
        residual's mean square, last part over first).
        """
        return variance_change_test(self.innovations, self.residual, subset_length)

    def pooled_acf(self, nlags=None) -> np.ndarray:
        """Autocorrelation of the standardised innovations, pooled within cycles (lags 0..nlags)."""
        nlags = self.default_lags() if nlags is None else int(nlags)
        return pooled_acf(self._per_cycle(self.innovations), nlags)

    def standardized_innovations(self) -> np.ndarray:
        """The filter's one-step innovations divided by their predicted sd, cycle after cycle (white N(0, 1) where
        the model and the filter's noise levels are right; the article's filter restarts in every cycle)."""
        return self.innovations

    def test_pvalues(self) -> dict:
        """The tests as the record-level person's ``test_pvalues`` gives them: ``ljung_box_p`` (combined over the
        cycles), ``ljung_box_q``, ``ljung_box_lags``, ``jarque_bera_p``, ``heteroskedasticity_p`` and the
        innovations' ``kurtosis``."""
        lags = self.default_lags()
        combined = self.test_serial_correlation(lags).loc["combined"]
        normal = self.test_normality()
        return {"ljung_box_p": float(combined["lb_pvalue"]), "ljung_box_q": float(combined["lb_stat"]),
                "ljung_box_lags": lags, "jarque_bera_p": float(normal["pvalue"]),
                "heteroskedasticity_p": float(self.test_heteroskedasticity()["pvalue"]),
                "kurtosis": float(normal["kurtosis"])}
