"""The smallest change of the person in time that a record would show: detection limits of the score tests.

A score test that finds no change of ``f_h`` during the record (:func:`~smd_statespace.person.screen.time_change`,
``diagnose``'s library) says that the record shows none *that it could see*. How large a change it could see
depends on the record: on a record whose force varies smoothly from cycle to cycle (the ``smooth`` variation
model), a slow change of ``f_h`` changes the force's response much as a slow change of the force does, and a drift
of ``f_h`` by 10 % over the record can pass unseen (``benchmarks/person_effects.py``: on the ``smooth`` generator a
drift 3.5 times the innovations' sd was found on none of 8 records). This module turns each time term's score test
into the change of ``f_h`` it would find, so that "no change" is printed with its limit, as a power analysis
gives it.

For a term's coefficient ``c`` (:mod:`~smd_statespace.effects.generic`) the efficient score summed over the record,
``S``, has mean about ``c I`` (``I`` the efficient information, the other parameters profiled out) and variance
``V`` (the cycle-clustered spread of the scores: :func:`~smd_statespace.person.screen.score_test`), so the robust
statistic ``S^2 / V`` is a noncentral chi-square(1) whose root is shifted by ``|c| I / sqrt(V) = |c| / sd`` with
``sd = sqrt(V) / I``. A test at critical value ``k`` finds ``c`` with probability ``power`` where::

    |c| = (sqrt(k) + z_power) sd

(``z_power`` the standard normal's ``power`` point; the other tail is neglected). ``k`` is the first step of Holm
over the tests of the family (``alpha / m``), and for a step whose time a scan found, the largest-of-the-scan's
(:func:`~smd_statespace.person.supremum.critical_value`). That is the information's limit; the fitted person has
absorbed part of a change that is there, so the tests find less than it predicts, and the limit printed is
:data:`DETECTION_FACTOR` times it, measured (found 4 times in 5 or more where it is printed). ``c`` is then said as
the change of ``f_h`` it makes: from the record's start to its end for a drift, across the step for a step.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

from ..effects.generic import TERMS
from .supremum import critical_value

__all__ = ["DETECTION_POWER", "DETECTION_FACTOR", "KINDS", "change_percent", "detection_limits", "limits_words",
           "unseen_change", "printed_limits"]

DETECTION_POWER = 0.8
"""The chance of finding a change at the detection limit (the usual power of a power analysis)."""

DETECTION_FACTOR = 2.0
"""The limit printed is this many times the one the information gives (module docstring), measured.

The information's limit assumes the score's shift under a change is ``c I``; at the fitted person it is less:
the fit without the change has already absorbed part of it (its cycle starts re-placed, its ``f_h`` and the
force's variation moved). ``benchmarks/change_limits.py`` (seed 5; 30 s records of the ``jumps`` generator and lab
exports, where ``f_h`` is determined) simulated each record again with ``f_h`` drifting, and stepping, by a multiple
of its clean record's information limit: found 11 of 24 at 1 times it (jumps 4/6 and 3/6, lab 3/6 and 1/6), 20 of
24 at 1.5 times, 23 of 24 at 2 times. Held out (seed 6), changes at the limit printed with this factor were found
on 30 of the 31 records where it is printed (jumps 14/14, lab exports 16/16, smooth 1/2), and on phones at the
waist, read back as a user's file, 12 of 12."""

KINDS = ("f_drift", "f_step")
"""The time terms whose limits are given: the changes of ``f_h`` the factor was measured on (a change of ``xi_h``
stands for a fading force as much as for a person's damping, and its limit was not measured)."""


def change_percent(kind: str, c: float) -> float:
    """The change (%) of ``f_h`` (``f_*`` kinds) or ``xi_h`` (``xi_*``) that coefficient ``c`` of time term
    ``kind`` makes: from the record's start to its end for a drift, from before to after a step.

    ``w_h^2`` (or ``xi_h w_h``) goes from ``1 - c / 2`` to ``1 + c / 2`` times its middle value, so ``f_h``
    changes by ``sqrt((1 + c/2) / (1 - c/2))`` and ``xi_h`` (at a fixed ``f_h``) by ``(1 + c/2) / (1 - c/2)``.

    >>> round(change_percent("f_drift", 0.2), 2), round(change_percent("xi_step", 0.2), 2)
    (10.55, 22.22)
    """
    if TERMS[kind][0] != "time":
        raise ValueError(f"{kind!r} is not a time term of the generic library")
    c = min(abs(float(c)), 1.999)
    ratio = (1.0 + c / 2.0) / (1.0 - c / 2.0)
    return 100.0 * ((math.sqrt(ratio) if kind.startswith("f_") else ratio) - 1.0)


