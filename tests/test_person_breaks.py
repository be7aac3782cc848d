"""The step scan (person.breaks): each of its statistics is the score test of a step at that sample, its
supremum's p-value that of Andrews' distribution, and a step of f_h placed where it is, to the sample."""

import numpy as np
import pytest

from smd_statespace.effects import GenericTerm
from smd_statespace.person import identify_person
from smd_statespace.person.breaks import located_step, short_fraction, step_scan
from smd_statespace.person.supremum import critical_value, log_p_value, sup_p_value
from smd_statespace.person.screen import score_test
from smd_statespace.simulation import simulate_bouncing

PERSON = dict(mass=70, f_b=2.2, f_h=2.7, xi_h=0.3, duration=20)


@pytest.fixture(scope="module")
def clean():
    return identify_person(simulate_bouncing(**PERSON, seed=5).record, check_change=False)


def test_each_statistic_of_the_scan_is_the_score_test_of_a_step_at_that_sample(clean):
    time = clean.model.time
    start, length = float(time[0]), float(time[-1] - time[0])
    for kind in ("f_step", "xi_step"):
        scan = step_scan(clean, kind)
        # the first and last times, and those next to where the scan's two reference steps are (0.3 and 0.7)
        near = [int(np.argmin(np.abs(scan["at"] - at))) for at in (0.3, 0.7)]
        for row in [0, len(scan) - 1] + [i + d for i in near for d in (-1, 0, 1)]:
            moment = float(scan["time_s"].iloc[row])
            exact = score_test(clean, GenericTerm(kind, scale=length, start=start, at=(moment - start) / length - 1e-9))
            assert scan["lm"].iloc[row] == pytest.approx(exact["lm"], rel=1e-6, abs=1e-9)
            assert scan["lm_robust"].iloc[row] == pytest.approx(exact["lm_robust"], rel=1e-6, abs=1e-9)
    assert scan["at"].between(0.15, 0.85).all() and scan["time_s"].is_monotonic_increasing


def test_the_supremum_p_value_is_that_of_a_squared_standardised_brownian_bridge():
    rng = np.random.default_rng(np.random.SeedSequence(2024))
    n, paths = 1000, 4000
    walk = np.cumsum(rng.standard_normal((paths, n)), axis=1) / np.sqrt(n)
    t = np.arange(1, n + 1) / n
    bridge = walk - t * walk[:, -1:]
    inside = (t >= 0.15) & (t <= 0.85)
    sup = np.max(bridge[:, inside] ** 2 / (t[inside] * (1 - t[inside])), axis=1)
    for level in (8.85, 12.0):
        assert np.mean(sup > level) == pytest.approx(sup_p_value(level, 0.15), abs=0.012)
    assert sup_p_value(3.84, 0.15) > 0.3  # chi-square(1)'s 5 % point is no evidence as the largest of many
    for p in (0.05, 1e-3, 1e-8):  # the level lines of the figures invert the p-value
        assert sup_p_value(critical_value(p, 1, 0.15), 0.15) == pytest.approx(p, rel=1e-6)
    assert critical_value(0.05, 1) == pytest.approx(3.8415, abs=1e-4)
    effect = GenericTerm("f_step", scale=20.0)
    assert log_p_value(10.0, 1, [effect]) == pytest.approx(np.log(0.0016), rel=0.01)  # chi-square(1): no scan
    effect.scan = {"trim": 0.15}
    assert log_p_value(10.0, 1, [effect]) == pytest.approx(np.log(sup_p_value(10.0, 0.15)))


def test_a_step_of_f_h_is_placed_where_it_is_and_a_clean_record_has_none(clean):
    assert located_step(clean, "f_step").scan["p"] > 0.01
    at = 0.43  # not one of the library's fixed steps
    time = clean.model.time
    step = GenericTerm("f_step", scale=20.0, start=0.0, at=at).with_values(c_f_step=0.3)
    person = identify_person(simulate_bouncing(**PERSON, seed=5, effects=[step]).record, check_change=False)
    found = located_step(person, "f_step")
    assert found.scan["time_s"] == pytest.approx(at * 20.0, abs=2.5 * float(np.diff(time).mean()))
    assert found.scan["p"] < 1e-6
    # the spec diagnose prints is short, and the step sits in the second half of the interval before its sample
    options = dict(part.split("=") for part in found.spec.split(":", 1)[1].split(","))
    assert len(options["at"]) <= 8 and len(options["scale"]) <= 8, found.spec
    sample = int(np.searchsorted(person.model.time, found.scan["time_s"]))
    before, after = person.model.time[sample - 1: sample + 1]
    assert 0.5 * (before + after) < found.breaks[0] < after


def test_a_short_fraction_stays_between_its_bounds():
    assert short_fraction(9.995, 10.0, 0.0, 20.0) == 0.4999  # 9.998 s
    assert short_fraction(9.9950001, 9.9950002, 0.0, 20.0) * 20.0 == pytest.approx(9.99500015, abs=5e-8)
    assert 4.81 + short_fraction(19.925, 19.93, 4.81, 30.4) * 30.4 < 19.93
