"""The cycle runner: repeated passes, the ±5 % rule, table columns, failures, reproducibility."""

from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pandas as pd
import pytest

from smd_statespace.errors import OptionError
from smd_statespace.estimators import Estimator, EstimatorFailure, FilterResult, GaussianStart
from smd_statespace.model import SMDModel
from smd_statespace.identify.plausibility import MAX_BLF, PRIOR_MARGIN, implausible_reasons
from smd_statespace.determined import DETERMINED_FRACTION
from smd_statespace.identify.runner import CycleRunner, converged
from smd_statespace.signals import preprocess
from smd_statespace.simulation import simulate_bouncing


@pytest.fixture(scope="module")
def record():
    return preprocess(simulate_bouncing(mass=64.0, f_b=2.2, f_h=2.6, xi_h=0.35, duration=9.0, seed=21).record)


class ScriptedEstimator(Estimator):
    """Reports f_h = 2 + 1 / 2**pass and fixed other values; fails on one cycle."""

    name = "scripted"

    def __init__(self, fail_cycle=None):
        self.fail_cycle = fail_cycle

    def run(self, model, data, start=None, rng=None, fixed=None):
        if data.index == self.fail_cycle:
            raise EstimatorFailure(f"cycle {data.index}: scripted failure")
        number = 1 if start is None else start.mean[0] + 1
        x = np.zeros(model.n_state)
        x[model.index("f_h")] = 2.0 + 1.0 / 2**number
        x[model.index("xi_h")] = 0.3
        x[model.index("a1")], x[model.index("b1")] = 0.3, 0.4
        x[model.index("a2")] = 0.1
        x[model.index("a3")] = x[model.index("a4")] = 0.05
        sd = np.full(model.n_state, 0.01)
        m = len(data)
        restart = GaussianStart(np.r_[number, np.zeros(model.n_state - 1)], np.eye(model.n_state))
        return FilterResult(self.name, model.state_names, data.t, np.tile(x, (m, 1)), np.tile(sd, (m, 1)),
                            np.zeros((m, model.n_obs)), np.tile(np.eye(model.n_obs), (m, 1, 1)), -1.0 * number,
                            restart, np.full(model.n_state, 0.5))


def test_convergence_rule_stops_where_it_should(record):
    # f_h per pass: 2.5, 2.25, 2.125, 2.0625, 2.03125 -> relative changes 10 %, 5.6 %, 2.9 %: stops at pass 4.
    runner = CycleRunner(estimator=ScriptedEstimator(), progress=False, max_passes=10)
    table = runner.run(record)
    ok = table[table.status == "ok"]
    assert (ok.passes == 4).all() and ok.converged.all()
    assert ok.f_h.iloc[0] == pytest.approx(2.0625)
    history = runner.history_[int(ok.cycle.iloc[0])]
    assert [h["f_h"] for h in history] == [2.5, 2.25, 2.125, 2.0625]
    tight = CycleRunner(estimator=ScriptedEstimator(), progress=False, max_passes=10, tolerance=0.01).run(record)
    assert (tight[tight.status == "ok"].passes == 6).all()
    capped = CycleRunner(estimator=ScriptedEstimator(), progress=False, max_passes=3).run(record)
    assert (capped[capped.status == "ok"].passes == 3).all() and not capped.converged.any()


def test_convergence_rule_function():
    model = SMDModel(n_harmonics=1)
    base = {"f_h": 2.0, "xi_h": 0.3, "blf_1": 0.2}
    assert converged(base, dict(base, f_h=2.09), model, 0.05)
    assert not converged(base, dict(base, f_h=2.11), model, 0.05)
    assert not converged(base, dict(base, blf_1=0.22), model, 0.05)
    # Tiny values are judged against the floor, not their own size.
    small = dict(base, xi_h=0.001)
    assert converged(small, dict(small, xi_h=0.003), model, 0.05)