def detection_limits(table, alpha: float, tests: int | None = None, power: float = DETECTION_POWER,
                     factor: float = DETECTION_FACTOR) -> dict:
    """The smallest change of ``f_h`` in time (each kind of :data:`KINDS`) the score tests in ``table`` would find.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`~smd_statespace.person.screen.screen`'s table: its ``label`` (``term:f_drift``), ``sd_robust`` and
        ``scan_trim`` columns are read; rows that are not time terms are skipped.
    alpha : float
        The family-wise level of the tests (Holm).
    tests : int, optional
        How many tests the family counts (default: the rows of ``table``); the limit is at Holm's first step,
        ``alpha / tests``.
    power : float
        The chance of finding a change at the limit.
    factor : float
        The measured widening of the information's limit (:data:`DETECTION_FACTOR`; 1 gives the information's).

    Returns
    -------
    dict
        Per kind of :data:`KINDS` present: ``c`` (the smallest ``|c|`` found with probability ``power``, ``factor``
        times the information's; of a kind's several steps the most sensitive), ``percent``
        (:func:`change_percent` of it, % of ``f_h``) and ``sd`` (the coefficient's robust sd at ``c = 0``).
    """
    tests = max(int(tests if tests is not None else len(table)), 1)
    z_power = float(stats.norm.ppf(power))
    out = {}
    for _, row in table.iterrows():
        kind = str(row["label"]).removeprefix("term:").split("@")[0]  # a step is labelled with its time
        if kind not in KINDS or not np.isfinite(row.get("sd_robust", np.nan)):
            continue
        trim = float(row.get("scan_trim", math.nan))
        k = critical_value(alpha / tests, 1, trim)
        c = factor * (math.sqrt(k) + z_power) * float(row["sd_robust"])
        if kind not in out or c < out[kind]["c"]:
            out[kind] = {"c": c, "percent": change_percent(kind, c), "sd": float(row["sd_robust"])}
    return out


def limits_words(limits: dict, f_h_determined: bool, power: float = DETECTION_POWER) -> str:
    """What a record that shows no change of ``f_h`` does not rule out, in words ("" when there is nothing to say).

    ``limits`` is :func:`detection_limits`' dict. A limit is said only where the record determines ``f_h``: where
    the model does not describe how the force varies the tests see less than the information says, and the record
    does not determine ``f_h`` either (``benchmarks/change_limits.py``, the ``smooth`` generator, ``f_h`` determined
    on 2 of 22 records: drifts at the information's limit found on 0 of 11, at twice it drifts on 7 of 9 and steps
    on 2 of 9). There the words say that a change of ``f_h`` is out of the record's reach.
    """
    shapes = [(shape, limits.get(f"f_{shape}")) for shape in ("drift", "step")]
    if not any(limit for _, limit in shapes):
        return ""
    if not f_h_determined:
        return "f_h is not determined, so neither is a change of it during the record"
    said = [("drifting by " if shape == "drift" else "stepping by ")
            + (f"{limit['percent']:.0f} %" if limit["percent"] < 100 else "more than double")
            + (" over the record" if shape == "drift" else " in mid-record")
            for shape, limit in shapes if limit]
    return f"f_h {' or '.join(said)} would be found {power:.0%} of the time or more, a smaller change may not"


def _quiet_tests(result) -> dict | None:
    """The score tests of a change in time of a fitted person (``result.change["time"]``) where they found none; None
    where they found one or were not made. A person fitted with the change they found in its model
    (``identify --effect``) no longer counts it as changing, and the tests (made without it) still found it."""
    change = result.change or {}
    tests = change.get("time")
    return None if change.get("changed") or not tests or tests.get("changed") else tests


def unseen_change(result) -> str:
    """:func:`limits_words` of a fitted person whose score tests of a change in time
    (:func:`~smd_statespace.person.screen.time_change`) found none; "" when they found one or were not made."""
    tests = _quiet_tests(result)
    return limits_words(tests.get("limits", {}), result.determined("f_h")) if tests else ""


def printed_limits(result) -> dict:
    """``{kind: percent}`` of the limits :func:`unseen_change` prints for a fitted person (no change found, ``f_h``
    determined); empty where it prints none."""
    tests = _quiet_tests(result)
    if not tests or not result.determined("f_h"):
        return {}
    return {kind: limit["percent"] for kind, limit in tests.get("limits", {}).items()}
