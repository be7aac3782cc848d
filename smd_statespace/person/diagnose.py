"""Is a physical effect missing? Candidates added to the record-level model, compared by likelihood ratio.

Each candidate effect enters the record-level model
(:mod:`smd_statespace.person.model`) with its *record-level* parameters only
(the per-cycle method re-fitted an effect in every cycle, so a penalised score
threw it away), the other parameters are re-fitted from the base fit, and the
likelihood-ratio statistic is referred to chi-square with the effect's true
number of parameters (Bonferroni over the candidates):

``harmonics``
    Two more harmonics of the force (orders ``n+1, n+2``): their template
    coefficients and one cycle-to-cycle spread each (6 parameters).
``cubic_stiffness``
    A hardening or softening leg, ``-w_h^2 beta u^3`` in ``u''`` with ``u``
    the displacement smoothed by the base fit (``beta`` in 1/m^2; 1 parameter).
``floor_measured``
    The leg acts on the motion relative to a floor whose acceleration is
    measured (the record's ``floor_acc``): ``-kappa z''`` moves the relative
    state but is not part of ``GRF / M_h``; ``kappa`` should be 1 (1 parameter).
``floor_mode``
    A floor mode without an accelerometer: its acceleration is predicted from
    the measured GRF, ``z'' = -mu H_f(s) u''`` (``H_f = s^2 / (s^2 + 2 xi_f w_f
    s + w_f^2)``), with ``f_f`` at the strongest unexplained line of the
    innovations' spectrum and ``xi_f`` the better of two trial values; ``mu``
    is the person-to-modal mass ratio (3 parameters).

A cubic spring makes harmonics of the bouncing frequency, so "harmonics" and
"cubic_stiffness" can explain the same residual; the report says so when both
are significant and what separates them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import signal, stats

from .fit import fit_model
from .model import RecordModel, Regressor

__all__ = ["CANDIDATES", "ALL_CANDIDATES", "PersonDiagnosis", "diagnose_person"]

CANDIDATES = ("harmonics", "cubic_stiffness", "floor_measured")
"""Candidate effects tried by default. ``floor_mode`` is tried only when asked for: on a clean
simulated record (f_b 2 Hz, f_h 2.5 Hz, seed 21) it was a false alarm (LR 65 for 3 parameters),
its predicted floor acting as a free filter that absorbs the base model's own misfit."""

ALL_CANDIDATES = CANDIDATES + ("floor_mode",)
"""Every candidate :func:`diagnose_person` knows."""

FLOOR_DAMPING_TRIALS = (0.005, 0.02)
"""Floor damping ratios tried for the floor mode without an accelerometer."""


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


def _innovation_line(result):
    """Frequency (Hz) of the strongest line of the innovations' spectrum away from the bouncing harmonics."""
    innov = result.standardized_innovations()
    fs = result.record.fs
    freq, power = signal.welch(innov, fs=fs, nperseg=min(innov.size, int(8 * fs)))
    f_b = float(np.median(result.model.timing.f_b))
    harmonic = np.abs(freq / f_b - np.round(freq / f_b)) * f_b < 0.15
    usable = (freq > 1.0) & (freq < 0.4 * fs) & ~harmonic
    return float(freq[usable][np.argmax(power[usable])])


def _floor_prediction(time, y, f_f, xi_f):
    """Floor acceleration (m/s^2) per unit mass ratio predicted from the measured ``u''``: ``-H_f(s) u''``."""
    w = 2.0 * np.pi * f_f
    _, out, _ = signal.lsim(([1.0, 0.0, 0.0], [1.0, 2.0 * xi_f * w, w * w]), y, time)
    return -out


