"""Screen a library of candidate effects by score (Rao, Lagrange-multiplier) tests at the fitted person: no fit.

``diagnose`` fits the person with each candidate effect and compares likelihoods: a fit per candidate. A
*score test* asks the same question at the fit that already exists: with the candidate's parameter ``c`` at 0
the model is the fitted person, and the slope of the log-likelihood in ``c`` there, against its own sd, says
whether the record pulls ``c`` away from 0 (Rao 1948; Engle 1984, *Handbook of Econometrics* II, ch. 13). The
exact gradient (:func:`~smd_statespace.person.score.score`, one pass of the Kalman filter's forward
sensitivities) gives it, for every candidate, at the cost of one derivative pass each.

For the candidate's coefficient ``c`` (index ``j``) and the person's free parameters ``theta`` (those not on a
search bound) with the template, the initial state and the noise scale profiled out:

    LM = g_j^2 / (I_jj - I_jt I_tt^-1 I_tj)

with ``g`` the gradient at ``c = 0`` and ``I`` the profile information (:func:`score`'s
``profile_information``); asymptotically chi-square(1) under "no such effect". The *robust* version replaces
the denominator by the cycle-clustered sum of squares of the efficient scores ``s_j - I_jt I_tt^-1 s_t``
summed per bouncing cycle (White 1982; Wooldridge 1990), centred on their mean (a t-test across cycles), which
stays calibrated when the innovations are correlated within a cycle or heavy-tailed; it is the one
:func:`screen` ranks by. Over a library the p-values are adjusted by Holm's step-down method, so the chance of
any false alarm on a record without a missing effect stays at ``alpha`` however long the library.

The score is a slope at ``c = 0``, and some terms show their effect only away from it: a spring stiffer on one
side (``|u|``) linearised about the path of the person without it is nearly a change of stiffness, so its
score is small (robust LM 13 on a record where its fit gives a likelihood ratio of 1021, ranked sixth of nine),
and only when the model is linearised again about its own path does the asymmetry appear. So the terms the
score test does not rule out are *tested and ranked* by a quick fit (:func:`quick_ratio`: one search at the person's
variation and cycle starts, a nonlinear term linearised once more about its own path, about a second each);
the score test only pre-filters them (a term it rules out is not fitted), the quick fits' likelihood ratios,
scaled for misspecification (:mod:`~smd_statespace.person.robust`: divided by how much the likelihood
overstates the evidence where the rest of the model is wrong) and adjusted by Holm over the whole library,
decide which are fitted.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pandas as pd
from scipy import stats

from ..effects.generic import TERMS, GenericTerm, label
from ..errors import SMDInputError
from .breaks import fitted_span, located_step
from .detection import detection_limits
from .extend import at_zero, model_on_top
from .robust import robust_scale
from .score import cycle_sums, profile_out, score
from .search import fit_model
from .supremum import log_p_value, scan_trim
from .threads import thread_map

__all__ = ["STEPS", "PREFILTER", "RELINEARISED", "CHANGE_ALPHA", "TIME_KINDS", "generic_library", "score_test",
           "score_tests", "quick_ratio", "screen", "holm", "time_change"]

STEPS = (1.0 / 3.0, 0.5, 2.0 / 3.0)
"""Where the library's steps in time are, as fractions of the record (one term each: a step elsewhere is
found, less strongly, by the nearest)."""

PREFILTER = 0.05
"""A term whose robust score p-value (unadjusted) is below this gets a quick fit in :func:`screen`."""

RELINEARISED = 1
"""How many times :func:`quick_ratio` linearises a nonlinear term again about its quick fit's own path."""


TIME_KINDS = ("f_drift", "f_step", "xi_drift", "xi_step")
"""The generic terms of a person who changes during the record (:func:`time_change`)."""

