"""Reliability: arbitrary input gives a record or a typed error, never a crash; failures stay in their cycle.

Property-based (hypothesis): the CSV reader on arbitrary text and on numeric
tables with NaN, inf, huge and repeated values; the pipeline and the cycle
runner on arbitrary finite signals. The only exceptions allowed out are
:class:`~smd_statespace.errors.SMDInputError` subclasses, with one-line messages.
"""

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from smd_statespace.errors import OptionError, SMDInputError
from smd_statespace.estimators import get_estimator
from smd_statespace.io import G, make_record, read_record
from smd_statespace.model import SMDModel
from smd_statespace.identify.runner import CycleRunner
from smd_statespace.signals import preprocess
from smd_statespace.simulation import simulate_bouncing

QUICK = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])

cells = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(-10**30, 10**30).map(str),
    st.sampled_from(["", "nan", "inf", "-inf", "abc", "1e400", " 700 ", "7,0", '"700"', "0x1F"]),
)


def assert_finite_or_explained(table):
    """Every value of an identified cycle is finite; every failed cycle says why."""
    ok = table[table["status"] == "ok"]
    numeric = ok.select_dtypes("number").drop(columns=[c for c in ok if c.endswith("width_ratio")], errors="ignore")
    assert np.all(np.isfinite(numeric.to_numpy(dtype=float)))
    assert (table.loc[table["status"] == "failed", "reason"].str.len() > 0).all()


def identified_or_refused(identify):
    """Run ``identify()``: either a typed one-line error, or a table that passes :func:`assert_finite_or_explained`."""
    try:
        table = identify()
    except SMDInputError as error:
        assert one_line(error)
        event(f"typed error: {type(error).__name__}")
        return
    event("identified")
    assert_finite_or_explained(table)


def one_line(error) -> bool:
    return "\n" not in str(error).strip() and str(error).strip() != ""


@QUICK
@given(text=st.text(max_size=400))
def test_reader_on_arbitrary_text(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("csv") / "r.csv"
    path.write_text(text, encoding="utf-8")
    try:
        record = read_record(path, 70.0)
    except SMDInputError as error:
        assert one_line(error) and "r.csv" in str(error)
    else:
        assert np.all(np.isfinite(record.force)) and np.all(np.diff(record.time) > 0)


@QUICK
@given(header=st.sampled_from(["time,force", "time,force,floor_acc", "force,time", "time;force", "time,force,x"]),
       rows=st.lists(st.lists(cells, min_size=1, max_size=4), min_size=0, max_size=30))
def test_reader_on_numeric_tables_with_bad_values(tmp_path_factory, header, rows):
    path = tmp_path_factory.mktemp("csv") / "t.csv"
    path.write_text(header + "\n" + "\n".join(",".join(row) for row in rows) + "\n", encoding="utf-8")
    try:
        record = read_record(path, 70.0)
    except SMDInputError as error:
        assert one_line(error) and "t.csv" in str(error)
    else:
        assert record.time.size >= 3 and np.all(np.isfinite(record.force))


@QUICK
@given(fs=st.floats(20.0, 400.0), n=st.integers(3, 1500),
       force=st.lists(st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False), min_size=1, max_size=50),
       seed=st.integers(0, 2**32 - 1))
def test_pipeline_and_runner_on_arbitrary_finite_signals(fs, n, force, seed):
    """Any finite signal: a typed error or cycles whose every reported value is finite."""
    rng = np.random.default_rng(seed)
    values = np.resize(np.asarray(force, dtype=float), n) + rng.normal(0.0, 1.0, n) * np.ptp(force)
    values = values - values.mean() + 70.0 * G  # about the body weight, so the unit check lets some through
    time = np.arange(n) / fs
    runner = CycleRunner(SMDModel(n_harmonics=2), estimator="ekf", max_passes=1, progress=False)
    identified_or_refused(lambda: runner.run(preprocess(make_record(time, values, 70.0, source="prop"))))