def test_table_columns_and_derived_quantities(record):
    table = CycleRunner(estimator="ekf", progress=False, max_passes=3).run(record)
    required = ["cycle", "t_start", "t_end", "f_b", "f_h", "f_h_sd", "xi_h", "xi_h_sd", "blf_1", "blf_2", "blf_3",
                "blf_4", "a0", "k_h", "c_h", "passes", "converged", "log_likelihood", "estimator",
                "f_h_determined", "xi_h_determined", "blf_1_determined"]
    assert all(column in table.columns for column in required)
    ok = table[table.status == "ok"]
    assert len(ok) >= 10
    mass = record.mass
    np.testing.assert_allclose(ok.k_h, mass * (2 * np.pi * ok.f_h) ** 2)  # Eq. 17
    np.testing.assert_allclose(ok.c_h, 2 * ok.xi_h * mass * 2 * np.pi * ok.f_h)  # Eq. 18
    np.testing.assert_allclose(ok.blf_2, np.hypot(ok.a2, ok.b2))  # Eq. 5
    np.testing.assert_allclose(ok.f_b, 1 / (ok.t_end - ok.t_start))
    assert (ok.estimator == "ekf").all()
    skipped = table[table.status == "skipped"]
    assert len(skipped) == len(record.cycles) - len(record.valid_cycles)
    assert skipped.reason.str.len().min() > 0


def test_failure_in_one_cycle_is_contained(record):
    bad = record.valid_cycles[2].index
    table = CycleRunner(estimator=ScriptedEstimator(fail_cycle=bad), progress=False).run(record)
    row = table.set_index("cycle").loc[bad]
    assert row.status == "failed" and "scripted failure" in row.reason and not row.converged
    assert np.isnan(row.f_h)
    assert (table[(table.status != "skipped") & (table.cycle != bad)].status == "ok").all()


def test_same_seed_same_table_whatever_the_number_of_jobs(record):
    options = dict(estimator="pf", n_particles=200, max_passes=2, progress=False, seed=5)
    serial = CycleRunner(**options).run(record)
    again = CycleRunner(**options).run(record)
    with ProcessPoolExecutor(max_workers=2) as pool:
        parallel = CycleRunner(executor=pool, **options).run(record)
    columns = [c for c in serial.columns if c != "seconds"]
    pd.testing.assert_frame_equal(serial[columns], again[columns])
    pd.testing.assert_frame_equal(serial[columns], parallel[columns])
    other = CycleRunner(**dict(options, seed=6)).run(record)
    assert not np.allclose(other.f_h.dropna(), serial.f_h.dropna())


def test_grid_runs_one_pass(record):
    table = CycleRunner(estimator="grid", progress=False, f_h_points=9, xi_h_points=7).run(record)
    ok = table[table.status == "ok"]
    assert (ok.passes == 1).all() and ok.converged.all()


@pytest.mark.parametrize(
    "kwargs,pattern",
    [({"estimator": "kalman"}, "unknown estimator 'kalman'"), ({"estimator": "pf", "n_particles": 0}, "n_particles"),
     ({"max_passes": 0}, "max_passes"), ({"tolerance": 5}, "tolerance"), ({"seed": -1}, "seed"),
     ({"rate": 0}, "rate=0"), ({"rate": "fast"}, "rate='fast'")],
)
def test_bad_runner_options(kwargs, pattern):
    with pytest.raises(OptionError, match=pattern):
        CycleRunner(**kwargs)


def test_failed_cycle_leaves_no_stale_result(record):
    class FailsOnSecondPass(ScriptedEstimator):
        def run(self, model, data, start=None, rng=None, fixed=None):
            if start is not None and data.index == self.fail_cycle:
                raise EstimatorFailure(f"cycle {data.index}: failed on pass 2")
            return super().run(model, data, start, rng, fixed)

    bad = record.valid_cycles[1].index
    runner = CycleRunner(estimator=FailsOnSecondPass(fail_cycle=bad), progress=False)
    table = runner.run(record)
    assert table.set_index("cycle").loc[bad, "status"] == "failed"
    assert bad not in runner.results_


# ---------------------------------------------------------------------------
# estimates that cannot be true


class ImpossibleEstimator(Estimator):
    """Claims every parameter determined (sd 0.01 over prior sd 0.1); on chosen cycles, with impossible values."""

    name = "impossible"

    def __init__(self, overrides):
        self.overrides = overrides  # cycle index -> {slot: value}

    def run(self, model, data, start=None, rng=None, fixed=None):
        values = {"f_h": 2.5, "xi_h": 0.3, "a1": 0.2, "b1": 0.15, "a2": 0.1, "b2": 0.05, "a3": 0.03, "a4": 0.01}
        values.update(self.overrides.get(data.index, {}))
        x = np.zeros(model.n_state)
        for name, value in values.items():
            x[model.index(name)] = value
        m = len(data)
        restart = GaussianStart(x, np.eye(model.n_state))
        return FilterResult(self.name, model.state_names, data.t, np.tile(x, (m, 1)),
                            np.tile(np.full(model.n_state, 0.01), (m, 1)), np.zeros((m, model.n_obs)),
                            np.tile(np.eye(model.n_obs), (m, 1, 1)), -1.0, restart, np.full(model.n_state, 0.1))