def _candidate_models(result, candidates):
    """``(name, n_params, [models])``: each candidate's model(s) built on the base fit."""
    base = result.model
    options = dict(variation=base.variation, process_noise=base.process_noise, drift=base.drift)
    f_h = result.f_h
    out = []
    for name in candidates:
        if name == "harmonics":
            template = None if base.phase_template is None else np.r_[base.phase_template, np.zeros(4)]
            model = RecordModel(base.time, base.y, base.timing, base.n_harmonics + 2, regressors=base.regressors,
                                phase_template=template, **options)
            out.append((name, 6, [model], "blf_extra"))
        elif name == "cubic_stiffness":
            u = result.statespace_results.smoothed_state[0]
            term = Regressor("beta", -(2.0 * np.pi * f_h) ** 2 * u**3, "1/m^2")
            out.append((name, 1, [_with(base, term, options)], "beta"))
        elif name == "floor_measured":
            floor = getattr(result.record, "floor_acc", None)
            if floor is None:
                continue
            term = Regressor("kappa", -np.asarray(floor, dtype=float), "-", observed=False)
            out.append((name, 1, [_with(base, term, options)], "kappa"))
        elif name == "floor_mode":
            f_f = _innovation_line(result)
            models = [_with(base, Regressor("mu", _floor_prediction(base.time, base.y, f_f, xi_f), "-",
                                            observed=False), options) for xi_f in FLOOR_DAMPING_TRIALS]
            for model, xi_f in zip(models, FLOOR_DAMPING_TRIALS):
                model.floor_settings = {"f_f": f_f, "xi_f": xi_f}
            out.append((name, 3, models, "mu"))
    return out


def _with(base, term, options):
    """The base model with one more regressor."""
    return RecordModel(base.time, base.y, base.timing, base.n_harmonics, regressors=base.regressors + (term,),
                       phase_template=base.phase_template, **options)


def diagnose_person(result, candidates=CANDIDATES, alpha=0.01) -> PersonDiagnosis:
    """Add each candidate effect to a record-level fit and test it by likelihood ratio.

    Parameters
    ----------
    result : PersonResult
        The base fit (:func:`~smd_statespace.person.fit.identify_person`).
    candidates : sequence of str
        Names from :data:`CANDIDATES`; ``floor_measured`` is skipped when the
        record has no floor acceleration.
    alpha : float
        Family-wise significance level; each candidate is tested at
        ``alpha / len(candidates)``.

    Returns
    -------
    PersonDiagnosis
    """
    built = _candidate_models(result, candidates)
    level = alpha / max(len(built), 1)
    rows = []
    for name, n_params, models, parameter in built:
        fits = [(model, fit_model(model, _start(model, result.model, result.params))) for model in models]
        model, fitted = max(fits, key=lambda pair: pair[1]["loglike"])
        lr = max(2.0 * (fitted["loglike"] - result.loglike), 0.0)
        out = model.filter(fitted["params"])
        row = {"effect": name, "n_params": n_params, "loglike": fitted["loglike"], "lr": lr,
               "lr_per_df": lr / n_params, "p_value": float(stats.chi2.sf(lr, n_params)),
               "delta_aic": 2 * n_params - lr,
               "noise_change_%": 100.0 * (np.sqrt(out["sigma2"]) / result.sigma - 1.0),
               "f_h_before": result.f_h, "f_h": float(fitted["params"][0]),
               "xi_h_before": result.xi_h, "xi_h": float(fitted["params"][1])}
        # a refit that runs f_h or xi_h to a search bound has not found an effect: the effect's term
        # and the person's resonance together imitate the residual (measured: a cubic spring "explained"
        # hidden harmonics with f_h 6 Hz, xi_h 3)
        row["on_bound"] = model.person_at_bound(fitted["params"])
        row["significant"] = bool(row["p_value"] < level) and not row["on_bound"]
        start = 2 + model.n_coefficients
        names = [r.name for r in model.regressors]
        if parameter in names:
            k = start + names.index(parameter)
            row["estimate"] = float(out["delta"][k])
            row["estimate_sd"] = float(np.sqrt(out["delta_cov_unscaled"][k, k] * out["sigma2"]))
        else:  # the extra harmonics' template amplitudes (g)
            tau = out["delta"][2:2 + model.n_coefficients]
            n = model.n_harmonics
            row["estimate"] = float(np.hypot(tau[2 * n - 3], tau[2 * n - 2]))
            row["estimate_sd"] = float("nan")
        settings = getattr(model, "floor_settings", None)
        if settings:
            row.update(settings)
        rows.append(row)
    return PersonDiagnosis(base=result, rows=rows, alpha=alpha)
