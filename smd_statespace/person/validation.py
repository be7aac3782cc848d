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
lowers the held-out log-likelihood. The held-out half is also simulated freely
(:func:`held_out_free_run`: the template in every cycle, never corrected by the measurement), and both
predictions are scored by MATLAB's fit % (``compare`` on validation data).

The halves are the ones :func:`~smd_statespace.person.change.change_test` compares
(:func:`part`: the same options, the cycle timing and regressors cut with the samples; a nonlinear
effect keeps the whole fit's linearisation path, cut likewise).

A change in time (a step, an effect's :attr:`~smd_statespace.model.effect.Effect.breaks`) cannot be
predicted by a fit that has not seen it: on one side of a step its term is a constant, confounded with
``f_h``. For such a model every fold is fitted on a part that holds the breaks (:func:`break_folds`): cut
at least :data:`BREAK_MARGIN` of the record after the last break, the part before the cut predicts the rest;
cut as far before the first, the part after it predicts the start. Both folds are scored where both cuts
leave :data:`MIN_HALF_CYCLES` cycles held out, so the record's either side of the change is predicted by a
person who has seen it. Until 2026-11-29 only one such fold was scored (the third of the record beyond one
cut): on a lab export whose ``f_h`` steps 16 % at the middle (``person_effects.py``, seed 92, step record 4;
likelihood ratio 29, p 3e-6) the step fitted on 4.6-25.3 s, with 5 s of it after the step, predicted
25.3-35.4 s worse than the person without it (z -0.83), and the step was not proposed.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..measures import fit_percent
from .dynamics import PersonDynamics
from .search import fit_model
from .timing import CycleTiming

__all__ = ["MIN_HALF_CYCLES", "BREAK_MARGIN", "halves", "break_folds", "part", "held_out_prediction",
           "held_out_loglike", "held_out_free_run", "cross_validated_loglike", "held_out_gain"]

MIN_HALF_CYCLES = 8
"""Fewest whole force cycles in each half (the record-level model needs as many to estimate the variation)."""

BREAK_MARGIN = 1.0 / 6.0
"""Least distance of the cut from a break (a step in time), as a fraction of the record: a step at the middle is cut
at a third (or two thirds), so the part that holds it has at least a quarter of its length on each side."""


def halves(model) -> list | None:
    """``[(keep, kept), (keep, kept)]``: the samples and cycle boundaries of the record's two halves.

    The cut is the cycle boundary nearest the middle of the boundaries inside the record, among those that
    leave :data:`MIN_HALF_CYCLES` cycles in each half. None when no boundary does. (A model with changes in time
    is judged on :func:`break_folds` instead.)
    """
    time, boundaries, inside, index = _cuts(model)
    return _split(time, boundaries, _middle(inside, index)) if index.size else None


def break_folds(model, breaks) -> list:
    """The folds that judge a model with changes at ``breaks`` (s): each fitted on a part that holds them all.

    ``[(fitted, held), ...]``, each ``(keep, kept)`` as :func:`halves` gives them: cut at the boundary nearest the
    middle among those at least :data:`BREAK_MARGIN` of the record after the last break, the part before the cut
    is fitted and the rest held out; cut likewise before the first break, the part after it is fitted and the
    start held out. Each cut leaves :data:`MIN_HALF_CYCLES` cycles on both sides. Empty when neither side has one.
    """
    time, boundaries, inside, index = _cuts(model)
    folds = []
    for before in (False, True):
        valid = index[_apart(inside[index], breaks, time, before)]
        if valid.size:
            first, second = _split(time, boundaries, _middle(inside, valid))
            folds.append((second, first) if before else (first, second))
    return folds


def _cuts(model) -> tuple:
    """``(time, boundaries, inside, index)``: the cycle boundaries inside the record and the indices (into
    ``inside``) of those that leave :data:`MIN_HALF_CYCLES` cycles on both sides (none on a short record)."""
    boundaries = np.asarray(model.timing.boundaries, dtype=float)
    time = model.time
    inside = boundaries[(boundaries > time[0]) & (boundaries < time[-1])]
    return time, boundaries, inside, np.arange(MIN_HALF_CYCLES, max(inside.size - MIN_HALF_CYCLES, MIN_HALF_CYCLES))


def _middle(inside, index) -> float:
    """The boundary of ``inside[index]`` nearest the middle of the boundaries."""
    return float(inside[index[np.argmin(np.abs(index - inside.size // 2))]])


def _split(time, boundaries, cut) -> list:
    """``[(keep, kept), (keep, kept)]``: the samples and cycle boundaries before and after ``cut``."""
    return [(time < cut, boundaries <= cut), (time >= cut, boundaries >= cut)]


def _apart(cuts, breaks, time, before: bool = False) -> np.ndarray:
    """Which ``cuts`` lie at least :data:`BREAK_MARGIN` of the record after every break (``before``: before)."""
    margin = BREAK_MARGIN * (time[-1] - time[0])
    distance = np.asarray(cuts)[:, None] - np.asarray(breaks, dtype=float)[None, :]
    return np.all(-distance >= margin if before else distance >= margin, axis=1)


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


def _own(model, size: int) -> np.ndarray:
    """Indices of the linear unknowns that are a held-out part's own: its initial state and regressor coefficients."""
    n_x, p = model.n_dynamic, model.n_coefficients
    return np.setdiff1d(np.r_[np.arange(n_x), np.arange(n_x + p, size)], model.held_delta).astype(int)


def held_out_prediction(model, params, delta, sigma2) -> dict:
    """One-step prediction of ``model``'s record (a held-out part) at parameters fitted elsewhere.

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
    dict
        ``loglike``: the sum of the one-step prediction log-densities over the held-out samples (-inf
        when the pass breaks down at these parameters); ``one_step``: the one-step predicted output
        (m/s^2, NaN when it breaks down); ``sample_loglike``: the log-density of each sample (NaN where
        missing or when it breaks down).
    """
    out = model.filter(params)
    raw, regression = out["innovations_raw"], out["innovation_regression"]
    variance = out["innovation_variance_unscaled"]
    if not (np.all(np.isfinite(raw)) and np.all(np.isfinite(variance))):
        return {"loglike": -np.inf, "one_step": np.full(model.y.size, np.nan),
                "sample_loglike": np.full(model.y.size, np.nan)}
    own = _own(model, len(delta))
    template = np.arange(model.n_dynamic, model.n_dynamic + model.n_coefficients)
    residual = raw - regression[:, template] @ np.asarray(delta)[template]
    weight = 1.0 / np.sqrt(variance)
    columns = regression[:, own] * weight[:, None]
    estimate, *_ = np.linalg.lstsq(columns, residual * weight, rcond=None)
    residual = residual - regression[:, own] @ estimate
    scaled = variance * sigma2
    sample = np.where(model.observed, -0.5 * (np.log(2.0 * np.pi * scaled) + residual**2 / scaled), np.nan)
    return {"loglike": float(np.nansum(sample)), "one_step": model.y - residual, "sample_loglike": sample}


def held_out_loglike(model, params, delta, sigma2) -> float:
    """The held-out log-likelihood of :func:`held_out_prediction` (its ``loglike``)."""
    return held_out_prediction(model, params, delta, sigma2)["loglike"]


def held_out_free_run(model, params, delta) -> np.ndarray:
    """Free run of ``model``'s record (a held-out part) at parameters and template fitted elsewhere (m/s^2).

    :meth:`~smd_statespace.person.model.RecordModel.free_run` with ``delta``'s template; the part's own
    initial state and regressor coefficients are estimated by least squares on the run, as MATLAB's
    ``compare`` estimates the initial condition of validation data.
    """
    own = _own(model, len(delta))
    base = np.array(delta, dtype=float)
    base[own] = 0.0
    columns = np.repeat(base[:, None], 1 + own.size, axis=1)
    columns[own, 1 + np.arange(own.size)] = 1.0
    runs = model.free_run(params, columns)
    response = runs[:, 1:] - runs[:, :1]  # the run is affine in the part's own unknowns
    observed = model.observed
    estimate, *_ = np.linalg.lstsq(response[observed], (model.y - runs[:, 0])[observed], rcond=None)
    return runs[:, 0] + response @ estimate


def cross_validated_loglike(model, params, breaks=()) -> dict | None:
    """Two-fold held-out validation of ``model``: each half fitted, the other half predicted.

    Parameters
    ----------
    model : RecordModel
        The whole record's model.
    params : ndarray
        Its estimate (each half's search starts there).
    breaks : sequence of float
        Times (s) where a candidate's term changes abruptly (its effects'
        :attr:`~smd_statespace.model.effect.Effect.breaks`): every fold is fitted on a part that holds them
        (:func:`break_folds`: one or two folds). Give the same ``breaks`` for the model without the candidate,
        so both are judged on the same samples.

    Returns
    -------
    dict or None
        ``loglike``: the held-out log-likelihood summed over the folds scored; ``one_step_fit`` and
        ``free_run_fit``: :func:`~smd_statespace.measures.fit_percent` (%) of the one-step prediction
        and of the free run over the held-out samples; ``time``, ``measured``, ``one_step``,
        ``free_run``: those over the record, each half as predicted from the other (arrays, s and
        m/s^2; NaN on a half no fold predicts); ``sample_loglike``: each held-out sample's log-density
        (NaN elsewhere); ``cycle``: each sample's force cycle (the clusters of :func:`held_out_gain`);
        ``cuts``: where the fitted and held-out parts meet (s; one for the halves); ``folds``: per
        fold scored the fitted part's ``start``, ``end`` (s), its parameters and the held-out log-likelihood
        of the rest. None when the record is too short to cut (:func:`halves`, :func:`break_folds`) or a fold's
        fit does not converge.
    """
    if len(breaks):  # only a part that holds the breaks can determine the change: folds fitted on such parts
        order = [((part(model, *fit), part(model, *held)), held) for fit, held in break_folds(model, breaks)]
        if not order:
            return None
    else:
        cut = halves(model)
        if cut is None:
            return None
        parts = [part(model, keep, kept) for keep, kept in cut]
        order = list(zip((parts, parts[::-1]), cut[::-1]))
    folds, one_step, free = [], np.full(model.y.size, np.nan), np.full(model.y.size, np.nan)
    sample = np.full(model.y.size, np.nan)
    for (fitted_part, held_part), (held, _) in order:
        fitted = fit_model(fitted_part, params, quick=True)
        if not fitted["converged"]:
            return None
        filtered = fitted_part.filter(fitted["params"])
        predicted = held_out_prediction(held_part, fitted["params"], filtered["delta"], filtered["sigma2"])
        one_step[held] = predicted["one_step"]
        sample[held] = predicted["sample_loglike"]
        free[held] = held_out_free_run(held_part, fitted["params"], filtered["delta"])
        folds.append({"start": float(fitted_part.time[0]), "end": float(fitted_part.time[-1]),
                      "params": fitted["params"], "held_out_loglike": predicted["loglike"]})
    cuts = sorted({float(max(fitted_part.time[0], held_part.time[0])) for (fitted_part, held_part), _ in order})
    scored = model.observed & np.isfinite(free)
    return {"loglike": float(sum(f["held_out_loglike"] for f in folds)), "folds": folds,
            "one_step_fit": fit_percent(model.y[scored], one_step[scored]),
            "free_run_fit": fit_percent(model.y[scored], free[scored]),
            "time": model.time, "measured": model.y, "one_step": one_step, "free_run": free,
            "sample_loglike": sample, "cycle": model._phase[0], "cuts": cuts}


def held_out_gain(before: dict, after: dict) -> dict:
    """How much better ``after`` predicts the held-out samples than ``before``, against the noise of that gain.

    ``before``, ``after``: :func:`cross_validated_loglike` of two models of the same record on the same cut. The
    gain in log-density is summed per force cycle ``g_c`` (a misfit is correlated within a cycle), and its total
    is compared with its cluster-robust sd ``sqrt(n / (n - 1) sum (g_c - mean)^2)`` over the ``n`` held-out
    cycles (a Diebold-Mariano comparison of two forecasts, with cycles as the blocks).

    Returns
    -------
    dict
        ``gain`` (the total), ``sd`` and ``z`` (``gain / sd``; NaN with fewer than 3 cycles), ``cycles``.
    """
    difference = after["sample_loglike"] - before["sample_loglike"]
    scored = np.isfinite(difference)
    cycles = np.unique(before["cycle"][scored], return_inverse=True)[1]
    per_cycle = np.bincount(cycles, weights=difference[scored]) if scored.any() else np.zeros(0)
    n, gain = per_cycle.size, float(per_cycle.sum())
    if n < 3:
        return {"gain": gain, "sd": float("nan"), "z": float("nan"), "cycles": n}
    sd = float(np.sqrt(n / (n - 1.0) * np.sum((per_cycle - per_cycle.mean()) ** 2)))
    return {"gain": gain, "sd": sd, "z": gain / sd if sd > 0 else float("nan"), "cycles": n}
