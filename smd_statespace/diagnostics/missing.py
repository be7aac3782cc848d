"""Which physical effect is missing? Refit with each candidate effect and rank them.

For a record identified with some model, every effect not yet in the model
(the built-ins and any the user registered with
:func:`~smd_statespace.effects.register_effect`) is added in turn, the record
is identified again with the same estimator, and the candidate is judged by

* the fall of the free-simulation residual RMS (what the user sees);
* a nested-model test of the added parameters. Each cycle's free simulation
  is linearised about its path (:meth:`ModelCheck.remove_absorbable`); the
  residual that no change of a cycle's identified values can remove,
  :attr:`ModelCheck.residual_unabsorbed`, is the least-squares residual of
  that linearised model, with ``n - p`` degrees of freedom (``p``:
  :attr:`ModelCheck.n_absorbable`). With the candidate the model has
  ``k = p_with - p`` more, and
  ``F = ((RSS - RSS_with) / k) / (RSS_with / (n - p_with))`` is
  F(k, n - p_with) distributed when the effect is absent. The Gaussian
  likelihood-ratio statistic of the same fits is
  ``LR = n log(RSS / RSS_with)``;
* Schwarz's criterion on those fits, ``score = LR - k log(n)`` (the fall of
  BIC), which penalises the added parameters and ranks the candidates. (With
  Akaike's lighter ``2 k`` penalty, two extra force harmonics, 4 values per
  cycle, out-scored a measured floor input that explains the same residual
  with none.)

The filters' own log-likelihoods are reported too (``filter_lr``), but not
used: with the article's observation noise (10 % of the RMS of each channel,
several times a force plate's noise) and its integrated ``u``, ``u_dot``
channels they understate a real improvement (a cubic spring that lowered the
residual by 37 % gave a filter likelihood ratio of p = 0.04) and are noisy
between fits.

Values an effect takes from the whole record before identification (the
floor candidate's frequency, read off the residual spectrum) count as fitted
parameters too (:attr:`Effect.record_parameters`). Without a floor
accelerometer the floor candidate is a mode of known frequency whose motion
``z``, ``z_dot`` each cycle estimates: two values per cycle, where two more
force harmonics take four, so of two candidates that explain the same
residual the floor ranks first.

A candidate is reported missing only if its F-test is significant after a
Bonferroni correction over the candidates, its score is positive *and* the
residual RMS falls by at least ``min_improvement``: a false alarm on a clean
record costs a user as much as a miss. When no candidate passes, the answer
is "the model is adequate for this record".

What no refit can show
----------------------
Each cycle has its own Fourier force (Eq. 4) and starting state, 11 or more
values for about 50 samples. Over one cycle those functions span every
smooth signal below about ``n f_b``, periodic or not, so an effect whose
contribution to the COM acceleration lies below ``n f_b`` is absorbed into
the force coefficients rather than left in the residual. The article's
plate (3.48 Hz, bouncing at 1.75 Hz) is the prominent case. When the record
has a measured ``floor_acc``, :func:`diagnose` says so in
:attr:`Diagnosis.notes`: how large the floor coupling
``M_h (w_h^2 z + 2 xi_h w_h z')`` is, how much of it a cycle absorbs, and
how the identified ``f_h`` and ``xi_h`` move when the floor is modelled
(Section 6, Table 4): there the floor shows in the parameters, not in the fit.
"""

from __future__ import annotations

import shlex
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .check import ModelCheck, check_model
from .effect_adapter import diagnosis_notes, fitted_record
from ..effects import EFFECTS, make_effect
from ..errors import OptionError
from ..model import SMDModel
from ..model.fitted import propose


@dataclass
class Candidate:
    """One refit: the effect, its model check and the evidence for it."""

    effect: object
    check: ModelCheck
    extra_parameters: int
    f_statistic: float
    lr_statistic: float
    lr_pvalue: float
    score: float
    filter_lr: float
    rms_fall: float
    significant: bool
    evidence: str

    @property
    def name(self) -> str:
        """Registry name of the candidate effect."""
        return self.effect.name