CHANGE_ALPHA = 0.01
"""Family-wise level of :func:`time_change`'s score tests (Holm over the time terms).

Measured on lab-shaped records (``simulate_lab_record``, 3 people): clean people, smallest robust p-value over the
8 time terms 0.024-0.31 (Holm 0.19 or more); ``f_h`` drifting or stepping 8 % over the bout, 3e-9 to 3e-5 on a term
of ``f_h``; a force that fades by 30 % (``tire``), 9e-10 to 3e-7 on a term of ``xi_h``. The halves' test
(:func:`~smd_statespace.person.change.change_test`) named none of these 9 changes. On ``benchmarks/lab_records.py``
(seed 4343, 16 records a row): changes of ``f_h`` by 8-20 % named on 9 of 16 (0 by the halves), none of 32
stationary people said to change; 4 of the 16 lab exports, whose forces fade by 3-26 %, have a ``xi_h`` term found
("the person or the force changes"). On the wider people of ``LabRanges`` (seed 4344) 4 of 32 stationary people
had an ``f_h`` term found, all with ``f_h`` not determined (``benchmarks/results/lab_records_time_change.md``)."""


def generic_library(result, kinds=None, scan: bool = False, threads: int = 1) -> list:
    """Every generic term (:data:`~smd_statespace.effects.generic.TERMS`, or those in ``kinds``) scaled to the
    record of the fitted ``result``: the RMS compression and rate its person predicts, and its fitted span's
    start and length; a step at each of :data:`STEPS`, or with ``scan`` one step of each kind at the time a
    scan of every sample finds (:func:`~smd_statespace.person.breaks.located_step`: a step placed a fraction of
    a cycle from the truth is found only in part). The scans (of ``f_step`` and ``xi_step``) run in up to
    ``threads`` threads, with the same terms."""
    kinds = list(TERMS if kinds is None else kinds)
    scales = {}
    if any(TERMS[kind][0] != "time" for kind in kinds):  # the path scales the terms in u and u'
        rms = np.sqrt(np.mean(result.predicted_path()[:, :2] ** 2, axis=0))
        scales = {"restoring": float(rms[0]), "damping": float(rms[1])}
    time = result.model.time
    start, length = fitted_span(time)

    def scanned(kind):
        try:
            return located_step(result, kind)
        except (SMDInputError, ArithmeticError, np.linalg.LinAlgError, ValueError):
            return None  # a record the scan cannot take: the steps at fixed times

    steps = [kind for kind in kinds if scan and TERMS[kind][0] == "time" and kind.endswith("step")]
    located = dict(zip(steps, thread_map(scanned, steps, threads)))
    out = []
    for kind in kinds:
        family = TERMS[kind][0]
        if located.get(kind) is not None:
            out.append(located[kind])
        elif family == "time":
            out += [GenericTerm(kind, scale=length, start=start, at=at)
                    for at in (STEPS if kind.endswith("step") else (0.5,))]
        else:
            out.append(GenericTerm(kind, scale=max(scales[family], 1e-9)))
    return out


def score_test(result, effect) -> dict:
    """The score test of one-parameter ``effect`` at the fitted ``result`` (a fit without it).

    Returns
    -------
    dict
        ``gradient`` (d loglike / d c at 0), ``lm`` and ``p`` (chi-square(1), from the profile information),
        ``lm_robust`` and ``p_robust`` (cycle-clustered), ``sd_robust`` (the coefficient's cycle-clustered sd at
        ``c = 0``: :mod:`~smd_statespace.person.detection`), ``loglike`` (the model with ``c = 0``: the fitted
        person's, a check), ``parameter`` (the coefficient's name), ``cycle_scores`` (the efficient score summed
        per bouncing cycle, shape (J,): ``lm_robust`` is the squared one-sample t statistic of their mean).
    """
    model, params, j = at_zero(result, effect)
    return _test_at(model, params, score(model, params), j, [j])


