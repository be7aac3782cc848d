"""The maximum-likelihood search of the record-level model and its cycle-start re-placement.

- :func:`fit_model`: the profile likelihood of a :class:`~smd_statespace.person.model.RecordModel`
  maximised by Fisher scoring with its exact gradient (:mod:`smd_statespace.person.score`), from a
  coarse start over :data:`START_F_H` x :data:`START_XI_H` or a given one;
- :func:`information`: the observed information (differences of the exact gradient) or its robust
  sandwich (the profile-likelihood intervals: :mod:`~smd_statespace.person.profile`);
- :func:`corrected_timing`, :func:`fit_timing`, :func:`choose_with_own_timing`: the cycle starts
  re-placed from a model's own smoothed phase and rate errors, and the variation model chosen once
  each has placed them.

:func:`~smd_statespace.person.fit.identify_person` drives these; they know nothing of records,
effects or results.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize

from ..errors import OptionError, SMDInputError
from .comparison import aic, comparison_row
from .model import PERSON, RecordModel
from .threads import spare_best, thread_map
from .timing import CycleTiming

__all__ = ["COV_TYPES", "WIDER_SANDWICH", "FitError", "fit_model", "information", "corrected_timing", "fit_timing",
           "choose_with_own_timing"]


START_F_H = (1.2, 1.7, 2.3, 3.0, 3.9, 5.0)
"""Starting values of ``f_h`` (Hz) of the coarse search."""


START_XI_H = (0.15, 0.45)
"""Starting values of ``xi_h`` of the coarse search."""


FIT_METHODS = ("scoring", "lbfgs", "lbfgs-difference")
"""Search methods of :func:`fit_model`."""


QUICK_GAIN = 1e-3
"""Stop rule of the intermediate fits (log-likelihood units gained by the last step)."""

FINAL_GAIN = 1e-5
"""Stop rule of the final fit (log-likelihood units gained by the last step)."""

SCORING_STEPS = 30
"""Most Fisher-scoring steps of a search before L-BFGS-B (exact gradient) finishes it from where scoring stopped.

Scoring converges in 3-21 steps where the profile's expected information is a good model of the likelihood; past
that it crawls along a ridge (a nonlinear effect's linearised likelihood: a cubic spring's final fit gained 0.08 in
100 steps, 6.1 s, where 30 steps and L-BFGS-B reached the same log-likelihood to 1e-4 in 2.7 s)."""


RIDGE_COSINE = 0.9
"""A scoring step whose direction is within this cosine of the last one's is stretched (:func:`_stretched`)."""

STRETCHES = 3
"""Up to how many doublings :func:`_stretched` tries a step at (2, 4 and 8 times its length)."""

TIMING_ITERATIONS = 3
"""Re-placements of the cycle starts from the model's own phase and rate errors (``timing="model"``)."""


PHASE_VARIANCE_STARTS = ((-8.0, -5.0, -2.0, 1.0), (-6.0, -3.0, 0.0, 3.0))
"""Starting log variance ratios of the phase and rate errors tried before the first timing fit."""


COV_TYPES = ("oim_or_robust", "oim", "robust")
"""Covariances of the estimates :func:`information` computes."""

WIDER_SANDWICH = "oim_or_robust"
"""The covariance :func:`~smd_statespace.person.fit.identify_person` gives by default: the observed information's,
``f_h``'s and ``xi_h``'s sds raised to the cycle-clustered sandwich's where that is wider.

The sandwich measures the spread of the scores the record actually has: where the model is right it agrees
with the information (on 40 clean records, 30 s at 100 Hz, 1 % BW noise, seed 4346 of
``benchmarks/lab_records.py``: sandwich / information sd of ``f_h`` 0.87-1.14, median 1.04), where it misses
something the innovations carry it is wider (on the same people's lab exports, quieter and with a lab's
artefacts: median 1.9, up to 3.6). The three confident misses of those lab records (``f_h`` +10 to +13 %, an
interval 7-10 % wide) were among the widest (2.2-2.7). A fixed factor for trimmed records (1.22 on ``f_h``'s sd,
measured on seed 4343) widened every lab answer alike and still missed them: the 90th percentile of
``|estimate - truth| / sd`` over 1.645 was 1.61 on seed 4346's lab records with it, 0.87 with this rule and no
such factor (clean records: 0.82 and 0.80); coverage 92.5 -> 100 %, confident misses 3 -> 0, ``f_h`` determined
on 20 -> 15 of 40 (clean records 24 -> 23)."""


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
    quick : bool or float
        Looser stop rule (intermediate fits): :data:`QUICK_GAIN` (or the gain
        given) instead of :data:`FINAL_GAIN` for ``"scoring"``, a relative change
        of 1e-7 of the likelihood for the L-BFGS-B methods.
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
        gain = FINAL_GAIN if not quick else QUICK_GAIN if quick is True else float(quick)
        params, loglike, n, converged, message = _scoring(model, start * scales, gain)
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


