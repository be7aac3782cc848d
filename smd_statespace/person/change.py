"""Does one person explain the whole record? The person fitted on each half, and a test of equality.

A person who tires, warms up or changes the way they bounce during a record is not one SMD
model: fitted whole, the record gives an ``f_h`` between the two and innovations that are not
white, and no candidate effect of ``diagnose`` takes what is missing (a parameter that varies
in time). :func:`change_test` fits the record-level model again on each half of the record (at
the cycle boundary nearest the middle), starting from the whole record's estimate with its
variation model and cycle timing, and compares the halves' ``f_h`` and ``xi_h`` by a z-test on
their calibrated standard errors (:data:`~smd_statespace.person.calibration.CALIBRATION`): where
each half determines the parameter on its own (the library's "determined" rule), a difference of
:data:`CHANGE_Z` standard errors or more, and at least :data:`CHANGE_MIN` of the value, is a
person who changes: the result says so in words with both halves' values
(:func:`~smd_statespace.person.report.change_words`, first among the warnings), does not call the
parameter determined, and widens its interval over both halves'. Halves that do not determine it
cannot tell a change from their own spread; the record's answer is then "not determined" already,
and says so.
"""

from __future__ import annotations

import numpy as np

from .calibration import CALIBRATION, wald_interval
from .judgement import DETERMINED_FRACTION, PRIOR_SD
from .search import fit_model, information
from .threads import thread_map
from .validation import halves, part

__all__ = ["CHANGE_MIN", "CHANGE_Z", "change_test", "compare_halves"]

CHANGE_Z = 2.58
"""Difference of the halves' estimates, in calibrated standard errors of the difference, from which the person
changes (two-sided 1 % per parameter for a normal z), when each half determines the parameter on its own.

Chosen on the halves of 40 lab records of stationary people and 40 whose ``f_h`` drifts or steps by 8-20 %
(``benchmarks/lab_records.py``'s draws, seed 4343; people of ``LabRanges``, f_h determined on a third of the
records): with calibrated sds and both halves determined, z >= 2.0 and z >= 2.58 each named 2 changes of
``f_h`` and no stationary person's (z >= 1.5: 3 and 1); without asking that the halves be determined, z >= 2.58
named 4 changes and 3 stationary people (7.5 %), and the information's own sds (too narrow) named 10 and 13.
At z >= 2.0, ``xi_h`` was named on a stationary 1000 Hz record whose innovations had a kurtosis of 31."""

CHANGE_MIN = {"f_h": 0.04, "xi_h": 0.06}
"""Smallest difference that is called a change: 4 % of ``f_h``, 0.06 of ``xi_h`` (absolute)."""

def change_test(model, params, level=0.9, threads=1) -> dict | None:
    """The person fitted on each half of the record, and whether ``f_h`` or ``xi_h`` differ between them.

    Parameters
    ----------
    model : RecordModel
        The whole record's fitted model (without effects: a model with effects is not split).
    params : ndarray
        Its estimate (the halves' searches start there).
    level : float
        Confidence level of the halves' intervals.
    threads : int
        The halves are fitted in up to this many threads (:mod:`~smd_statespace.person.threads`).

    Returns
    -------
    dict or None
        ``halves``: per half its ``start``, ``end`` (s), ``f_h``, ``xi_h``, their calibrated sds
        and intervals; ``z`` (per parameter, the difference over its sd); ``changed``: the
        parameters that differ (empty: one person explains the record). None when the record
        is too short to split (fewer than :data:`~smd_statespace.person.validation.MIN_HALF_CYCLES` cycles a
        half), the model
        has effects, or a half's fit fails.
    """
    cut = halves(model)
    if model.dynamics.model.effects or cut is None:
        return None

    def fit_half(piece):
        half = part(model, *piece)
        fitted = fit_model(half, params, quick=True)
        if not fitted["converged"] or half.person_at_bound(fitted["params"]):
            return None
        return _summary(half, fitted["params"], level)

    summaries = thread_map(fit_half, cut, threads)
    return None if None in summaries else compare_halves(summaries)


def _summary(model, params, level) -> dict:
    """A half's ``f_h``, ``xi_h``, calibrated sds and intervals."""
    cov, _ = information(model, params, "oim")
    named = model.unpack(params)
    out = {"start": float(model.time[0]), "end": float(model.time[-1])}
    for name in ("f_h", "xi_h"):
        position = model.position(name)
        sd = float(np.sqrt(cov[position, position])) * CALIBRATION[model.variation][name]
        out[name], out[f"{name}_sd"] = float(named[name]), sd
        out[f"{name}_low"], out[f"{name}_high"] = wald_interval(named[name], sd, level, model.bound(name))
    return out


def compare_halves(halves) -> dict:
    """``z`` and the parameters that changed between two halves' summaries (as :func:`change_test` returns them).

    Each half: ``start``, ``end`` (s) and, per parameter, its value, ``{name}_sd`` (calibrated) and interval.
    A parameter changed when both halves determine it, their difference is :data:`CHANGE_Z` sds of the
    difference or more and at least :data:`CHANGE_MIN`.
    """
    first, second = halves
    z, changed = {}, []
    for name in ("f_h", "xi_h"):
        difference = second[name] - first[name]
        sd = float(np.hypot(first[f"{name}_sd"], second[f"{name}_sd"]))
        z[name] = float(difference / sd) if np.isfinite(sd) and sd > 0 else 0.0
        size = abs(difference) / first[name] if name == "f_h" else abs(difference)
        determined = all(half[f"{name}_sd"] < DETERMINED_FRACTION * PRIOR_SD[name] for half in halves)
        if determined and abs(z[name]) >= CHANGE_Z and size >= CHANGE_MIN[name]:
            changed.append(name)
    return {"halves": halves, "z": z, "changed": changed}