@dataclass
class Diagnosis:
    """The base model's check and every candidate's refit, ranked best first.

    The same vocabulary as the record-level diagnosis
    (:class:`~smd_statespace.person.diagnose.PersonDiagnosis`): :attr:`missing`
    names the significant candidates, best first; :meth:`table` has one row per
    candidate with ``significant``, ``df``, ``lr``, ``p_value``, ``f_h_before``,
    ``f_h``, ``xi_h_before``, ``xi_h`` (here the medians over the cycles),
    ``ljung_box_p_before``, ``ljung_box_p`` and ``parameters``, then this
    path's own evidence; :meth:`notes`, :meth:`command` and :meth:`report` as
    there. The Ljung-Box p-values here are of the free-simulation residual,
    per cycle and combined (:meth:`ModelCheck.test_serial_correlation
    <smd_statespace.diagnostics.check.ModelCheck.test_serial_correlation>`:
    lags a quarter of a cycle, since each cycle is its own series); the
    record-level ones are of the one-step innovations over the whole record
    with one cycle's lags.
    """

    base: ModelCheck
    candidates: list = field(default_factory=list)
    alpha: float = 0.01
    min_improvement: float = 0.10
    effect_notes: list = field(default_factory=list)

    @property
    def missing(self) -> list:
        """Names of the candidates judged missing, best first."""
        return [c.name for c in self.candidates if c.significant]

    @property
    def best(self):
        """The most likely missing :class:`Candidate` (its refit, evidence), or None when adequate."""
        return next((c for c in self.candidates if c.significant), None)

    @property
    def adequate(self) -> bool:
        """True when no candidate effect is a significant improvement."""
        return not self.missing

    def table(self) -> pd.DataFrame:
        """One row per candidate, best first: the shared columns of both diagnoses, then the per-cycle evidence."""
        rows = []
        base_cycles = _cycle_medians(self.base)
        base_whiteness = self.base.whiteness_pvalue(series="residual")
        for c in self.candidates:
            cycles = _cycle_medians(c.check)
            parameters = _effect_parameters(c.check)
            rows.append({
                "effect": c.name, "spec": c.effect.spec, "significant": c.significant, "df": c.extra_parameters,
                "lr": c.lr_statistic, "p_value": c.lr_pvalue, "f_h_before": base_cycles["f_h"],
                "f_h": cycles["f_h"], "xi_h_before": base_cycles["xi_h"], "xi_h": cycles["xi_h"],
                "ljung_box_p_before": base_whiteness, "ljung_box_p": c.check.whiteness_pvalue(series="residual"),
                "parameters": "; ".join(f"{name} {value:.4g}" for name, value in parameters.items()) or "none",
                "score": c.score, "residual_rms_bw_%": c.check.residual_rms_bw, "rms_fall_%": 100.0 * c.rms_fall,
                "fit_%": c.check.fit_percent, "F": c.f_statistic, "filter_lr": c.filter_lr,
                "serial_ratio": c.check.serial_correlation_ratio(),
            })
        return pd.DataFrame(rows).set_index("effect") if rows else pd.DataFrame()

    def verdict(self) -> str:
        """The verdict in one line, as ``diagnose`` prints it after ``verdict:`` (the record-level diagnosis's
        :meth:`~smd_statespace.person.diagnose.PersonDiagnosis.verdict` in its own evidence)."""
        if self.adequate:
            return "the model is adequate for this record (no candidate effect is a significant improvement)"
        return f"missing effect '{self.best.name}': {self.best.evidence}"

    def notes(self) -> list:
        """Plain-word notes of the effects that were not found (what the residual cannot show)."""
        return list(self.effect_notes)

    def command(self, record: str, mass: float, estimator: str = "ekf", extra: str = "") -> str:
        """The ``diagnose`` command that adds the best candidate to the model and compares the fits with and
        without it, on this per-cycle estimator (runs as printed); empty when adequate."""
        if self.adequate:
            return ""
        specs = [effect.spec for effect in self.base.model.effects] + [self.best.effect.spec]
        effects = " ".join(f"--effect {shlex.quote(spec)}" for spec in specs)
        return (f"smd-statespace {extra}diagnose {shlex.quote(str(record))} --mass {mass:g} --estimator {estimator} "
                f"{effects}")

    def report(self) -> dict:
        """The JSON report of ``smd-statespace diagnose --estimator ekf --json``.

        The keys of the record-level report (``missing``, ``adequate``, ``verdict``,
        ``alpha``, ``candidates``, ``notes``) plus this path's fit of the base
        model and, per missing effect, its evidence and identified values.
        """
        table = self.table()
        return {
            "missing": self.missing,
            "adequate": bool(self.adequate),
            "verdict": self.verdict(),
            "alpha": self.alpha,
            "candidates": table.reset_index().to_dict(orient="records") if not table.empty else [],
            "notes": self.notes(),
            "fit_percent": float(self.base.fit_percent),
            "residual_rms": float(self.base.residual_rms),
            "whiteness_pvalue": float(self.base.whiteness_pvalue(series="residual")),
            "effects_in_model": [effect.name for effect in self.base.model.effects],
            "missing_effects": [
                {"effect": c.name, "spec": c.effect.spec, "score": float(c.score),
                 "fit_percent_with": float(c.check.fit_percent), "residual_rms_with": float(c.check.residual_rms),
                 "evidence": c.evidence, "params": _effect_parameters(c.check)}
                for c in self.candidates if c.significant
            ],
        }


def _cycle_medians(check: ModelCheck) -> dict:
    """Median ``f_h`` and ``xi_h`` over the cycles the check identified."""
    ok = check.table[check.table["status"] == "ok"]
    return {name: float(ok[name].median()) if name in ok and len(ok) else float("nan") for name in ("f_h", "xi_h")}


