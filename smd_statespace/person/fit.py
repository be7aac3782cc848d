"""Identify the person from a whole record: maximum likelihood on the record-level model.

:func:`identify_person` estimates one ``f_h``, one ``xi_h`` and the force's
template and cycle-to-cycle variation from a whole bouncing record
(:mod:`smd_statespace.person.model`), with standard errors from the observed
information and profile-likelihood intervals for ``f_h`` and ``xi_h``, and
returns a :class:`~smd_statespace.person.results.PersonResult`.

Steps:

1. COM acceleration ``y = GRF / M_h - g`` (Eq. 3), not filtered;
2. force-cycle boundaries (:func:`~smd_statespace.person.timing.estimate_timing`);
3. for each variation model, a coarse search over ``f_h`` and ``xi_h`` and then
   Fisher scoring on the profile likelihood with its exact gradient
   (:mod:`smd_statespace.person.score`) (template, initial state, offset and
   ``sigma^2`` concentrated out); the variation model with the lowest AIC wins;
4. the observed information (differences of the exact gradient) and,
   for ``f_h`` and ``xi_h``, the profile-likelihood interval (every other
   parameter re-maximised at each point).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from scipy import optimize, stats

from ..diagnostics.applicability import check_bouncing
from ..errors import CycleError, OptionError, SMDInputError
from ..io import G, Record
from ..progress import tqdm
from ..signals import RECORD_RATE, decimate_record, decimation_note
from .model import VARIATIONS, Regressor, RecordModel
from .timing import TIMING_METHODS, CycleTiming, estimate_timing

__all__ = ["FitError", "MIN_CYCLES", "identify_person", "fit_model", "person_result", "profile_interval",
           "honest_intervals", "undetermined_interval"]

MIN_CYCLES = 8
"""Fewest force cycles for the record-level model (the cycle-to-cycle spread needs several)."""

START_F_H = (1.2, 1.7, 2.3, 3.0, 3.9, 5.0)
"""Starting values of ``f_h`` (Hz) of the coarse search."""

START_XI_H = (0.15, 0.45)
"""Starting values of ``xi_h`` of the coarse search."""

AUTO_VARIATIONS = ("independent", "smooth")
"""Variation models compared by ``variation="auto"``."""

INTERVAL_METHODS = ("calibrated", "wald", "profile")
"""Interval methods of :func:`identify_person`."""

CALIBRATION = {"independent": {"f_h": 2.75, "xi_h": 2.72}, "smooth": {"f_h": 3.29, "xi_h": 1.68},
               "random_walk": {"f_h": 3.01, "xi_h": 2.48}, "both": {"f_h": 3.01, "xi_h": 2.48}}
"""Factors on the standard errors of ``f_h`` and ``xi_h`` for ``intervals="calibrated"`` (the default).

The observed information ignores the error of the cycle timing and what the
model misses, so its intervals are too narrow. Each factor is the 90th
percentile of ``|estimate - truth| / sd`` over simulated records, divided by
1.645, for the variation model that ``variation="auto"`` chose on them, over the
records whose parameter nothing but its sd could leave undetermined (not a misfit,
not an artefact): measured with ``benchmarks/person_calibration.py`` on the rows of
``benchmarks/person_accuracy.py`` runs with all five generators of force variation
(jumps, smooth, coefficients, pulses, tempo), 30 s at 100 Hz, at 1 % BW noise (seed
2027, 40 records each) and 0.3 % BW (seed 2028, 24 each): 504 records, "independent"
chosen on 280, "smooth" on 224 (docs/person-calibration.md).
"random_walk" and "both" were not measured: they take the pooled factors. The factors
before (1.89, 2.63 and 3.21, 1.96) were measured on the jumps and smooth generators
alone at 1 % BW, with an earlier search.
"""

MODEL_ERROR_FLOOR = {"independent": {"f_h": 0.035, "xi_h": 0.015}, "smooth": {"f_h": 0.08, "xi_h": 0.08},
                     "random_walk": {"f_h": 0.08, "xi_h": 0.08}, "both": {"f_h": 0.08, "xi_h": 0.08}}
"""Standard deviations added (in quadrature) to the calibrated ones in the intervals, per variation model: relative
to ``f_h`` for ``f_h`` (3.5 % and 8 %), absolute for ``xi_h``.

Only the intervals widen; the standard errors (``result.se``, and whether a parameter is
determined) stay what the record's information says.

