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

__all__ = ["ModelCheck", "check_model", "fit_percent", "INITIAL_STATES"]

INITIAL_STATES = ("estimate", "filtered")
"""Where each cycle's free simulation starts (``initial_state`` of :func:`check_model`):
``"estimate"`` fits the dynamic slots' starting values to the cycle by least
squares, as MATLAB's ``compare`` does by default; ``"filtered"`` takes the
filter's estimate at the cycle's first sample."""

HARMONIC_TOLERANCE = 0.05
"""A spectral peak within this fraction of ``f_b`` (or 1.5 frequency bins,
whichever is larger) of ``k f_b`` is labelled "harmonic k"."""

PEAK_FALSE_ALARM = 0.01
"""Probability that pure noise puts at least one bin of a residual spectrum
above the peak threshold (sets the threshold from the Welch estimate's
chi-square distribution)."""

SEGMENT_CYCLES = 6.0
"""Default Welch segment length in bouncing cycles: frequency resolution
about ``f_b / 6`` (0.33 Hz at 2 Hz), enough to tell harmonic ``k`` from
``k +- 1/2``, while a 10 s stretch still gives several segments to average."""


def fit_percent(measured, predicted) -> float:
    """Normalised root-mean-square fit (%), as in system identification toolboxes.

    ``100 (1 - ||y - y_hat|| / ||y - mean(y)||)``: 100 for a perfect
    prediction, 0 for predicting the mean, negative for worse.

    Parameters
    ----------
    measured, predicted : array_like, shape (T,)
    """
    y = np.asarray(measured, dtype=float)
    y_hat = np.asarray(predicted, dtype=float)
    spread = np.linalg.norm(y - y.mean())
    if spread == 0:
        return float("nan")
    return float(100.0 * (1.0 - np.linalg.norm(y - y_hat) / spread))


