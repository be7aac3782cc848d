"""Held-out validation of the record-level model: fitted on one half of the record, scored on the other.

A term added to the person's model can raise the likelihood of the record it was fitted on without
describing the person: a free parameter follows what is peculiar to this record (a stretch of
noise, a misplaced cycle start) and a likelihood-ratio test that trusts the model counts it as
evidence. The held-out check asks the question a user means: does the model fitted on one half
predict the other half better? :func:`cross_validated_loglike` cuts the record at the cycle
boundary nearest its middle (:func:`halves`), fits the model on each half (starting from the whole
record's estimate) and scores the *other* half with the one-step prediction density at the fitted
half's parameters, force template and noise scale (two folds, summed). Only what is the other half's
own is estimated there: the initial state (the person's motion when the half begins) and the
measurement's offset and zero drift (the plate's). An effect that helps only where it was fitted
lowers the held-out log-likelihood.

The halves are the ones :func:`~smd_statespace.person.change.change_test` compares
(:func:`part`: the same options, the cycle timing and regressors cut with the samples; a nonlinear
effect keeps the whole fit's linearisation path, cut likewise).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .dynamics import PersonDynamics
from .search import fit_model
from .timing import CycleTiming

__all__ = ["MIN_HALF_CYCLES", "halves", "part", "held_out_loglike", "cross_validated_loglike"]

MIN_HALF_CYCLES = 8
"""Fewest whole force cycles in each half (the record-level model needs as many to estimate the variation)."""


def halves(model) -> list | None:
    """``[(keep, kept), (keep, kept)]``: the samples and cycle boundaries of the record's two halves.

    The cut is the cycle boundary nearest the middle of the boundaries inside the record; None when
    a half would hold fewer than :data:`MIN_HALF_CYCLES` cycles.
    """
    boundaries = np.asarray(model.timing.boundaries, dtype=float)
    time = model.time
    inside = boundaries[(boundaries > time[0]) & (boundaries < time[-1])]
    if inside.size < 2 * MIN_HALF_CYCLES + 1:
        return None
    cut = inside[inside.size // 2]
    return [(time < cut, boundaries <= cut), (time >= cut, boundaries >= cut)]


def part(model, keep, kept):
    """The record-level model on the samples ``keep`` with the cycle boundaries ``kept`` (the same options).

    The regressors' values, a measured input of an effect (``floor_disp``) and the path a nonlinear
    effect is linearised about are cut with the samples.
    """
    timing = CycleTiming(model.timing.boundaries[kept], model.timing.method)
    regressors = tuple(replace(r, values=np.asarray(r.values)[keep]) for r in model.regressors)
    dynamics = None
    if model.dynamics.model.effects:
        signals = {name: np.asarray(values)[keep] for name, values in model.dynamics.inputs.signals.items()}
        dynamics = PersonDynamics(model.dynamics.model, model.time[keep], signals)
    nominal = None if model.nominal is None else np.asarray(model.nominal)[keep]
    return replace(model, time=model.time[keep], y=model.y[keep], timing=timing, regressors=regressors,
                   dynamics=dynamics, nominal=nominal, observed=model.observed[keep])


def held_out_loglike(model, params, delta, sigma2) -> float:
    """Log-likelihood of ``model``'s record (a held-out part) at parameters fitted elsewhere.

    Parameters
    ----------
    model : RecordModel
        The held-out part (:func:`part`).
    params : ndarray
        The searched parameters fitted on the other part.
    delta : ndarray
        Its concentrated linear unknowns (``model.delta_names``): the force template is taken from
        it; the initial state and the regressors' coefficients (offset, zero drift) are the held-out
        part's own and estimated on it by generalised least squares.
    sigma2 : float
        The noise scale fitted on the other part.

    Returns
    -------
    float
        The sum of the one-step prediction log-densities over the held-out samples (-inf when the
        pass breaks down at these parameters).
    """
    out = model.filter(params)
    raw, regression = out["innovations_raw"], out["innovation_regression"]
    variance = out["innovation_variance_unscaled"]
    if not (np.all(np.isfinite(raw)) and np.all(np.isfinite(variance))):
        return -np.inf
    n_x, p = model.n_dynamic, model.n_coefficients
    own = np.r_[np.arange(n_x), np.arange(n_x + p, len(delta))]
    own = np.setdiff1d(own, model.held_delta)
    template = np.arange(n_x, n_x + p)
    residual = raw - regression[:, template] @ np.asarray(delta)[template]
    weight = 1.0 / np.sqrt(variance)
    columns = regression[:, own] * weight[:, None]
    estimate, *_ = np.linalg.lstsq(columns, residual * weight, rcond=None)
    residual = residual - regression[:, own] @ estimate
    scaled = variance * sigma2
    return float(-0.5 * np.sum((np.log(2.0 * np.pi * scaled) + residual**2 / scaled)[model.observed]))


def cross_validated_loglike(model, params) -> dict | None:
    """Two-fold held-out log-likelihood of ``model``: each half fitted, the other half scored.

    Parameters
    ----------
    model : RecordModel
        The whole record's model.
    params : ndarray
        Its estimate (each half's search starts there).

    Returns
    -------
    dict or None
        ``loglike``: the sum over both folds; ``folds``: per fold the fitted half's ``start``,
        ``end`` (s), its parameters and the held-out log-likelihood of the other half. None when the
        record is too short to halve (:func:`halves`) or a half's fit does not converge.
    """
    cut = halves(model)
    if cut is None:
        return None
    parts = [part(model, keep, kept) for keep, kept in cut]
    folds = []
    for fitted_part, held_part in (parts, parts[::-1]):
        fitted = fit_model(fitted_part, params, quick=True)
        if not fitted["converged"]:
            return None
        filtered = fitted_part.filter(fitted["params"])
        score = held_out_loglike(held_part, fitted["params"], filtered["delta"], filtered["sigma2"])
        folds.append({"start": float(fitted_part.time[0]), "end": float(fitted_part.time[-1]),
                      "params": fitted["params"], "held_out_loglike": score})
    return {"loglike": float(sum(f["held_out_loglike"] for f in folds)), "folds": folds}
