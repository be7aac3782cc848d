"""Estimates that cannot be true: per-cycle checks against physics and against the model's own prior.

A filter always returns numbers. Some of them describe no person: a negative
damping ratio (the "damper" would feed energy into the body), an ``f_h``
pinned at or beyond the edge of the prior the model was given (the data
pushed it there, the prior stopped it: the true value is not in the model's
range, or the model does not describe the record), a force harmonic larger
than any human rhythmic activity produces. :func:`implausible_reasons` names
what is wrong with each row of a table of cycles; the cycle runner
(:mod:`smd_statespace.identify.runner`) writes the result as the columns
``implausible`` and ``implausible_reason`` and never marks such a cycle
determined, ``identify`` counts them and prints a ``warning:`` line, and
``stats`` leaves them out of the population (:mod:`smd_statespace.population.statistics`).

The limits, each a module constant with its reason:

============================ ========================================================================
reason                       limit
============================ ========================================================================
``xi_h < 0``                 :data:`XI_H_MIN`: negative damping
``C_h < 0``                  :data:`C_H_MIN`: negative damping coefficient (Eq. 18)
``f_h on prior bound``       within :data:`PRIOR_MARGIN` of an edge of the model's prior, or
``f_h outside prior``        beyond it (any parameter of the model: ``xi_h``, ``a0``, ``a1`` ...)
``BLF_i > 2 g``              :data:`MAX_BLF`
``GRF harmonic i > 2 g``     :data:`MAX_GRF_HARMONIC`, the force harmonic the SMD (Eq. 2) would put
                             on the floor with the cycle's ``f_h``, ``xi_h`` and ``BLF_i``
============================ ========================================================================

The prior checks need the model (``model=``); without it (a table from
elsewhere, read by ``stats``) only the physical limits apply.
"""

from __future__ import annotations

import re

import numpy as np
import pandas as pd

from ..model import acceleration_frf

__all__ = ["XI_H_MIN", "C_H_MIN", "PRIOR_MARGIN", "MAX_BLF", "MAX_GRF_HARMONIC", "implausible_reasons",
           "flagged", "reason_counts", "implausible_ok", "plausible_cycles"]

XI_H_MIN = 0.0
"""Smallest damping ratio ``xi_h`` (-): below 0 the SMD's damper would feed energy into the body (Eq. 2)."""

C_H_MIN = 0.0
"""Smallest damping coefficient ``C_h`` (N s/m, Eq. 18): below 0 the same impossibility as ``xi_h < 0``."""

PRIOR_MARGIN = 0.02
"""Fraction of a parameter's prior width: an estimate closer than this to an edge of the model's uniform
prior (``f_h`` 1-4 Hz: 0.06 Hz; ``xi_h`` 0-1: 0.02) is "on the prior bound". The particle filters reflect
at the edges and the Kalman filters are not bounded at all, so a cycle whose data push a parameter to or
past the edge reports the edge (or beyond), not a value the data determined."""

MAX_BLF = 2.0
"""Largest biomechanical load factor ``BLF_i`` (g, Eq. 5): an internal force oscillating with more than
twice the body weight. Bouncing with both feet on the ground has BLF1 of 0.1-0.6 g (Table 2's band means
0.25-0.35 g); even jumping, with flight phases, has a first force harmonic below 2 body weights."""

MAX_GRF_HARMONIC = 2.0
"""Largest amplitude (g, i.e. in body weights) of a harmonic of the ground reaction force. A force that
never pulls on the floor (GRF >= 0, mean one body weight) has every Fourier amplitude at most twice its
mean: ``|c_k| = |(2/T) int GRF e^(-ik w t) dt| <= (2/T) int GRF dt = 2 M_h g``. The harmonic the
identified SMD would put on the floor is ``BLF_i r^2 / sqrt((1 - r^2)^2 + (2 xi_h r)^2)``, ``r = i f_b /
f_h`` (Eq. 2-3 in steady state); above this limit the cycle's ``f_h``, ``xi_h`` and ``BLF_i`` together
describe no person standing on a floor."""


def _column(table: pd.DataFrame, name: str) -> np.ndarray:
    if name not in table:
        return np.full(len(table), np.nan)
    return pd.to_numeric(table[name], errors="coerce").to_numpy(dtype=float)