def _effect_parameters(check: ModelCheck) -> dict:
    """The effects' given constants and the median identified value of every parameter slot they added."""
    ok = check.table[check.table["status"] == "ok"]
    base_names = set(SMDModel(n_harmonics=check.model.n_harmonics).state_names)
    names = [n for n in check.model.parameter_names if n not in base_names]
    out = {name: float(value) for effect in check.model.effects for name, value in effect.constants.items()}
    out.update({name: float(ok[name].median()) for name in names if name in ok})
    return out


def default_candidates(model: SMDModel, base: ModelCheck) -> list:
    """Every registered effect not yet in ``model``, configured for this record by its own class.

    :func:`~smd_statespace.model.fitted.propose` decides, as for the
    record-level diagnosis (``floor_mode``: the measured floor when the record
    has one, else a known mode at the strongest line of the residual that is
    not locked to the bouncing cycle, or nothing; ``cubic_stiffness``: its
    range scaled to the displacement); an effect that returns None is left out.
    """
    present = {effect.name for effect in model.effects}
    fitted = fitted_record(base)
    chosen = (propose(cls, fitted) for name, cls in EFFECTS.items() if name not in present)
    return [effect for effect in chosen if effect is not None]


def _judge(base: ModelCheck, check: ModelCheck, effect, n_candidates: int, alpha: float, min_improvement: float):
    cycles = int((check.table["status"] == "ok").sum())
    n = base.residual.size
    extra = check.n_absorbable - base.n_absorbable + effect.record_parameters
    rss, rss_with = (float(np.sum(c.residual_unabsorbed**2)) for c in (base, check))
    dof = n - check.n_absorbable
    # A measured input (floor_acc) adds a term but no parameter: tested as if it had one coefficient.
    tested = max(extra, 1)
    comparable = check.residual.size == n and extra >= 0 and dof > 0 and rss_with > 0
    if comparable:
        f_statistic = (rss - rss_with) / tested / (rss_with / dof)
        from scipy import stats  # imported here: scipy.signal, scipy.stats take ~1 s (not needed to start)

        pvalue = float(stats.f.sf(f_statistic, tested, dof))
        lr = n * np.log(rss / rss_with)
    else:  # fewer dimensions than the base, or the refit checked other cycles: no nested test
        f_statistic, pvalue, lr = float("nan"), 1.0, 0.0
    score = lr - extra * np.log(n)
    filter_lr = 2.0 * (check.log_likelihood - base.log_likelihood)
    rms_fall = 1.0 - check.residual_rms / base.residual_rms
    significant = bool(pvalue < alpha / max(n_candidates, 1) and score > 0 and rms_fall >= min_improvement)
    evidence = (
        f"residual RMS {base.residual_rms_bw:.2f} -> {check.residual_rms_bw:.2f} % BW ({-100 * rms_fall:+.0f} %); "
        f"F = {f_statistic:.2f} on ({tested}, {dof}) df over {cycles} cycles (p = {pvalue:.2g}); "
        f"score (fall of BIC) {score:+.1f}; residual serial correlation (Ljung-Box per df) "
        f"{base.serial_correlation_ratio():.2f} -> {check.serial_correlation_ratio():.2f}"
    )
    return Candidate(effect, check, extra, f_statistic, lr, pvalue, score, filter_lr, rms_fall, significant, evidence)


def diagnose(preprocessed, model: SMDModel | None = None, estimator: str = "ekf", candidates=None,
             alpha: float = 0.01, min_improvement: float = 0.10, **runner_options) -> Diagnosis:
    """Check ``model`` against the record and rank the candidate effects that could be missing.

    Parameters
    ----------
    preprocessed : Preprocessed
        The record after the pipeline.
    model : SMDModel, optional
        The model to check (default ``SMDModel()``).
    estimator : str
        Estimator used for every fit (default the EKF: fast and close to the reference).
    candidates : list of Effect or str, optional
        Effects to try (default: every registered effect not in the model).
    alpha : float
        Family-wise significance level of the likelihood-ratio tests (Bonferroni over candidates).
    min_improvement : float
        Smallest relative fall of the residual RMS that counts as an improvement.
    **runner_options
        Passed to the cycle runner (``max_passes``, ``seed``, ...).
    """
    model = SMDModel() if model is None else model
    if not 0 < alpha < 1:
        raise OptionError(f"alpha must be in (0, 1), got {alpha!r}")
    base = check_model(preprocessed, model, estimator=estimator, **runner_options)
    effects = default_candidates(model, base) if candidates is None else [make_effect(c) for c in candidates]
    judged = []
    for effect in effects:
        extended = model.with_effects(effect)
        check = check_model(preprocessed, extended, estimator=estimator, **runner_options)
        judged.append(_judge(base, check, effect, len(effects), alpha, min_improvement))
    judged.sort(key=lambda c: (not c.significant, -c.score))
    notes = [note for name, cls in EFFECTS.items() if not any(c.significant and c.name == name for c in judged)
             for note in diagnosis_notes(cls, base, judged)]
    return Diagnosis(base, judged, alpha, min_improvement, notes)