@pytest.fixture(scope="module")
def record():
    return preprocess(simulate_bouncing(mass=70.0, f_b=2.0, f_h=2.5, xi_h=0.3, duration=8.0, seed=3).record)


@pytest.mark.parametrize("error", [FloatingPointError("overflow in the transition"),
                                   np.linalg.LinAlgError("Singular matrix")])
def test_a_diverging_cycle_fails_alone(record, monkeypatch, error):
    """A cycle whose filter blows up is marked failed with the reason; the other cycles are identified."""
    estimator = get_estimator("ekf")
    original = type(estimator).run
    victim = record.valid_cycles[1].index

    def run(self, model, data, *args, **kwargs):
        if data.index == victim:
            raise error
        return original(self, model, data, *args, **kwargs)

    monkeypatch.setattr(type(estimator), "run", run)
    table = CycleRunner(estimator=estimator, max_passes=2, progress=False).run(record)
    failed = table[table["status"] == "failed"]
    assert failed["cycle"].tolist() == [victim]
    assert type(error).__name__ in failed["reason"].iloc[0]
    assert (table["status"] == "ok").sum() == len(record.valid_cycles) - 1
    assert table.loc[table["cycle"] == victim, ["f_h", "xi_h"]].isna().all(axis=None)  # no value reported


def test_a_non_finite_estimate_is_a_failure_not_a_nan_in_the_table(record, monkeypatch):
    import smd_statespace.identify.runner as runner

    summarise = runner.summarise

    def poisoned(model, result, mass):
        out = summarise(model, result, mass)
        out["xi_h"] = float("nan")
        return out

    monkeypatch.setattr(runner, "summarise", poisoned)
    table = CycleRunner(estimator="ekf", max_passes=1, progress=False).run(record)
    assert (table["status"] != "ok").all()
    assert table.loc[table["status"] == "failed", "reason"].str.contains("non-finite xi_h").all()


def test_sampling_too_slow_for_the_harmonics_is_refused(record):
    with pytest.raises(OptionError, match=r"too slowly for force harmonic 30 .* lower --harmonics"):
        CycleRunner(SMDModel(n_harmonics=30), estimator="ekf", progress=False).run(record)
    from smd_statespace.effects import Harmonics

    with pytest.raises(OptionError, match="force harmonic 25"):
        CycleRunner(SMDModel(n_harmonics=20, effects=[Harmonics(count=5)]), estimator="ekf",
                    progress=False).run(record)


def test_same_seed_same_table(record):
    tables = [CycleRunner(estimator="pf", n_particles=300, max_passes=2, seed=8, progress=False).run(record)
              for _ in range(2)]
    pd.testing.assert_frame_equal(*(t.drop(columns="seconds") for t in tables))


@pytest.mark.slow
@QUICK
@given(f_b=st.floats(1.3, 3.8), amplitudes=st.lists(st.floats(0.0, 600.0), min_size=1, max_size=8),
       spikes=st.lists(st.tuples(st.integers(0, 1199), st.floats(-5e4, 5e4)), max_size=5),
       noise=st.floats(0.0, 200.0), seed=st.integers(0, 2**32 - 1))
def test_runner_on_arbitrary_bouncing_like_signals(f_b, amplitudes, spikes, noise, seed):
    """Periodic signals with arbitrary harmonics, spikes and noise: every ok row finite, failures explained."""
    rng = np.random.default_rng(seed)
    time = np.arange(1200) / 100.0
    phases = rng.uniform(0, 2 * np.pi, len(amplitudes))
    force = 70.0 * G + sum(a * np.cos(2 * np.pi * (k + 1) * f_b * time + p)
                           for k, (a, p) in enumerate(zip(amplitudes, phases)))
    force = force + rng.normal(0.0, noise, time.size)
    for index, value in spikes:
        force[index] += value
    identified_or_refused(lambda: CycleRunner(estimator="ekf", max_passes=1, progress=False).run(
        preprocess(make_record(time, force, 70.0, source="periodic"))))
