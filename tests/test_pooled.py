"""The per-cycle method's answer for a record (identify.pooled): what its cycles say together, never determined."""

import numpy as np
import pandas as pd
import pytest

from smd_statespace.identify.pooled import pool_cycles, pooled_people, pooled_row


def cycles_table(values, determined, implausible=None, name="f_h"):
    n = len(values)
    return pd.DataFrame({"record": "r.csv", "mass": 70.0, "cycle": np.arange(n), "status": "ok", "f_b": 2.0,
                         name: values, f"{name}_sd": 0.05, f"{name}_determined": determined,
                         "implausible": np.zeros(n, bool) if implausible is None else implausible,
                         "implausible_reason": ""})


def test_the_cycles_median_and_central_range_every_cycle_determining_or_not():
    """The median and central 90 % of the plausible cycles (an implausible one left out); not determined even
    where every cycle determines f_h on its own (they share the estimator's error: benchmarks/pooled_cycles.py),
    with the count of those that do."""
    values = np.array([2.50, 2.45, 2.55, 2.48, 2.52, 2.47, 2.53, 2.50, 2.49, 2.51, 2.90, 2.92, 9.0])
    implausible = np.array([False] * 12 + [True])
    for determined in (np.zeros(13, bool), np.ones(13, bool)):
        row = pool_cycles(cycles_table(values, determined, implausible)).loc["f_h"]
        assert row["value"] == pytest.approx(np.median(values[:12]))
        assert (row["low"], row["high"]) == pytest.approx(tuple(np.quantile(values[:12], [0.05, 0.95])))
        assert not row["determined"] and np.isnan(row["sd"])
        assert row["cycles"] == 12 and row["determining"] == 12 * determined[0]
    as_read = cycles_table(values, np.where(np.arange(13) < 4, "True", "False"), implausible)  # from a CSV
    assert pool_cycles(as_read).loc["f_h", "determining"] == 4
    flat = pooled_row(cycles_table(values, np.ones(13, bool), implausible), level=0.5)
    assert flat["n_cycles"] == 12 and flat["f_h_determined"] is False
    assert flat["f_h_high"] == pytest.approx(np.quantile(values[:12], 0.75))
    with pytest.raises(ValueError, match="level"):
        pool_cycles(cycles_table(values, np.ones(13, bool)), level=90)


def test_a_batch_gives_one_row_per_record_and_keeps_a_failure_and_its_reason():
    good = cycles_table([2.4, 2.6, 2.5], [True] * 3)
    bad = pd.DataFrame([{"record": "flat.csv", "mass": 70.0, "status": "failed", "reason": "not a bouncing record"}])
    only_implausible = cycles_table([9.0], [False], implausible=np.array([True])).assign(record="odd.csv")
    people = pooled_people(pd.concat([good, bad, only_implausible], ignore_index=True)).set_index("record")
    assert list(people.index) == ["r.csv", "flat.csv", "odd.csv"]
    assert people.loc["r.csv", "f_h"] == 2.5 and people.loc["r.csv", "n_cycles"] == 3
    assert people.loc["r.csv", "f_b"] == 2.0 and people.loc["r.csv", "status"] == "ok"
    assert people.loc["flat.csv", "reason"] == "not a bouncing record"
    assert people.loc["odd.csv", "status"] == "failed" and people.loc["odd.csv", "reason"] == \
        "no plausible identified cycle"


def test_the_comparison_figure_draws_each_answer_filled_where_determined_and_hollow_where_not():
    from matplotlib.colors import to_rgba

    from smd_statespace.plotting.cycles import plot_comparison

    table = cycles_table([2.4, 2.6, 2.5], [False] * 3).assign(t_start=[0.0, 0.5, 1.0], t_end=[0.5, 1.0, 1.5],
                                                              xi_h=0.3, xi_h_sd=0.1, xi_h_determined=False)
    answers = pd.DataFrame([{"f_h": 2.6, "f_h_low": 2.4, "f_h_high": 2.8, "f_h_determined": True},
                            {**pooled_row(table, parameters=("f_h",))}], index=["record", "ekf"])
    fig = plot_comparison({"ekf": table}, truth={"f_h": 2.6}, names=("f_h", "xi_h"), answers=answers)
    assert len(fig.axes) == 4  # the cycles and, beside them, the answers, per parameter
    markers = [line for line in fig.axes[1].get_lines() if line.get_marker() == "o"]
    faces = {line.get_xdata()[0]: to_rgba(line.get_markerfacecolor()) for line in markers}
    assert faces[0] != to_rgba("white") and faces[1] == to_rgba("white")  # record determined, the cycles not
    assert [t.get_text() for t in fig.axes[3].get_xticklabels()] == ["record", "ekf"]