The floor stands for the model error of a generator of force variation not yet seen. It
is sized by leaving one generator out at a time: :data:`CALIBRATION`'s factors measured
on the other four, the floor each variation model needs for the left-out generator's
records of it to be covered at 90 % at both noise levels; the largest need over the five
generators is the floor (``person_calibration.held_out_floors``). "independent" needs
3.5 % of ``f_h`` and 0.015 of ``xi_h`` (for the coefficients and jumps generators), "smooth"
8 % and 0.08 (for the smooth generator: the others' smooth fits are better than its own).
A generator unlike all others is not covered by it: with the smooth generator left out,
the floor measured on the other four (none of which asks for a smooth floor) covers its
``f_h`` on 74-79 %. "random_walk" and "both" take the larger floors.

The floor before (6 % and 0.05 for every variation model) was chosen on quiet records of
two generators; on records with 1 % BW noise it made the intervals of the well-fitted
generators too wide (coverage 97-100 %).
"""

FIT_METHODS = ("scoring", "lbfgs", "lbfgs-difference")
"""Search methods of :func:`fit_model`."""

QUICK_GAIN = 1e-3
"""Stop rule of the intermediate fits (log-likelihood units gained by the last step)."""

FINAL_GAIN = 1e-5
"""Stop rule of the final fit (log-likelihood units gained by the last step)."""

TIMING_ITERATIONS = 3
"""Re-placements of the cycle starts from the model's own phase and rate errors (``timing="model"``)."""

PHASE_VARIANCE_STARTS = ((-8.0, -5.0, -2.0, 1.0), (-6.0, -3.0, 0.0, 3.0))
"""Starting log variance ratios of the phase and rate errors tried before the first timing fit."""


class FitError(SMDInputError):
    """The maximum-likelihood fit failed (no convergence, information not positive definite)."""


def fit_model(model: RecordModel, start=None, quick=False, method="scoring") -> dict:
    """Maximise the profile likelihood of ``model``.

    Parameters
    ----------
    model : RecordModel
    start : ndarray, optional
        Starting parameters; default the best of a coarse search over
        :data:`START_F_H` x :data:`START_XI_H`.
    quick : bool
        Looser stop rule (intermediate fits): :data:`QUICK_GAIN` instead of
        :data:`FINAL_GAIN` for ``"scoring"``, a relative change of 1e-7 of the
        likelihood for the L-BFGS-B methods.
    method : {"scoring", "lbfgs", "lbfgs-difference"}
        ``"scoring"`` (default): Fisher scoring with the exact gradient and the
        profile's expected information, both from one derivative pass of the
        Kalman filter (:func:`~smd_statespace.person.score.score`), damped as
        Levenberg-Marquardt and kept inside the bounds (:func:`_scoring`);
        ``"lbfgs"``: scipy's L-BFGS-B with the exact gradient;
        ``"lbfgs-difference"``: L-BFGS-B with forward-difference gradients
        (what the library did before; kept for comparison in
        ``benchmarks/person_perf.py``). Measured on a 30 s record: 9 passes
        with derivatives for "scoring" where L-BFGS-B took 26 with the exact
        gradient and 220 likelihoods with differences, to the same maximum.

    Returns
    -------
    dict
        ``params`` (ndarray), ``loglike``, ``n_evaluations`` (likelihoods, with
        or without derivatives), ``converged`` (bool), ``message``. A scoring
        search still gaining after its last allowed step is finished by L-BFGS-B
        with the exact gradient from where it stopped (the message says so).
    """
    from .score import score

    if method not in FIT_METHODS:
        raise OptionError(f"method {method!r} is not one of: {', '.join(FIT_METHODS)}")
    count = [0]
    # the search runs in units of each parameter's typical size (1 for f_h, xi_h and the log
    # variances; an effect's nominal magnitude for its parameters: a cubic coefficient of 400 1/m^2)
    scales = model.scales
    bounds = [(low / scale, high / scale) for (low, high), scale in zip(model.bounds, scales)]

    def negative(scaled):
        count[0] += 1
        value = model.loglike(scaled * scales)
        return -value if np.isfinite(value) else 1e300

    def negative_and_gradient(scaled):
        count[0] += 1
        out = score(model, scaled * scales)
        if not (np.isfinite(out["loglike"]) and np.all(np.isfinite(out["gradient"]))):
            return 1e300, np.zeros(scaled.size)  # the pass broke down there: the line search steps back
        return -out["loglike"], -out["gradient"] * scales

    if start is None:
        candidates = [model.start_params(f, x) for f in START_F_H for x in START_XI_H]
        start = min(candidates, key=lambda params: negative(params / scales))
    start = np.asarray(start, dtype=float) / scales
    prefix = ""
    if method == "scoring":
        params, loglike, n, converged, message = _scoring(model, start * scales, QUICK_GAIN if quick else FINAL_GAIN)
        count[0] += n
        if converged or not np.isfinite(loglike):
            return {"params": params, "loglike": loglike, "n_evaluations": count[0], "converged": converged,
                    "message": message}
        # still gaining after every step allowed: scoring crawls along a ridge (a measured floor's fit took
        # more than 100 steps); L-BFGS-B with the exact gradient finishes from where it stopped
        start, method, prefix = params / scales, "lbfgs", f"scoring: {message}; then L-BFGS-B: "
    options = {"ftol": 1e-7} if quick else {}
    fun, jac = (negative_and_gradient, True) if method == "lbfgs" else (negative, None)
    result = optimize.minimize(fun, start, method="L-BFGS-B", jac=jac, bounds=bounds, options=options)
    if quick:
        return {"params": result.x * scales, "loglike": -float(result.fun), "n_evaluations": count[0],
                "converged": True, "message": prefix + str(result.message)}
    # L-BFGS-B often stops on its line search at the optimum; a restart from there that gains nothing
    # confirms it
    if not result.success:
        again = optimize.minimize(fun, result.x, method="L-BFGS-B", jac=jac, bounds=bounds)
        converged = again.success or abs(again.fun - result.fun) < 1e-3
        result = again if again.fun <= result.fun else result
    else:
        converged = True
    return {"params": result.x * scales, "loglike": -float(result.fun), "n_evaluations": count[0],
            "converged": bool(converged), "message": prefix + str(result.message)}


def _scoring(model: RecordModel, start, gain, max_iterations=100) -> tuple:
    """Fisher scoring, damped as Levenberg-Marquardt, inside the parameters' bounds.

    Each step solves ``(I + lambda diag(I)) step = g`` with ``g`` the exact
    gradient and ``I`` the expected information of the profile likelihood
    (:func:`~smd_statespace.person.score.score`), in the units of
    :attr:`RecordModel.scales`, over the parameters not held at a bound by a
    gradient pointing out of it, and clips the new point to the bounds. A
    step that lowers the likelihood is taken again with ten times the
    damping; an accepted one divides it by ten. The search stops when an
    accepted step gains less than ``gain`` (log-likelihood units), or when no
    damping finds a gain (the point is a maximum to the precision of the pass).
    A trial point is judged by its likelihood (the filter alone); the
    derivative pass, five times dearer, runs only at the points the search
    goes on from: rejected trials and the last step cost a likelihood each
    (the same steps and answer as computing the derivatives everywhere, 25-30 %
    fewer derivative passes: ``benchmarks/person_fits.py``).

    Returns
    -------
    tuple
        ``(params, loglike, n_evaluations, converged, message)``.
    """
    from .score import score

    scales = model.scales
    bounds = np.asarray(model.bounds, dtype=float) / scales[:, None]
    low, high = bounds[:, 0], bounds[:, 1]
    x = np.clip(np.asarray(start, dtype=float) / scales, low, high)
    current = score(model, x * scales)
    count = 1
    if not np.isfinite(current["loglike"]):
        return x * scales, -math.inf, count, False, "the likelihood is not finite at the start"
    damping = 1e-3
    for iteration in range(max_iterations):
        g = current["gradient"] * scales
        info = current["profile_information"] * np.outer(scales, scales)
        free = np.flatnonzero(~(((x <= low) & (g < 0.0)) | ((x >= high) & (g > 0.0))))
        if free.size == 0:  # every parameter held at a bound by its gradient: a corner maximum
            return x * scales, current["loglike"], count, True, "every parameter on a bound"
        sub = info[np.ix_(free, free)]
        diagonal = np.maximum(np.diag(sub), 1e-12 * max(float(np.max(np.abs(np.diag(sub)))), 1e-300))
        accepted = None
        for _ in range(12):
            step = np.zeros_like(x)
            try:
                step[free] = np.linalg.solve(sub + damping * np.diag(diagonal), g[free])
            except np.linalg.LinAlgError:
                damping *= 10.0
                continue
            trial = np.clip(x + step, low, high)
            # a trial is judged by its likelihood alone (the filter, a fifth of a derivative pass); the
            # derivatives are computed only where the search goes on from it
            filtered = model.filter(trial * scales)
            count += 1
            if not (np.isfinite(filtered["loglike"]) and filtered["loglike"] >= current["loglike"]):
                damping *= 10.0
                continue
            improvement = filtered["loglike"] - current["loglike"]
            if improvement < gain:
                return trial * scales, filtered["loglike"], count, True, f"gain {improvement:.2g} < {gain:g}"
            out = score(model, trial * scales, fitted=filtered)
            if np.all(np.isfinite(out["gradient"])):
                accepted = (trial, out)
                break
            damping *= 10.0
        if accepted is None:
            return x * scales, current["loglike"], count, True, "no step gains: a maximum"
        x, current = accepted
        damping = max(damping / 10.0, 1e-6)
    return x * scales, current["loglike"], count, False, f"no convergence in {max_iterations} steps"


def _hessian(model: RecordModel, params, index, steps):
    """Observed information's Hessian: forward differences of the exact gradient (:func:`score.score`).

    ``len(index) + 1`` derivative passes, where differencing the likelihood
    itself needed ``2 k^2`` likelihoods and was noisier; the result is
    symmetrised. Returns the Hessian over ``index`` (the other parameters
    held). Central differences (``2 len(index)`` passes, up to 2026-11-26)
    gave the same standard errors of ``f_h`` and ``xi_h`` within 1.3e-4 of
    their size on nine fitted 30 s records (three generators, both variation
    models) in 55-60 % of the time.
    """
    from .score import score

    base = score(model, params)["gradient"][index]
    hess = np.empty((index.size, index.size))
    for column, (i, h) in enumerate(zip(index, steps)):
        up = params.copy()
        up[i] += h
        hess[:, column] = (score(model, up)["gradient"][index] - base) / h
    return 0.5 * (hess + hess.T)


def information(model: RecordModel, params, cov_type="robust") -> tuple:
    """Covariance of the estimates; parameters at a bound are held fixed.

    Parameters
    ----------
    model : RecordModel
    params : ndarray
        The estimate.
    cov_type : {"robust", "oim"}
        ``"oim"``: the inverse observed information (the Hessian of the
        profile likelihood by forward differences of its exact gradient,
        :func:`_hessian`), right when the model is right. ``"robust"``
        (default): the sandwich ``H^-1 B H^-1`` with ``B`` the outer product
        of the per-cycle sums of the efficient scores (the template, initial
        state and scale profiled out; clustered by force cycle), which stays
        right when the innovations are not what the model says (heavy tails,
        the cycle timing's own error); never narrower than needed for the
        measured spread of the scores.

    Returns
    -------
    cov : ndarray, shape (k, k)
        NaN rows and columns for parameters at a bound.
    free : ndarray of bool, shape (k,)
        Parameters not at a bound.
    """
    params = np.asarray(params, dtype=float)
    bounds = np.asarray(model.bounds)
    steps = np.where(np.arange(params.size) < 2, 1e-4 * np.maximum(np.abs(params), 0.05), 1e-3 * model.scales)
    free = (params - steps > bounds[:, 0]) & (params + steps < bounds[:, 1])
    free[:2] = True
    index = np.flatnonzero(free)
    hess = _hessian(model, params, index, steps[index])
    cov = np.full((params.size, params.size), np.nan)
    w, v = np.linalg.eigh(-hess)
    if np.any(w <= 0):
        core = -hess[:2, :2]
        # on a search bound f_h or xi_h is no estimate and the likelihood need not be curved there: the
        # regularised inverse below gives it an sd as wide as the record leaves it (said "not determined")
        if np.any(np.linalg.eigvalsh(core) <= 0) and not model.person_at_bound(params):
            raise FitError("the likelihood is not curved in f_h and xi_h at the estimate (information not positive "
                           "definite): the record does not determine them; use a longer record or a per-cycle "
                           "estimator (--estimator ekf)")
        w = np.maximum(w, w.max() * 1e-10)
    inverse = (v / w) @ v.T
    if cov_type == "robust":
        inverse[:2, :2] = _robust_core(model, params, index, -hess)
    cov[np.ix_(index, index)] = inverse
    return cov, free


def _robust_core(model, params, index, info):
    """Cycle-clustered sandwich covariance of ``(f_h, xi_h)`` with the other parameters profiled out.

    Effective information ``I* = I_ff - I_fn I_nn^-1 I_nf`` and effective
    scores ``s* = s_f - I_fn I_nn^-1 s_n`` summed per force cycle;
    ``cov = I*^-1 (sum_j s*_j s*_j') I*^-1``.
    """
    per_cycle = _cluster_scores(model, params, index)
    if index.size > 2:
        nuisance = info[2:, 2:]
        w, v = np.linalg.eigh(nuisance)
        w = np.maximum(w, w.max() * 1e-8)
        coupling = info[:2, 2:] @ ((v / w) @ v.T)
        effective_info = info[:2, :2] - coupling @ info[2:, :2]
        effective_scores = per_cycle[:, :2] - per_cycle[:, 2:] @ coupling.T
    else:
        effective_info, effective_scores = info[:2, :2], per_cycle
    bread = np.linalg.inv(effective_info)
    return bread @ (effective_scores.T @ effective_scores) @ bread


def _cluster_scores(model, params, index):
    """Per-cycle sums of the exact efficient scores (:func:`score.score`: ``delta`` and ``sigma^2`` profiled
    out), shape (J, len(index))."""
    from .score import score

    scores = score(model, params)["efficient_per_sample"][:, index]
    cycle = model._phase[0]
    per_cycle = np.zeros((cycle.max() + 1, index.size))
    np.add.at(per_cycle, cycle, scores)
    return per_cycle


def profile_interval(model: RecordModel, params, loglike, which, se, level=0.9):
    """Profile-likelihood interval of ``f_h`` (``which=0``) or ``xi_h`` (``which=1``).

    At each trial value the other parameters are re-maximised (warm start);
    the interval's ends are where twice the fall of the profile likelihood
    equals the chi-square(1) quantile of ``level``, found by bracketing and
    linear interpolation. An end that reaches the search bound is returned as
    the bound (the record does not exclude it).

    Returns
    -------
    tuple of float
        ``(low, high)``.
    """
    target = stats.chi2.ppf(level, 1) / 2.0
    bounds = model.bounds
    lo_bound, hi_bound = bounds[which]
    others = [i for i in range(len(params)) if i != which]
    sub_bounds = [bounds[i] for i in others]
    step = se if np.isfinite(se) and se > 0 else 0.05 * abs(params[which]) + 0.01
    ends = []
    for sign in (-1.0, 1.0):
        warm = np.asarray(params, dtype=float)[others]
        previous_value, previous_drop = params[which], 0.0
        value = params[which]
        found = None
        for k in range(12):
            value = float(np.clip(params[which] + sign * step * (1.2 + 0.6 * k), lo_bound, hi_bound))

            def negative(sub, v=value):
                full = np.empty(len(params))
                full[which] = v
                full[others] = sub
                out = model.loglike(full)
                return -out if np.isfinite(out) else 1e300

            res = optimize.minimize(negative, warm, method="L-BFGS-B", bounds=sub_bounds, options={"maxiter": 60})
            warm = res.x
            drop = loglike + res.fun
            if drop >= target:
                frac = (target - previous_drop) / max(drop - previous_drop, 1e-12)
                found = previous_value + frac * (value - previous_value)
                break
            if value in (lo_bound, hi_bound):
                found = value
                break
            previous_value, previous_drop = value, drop
        ends.append(found if found is not None else value)
    return tuple(ends)


def corrected_timing(model: RecordModel, params) -> CycleTiming:
    """Cycle starts moved by the smoothed phase and rate errors of a model with a phase template.

    The force of cycle ``j`` is ``F(theta + phi_j + rho_j (t - t_mid))`` to first
    order, so its true start is where that corrected phase reaches ``2 pi j``.
    Each boundary is placed from both cycles that meet there and the two
    placements are averaged. Returns the new :class:`CycleTiming`.
    """
    from .statespace import RecordStateSpace

    fitted = model.filter(params)
    smoothed = RecordStateSpace(model, fitted["delta"]).smoothed_state(params)
    cycle = model._phase[0]
    p = model.n_coefficients
    b = model.timing.boundaries
    first = np.flatnonzero(np.r_[True, cycle[1:] != cycle[:-1]])
    phi = np.full(b.size - 1, np.nan)
    rho = np.full(b.size - 1, np.nan)
    nx = model.n_dynamic
    phi[cycle[first]] = smoothed[nx + p, first]
    rho[cycle[first]] = smoothed[nx + 1 + p, first]
    period, middle = np.diff(b), 0.5 * (b[:-1] + b[1:])

    def start_from(j, at):  # where cycle j's corrected phase reaches its own start
        return at - (phi[j] + rho[j] * (at - middle[j])) / (2.0 * np.pi / period[j] + rho[j])

    inner = np.arange(1, b.size - 1)
    placed = np.nanmean(np.vstack([start_from(inner, b[inner]), start_from(inner - 1, b[inner])]), axis=0)
    new = b.copy()
    new[inner] = np.where(np.isfinite(placed), placed, b[inner])
    new[0] = new[1] - (new[2] - new[1])
    new[-1] = new[-2] + (new[-2] - new[-3])
    if np.any(np.diff(new) <= 0):
        return model.timing
    return CycleTiming(new, "model")


def _comparison_row(model, fitted, timing) -> dict:
    """One variation model's fit in ``result.comparison``: its likelihood, AIC, person, and at which timing."""
    return {"variation": model.variation, "timing": timing, "loglike": fitted["loglike"],
            "n_params": len(fitted["params"]), "aic": 2 * len(fitted["params"]) - 2 * fitted["loglike"],
            "converged": fitted["converged"], "on_bound": model.person_at_bound(fitted["params"]),
            "f_h": float(fitted["params"][0]), "xi_h": float(fitted["params"][1])}


def _choose_with_own_timing(model_for, timing, fits, first_best, step) -> tuple:
    """Re-place every variation model's cycle starts with its own fit (:func:`_fit_timing`); keep the lowest AIC.

    The choice is made once each model has placed the cycle starts it likes: the starts are estimated as
    much as ``f_h`` is, by each model. Fitting the losers of the first comparison at the *winner's*
    re-placed starts (the method up to 2026-11-26) chose "smooth" on records of a wandering tempo where
    "independent", at its own starts, ended 50-180 higher in log-likelihood: ``f_h`` -33 % and -21 % with
    intervals that missed the truth (seed 2027, records 27 and 35 of ``person_accuracy.py``; at its own
    starts -6 % and -2 %). Returns ``(model, fitted, rows)``, ``rows`` for ``result.comparison`` (timing
    "re-placed"). The first comparison's winner (``first_best``) is kept when no model finishes off its
    search bounds and converged.

    The choice is made on each model's best quick fit (:data:`QUICK_GAIN`); only the winner is then refitted
    to full precision (:data:`FINAL_GAIN`), and its row carries that fit. On 40 records of five generators
    (``benchmarks/person_fits.py``, seed 77) the quick fits chose as the full-precision ones on all 40; the
    losers' final fits had taken 7 % of the fits' time.
    """
    finished = [_fit_timing(model_for, timing, m.variation, first=(m, f), step=step) for m, f in fits]
    rows = [_comparison_row(m, f, "re-placed") for m, f in finished]
    eligible = [i for i, row in enumerate(rows) if not row["on_bound"] and row["converged"]] or [first_best]
    best = min(eligible, key=lambda i: rows[i]["aic"])
    model, quick = finished[best]
    fitted = fit_model(model, quick["params"])
    step()
    rows[best] = _comparison_row(model, fitted, "re-placed")
    return model, fitted, rows


def _fit_timing(model_for, timing, variation, first=None, step=lambda: None):
    """Fit with a phase template and re-place the cycle starts; returns the best ``(model, fit)`` by likelihood
    (a quick fit: :func:`_choose_with_own_timing` refits the winner to full precision).

    ``first``: the ``(model, fit)`` without phase template at ``timing`` when already made;
    ``step`` is called after each of the ``TIMING_ITERATIONS + 1`` fits (a progress bar).
    """
    base, fitted = first if first is not None else (None, None)
    if base is None:
        base = model_for(timing, variation, None)
        fitted = fit_model(base, quick=True)
    params = fitted["params"]
    best = (base, fitted)
    model = base
    for iteration in range(TIMING_ITERATIONS + 1):
        template = model.filter(params)["delta"][model.n_dynamic:model.n_dynamic + model.n_coefficients]
        model = model_for(timing, variation, template)
        if iteration == 0:
            named = dict(zip(base.param_names, params))

            def start_for(phase, rate):
                values = {**named, "log_var_phase": phase, "log_var_rate": rate}
                return np.array([values[name] for name in model.param_names])

            candidates = [start_for(a, b) for a in PHASE_VARIANCE_STARTS[0] for b in PHASE_VARIANCE_STARTS[1]]
            start = max(candidates, key=model.loglike)
        else:
            start = params
        fitted = fit_model(model, start, quick=True)
        step()
        params = fitted["params"]
        if fitted["loglike"] > best[1]["loglike"]:
            best = (model, fitted)
        if iteration < TIMING_ITERATIONS:
            timing = corrected_timing(model, params)
    return best


def model_error_floor(name: str, f_h: float, variation: str) -> float:
    """The sd :data:`MODEL_ERROR_FLOOR` adds to ``name``'s calibrated one for a fit with ``variation``'s model of
    the force's variation: relative for ``f_h`` (Hz), absolute for ``xi_h``."""
    return MODEL_ERROR_FLOOR[variation][name] * (f_h if name == "f_h" else 1.0)


def wald_interval(estimate, standard_error, level, bounds) -> tuple:
    """Estimate +- z * standard error, cut at the parameter's search bounds.

    A damping ratio cannot be negative, nor ``f_h`` leave its search range: where the
    symmetric interval reaches past a bound, it ends at the bound (the values cut off are
    impossible, so the coverage is unchanged).

    Parameters
    ----------
    estimate, standard_error : float
    level : float
        Confidence level in (0, 1); ``z`` is the standard normal's ``0.5 + level / 2`` quantile.
    bounds : (float, float)
        Lowest and highest possible value.

    Examples
    --------
    >>> wald_interval(0.05, 0.1, 0.9, (1e-3, 3.0))  # doctest: +ELLIPSIS
    (0.001, 0.214...)
    """
    z = stats.norm.ppf(0.5 + level / 2.0)
    low, high = bounds
    return (float(max(low, estimate - z * standard_error)), float(min(high, estimate + z * standard_error)))


def identify_person(record: Record, n_harmonics=4, variation="auto", timing="model", process_noise=False,
                    intervals="calibrated", level=0.9, regressors=(), cov_type="oim", drift=False, check=True,
                    rate=RECORD_RATE, progress=False, effects=(), measured_floor=True):
    """Identify one person's SMD model from a whole bouncing record.

    Parameters
    ----------
    record : Record
        The measurement (``time``, ``force`` in N, ``mass`` in kg).
    n_harmonics : int
        Harmonics ``n`` of the force, Eq. 4.
    variation : {"auto", "independent", "smooth", "random_walk", "both"}
        How the force coefficients vary (:mod:`~smd_statespace.person.model`):
        jumping at every cycle start (``"independent"``), drifting smoothly
        in time (``"smooth"``), a random walk from cycle to cycle
        (``"random_walk"``) or a wandering template plus draws (``"both"``).
        ``"auto"`` (default) fits
        :data:`AUTO_VARIATIONS` at the first cycle timing and keeps the lowest
        AIC among the fits whose ``f_h`` and ``xi_h`` are off their search
        bounds (the list of fits is ``result.comparison``); with
        ``timing="model"`` each model then re-places the cycle starts with
        its own fit and the choice is made again there.
    timing : {"model", "template", "peaks"}
        How the force-cycle boundaries are placed: ``"template"`` and
        ``"peaks"`` as :func:`~smd_statespace.person.timing.estimate_timing`
        places them; ``"model"`` (default) starts from the template
        alignment and then lets the model place them: each cycle gets a
        phase error and a phase-rate error (states of the model, drawn afresh
        every cycle), and the starts are moved by their smoothed values,
        :data:`TIMING_ITERATIONS` times; the fit with the highest likelihood
        is kept.
    process_noise : bool
        Add a white force on the COM with an estimated level.
    intervals : {"calibrated", "wald", "profile"}
        ``"calibrated"`` (default): estimate +- z * standard error, the
        standard errors of ``f_h`` and ``xi_h`` (and of ``k_h``, ``c_h``)
        multiplied by :data:`CALIBRATION`, the intervals widened by
        :data:`MODEL_ERROR_FLOOR`; ``"wald"``: the same from the
        observed information alone (too narrow: docs/person-benchmark.md);
        both cut at the search bounds (:func:`wald_interval`: ``xi_h`` never below 0);
        ``"profile"``: profile-likelihood intervals (measured: about 9 s more
        on a 30 s record; as narrow as the Wald ones).
    level : float
        Confidence level of the intervals.
    regressors : sequence of Regressor
        Effects' signals with unknown coefficients (a constant offset, for an
        imprecise body mass or plate zero, is always included).
    cov_type : {"robust", "oim"}
        Covariance of the estimates (:func:`information`): inverse observed
        information (default) or cycle-clustered sandwich.
    drift : bool
        Let the force coefficients also wander within cycles (a per-sample
        random walk with one estimated variance per harmonic group).
    check : bool
        True (default): refuse a record that is not one person bouncing in
        contact with the plate (:func:`~smd_statespace.diagnostics.applicability.check_bouncing`);
        False: identify anyway, its findings become warnings.
    rate : float or None
        A record sampled at twice this rate (Hz) or faster is low-pass filtered and
        decimated to between ``rate`` and ``2 rate`` before the fit
        (:func:`~smd_statespace.signals.decimate_record`; default
        :data:`~smd_statespace.signals.RECORD_RATE`, the rate the calibration was
        measured at), with the regressors; ``result.notes`` says so. None keeps every sample
        (slower: the likelihood's cost grows with the samples, and the calibrated intervals
        were not measured there).
    progress : bool
        Show a progress bar (tqdm) over the likelihood searches (one per variation model,
        ``TIMING_ITERATIONS + 1`` more for ``timing="model"`` and the winner's final fit, then the
        information matrix):
        a 30 s record takes 7-25 s.
    effects : sequence of Effect or str
        Physical effects added to the person's model (objects, names or
        ``NAME:key=value`` specs, as ``--effect``): the same effects every
        estimator and the simulator use (:mod:`smd_statespace.effects`). The
        person is first identified without them (``result.before``), then with
        them, their parameters estimated jointly with ``f_h`` and ``xi_h``, the
        cycle starts and the variation model chosen again with the effects in
        the model (:func:`~smd_statespace.person.extend.fit_effects`). A bare name
        takes the options its class chooses for the record, as ``diagnose``
        proposes it (a cubic spring's search range scaled to the record's
        displacement).
    measured_floor : bool
        When the record has a ``floor_acc`` column, the person rides the floor it
        measured: the measured floor (``floor_mode``, source "measured": the floor's
        displacement and velocity are known inputs of Eq. 2, no unknown is added) is
        one of ``effects`` unless a ``floor_mode`` is given there or this is False
        (``--no-floor``). Without it, on simulated records of people on a moving
        floor the person came out wrong with an interval that missed the truth on 3
        of 21 (:func:`~smd_statespace.person.extend.record_effects`).

    Returns
    -------
    PersonResult

    Raises
    ------
    NotBouncingError
        The record is not bouncing (contact lost, clipped, not rhythmic, walking) and ``check`` is True.
    CycleError
        No bouncing cycles, or fewer than :data:`MIN_CYCLES`.
    OptionError
        Unknown ``variation``, ``timing``, ``intervals`` or effect, or an effect that needs a
        column the record lacks (``floor_acc``).
    FitError
        The fit does not converge or does not determine ``f_h`` and ``xi_h``.
    """
    from .extend import check_effects, fit_effects, record_effects

    effects_asked = tuple(effects)
    given = record_effects(record, effects_asked, measured_floor)
    effects = check_effects(given, record)  # bad specs and missing columns fail before any fit
    if variation != "auto" and variation not in VARIATIONS:
        raise OptionError(f"variation {variation!r} is not one of: auto, {', '.join(VARIATIONS)}")
    if intervals not in INTERVAL_METHODS:
        raise OptionError(f"intervals {intervals!r} is not one of: {', '.join(INTERVAL_METHODS)}")
    record_warnings = check_bouncing(record).raise_if_refused(override=not check)
    measured_rate = record.fs
    record, factor, values = decimate_record(record, rate, [r.values for r in regressors])
    regressors = [replace(r, values=v) for r, v in zip(regressors, values)]
    notes = decimation_note(measured_rate, record, factor, rate)
    y = record.force / record.mass - G  # Eq. 3
    if timing not in ("model",) + TIMING_METHODS:
        raise OptionError(f"timing {timing!r} is not one of: model, {', '.join(TIMING_METHODS)}")
    first = "template" if timing == "model" else timing
    cycle_timing = estimate_timing(record.time, record.force, n_harmonics, first, source=record.source)
    inside = np.sum((cycle_timing.boundaries > record.time[0]) & (cycle_timing.boundaries < record.time[-1]))
    if inside - 1 < MIN_CYCLES:
        raise CycleError(f"{record.source}: {max(inside - 1, 0)} whole bouncing cycles found; the record-level model "
                         f"needs at least {MIN_CYCLES} to estimate the cycle-to-cycle variation: use a longer record "
                         "or a per-cycle estimator (--estimator ekf)")
    offset = Regressor("offset", np.ones_like(y), "m/s^2", dynamic=False)
    all_regressors = (offset,) + tuple(regressors)
    names = AUTO_VARIATIONS if variation == "auto" else (variation,)

    def model_for(timing_, variation_, template):
        return RecordModel(record.time, y, timing_, n_harmonics, variation_, process_noise, drift=drift,
                           regressors=all_regressors, phase_template=template)

    if cov_type not in ("robust", "oim"):
        raise OptionError(f"cov_type {cov_type!r} is not one of: robust, oim")
    steps = len(names) * (1 + (TIMING_ITERATIONS + 1 if timing == "model" else 0)) + (2 if timing == "model" else 1)
    with tqdm(total=steps, desc="identify (record)", unit="fit", disable=not progress, leave=False) as bar:
        step = bar.update
        # every variation model is fitted at the first cycle timing and compared by AIC there; with
        # timing="model" each then re-places the cycle starts with its own fit, and the choice is made again
        fits = []
        for name in names:
            model = model_for(cycle_timing, name, None)
            fits.append((model, fit_model(model, quick=timing == "model")))
            step()
        comparison = [_comparison_row(m, f, "first") for m, f in fits]
        # a fit with f_h or xi_h on its search bound has not estimated them (a variation model that is
        # too flexible lets the person's resonance imitate a missing effect): it wins only if all do
        eligible = [i for i, row in enumerate(comparison) if not row["on_bound"]] or list(range(len(fits)))
        best = min(eligible, key=lambda i: comparison[i]["aic"])
        model, fitted = fits[best]
        if timing == "model":
            model, fitted, refined = _choose_with_own_timing(model_for, cycle_timing, fits, best, step)
            comparison += refined
        if not fitted["converged"]:
            raise FitError(f"{record.source}: the likelihood search did not converge ({fitted['message']}); try "
                           "--variation independent, a longer record or a per-cycle estimator (--estimator ekf)")
        result = person_result(record, model, fitted, intervals=intervals, level=level, cov_type=cov_type,
                               comparison=comparison, record_warnings=record_warnings, notes=notes)
        step()
    if effects:  # as given: a bare name is configured for the record (extend.configured_for_record)
        result = fit_effects(result, given, intervals=intervals, cov_type=cov_type, progress=progress)
        if len(given) > len(effects_asked):  # the record brought its floor
            result.notes.append(f"the record's floor_acc is in the model (floor_mode, measured: the person rides "
                                f"the floor, no unknown added; likelihood ratio against the person without it "
                                f"{result.effect_test()['lr']:.1f}); --no-floor (measured_floor=False) leaves it out")
    return result


def person_result(record, model, fitted, *, intervals="calibrated", level=0.9, cov_type="oim", comparison=(),
                  record_warnings=(), notes=(), **extra):
    """The :class:`~smd_statespace.person.results.PersonResult` of a fitted record-level model.

    The covariance of the estimates (:func:`information`), the intervals of
    ``f_h`` and ``xi_h`` (calibrated Wald, Wald or profile, see
    :func:`identify_person`) and Wald intervals of the effects' parameters.
    ``extra`` goes to the result (``before``, ``effects``, ``linearisations``, ``settled``).
    """
    from .results import PersonResult

    params = fitted["params"]
    cov, free = information(model, params, cov_type)
    factors = CALIBRATION[model.variation]
    if intervals == "calibrated":
        scale = np.ones(params.size)
        scale[0], scale[1] = factors["f_h"], factors["xi_h"]
        cov = cov * np.outer(scale, scale)
    se = np.sqrt(np.diag(cov))
    interval = {}
    for which, name in enumerate(("f_h", "xi_h")):
        if intervals == "profile":
            interval[name] = profile_interval(model, params, fitted["loglike"], which, se[which], level)
        else:
            # the floor widens the interval, not the sd: the sd says what the record determines
            floor = 0.0 if intervals == "wald" else model_error_floor(name, params[0], model.variation)
            interval[name] = wald_interval(params[which], float(np.hypot(se[which], floor)), level,
                                           model.bounds[which])
    for name in model.effect_parameters:  # the effects' parameters: Wald intervals from the information
        which = model.param_names.index(name)
        interval[name] = (wald_interval(params[which], se[which], level, model.bounds[which])
                          if np.isfinite(se[which]) else tuple(model.bounds[which]))
    method = {"profile": "profile", "wald": f"wald ({cov_type})"}.get(
        intervals, f"calibrated wald ({cov_type}, sds x {factors['f_h']:g}, {factors['xi_h']:g}, "
                   "with a model-error floor; undetermined: the yardstick's width)")
    result = PersonResult(record=record, model=model, params=params, cov=cov, free=free, loglike=fitted["loglike"],
                          intervals=interval, interval_method=method, level=level, comparison=list(comparison),
                          n_evaluations=fitted["n_evaluations"], record_warnings=list(record_warnings),
                          notes=list(notes), **extra)
    if intervals == "calibrated":
        result.narrow_intervals = dict(result.intervals)
        result.intervals.update(honest_intervals(result))
    return result


def honest_intervals(result) -> dict:
    """The calibrated intervals of ``f_h`` and ``xi_h``, widened where the record leaves more open.

    - A parameter the record does not determine (a model that misfits the record
      included: :attr:`PersonResult.misfit <smd_statespace.person.results.PersonResult.misfit>`),
      or whose estimate is an artefact: :func:`undetermined_interval`.
    - ``f_h`` when the variation models the record cannot rule out
      (:meth:`~smd_statespace.person.results.PersonResult.plausible_variations`) disagree
      by more than ``VARIATION_DISAGREEMENT``: the interval spans their estimates too (the
      answer depends on a modelling choice the record does not settle). On a record from
      a generator outside this project, "independent" gave 2.10-2.26 Hz and "smooth"
      2.84-3.69 Hz, 5.2 apart in log-likelihood, for a true 2.45 Hz
      (``../shared/findings/person-unseen-records.md``).
    """
    from .results import VARIATION_DISAGREEMENT

    out = {name: undetermined_interval(result, name) for name in ("f_h", "xi_h")}
    values = [row["f_h"] for row in result.plausible_variations()]
    if values and max(values) > (1.0 + VARIATION_DISAGREEMENT) * min(values):
        low, high = out["f_h"]
        out["f_h"] = (float(min(low, *values)), float(max(high, *values)))
    return out


def undetermined_interval(result, name) -> tuple:
    """The interval of ``f_h`` or ``xi_h`` that says what a record which does not determine it allows.

    A determined parameter keeps its interval. One the record does not determine
    (:meth:`PersonResult.determined <smd_statespace.person.results.PersonResult.determined>`)
    gets at least the width of its yardstick: ``estimate +- z * PRIOR_SD`` (the
    article's uniform range, ``f_h`` 1-4 Hz, ``xi_h`` 0-1, as a standard deviation:
    what the record says is then no more than what was known before it), cut at the
    search bounds. Where the estimate is an artefact, not a poorly determined value
    (``f_h`` or ``xi_h`` on a search bound, ``xi_h`` over-damped, a resonance standing
    in for a force harmonic: :meth:`~smd_statespace.person.results.PersonResult.artefact`),
    the interval is the whole search range.

    Measured before the rule (docs/person-benchmark-generators.md, 60 records): of the 14
    calibrated ``f_h`` intervals that missed the truth, 8 belonged to estimates already
    flagged as not determined (3 smooth-drift records, 5 pulse trains).
    """
    from .results import PRIOR_SD

    which = {"f_h": 0, "xi_h": 1}[name]
    low, high = result.intervals[name]
    bounds = result.model.bounds[which]
    if result.artefact(name):
        return float(bounds[0]), float(bounds[1])
    if result.determined(name):
        return low, high
    wide = wald_interval(result.params[which], PRIOR_SD[name], result.level, bounds)
    return min(low, wide[0]), max(high, wide[1])

