"""The per-cycle method's answer for a record (identify.pooled): its cycles pooled, or said not to determine."""

import numpy as np
import pandas as pd
import pytest

from smd_statespace.identify.pooled import MAJORITY, pool_cycles, pooled_row


def cycles_table(values, sds, determined, name="f_h", implausible=None):
    n = len(values)
    table = pd.DataFrame({"cycle": np.arange(n), "status": "ok", name: values, f"{name}_sd": sds,
                          f"{name}_determined": determined,
                          "implausible": np.zeros(n, bool) if implausible is None else implausible,
                          "implausible_reason": ""})
    return table


def test_overconfident_cycles_pool_to_an_interval_that_covers_as_stated():
    """Cycles that scatter twice as far as their own sds claim, around a person who does not change, plus a spread
    of their own: the random-effects pool's 90 % interval holds the truth about 90 % of the time; with equal sds
    its value is the plain mean (equal weights whatever the between-cycle variance)."""
    rng = np.random.default_rng(np.random.SeedSequence(2024))
    held = []
    for _ in range(400):
        n = int(rng.integers(8, 40))
        claimed = rng.uniform(0.03, 0.08, n)
        values = 2.6 + rng.normal(0.0, 0.03, n) + rng.normal(0.0, 2.0 * claimed)
        row = pool_cycles(cycles_table(values, claimed, np.ones(n, bool)), level=0.9).loc["f_h"]
        assert row["determined"] and row["cycles"] == row["determining"] == n
        held.append(row["low"] <= 2.6 <= row["high"])
    assert 0.85 <= np.mean(held) <= 0.97, np.mean(held)
    equal = cycles_table([2.5, 2.7, 2.6, 2.65], [0.05] * 4, [True] * 4)
    assert pool_cycles(equal).loc["f_h", "value"] == pytest.approx(2.6125, abs=1e-12)


def test_cycles_that_do_not_determine_give_their_median_and_range_not_a_pooled_sd():
    """Ten cycles pulled towards the prior's centre, two that determine: no pool (2 < the majority), the median of
    the plausible cycles and the range of their central 90 %, no sd; an implausible cycle is left out."""
    values = np.array([2.50, 2.45, 2.55, 2.48, 2.52, 2.47, 2.53, 2.50, 2.49, 2.51, 2.90, 2.92, 9.0])
    determined = np.array([False] * 10 + [True, True, True])
    implausible = np.array([False] * 12 + [True])
    row = pool_cycles(cycles_table(values, np.full(13, 0.3), determined, implausible=implausible)).loc["f_h"]
    assert not row["determined"] and row["cycles"] == 12 and row["determining"] == 2 < MAJORITY * 12
    assert row["value"] == pytest.approx(np.median(values[:12]))
    assert row["low"] == pytest.approx(np.quantile(values[:12], 0.05)) and np.isnan(row["sd"])
    flat = pooled_row(cycles_table(values, np.full(13, 0.3), determined, implausible=implausible))
    assert flat["n_cycles"] == 12 and flat["f_h_determined"] is False and flat["f_h_high"] == row["high"]
    with pytest.raises(ValueError, match="level"):
        pool_cycles(cycles_table(values, np.full(13, 0.3), determined), level=90)


def test_load_factors_are_determined_only_where_f_h_is():
    """Every cycle determines BLF_2; where the cycles also determine f_h the pool says so, where none does (their
    f_h pulled to the prior's centre, which the BLFs are read through) BLF_2 is not determined either."""
    n = 12
    rng = np.random.default_rng(np.random.SeedSequence(7))
    base = cycles_table(2.6 + rng.normal(0.0, 0.05, n), np.full(n, 0.05), np.ones(n, bool))
    base["blf_2"], base["blf_2_sd"], base["blf_2_determined"] = 0.15 + rng.normal(0.0, 0.003, n), 0.003, True
    assert pool_cycles(base).loc["blf_2", "determined"]
    base["f_h_determined"] = False
    pooled = pool_cycles(base)
    assert not pooled.loc["f_h", "determined"] and not pooled.loc["blf_2", "determined"]
    assert pooled.loc["blf_2", "determining"] == n and np.isnan(pooled.loc["blf_2", "sd"])