def _scoring(model: RecordModel, start, gain, max_iterations=SCORING_STEPS) -> tuple:
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
    fewer derivative passes: ``benchmarks/person_fits.py``). A step that points
    the way the last one did (within :data:`RIDGE_COSINE`) is stretched while
    the likelihood rises (:func:`_stretched`): on a ridge the expected
    information makes every step short.

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
    damping, previous = 1e-3, None
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
            if previous is not None and _cosine(trial - x, previous) > RIDGE_COSINE:  # creeping along a ridge
                trial, filtered, tried = _stretched(model, x, trial, filtered, low, high)
                count += tried
            out = score(model, trial * scales, fitted=filtered)
            if np.all(np.isfinite(out["gradient"])):
                accepted = (trial, out)
                break
            damping *= 10.0
        if accepted is None:
            return x * scales, current["loglike"], count, True, "no step gains: a maximum"
        previous = accepted[0] - x
        x, current = accepted
        damping = max(damping / 10.0, 1e-6)
    return x * scales, current["loglike"], count, False, f"no convergence in {max_iterations} steps"


def _cosine(a, b) -> float:
    """Cosine of the angle between two steps (0 when either is zero)."""
    norms = float(np.linalg.norm(a) * np.linalg.norm(b))
    return float(a @ b) / norms if norms > 0.0 else 0.0


def _stretched(model: RecordModel, x, trial, filtered, low, high) -> tuple:
    """The accepted ``trial`` (scaled units, from ``x``) stretched along its step while the likelihood rises.

    Where the expected information curves more than the likelihood does (a ridge the variation model leaves
    flat), each scoring step is short and the next one points the same way: the "smooth" model's search of
    one record crept 30 steps along such a ridge, ``f_h`` 3.10 -> 3.54 Hz gaining 0.02-0.04 a step. The step is
    tried again at twice its length, then four times, up to ``2 ** STRETCHES`` (:data:`STRETCHES`; clipped to the
    bounds), one likelihood each, for as long as each gains over the one before (a pattern move, Hooke and
    Jeeves 1961). Returns ``(trial, filtered, likelihoods computed)``.
    """
    step = trial - x
    tried = 0
    for factor in 2.0 ** np.arange(1, STRETCHES + 1):
        longer = np.clip(x + factor * step, low, high)
        if np.array_equal(longer, trial):  # every parameter on a bound: no farther
            break
        out = model.filter(longer * model.scales)
        tried += 1
        if not (np.isfinite(out["loglike"]) and out["loglike"] > filtered["loglike"]):
            break
        trial, filtered = longer, out
    return trial, filtered, tried


def _hessian(model: RecordModel, params, index, steps, threads=1, central=False):
    """Observed information's Hessian over ``index`` (the other parameters held), symmetrised: forward differences
    of the exact gradient (:func:`score.score`; ``len(index) + 1`` passes, in up to ``threads`` threads), or
    central ones (``2 len(index)``, the default up to 2026-11-26: the same sds of ``f_h`` and ``xi_h`` within 1.3e-4
    of their size on nine 30 s records), which cancel the gradient's own rounding (:func:`information`)."""
    from .score import score

    def gradient(shift):  # the passes do not depend on each other: in threads
        point = params.copy()
        if shift[0] >= 0:
            point[index[shift[0]]] += shift[1] * steps[shift[0]]
        return score(model, point)["gradient"][index]

    shifts = [(column, 1.0) for column in range(index.size)]
    shifts += [(column, -1.0) for column in range(index.size)] if central else [(-1, 0.0)]
    passes = thread_map(gradient, shifts, threads)
    minus = np.column_stack(passes[index.size:]) if central else passes[-1][:, None]
    hess = (np.column_stack(passes[:index.size]) - minus) / ((2.0 if central else 1.0) * np.asarray(steps)[None, :])
    return 0.5 * (hess + hess.T)