def _rms(x) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


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
        from ..estimators import cycle_data

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
        channel = model.channels.index("u_ddot")
        dynamic = np.array([slot.kind == "dynamic" for slot in model.slots])
        mass = float(preprocessed.mass)

        pieces = {name: [] for name in ("time", "cycle", "sample", "phase", "measured", "simulated", "one_step",
                                        "innovations")}
        free_counts, nobs, previous_stop, position = [], 0, None, 0
        self._linear = []
        for cycle in cycles:
            result = self.results[cycle.index]
            data = cycle_data(model, preprocessed, cycle)
            std = np.asarray(result.std)
            free = dynamic | np.any(std > 0, axis=0) if std.ndim == 2 and std.size else np.ones(model.n_state, bool)
            keep = slice(1, None) if cycle.start == previous_stop else slice(None)
            states = self._free_simulation(result, data, dynamic)
            if initial_state == "estimate":
                states = self._fit_initial_state(states, data, dynamic, keep, channel)
            predicted = model.observe(states, data.t, data.inputs)[:, channel]
            previous_stop = cycle.stop
            samples = np.arange(cycle.start, cycle.stop + 1)
            kept = samples[keep]
            acc = data.y[keep, channel]
            pieces["time"].append(data.t[keep])
            pieces["cycle"].append(np.full(kept.size, cycle.index))
            pieces["sample"].append(kept)
            pieces["phase"].append((data.t[keep] - cycle.t_start) / (cycle.t_end - cycle.t_start))
            pieces["measured"].append(mass * acc)
            pieces["simulated"].append(mass * predicted[keep])
            pieces["one_step"].append(mass * (acc - result.innovations[keep, channel]))
            pieces["innovations"].append(result.standardised_innovations[keep, channel])
            nobs += len(data)
            free_counts.append(int(np.sum(free & ~dynamic)))
            self._linear.append({
                "rows": slice(position, position + kept.size), "samples": samples, "keep": keep, "data": data,
                "free": free, "states": states, "harmonic_basis": self._harmonic_basis(cycle, data.t[keep]),
            })
            position += kept.size

        joined = {name: np.concatenate(values) for name, values in pieces.items()}
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
        self.residual_rms = _rms(self.residual)
        self.weight = mass * G
        self.residual_rms_bw = 100.0 * self.residual_rms / self.weight
        self.log_likelihood = float(sum(float(r.log_likelihood) for r in self.results.values()))
        self.n_parameters = int(sum(free_counts))
        self.nobs = int(nobs)
        self.f_b = float(np.median([c.f_b for c in cycles]))
        self.fs = float(preprocessed.fs)

    # -- construction helpers ----------------------------------------------

    def _harmonic_basis(self, cycle, t):
        """Orthonormal basis of the force regressors of Eq. 4 on a cycle's kept samples, shape (m, p)."""
        theta = TWO_PI * cycle.f_b * (np.asarray(t, dtype=float) - cycle.t_start)
        orders = self.harmonic_orders()
        regressors = np.column_stack([np.ones_like(theta)] + [f(k * theta) for k in orders for f in (np.cos, np.sin)])
        return _orthonormal_columns(regressors)

    def _free_simulation(self, result, data, dynamic):
        """States of the free simulation of one cycle, shape (m, n_state).

        Dynamic slots start from the filtered mean at the cycle's first
        sample, parameters are the final-pass values (``final_mean``);
        :meth:`SMDModel.transition` without process noise.
        """
        x = np.array(result.final_mean, dtype=float)
        x[dynamic] = np.asarray(result.mean)[0, dynamic]
        return self._simulate_from(x, data)

    def _simulate_from(self, x, data):
        """Integrate the model without noise from state ``x`` over the cycle's samples, shape (m, n_state)."""
        model = self.model
        states = np.empty((len(data.t), model.n_state))
        states[0] = x
        with np.errstate(over="ignore", invalid="ignore"):
            for k in range(1, len(data.t)):
                x = model.transition(x, data.t[k - 1], data.t[k] - data.t[k - 1], data.inputs)
                states[k] = x
        return states

    def _fit_initial_state(self, states, data, dynamic, keep, channel, iterations=2):
        """Free simulation from the dynamic starting state that best fits the cycle (least squares).

        The parameters stay at their identified values; only the dynamic
        slots' starting values (``u``, ``u_dot``, an estimated floor's ``z``,
        ``z_dot``, ...) change, by Gauss-Newton steps on the measured
        ``u''`` of the cycle's kept samples, with the sensitivities
        ``H_k F_{k-1} ... F_0`` of the model's own Jacobians. One step is
        exact when the model is linear in those slots (every built-in
        effect but ``cubic_stiffness``).
        """
        model = self.model
        measured = data.y[keep, channel]
        for _ in range(iterations):
            sensitivity = self._path_sensitivity(states, data, channel)[keep][:, dynamic]
            predicted = model.observe(states, data.t, data.inputs)[keep, channel]
            step, *_ = np.linalg.lstsq(sensitivity, measured - predicted, rcond=None)
            if not np.all(np.isfinite(step)):
                return states
            start = states[0].copy()
            start[dynamic] += step
            states = self._simulate_from(start, data)
        return states

    def _path_sensitivity(self, states, data, channel):
        """Derivative of the simulated ``u''`` at every sample with respect to the starting state, (m, n_state)."""
        model = self.model
        with np.errstate(over="ignore", invalid="ignore"):
            jacobians = np.array([model.transition_jacobian(states[k - 1], data.t[k - 1],
                                                            data.t[k] - data.t[k - 1], data.inputs)
                                  for k in range(1, len(data.t))]).reshape(-1, model.n_state, model.n_state)
            observation = model.observation_jacobian(states, data.t, data.inputs)[:, channel, :]
        # d y_k / d x_0 = H_k F_{k-1} ... F_0 (Eq. 11-16 linearised along the free simulation).
        return _chain_sensitivity(jacobians, observation)

    @cached_property
    def _absorbable_bases(self):
        """Per cycle, an orthonormal basis of the output changes a re-fit of the cycle could make."""
        channel = self.model.channels.index("u_ddot")
        bases = []
        for piece in self._linear:
            sensitivity = self._path_sensitivity(piece["states"], piece["data"], channel)[:, piece["free"]]
            bases.append(_orthonormal_columns(sensitivity[piece["keep"]]))
        return bases

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
        breaks = np.flatnonzero(np.diff(self.cycle_index)) + 1
        return np.split(np.asarray(values), breaks)

    # -- tests on the standardised innovations ------------------------------

    def default_lags(self) -> int:
        """Default Ljung-Box lag within a cycle: a quarter of the median cycle length, at most 20 (see :meth:`test_serial_correlation`)."""
        lengths = np.array([piece.size for piece in self._per_cycle(self.innovations)])
        return int(max(1, min(np.median(lengths) // 4, 20)))

    def test_serial_correlation(self, lags=None, series="innovations") -> pd.DataFrame:
        """Ljung-Box test of the standardised innovations (or of the residual), per cycle and combined.

        The filter starts afresh in every cycle, so the concatenated
        innovations are not one time series: correlations across a cycle
        boundary compare two unrelated filter runs (and each cycle's first
        samples carry its start-up). The test is therefore run on each
        cycle's innovations separately
        (:func:`statsmodels.stats.diagnostic.acorr_ljungbox`). Under the null
        hypothesis (white innovations) the cycles are independent, so their
        statistics add: ``Q = sum_c Q_c`` is chi-square with
        ``sum_c lags_c`` degrees of freedom, which gives the combined p-value.

        Parameters
        ----------
        lags : int, optional
            Largest lag in samples within a cycle. Default
            :meth:`default_lags`: a quarter of the median cycle length (12
            samples for a 2 Hz cycle at 100 Hz, i.e. up to 0.12 s), capped at
            20. This covers the period of the 4th to 5th harmonic and half a
            period of a floor mode near 4 Hz, where a missing effect puts its
            structure, while keeping the lag well below the cycle length
            (statsmodels' own default, ``min(10, n // 5)``, is similar for a
            50-sample cycle). Cycles shorter than ``2 lags`` use ``n // 2``.
        series : {"innovations", "residual"}
            ``"innovations"`` (default, as statsmodels): the filter's
            standardised innovations. ``"residual"``: the free-simulation
            residual :attr:`residual`, the error a user sees. The
            innovations of the article's filter are serially correlated even
            when the model is right (its ``u`` and ``u_dot`` channels are
            integrals of the measured acceleration, so their errors are
            not independent, and its observation noise is set at 10 % of the
            RMS, far above a force plate's), so a missing effect is judged on
            the residual, whose ``lb_stat / lags`` is about 1.2-1.9 on records
            without a missing effect and 7-10 with one (measured, see
            :mod:`smd_statespace.diagnostics.missing`).

        Returns
        -------
        pandas.DataFrame
            One row per cycle (index ``cycle``) with ``nobs``, ``lags``,
            ``lb_stat``, ``lb_pvalue``, and a last row ``"combined"`` with
            the summed statistic and degrees of freedom and the chi-square
            p-value.
        """
        from scipy import stats  # imported here: scipy.signal, scipy.stats take ~1 s (not needed to start)
        from statsmodels.stats.diagnostic import acorr_ljungbox

        lags = self.default_lags() if lags is None else int(lags)
        if lags < 1:
            raise OptionError(f"lags must be a whole number >= 1, got {lags!r}")
        if series not in ("innovations", "residual"):
            raise OptionError(f"series must be 'innovations' or 'residual', got {series!r}")
        values = self.innovations if series == "innovations" else self.residual
        rows = []
        for number, piece in zip(self._cycle_numbers(), self._per_cycle(values)):
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
        breaks = np.flatnonzero(np.diff(self.cycle_index)) + 1
        return [int(self.cycle_index[i]) for i in np.r_[0, breaks]]

    def test_normality(self) -> dict:
        """Jarque-Bera test of the standardised innovations (all cycles pooled).

        Returns
        -------
        dict
            ``statistic``, ``pvalue``, ``skew`` and ``kurtosis`` (3 for a
            normal distribution), from
            :func:`statsmodels.stats.stattools.jarque_bera`.
        """
        from statsmodels.stats.stattools import jarque_bera

        statistic, pvalue, skew, kurtosis = jarque_bera(self.innovations)
        return {"statistic": float(statistic), "pvalue": float(pvalue), "skew": float(skew),
                "kurtosis": float(kurtosis)}

    def test_heteroskedasticity(self, subset_length=1.0 / 3.0) -> dict:
        """Does the residual variance change over the record? (statsmodels' breakvar test).

        The test statistic is the sum of squares of the standardised
        innovations in the last third of the record over that in the first
        third, F-distributed with ``(h, h)`` degrees of freedom under the null
        hypothesis of constant variance (two-sided),
        :func:`statsmodels.tsa.stattools.breakvar_heteroskedasticity_test`.
        It is run on the innovations rather than on the free-simulation
        residual because the F distribution needs independent samples; the
        residual's own ratio is reported beside it as a description.

        Parameters
        ----------
        subset_length : float
            Fraction of the record in each of the two compared parts.

        Returns
        -------
        dict
            ``statistic``, ``pvalue`` (innovations), ``residual_ratio``: the
            mean square of the free-simulation residual in the last part
            over that in the first part.
        """
        from statsmodels.tsa.stattools import breakvar_heteroskedasticity_test

        statistic, pvalue = breakvar_heteroskedasticity_test(self.innovations, subset_length=subset_length)
        h = int(np.round(subset_length * self.residual.size))
        ratio = float(np.mean(self.residual[-h:] ** 2) / np.mean(self.residual[:h] ** 2)) if h > 0 else float("nan")
        return {"statistic": float(statistic), "pvalue": float(pvalue), "residual_ratio": ratio}

    # -- spectra --------------------------------------------------------------

    def _welch(self, x, nperseg=None):
        from scipy import signal  # imported here: scipy.signal, scipy.stats take ~1 s (not needed to start)

        n = len(x)
        if nperseg is None:
            nperseg = int(round(SEGMENT_CYCLES * self.fs / self.f_b))
        nperseg = int(min(max(nperseg, 16), n))
        return signal.welch(x, fs=self.fs, nperseg=nperseg, detrend="constant", scaling="density")

    def _welch_dof(self, n, nperseg):
        """Equivalent degrees of freedom of a Hann-window, 50 %-overlap Welch estimate."""
        segments = max(1, 1 + (n - nperseg) // (nperseg // 2))
        # Overlap correlation of two Hann segments at 50 %: c = 0.167 (Welch 1967; Percival & Walden).
        return 2.0 * segments / (1.0 + 2.0 * 0.167**2 * (segments - 1) / segments)

    def measured_spectrum(self, nperseg=None):
        """Welch power spectral density of the measured dynamic GRF.

        Returns
        -------
        freq : ndarray (Hz)
        psd : ndarray (N^2/Hz)
        """
        return self._welch(self.measured, nperseg)

    def residual_spectrum(self, nperseg=None, false_alarm=PEAK_FALSE_ALARM, tolerance=None, min_frequency=None,
                          values=None):
        """Welch spectrum of the free-simulation residual and its peaks above the noise floor.

        A missing force harmonic leaves a line at ``k f_b``; a floor mode
        leaves content at its own frequency, in general not a multiple of
        ``f_b``; a nonlinearity (cubic spring) leaves harmonics above those
        the force model has.

        The noise floor is the median of the residual PSD above the high-pass
        cut-off (measurement noise is white, and model error occupies a
        minority of the bins). A peak is a local maximum whose PSD exceeds
        the floor by the factor pure noise would exceed in any bin with
        probability ``false_alarm`` (chi-square distribution of the Welch
        estimate with its equivalent degrees of freedom). Peak frequencies are
        refined by parabolic interpolation of the log PSD.

        Parameters
        ----------
        nperseg : int, optional
            Welch segment length in samples; default :data:`SEGMENT_CYCLES`
            bouncing periods (frequency resolution about ``f_b / 6``).
        false_alarm : float
            Chance that pure noise gives at least one peak.
        tolerance : float, optional
            Largest distance (Hz) from ``k f_b`` for the label "harmonic k";
            default the larger of :data:`HARMONIC_TOLERANCE` ``* f_b`` and 1.5
            frequency bins.
        min_frequency : float, optional
            Lowest frequency searched for peaks (Hz); default the high-pass cut-off.
        values : array_like, shape (T,), optional
            Another series on the checked samples to analyse the same way
            (default :attr:`residual`), e.g. the residual without its
            phase-locked part (:meth:`phase_locked`).

        Returns
        -------
        freq : ndarray, shape (F,)
            Frequencies (Hz).
        psd : ndarray, shape (F,)
            Residual power spectral density (N^2/Hz).
        peaks : pandas.DataFrame
            One row per peak, strongest first: ``frequency`` (Hz), ``power``
            (N^2/Hz), ``ratio_to_floor``, ``label`` ("harmonic k" or
            "non-harmonic"), ``k`` (nearest harmonic order, or <NA> for a
            non-harmonic peak) and ``f_over_fb``. ``peaks.attrs`` holds
            ``noise_floor``, ``threshold`` (N^2/Hz), ``f_b``, ``tolerance``
            (Hz) and ``resolution`` (Hz).
        """
        from scipy import signal, stats  # imported here: scipy.signal, scipy.stats take ~1 s (not needed to start)

        series = self.residual if values is None else np.asarray(values, dtype=float)
        if series.shape != self.residual.shape:
            raise OptionError(f"values has shape {series.shape}; the check has {self.residual.shape}")
        freq, psd = self._welch(series, nperseg)
        n = len(series)
        segment = int(min(max(int(round(SEGMENT_CYCLES * self.fs / self.f_b)) if nperseg is None else nperseg, 16), n))
        resolution = float(freq[1] - freq[0])
        low = float(getattr(self.preprocessed, "cutoff", 0.5)) if min_frequency is None else float(min_frequency)
        band = freq > low
        floor = float(np.median(psd[band]))
        dof = self._welch_dof(n, segment)
        n_bins = int(band.sum())
        # Noise PSD ~ level * chi2(dof) / dof; the median of that is level * chi2.median(dof) / dof.
        ratio = stats.chi2.isf(false_alarm / max(n_bins, 1), dof) / stats.chi2.median(dof)
        threshold = floor * ratio
        tol = max(HARMONIC_TOLERANCE * self.f_b, 1.5 * resolution) if tolerance is None else float(tolerance)
        where, _ = signal.find_peaks(psd)
        where = where[band[where] & (psd[where] > threshold)]
        rows = []
        for i in where:
            f_peak = float(freq[i])
            if 0 < i < len(psd) - 1:
                a, b, c = np.log(psd[i - 1 : i + 2])
                denominator = a - 2.0 * b + c
                if denominator < 0:
                    f_peak += 0.5 * (a - c) / denominator * resolution
            k = int(np.round(f_peak / self.f_b))
            harmonic = k >= 1 and abs(f_peak - k * self.f_b) <= tol
            rows.append({"frequency": f_peak, "power": float(psd[i]), "ratio_to_floor": float(psd[i] / floor),
                         "label": f"harmonic {k}" if harmonic else "non-harmonic",
                         "k": k if harmonic else pd.NA, "f_over_fb": f_peak / self.f_b})
        peaks = pd.DataFrame(rows, columns=["frequency", "power", "ratio_to_floor", "label", "k", "f_over_fb"])
        peaks["k"] = peaks["k"].astype("Int64")
        peaks = peaks.sort_values("power", ascending=False).reset_index(drop=True)
        peaks.attrs.update(noise_floor=floor, threshold=threshold, f_b=self.f_b, tolerance=tol,
                           resolution=resolution)
        return freq, psd, peaks

    # -- structure of the residual -----------------------------------------

    def phase_locked(self, values=None, orders=None) -> np.ndarray:
        """The part of a series that repeats with the bouncing cycle (least squares over the whole record).

        The series is regressed on ``1, cos(2 pi k p), sin(2 pi k p)``,
        ``p`` the cycle phase (:attr:`phase`), with coefficients common to
        every cycle. What the person does every cycle (a missing force
        harmonic, a nonlinearity of the periodic motion) is phase-locked;
        what another source does to the floor is not, whatever its
        frequency, even at a multiple of ``f_b``.

        Parameters
        ----------
        values : array_like, shape (T,), optional
            Series on the checked samples (default :attr:`residual`, N).
        orders : int, optional
            Highest order ``k`` (default: up to the Nyquist frequency at the
            median bouncing frequency).

        Returns
        -------
        ndarray, shape (T,)
            The fitted phase-locked part, in the series' unit.
        """
        series = self.residual if values is None else np.asarray(values, dtype=float)
        if series.shape != self.residual.shape:
            raise OptionError(f"values has shape {series.shape}; the check has {self.residual.shape}")
        top = int(0.5 * self.fs / self.f_b) if orders is None else int(orders)
        angle = TWO_PI * self.phase[:, None] * np.arange(1, max(top, 0) + 1)
        design = np.column_stack([np.ones_like(self.phase), np.cos(angle), np.sin(angle)])
        coefficients, *_ = np.linalg.lstsq(design, series, rcond=None)
        return design @ coefficients

    def phase_profile(self, bins=24) -> pd.DataFrame:
        """Residual against the bouncing-cycle phase: where in the cycle the model fails.

        The phase of a sample is ``(t - t_start) / (t_end - t_start)`` of its
        cycle (0 and 1 at the GRF peaks that bound it).

        Parameters
        ----------
        bins : int
            Number of equal phase bins.

        Returns
        -------
        pandas.DataFrame
            One row per bin: ``phase`` (centre), ``phase_low``,
            ``phase_high``, ``n`` (samples), ``mean`` and ``sd`` of the
            residual (N), ``mean_bw`` and ``sd_bw`` (% body weight), and
            ``sem`` (N): the standard error of the mean over cycles
            (``sd / sqrt(n_cycles)``).
        """
        bins = int(bins)
        if bins < 1:
            raise OptionError(f"bins must be a whole number >= 1, got {bins!r}")
        edges = np.linspace(0.0, 1.0, bins + 1)
        which = np.clip(np.searchsorted(edges, self.phase, side="right") - 1, 0, bins - 1)
        count = np.bincount(which, minlength=bins)
        total = np.bincount(which, weights=self.residual, minlength=bins)
        square = np.bincount(which, weights=self.residual**2, minlength=bins)
        with np.errstate(invalid="ignore", divide="ignore"):
            mean = total / count
            sd = np.sqrt(np.maximum(square / count - mean**2, 0.0) * count / np.maximum(count - 1, 1))
        frame = pd.DataFrame({
            "phase": 0.5 * (edges[:-1] + edges[1:]), "phase_low": edges[:-1], "phase_high": edges[1:], "n": count,
            "mean": mean, "sd": sd, "mean_bw": 100.0 * mean / self.weight, "sd_bw": 100.0 * sd / self.weight,
            "sem": sd / np.sqrt(max(self.n_cycles, 1)),
        })
        return frame

    def remove_absorbable(self, values) -> np.ndarray:
        """What is left of a signal after removing, cycle by cycle, what re-identifying the model could absorb.

        Each cycle's free simulation is linearised about its path: the
        derivative of the simulated ``u''`` at every sample with respect to
        the cycle's starting state (``u``, ``u_dot`` and every free parameter:
        ``f_h``, ``xi_h``, the Fourier coefficients, effects' slots) is the
        chain ``H_k F_{k-1} ... F_0`` of the model's own Jacobians
        (:meth:`SMDModel.transition_jacobian`, :meth:`SMDModel.observation_jacobian`).
        Its columns span every change of the simulated output a small change
        of the cycle's identified values can make; the signal's least-squares
        projection on that span is removed, cycle by cycle.

        Parameters
        ----------
        values : array_like, shape (T,)
            A signal on the checked samples (e.g. :attr:`residual`).

        Returns
        -------
        ndarray, shape (T,)
        """
        values = np.asarray(values, dtype=float)
        if values.shape[0] != self.residual.size:
            raise OptionError(f"values has {values.shape[0]} samples; the check has {self.residual.size}")
        out = values.copy()
        for piece, basis in zip(self._linear, self._absorbable_bases):
            block = out[piece["rows"]]
            out[piece["rows"]] = block - basis @ (basis.T @ block)
        return out

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
        return 100.0 * _rms(self.residual_unabsorbed) / self.weight

    def remove_force_harmonics(self, values) -> np.ndarray:
        """What is left of a signal after removing, cycle by cycle, its fit by the force model's basis.

        Each checked cycle's samples are regressed (least squares) on the
        regressors of Eq. 4, ``1, cos(k theta), sin(k theta)`` for the orders
        of :meth:`harmonic_orders`, ``theta = 2 pi f_b (t - t_start)`` with the
        cycle's own ``f_b``, and replaced by the regression residual.
        Anything in that span the identification can absorb into the cycle's
        force coefficients, so it says nothing about a missing effect.

        Parameters
        ----------
        values : array_like, shape (T,) or (T, q)
            Signal(s) on the checked samples.

        Returns
        -------
        ndarray, same shape
        """
        values = np.asarray(values, dtype=float)
        if values.shape[0] != self.residual.size:
            raise OptionError(f"values has {values.shape[0]} samples; the check has {self.residual.size}")
        out = values.copy()
        for piece in self._linear:
            basis = piece["harmonic_basis"]
            block = out[piece["rows"]]
            out[piece["rows"]] = block - basis @ (basis.T @ block)
        return out

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
        i = self.model.index(name)
        pre = self.preprocessed
        fill = {"u": pre.disp, "u_dot": pre.vel}.get(name)
        if fill is None:
            values = np.full(len(pre.time), float(np.median([p["states"][-1, i] for p in self._linear])))
        else:
            values = np.array(fill, dtype=float)
        for piece in self._linear:
            values[piece["samples"]] = piece["states"][:, i]
        return values

    def cross_correlation(self, candidates=None, max_lag_s=0.0, remove_harmonics=True) -> pd.DataFrame:
        """Correlation of the free-simulation residual with candidate terms: what does the error look like?

        By default both the residual and every candidate first lose, cycle
        by cycle, their least-squares fit by the force model's own basis
        (:meth:`remove_force_harmonics`). Without that step (measured on
        synthetic records) every candidate correlates about equally, 0.2-0.3:
        ``u``, ``u_dot``, ``u^3`` and the floor motion are all dominated by
        the bouncing harmonics, which is also where the free simulation's
        unavoidable error sits, and what lies in that span the identification
        absorbs into the force coefficients anyway. After it, a cubic spring
        makes its term ``cubic_stiffness`` the strongest (about twice its value
        on the same record without the effect), and missing force harmonics
        make ``harmonics`` the strongest.

        Multi-column candidates (``harmonics``: cosines and sines) are scored
        by the multiple correlation of a least-squares fit of all their
        columns (``corr`` is then NaN); single columns by the Pearson
        correlation. For each lag ``tau`` (whole samples, ``|tau| <=
        max_lag_s``) the candidate ``c(t - tau)`` is used (``tau > 0``: the
        candidate leads the residual) and the lag with the largest absolute
        correlation is reported. The default is no lag: the candidate terms
        act on the acceleration at once, and searching over lags lets any
        near-periodic candidate match the residual's periodic error (on the
        raw signals the best lag sat at the +-0.1 s edge of the search for
        most candidates); a lag is for a sensor with its own delay.

        Parameters
        ----------
        candidates : mapping of str to array_like, optional
            Signals over the whole record, each of shape
            ``(len(preprocessed.time),)`` or ``(len(preprocessed.time), q)``.
            Default :meth:`default_candidates`; to add your own:
            ``check.cross_correlation({**check.default_candidates(), "mine": x})``.
        max_lag_s : float
            Largest lag (s).
        remove_harmonics : bool
            Remove the per-cycle force-basis fit first (see above).

        Returns
        -------
        pandas.DataFrame
            One row per candidate, strongest first: ``signal``,
            ``max_abs_corr``, ``corr`` (signed value there, NaN for
            multi-column candidates), ``lag_s`` (s), ``corr_at_zero`` (no
            lag) and ``explained`` (``max_abs_corr^2``: fraction of the
            residual's variance a least-squares multiple of the candidate
            removes).
        """
        candidates = self.default_candidates() if candidates is None else dict(candidates)
        n_record = len(self.preprocessed.time)
        max_lag = int(np.floor(float(max_lag_s) * self.fs + 1e-9))
        if max_lag < 0:
            raise OptionError(f"max_lag_s must be >= 0, got {max_lag_s!r}")
        lags = np.arange(-max_lag, max_lag + 1)
        target = self.remove_force_harmonics(self.residual) if remove_harmonics else self.residual
        rows = []
        for name, values in candidates.items():
            values = np.asarray(values, dtype=float)
            columns = values[:, None] if values.ndim == 1 else values
            if columns.ndim != 2 or columns.shape[0] != n_record:
                raise OptionError(
                    f"candidate {name!r} has shape {values.shape}; give ({n_record},) or ({n_record}, q): "
                    "values over the whole record"
                )
            if not np.all(np.isfinite(columns)):
                raise OptionError(f"candidate {name!r} holds NaN or infinite values")
            corr = np.empty(lags.size)
            for j, lag in enumerate(lags):
                where = np.clip(self.sample_index - lag, 0, n_record - 1)
                block = columns[where]
                if remove_harmonics:
                    block = self.remove_force_harmonics(block)
                corr[j] = _corr(target, block[:, 0]) if block.shape[1] == 1 else _multiple_corr(target, block)
            if np.all(np.isnan(corr)):
                best, value = max_lag, float("nan")
            else:
                best = int(np.nanargmax(np.abs(corr)))
                value = float(corr[best])
            rows.append({"signal": name, "max_abs_corr": abs(value), "corr": value if columns.shape[1] == 1 else np.nan,
                         "lag_s": lags[best] / self.fs, "corr_at_zero": float(corr[max_lag]), "explained": value**2})
        frame = pd.DataFrame(rows, columns=["signal", "max_abs_corr", "corr", "lag_s", "corr_at_zero", "explained"])
        return frame.sort_values("max_abs_corr", ascending=False, na_position="last").reset_index(drop=True)

    # -- text -----------------------------------------------------------------

    def summary(self, n_peaks=5, n_signals=5) -> str:
        """Readable report: fit, residual size, tests, spectral peaks, strongest correlations."""
        pre = self.preprocessed
        lb = self.test_serial_correlation()
        combined = lb.loc["combined"]
        normal = self.test_normality()
        hetero = self.test_heteroskedasticity()
        _, _, peaks = self.residual_spectrum()
        corr = self.cross_correlation()
        estimator = self.table["estimator"].iloc[0] if "estimator" in self.table and len(self.table) else "?"
        width = 78
        lines = [
            "Model check".center(width),
            "=" * width,
            f"record: {getattr(pre, 'source', '?')}    model: {self.model!r}",
            f"estimator: {estimator}    cycles checked: {self.n_cycles}    samples: {self.residual.size}"
            f"    median f_b: {self.f_b:.3f} Hz",
            f"log-likelihood: {self.log_likelihood:.1f}    parameters: {self.n_parameters}"
            f"    AIC: {self.aic:.1f}    BIC: {self.bic:.1f}",
            "-" * width,
            f"fit, free simulation:        {self.fit_percent:6.2f} %",
            f"fit, one-step prediction:    {self.fit_percent_one_step:6.2f} %",
            f"residual RMS (free sim.):    {self.residual_rms:8.2f} N = {self.residual_rms_bw:.2f} % of body weight"
            f" ({self.weight:.0f} N)",
            f"  of which no re-fit of the cycles could remove: {self.residual_unabsorbed_rms_bw:.2f} % of body weight",
            f"innovation variance:         {self.innovation_variance:6.3f}   (1 if the filter's noise levels fit)",
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

        ``sum_c sum_t z_t z_{t-k} / sum_c sum_t z_t^2`` with both samples in the same cycle.
        """
        nlags = self.default_lags() if nlags is None else int(nlags)
        pieces = [p - p.mean() for p in self._per_cycle(self.innovations)]
        denominator = sum(float(np.dot(p, p)) for p in pieces)
        out = np.empty(nlags + 1)
        for k in range(nlags + 1):
            out[k] = sum(float(np.dot(p[k:], p[: p.size - k])) for p in pieces if p.size > k) / denominator
        return out

    def plot_diagnostics(self, path=None, lags=None):
        """One figure to read at a glance where and how the model fails (:func:`~smd_statespace.plotting.check.plot_diagnostics`)."""
        from ..plotting.check import plot_diagnostics

        return plot_diagnostics(self, path, lags)


def _corr(a, b) -> float:
    """Pearson correlation of two equal-length arrays (NaN when either is constant)."""
    a = a - a.mean()
    b = b - b.mean()
    denominator = np.sqrt(np.dot(a, a) * np.dot(b, b))
    return float(np.dot(a, b) / denominator) if denominator > 0 else float("nan")


def _multiple_corr(target, columns) -> float:
    """Multiple correlation of ``target`` with a least-squares fit of ``columns`` (and a constant)."""
    design = np.column_stack([np.ones(target.size), columns])
    coefficients, *_ = np.linalg.lstsq(design, target, rcond=None)
    centred = target - target.mean()
    total = float(np.dot(centred, centred))
    if total == 0:
        return float("nan")
    left = target - design @ coefficients
    return float(np.sqrt(max(0.0, 1.0 - float(np.dot(left, left)) / total)))


def _chain_sensitivity(jacobians, obs_jacobians):
    """Rows ``H_k F_{k-1} ... F_0``: derivative of each output with respect to the first state, shape (m, n)."""
    m, n = obs_jacobians.shape
    out = np.empty((m, n))
    phi = np.eye(n)
    out[0] = obs_jacobians[0]
    for k in range(1, m):
        phi = jacobians[k - 1] @ phi
        out[k] = obs_jacobians[k] @ phi
    return out


def _orthonormal_columns(matrix, rtol=1e-7):
    """Orthonormal basis of the column space of ``matrix`` (columns scaled to unit norm first)."""
    matrix = np.asarray(matrix, dtype=float)
    norms = np.linalg.norm(matrix, axis=0)
    usable = np.isfinite(norms) & (norms > 0)
    if not usable.any():
        return np.zeros((matrix.shape[0], 0))
    scaled = matrix[:, usable] / norms[usable]
    u, s, _ = np.linalg.svd(scaled, full_matrices=False)
    return u[:, s > rtol * s[0]]
