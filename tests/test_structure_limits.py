"""Published limits (smd_statespace.structure.limits): the numbers as read, the bands at and around their edges, a
value in each band, a sampled response classified, and a result's worst point in summary.json and the printout."""

import numpy as np
import pytest

from smd_statespace.structure import ROUTE2, Criterion, Limits, analyse_structure, draw_occupants, measures, sdof
from smd_statespace.structure.limits import G_SOURCE

WORDS = ["within the criteria of scenarios 2, 3 and 4",
         "exceeds the criterion of scenario 2; within the criteria of scenarios 3 and 4",
         "exceeds the criteria of scenarios 2 and 3; within the criterion of scenario 4",
         "exceeds the criteria of scenarios 2, 3 and 4"]


def test_route2_is_3_7p5_and_20_percent_g_on_the_unweighted_1s_rms_as_the_source_codes_it():
    assert ROUTE2.measure == "rms_1s_max" and G_SOURCE == 9.81
    assert [c.name for c in ROUTE2.criteria] == ["2", "3", "4"]
    assert [c.stated for c in ROUTE2.criteria] == ["3 %g", "7.5 %g", "20 %g"]
    assert ROUTE2.edges == pytest.approx([0.2943, 0.73575, 1.962], rel=1e-15)
    assert "ISBN 978-1-906335-12-0" in ROUTE2.citation and "sgettler/grandstand-dynamics" in ROUTE2.source
    assert "not checked against the guide's text" in ROUTE2.source


@pytest.mark.parametrize("value, band", [(0.0, 0), (0.1, 0), (0.5, 1), (1.0, 2), (3.0, 3)])
def test_a_value_in_each_band_gets_that_band_and_its_words(value, band):
    item = ROUTE2.classify(value)
    assert item["band"] == band and item["words"] == WORDS[band]
    assert item["within"] == {f"scenario {c.name}": k >= band for k, c in enumerate(ROUTE2.criteria)}
    assert item["percent_g"] == pytest.approx(100 * value / 9.81)


@pytest.mark.parametrize("k", [0, 1, 2])
def test_a_value_at_a_limit_is_within_it_and_the_next_float_above_is_not(k):
    edge = ROUTE2.edges[k]
    assert ROUTE2.band(edge) == k and ROUTE2.classify(edge)["within"][f"scenario {ROUTE2.criteria[k].name}"]
    assert ROUTE2.band(np.nextafter(edge, np.inf)) == k + 1
    assert ROUTE2.band(np.nextafter(edge, 0.0)) == k


def test_bands_cover_zero_to_infinity_with_the_criteria_as_edges():
    bands = ROUTE2.bands()
    assert [b["lower"] for b in bands] == [0.0, *ROUTE2.edges]
    assert [b["upper"] for b in bands] == [*ROUTE2.edges, None]
    assert [b["words"] for b in bands] == WORDS


@pytest.mark.parametrize("factor, band", [(0.999, 0), (1.001, 1)])
def test_a_sampled_sine_just_below_and_above_scenario_2s_criterion(factor, band):
    fs, f = 200.0, 2.0
    t = np.arange(0, 10.0, 1 / fs)
    a = factor * ROUTE2.edges[0] * np.sqrt(2.0) * np.sin(2 * np.pi * f * t)  # rms_1s_max = factor x the criterion
    value = measures(a, fs)["rms_1s_max"]
    assert value == pytest.approx(factor * ROUTE2.edges[0], rel=1e-9)
    assert ROUTE2.classify(value)["band"] == band


@pytest.mark.parametrize("value", [np.nan, -0.1, np.inf])
def test_a_value_that_is_no_rms_is_refused(value):
    with pytest.raises(ValueError, match="rms_1s_max must be a finite value >= 0"):
        ROUTE2.classify(value)


def test_limits_out_of_order_or_on_an_unknown_measure_are_refused():
    criteria = (Criterion("a", 2.0, "2", ""), Criterion("b", 1.0, "1", ""))
    with pytest.raises(ValueError, match="increasing order"):
        Limits("x", "rms_1s_max", "level", criteria, "c", "l", "s")
    with pytest.raises(ValueError, match="measure must be one of"):
        Limits("x", "rms", "level", criteria[1:], "c", "l", "s")


def test_a_results_points_in_the_summary_and_its_worst_point_in_the_printout():
    model = sdof()
    occupants = draw_occupants(model, 10, 0.5, seed=np.random.SeedSequence(3), f_b=2.0, duration=4.0, fs=200.0,
                               phase_spread=1.0)
    result = analyse_structure(model, occupants)
    summary = result.summary()
    assert summary["limits"]["name"] == ROUTE2.name and len(summary["limits"]["bands"]) == 4
    for item in summary["points"]:
        for model_name in ("coupled", "force_only"):
            value = item[model_name]["rms_1s_max"]
            assert item["limits"][model_name] == ROUTE2.classify(value)
    worst = result.classify()
    assert worst["point"] == summary["worst_point"]
    text = result.text()
    assert f"limits at {worst['point']} ({ROUTE2.label}):" in text
    assert f"coupled: {ROUTE2.sentence(worst['coupled']['value'])}" in text
    assert f"force-only: {ROUTE2.sentence(worst['force_only']['value'])}" in text
