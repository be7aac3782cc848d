"""Is a physical effect missing? Candidates added to the record-level model, compared by likelihood ratio.

Each candidate effect enters the record-level model
(:mod:`smd_statespace.person.model`) with its *record-level* parameters only
(the per-cycle method re-fitted an effect in every cycle, so a penalised score
threw it away), the other parameters are re-fitted from the base fit, and the
likelihood-ratio statistic is referred to chi-square with the effect's true
number of parameters (Bonferroni over the candidates).

Every registered effect (:mod:`smd_statespace.effects`, a user's too) says
how it enters the record-level model, :meth:`Effect.record_candidate
<smd_statespace.model.Effect.record_candidate>`:

any effect, by default
    Its own score terms (:meth:`~smd_statespace.model.Effect.score_terms`:
    the derivative of its acceleration term in each parameter, at 0) on the
    base fit's smoothed path, one regressor with one coefficient each
    (:func:`score_term_candidate`). A cubic spring becomes
    ``-w_h^2 beta_3 u^3`` with ``u`` the smoothed displacement (1 parameter).
``harmonics``
    Two more harmonics of the force (orders ``n+1, n+2``): their template
    coefficients and one cycle-to-cycle spread each (6 parameters).
``floor_mode`` with an accelerometer
    The leg acts on the motion relative to a floor whose acceleration is
    measured (the record's ``floor_acc``): ``-kappa z''`` moves the relative
    state but is not part of ``GRF / M_h``; ``kappa`` should be 1 (1 parameter).
``floor_mode`` without one (only when asked for)
    Its acceleration is predicted from the measured GRF, ``z'' = -mu H_f(s)
    u''`` (``H_f = s^2 / (s^2 + 2 xi_f w_f s + w_f^2)``), with ``f_f`` at the
    strongest unexplained line of the innovations' spectrum
    (:func:`innovation_line`) and ``xi_f`` the better of two trial values;
    ``mu`` is the person-to-modal mass ratio (3 parameters). Not tried by
    default: on a clean simulated record (f_b 2 Hz, f_h 2.5 Hz, seed 21) it
    was a false alarm (LR 65 for 3 parameters), its predicted floor acting as
    a free filter that absorbs the base model's own misfit.

A cubic spring makes harmonics of the bouncing frequency, so "harmonics" and
"cubic_stiffness" can explain the same residual; the report says so when both
are significant and what separates them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import signal, stats

from ..effects import EFFECTS, make_effect
from ..model import F_H, U, U_DOT, XI_H, CycleInputs, SMDModel
from .fit import fit_model
from .model import RecordModel, Regressor

__all__ = ["RecordCandidate", "PersonDiagnosis", "diagnose_person", "score_term_candidate", "innovation_line",
           "with_regressor", "with_harmonics"]


@dataclass
class RecordCandidate:
    """One effect as the record-level model takes it: what :func:`diagnose_person` fits.

    Attributes
    ----------
    n_params : int
        The effect's parameters (degrees of freedom of the likelihood-ratio test).
    models : list of RecordModel
        The base model extended by the effect; with several (trial values
        of a setting), the one with the highest likelihood is kept.
    parameter : str or None
        The regressor whose coefficient the table reports (None: the extra
        harmonics' amplitude).
    settings : dict
        Values read off the record to build the models (e.g. ``f_f``), by model.
    """

    n_params: int
    models: list
    parameter: str | None = None
    settings: list = field(default_factory=list)


@dataclass
class PersonDiagnosis:
    """The candidates' table and the verdict of :func:`diagnose_person`.

    Attributes
    ----------
    base : PersonResult
        The fit without any effect.
    rows : list of dict
        One per candidate: ``effect, n_params, loglike, lr, p_value,
        significant, on_bound, delta_aic, noise_change_%, f_h, xi_h`` (after) and the
        effect's parameter estimate with its sd.
    alpha : float
        Family-wise significance level (Bonferroni over the candidates).
    """

    base: object
    rows: list
    alpha: float

    def table(self) -> pd.DataFrame:
        """The candidates, most significant first."""
        if not self.rows:
            return pd.DataFrame()
        return pd.DataFrame(self.rows).sort_values("lr_per_df", ascending=False).set_index("effect")

    @property
    def missing(self) -> list:
        """Names of the significant candidates, best first."""
        table = self.table()
        return [] if table.empty else list(table.index[table["significant"]])

    @property
    def adequate(self) -> bool:
        """True when no candidate is a significant improvement."""
        return not self.missing

    def notes(self) -> list:
        """Plain-word notes: candidates that explain the same residual, what separates them, degenerate refits."""
        out = []
        table = self.table()
        if not table.empty and "on_bound" in table:
            for name in table.index[table["on_bound"].astype(bool)]:
                out.append(f"{name}: its refit put f_h or xi_h on a search bound (f_h {table.loc[name, 'f_h']:.3g} "
                           f"Hz, xi_h {table.loc[name, 'xi_h']:.3g}); the term and the person's resonance together "
                           "imitate the residual, so it is not proposed")
        if {"harmonics", "cubic_stiffness"} <= set(self.missing):
            out.append("harmonics and cubic_stiffness both explain the residual: a cubic spring makes harmonics "
                       "of the bouncing frequency. Only the spring's harmonics grow with the displacement "
                       "amplitude (as its cube); the one with more likelihood per parameter is ranked first")
        return out

    def report(self) -> dict:
        """JSON-able report: base person, candidates, verdict, notes."""
        table = self.table()
        return {"base": self.base.to_dict(), "candidates": table.reset_index().to_dict(orient="records"),
                "missing": self.missing, "adequate": self.adequate, "alpha": self.alpha, "notes": self.notes()}


def _start(model: RecordModel, base_model: RecordModel, base_params, default=-6.0):
    """Starting parameters of ``model``: the base fit's values by name, ``default`` for new ones."""
    named = dict(zip(base_model.param_names, base_params))
    return np.array([named.get(name, default) for name in model.param_names])


def innovation_line(result):
    """Frequency (Hz) of the strongest line of the innovations' spectrum away from the bouncing harmonics."""
    innov = result.standardized_innovations()
    fs = result.record.fs
    freq, power = signal.welch(innov, fs=fs, nperseg=min(innov.size, int(8 * fs)))
    f_b = float(np.median(result.model.timing.f_b))
    harmonic = np.abs(freq / f_b - np.round(freq / f_b)) * f_b < 0.15
    usable = (freq > 1.0) & (freq < 0.4 * fs) & ~harmonic
    return float(freq[usable][np.argmax(power[usable])])


def _options(base):
    return dict(variation=base.variation, process_noise=base.process_noise, drift=base.drift)


def with_regressor(result, *terms: Regressor) -> RecordModel:
    """The base fit's model with more regressors (effects' known signals with unknown coefficients)."""
    base = result.model
    return RecordModel(base.time, base.y, base.timing, base.n_harmonics, regressors=base.regressors + tuple(terms),
                       phase_template=base.phase_template, **_options(base))


def with_harmonics(result, count: int) -> RecordModel:
    """The base fit's model with ``count`` more force harmonics (template coefficients and spreads)."""
    base = result.model
    template = None if base.phase_template is None else np.r_[base.phase_template, np.zeros(2 * count)]
    return RecordModel(base.time, base.y, base.timing, base.n_harmonics + count, regressors=base.regressors,
                       phase_template=template, **_options(base))


def score_term_candidate(result, effect) -> RecordCandidate | None:
    """The default record-level form of ``effect``: its score terms on the base fit's smoothed path.

    Builds the state of ``SMDModel(effects=[effect])`` along the record from
    the smoothed ``u``, ``u'`` and the fitted ``f_h``, ``xi_h`` (the
    effect's parameters at 0), asks the effect for
    :meth:`~smd_statespace.model.Effect.score_terms` and adds each as a
    :class:`~smd_statespace.person.model.Regressor` (linearised in the
    parameters about the base fit). None when the effect needs measured
    signals or adds no term on this path.
    """
    if effect.requires:
        return None
    base = result.model
    model = SMDModel(n_harmonics=base.n_harmonics, effects=[effect])
    smoothed = result.statespace_results.smoothed_state
    x = np.zeros((base.time.size, model.n_state))
    x[:, U], x[:, U_DOT] = smoothed[0], smoothed[1]
    x[:, F_H], x[:, XI_H] = result.f_h, result.xi_h
    inputs = CycleInputs(f_b=float(np.median(base.timing.f_b)), time=base.time)
    terms = effect.score_terms(model, x, base.time, inputs)
    if not terms:
        return None
    units = {slot.name: slot.unit for slot in model.slots}
    regressors = [Regressor(key.split(":")[-1], values, units.get(key.split(":")[-1], "-"))
                  for key, values in terms.items()]
    return RecordCandidate(len(regressors), [with_regressor(result, *regressors)], regressors[0].name)


def diagnose_person(result, candidates=None, alpha=0.01) -> PersonDiagnosis:
    """Add each candidate effect to a record-level fit and test it by likelihood ratio.

    Parameters
    ----------
    result : PersonResult
        The base fit (:func:`~smd_statespace.person.fit.identify_person`).
    candidates : sequence of str or Effect, optional
        Effects to try (names, ``NAME:key=value`` specs or objects). Default:
        every registered effect not in the base fit as its class configures
        itself for this record (:meth:`Effect.record_default
        <smd_statespace.model.Effect.record_default>`: ``floor_mode`` only with
        a floor accelerometer).
    alpha : float
        Family-wise significance level; each candidate is tested at
        ``alpha / len(candidates)``.

    Returns
    -------
    PersonDiagnosis
    """
    if candidates is None:
        effects = [cls.record_default(result) for cls in EFFECTS.values()]
    else:
        effects = [make_effect(candidate) for candidate in candidates]
    built = [(effect, effect.record_candidate(result)) for effect in effects if effect is not None]
    built = [(effect, candidate) for effect, candidate in built if candidate is not None]
    level = alpha / max(len(built), 1)
    rows = []
    for effect, candidate in built:
        fits = [(model, fit_model(model, _start(model, result.model, result.params))) for model in candidate.models]
        best = max(range(len(fits)), key=lambda i: fits[i][1]["loglike"])
        model, fitted = fits[best]
        n_params = candidate.n_params
        lr = max(2.0 * (fitted["loglike"] - result.loglike), 0.0)
        out = model.filter(fitted["params"])
        row = {"effect": effect.name, "n_params": n_params, "loglike": fitted["loglike"], "lr": lr,
               "lr_per_df": lr / n_params, "p_value": float(stats.chi2.sf(lr, n_params)),
               "delta_aic": 2 * n_params - lr,
               "noise_change_%": 100.0 * (np.sqrt(out["sigma2"]) / result.sigma - 1.0),
               "f_h_before": result.f_h, "f_h": float(fitted["params"][0]),
               "xi_h_before": result.xi_h, "xi_h": float(fitted["params"][1]), "spec": effect.spec}
        # a refit that runs f_h or xi_h to a search bound has not found an effect: the effect's term
        # and the person's resonance together imitate the residual (measured: a cubic spring "explained"
        # hidden harmonics with f_h 6 Hz, xi_h 3)
        row["on_bound"] = model.person_at_bound(fitted["params"])
        row["significant"] = bool(row["p_value"] < level) and not row["on_bound"]
        start = model.n_dynamic + model.n_coefficients
        names = [r.name for r in model.regressors]
        if candidate.parameter in names:
            k = start + names.index(candidate.parameter)
            row["estimate"] = float(out["delta"][k])
            row["estimate_sd"] = float(np.sqrt(out["delta_cov_unscaled"][k, k] * out["sigma2"]))
        else:  # the extra harmonics' template amplitudes (g)
            tau = out["delta"][model.n_dynamic:model.n_dynamic + model.n_coefficients]
            n = result.model.n_harmonics + 1
            row["estimate"] = float(np.hypot(tau[2 * n - 1], tau[2 * n]))
            row["estimate_sd"] = float("nan")
        if candidate.settings:
            row.update(candidate.settings[best])
        rows.append(row)
    return PersonDiagnosis(base=result, rows=rows, alpha=alpha)
