"""The person over the record when a time term lets f_h change (person.in_time): the values either side of a step
recover the simulated person's, their delta-method sds are those of the values' own spread, a drift is given at
the span's ends, and a person without a time term has no such table."""

from types import SimpleNamespace

import numpy as np
import pytest

from smd_statespace.effects import GenericTerm
from smd_statespace.person import identify_person
from smd_statespace.person.in_time import in_time_words, person_in_time
from smd_statespace.simulation import simulate_bouncing

PERSON = dict(mass=70, f_b=2.2, f_h=2.7, xi_h=0.3, duration=20)


def stand_in(effects, values, cov, intervals, time=(2.0, 22.0), determined=True):
    """A fitted result reduced to what person_in_time reads: f_h, xi_h, then the effects' coefficients."""
    names = ["f_h", "xi_h"] + [effect.coefficient for effect in effects]
    model = SimpleNamespace(time=np.linspace(*time, 2001), unpack=lambda params: dict(zip(names, params)),
                            position=names.index)
    return SimpleNamespace(model=model, params=np.array(values, dtype=float), cov=np.array(cov, dtype=float),
                           intervals=intervals, level=0.9, effects=tuple(effects), determined=lambda name: determined)


def test_a_step_of_f_h_is_given_either_side_with_the_simulated_values_inside_the_intervals():
    at = 0.43
    step = GenericTerm("f_step", scale=PERSON["duration"], at=at)
    record = simulate_bouncing(**PERSON, seed=11, effects=[step.with_values(c_f_step=0.3)]).record
    result = identify_person(record, effects=[step], check_change=False)
    table = result.in_time()
    assert list(table["side"]) == ["start", "before", "after", "end"]
    assert table["time_s"].iloc[1] == pytest.approx(at * PERSON["duration"])
    truth = {"before": PERSON["f_h"] * np.sqrt(1 - 0.15), "after": PERSON["f_h"] * np.sqrt(1 + 0.15)}
    for side, value in truth.items():
        row = table[table["side"] == side].iloc[0]
        assert row["f_h_low"] <= value <= row["f_h_high"], (side, row["f_h"], value)
        assert row["f_h"] == pytest.approx(value, rel=0.08)
    # the fitted f_h is the middle of the two in w_h^2; xi_h is not changed by a term of f_h
    assert np.mean(table["f_h"].iloc[[1, 2]] ** 2) == pytest.approx(result.f_h**2, rel=1e-9)
    assert np.allclose(table["xi_h"], result.xi_h)
    words = result.summary()
    line = next(line for line in words.splitlines() if line.startswith("  f_h in time"))
    start, moment, end = (f"{t:.2f}" for t in table["time_s"].iloc[[0, 1, 3]])
    assert f"{table['f_h'].iloc[0]:.2f} Hz" in line and f"in {start}-{moment} s" in line
    assert f"{table['f_h'].iloc[3]:.2f} Hz" in line and f"in {moment}-{end} s" in line
    assert "xi_h in time" not in words and result.to_dict()["in_time"][2]["side"] == "after"


def test_the_delta_method_sd_is_that_of_the_values_drawn_from_the_scaled_covariance():
    """f_h(t) = f_h sqrt(1 + c m(t)): draws of (f_h, xi_h, c) from the covariance, f_h and xi_h scaled to the
    widths of the result's intervals, give the same sd at both ends of a drift as the delta method."""
    drift = GenericTerm("f_drift", scale=20.0, start=2.0)
    values = [3.0, 0.3, 0.2]
    sd = np.array([0.01, 0.02, 0.004])  # raw sds; the intervals below make f_h's 0.03 and xi_h's 0.02
    correlation = np.array([[1.0, 0.3, -0.5], [0.3, 1.0, 0.1], [-0.5, 0.1, 1.0]])
    cov = correlation * np.outer(sd, sd)
    z = 1.6448536269514722
    result = stand_in([drift], values, cov, {"f_h": (3.0 - 0.03 * z, 3.0 + 0.03 * z), "xi_h": (0.3 - 0.02 * z,
                                                                                              0.3 + 0.02 * z)})
    table = person_in_time(result)
    assert list(table["side"]) == ["start", "end"]
    scaled = cov * np.outer([3.0, 1.0, 1.0], [3.0, 1.0, 1.0])
    draws = np.random.default_rng(np.random.SeedSequence(7)).multivariate_normal(values, scaled, 200_000)
    for row, moment in zip(table.itertuples(), (-0.5, 0.5)):
        spread = draws[:, 0] * np.sqrt(1 + draws[:, 2] * moment)
        assert row.f_h == pytest.approx(3.0 * np.sqrt(1 + 0.2 * moment), rel=1e-12)
        assert row.f_h_sd == pytest.approx(np.std(spread), rel=0.02)
        assert row.xi_h == pytest.approx(0.3) and row.xi_h_sd == pytest.approx(0.02, rel=1e-9)
    line = in_time_words(result)[0]
    assert f"{table['f_h'].iloc[0]:.2f} Hz" in line and "at 2.00 s" in line and "at 22.00 s" in line
    assert "linearly in w_h^2 between" in line and "NOT DETERMINED" not in line


def test_a_damping_step_changes_xi_h_alone_and_an_undetermined_person_is_said_so():
    step = GenericTerm("xi_step", scale=20.0, start=2.0, at=0.5)
    result = stand_in([step], [3.0, 0.3, 0.4], np.diag([0.01, 0.02, 0.05]) ** 2,
                      {"f_h": (2.9, 3.1), "xi_h": (0.25, 0.35)}, determined=False)
    table = person_in_time(result)
    assert np.allclose(table["xi_h"], [0.3 * 0.8, 0.3 * 0.8, 0.3 * 1.2, 0.3 * 1.2]) and np.allclose(table["f_h"], 3.0)
    (line,) = in_time_words(result)
    assert line.startswith("  xi_h in time") and "in 2.00-12.00 s" in line and line.endswith("NOT DETERMINED")


def test_a_person_without_a_time_term_has_no_table():
    cubic = SimpleNamespace(coefficient="beta_3")  # an effect with no parameter that changes in time
    result = stand_in([cubic], [3.0, 0.3, 1.0], np.eye(3) * 1e-4, {"f_h": (2.9, 3.1), "xi_h": (0.25, 0.35)})
    assert person_in_time(result).empty and in_time_words(result) == []