def score_tests(result, effects, threads: int = 1) -> list:
    """:func:`score_test` of every effect of ``effects`` (in their order), effects sharing derivative passes.

    At ``c = 0`` for every candidate the model with several of them is the fitted person, and the slope and
    information of each coefficient there are those of the model with that candidate alone: one derivative
    pass of the model with them all gives every test. Candidates are put together where their coefficients have
    different names and they keep the person's harmonics and states (the steps of one kind at several times share
    a name: they go to separate passes), so the library of 15 terms takes three passes instead of 15 (on a 30 s
    record 0.77 s against 1.60 s one by one: a pass's cost grows with its parameters). The passes run in up to
    ``threads`` threads. The same numbers as :func:`score_test` one by one, to rounding (a test).
    """
    effects = list(effects)
    placed = [at_zero(result, effect) for effect in effects]
    names = [model.param_names[j] for model, _, j in placed]
    batches = []
    for i, (model, _, _) in enumerate(placed):
        shape = (model.n_harmonics, model.n_dynamic)  # a candidate that adds states or harmonics goes alone
        alone = shape != (result.model.n_harmonics, result.model.n_dynamic)
        batch = next((b for b in batches if not alone and b["shape"] == shape and names[i] not in b["names"]), None)
        if batch is None:
            batches.append(batch := {"shape": None if alone else shape, "names": set(), "members": []})
        batch["names"].add(names[i])
        batch["members"].append(i)

    def run(batch) -> list:
        members = batch["members"]
        if len(members) == 1:
            model, params, j = placed[members[0]]
            return [_test_at(model, params, score(model, params), j, [j])]
        model = model_on_top(result, [effects[i] for i in members])
        named = {**dict(zip(placed[members[0]][0].param_names, placed[members[0]][1])),
                 **{names[i]: 0.0 for i in members}}
        params = np.array([named.get(name, 0.0) for name in model.param_names], dtype=float)
        added = [model.position(names[i]) for i in members]
        out = score(model, params)
        return [_test_at(model, params, out, j, added) for j in added]

    found = thread_map(run, batches, threads)
    tests = [None] * len(effects)
    for batch, rows in zip(batches, found):
        for i, row in zip(batch["members"], rows):
            tests[i] = row
    return tests


def _test_at(model, params, out, j, added) -> dict:
    """The score test of coefficient ``j`` from the derivative pass ``out`` of ``model`` at ``params`` (every
    coefficient of ``added`` at 0; the person's free parameters profiled out, the other candidates left out)."""
    free = [i for i in range(params.size) if i not in added and not model.at_bound(params, i)]
    info, scores = profile_out(out["profile_information"], out["efficient_per_sample"], [j], free, 1e-10)
    efficient_info, scores = float(info[0, 0]), scores[:, 0]
    gradient = float(out["gradient"][j])
    per_cycle = cycle_sums(model, scores)
    lm = gradient**2 / efficient_info if efficient_info > 0 else float("nan")
    # centred: under "no such effect" the cycles' scores have mean 0 and this is the usual clustered variance; where
    # the effect is there their mean is not 0, and the uncentred sum of squares would count it as noise (the
    # statistic is then at most the number of cycles). On a lab export whose f_h steps 16 %, the steps tested
    # 80 ms and 1.5 s either side of it scored 13 and 38 uncentred, 17 and 100-105 centred
    cycles = per_cycle.size
    spread = float(np.sum((per_cycle - per_cycle.mean()) ** 2)) * cycles / max(cycles - 1, 1)
    lm_robust = float(scores.sum()) ** 2 / spread if spread > 0 else float("nan")
    # the coefficient's sd at c = 0 (its one-step estimate is the score over the information): what a test finds
    sd_robust = math.sqrt(spread) / efficient_info if spread > 0 and efficient_info > 0 else float("nan")
    return {"parameter": model.param_names[j], "gradient": gradient, "lm": float(lm), "p": float(stats.chi2.sf(lm, 1)),
            "lm_robust": lm_robust, "p_robust": float(stats.chi2.sf(lm_robust, 1)), "sd_robust": sd_robust,
            "loglike": float(out["loglike"]), "cycle_scores": per_cycle}


