"""What every estimator's answer for a record provides: one vocabulary, whichever estimator made it.

The record-level person (:class:`~smd_statespace.person.results.PersonResult`, ``identify``'s default) and the
article's per-cycle method checked against the record (:class:`~smd_statespace.diagnostics.check.ModelCheck`)
answer the same questions by the same names, as a statsmodels results object would:

- ``parameters()``: per parameter (``f_h`` in Hz, ``xi_h``, ``blf_i`` in g) its ``value``, ``sd``, 90 % ``low`` and
  ``high`` and whether the record ``determined`` it (the per-cycle method: the cycles' median and central range,
  never determined; ``sd`` NaN);
- ``loglike``: the log-likelihood (the per-cycle method: its cycles' own, summed, which is not one person's);
- ``standardized_innovations()``: the one-step innovations over their predicted sd;
- ``test_pvalues()``: ``ljung_box_p``, ``ljung_box_q``, ``ljung_box_lags``, ``jarque_bera_p``,
  ``heteroskedasticity_p`` and the innovations' ``kurtosis`` (the per-cycle filter restarts in every cycle:
  its Ljung-Box test is within cycles, and its innovations are correlated even where the model is right,
  see ``ModelCheck.test_serial_correlation``);
- ``free_run()``: the model simulated freely over the record, as ``GRF / M_h - g`` (m/s^2), and ``fit_percent``:
  MATLAB's fit % of it;
- ``plot_diagnostics(path=None, lags=None)``: the innovations' four panels
  (:mod:`~smd_statespace.plotting.innovations`) and whatever the estimator adds.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

__all__ = ["RecordAnswer"]


@runtime_checkable
class RecordAnswer(Protocol):
    """An estimator's answer for a record (module docstring): ``isinstance(result, RecordAnswer)`` holds for the
    person and for a per-cycle check."""

    loglike: float
    fit_percent: float

    def parameters(self):
        """Per parameter: ``value``, ``sd``, ``low``, ``high``, ``determined``."""

    def standardized_innovations(self):
        """The one-step innovations over their predicted sd."""

    def test_pvalues(self) -> dict:
        """The residual tests' p-values by name."""

    def free_run(self):
        """The free simulation as ``GRF / M_h - g`` (m/s^2)."""

    def plot_diagnostics(self, path=None, lags=None):
        """The diagnostics figure, beginning with the innovations' four panels."""
