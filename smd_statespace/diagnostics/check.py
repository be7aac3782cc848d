"""Compare the identified SMD model with the measurement and see where it fails.

After identification (:class:`~smd_statespace.identify.runner.CycleRunner`) every cycle
has its own parameters (``f_h``, ``xi_h``, Fourier force coefficients, ...).
:func:`check_model` turns those into predictions of the measured dynamic
ground reaction force and :class:`ModelCheck` compares the two, the way a
statsmodels results object does (``test_serial_correlation``,
``test_normality``, ``plot_diagnostics``)::

    check = check_model(preprocessed, estimator="ekf", max_passes=3)
    print(check.summary())
    check.plot_fit("fit.png")
    check.plot_diagnostics("diagnostics.png")

Two predictions of the dynamic GRF ``M_h u''`` (N, Eq. 3) are made, the free
simulation (:attr:`ModelCheck.simulated`) and the one-step-ahead prediction
(:attr:`ModelCheck.one_step`): see :mod:`smd_statespace.diagnostics.cycles`.
What a per-cycle model can and cannot show (which hidden effect reaches the
residual, and which diagnostic shows it): see :mod:`smd_statespace.diagnostics.subspace`.

The series (SI units) are :class:`ModelCheck`'s attributes; its tools are functions over arrays in the
modules beside it (spectra, correlation, phase, subspace, residual_tests, cycles, free_simulation).
"""

from __future__ import annotations

from functools import cached_property
from typing import Mapping

import numpy as np
import pandas as pd

from ..errors import OptionError
from ..io import G
from .correlation import cross_correlation_table
from .cycles import absorbable_bases, checked_series, cycle_harmonic, identified_runner, state_over_record
from ..model.fitted import propose
from .effect_adapter import fitted_record, score_terms
from ..measures import fit_percent, rms
from .free_simulation import path_sensitivity
from .phase import phase_locked, phase_profile
from .report import summary_text
from .residual_tests import CycleResidualTests
from .spectra import HARMONIC_TOLERANCE, PEAK_FALSE_ALARM, SEGMENT_CYCLES  # noqa: F401 (importable from here too)
from .spectra import residual_spectrum as spectrum_with_peaks, welch_spectrum
from .subspace import remove_projections

__all__ = ["ModelCheck", "check_model", "fit_percent", "INITIAL_STATES"]

INITIAL_STATES = ("estimate", "filtered")
"""Where each cycle's free simulation starts (``initial_state`` of :func:`check_model`):
``"estimate"`` fits the dynamic slots' starting values to the cycle by least
squares, as MATLAB's ``compare`` does by default; ``"filtered"`` takes the
filter's estimate at the cycle's first sample."""


def check_model(preprocessed=None, model=None, estimator="ekf", runner=None, initial_state="estimate",
                **runner_options) -> "ModelCheck":
    """Identify a record cycle by cycle (or take a finished run) and compare the model with it.

    Parameters
    ----------
    preprocessed : Preprocessed or Record, optional
        The pipeline output (a :class:`~smd_statespace.io.Record` is
        preprocessed first). May be omitted when ``runner`` is given.
    model : SMDModel, optional
        The model to identify (default ``SMDModel()``). Ignored with ``runner``.
    estimator : str or Estimator
        Estimator of the run (default ``"ekf"``: deterministic and fast).
        Ignored with ``runner``.
    runner : CycleRunner, optional
        A runner that has already run (it has ``table_``, ``results_``,
        ``model`` and ``preprocessed_``), made with ``keep_results=True``.
        Nothing is re-identified.
    **runner_options
        Passed to :class:`~smd_statespace.identify.runner.CycleRunner` (``max_passes``,
        ``seed``, ``n_particles``, ...); ``progress`` defaults to False and
        ``keep_results`` is always True.

    Returns
    -------
    ModelCheck

    Raises
    ------
    OptionError
        The runner has not run, kept no filter results, or no cycle was identified.
    """
    runner = identified_runner(preprocessed, model, estimator, runner, runner_options)
    return ModelCheck(runner.table_, runner.model, runner.preprocessed_, runner.results_, initial_state)