def quick_ratio(result, effect) -> dict:
    """The likelihood ratio of a one-parameter ``effect`` from a quick fit: what :func:`screen` tests (chi-square(1),
    Holm over the library) and ranks by; the candidates it passes are then fitted in full and tested again.

    One search (the looser stop rule) from the fitted ``result`` with the coefficient at 0, at its variation
    model and cycle starts; a nonlinear effect, first linearised about ``result``'s path, is linearised
    :data:`RELINEARISED` more time(s) about the fit's own path and searched again. ``diagnose``'s full fit
    settles the path and re-places the starts.

    Returns
    -------
    dict
        ``lr_quick`` (twice the gain of log-likelihood over ``result``), ``estimate`` (the coefficient) and
        ``lr_scale`` (:func:`~smd_statespace.person.robust.robust_scale` at the quick fit: the ratio over it is
        what is tested) and ``end`` (the quick fit's ``(model, params)``, about its last path: where
        :func:`~smd_statespace.person.extend.fit_effects` continues the search, ``start``).
    """
    from .statespace import nominal_path  # statsmodels: imported when an effect is linearised

    model, params, j = at_zero(result, effect)
    fitted = fit_model(model, params, quick=True)
    for _ in range(RELINEARISED if model.approximate else 0):
        model = replace(model, nominal=nominal_path(model, fitted["params"]))
        fitted = fit_model(model, fitted["params"], quick=True)
    return {"lr_quick": float(2.0 * (fitted["loglike"] - result.loglike)), "estimate": float(fitted["params"][j]),
            "lr_scale": robust_scale(model, fitted["params"], [model.param_names[j]]), "end": (model, fitted["params"])}


def holm(p_values) -> np.ndarray:
    """Holm's step-down adjusted p-values (family-wise error): the ``k``-th smallest times ``m - k + 1``,
    made monotone and capped at 1.

    >>> holm([0.01, 0.04, 0.03]).round(3).tolist()
    [0.03, 0.06, 0.06]
    """
    p = np.asarray(p_values, dtype=float)
    order = np.argsort(p)
    adjusted = np.minimum(1.0, np.maximum.accumulate(p[order] * (p.size - np.arange(p.size))))
    out = np.empty_like(adjusted)
    out[order] = adjusted
    return out