def implausible_reasons(table: pd.DataFrame, model=None, grf: bool = True) -> pd.Series:
    """What makes each cycle's estimates impossible, ``"; "``-joined (``""`` for a plausible cycle).

    Parameters
    ----------
    table : pandas.DataFrame
        One row per cycle with any of the columns ``f_b`` (Hz), ``f_h`` (Hz), ``xi_h``, ``c_h``
        (N s/m), ``blf_1 ... blf_n`` (g) and the model's parameter names (``a0``, ``a1`` ...).
        Missing columns and NaN values are not checked.
    model : SMDModel, optional
        The model the cycles were identified with; its parameters' prior ranges are checked
        (:data:`PRIOR_MARGIN`). Without it only the physical limits apply.
    grf : bool
        Check :data:`MAX_GRF_HARMONIC` (it uses the base SMD of Eq. 2; the runner switches it
        off for models with effects, whose floor force differs).

    Returns
    -------
    pandas.Series of str
        Indexed like ``table``, e.g. ``"xi_h < 0; C_h < 0"`` or ``"f_h outside prior"``.
    """
    n = len(table)
    found: list[tuple[np.ndarray, str]] = []
    xi = _column(table, "xi_h")
    f_h = _column(table, "f_h")
    found.append((xi < XI_H_MIN, "xi_h < 0"))
    found.append((_column(table, "c_h") < C_H_MIN, "C_h < 0"))
    if model is not None:
        for slot in model.slots:
            if slot.kind != "parameter" or slot.name not in table:
                continue
            value = _column(table, slot.name)
            margin = PRIOR_MARGIN * (slot.high - slot.low)
            outside = (value < slot.low) | (value > slot.high)
            near = ~outside & ((value < slot.low + margin) | (value > slot.high - margin))
            if slot.name == "xi_h":
                outside &= ~(value < XI_H_MIN)  # already said: "xi_h < 0"
            found.append((outside, f"{slot.name} outside prior"))
            found.append((near, f"{slot.name} on prior bound"))
    orders = sorted(int(match.group(1)) for c in table.columns
                    if isinstance(c, str) and (match := re.fullmatch(r"blf_(\d+)", c)))
    f_b = _column(table, "f_b")
    for i in orders:
        value = _column(table, f"blf_{i}")
        found.append((value > MAX_BLF, f"BLF_{i} > {MAX_BLF:g} g"))
        if grf:
            with np.errstate(divide="ignore", invalid="ignore"):
                floor_force = value * np.abs(acceleration_frf(i * f_b, f_h, xi))  # Eq. 2's response at i f_b
            possible = (f_h > 0) & (xi >= XI_H_MIN) & (value <= MAX_BLF)  # otherwise already said
            found.append((possible & (floor_force > MAX_GRF_HARMONIC), f"GRF harmonic {i} > {MAX_GRF_HARMONIC:g} g"))
    reasons = [[] for _ in range(n)]
    for mask, text in found:
        for row in np.flatnonzero(mask):
            reasons[row].append(text)
    return pd.Series(["; ".join(r) for r in reasons], index=table.index, dtype=object)


def flagged(table: pd.DataFrame, column: str = "implausible") -> np.ndarray:
    """The rows whose ``column`` is True (bools, or "True"/"true"/1 as read back from a CSV; blank: False)."""
    if column not in table:
        return np.zeros(len(table), dtype=bool)
    values = table[column]
    if values.dtype == bool:
        return values.to_numpy()
    return values.astype(str).str.strip().str.lower().isin({"true", "1", "1.0", "yes"}).to_numpy()


def reason_counts(reasons) -> dict:
    """How many rows give each reason (``{"xi_h < 0": 8, ...}``, most frequent first)."""
    counts: dict = {}
    for text in reasons:
        if not isinstance(text, str):
            continue
        for reason in filter(None, (part.strip() for part in text.split(";"))):
            counts[reason] = counts.get(reason, 0) + 1
    return dict(sorted(counts.items(), key=lambda item: (-item[1], item[0])))


def implausible_ok(table: pd.DataFrame) -> tuple:
    """``(ok, implausible, reasons)``: the ``ok`` rows, those of them flagged implausible (boolean masks), and
    :func:`reason_counts` of the flagged ones' ``implausible_reason`` (``{}`` without that column)."""
    ok = (table["status"] == "ok").to_numpy() if "status" in table else np.zeros(len(table), dtype=bool)
    bad = ok & flagged(table)
    reasons = reason_counts(table.loc[bad, "implausible_reason"]) if "implausible_reason" in table else {}
    return ok, bad, reasons


def plausible_cycles(table: pd.DataFrame) -> pd.DataFrame:
    """The ``ok`` cycles whose estimates are possible (not flagged ``implausible``)."""
    ok, bad, _ = implausible_ok(table)
    return table[ok & ~bad]
