"""The per-cycle method's answer for the record: its cycles pooled into one value per parameter.

The article identifies every bouncing cycle on its own (:class:`~smd_statespace.identify.runner.CycleRunner`).
A user comparing it with the record-level person (:func:`smd_statespace.person.identify_person`) asks the
same question of both: what value, how sure, determined or not. :func:`pool_cycles` answers it for a table
of cycles in the person's vocabulary (``value``, ``sd``, ``low``, ``high``, ``determined``), and
:func:`pooled_row` gives the flat keys the person's ``to_dict`` gives (``f_h``, ``f_h_sd``, ``f_h_low``,
``f_h_high``, ``f_h_determined``, ...), so that ``compare`` and tables read both the same way.

How the cycles are pooled
-------------------------
- Only the plausible identified cycles count (:func:`~smd_statespace.identify.plausibility.flagged`).
- A parameter is pooled over the cycles that determine it by the one rule
  (:data:`~smd_statespace.determined.DETERMINED_FRACTION`): a cycle that does not has an estimate pulled
  towards the prior's centre, and averaging such estimates reports the prior, not the record.
- The pool is a random-effects mean (Paule-Mandel between-cycle variance, ``statsmodels``'
  :func:`~statsmodels.stats.meta_analysis.combine_effects`). Its sd is the larger of the random-effects sd
  and the Hartung-Knapp-Sidik-Jonkman one (Jackson et al. 2017, Stat. Med. 36:3923), and its interval a
  Student t interval on ``k - 1`` degrees of freedom. The between-cycle variance takes up what the
  filters' own sds leave out (their 90 % intervals cover the truth on 67 % of cycles for the EKF,
  docs/benchmarks.md), so the interval is as wide as the cycles scatter, not as narrow as each claims.
- The pool is *determined* when at least :data:`MAJORITY` of the plausible cycles determine the parameter
  and at least :data:`MIN_CYCLES` do: the record, not a selected few of its cycles, then says it.
- The force's load factors and ``xi_h`` are read through the leg's response at ``f_h`` (Eq. 2). Where the
  cycles do not determine ``f_h``, each cycle's estimate is pulled towards the prior's centre and their
  BLFs share that error, which no pooling removes: on 32 simulated records (``benchmarks/pooled_cycles.py``)
  the pooled interval of ``BLF_2`` held the truth on 12 of 27 records where its cycles determined it, the
  largest misses where ``f_h`` was 0.3-1.2 Hz off. So their pool is determined only where ``f_h``'s is
  (:data:`THROUGH_F_H`).
- Otherwise no pool is made. The value is the median of the plausible cycles, the interval the range
  holding the central ``level`` of them, and the sd NaN, with ``determined`` False. Pooling cycles that
  do not determine a parameter gives a narrow interval about the prior's centre (on a 30 s record, 46
  such cycles pooled to 2.38-2.54 Hz for a truth of 2.6), and the few cycles that do are a selection
  (4 of 46 pooled to 0.06-0.22 for a ``xi_h`` of 0.30).

Assumed: the cycles' estimates are independent given the person (each cycle is fitted on its own samples).
A person who changes within the record breaks it; the between-cycle spread (``between_sd``) then grows.
"""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
from scipy import stats

from .plausibility import flagged

__all__ = ["POOLED", "MAJORITY", "MIN_CYCLES", "THROUGH_F_H", "pool_cycles", "pooled_row"]

POOLED = ("f_h", "xi_h", "blf_1", "blf_2", "blf_3")
"""Parameters pooled (those the per-cycle table and the person both report)."""

MAJORITY = 0.5
"""Share of the plausible cycles that must determine a parameter for the pool to be called determined."""

MIN_CYCLES = 3
"""Fewest determining cycles that make a pool."""

THROUGH_F_H = ("xi_h", "blf_1", "blf_2", "blf_3")
"""Parameters whose pool is determined only where that of ``f_h`` is (pooled first)."""

COLUMNS = ["value", "sd", "low", "high", "determined", "cycles", "determining", "between_sd"]


def _random_effects(values: np.ndarray, sds: np.ndarray, level: float) -> tuple:
    """Random-effects mean, sd (the larger of the plain and the HKSJ one), t interval and between-cycle sd."""
    from statsmodels.stats.meta_analysis import combine_effects

    with warnings.catch_warnings(), np.errstate(divide="ignore", invalid="ignore"):
        warnings.simplefilter("ignore")  # identical estimates: an undefined I^2, not our answer
        fit = combine_effects(values, np.maximum(sds, 1e-12) ** 2)
    mean = float(fit.mean_effect_re)
    sd = float(max(fit.sd_eff_w_re, np.nan_to_num(fit.sd_eff_w_re_hksj)))
    half = stats.t.ppf(0.5 + level / 2.0, values.size - 1) * sd
    return mean, sd, mean - half, mean + half, float(np.sqrt(max(fit.tau2, 0.0)))


def pool_cycles(table: pd.DataFrame, level: float = 0.9, parameters=POOLED) -> pd.DataFrame:
    """The record's answer from its identified cycles, one row per parameter.

    Parameters
    ----------
    table : DataFrame
        A per-cycle results table (:meth:`CycleRunner.run`, ``results.csv``):
        ``status``, and per parameter its value, ``*_sd`` and ``*_determined``.
    level : float
        Coverage of the interval ``low``-``high``.
    parameters : sequence of str
        Parameters to pool; those absent from the table are skipped.

    Returns
    -------
    DataFrame
        Indexed by parameter: ``value``, ``sd``, ``low``, ``high`` (the parameter's units: Hz for ``f_h``,
        ``-`` for ``xi_h``, g for ``blf_i``), ``determined`` (bool), ``cycles`` (plausible identified
        cycles), ``determining`` (those that determine it) and ``between_sd`` (the spread of the cycles
        beyond their own sds). Not determined: the cycles' median and the range of the central ``level`` of
        them, sd and ``between_sd`` NaN; all NaN where no cycle has an estimate.
    """
    if not 0.0 < level < 1.0:
        raise ValueError(f"level: {level!r} is not between 0 and 1")
    ok = table[(table["status"] == "ok").to_numpy()] if "status" in table else table.iloc[:0]
    ok = ok[~np.asarray(flagged(ok), dtype=bool)]
    rows = {}
    for name in parameters:
        if name not in ok or f"{name}_sd" not in ok:
            continue
        usable = ok[np.isfinite(ok[name]) & np.isfinite(ok[f"{name}_sd"])]
        determining = usable[usable[f"{name}_determined"].astype(bool).to_numpy()] if f"{name}_determined" in usable \
            else usable.iloc[:0]
        row = dict.fromkeys(["value", "sd", "low", "high", "between_sd"], np.nan)
        row["cycles"], row["determining"] = len(usable), len(determining)
        row["determined"] = bool(len(determining) >= max(MIN_CYCLES, MAJORITY * len(usable)))
        if name in THROUGH_F_H and "f_h" in rows:  # read through the leg's response at f_h: they share its error
            row["determined"] = row["determined"] and bool(rows["f_h"]["determined"])
        if row["determined"]:
            mean, sd, low, high, between = _random_effects(determining[name].to_numpy(float),
                                                           determining[f"{name}_sd"].to_numpy(float), level)
            row.update(value=mean, sd=sd, low=low, high=high, between_sd=between)
        elif len(usable):  # what the cycles say, and how far they scatter: no sd of a value the record leaves open
            tail = (1.0 - level) / 2.0
            row.update(value=float(usable[name].median()), low=float(usable[name].quantile(tail)),
                       high=float(usable[name].quantile(1.0 - tail)))
        rows[name] = row
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
