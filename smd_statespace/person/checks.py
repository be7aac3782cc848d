"""A fitted person checked against its record: statsmodels' residual tests at the estimate and the free run.

:class:`RecordChecks` gives :class:`~smd_statespace.person.results.PersonResult` the names every estimator's
answer answers by (:mod:`smd_statespace.answers`): ``standardized_innovations``, ``test_pvalues`` and
statsmodels' ``test_serial_correlation``, ``test_normality``, ``test_heteroskedasticity`` of the state-space
view at the estimate (:class:`~smd_statespace.person.statespace.RecordStateSpace`, imported when first asked
for), and the free run with its fit % (MATLAB's ``compare``).
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from ..measures import fit_percent

__all__ = ["RecordChecks"]


class RecordChecks:
    """A fitted person checked against its record: statsmodels' results at the estimate and their residual tests
    (named as statsmodels names them), and the free run with its fit (MATLAB's ``compare``).

    A mixin of :class:`~smd_statespace.person.results.PersonResult`: the class provides ``record``, ``model``,
    ``params`` and ``filtered`` (the compiled pass at ``params``, its ``delta``).
    """

    @cached_property
    def statespace_results(self):
        """statsmodels' ``MLEResults`` at the estimate (smoother, tests)."""
        from .statespace import RecordStateSpace  # statsmodels: imported when its view is asked for

        ssm = RecordStateSpace(self.model, self.filtered["delta"])
        return ssm.smooth(self.params, cov_type="none")

    def standardized_innovations(self) -> np.ndarray:
        """One-step innovations divided by their predicted sd (white N(0, 1) if the model fits)."""
        return self.model.innovations(self.params, self.filtered)[0]

    def test_serial_correlation(self, lags=None):
        """Ljung-Box test of the standardised innovations, as statsmodels' ``test_serial_correlation("ljungbox")``
        of :attr:`statespace_results` gives it (an array ``(1, 2, lags)``: statistic and p-value at each lag).

        Computed on :meth:`standardized_innovations`, the series statsmodels' filter gives at the estimate (tested
        to rounding; a missing sample, a phone's gap, is an innovation of 0 in both), without running statsmodels'
        smoother: that took 0.2-0.3 s per fit, and ``diagnose`` tests every candidate's fit.
        """
        from statsmodels.stats.diagnostic import acorr_ljungbox

        lags = lags if lags is not None else self.default_lags()
        return np.asarray(acorr_ljungbox(self.standardized_innovations(), lags=lags))[:, [0, 1]].T[None]

    def default_lags(self) -> int:
        """Lags of the residual tests: one bouncing cycle's samples, at least 10."""
        return int(max(10, round(self.record.fs / np.median(self.model.timing.f_b))))

    def test_normality(self):
        """Jarque-Bera test of the standardised innovations (statsmodels' ``test_normality("jarquebera")``: an array
        ``(1, 4)`` of statistic, p-value, skew and kurtosis)."""
        from statsmodels.stats.stattools import jarque_bera

        return np.array([jarque_bera(self.standardized_innovations())])

    def test_heteroskedasticity(self):
        """Test of a change of innovation variance between the first and last third (statsmodels'
        ``test_heteroskedasticity("breakvar")``: an array ``(1, 2)`` of statistic and two-sided F p-value)."""
        from statsmodels.tsa.stattools import breakvar_heteroskedasticity_test

        innovations = self.standardized_innovations()
        third = int(np.round(innovations.size / 3))
        statistic, pvalue = breakvar_heteroskedasticity_test(innovations, subset_length=third)
        return np.array([[statistic, pvalue]])

    def test_pvalues(self) -> dict:
        """``ljung_box_p`` (and its statistic ``ljung_box_q``), ``jarque_bera_p``, ``heteroskedasticity_p`` and the
        innovations' kurtosis."""
        lb = self.test_serial_correlation()
        lags = self.default_lags()
        innov = self.standardized_innovations()[self.model.observed]  # a missing sample has no innovation
        centred = innov - innov.mean()
        return {
            "ljung_box_p": float(lb[0, 1, lags - 1]),
            "ljung_box_q": float(lb[0, 0, lags - 1]),
            "ljung_box_lags": lags,
            "jarque_bera_p": float(self.test_normality()[0, 1]),
            "heteroskedasticity_p": float(self.test_heteroskedasticity()[0, 1]),
            "kurtosis": float(np.mean(centred**4) / np.mean(centred**2) ** 2),
        }

    def free_run(self) -> np.ndarray:
        """The COM acceleration ``GRF / M_h - g`` (m/s^2) the model gives when simulated freely over the record.

        :meth:`~smd_statespace.person.model.RecordModel.free_run` at the fit: the record's template in every cycle
        (the cycles' own variation is what the model leaves to chance; a smoothed per-cycle force would absorb the
        model's misfit too), from the estimated initial state, without any correction by the measurement.
        """
        return self.model.free_run(self.params, self.filtered["delta"])

    @cached_property
    def fit_percent(self) -> float:
        """MATLAB's fit % of the free run (:meth:`free_run`) over the samples the likelihood uses."""
        observed = self.model.observed
        return fit_percent(self.model.y[observed], self.free_run()[observed])