def test_impossible_cycles_are_flagged_never_determined_and_left_out_of_the_summary(record):
    from smd_statespace.cli.identify import implausible_warning, run_summary, summary_table

    cycles = [c.index for c in record.valid_cycles]
    model = SMDModel()
    prior = model.slots[model.index("f_h")]
    overrides = {cycles[0]: {"xi_h": -0.05},                      # negative damping: C_h < 0 too
                 cycles[1]: {"f_h": prior.high - 0.5 * PRIOR_MARGIN * (prior.high - prior.low)},  # at 4 Hz
                 cycles[2]: {"f_h": 5.41},                        # beyond the prior (the 0.38-5.41 Hz)
                 cycles[3]: {"a1": 0.39, "b1": 0.39}}             # two coefficients on their bound
    table = CycleRunner(model, estimator=ImpossibleEstimator(overrides), progress=False).run(record)
    ok = table[table.status == "ok"].set_index("cycle")
    assert ok.loc[cycles[0], "implausible_reason"] == "xi_h < 0; C_h < 0" and ok.loc[cycles[0], "c_h"] < 0
    assert ok.loc[cycles[1], "implausible_reason"] == "f_h on prior bound"
    assert ok.loc[cycles[2], "implausible_reason"] == "f_h outside prior"
    assert ok.loc[cycles[3], "implausible_reason"] == "a1 on prior bound; b1 on prior bound"
    bad = ok.index.isin(list(overrides))
    assert ok.implausible.tolist() == bad.tolist()
    assert (ok.loc[~bad, "implausible_reason"] == "").all()
    determined = [c for c in ok.columns if c.endswith("_determined")]
    assert not ok.loc[bad, determined].any().any()       # never determined, whatever the filter claims
    assert ok.loc[~bad, determined].all().all()
    assert (ok.loc[bad, "f_h_width_ratio"] < DETERMINED_FRACTION).all()  # the filter's own claim stays readable
    skipped = table[table.status == "skipped"]
    assert len(skipped) and not skipped.implausible.any()

    summary = summary_table(table)
    assert summary.loc["f_h", "median"] == 2.5 and summary.loc["f_h", "q25"] == 2.5  # the impossible ones left out
    assert summary.loc["xi_h", "determined_%"] == 100.0
    warning = implausible_warning(table)
    assert warning.startswith(f"warning: 4 of {len(ok)} identified cycles gave estimates that cannot be true")
    for reason in ("xi_h < 0: 1", "f_h on prior bound: 1", "f_h outside prior: 1", "a1 on prior bound: 1"):
        assert reason in warning
    assert "4 implausible" in run_summary(table, 1.0)
    from smd_statespace.plotting.cycles import plot_parameters

    f_h_axes = plot_parameters(table).axes[0]
    crosses = [c for c in f_h_axes.containers if c.get_label() == "implausible"]
    assert len(crosses) == 1 and len(crosses[0].lines[0].get_xdata()) == 4  # drawn apart, as red crosses
    everything_bad = CycleRunner(model, estimator=ImpossibleEstimator({c: {"xi_h": -0.1} for c in cycles}),
                                 progress=False).run(record)
    assert summary_table(everything_bad).empty  # nothing to summarise, and no KeyError


def test_physical_limits_of_a_cycle():
    table = pd.DataFrame({"f_b": [2.0, 2.0, 2.0, 2.0, 2.0], "f_h": [2.5, 2.5, 4.0, 2.5, 2.5],
                          "xi_h": [0.3, 0.3, 0.01, 0.3, 0.3], "c_h": [800.0, 800.0, 30.0, 800.0, -1.0],
                          "blf_1": [0.3, MAX_BLF + 0.1, 0.2, 0.3, 0.3], "blf_2": [0.15, 0.1, 0.1, 0.15, 0.15]})
    reasons = implausible_reasons(table)  # no model: no prior bounds, physics only
    assert reasons.tolist() == ["", "BLF_1 > 2 g", "GRF harmonic 2 > 2 g", "", "C_h < 0"]
    # GRF harmonic 2 of cycle 2: 0.1 g at resonance (2 f_b = f_h) with xi_h 0.01 is 0.1 / 0.02 = 5 g on the floor.


