"""What the record-level identification found: the person, with intervals, and its own tests.

:class:`PersonResult` is returned by
:func:`~smd_statespace.person.fit.identify_person`. Like statsmodels'
``MLEResults`` it carries its tests (``test_serial_correlation``,
``test_normality``, ``test_heteroskedasticity``: statsmodels' at the estimate,
:class:`~smd_statespace.person.statespace.RecordStateSpace`) and ``plot_diagnostics``
(:mod:`~smd_statespace.plotting.innovations`, as a per-cycle check), plus what a
structural engineer needs: ``f_h``, ``xi_h``, ``K_h``, ``C_h`` (Eq. 17-18) and
the force template's load factors (Eq. 5) with standard errors and their
cycle-to-cycle spread, one row per cycle from the smoother (:attr:`cycles`),
and plain-word warnings (:attr:`warnings`).
"""

from __future__ import annotations

import shlex
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import pandas as pd
from scipy import stats

from .calibration import model_error_floor
from .fade import fade_shift
from .in_time import person_in_time
from .judgement import (DETERMINED_FRACTION, F_B_COINCIDENCE, MISFIT_SHARE, PRIOR_SD, VARIATION_AIC_CLOSE,  # noqa: F401
                        VARIATION_DISAGREEMENT, WHITENESS_ALPHA, XI_H_RESONANCE_MIMIC, mimicked_harmonic, narrowed,
                        plausible_variations, stands_in_for_force, variation_disagreement)
from .model import RecordModel
from .report import person_warnings, result_dict, summary_text, table_row
from .checks import RecordChecks

__all__ = ["PersonResult", "DETERMINED_FRACTION", "MISFIT_SHARE", "PRIOR_SD"]