def information(model: RecordModel, params, cov_type="robust", threads=1) -> tuple:
    """Covariance of the estimates; parameters at a bound are held fixed.

    Parameters
    ----------
    model : RecordModel
    params : ndarray
        The estimate.
    cov_type : {"robust", "oim", "oim_or_robust"}
        ``"oim"``: the inverse observed information (the Hessian of the
        profile likelihood by forward differences of its exact gradient,
        :func:`_hessian`), right when the model is right. ``"robust"``
        (default): the sandwich ``H^-1 B H^-1`` with ``B`` the outer product
        of the per-cycle sums of the efficient scores (the template, initial
        state and scale profiled out; clustered by force cycle), which stays
        right when the innovations are not what the model says (heavy tails,
        the cycle timing's own error); never narrower than needed for the
        measured spread of the scores. ``"oim_or_robust"``: the observed
        information's, with the sds of ``f_h`` and ``xi_h`` raised to the
        sandwich's where that is wider (:data:`WIDER_SANDWICH`).
    threads : int
        The Hessian's derivative passes run in up to this many threads (the same numbers).

    Returns
    -------
    cov : ndarray, shape (k, k)
        NaN rows and columns for parameters at a bound.
    free : ndarray of bool, shape (k,)
        Parameters not at a bound.
    """
    params = np.asarray(params, dtype=float)
    n_person = len(PERSON)
    steps, free = _differencing(model, params)
    index = np.flatnonzero(free)
    hess = _hessian(model, params, index, steps[index], threads)
    if np.any(np.linalg.eigvalsh(-hess[:n_person, :n_person]) <= 0):  # a forward step's rounding, or no curvature
        hess = _hessian(model, params, index, steps[index], threads, central=True)
    cov = np.full((params.size, params.size), np.nan)
    w, v = np.linalg.eigh(-hess)
    if np.any(w <= 0):
        core = -hess[:n_person, :n_person]
        # on a search bound f_h or xi_h is no estimate and the likelihood need not be curved there: the
        # regularised inverse below gives it an sd as wide as the record leaves it (said "not determined")
        if np.any(np.linalg.eigvalsh(core) <= 0) and not model.person_at_bound(params):
            raise FitError("the likelihood is not curved in f_h and xi_h at the estimate (information not positive "
                           "definite): the record does not determine them; use a longer record or a per-cycle "
                           "estimator (--estimator ekf)")
        w = np.maximum(w, w.max() * 1e-10)
    inverse = (v / w) @ v.T
    if cov_type == "robust":
        inverse[:n_person, :n_person] = _robust_core(model, params, index, -hess)
    elif cov_type == "oim_or_robust":
        ratio = np.sqrt(np.diag(_robust_core(model, params, index, -hess)) / np.diag(inverse)[:n_person])
        raise_by = np.ones(index.size)
        raise_by[:n_person] = np.maximum(np.nan_to_num(ratio, nan=1.0), 1.0)
        inverse = inverse * np.outer(raise_by, raise_by)  # a congruence: still a covariance
    cov[np.ix_(index, index)] = inverse
    return cov, free


def _differencing(model: RecordModel, params) -> tuple:
    """``(steps, free)``: the Hessian's difference steps and the parameters off their bounds by more than a step."""
    bounds, n_person = np.asarray(model.bounds), len(PERSON)  # f_h, xi_h lead: always free, steps relative to size
    steps = np.where(np.arange(params.size) < n_person, 1e-4 * np.maximum(np.abs(params), 0.05), 1e-3 * model.scales)
    free = (params - steps > bounds[:, 0]) & (params + steps < bounds[:, 1])
    free[:n_person] = True
    return steps, free


def _robust_core(model, params, index, info, keep=range(len(PERSON))):
    """Cycle-clustered sandwich covariance of the parameters ``keep`` (positions in ``index``; default ``(f_h,
    xi_h)``) with the others profiled out: effective information ``I* = I_ff - I_fn I_nn^-1 I_nf`` and effective
    scores ``s* = s_f - I_fn I_nn^-1 s_n`` summed per force cycle; ``cov = I*^-1 (sum_j s*_j s*_j') I*^-1``."""
    from .score import profile_out

    per_cycle = _cluster_scores(model, params, index)
    others = [i for i in range(index.size) if i not in keep]
    effective_info, effective_scores = profile_out(info, per_cycle, keep, others, 1e-8)
    bread = np.linalg.inv(effective_info)
    return bread @ (effective_scores.T @ effective_scores) @ bread


