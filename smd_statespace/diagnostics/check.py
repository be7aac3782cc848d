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

Two predictions of the dynamic GRF ``M_h u''`` (N, Eq. 3) are made:

free simulation (:attr:`ModelCheck.simulated`)
    Each cycle is integrated with the model alone (:meth:`SMDModel.transition`,
    no process noise, no measurement update) with the cycle's identified
    parameters held at their final-pass values, from the dynamic starting
    state (``u``, ``u_dot``, an estimated floor's ``z``, ``z_dot``) that fits
    the cycle best in the least-squares sense, as MATLAB's ``compare`` does
    by default (``initial_state="filtered"`` starts from the filter's
    estimate at the first sample instead: for a slot no channel measures,
    such as an estimated floor's motion, that is only its prior). What the
    model cannot produce stays in the residual ``measured - simulated``:
    this is the signal the missing-effect diagnostics look at.
one-step-ahead prediction (:attr:`ModelCheck.one_step`)
    The filter's prediction of each sample from all earlier ones
    (measurement minus innovation). The filter corrects the state at every
    sample, so this fits better and hides model error in the state
    corrections; its standardised innovations are what the serial
    correlation, normality and heteroskedasticity tests examine (as in
    statsmodels).

What a per-cycle model can and cannot show
------------------------------------------
Each cycle has its own ``f_h``, ``xi_h``, ``1 + 2n`` force coefficients and
starting ``u``, ``u_dot`` (13 numbers for ``n = 4``) for about 50 samples (a
2 Hz cycle at 100 Hz). A
smooth extra term below about ``n f_b`` is largely absorbed into them, so it
barely reaches the residual (measured on synthetic records of
:func:`~smd_statespace.simulation.simulate_bouncing`, 12 s, 1 % BW noise, EKF):

=================== ======================================== ============================================
hidden effect       what reaches the residual                which diagnostic shows it
=================== ======================================== ============================================
``harmonics``       lines at ``(n+1) f_b``, ``(n+2) f_b``:   :meth:`ModelCheck.residual_spectrum`: top
                    fit 95 -> 82-87 %, residual 1.1-1.3 ->   peak "harmonic 5"; candidate
                    3.3-4.6 % BW                             ``harmonics`` (R about 0.9) strongest
``cubic_stiffness`` mostly absorbed (identified ``f_h`` up   :meth:`ModelCheck.cross_correlation`:
                    3-12 %); fit -0.5 to -1.5 points,        ``cubic_stiffness`` strongest, 2-3.5 times
                    residual +0.1-0.3 % BW                   its value without the effect
``floor_mode``      below ``n f_b`` (the article's 3.48 Hz   nothing: fit, residual and correlations as
                    plate): about 99 % absorbed              on a rigid floor. Above ``n f_b`` (a floor
                                                             excited by other sources): candidate
                                                             ``floor_mode`` and a non-harmonic peak
=================== ======================================== ============================================

:attr:`ModelCheck.residual_unabsorbed` (the residual minus everything a small
change of the cycles' identified values could remove) separates estimator
error from model error: on a clean record it is the measurement noise.

Symbols and attributes (SI units):

==================== =================================== ==========
symbol               attribute                           unit
==================== =================================== ==========
``y = M_h u''``      :attr:`ModelCheck.measured`         N
``y_sim``            :attr:`ModelCheck.simulated`        N
``y_1``              :attr:`ModelCheck.one_step`         N
``r = y - y_sim``    :attr:`ModelCheck.residual`         N
``e / sqrt(S)``      :attr:`ModelCheck.innovations`      \\-
``f_b``              :attr:`ModelCheck.f_b`              Hz
==================== =================================== ==========
"""

from __future__ import annotations

from functools import cached_property
from typing import Mapping

import numpy as np
import pandas as pd

from ..errors import OptionError
from ..io import G, Record
from ..model import TWO_PI
from .correlation import cross_correlation_table
from .cycles import absorbable_bases, checked_series, state_over_record
from .fit import fit_percent, rms
from .free_simulation import path_sensitivity
from .phase import phase_locked, phase_profile
from .report import summary_text
from .residual_tests import (cycle_numbers, default_lags, jarque_bera_test, ljung_box_table, pooled_acf, split_cycles,
                             variance_change_test)
from .spectra import HARMONIC_TOLERANCE, PEAK_FALSE_ALARM, SEGMENT_CYCLES  # noqa: F401 (importable from here too)
from .spectra import residual_spectrum as spectrum_with_peaks
from .spectra import welch_spectrum
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
    from ..identify.runner import CycleRunner
    from ..signals import preprocess

    if runner is None:
        if preprocessed is None:
            raise OptionError("check_model needs a preprocessed record or a finished runner")
        if isinstance(preprocessed, Record):
            preprocessed = preprocess(preprocessed)
        runner_options.setdefault("progress", False)
        runner_options["keep_results"] = True
        runner = CycleRunner(model, estimator=estimator, **runner_options)
        runner.run(preprocessed)
    else:
        if runner_options:
            raise OptionError(
                f"check_model: runner options {', '.join(sorted(runner_options))} cannot apply to a finished runner"
            )
        if not hasattr(runner, "table_"):
            raise OptionError("check_model: the runner has not run yet; call runner.run(record) first")
        if not getattr(runner, "results_", None):
            raise OptionError("check_model: the runner kept no filter results; make it with keep_results=True")
        if preprocessed is not None and isinstance(preprocessed, Record):
            raise OptionError("check_model: with a finished runner, pass the Preprocessed it ran on (or nothing)")
        if preprocessed is not None and preprocessed is not runner.preprocessed_:
            raise OptionError("check_model: preprocessed is not the record the runner identified")
    return ModelCheck(runner.table_, runner.model, runner.preprocessed_, runner.results_, initial_state)


class ModelCheck:
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
        Measured dynamic GRF ``M_h u''`` (N), ``u''`` the high-passed COM
        acceleration of the pipeline (Eq. 3).
    simulated : ndarray, shape (T,)
        Free simulation of ``M_h u''`` (N), see the module docstring.
    one_step : ndarray, shape (T,)
        One-step-ahead prediction of ``M_h u''`` (N): ``M_h (u'' - innovation)``.
    residual : ndarray, shape (T,)
        ``measured - simulated`` (N).
    innovations : ndarray, shape (T,)
        Standardised innovations of the ``u''`` channel (innovation divided
        by the square root of its predicted variance).
    fit_percent, fit_percent_one_step : float
        :func:`fit_percent` of the free simulation and of the one-step prediction.
    residual_rms : float
        RMS of :attr:`residual` (N).
    residual_rms_bw : float
        The same in % of body weight ``M_h g``.
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
        self.initial_state = initial_state
        self.table = table
        self.model = model
        self.preprocessed = preprocessed
        ok = set(table.loc[table["status"] == "ok", "cycle"].astype(int)) if "status" in table else set(results)
        cycles = [c for c in preprocessed.cycles if c.index in results and c.index in ok]
        if not cycles:
            raise OptionError(f"{getattr(preprocessed, 'source', 'record')}: no identified cycle to check")
        self.results = {c.index: results[c.index] for c in cycles}
        self.cycles = cycles
        joined, self._linear, self.n_parameters, self.nobs = checked_series(model, preprocessed, cycles, self.results,
                                                                            initial_state)
        self.time = joined["time"]
        self.cycle_index = joined["cycle"].astype(int)
        self.sample_index = joined["sample"].astype(int)
        self.phase = joined["phase"]
        self.measured = joined["measured"]
        self.simulated = joined["simulated"]
        self.one_step = joined["one_step"]
        self.innovations = joined["innovations"]
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

        Much below 1: the assumed observation noise (10 % of RMS by default) is
        larger than the actual noise; much above 1: the model misses something
        or the noise is underestimated.
        """
        return float(np.mean(self.innovations**2))

    def _per_cycle(self, values):
        """Split a (T,) array into the cycles' pieces."""
        return split_cycles(values, self.cycle_index)

    # -- tests on the standardised innovations ------------------------------

    def default_lags(self) -> int:
        """Default Ljung-Box lag within a cycle: a quarter of the median cycle length, at most 20 (see :meth:`test_serial_correlation`)."""
        return default_lags(self._per_cycle(self.innovations))

    def test_serial_correlation(self, lags=None, series="innovations") -> pd.DataFrame:
        """Ljung-Box test of the standardised innovations (or of the residual), per cycle and combined.

        The filter starts afresh in every cycle, so the concatenated innovations
        are not one time series: each cycle is tested separately and the
        statistics add (:func:`~.residual_tests.ljung_box_table`).

        Parameters
        ----------
        lags : int, optional
            Largest lag in samples within a cycle; default :meth:`default_lags`
            (12 samples for a 2 Hz cycle at 100 Hz, see
            :func:`~.residual_tests.default_lags`). Cycles shorter than ``2 lags``
            use ``n // 2``.
        series : {"innovations", "residual"}
            ``"innovations"`` (default, as statsmodels): the filter's
            standardised innovations. ``"residual"``: the free-simulation
            residual :attr:`residual`, the error a user sees. The article
            filter's innovations are serially correlated even when the model is
            right (its ``u`` and ``u_dot`` channels are integrals of the measured
            acceleration, and its observation noise is 10 % of the RMS), so a
            missing effect is judged on the residual, whose ``lb_stat / lags`` is
            about 1.2-1.9 on records without a missing effect and 7-10 with one
            (measured, see :mod:`smd_statespace.diagnostics.missing`).

        Returns
        -------
        pandas.DataFrame
            One row per cycle (index ``cycle``) with ``nobs``, ``lags``,
            ``lb_stat``, ``lb_pvalue``, and a last row ``"combined"`` with the
            summed statistic and degrees of freedom and the chi-square p-value.
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
        """Combined Ljung-Box statistic per degree of freedom: about 1 for a white series.

        Unlike the p-value it does not grow with the record length, so it
        compares records and models: the size of the serial structure left
        (default: in the free-simulation residual).
        """
        combined = self.test_serial_correlation(lags, series).loc["combined"]
        return float(combined["lb_stat"] / combined["lags"]) if combined["lags"] > 0 else float("nan")

    @property
    def n_absorbable(self) -> int:
        """Dimensions of the output changes re-identifying the cycles could make, summed over cycles.

        The ranks of the per-cycle linearised sensitivities
        (:meth:`remove_absorbable`): the number of values the model
        effectively fits to the checked samples. The residual degrees of
        freedom are ``residual.size - n_absorbable``.
        """
        return int(sum(basis.shape[1] for basis in self._absorbable_bases))

    def _cycle_numbers(self):
        return cycle_numbers(self.cycle_index)

    def test_normality(self) -> dict:
        """Jarque-Bera test of the standardised innovations, all cycles pooled (:func:`~.residual_tests.jarque_bera_test`).

        Returns
        -------
        dict
            ``statistic``, ``pvalue``, ``skew`` and ``kurtosis`` (3 for a
            normal distribution).
        """
        return jarque_bera_test(self.innovations)

    def test_heteroskedasticity(self, subset_length=1.0 / 3.0) -> dict:
        """Does the residual variance change over the record? (:func:`~.residual_tests.variance_change_test`).

        statsmodels' breakvar test on the standardised innovations (last third
        against first third, F-distributed), with the free-simulation residual's
        own ratio beside it as a description.

        Parameters
        ----------
        subset_length : float
            Fraction of the record in each of the two compared parts.

        Returns
        -------
        dict
            ``statistic``, ``pvalue`` (innovations), ``residual_ratio`` (mean
            square of the residual in the last part over the first).
        """
        return variance_change_test(self.innovations, self.residual, subset_length)

    # -- spectra (diagnostics.spectra) ------------------------------------------

    def measured_spectrum(self, nperseg=None):
        """Welch power spectral density of the measured dynamic GRF.

        Returns
        -------
        freq : ndarray (Hz)
        psd : ndarray (N^2/Hz)
        """
        return welch_spectrum(self.measured, self.fs, self.f_b, nperseg)

    def residual_spectrum(self, nperseg=None, false_alarm=PEAK_FALSE_ALARM, tolerance=None, min_frequency=None,
                          values=None):
        """Welch spectrum of the free-simulation residual and its peaks above the noise floor (:func:`~.spectra.residual_spectrum`).

        A missing force harmonic leaves a line at ``k f_b``; a floor mode leaves
        content at its own frequency; a cubic spring leaves harmonics above those
        the force model has.

        Parameters
        ----------
        nperseg : int, optional
            Welch segment length in samples; default :data:`~.spectra.SEGMENT_CYCLES` bouncing periods.
        false_alarm : float
            Chance that pure noise gives at least one peak.
        tolerance : float, optional
            Largest distance (Hz) from ``k f_b`` for the label "harmonic k" (:func:`~.spectra.spectral_peaks`).
        min_frequency : float, optional
            Lowest frequency searched for peaks (Hz); default the high-pass cut-off.
        values : array_like, shape (T,), optional
            Another series on the checked samples (default :attr:`residual`), e.g.
            the residual without its phase-locked part (:meth:`phase_locked`).

        Returns
        -------
        freq : ndarray, shape (F,)
            Frequencies (Hz).
        psd : ndarray, shape (F,)
            Residual power spectral density (N^2/Hz).
        peaks : pandas.DataFrame
            One row per peak, strongest first (:func:`~.spectra.spectral_peaks`):
            ``frequency`` (Hz), ``power`` (N^2/Hz), ``ratio_to_floor``, ``label``,
            ``k`` and ``f_over_fb``; ``attrs`` holds ``noise_floor``,
            ``threshold``, ``f_b``, ``tolerance`` and ``resolution``.
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
        """The part of a series that repeats with the bouncing cycle (:func:`~.phase.phase_locked` in :attr:`phase`).

        Parameters
        ----------
        values : array_like, shape (T,), optional
            Series on the checked samples (default :attr:`residual`, N).
        orders : int, optional
            Highest order ``k`` (default: up to the Nyquist frequency at the median bouncing frequency).

        Returns
        -------
        ndarray, shape (T,)
            The fitted phase-locked part, in the series' unit.
        """
        series = self._series(values)
        top = int(0.5 * self.fs / self.f_b) if orders is None else int(orders)
        return phase_locked(series, self.phase, top)

    def phase_profile(self, bins=24) -> pd.DataFrame:
        """Residual against the bouncing-cycle phase: where in the cycle the model fails (:func:`~.phase.phase_profile`).

        Parameters
        ----------
        bins : int
            Number of equal phase bins.

        Returns
        -------
        pandas.DataFrame
            One row per bin: ``phase`` (centre), ``phase_low``, ``phase_high``,
            ``n``, ``mean`` and ``sd`` of the residual (N), ``mean_bw`` and
            ``sd_bw`` (% body weight), and ``sem`` (N, over cycles).
        """
        return phase_profile(self.residual, self.phase, self.weight, self.n_cycles, bins)

    def remove_absorbable(self, values) -> np.ndarray:
        """What is left of a signal after removing, cycle by cycle, what re-identifying the model could absorb.

        The derivative of each cycle's simulated ``u''`` with respect to its
        starting state and free parameters (:func:`~.free_simulation.path_sensitivity`)
        spans every change of the output a small change of the cycle's identified
        values can make; the signal's least-squares projection on that span is
        removed (:func:`~.subspace.remove_projections`).

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
        """The part of :attr:`residual` (N) that no small change of the cycles' identified values can remove.

        :meth:`remove_absorbable` applied to the residual: what is left is
        the evidence of an effect the model lacks (plus measurement noise,
        with ``n_state`` fewer degrees of freedom per cycle).
        """
        return self.remove_absorbable(self.residual)

    @property
    def residual_unabsorbed_rms_bw(self) -> float:
        """RMS of :attr:`residual_unabsorbed` in % of body weight."""
        return 100.0 * rms(self.residual_unabsorbed) / self.weight

    def remove_force_harmonics(self, values) -> np.ndarray:
        """What is left of a signal after removing, cycle by cycle, its fit by the force model's basis.

        The regressors of Eq. 4, ``1, cos(k theta), sin(k theta)`` for the
        orders of :meth:`harmonic_orders` and the cycle's own ``f_b``: anything in
        that span the identification absorbs into the force coefficients.

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
        """``[cos(k theta), sin(k theta)]`` of each checked cycle over the whole record, shape (n, 2).

        ``theta = 2 pi f_b (t - t_start)`` of the cycle (Eq. 4); zero outside
        the checked cycles. A force harmonic the model lacks adds
        ``g (a_k cos + b_k sin)`` to the COM acceleration.
        """
        time = np.asarray(self.preprocessed.time, dtype=float)
        out = np.zeros((time.size, 2))
        for cycle in self.cycles:
            span = slice(cycle.start, cycle.stop + 1)
            theta = TWO_PI * cycle.f_b * (time[span] - cycle.t_start)
            out[span, 0], out[span, 1] = np.cos(order * theta), np.sin(order * theta)
        return out

    def default_candidates(self) -> dict:
        """Candidate terms of the COM acceleration that a missing physical effect would add.

        Every registered effect not in the model (:mod:`smd_statespace.effects`,
        a user's included), as its class configures itself for this record
        (:meth:`Effect.candidate <smd_statespace.model.Effect.candidate>`),
        contributes its own terms (:meth:`effect_terms`), named by the
        effect: ``harmonics`` (four columns: ``g cos(j theta), g sin(j
        theta)`` for the two orders above the model's), ``cubic_stiffness``
        (``-w_h^2 u^3``), ``floor_mode`` (with a measured floor: ``w_h^2 z +
        2 xi_h w_h z'``, exactly what a vibrating floor adds, Section 6). A
        term that needs the effect's own unmeasured state (a floor mode
        without accelerometer) is left out. Besides them, model-free probes:

        ``u``, ``u_dot``
            a stiffness or damping the cycle's identification did not catch.
        ``u^2``
            an asymmetric spring.
        ``floor_acc``, ``floor_disp``
            the measured floor signals, when the record has them.

        ``u``, ``u_dot``, ``f_h`` and ``xi_h`` are the free simulation's
        (:meth:`simulated_state`), not the pipeline's ``disp`` and ``vel``:
        those are integrals of the measured acceleration and so carry the
        residual itself, integrated; a candidate built from them correlates
        with the residual whatever the model lacks. (This is the score-test
        rule: evaluate a candidate term on the fitted model.) The measured
        acceleration is not a candidate for the same reason.

        Returns
        -------
        dict of str to ndarray, each of shape ``(len(preprocessed.time),)`` or ``(len(preprocessed.time), q)``
        """
        from ..effects import EFFECTS

        pre = self.preprocessed
        out = {}
        present = {effect.name for effect in self.model.effects}
        for name, cls in EFFECTS.items():
            effect = None if name in present else cls.candidate(self)
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
        its :meth:`~smd_statespace.model.Effect.score_terms`. Samples outside
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
            for key, values in effect.score_terms(model, x[samples], data.t, data.inputs).items():
                out.setdefault(key, np.zeros(len(pre.time)))[samples] = values
        return out

    def simulated_state(self, name) -> np.ndarray:
        """A slot of the free simulation's state over the whole record.

        On the checked cycles the simulated value (a cycle's first sample,
        shared with the previous cycle, takes the later cycle's starting
        value); elsewhere the pipeline's measurement for ``"u"`` (``disp``)
        and ``"u_dot"`` (``vel``), or the median identified value for a
        parameter, so that the array is finite everywhere.

        Parameters
        ----------
        name : str
            A state slot (``"u"``, ``"u_dot"``, ``"f_h"``, ...).

        Returns
        -------
        ndarray, shape (len(preprocessed.time),)
        """
        pre = self.preprocessed
        fill = {"u": pre.disp, "u_dot": pre.vel}.get(name)
        return state_over_record(self._linear, self.model.index(name), len(pre.time), fill)

    def cross_correlation(self, candidates=None, max_lag_s=0.0, remove_harmonics=True) -> pd.DataFrame:
        """Correlation of the free-simulation residual with candidate terms (:func:`~.correlation.cross_correlation_table`).

        By default the residual and every candidate first lose, cycle by cycle,
        their fit by the force model's own basis (:meth:`remove_force_harmonics`):
        without it every candidate correlates about equally (0.2-0.3, measured),
        all being dominated by the bouncing harmonics the identification absorbs
        anyway; with it a cubic spring makes ``cubic_stiffness`` the strongest
        (about twice its value without the effect) and missing force harmonics
        ``harmonics``. Multi-column candidates are scored by their multiple
        correlation. The default is no lag: the candidate terms act on the
        acceleration at once, and a lag search lets any near-periodic candidate
        match the residual's periodic error; a lag is for a sensor with its own delay.

        Parameters
        ----------
        candidates : mapping of str to array_like, optional
            Signals over the whole record, shape ``(len(preprocessed.time),)`` or
            ``(len(preprocessed.time), q)``; default :meth:`default_candidates`.
            To add your own: ``check.cross_correlation({**check.default_candidates(), "mine": x})``.
        max_lag_s : float
            Largest lag (s); at lag ``tau > 0`` the candidate leads the residual.
        remove_harmonics : bool
            Remove the per-cycle force-basis fit first (see above).

        Returns
        -------
        pandas.DataFrame
            One row per candidate, strongest first: ``signal``, ``max_abs_corr``,
            ``corr`` (NaN for multi-column candidates), ``lag_s`` (s),
            ``corr_at_zero`` and ``explained`` (``max_abs_corr^2``).
        """
        candidates = self.default_candidates() if candidates is None else dict(candidates)
        target = self.remove_force_harmonics(self.residual) if remove_harmonics else self.residual
        return cross_correlation_table(target, candidates, self.sample_index, len(self.preprocessed.time), self.fs,
                                       max_lag_s, self.remove_force_harmonics if remove_harmonics else None)

    # -- text -----------------------------------------------------------------

    def summary(self, n_peaks=5, n_signals=5) -> str:
        """Readable report: fit, residual size, tests, spectral peaks, strongest correlations (:func:`~.report.summary_text`)."""
        return summary_text(self, n_peaks, n_signals)

    def __repr__(self):
        return (f"ModelCheck(cycles={self.n_cycles}, fit={self.fit_percent:.1f} %, "
                f"residual_rms={self.residual_rms_bw:.2f} % BW)")

    # -- figures (drawn by smd_statespace.plotting.check) ----------------------

    def plot_fit(self, path=None, cycles=None):
        """Measured GRF against the free simulation and the one-step prediction (:func:`~smd_statespace.plotting.check.plot_fit`)."""
        from ..plotting.check import plot_fit

        return plot_fit(self, path, cycles)

    def pooled_acf(self, nlags=None) -> np.ndarray:
        """Autocorrelation of the standardised innovations, pooled within cycles (lags 0..nlags).

        ``sum_c sum_t z_t z_{t-k} / sum_c sum_t z_t^2`` with both samples in the same cycle
        (:func:`~.residual_tests.pooled_acf`).
        """
        nlags = self.default_lags() if nlags is None else int(nlags)
        return pooled_acf(self._per_cycle(self.innovations), nlags)

    def plot_diagnostics(self, path=None, lags=None):
        """One figure to read at a glance where and how the model fails (:func:`~smd_statespace.plotting.check.plot_diagnostics`)."""
        from ..plotting.check import plot_diagnostics

        return plot_diagnostics(self, path, lags)
