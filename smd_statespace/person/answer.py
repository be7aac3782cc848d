"""The answer of a fit: a :class:`~smd_statespace.person.results.PersonResult` with its calibrated intervals.

:func:`person_result` turns a maximum-likelihood fit (:mod:`~smd_statespace.person.search`) into the
result users get: standard errors from the observed information, intervals calibrated
(:mod:`~smd_statespace.person.calibration`) and widened where the record leaves more open
(:func:`honest_intervals`).
"""

from __future__ import annotations

import numpy as np

from .calibration import CALIBRATION, EFFECT_CALIBRATION, model_error_floor, wald_interval
from .fade import NOTE_TAIL, fade_note
from .results import PRIOR_SD, VARIATION_DISAGREEMENT, PersonResult
from .profile import profile_interval
from .search import WIDER_SANDWICH, information

__all__ = ["person_result", "honest_intervals", "undetermined_interval"]


def person_result(record, model, fitted, *, intervals="calibrated", level=0.9, cov_type=WIDER_SANDWICH, comparison=(),
                  record_warnings=(), notes=(), threads=1, **extra):
    """The :class:`~smd_statespace.person.results.PersonResult` of a fitted record-level model.

    The covariance of the estimates (:func:`information`), the intervals of
    ``f_h`` and ``xi_h`` (calibrated Wald, Wald or profile, see
    :func:`identify_person`) and Wald intervals of the effects' parameters (widened by
    :data:`~smd_statespace.person.calibration.EFFECT_CALIBRATION` where calibrated).
    ``extra`` goes to the result (``before``, ``effects``, ``linearisations``, ``settled``).
    """
    params = fitted["params"]
    cov, free = information(model, params, cov_type, threads)
    factors = dict(CALIBRATION[model.variation])
    if intervals == "calibrated":
        scale = np.ones(params.size)
        scale[model.position("f_h")], scale[model.position("xi_h")] = factors["f_h"], factors["xi_h"]
        cov = cov * np.outer(scale, scale)
    se = dict(zip(model.param_names, np.sqrt(np.diag(cov))))
    named = model.unpack(params)
    bounds = dict(zip(model.param_names, model.bounds))
    interval = {}
    for name in ("f_h", "xi_h"):
        if intervals == "profile":
            interval[name] = profile_interval(model, params, fitted["loglike"], model.position(name), se[name],
                                              level)
        else:
            # the floor widens the interval, not the sd: the sd says what the record determines
            floor = 0.0 if intervals == "wald" else model_error_floor(name, named["f_h"], model.variation)
            interval[name] = wald_interval(named[name], float(np.hypot(se[name], floor)), level, bounds[name])
    widen = EFFECT_CALIBRATION if intervals == "calibrated" else 1.0  # the interval, not the sd (calibration.py)
    for name in model.effect_parameters:  # the effects' parameters: Wald intervals from the information
        interval[name] = (wald_interval(named[name], widen * se[name], level, bounds[name])
                          if np.isfinite(se[name]) else tuple(bounds[name]))
    effects = f"; effects' parameters: intervals x {EFFECT_CALIBRATION:g}" if model.effect_parameters else ""
    method = {"profile": "profile", "wald": f"wald ({cov_type})"}.get(
        intervals, f"calibrated wald ({cov_type}, sds x {factors['f_h']:g}, {factors['xi_h']:g}, "
                   f"with a model-error floor; undetermined: the yardstick's width{effects})")
    result = PersonResult(record=record, model=model, params=params, cov=cov, free=free, loglike=fitted["loglike"],
                          intervals=interval, interval_method=method, level=level, comparison=list(comparison),
                          n_evaluations=fitted["n_evaluations"], record_warnings=list(record_warnings),
                          notes=[note for note in notes if NOTE_TAIL not in note], **extra)
    if "fade" in model.delta_names:  # what the fade found: this fit's own note, not one given for another fit
        result.notes.append(fade_note(result))
    if intervals == "calibrated":
        result.narrow_intervals = dict(result.intervals)
        result.intervals.update(honest_intervals(result))
    return result


def honest_intervals(result) -> dict:
    """The calibrated intervals of ``f_h`` and ``xi_h``, widened where the record leaves more open.

    - A parameter the record does not determine (a model that misfits the record
      included: :attr:`PersonResult.misfit <smd_statespace.person.results.PersonResult.misfit>`),
      or whose estimate is an artefact: :func:`undetermined_interval`.
    - ``f_h`` or ``xi_h`` when the record's halves differ (a person who changes,
      :attr:`~smd_statespace.person.results.PersonResult.change`): the interval spans both halves'.
    - ``f_h`` when the variation models the record cannot rule out
      (:meth:`~smd_statespace.person.results.PersonResult.plausible_variations`) disagree
      by more than ``VARIATION_DISAGREEMENT``: the interval spans their estimates too (the
      answer depends on a modelling choice the record does not settle). On a record from
      a generator outside this project, "independent" gave 2.10-2.26 Hz and "smooth"
      2.84-3.69 Hz, 5.2 apart in log-likelihood, for a true 2.45 Hz
      (``../shared/findings/person-unseen-records.md``).
    """
    out = {name: undetermined_interval(result, name) for name in ("f_h", "xi_h")}
    for name in (result.change or {}).get("changed", ()):  # a person who changes: every half's interval inside
        halves = result.change["halves"]
        out[name] = (float(min(out[name][0], *(h[f"{name}_low"] for h in halves))),
                     float(max(out[name][1], *(h[f"{name}_high"] for h in halves))))
    values = [row.f_h for row in result.plausible_variations()]
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

    A parameter not determined only because the person changes during the record keeps its
    interval here: :func:`honest_intervals` widens it to span the record's parts'.
    """
    low, high = result.intervals[name]
    bounds = result.model.bound(name)
    if result.artefact(name):
        return float(bounds[0]), float(bounds[1])
    if result.determined_apart_from_change(name):  # a person who changes: honest_intervals spans the parts'
        return low, high
    wide = wald_interval(result.model.unpack(result.params)[name], PRIOR_SD[name], result.level, bounds)
    return min(low, wide[0]), max(high, wide[1])
