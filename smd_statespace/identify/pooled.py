"""The per-cycle method's answer for the record, in the person's vocabulary: what its cycles say together.

The article identifies every bouncing cycle on its own (:class:`~smd_statespace.identify.runner.CycleRunner`).
A user comparing it with the record-level person (:func:`smd_statespace.person.identify_person`) asks the
same question of both: what value, how sure, determined or not. :func:`pool_cycles` answers it for a table
of cycles in the person's vocabulary (``value``, ``sd``, ``low``, ``high``, ``determined``);
:func:`pooled_row` gives the flat keys of the person's ``to_dict`` (``f_h``, ``f_h_sd``, ``f_h_low``,
``f_h_high``, ``f_h_determined``, ...) and :func:`pooled_people` a batch's table of them, one row per
record, so that ``compare``, batch tables and ``stats`` read both the same way.

The answer
----------
Over the plausible identified cycles (:func:`~smd_statespace.identify.plausibility.plausible_cycles`): the value is
their median, ``low``-``high`` the range that holds the central ``level`` of them, and the parameter is
**never determined** by the per-cycle method, whatever share of its cycles determine it one by one
(``determining`` counts those). The sd is NaN: the cycles give no standard error of the person.

Why nothing is pooled into an interval
--------------------------------------
The cycles of one record share the estimator's error; averaging them removes the noise of each cycle, not
that. Measured with ``benchmarks/pooled_cycles.py`` (64 simulated 30 s records, EKF, seed 7;
docs/benchmarks.md): a random-effects pool (``statsmodels``' ``combine_effects``, Paule-Mandel, the
Hartung-Knapp sd where wider) of the cycles that determine ``f_h``, made where most of them did, held the
truth in its 90 % interval on 4 of 11 records, its sd 0.027 Hz against errors of 0.08 Hz and, where the
cycles had settled on a resonance at ``f_b`` standing in for the force, 0.5 Hz. Cycles that do not
determine ``f_h`` are pulled towards the prior's centre, so pooling them reports the prior: 46 such cycles
of one record pooled to 2.38-2.54 Hz for a truth of 2.6. The load factors are read through the leg's
response at each cycle's ``f_h`` and share its error. The person from the whole record is the answer with
an interval (:func:`smd_statespace.person.identify_person`); this one says what the cycles say.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from .plausibility import flagged, plausible_cycles

__all__ = ["POOLED", "pool_cycles", "pooled_row", "pooled_people"]

POOLED = ("f_h", "xi_h", "blf_1", "blf_2", "blf_3")
"""Parameters answered (those the per-cycle table and the person both report)."""

COLUMNS = ["value", "sd", "low", "high", "determined", "cycles", "determining"]


def pool_cycles(table: pd.DataFrame, level: float = 0.9, parameters=POOLED) -> pd.DataFrame:
    """The record's answer from its identified cycles, one row per parameter.

    Parameters
    ----------
    table : DataFrame
        A per-cycle results table (:meth:`CycleRunner.run`, ``results.csv``):
        ``status``, and per parameter its value and ``*_determined``.
    level : float
        Share of the cycles inside ``low``-``high``.
    parameters : sequence of str
        Parameters answered; those absent from the table are skipped.

    Returns
    -------
    DataFrame
        Indexed by parameter: ``value`` (the cycles' median; Hz for ``f_h``, ``-`` for ``xi_h``, g for
        ``blf_i``), ``sd`` (NaN), ``low``, ``high`` (the range of the central ``level`` of the cycles),
        ``determined`` (False), ``cycles`` (plausible identified cycles with an estimate) and ``determining``
        (those that determine it on their own). NaN values where no cycle has an estimate.
    """
    if not 0.0 < level < 1.0:
        raise ValueError(f"level: {level!r} is not between 0 and 1")
    plausible = plausible_cycles(table)
    tail = (1.0 - level) / 2.0
    rows = {}
    for name in parameters:
        if name not in plausible:
            continue
        values = plausible[name][np.isfinite(plausible[name])]
        determining = flagged(plausible.loc[values.index], f"{name}_determined")  # bools, or as read from a CSV
        rows[name] = {"value": values.median(), "sd": np.nan, "low": values.quantile(tail),
                      "high": values.quantile(1.0 - tail), "determined": False, "cycles": len(values),
                      "determining": int(determining.sum())}
    return pd.DataFrame.from_dict(rows, orient="index", columns=COLUMNS).rename_axis("parameter")


def pooled_row(table: pd.DataFrame, level: float = 0.9, parameters=POOLED) -> dict:
    """:func:`pool_cycles` as the flat keys of the person's ``to_dict``: ``f_h``, ``f_h_sd``, ``f_h_low``,
    ``f_h_high``, ``f_h_determined``, ... and ``n_cycles`` (plausible identified cycles)."""
    pooled = pool_cycles(table, level, parameters)
    out = {"n_cycles": int(pooled["cycles"].max()) if len(pooled) else 0}
    for name, row in pooled.iterrows():
        out[name], out[f"{name}_sd"] = float(row["value"]), float(row["sd"])
        out[f"{name}_low"], out[f"{name}_high"] = float(row["low"]), float(row["high"])
        out[f"{name}_determined"] = bool(row["determined"])
    return out


def pooled_people(table: pd.DataFrame, level: float = 0.9) -> pd.DataFrame:
    """One row per record of a per-cycle batch's ``results.csv``: the record's cycles together (:func:`pooled_row`).

    The columns are the record-level person's (``identify FOLDER`` with its default estimator): ``record``,
    ``mass``, ``status``, ``reason``, ``f_b`` (the median of the plausible cycles', Hz), ``n_cycles`` and each
    parameter with ``_sd``, ``_low``, ``_high``, ``_determined``, so that ``stats`` reads the table as people
    whichever estimator made it (none of them determined: ``stats --include-undetermined`` takes them). A
    record that failed keeps its reason; one with no plausible identified cycle fails with that reason.
    """
    rows = []
    for record, cycles in table.groupby("record", sort=False):
        row = {"record": record, "mass": cycles["mass"].iloc[0] if "mass" in cycles else np.nan}
        plausible = plausible_cycles(cycles)
        if plausible.empty:
            failed = cycles[cycles["status"] == "failed"]
            reason = (failed["reason"].iloc[0] if len(cycles) == 1 and len(failed) else
                      "no plausible identified cycle")
            rows.append({**row, "status": "failed", "reason": reason})
            continue
        rows.append({**row, "status": "ok", "reason": "", "f_b": float(plausible["f_b"].median()),
                     **pooled_row(cycles, level)})
    return pd.DataFrame(rows)
