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

from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import stats

from .diagnostics import ModelCheck, check_model
from .effects import EFFECTS, make_effect
from .errors import OptionError
from .model import TWO_PI, SMDModel


FLOOR_DAMPING = 0.01
"""Damping ratio of the modal floor candidate seeded from the residual spectrum (floors: about 0.3-3 %)."""


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
    """The base model's check and every candidate's refit, ranked best first."""

    base: ModelCheck
    candidates: list = field(default_factory=list)
    alpha: float = 0.01
    min_improvement: float = 0.10
    notes: list = field(default_factory=list)

    @property
    def missing(self) -> list:
        """Candidates judged missing, best first."""
        return [c for c in self.candidates if c.significant]

    @property
    def adequate(self) -> bool:
        """True when no candidate effect is a significant improvement."""
        return not self.missing

    def table(self) -> pd.DataFrame:
        """One row per candidate: residual RMS, fit, nested-model test, score, verdict."""
        rows = []
        for c in self.candidates:
            rows.append({
                "effect": c.name, "missing": c.significant, "score": c.score,
                "residual_rms_bw_%": c.check.residual_rms_bw, "rms_fall_%": 100.0 * c.rms_fall,
                "fit_%": c.check.fit_percent, "F": c.f_statistic, "lr_stat": c.lr_statistic,
                "df": c.extra_parameters, "lr_pvalue": c.lr_pvalue, "filter_lr": c.filter_lr,
                "serial_ratio": c.check.serial_correlation_ratio(),
            })
        return pd.DataFrame(rows).set_index("effect") if rows else pd.DataFrame()

    def report(self) -> dict:
        """The JSON report of ``smd-statespace diagnose --json``."""
        return {
            "fit_percent": float(self.base.fit_percent),
            "residual_rms": float(self.base.residual_rms),
            "whiteness_pvalue": float(self.base.whiteness_pvalue(series="residual")),
            "effects_in_model": [effect.name for effect in self.base.model.effects],
            "adequate": bool(self.adequate),
            "missing_effects": [
                {"effect": c.name, "spec": c.effect.spec, "score": float(c.score),
                 "fit_percent_with": float(c.check.fit_percent), "residual_rms_with": float(c.check.residual_rms),
                 "evidence": c.evidence, "params": _effect_parameters(c.check)}
                for c in self.missing
            ],
            "notes": list(self.notes),
        }


def _effect_parameters(check: ModelCheck) -> dict:
    """The effects' given constants and the median identified value of every parameter slot they added."""
    ok = check.table[check.table["status"] == "ok"]
    base_names = set(SMDModel(n_harmonics=check.model.n_harmonics).state_names)
    names = [n for n in check.model.parameter_names if n not in base_names]
    out = {name: float(value) for effect in check.model.effects for name, value in effect.constants.items()}
    out.update({name: float(ok[name].median()) for name in names if name in ok})
    return out


def default_candidates(model: SMDModel, base: ModelCheck) -> list:
    """Every registered effect not yet in ``model``, configured for this record.

    ``floor_mode`` uses the measured floor acceleration when the record has
    one; otherwise it is a known mode at the strongest line of the residual
    that is not locked to the bouncing cycle (see :func:`_floor_candidate`;
    if there is none, it is left out).
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
    """The floor effect to try: the measured floor, or a known mode at the residual's strongest unlocked line.

    A floor excited by anything but this person moves at its own frequency
    with no fixed phase to the bouncing cycle. The residual's phase-locked
    part (:meth:`ModelCheck.phase_locked`: missing harmonics, a
    nonlinearity) is removed first, so that such a line is found even next
    to a multiple of ``f_b``; a peak is taken only where at least half of
    the residual's power is unlocked. Weak lines at ``(k + 1/2) f_b`` come
    from cycle-to-cycle variation of the force: one is taken only when it is
    stronger than every harmonic line of the residual.
    """
    if base.preprocessed.floor_acc is not None:
        return make_effect("floor_mode:source=measured")
    freq, psd, whole = base.residual_spectrum()
    unlocked = base.residual - base.phase_locked()
    _, psd_unlocked, peaks = base.residual_spectrum(values=unlocked)
    bins = np.clip(np.searchsorted(freq, peaks["frequency"]), 0, freq.size - 1)
    mostly_unlocked = psd_unlocked[bins] >= 0.5 * psd[bins]
    half = (peaks["f_over_fb"] % 1.0 - 0.5).abs() < 0.1
    harmonic_power = whole.loc[whole["label"] != "non-harmonic", "power"].max()
    dominant = peaks["power"] > (0.0 if pd.isna(harmonic_power) else harmonic_power)
    other = peaks[mostly_unlocked & (~half | dominant)]
    if other.empty:
        return None
    frequency = float(other["frequency"].iloc[0])  # peaks are sorted strongest first
    # A floor mode is one frequency for the whole record: a known mode at the line, not a per-cycle estimate.
    effect = make_effect(f"floor_mode:source=modal,frequency={frequency:.3f},damping={FLOOR_DAMPING}")
    effect.record_parameters = 1
    return effect


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


def _floor_notes(base: ModelCheck, judged) -> list:
    """What the residual cannot say about a measured floor motion (see the module docstring)."""
    pre = base.preprocessed
    if pre.floor_acc is None or any(effect.name == "floor_mode" for effect in base.model.effects):
        return []
    table = base.table.set_index("cycle").loc[base.cycle_index]
    omega, xi = TWO_PI * table["f_h"].to_numpy(), table["xi_h"].to_numpy()
    rows = base.sample_index
    coupling = pre.mass * (omega**2 * pre.floor_disp[rows] + 2.0 * xi * omega * pre.floor_vel[rows])
    size = float(np.sqrt(np.mean(coupling**2)))
    if size == 0.0:
        return []
    left = float(np.sqrt(np.mean(base.remove_absorbable(coupling) ** 2)))
    absorbed = 1.0 - left / size
    note = (f"floor_mode: the measured floor moves; its coupling M_h (w_h^2 z + 2 xi_h w_h z') is "
            f"{100 * size / base.weight:.2f} % BW RMS, {100 * absorbed:.0f} % of it absorbed by the per-cycle force")
    if absorbed >= 0.9:
        note += f" (it lies below n f_b = {base.model.n_harmonics * base.f_b:.1f} Hz), so the residual cannot test it"
    with_floor = next((c.check for c in judged if c.name == "floor_mode"), None)
    if with_floor is not None:
        medians = [(check.table.loc[check.table["status"] == "ok", ["f_h", "xi_h"]].median()) for check in
                   (base, with_floor)]
        note += (f"; modelling the floor moves the median f_h {medians[0]['f_h']:.2f} -> {medians[1]['f_h']:.2f} Hz "
                 f"and xi_h {medians[0]['xi_h']:.2f} -> {medians[1]['xi_h']:.2f} (Section 6, Table 4)")
    return [note]


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
    notes = [] if any(c.significant and c.name == "floor_mode" for c in judged) else _floor_notes(base, judged)
    return Diagnosis(base, judged, alpha, min_improvement, notes)