def screen(result, effects=None, alpha=None, threads=1, ends=None) -> pd.DataFrame:
    """Score-test every candidate of ``effects`` (default :func:`generic_library`) at ``result``, most
    significant first; with ``alpha``, the terms the score test does not rule out fitted quickly and tested
    by their likelihood ratio over the library.

    With ``alpha``, two stages: every term whose robust score p-value is below :data:`PREFILTER` (unadjusted:
    a term that shows only away from ``c = 0`` has a small score) gets a quick fit (:func:`quick_ratio`); the
    p-value of its likelihood ratio over its misspecification scale (chi-square(1); for a step whose time a scan
    found, the largest of the scan's: :func:`~smd_statespace.person.breaks.log_p_value`) is adjusted by Holm over the
    *whole* library (a term not fitted counts as p = 1, so the pre-filter can lose power, never add false
    alarms). Those below ``alpha`` come first, the largest scaled quick likelihood ratio first: they are what
    ``diagnose`` fits.

    Returns
    -------
    pandas.DataFrame
        Indexed by the effect's spec: ``label`` (``term:abs_u``), ``physics`` (its physical name, where it has
        one), ``parameter``, ``gradient``, ``lm``, ``p``, ``sd_robust``, ``lm_robust``, ``p_robust`` (for a step
        whose time a scan found, the scan's largest robust statistic and its p-value as the largest of many;
        ``scan_trim`` its scan's trimming, NaN for the others) and ``p_holm`` (the robust p-values adjusted over
        the library by :func:`holm`), sorted by ``p_robust``. With ``alpha``: ``lr_quick``, ``estimate``,
        ``lr_scale`` (:func:`quick_ratio`; NaN where not fitted) and ``p_quick_holm`` (of ``lr_quick /
        lr_scale``), ordered as above. The tests, and the quick fits, run in up to ``threads`` threads
        (:mod:`~smd_statespace.person.threads`), with the same table. A dict ``ends`` receives each quick fit's
        end by spec (``quick_ratio``'s ``end``): ``diagnose`` fits the terms it passes on from there.
    """
    effects = generic_library(result) if effects is None else list(effects)
    tests = score_tests(result, effects, threads)
    rows = [{"effect": effect.spec, "label": label(effect), "physics": getattr(effect, "physics", effect.name),
             **{key: value for key, value in row.items() if key != "cycle_scores"}}
            for effect, row in zip(effects, tests)]
    table = pd.DataFrame(rows).set_index("effect")
    table["scan_trim"] = [scan_trim([effect]) for effect in effects]
    for effect in effects:  # a step placed by a scan is tested as the largest of the scan's statistics
        if getattr(effect, "scan", None):
            table.loc[effect.spec, ["lm_robust", "p_robust"]] = [effect.scan["lm_robust"], effect.scan["p"]]
    table["p_holm"] = holm(table["p_robust"].to_numpy())
    table = table.sort_values("p_robust")
    if alpha is None:
        return table
    table["lr_quick"], table["estimate"], table["lr_scale"] = np.nan, np.nan, np.nan
    by_spec = {effect.spec: effect for effect in effects}
    fitted = list(table.index[table["p_robust"] < PREFILTER])
    for spec, quick in zip(fitted, thread_map(lambda spec: quick_ratio(result, by_spec[spec]), fitted, threads)):
        table.loc[spec, ["lr_quick", "estimate", "lr_scale"]] = [quick[key] for key in ("lr_quick", "estimate",
                                                                                         "lr_scale")]
        if ends is not None:
            ends[spec] = quick["end"]
    scaled = (table["lr_quick"] / table["lr_scale"]).fillna(0.0).to_numpy()
    p_quick = np.exp([log_p_value(value, 1, [by_spec[spec]]) for spec, value in zip(table.index, scaled)])
    table["p_quick_holm"] = holm(np.where(table["lr_quick"].notna(), p_quick, 1.0))
    passed = table["p_quick_holm"] < alpha
    return pd.concat([table[passed].assign(_scaled=scaled[passed.to_numpy()]).sort_values("_scaled", ascending=False)
                      .drop(columns="_scaled"), table[~passed]])


def time_change(result, alpha: float = CHANGE_ALPHA, threads: int = 1) -> dict:
    """Is the record one unchanging person? Score tests of ``f_h`` and ``xi_h`` changing in time, at the fit.

    Every term of :data:`TIME_KINDS` (a drift over the fitted span, a step at each of :data:`STEPS`) is
    score-tested at the fitted ``result`` (:func:`screen`: the robust, cycle-clustered statistic; no fit), the
    p-values adjusted by Holm over them. A parameter with a term below ``alpha`` changes during the record. A
    person who tires, warms up or changes stance is found here where the record's halves, each fitted on its
    own, are too short to tell their ``f_h`` apart; so is a force that fades, which a ``xi_h`` that drifts
    stands in for.

    Returns
    -------
    dict
        ``terms``: per term its ``term`` (:func:`~smd_statespace.effects.generic.label`), ``physics``,
        ``parameter`` (``f_h`` or ``xi_h``), ``p`` (robust) and ``p_holm``, smallest first; ``changed``: the
        parameters that change; ``alpha``; ``limits``: the smallest change of each kind the tests would find
        (:func:`~smd_statespace.person.detection.detection_limits`), which a record that shows none is said with.
    """
    library = generic_library(result, TIME_KINDS)
    parameter = {term.spec: term.changes for term in library}
    table = screen(result, library, threads=threads)
    terms = [{"term": row["label"], "physics": row["physics"], "parameter": parameter[spec],
              "p": float(row["p_robust"]), "p_holm": float(row["p_holm"])} for spec, row in table.iterrows()]
    flagged = {term["parameter"] for term in terms if term["p_holm"] < alpha}
    return {"terms": terms, "changed": [name for name in ("f_h", "xi_h") if name in flagged], "alpha": alpha,
            "limits": detection_limits(table, alpha)}
