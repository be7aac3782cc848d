"""Likelihood ratios that stay calibrated when the rest of the model is wrong: the sandwich and a scaled ratio.

A candidate effect's likelihood ratio is chi-square(df) when the model without it is right in everything else.
When it is not, the ratio is a weighted sum of independent chi-square(1)s whose weights are the eigenvalues of
``I^-1 J`` (Kent 1982, *Biometrika* 69, 19-27; White 1982, *Econometrica* 50, 1-25): ``I`` is the information the
Gaussian likelihood claims for the candidate's unknowns (the person's other unknowns profiled out), ``J`` the
variance its scores really have. Where the model is right the two agree and every weight is 1.

On a quiet force plate they do not. The force of a real person varies from cycle to cycle in ways no variation
model describes exactly, and with a plate noise of 0.15 % of body weight what the model misses is no longer
small against the noise: the innovations carry it (kurtosis 16-30, Ljung-Box p about 1e-60 on clean lab-shaped
records). A candidate then takes a share of that misfit, and its plain ratio calls the share significant: clean
records got a cubic spring at LR 52.6 on 1 and a drift of ``f_h`` at LR 39.6 on 1 (``benchmarks/person_effects.py``,
the ``lab`` generator).

:func:`misspecification_scale` estimates ``J`` by the outer products of the efficient scores summed per bouncing
cycle (cycles as clusters: the misfit is correlated within a cycle, and cycles are close to independent), at
the fit *with* the candidate (where the summed scores are zero, so the sums need no centring), and gives
``c = tr(I^-1 J) / q`` over the candidate's ``q`` unknowns; the ratio divided by ``c`` is referred to
chi-square(q) (the mean-scaled statistic of Satorra & Bentler 1994, in *Latent variables analysis*, 399-419).
``c`` is floored at :data:`MIN_SCALE`: with about 70 cycles ``J`` is itself uncertain, and a test must never be
made more liberal than the plain one by that noise. On the two clean lab records above, ``c`` was 6.3 for the
cubic spring and 2.2 for the drift.
"""

from __future__ import annotations

import numpy as np

from ..errors import SMDInputError
from .score import cycle_sums, profile_out, score

__all__ = ["MIN_SCALE", "information_and_scores", "misspecification_scale", "robust_scale", "added_unknowns"]

MIN_SCALE = 1.0
"""The smallest scale :func:`misspecification_scale` returns: a ratio is never made larger than the plain one."""


def information_and_scores(model, params) -> tuple:
    """The information and per-sample scores of every unknown of ``model`` at ``params``, ``sigma^2`` profiled out.

    The unknowns are the searched ``params`` (:attr:`~smd_statespace.person.model.RecordModel.param_names`) and
    the concentrated linear ones (:attr:`~smd_statespace.person.model.RecordModel.delta_names`, those not held
    at 0), at their estimates: the template, the initial state, a floor's initial state, the regressors.

    Returns
    -------
    names : list of str
    information : ndarray, shape (m, m)
        Expected information (Harvey 1989, Sect. 3.4.5): for the searched parameters as
        :func:`~smd_statespace.person.score.score`'s, for a linear unknown ``sum Ev' Ev / (sigma^2 f)``
        (``d v / d delta = -Ev``), with ``sigma^2`` profiled out (it is orthogonal to ``delta``).
    scores : ndarray, shape (N, m)
        Per-sample scores; their sum is the gradient (zero at the maximum).
    """
    params = np.asarray(params, dtype=float)
    fitted = model.filter(params)
    out = score(model, params, fitted=fitted)
    held = set(model.held_delta)
    free = [i for i in range(len(model.delta_names)) if i not in held]
    regression = fitted["innovation_regression"][:, free]
    v, variance = out["innovations"], out["variances"]
    relative = out["d_log_variances"]
    total = relative.sum(axis=0)
    n = model.n_observed
    cross = -(out["d_innovations"] / variance[:, None]).T @ regression
    information = np.block([[out["expected_information"] - 0.5 * np.outer(total, total) / n, cross],
                            [cross.T, regression.T @ (regression / variance[:, None])]])
    standard2 = np.where(model.observed, 1.0 - v**2 / variance, 0.0)
    scores = np.hstack([out["per_sample"] + 0.5 * np.outer(standard2, total) / n,
                        (v / variance)[:, None] * regression])
    names = list(model.param_names) + [model.delta_names[i] for i in free]
    return names, 0.5 * (information + information.T), scores


def added_unknowns(fitted, base) -> list:
    """Names of the unknowns ``fitted``'s model estimates that ``base``'s does not: an added effect's parameters,
    its variances and its concentrated unknowns (the template of extra harmonics, a floor's initial state)."""
    held = {fitted.model.delta_names[i] for i in fitted.model.held_delta}
    return ([name for name in fitted.model.param_names if name not in base.model.param_names]
            + [name for name in fitted.model.delta_names if name not in base.model.delta_names and name not in held])


def misspecification_scale(model, params, tested) -> dict:
    """How much the likelihood overstates the evidence for the unknowns ``tested`` at the fit ``params``.

    Parameters
    ----------
    model : RecordModel
        The model with the candidate, at its estimate ``params``.
    tested : sequence of str
        The candidate's unknowns (:func:`added_unknowns`); a searched one on a bound is left out (it is not
        estimated).

    Returns
    -------
    dict
        ``scale``: ``tr(I^-1 J) / q`` floored at :data:`MIN_SCALE` (1 when nothing is left to test or the
        information is singular); ``eigenvalues``: those of ``I^-1 J`` (the weights of the ratio's
        chi-square(1) terms, all 1 when the model is right); ``tested``: the unknowns used.
    """
    if not len(tested):  # nothing added (a measured floor): the plain ratio, and no pass is run
        return {"scale": MIN_SCALE, "eigenvalues": np.array([]), "tested": []}
    params = np.asarray(params, dtype=float)
    names, information, scores = information_and_scores(model, params)
    on_bound = {model.param_names[i] for i in range(params.size) if model.at_bound(params, i)}
    keep = [names.index(name) for name in tested if name in names and name not in on_bound]
    nuisance = [i for i in range(len(names)) if i not in keep and names[i] not in on_bound]
    if not keep:
        return {"scale": MIN_SCALE, "eigenvalues": np.array([]), "tested": []}
    effective, efficient = profile_out(information, scores, keep, nuisance, 1e-10)
    clusters = cycle_sums(model, efficient)
    try:
        weights = np.linalg.solve(effective, clusters.T @ clusters)
    except np.linalg.LinAlgError:
        return {"scale": MIN_SCALE, "eigenvalues": np.full(len(keep), np.nan), "tested": [names[i] for i in keep]}
    eigenvalues = np.sort(np.linalg.eigvals(weights).real)[::-1]
    scale = float(np.trace(weights)) / len(keep)
    return {"scale": max(scale, MIN_SCALE) if np.isfinite(scale) else MIN_SCALE, "eigenvalues": eigenvalues,
            "tested": [names[i] for i in keep]}


def robust_scale(model, params, tested) -> float:
    """:func:`misspecification_scale`'s ``scale`` of the unknowns ``tested`` at ``params``; :data:`MIN_SCALE` (the
    plain ratio) where it cannot be computed (a pass that breaks down, a singular information)."""
    try:
        return misspecification_scale(model, params, tested)["scale"]
    except (SMDInputError, ArithmeticError, np.linalg.LinAlgError, ValueError):
        return MIN_SCALE