@dataclass
class PersonResult(RecordChecks):
    """One person identified from one record.

    Attributes
    ----------
    record : Record
    model : RecordModel
        The fitted model (its timing, variation model, regressors).
    params : ndarray
        Maximum-likelihood estimates in the order of ``model.param_names``.
    cov : ndarray
        Their covariance from the observed information (NaN for parameters
        held at a bound).
    free : ndarray of bool
        Parameters not at a search bound.
    loglike : float
        Profile log-likelihood at the estimate.
    intervals : dict
        ``{"f_h": (low, high), "xi_h": (low, high)}`` at ``level``.
    interval_method : str
        ``"profile"`` or ``"wald"``.
    level : float
    comparison : list of VariationFit
        The variation models tried (:class:`~smd_statespace.person.comparison.VariationFit`).
    n_evaluations : int
        Likelihood evaluations of the search.
    record_warnings : list of str
        What the checks of :func:`~smd_statespace.applicability.check_bouncing`
        found in the record before the fit (first in :attr:`warnings`).
    notes : list of str
        What was done to the record before the fit (decimation), in words.
    before : PersonResult or None
        With effects: the fit they were added to, the comparison's "before" (the same person without them, or
        with only the effects added earlier).
    effects : tuple of Effect
        The effects in the model (their parameters are in :attr:`params`, last).
    linearisations : int
        How many paths a nonlinear effect was linearised about (0: the likelihood is exact).
    settled : bool
        False when a nonlinear effect's path was still moving after the last linearisation: the
        approximate likelihood kept rising as the path followed the data, so its likelihood ratio is
        not evidence (``diagnose`` does not propose such an effect).
    tested_loglike : float or None
        With effects: the log-likelihood with them at :attr:`before`'s cycle starts and variation
        model, where :meth:`effect_test` compares the two (None: :attr:`loglike`, the starts kept).
    tested_df : int or None
        The unknowns that fit added to :attr:`before` (None: those of this fit): the likelihood ratio's
        degrees of freedom. The fit kept after re-placing the starts may have chosen another variation
        model, with another count.
    change : dict or None
        The person fitted on each half of the record and the test of equality
        (:func:`~smd_statespace.person.change.change_test`; None: not tested). A parameter in its
        ``changed`` list is not determined, and its interval spans both halves'.
    prepared : PreparedRecord or None
        What was done to the record before the fit (:func:`~smd_statespace.signals.prepare_record`: the
        record as read, its parts, the mains hum, the fitted span); :attr:`record` is what was fitted.
    narrow_intervals : dict
        The calibrated intervals of ``f_h`` and ``xi_h`` as the record's information gives them,
        before :func:`~smd_statespace.person.answer.honest_intervals` widened them (empty for other
        interval methods); :attr:`intervals` are the ones to read.
    """

    record: object
    model: RecordModel
    params: np.ndarray
    cov: np.ndarray
    free: np.ndarray
    loglike: float
    intervals: dict
    interval_method: str
    level: float
    comparison: list
    n_evaluations: int = 0
    record_warnings: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    before: "PersonResult | None" = None
    effects: tuple = ()
    linearisations: int = 0
    settled: bool = True
    tested_loglike: float | None = None
    tested_df: int | None = None
    change: dict | None = None
    prepared: object = None
    narrow_intervals: dict = field(default_factory=dict)

    # ------------------------------------------------------------------ estimates
    @cached_property
    def filtered(self) -> dict:
        """The compiled pass at the estimate (:meth:`RecordModel.filter`)."""
        return self.model.filter(self.params)

    @property
    def f_h(self) -> float:
        """SMD natural frequency ``f_h`` (Hz)."""
        return self.model.unpack(self.params)["f_h"]

    @property
    def xi_h(self) -> float:
        """SMD damping ratio ``xi_h`` (-)."""
        return self.model.unpack(self.params)["xi_h"]

    @property
    def se(self) -> np.ndarray:
        """Standard errors of :attr:`params`."""
        return np.sqrt(np.diag(self.cov))

    def sd(self, name) -> float:
        """Standard error of the parameter ``name`` (in its unit)."""
        return float(self.se[self.model.position(name)])

    @property
    def sigma(self) -> float:
        """Estimated observation-noise sd of ``GRF / M_h`` (m/s^2)."""
        return float(np.sqrt(self.filtered["sigma2"]))

    @property
    def n_cycles(self) -> int:
        """Whole force cycles inside the record."""
        b = self.model.timing.boundaries
        return int(np.sum((b > self.record.time[0]) & (b < self.record.time[-1])) - 1)

    def _delta(self):
        out = self.filtered
        return out["delta"], out["delta_cov_unscaled"] * out["sigma2"]

    @property
    def template(self) -> pd.DataFrame:
        """Record-level force coefficients (g) with their sds (conditional on ``f_h``, ``xi_h``)."""
        delta, cov = self._delta()
        p, nx = self.model.n_coefficients, self.model.n_dynamic
        return pd.DataFrame({"value": delta[nx:nx + p], "sd": np.sqrt(np.diag(cov)[nx:nx + p])},
                            index=self.model.coefficient_names)

    def template_blf(self) -> pd.DataFrame:
        """Load factors ``BLF_i`` of the template (Eq. 5) with sds that include the person's uncertainty (g).

        Columns ``blf``, ``sd``, ``sd_given_person``, ``spread`` (the cycle-to-cycle sd), ``low``,
        ``high`` (the interval at :attr:`level`) and ``determined``.
        ``sd_given_person`` is the delta method on the template's own (generalised least-squares)
        covariance at the estimated ``f_h``, ``xi_h`` and variances: it says how well the force
        is known *if* the person is right, a few thousandths of g on a 30 s record. But the force
        is read through Eq. 2, so a wrong ``f_h`` moves the BLFs by far more: ``sd`` adds
        ``J C J'`` in quadrature, ``J`` the derivatives of the BLFs with respect to ``f_h``,
        ``xi_h`` and the effects' parameters (central differences of the concentrated template,
        :attr:`BLF_STEP` sds apart) and ``C`` their covariance as the intervals use it
        (calibrated, with the model-error floor of ``f_h`` and ``xi_h``). The variances are left
        out: they weight the template's least squares but hardly move it.

        When ``f_h`` or ``xi_h`` has an interval wider than its information says (not determined, an
        artefact, a misfit: :func:`~smd_statespace.person.answer.honest_intervals`), the linear ``sd`` does
        not hold across it: the template is concentrated again at a grid across the person's intervals
        (:data:`BLF_GRID`) and ``low``, ``high`` span what it gives; a BLF whose interval is then wider
        than its value is ``determined`` False (said in :attr:`warnings`). (On a record whose force drifts,
        ``f_h`` 1.76 Hz NOT DETERMINED with interval 0.50-3.18 Hz, truth 2.41: BLF1 had been 0.068 ± 0.046 g
        against a truth of 0.25 g.)
        """
        return self._template_blf

    BLF_STEP = 0.1
    """Step of the central differences of :meth:`template_blf`, in standard errors of each parameter."""

    def _blf_values(self, params) -> np.ndarray:
        delta = self.model.filter(params)["delta"]
        ia = self.model.n_dynamic + 2 * np.arange(1, self.model.n_harmonics + 1) - 1
        return np.hypot(delta[ia], delta[ia + 1])

    def _parameter_cov_for_blf(self) -> np.ndarray:
        """:attr:`cov` with the model-error floor of ``f_h`` and ``xi_h`` added, as the intervals have it."""
        cov = np.array(self.cov, dtype=float)
        if self.interval_method.startswith("calibrated"):
            for name in ("f_h", "xi_h"):
                which = self.model.position(name)
                cov[which, which] += model_error_floor(name, self.f_h, self.model.variation) ** 2
        return cov

    @cached_property
    def _template_blf(self) -> pd.DataFrame:
        delta, cov = self._delta()
        values = self._blf_values(self.params)
        given = []
        for i in range(1, self.model.n_harmonics + 1):
            ia, ib = self.model.n_dynamic + 2 * i - 1, self.model.n_dynamic + 2 * i
            grad = np.array([delta[ia], delta[ib]]) / max(values[i - 1], 1e-12)
            given.append(float(np.sqrt(grad @ cov[np.ix_([ia, ib], [ia, ib])] @ grad)))
        param_cov = self._parameter_cov_for_blf()
        se = np.sqrt(np.diag(param_cov))
        physical = [0, 1] + [self.model.param_names.index(name) for name in self.model.effect_parameters]
        index = [k for k in physical if self.free[k] and np.isfinite(se[k]) and se[k] > 0]
        jac = np.full((values.size, len(index)), np.nan)  # nan where no difference could be taken: sd unknown
        for column, k in enumerate(index):
            for fraction in (self.BLF_STEP, self.BLF_STEP / 10.0):  # a pass can break down far out: go closer
                step = np.zeros(self.params.size)
                step[k] = fraction * se[k]
                plus, minus = self._blf_values(self.params + step), self._blf_values(self.params - step)
                if np.all(np.isfinite(plus)) and np.all(np.isfinite(minus)):
                    jac[:, column] = (plus - minus) / (2.0 * step[k])
                    break
                if np.all(np.isfinite(plus)) or np.all(np.isfinite(minus)):  # one side only
                    jac[:, column] = ((plus - values) if np.all(np.isfinite(plus)) else (values - minus)) / step[k]
                    break
        person = np.einsum("ij,jk,ik->i", jac, param_cov[np.ix_(index, index)], jac) if index else np.zeros_like(values)
        spread = self.spread()
        sd = np.sqrt(np.array(given) ** 2 + np.maximum(person, 0.0))
        low, high = stats.norm.interval(self.level, values, np.maximum(sd, 1e-300))
        low = np.maximum(low, 0.0)
        over = self._blf_over_person_interval()
        widened = np.zeros(values.size, dtype=bool)
        if over is not None:  # the person is not determined: the BLFs read through it are not either
            low, high = np.minimum(low, over.min(axis=0)), np.maximum(high, over.max(axis=0))
            widened = high - low > values  # wider than the value itself: not even its size is known
        rows = [{"harmonic": i, "blf": float(values[i - 1]), "sd": float(sd[i - 1]),
                 "sd_given_person": given[i - 1], "spread": spread[i], "low": float(low[i - 1]),
                 "high": float(high[i - 1]), "determined": not bool(widened[i - 1])}
                for i in range(1, values.size + 1)]
        return pd.DataFrame(rows).set_index("harmonic")

    @property
    def person_widened(self) -> bool:
        """True when the interval of ``f_h`` or ``xi_h`` is wider than its information says
        (:attr:`narrow_intervals`, kept by ``intervals="calibrated"``: not determined, an artefact, a misfit,
        variation models that disagree)."""
        return bool(self.narrow_intervals) and not all(
            np.allclose(self.intervals[name], self.narrow_intervals[name]) for name in ("f_h", "xi_h"))

    BLF_GRID = (7, 3)
    """Points of ``f_h`` and ``xi_h`` across their intervals at which :meth:`template_blf` reads the BLFs
    when the person is not determined."""

    def _blf_over_person_interval(self):
        """The BLFs at a grid of ``(f_h, xi_h)`` across their intervals, shape (points, n), or None.

        Only when an interval is wider than the information says (:attr:`narrow_intervals`: ``f_h`` or
        ``xi_h`` not determined, an artefact, a misfit, variation models that disagree): the template is
        then concentrated again at each point (the other parameters held), and the BLFs' interval spans
        what it gives, since the force is read through Eq. 2 at a person the record does not settle.
        """
        if not self.person_widened:
            return None
        (f_low, f_high), (x_low, x_high) = self.intervals["f_h"], self.intervals["xi_h"]
        f_bounds, x_bounds = self.model.bound("f_h"), self.model.bound("xi_h")
        out = []
        for f_h in np.linspace(f_low, f_high, self.BLF_GRID[0]):
            for xi_h in np.unique(np.r_[np.linspace(x_low, x_high, self.BLF_GRID[1]), self.xi_h]):
                params = self.model.pack({**self.model.unpack(self.params), "f_h": np.clip(f_h, *f_bounds),
                                          "xi_h": np.clip(xi_h, max(x_bounds[0], 0.02), x_bounds[1])})
                values = self._blf_values(params)
                if np.all(np.isfinite(values)):
                    out.append(values)
        return np.array(out) if out else None

    def spread(self, kind="d") -> np.ndarray:
        """Cycle-to-cycle sd of each harmonic's coefficients (g): ``kind`` "d" (independent) or "e" (random walk).

        Index 0 is ``a0``; zeros when the variation model has no such part.
        """
        named = self.model.unpack(self.params)
        out = np.zeros(self.model.n_harmonics + 1)
        for i in range(out.size):
            key = f"log_var_{kind}_{i}"
            if key in named:
                out[i] = np.sqrt(np.exp(named[key]) * self.filtered["sigma2"])
        return out

    def regressor_coefficients(self) -> pd.DataFrame:
        """Coefficients of the regressors (the offset, effects) with sds."""
        delta, cov = self._delta()
        start = self.model.n_dynamic + self.model.n_coefficients
        names = [r.name for r in self.model.all_regressors]
        return pd.DataFrame({"value": delta[start:], "sd": np.sqrt(np.diag(cov)[start:])}, index=names)

    def effect_estimates(self) -> pd.DataFrame:
        """The effects' parameters: value, sd, interval at :attr:`level`, search range, on a bound (SI units)."""
        slots = {slot.name: slot for slot in self.model.dynamics.parameters}
        rows = []
        named = self.model.unpack(self.params)
        for name in self.model.effect_parameters:
            low, high = self.model.bound(name)
            rows.append({"parameter": name, "unit": slots[name].unit, "value": float(named[name]),
                         "sd": self.sd(name), "low": float(self.intervals[name][0]),
                         "high": float(self.intervals[name][1]), "range_low": low, "range_high": high,
                         "on_bound": self.model.at_bound(self.params, name)})
        columns = ["parameter", "unit", "value", "sd", "low", "high", "range_low", "range_high", "on_bound"]
        return pd.DataFrame(rows, columns=columns).set_index("parameter")

    def in_time(self) -> pd.DataFrame:
        """``f_h`` and ``xi_h`` at the fitted span's ends and either side of a step, with intervals, where a time
        term among :attr:`effects` lets them change (:func:`~smd_statespace.person.in_time.person_in_time`; empty
        without one): the fitted ``f_h`` and ``xi_h`` are then the record's middle values."""
        return person_in_time(self)

    def added_unknowns(self, other) -> int:
        """How many more unknowns this fit estimates than ``other``: searched parameters and concentrated ones."""
        return self.model.unknowns(self.params) - other.model.unknowns(other.params)

    def effect_test(self) -> dict:
        """Likelihood ratio of the effects against :attr:`before` (the same person without them).

        ``df`` counts every added unknown: the effects' parameters, variances
        and concentrated linear unknowns (template coefficients of extra
        harmonics, a floor's initial state). With ``df`` 0 (a measured floor:
        nothing is estimated) the two models are not nested and ``p`` is NaN;
        compare the log-likelihoods (equal parameter counts: AIC alike).
        Empty without effects.

        The ratio is taken at :attr:`before`'s cycle starts and variation model
        (:attr:`tested_loglike`): the fit with the effects that re-placed the
        starts (:func:`~smd_statespace.person.extend.fit_effects`, ``timing=True``)
        searched more than :attr:`before` did, and would be favoured for that alone.
        """
        if self.before is None:
            return {}
        tested = self.loglike if self.tested_loglike is None else self.tested_loglike
        lr = 2.0 * (tested - self.before.loglike)
        df = self.added_unknowns(self.before) if self.tested_df is None else self.tested_df
        p = float(stats.chi2.sf(max(lr, 0.0), df)) if df > 0 else float("nan")
        return {"lr": float(lr), "lr_df": int(df), "lr_p": p, "loglike_tested": float(tested),
                "loglike_before": float(self.before.loglike)}

    def predicted_path(self) -> np.ndarray:
        """One-step predicted dynamic states (``u`` in m, ``u'`` in m/s, then any effect's), shape (N, n_x).

        The path a nonlinear effect is linearised about
        (:func:`~smd_statespace.person.statespace.nominal_path`); an effect's
        :meth:`~smd_statespace.model.fitted.Proposes.propose` may read its size. Computed once per result (a
        filter pass of statsmodels, about 0.07 s on a 30 s record; every candidate of a screen starts from it)
        and returned as a copy.
        """
        return self._predicted_path.copy()

    @cached_property
    def _predicted_path(self) -> np.ndarray:
        from .statespace import nominal_path  # statsmodels: imported when a path is asked for

        return nominal_path(self.model, self.params)

    def innovation_line(self) -> float:
        """Frequency (Hz) of the strongest line of the innovations' spectrum away from the bouncing harmonics.

        Where an unexplained resonance (a floor mode) would show; the
        harmonics of the median ``f_b`` (within 0.15 Hz) are left out.
        """
        from scipy import signal

        innov = self.standardized_innovations()
        fs = self.record.fs
        freq, power = signal.welch(innov, fs=fs, nperseg=min(innov.size, int(8 * fs)))
        f_b = float(np.median(self.model.timing.f_b))
        harmonic = np.abs(freq / f_b - np.round(freq / f_b)) * f_b < 0.15
        usable = (freq > 1.0) & (freq < 0.4 * fs) & ~harmonic
        return float(freq[usable][np.argmax(power[usable])])

    def determined(self, name) -> bool:
        """True when the standard error of ``f_h`` or ``xi_h`` is below :data:`DETERMINED_FRACTION` of its yardstick,
        the estimate is not at a search bound, ``xi_h`` is at most 1 (an over-damped fit has no resonance to
        determine), ``f_h`` is not where a resonance mimics the force (:attr:`at_bouncing_frequency`), the
        record's halves agree on it (:attr:`change`) and the model does not misfit the record (:attr:`misfit`)."""
        if self.change and name in self.change["changed"]:  # two people in one record: no one value
            return False
        return self.determined_apart_from_change(name)

    def determined_apart_from_change(self, name) -> bool:
        """:meth:`determined` but for the person changing during the record: where this is True and the person
        changes, the whole record's fit pins the parameter down but no one value describes it, and its interval
        spans the whole record's and the halves' (:func:`~smd_statespace.person.answer.honest_intervals`) rather than
        what was known before the record."""
        if name == "f_h" and self.at_bouncing_frequency:
            return False
        if self.misfit:
            return False
        if self.xi_h > 1.0:  # over-damped: no resonance to determine, outside what bouncing people show
            return False
        return narrowed(self.sd(name), name) and not bool(self.model.at_bound(self.params, name))

    @cached_property
    def misfit_share(self) -> float:
        """RMS of the predictable part of the innovations over the RMS of the measured acceleration.

        The raw one-step innovations are regressed on their own last ``L`` values
        (``L`` = :meth:`default_lags`, one cycle); the R² beyond what such a regression
        reaches on white noise (mean ``L / N``, plus twice its sd ``sqrt(2 L) / N``) is the
        share of the innovations' variance the model could have predicted and did not.
        0 when the model fits, whatever the noise level or the record's length (unlike a
        p-value).
        """
        _, raw = self.model.innovations(self.params, self.filtered)
        lags = self.default_lags()
        if raw.size < 4 * lags:
            return 0.0
        past = np.column_stack([raw[lags - k - 1:raw.size - k - 1] for k in range(lags)])
        target = raw[lags:]
        coef, *_ = np.linalg.lstsq(past, target, rcond=None)
        # R² beyond what an autoregression reaches on white noise: its mean L/N and twice its sd sqrt(2L)/N
        chance = (lags + 2.0 * np.sqrt(2.0 * lags)) / target.size
        explained = 1.0 - np.var(target - past @ coef) / np.var(target) - chance
        return float(np.sqrt(max(explained, 0.0)) * np.std(raw) / np.std(self.model.y))

    @property
    def misfit(self) -> bool:
        """True when :attr:`misfit_share` exceeds :data:`MISFIT_SHARE`: the model misses something, and
        ``f_h``, ``xi_h`` are not determined until it is found (``diagnose``) and added."""
        return self.misfit_share > MISFIT_SHARE

    def artefact(self, name) -> bool:
        """True when the estimate of ``f_h`` or ``xi_h`` is an artefact of the fit, not a value the record
        determines poorly: on a search bound, ``xi_h`` over-damped (> 1), or ``f_h`` where a resonance stands in
        for the force (:attr:`at_bouncing_frequency`; a mimicked harmonic takes ``xi_h`` with it)."""
        if self.model.at_bound(self.params, name) or self.xi_h > 1.0:
            return True
        return self.at_bouncing_frequency if name == "f_h" else bool(self.mimicked_harmonic)

    @property
    def mimicked_harmonic(self) -> int:
        """The force harmonic ``i`` a lightly damped resonance stands in for, 0 when none.

        ``f_h`` within :data:`F_B_COINCIDENCE` of ``i f_b`` (``i`` = 1 ... n) with ``xi_h`` below
        :data:`XI_H_RESONANCE_MIMIC`: an undamped resonance there replaces the force's ``i``-th
        harmonic (its template BLF near 0). On a held-out pulse-train record the fit ended at
        ``f_h`` 4.39 Hz = 1.92 ``f_b``, ``xi_h`` 0.028, template BLF2 0.009 g against 0.16 g
        (truth ``f_h`` 3.58 Hz, ``xi_h`` 0.26).
        """
        return mimicked_harmonic(self.f_h, self.xi_h, float(np.median(self.model.timing.f_b)),
                                 self.model.n_harmonics)

    @property
    def at_bouncing_frequency(self) -> bool:
        """True when the fit put ``f_h`` where the record cannot tell a resonance from the force: within
        :data:`F_B_COINCIDENCE` of the median ``f_b`` with the smooth variation, or at any harmonic
        ``i f_b`` with ``xi_h`` below :data:`XI_H_RESONANCE_MIMIC` (:attr:`mimicked_harmonic`)."""
        return stands_in_for_force(self.f_h, self.xi_h, float(np.median(self.model.timing.f_b)),
                                   self.model.n_harmonics, self.model.variation)

    def record_arguments(self, record=None, mass=None) -> str:
        """The command line's record arguments for this result's record: ``REC --mass KG`` or, for an
        accelerometer's, ``REC --accelerometer`` (with ``--mass`` when it was given). ``record``, ``mass``:
        as the user gave them (default: the record's source and mass)."""
        weighed = mass is None and self.record.extra.get("weighed")  # weighed on the plate: again so, as given
        record = self.record.source if record is None else record
        mass = self.record.mass if mass is None else mass
        if self.record.extra.get("sensor") == "accelerometer":
            return f"{shlex.quote(str(record))} --accelerometer" + (f" --mass {mass:g}" if self.mass_known else "")
        return shlex.quote(str(record)) + ("" if weighed else f" --mass {mass:g}")

    @property
    def mass_known(self) -> bool:
        """False for an accelerometer record identified without a body mass (``K_h``, ``C_h`` left out)."""
        return bool(self.record.extra.get("mass_known", True))

    def derived(self) -> dict:
        """``k_h`` (N/m) and ``c_h`` (N s/m), Eq. 17-18, with delta-method sds; empty without a known mass."""
        from ..model import c_h, k_h

        if not self.mass_known:
            return {}

        mass, f_h, xi_h = self.record.mass, self.f_h, self.xi_h
        person = [self.model.position("f_h"), self.model.position("xi_h")]
        cov = self.cov[np.ix_(person, person)]
        k = float(k_h(f_h, mass))  # Eq. 17
        c = float(c_h(xi_h, f_h, mass))  # Eq. 18
        gk = np.array([2 * k / f_h, 0.0])
        gc = np.array([c / f_h, c / xi_h])
        return {"k_h": k, "k_h_sd": float(np.sqrt(gk @ cov @ gk)), "c_h": c, "c_h_sd": float(np.sqrt(gc @ cov @ gc))}

    @cached_property
    def cycles(self) -> pd.DataFrame:
        """One row per force cycle: times, ``f_b``, smoothed coefficients and load factors with sds."""
        res = self.statespace_results
        model = self.model
        cycle, _, _, _ = model._phase
        p, n, nx = model.n_coefficients, model.n_harmonics, model.n_dynamic
        first = np.flatnonzero(np.r_[True, cycle[1:] != cycle[:-1]])
        last = np.r_[first[1:] - 1, cycle.size - 1]
        mid = (first + last) // 2
        state = res.smoothed_state[nx:nx + p, mid].T + fade_shift(self, mid)  # the cycles' forces, fade included
        state_cov = res.smoothed_state_cov[nx:nx + p, nx:nx + p, mid].transpose(2, 0, 1) * self.filtered["sigma2"]
        b = model.timing.boundaries
        j = cycle[first]
        table = pd.DataFrame({"cycle": j, "t_start": b[j], "t_end": b[j + 1], "f_b": 1.0 / (b[j + 1] - b[j]),
                              "whole": (b[j] >= self.record.time[0]) & (b[j + 1] <= self.record.time[-1])})
        for k, name in enumerate(model.coefficient_names):
            table[name] = state[:, k]
        for i in range(1, n + 1):
            a, bb = state[:, 2 * i - 1], state[:, 2 * i]
            value = np.hypot(a, bb)
            grad = np.stack([a, bb], axis=1) / np.maximum(value, 1e-12)[:, None]
            sub = state_cov[:, 2 * i - 1:2 * i + 1, 2 * i - 1:2 * i + 1]
            table[f"blf_{i}"] = value
            table[f"blf_{i}_sd"] = np.sqrt(np.einsum("ci,cij,cj->c", grad, sub, grad))
        return table

    def parameters(self) -> pd.DataFrame:
        """The answer by parameter, as every estimator's answer gives it
        (:class:`~smd_statespace.answers.RecordAnswer`):
        ``value``, ``sd``, ``low``, ``high`` (the 90 % interval) and ``determined``, for ``f_h`` (Hz), ``xi_h`` and the
        template's ``blf_i`` (g)."""
        flat = self.to_dict()
        names = ["f_h", "xi_h"] + [f"blf_{i}" for i in range(1, self.model.n_harmonics + 1) if f"blf_{i}" in flat]
        rows = {name: {"value": flat[name], "sd": flat[f"{name}_sd"], "low": flat[f"{name}_low"],
                       "high": flat[f"{name}_high"], "determined": bool(flat[f"{name}_determined"])} for name in names}
        return pd.DataFrame.from_dict(rows, orient="index").rename_axis("parameter")

    # ------------------------------------------------------------------ words
    @property
    def warnings(self) -> list:
        """Plain-word warnings: the record's checks, parameters at a bound or not determined, residual tests that
        reject (:func:`~smd_statespace.person.report.person_warnings`)."""
        return person_warnings(self)

    def variation_disagreement(self) -> str:
        """In words, when variation models the record cannot rule out disagree on ``f_h`` (empty otherwise;
        :func:`~smd_statespace.person.judgement.variation_disagreement`)."""
        return variation_disagreement(self)

    def plausible_variations(self) -> list:
        """The variation models' fits the record cannot rule out
        (:func:`~smd_statespace.person.judgement.plausible_variations`)."""
        return plausible_variations(self)

    def to_dict(self) -> dict:
        """Flat JSON-able summary: the content of ``person.json``
        (:func:`~smd_statespace.person.report.result_dict`)."""
        return result_dict(self)

    def table_row(self) -> dict:
        """One flat row for a table of people (a batch's ``results.csv``; what ``stats`` reads;
        :func:`~smd_statespace.person.report.table_row`)."""
        return table_row(self)

    def summary(self, verbose=False) -> str:
        """The person in a few lines: the answer first, then noise, force, tests, warnings
        (:func:`~smd_statespace.person.report.summary_text`; ``verbose`` adds how the intervals were made)."""
        return summary_text(self, verbose)

    # ------------------------------------------------------------------ figures
    def plot_diagnostics(self, path=None, lags=None):
        """The innovations' four panels (over time, histogram, Q-Q, autocorrelation), as a per-cycle check's
        (:func:`~smd_statespace.plotting.person.plot_person_diagnostics`); saved as PNG if ``path``."""
        from ..plotting.person import plot_person_diagnostics  # the result's own figure: matplotlib when drawn

        return plot_person_diagnostics(self, path, lags)

    def plot_fit(self, path=None, seconds=3.0, truth=None):
        """Measured against one-step predicted ``GRF / M_h - g`` where the fit is best and worst, and every cycle's
        BLFs (:func:`~smd_statespace.plotting.person.plot_person_fit`); saved as PNG if ``path``."""
        from ..plotting.person import plot_person_fit  # the result's own figure: matplotlib when drawn

        return plot_person_fit(self, path, seconds, truth)
