"""Which physical effect is missing? Refit with each candidate effect and rank them.

For a record identified with some model, every effect not yet in the model
(the built-ins and any the user registered with
:func:`~smd_statespace.effects.register_effect`) is added in turn, the record
is identified again with the same estimator, and the candidate is judged by

* the fall of the free-simulation residual RMS (what the user sees),
* the change of the filters' total log-likelihood, turned into a
  likelihood-ratio statistic ``2 (l_with - l_without)`` on
  ``k x cycles`` degrees of freedom (``k`` new parameter slots per cycle), and
  Schwarz's criterion ``Delta BIC = 2 Delta l - k_total log(n)``, which
  penalises the added parameters.

A candidate is reported missing only if its likelihood-ratio test is
significant after a Bonferroni correction over the candidates, its BIC
improves, *and* the residual RMS falls by at least ``min_improvement``: a
false alarm on a clean record costs a user as much as a miss. When no
candidate passes, the answer is "the model is adequate for this record".
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import stats

from .diagnostics import ModelCheck, check_model
from .effects import EFFECTS, make_effect
from .errors import OptionError
from .model import SMDModel


@dataclass
class Candidate:
    """One refit: the effect, its model check and the evidence for it."""

    effect: object
    check: ModelCheck
    extra_parameters: int
    lr_statistic: float
    lr_pvalue: float
    delta_bic: float
    rms_fall: float
    significant: bool
    evidence: str

    @property
    def name(self) -> str:
        return self.effect.name


@dataclass
class Diagnosis:
    """The base model's check and every candidate's refit, ranked best first."""

    base: ModelCheck
    candidates: list = field(default_factory=list)
    alpha: float = 0.01
    min_improvement: float = 0.10

    @property
    def missing(self) -> list:
        """Candidates judged missing, best first."""
        return [c for c in self.candidates if c.significant]

    @property
    def adequate(self) -> bool:
        """True when no candidate effect is a significant improvement."""
        return not self.missing

    def table(self) -> pd.DataFrame:
        """One row per candidate: residual RMS, fit, likelihood-ratio test, BIC, verdict."""
        rows = []
        for c in self.candidates:
            rows.append({
                "effect": c.name, "missing": c.significant, "score": c.delta_bic,
                "residual_rms_bw_%": c.check.residual_rms_bw, "rms_fall_%": 100.0 * c.rms_fall,
                "fit_%": c.check.fit_percent, "lr_stat": c.lr_statistic, "df": c.extra_parameters,
                "lr_pvalue": c.lr_pvalue, "whiteness_p": c.check.whiteness_pvalue(),
            })
        return pd.DataFrame(rows).set_index("effect") if rows else pd.DataFrame()

    def report(self) -> dict:
        """The JSON report of ``smd-statespace diagnose --json``."""
        return {
            "fit_percent": float(self.base.fit_percent),
            "residual_rms": float(self.base.residual_rms),
            "whiteness_pvalue": float(self.base.whiteness_pvalue()),
            "effects_in_model": [effect.name for effect in self.base.model.effects],
            "adequate": bool(self.adequate),
            "missing_effects": [
                {"effect": c.name, "score": float(c.delta_bic), "fit_percent_with": float(c.check.fit_percent),
                 "residual_rms_with": float(c.check.residual_rms), "evidence": c.evidence,
                 "params": _effect_parameters(c.check)}
                for c in self.missing
            ],
        }


def _effect_parameters(check: ModelCheck) -> dict:
    """Median identified value of every slot the effects added (over the identified cycles)."""
    ok = check.table[check.table["status"] == "ok"]
    base_names = set(SMDModel(n_harmonics=check.model.n_harmonics).state_names)
    names = [n for n in check.model.parameter_names if n not in base_names]
    return {name: float(ok[name].median()) for name in names if name in ok}


def default_candidates(model: SMDModel, base: ModelCheck) -> list:
    """Every registered effect not yet in ``model``, configured for this record.

    ``floor_mode`` uses the measured floor acceleration when the record has
    one; otherwise it is a modal oscillator seeded at the strongest
    non-harmonic peak of the residual spectrum (if there is none, it is left out).
    """
    present = {effect.name for effect in model.effects}
    candidates = []
    for name in EFFECTS:
        if name in present:
            continue
        if name == "floor_mode":
            effect = _floor_candidate(base)
            if effect is not None:
                candidates.append(effect)
            continue
        candidates.append(make_effect(name))
    return candidates


def _floor_candidate(base: ModelCheck):
    if base.preprocessed.floor_acc is not None:
        return make_effect("floor_mode:source=measured")
    _, _, peaks = base.residual_spectrum()
    # Lines at (k + 1/2) f_b come from cycle-to-cycle variation of the force, not from a floor.
    half = (peaks["f_over_fb"] % 1.0 - 0.5).abs() < 0.1
    other = peaks[(peaks["label"] == "non-harmonic") & ~half]
    if other.empty:
        return None
    frequency = float(other.sort_values("power", ascending=False)["frequency"].iloc[0])
    return make_effect(f"floor_mode:source=modal,frequency={frequency:.3f}")


def _judge(base: ModelCheck, check: ModelCheck, effect, n_candidates: int, alpha: float, min_improvement: float):
    cycles = int((check.table["status"] == "ok").sum())
    extra = max(check.n_parameters - base.n_parameters, 0)
    lr = 2.0 * (check.log_likelihood - base.log_likelihood)
    pvalue = float(stats.chi2.sf(lr, extra)) if extra > 0 else (0.0 if lr > 0 else 1.0)
    n_obs = max(len(check.time), 2)
    delta_bic = lr - extra * np.log(n_obs)
    rms_fall = 1.0 - check.residual_rms / base.residual_rms
    significant = bool(pvalue < alpha / max(n_candidates, 1) and delta_bic > 0 and rms_fall >= min_improvement)
    evidence = (
        f"residual RMS {base.residual_rms_bw:.2f} -> {check.residual_rms_bw:.2f} % BW ({-100 * rms_fall:+.0f} %); "
        f"likelihood ratio {lr:.1f} on {extra} df over {cycles} cycles (p = {pvalue:.2g}); "
        f"delta BIC {delta_bic:+.1f}; whiteness p {base.whiteness_pvalue():.2g} -> {check.whiteness_pvalue():.2g}"
    )
    return Candidate(effect, check, extra, lr, pvalue, delta_bic, rms_fall, significant, evidence)


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
    judged.sort(key=lambda c: (not c.significant, -c.delta_bic))
    return Diagnosis(base, judged, alpha, min_improvement)