def test_clean_record_has_no_implausible_cycle(record):
    table = CycleRunner(estimator="ekf", progress=False).run(record)
    ok = table[table.status == "ok"]
    assert len(ok) >= 10 and not ok.implausible.any() and (ok.implausible_reason == "").all()


def test_identify_warns_about_impossible_cycles_of_a_record_with_extra_harmonics(tmp_path, capsys):
    from smd_statespace.cli import main

    record = tmp_path / "rec.csv"
    # Two force harmonics beyond the model's four: the base model's EKF answers f_h beyond its own prior.
    assert main(["simulate", "--out", str(record), "--mass", "65", "--fb", "2.0", "--fh", "2.5", "--xi", "0.3",
                 "--duration", "8", "--seed", "3", "--blf", "0.25,0.15,0.05,0.02,0.06,0.05"]) == 0
    capsys.readouterr()
    out = tmp_path / "id"
    assert main(["identify", str(record), "--mass", "65", "--estimator", "ekf", "--out", str(out), "--quiet"]) == 0
    printed = capsys.readouterr().out
    table = pd.read_csv(out / "results.csv")
    ok = table[table.status == "ok"]
    n_bad = int(ok.implausible.sum())
    assert n_bad >= len(ok) // 2 and ok.loc[ok.implausible, "f_h"].gt(4.0).any()
    assert not ok.loc[ok.implausible, "f_h_determined"].any()
    warnings = [line for line in printed.splitlines() if line.startswith("warning: ")]
    assert len(warnings) == 1 and f"{n_bad} of {len(ok)} identified cycles" in warnings[0]
    assert "f_h outside prior" in warnings[0] and f"{n_bad} implausible" in printed


def test_comparison_figure_draws_a_simulations_truth_on_every_panel_and_takes_a_title():
    """A simulation's truth (``blf`` as a list) gives dashed truth lines on the BLF panels too."""
    from smd_statespace.plotting.cycles import plot_comparison

    table = pd.DataFrame({"status": ["ok"] * 3, "t_start": [0.0, 0.5, 1.0], "t_end": [0.5, 1.0, 1.5],
                          "f_h": [2.4, 2.5, 2.6], "xi_h": [0.3] * 3, "blf_1": [0.2] * 3, "blf_2": [0.1] * 3})
    truth = {"f_h": 2.5, "xi_h": 0.3, "blf": [0.25, 0.15, 0.05]}
    fig = plot_comparison({"model A": table, "model B": table}, truth=truth, title="Two models compared")
    for ax, expected in zip(fig.axes, (2.5, 0.3, 0.25, 0.15)):
        lines = [line for line in ax.get_lines() if line.get_label() == "truth"]
        assert len(lines) == 1 and lines[0].get_ydata()[0] == expected
    assert fig._suptitle.get_text().startswith("Two models compared")


def test_a_fast_record_is_decimated_before_its_cycles_and_the_runner_says_so():
    fast = simulate_bouncing(mass=64.0, f_b=2.2, f_h=2.6, xi_h=0.35, duration=9.0, fs=1000.0, seed=21).record
    runner = CycleRunner(estimator=ScriptedEstimator(), progress=False)
    table = runner.run(fast)
    assert runner.preprocessed_.fs == pytest.approx(100.0)
    assert runner.notes_ == ["fitted at 100 Hz: the record (1000 Hz) was low-pass filtered and one sample in 10 "
                             "kept (the rate asked: 100 Hz; to keep every sample, rate=None in Python or --rate 0 "
                             "on the command line)"]
    every = CycleRunner(estimator=ScriptedEstimator(), progress=False, rate=None)
    full = every.run(fast)
    assert every.preprocessed_.fs == pytest.approx(1000.0) and every.notes_ == []
    # the same bouncing cycles, found from a tenth of the samples (starts within two 100 Hz samples)
    assert list(table.status) == list(full.status)
    np.testing.assert_allclose(table.t_start, full.t_start, atol=0.02)
    # each cycle's f_b is quantised by the 10 ms samples (about 2 % at 2.2 Hz), their mean is not
    np.testing.assert_allclose(table.f_b, full.f_b, rtol=0.05)
    assert table.f_b.mean() == pytest.approx(full.f_b.mean(), rel=0.005)
    # a pipeline output is used as it is: the user preprocessed it, the runner does not decimate it again
    given = CycleRunner(estimator=ScriptedEstimator(), progress=False)
    given.run(preprocess(fast))
    assert given.preprocessed_.fs == pytest.approx(1000.0) and given.notes_ == []