def _cluster_scores(model, params, index):
    """Per-cycle sums of the exact efficient scores (:func:`score.score`: ``delta`` and ``sigma^2`` profiled
    out), shape (J, len(index))."""
    from .score import cycle_sums, score

    return cycle_sums(model, score(model, params)["efficient_per_sample"][:, index])


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


def choose_with_own_timing(model_for, timing, fits, first_best, step, suspect=(), threads=1) -> tuple:
    """Re-place every variation model's cycle starts with its own fit (:func:`fit_timing`); keep the lowest AIC.

    The choice is made once each model has placed the cycle starts it likes: the starts are estimated as
    much as ``f_h`` is, by each model. Fitting the losers of the first comparison at the *winner's*
    re-placed starts (the method up to 2026-11-26) chose "smooth" on records of a wandering tempo where
    "independent", at its own starts, ended 50-180 higher in log-likelihood: ``f_h`` -33 % and -21 % with
    intervals that missed the truth (seed 2027, records 27 and 35 of ``person_accuracy.py``; at its own
    starts -6 % and -2 %). Returns ``(model, fitted, rows)``, ``rows`` for ``result.comparison`` (timing
    "re-placed"). The first comparison's winner (``first_best``) is kept when no model finishes off its
    search bounds and converged. A model whose fit at the first timing sat on a search bound is chosen only
    if every model did: on quiet lab records (noise under 0.2 % of body weight, seed 4346 of
    ``benchmarks/lab_records.py``) "smooth" ran to ``f_h`` = 6 Hz at the first timing, came back to 5.99 and
    4.46 Hz at its re-placed starts with a force variance thousands of times the noise's, and won by AIC:
    ``f_h`` +100 % and +60 %, intervals that missed (truth 2.99 and 2.79 Hz). The variation models named in
    ``suspect`` count as having sat on a bound at the first timing whatever their fits in ``fits`` did (those
    the person's own fit ran onto a bound, when a floor is added: :func:`~smd_statespace.person.extend.fit_effects`),
    and so does a model whose re-placements ran onto a bound (:func:`fit_timing`, which then stops re-placing).

    The choice is made on each model's best quick fit (:data:`QUICK_GAIN`); only the winner is then refitted
    to full precision (:data:`FINAL_GAIN`), and its row carries that fit. On 40 records of five generators
    (``benchmarks/person_fits.py``, seed 77) the quick fits chose as the full-precision ones on all 40; the
    losers' final fits had taken 7 % of the fits' time.

    The models re-place their starts side by side, one fit each at a time, in up to ``threads`` threads
    (:func:`~smd_statespace.person.threads.thread_map`; the same results in any number). From the first
    re-placement on, a model whose best fit is more than :data:`BEHIND` below the best model's (half
    their AIC difference), that one off its bounds and not suspect, stops re-placing (:func:`_left_behind`).
    It is taken up again, and every model finishes as before, when the model it was behind ends on a bound
    or is not the one chosen.
    """
    chains = [_Chain(_replacements(model_for, timing, fit[0].variation, fit, step)) for fit in fits]
    clean = [not fit[0].person_at_bound(fit[1]["params"]) and fit[0].variation not in suspect for fit in fits]
    stopped, leader = [], None
    for rounds in range(1, TIMING_ITERATIONS + 2):
        thread_map(_Chain.advance, [c for c in chains if not c.finished and c not in stopped], threads)
        if rounds >= 2 and not stopped:  # from the first re-placement on
            leader, stopped = _left_behind(chains, clean)
    model, fitted, rows, best = _choose(chains, clean, first_best)
    if stopped and (chains[best] is not leader or leader.ran_onto_bound or rows[best].on_bound):
        thread_map(_Chain.finish, stopped, threads)  # every model's re-placements, as without the stop
        model, fitted, rows, best = _choose(chains, clean, first_best)
    step(sum(chain.remaining for chain in stopped))  # the fits not made
    fitted = fit_model(model, fitted["params"])
    step()
    rows[best] = comparison_row(model, fitted, "re-placed")
    return model, fitted, rows


BEHIND = 50.0
"""Log-likelihood (half the AIC difference) by which a variation model's best fit, from the cycle starts'
first re-placement on, trails the best model's when it stops re-placing (:func:`choose_with_own_timing`).

On 120 records of five generators (``benchmarks/person_fits.py``, seeds 77-79) no model trailing by more than 15
there came back to be chosen (before any re-placement, models trailing by up to 194 did: a wandering tempo that
the re-placed starts follow). At 50 the loser stopped early on 87 of the 120, saving 11 % of the fits' time."""