class ModelCheck(CycleResidualTests):
    """The identified model against the measurement: fit, residual tests, spectra, correlations.

    Built by :func:`check_model`. Every identified cycle (table ``status`` "ok")
    contributes its samples; consecutive cycles share their boundary sample,
    which is kept once, in the earlier cycle (where the free simulation has
    run longest).

    Parameters
    ----------
    table : pandas.DataFrame
        The runner's table (one row per cycle).
    model : SMDModel
        The identified model.
    preprocessed : Preprocessed
        The record the cycles came from.
    results : dict of int to FilterResult
        Final-pass filter result of every identified cycle.

    Attributes
    ----------
    time : ndarray, shape (T,)
        Sample times (s) of the identified cycles.
    cycle_index : ndarray of int, shape (T,)
        Cycle number of each sample.
    sample_index : ndarray of int, shape (T,)
        Position of each sample in the record (``preprocessed.time``).
    phase : ndarray, shape (T,)
        Bouncing-cycle phase ``(t - t_start) / (t_end - t_start)`` in [0, 1].
    measured : ndarray, shape (T,)
        Measured dynamic GRF ``M_h u''`` (N), ``u''`` the pipeline's high-passed COM acceleration (Eq. 3).
    simulated : ndarray, shape (T,)
        Free simulation of ``M_h u''`` (N), see :mod:`smd_statespace.diagnostics.cycles`.
    one_step : ndarray, shape (T,)
        One-step-ahead prediction of ``M_h u''`` (N): ``M_h (u'' - innovation)``.
    residual : ndarray, shape (T,)
        ``measured - simulated`` (N).
    innovations : ndarray, shape (T,)
        Standardised innovations of the ``u''`` channel (innovation over the root of its predicted variance).
    fit_percent, fit_percent_one_step : float
        :func:`fit_percent` of the free simulation and of the one-step prediction.
    residual_rms, residual_rms_bw : float
        RMS of :attr:`residual` (N), and the same in % of body weight ``M_h g``.
    log_likelihood : float
        Sum of the cycles' filter log-likelihoods.
    n_parameters : int
        Free parameter slots per cycle times the number of identified cycles.
    nobs : int
        Number of filtered samples (every cycle's samples, boundaries counted in both cycles).
    f_b : float
        Median bouncing frequency of the identified cycles (Hz).
    fs : float
        Sampling frequency (Hz).
    weight : float
        Body weight ``M_h g`` (N).
    cycles : list of Cycle
        The checked cycles, in record order.
    """

    def __init__(self, table: pd.DataFrame, model, preprocessed, results: Mapping[int, object],
                 initial_state: str = "estimate"):
        if initial_state not in INITIAL_STATES:
            raise OptionError(f"initial_state {initial_state!r} is unknown; choose {' or '.join(INITIAL_STATES)}")
        self.initial_state, self.table, self.model, self.preprocessed = initial_state, table, model, preprocessed
        ok = set(table.loc[table["status"] == "ok", "cycle"].astype(int)) if "status" in table else set(results)
        cycles = [c for c in preprocessed.cycles if c.index in results and c.index in ok]
        if not cycles:
            raise OptionError(f"{getattr(preprocessed, 'source', 'record')}: no identified cycle to check")
        self.results = {c.index: results[c.index] for c in cycles}
        self.cycles = cycles
        joined, self._linear, self.n_parameters, self.nobs = checked_series(model, preprocessed, cycles, self.results,
                                                                            initial_state)
        self.time, self.phase, self.measured, self.simulated, self.one_step, self.innovations = (
            joined[name] for name in ("time", "phase", "measured", "simulated", "one_step", "innovations"))
        self.cycle_index = joined["cycle"].astype(int)
        self.sample_index = joined["sample"].astype(int)
        self.residual = self.measured - self.simulated
        self.fit_percent = fit_percent(self.measured, self.simulated)
        self.fit_percent_one_step = fit_percent(self.measured, self.one_step)
        self.residual_rms = rms(self.residual)
        self.weight = float(preprocessed.mass) * G
        self.residual_rms_bw = 100.0 * self.residual_rms / self.weight
        self.log_likelihood = float(sum(float(r.log_likelihood) for r in self.results.values()))
        self.f_b = float(np.median([c.f_b for c in cycles]))
        self.fs = float(preprocessed.fs)

    # -- construction helpers (the free simulation: diagnostics.free_simulation) ----

    def _path_sensitivity(self, states, data, channel):
        """Derivative of the simulated ``u''`` at every sample with respect to the starting state, (m, n_state)."""
        return path_sensitivity(self.model, states, data, channel)

    @cached_property
    def _absorbable_bases(self):
        """Per cycle, an orthonormal basis of the output changes a re-fit of the cycle could make."""
        return absorbable_bases(self.model, self._linear)

    # -- derived numbers ----------------------------------------------------

    @property
    def loglike(self) -> float:
        """The cycles' log-likelihoods summed, each at its own identified parameters (:attr:`log_likelihood`): a
        likelihood of the per-cycle fits, not of one person for the record, so not comparable with the
        record-level person's ``loglike``."""
        return self.log_likelihood

    def parameters(self, level: float = 0.9) -> pd.DataFrame:
        """The answer by parameter, as every estimator's answer gives it
        (:class:`~smd_statespace.answers.RecordAnswer`):
        the cycles' median and central ``level`` range, never determined
        (:func:`~smd_statespace.identify.pooled.pool_cycles`, whose docstring says why)."""
        from ..identify.pooled import pool_cycles

        return pool_cycles(self.table, level)[["value", "sd", "low", "high", "determined"]]

    def free_run(self) -> np.ndarray:
        """The free simulation as the COM acceleration ``GRF / M_h - g`` (m/s^2, :attr:`simulated` over the mass),
        cycle after cycle, each from its own identified parameters and starting state."""
        return self.simulated / float(self.preprocessed.mass)

    @property
    def n_cycles(self) -> int:
        """Number of identified cycles checked."""
        return len(self.cycles)

    @property
    def aic(self) -> float:
        """Akaike information criterion ``-2 log L + 2 k`` (``k`` = :attr:`n_parameters`)."""
        return -2.0 * self.log_likelihood + 2.0 * self.n_parameters

    @property
    def bic(self) -> float:
        """Bayesian information criterion ``-2 log L + k log(nobs)``."""
        return -2.0 * self.log_likelihood + self.n_parameters * np.log(self.nobs)

    @property
    def innovation_variance(self) -> float:
        """Mean square of the standardised innovations: 1 when the filter's noise levels match the data.

        Much below 1: the assumed observation noise (10 % of RMS by default) is larger
        than the actual noise; much above 1: the model misses something or the noise is underestimated.
        """
        return float(np.mean(self.innovations**2))

    @property
    def n_absorbable(self) -> int:
        """Dimensions of the output changes re-identifying the cycles could make (:meth:`remove_absorbable`).

        The number of values the model effectively fits; the residual degrees of
        freedom are ``residual.size - n_absorbable``.
        """
        return int(sum(basis.shape[1] for basis in self._absorbable_bases))

    # -- spectra (diagnostics.spectra) ------------------------------------------

    def measured_spectrum(self, nperseg=None):
        """Welch power spectral density of the measured dynamic GRF: ``freq`` (Hz), ``psd`` (N^2/Hz)."""
        return welch_spectrum(self.measured, self.fs, self.f_b, nperseg)

    def residual_spectrum(self, nperseg=None, false_alarm=PEAK_FALSE_ALARM, tolerance=None, min_frequency=None,
                          values=None):
        """Welch spectrum of the free-simulation residual and its peaks above the noise floor.

        A missing force harmonic leaves a line at ``k f_b``; a floor mode leaves
        content at its own frequency; a cubic spring leaves harmonics above those
        the force model has (:func:`spectra.residual_spectrum`).

        Parameters
        ----------
        nperseg : int, optional
            Welch segment length (samples); default :data:`spectra.SEGMENT_CYCLES` bouncing periods.
        false_alarm : float
            Chance that pure noise gives at least one peak.
        tolerance : float, optional
            Largest distance (Hz) from ``k f_b`` for the label "harmonic k" (:func:`spectra.spectral_peaks`).
        min_frequency : float, optional
            Lowest frequency searched for peaks (Hz); default the high-pass cut-off.
        values : array_like, shape (T,), optional
            Another series on the checked samples (default :attr:`residual`), e.g.
            the residual without its phase-locked part (:meth:`phase_locked`).

        Returns
        -------
        freq, psd : ndarray, shape (F,)
            Frequencies (Hz) and the power spectral density (N^2/Hz).
        peaks : pandas.DataFrame
            :func:`spectra.spectral_peaks`: ``frequency`` (Hz), ``power``, ``ratio_to_floor``, ``label``, ``k``,
            ``f_over_fb``, strongest first; ``attrs``: ``noise_floor``, ``threshold``, ``f_b``, ``tolerance``,
            ``resolution``.
        """
        series = self._series(values)
        low = float(getattr(self.preprocessed, "cutoff", 0.5)) if min_frequency is None else float(min_frequency)
        return spectrum_with_peaks(series, self.fs, self.f_b, nperseg, false_alarm, tolerance, low)

    # -- structure of the residual (diagnostics.phase, diagnostics.subspace) ------

    def _series(self, values):
        """:attr:`residual`, or ``values`` as floats if it has the residual's shape."""
        series = self.residual if values is None else np.asarray(values, dtype=float)
        if series.shape != self.residual.shape:
            raise OptionError(f"values has shape {series.shape}; the check has {self.residual.shape}")
        return series

    def _samples(self, values):
        """``values`` as floats if it has a value per checked sample."""
        values = np.asarray(values, dtype=float)
        if values.shape[0] != self.residual.size:
            raise OptionError(f"values has {values.shape[0]} samples; the check has {self.residual.size}")
        return values

    def phase_locked(self, values=None, orders=None) -> np.ndarray:
        """The part of a series that repeats with the bouncing cycle (:func:`phase.phase_locked` in :attr:`phase`).

        Parameters
        ----------
        values : array_like, shape (T,), optional
            Series on the checked samples (default :attr:`residual`, N).
        orders : int, optional
            Highest order ``k`` (default: up to the Nyquist frequency at the median bouncing frequency).

        Returns
        -------
        ndarray, shape (T,)
        """
        series = self._series(values)
        top = int(0.5 * self.fs / self.f_b) if orders is None else int(orders)
        return phase_locked(series, self.phase, top)

    def phase_profile(self, bins=24) -> pd.DataFrame:
        """Residual against the bouncing-cycle phase: where in the cycle the model fails.

        Parameters
        ----------
        bins : int
            Number of equal phase bins.

        Returns
        -------
        pandas.DataFrame
            :func:`phase.phase_profile`: per bin ``phase``, ``phase_low``, ``phase_high``, ``n``, ``mean``, ``sd``,
            ``sem`` (N), ``mean_bw``, ``sd_bw`` (% body weight).
        """
        return phase_profile(self.residual, self.phase, self.weight, self.n_cycles, bins)

    def remove_absorbable(self, values) -> np.ndarray:
        """What is left of a signal after removing, cycle by cycle, what re-identifying the model could absorb.

        Its least-squares projection on the span of each cycle's sensitivity to its
        starting state and free parameters (:func:`cycles.absorbable_bases`) is removed.

        Parameters
        ----------
        values : array_like, shape (T,)
            A signal on the checked samples (e.g. :attr:`residual`).

        Returns
        -------
        ndarray, shape (T,)
        """
        blocks = [(piece["rows"], basis) for piece, basis in zip(self._linear, self._absorbable_bases)]
        return remove_projections(self._samples(values), blocks)

    @cached_property
    def residual_unabsorbed(self) -> np.ndarray:
        """The part of :attr:`residual` (N) that no small change of the cycles' identified values can remove
        (:meth:`remove_absorbable`): the evidence of a missing effect, plus measurement noise.
        """
        return self.remove_absorbable(self.residual)

    @property
    def residual_unabsorbed_rms_bw(self) -> float:
        """RMS of :attr:`residual_unabsorbed` in % of body weight."""
        return 100.0 * rms(self.residual_unabsorbed) / self.weight

    def remove_force_harmonics(self, values) -> np.ndarray:
        """What is left of a signal after removing, cycle by cycle, its fit by the force model's basis.

        The regressors of Eq. 4 (orders :meth:`harmonic_orders`, the cycle's own
        ``f_b``): what the identification absorbs into the force coefficients.

        Parameters
        ----------
        values : array_like, shape (T,) or (T, q)
            Signal(s) on the checked samples.

        Returns
        -------
        ndarray, same shape
        """
        blocks = [(piece["rows"], piece["harmonic_basis"]) for piece in self._linear]
        return remove_projections(self._samples(values), blocks)

    def harmonic_orders(self) -> np.ndarray:
        """Force harmonic orders of the identified model (:meth:`SMDModel.harmonic_orders`)."""
        return self.model.harmonic_orders()

    def harmonic_signal(self, order) -> np.ndarray:
        """``[cos(k theta), sin(k theta)]`` of each checked cycle over the whole record, shape (n, 2)
        (:func:`cycles.cycle_harmonic`; Eq. 4, zero outside the checked cycles).
        """
        return cycle_harmonic(self.preprocessed.time, self.cycles, order)

    def default_candidates(self) -> dict:
        """Candidate terms of the COM acceleration that a missing physical effect would add.

        Every registered effect not in the model (:mod:`smd_statespace.effects`, a user's included), as
        it proposes itself (:func:`~smd_statespace.model.fitted.propose`), contributes its own terms
        (:meth:`effect_terms`), named by the effect:
        ``harmonics`` (``g cos(j theta), g sin(j theta)`` for the two orders above
        the model's), ``cubic_stiffness`` (``-w_h^2 u^3``), ``floor_mode`` (with a
        measured floor: ``w_h^2 z + 2 xi_h w_h z'``, Section 6); a term that needs
        an unmeasured state is left out. Besides them, model-free probes: ``u``,
        ``u_dot`` (a stiffness or damping not caught), ``u^2`` (an asymmetric
        spring) and, when the record has them, ``floor_acc``, ``floor_disp``.

        ``u``, ``u_dot``, ``f_h`` and ``xi_h`` are the free simulation's
        (:meth:`simulated_state`), not the pipeline's ``disp`` and ``vel``: those
        integrate the measured acceleration and so carry the residual itself (the
        score-test rule: evaluate a candidate term on the fitted model). The
        measured acceleration is not a candidate for the same reason.

        Returns
        -------
        dict of str to ndarray, each of shape ``(len(preprocessed.time),)`` or ``(len(preprocessed.time), q)``
        """
        from ..effects import EFFECTS

        pre = self.preprocessed
        out = {}
        present = {effect.name for effect in self.model.effects}
        fitted = fitted_record(self)
        for name, cls in EFFECTS.items():
            effect = None if name in present else propose(cls, fitted)
            terms = {} if effect is None else self.effect_terms(effect)
            if terms:
                columns = np.column_stack(list(terms.values()))
                out[name] = columns[:, 0] if columns.shape[1] == 1 else columns
        u = self.simulated_state("u")
        out.update({"u": u, "u_dot": self.simulated_state("u_dot"), "u^2": u**2})
        if getattr(pre, "floor_acc", None) is not None:
            out["floor_acc"] = np.asarray(pre.floor_acc, dtype=float)
            out["floor_disp"] = np.asarray(pre.floor_disp, dtype=float)
        return out

    def effect_terms(self, effect) -> dict:
        """The terms ``effect`` would add to ``u''`` along this check's free simulation (m/s^2 per unit).

        The model extended by ``effect`` is evaluated on the free
        simulation's state (:meth:`simulated_state`; the effect's own slots
        at 0) cycle by cycle, with each cycle's inputs, and the effect gives
        its :func:`~smd_statespace.diagnostics.effect_adapter.score_terms`. Samples outside
        the checked cycles are 0. An effect whose measured signals the record
        lacks gives none.

        Returns
        -------
        dict of str to ndarray, each of shape ``(len(preprocessed.time),)``
        """
        from ..estimators import cycle_data

        model = self.model.with_effects(effect)
        pre = self.preprocessed
        x = np.zeros((len(pre.time), model.n_state))
        for name in self.model.state_names:
            x[:, model.index(name)] = self.simulated_state(name)
        out = {}
        for cycle in self.cycles:
            try:
                data = cycle_data(model, pre, cycle)
            except OptionError:
                return {}
            samples = np.arange(cycle.start, cycle.stop + 1)
            for key, values in score_terms(effect, model, x[samples], data.t, data.inputs).items():
                out.setdefault(key, np.zeros(len(pre.time)))[samples] = values
        return out

    def simulated_state(self, name) -> np.ndarray:
        """A slot of the free simulation's state over the whole record (:func:`cycles.state_over_record`).

        On the checked cycles the simulated value (a shared first sample takes the
        later cycle's value); elsewhere the pipeline's ``disp`` for ``"u"``,
        ``vel`` for ``"u_dot"``, or the median identified value for a parameter.
        ``name`` is a state slot (``"u"``, ``"u_dot"``, ``"f_h"``, ...); the
        result has shape (len(preprocessed.time),).
        """
        pre = self.preprocessed
        fill = {"u": pre.disp, "u_dot": pre.vel}.get(name)
        return state_over_record(self._linear, self.model.index(name), len(pre.time), fill)

    def cross_correlation(self, candidates=None, max_lag_s=0.0, remove_harmonics=True) -> pd.DataFrame:
        """Correlation of the free-simulation residual with candidate terms: what does the error look like?

        By default the residual and every candidate first lose their per-cycle
        fit by the force model's basis (:meth:`remove_force_harmonics`): without
        it every candidate correlates about equally (0.2-0.3, measured), all being
        dominated by the bouncing harmonics; with it a cubic spring makes
        ``cubic_stiffness`` the strongest (about twice its value without the
        effect) and missing force harmonics ``harmonics``. The default is no lag:
        the terms act on the acceleration at once, and a lag search lets any
        near-periodic candidate match the residual's periodic error (:func:`correlation.cross_correlation_table`).

        Parameters
        ----------
        candidates : mapping of str to array_like, optional
            Signals over the whole record, shape ``(len(preprocessed.time),)`` or ``(len(preprocessed.time), q)``;
            default :meth:`default_candidates` (yours: ``{**check.default_candidates(), "mine": x}``).
        max_lag_s : float
            Largest lag (s); at lag ``tau > 0`` the candidate leads (for a sensor with its own delay).
        remove_harmonics : bool
            Remove the per-cycle force-basis fit first.

        Returns
        -------
        pandas.DataFrame
            One row per candidate, strongest first: ``signal``, ``max_abs_corr``, ``corr`` (NaN for multi-column
            candidates), ``lag_s``, ``corr_at_zero``, ``explained``.
        """
        candidates = self.default_candidates() if candidates is None else dict(candidates)
        target = self.remove_force_harmonics(self.residual) if remove_harmonics else self.residual
        return cross_correlation_table(target, candidates, self.sample_index, len(self.preprocessed.time), self.fs,
                                       max_lag_s, self.remove_force_harmonics if remove_harmonics else None)

    # -- text -----------------------------------------------------------------

    def summary(self, n_peaks=5, n_signals=5) -> str:
        """Readable report: fit, residual size, tests, spectral peaks, strongest correlations."""
        return summary_text(self, n_peaks, n_signals)

    def __repr__(self):
        return (f"ModelCheck(cycles={self.n_cycles}, fit={self.fit_percent:.1f} %, "
                f"residual_rms={self.residual_rms_bw:.2f} % BW)")

    # -- figures (drawn by smd_statespace.plotting.check) ----------------------

    def plot_fit(self, path=None, cycles=None):
        """Measured GRF against the free simulation and the one-step prediction
        (:func:`~smd_statespace.plotting.check.plot_fit`).
        """
        from ..plotting.check import plot_fit

        return plot_fit(self, path, cycles)

    def plot_diagnostics(self, path=None, lags=None):
        """One figure to read at a glance where and how the model fails
        (:func:`~smd_statespace.plotting.check.plot_diagnostics`).
        """
        from ..plotting.check import plot_diagnostics

        return plot_diagnostics(self, path, lags)