def _left_behind(chains, clean) -> tuple:
    """``(leader, chains to stop)``: the chain of the best fit so far among the models whose fits are all off
    their bounds and that are not suspect, and those whose best trails it by more than :data:`BEHIND`."""
    candidates = [chain for chain, ok in zip(chains, clean) if ok and not chain.ran_onto_bound
                  and chain.best[1]["converged"]]
    leader = min(candidates, key=lambda chain: aic(chain.best[1]), default=None)
    return leader, [chain for chain in chains if leader is not None and not chain.finished and chain is not leader
                    and aic(chain.best[1]) - aic(leader.best[1]) > 2 * BEHIND]


def _choose(chains, clean, first_best) -> tuple:
    """``(model, quick fit, rows, index)`` of the variation model chosen among the chains' best quick fits;
    ``clean``: per chain, its first fit off the bounds and its model not suspect."""
    finished = [chain.best for chain in chains]
    rows = [comparison_row(m, f, "re-placed") for m, f in finished]
    inside = [i for i, row in enumerate(rows) if not row.on_bound and row.converged]
    # a model that ran onto a bound at the first timing is suspect even when the re-placed starts bring it in
    never_on_bound = [i for i in inside if clean[i] and not chains[i].ran_onto_bound]
    eligible = never_on_bound or inside or [first_best]
    best = min(eligible, key=lambda i: rows[i].aic)
    return (*finished[best], rows, best)


class _Chain:
    """One variation model re-placing its cycle starts (:func:`_replacements`), advanced one fit at a time."""

    def __init__(self, fits):
        self._fits, self.best, self.ran_onto_bound, self.finished, self.remaining = fits, None, False, False, 0

    def advance(self):
        """Its next fit (and the re-placement after it); ``best``: its best ``(model, fit)`` so far."""
        try:
            self.best, self.remaining = next(self._fits)
        except StopIteration as stop:
            self.best, self.ran_onto_bound = stop.value
            self.finished, self.remaining = True, 0
        return self

    def finish(self):
        """Every fit it has left."""
        while not self.finished:
            self.advance()
        return self


def fit_timing(model_for, timing, variation, first=None, step=lambda *_: None):
    """Fit with a phase template and re-place the cycle starts; returns the best ``(model, fit)`` by likelihood
    (a quick fit: :func:`choose_with_own_timing` refits the winner to full precision) and whether a fit ran onto a
    search bound of ``f_h`` or ``xi_h``.

    A fit on such a bound ends the re-placements: the model has not estimated the person there, and
    :func:`choose_with_own_timing` sets it aside as it sets aside one whose first fit did. (On a jumps
    record the "smooth" model's second re-placement ran to ``xi_h`` = 3; its third took 17 more scoring
    steps to stay there.)

    ``first``: the ``(model, fit)`` without phase template at ``timing`` when already made;
    ``step`` is called after each of the ``TIMING_ITERATIONS + 1`` fits (a progress bar; with the
    number of fits skipped when the re-placements end early).
    """
    chain = _Chain(_replacements(model_for, timing, variation, first, step)).finish()
    return chain.best + (chain.ran_onto_bound,)


def _replacements(model_for, timing, variation, first, step):
    """:func:`fit_timing` as a generator: after each fit but the last, yields the best ``(model, fit)`` so far
    and the fits left; returns ``(best, whether a fit ran onto a bound)``."""
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
            named = base.unpack(params)

            def start_for(phase, rate):
                return model.pack({**named, "log_var_phase": phase, "log_var_rate": rate})

            candidates = [start_for(a, b) for a in PHASE_VARIANCE_STARTS[0] for b in PHASE_VARIANCE_STARTS[1]]
            start = spare_best(model.loglike, candidates)  # their likelihoods half in an idle thread
        else:
            start = params
        fitted = fit_model(model, start, quick=True)
        step()
        params = fitted["params"]
        if fitted["loglike"] > best[1]["loglike"]:
            best = (model, fitted)
        if model.person_at_bound(params):
            step(TIMING_ITERATIONS - iteration)
            return best, True
        if iteration < TIMING_ITERATIONS:
            yield best, TIMING_ITERATIONS - iteration
            timing = corrected_timing(model, params)
    return best, False
