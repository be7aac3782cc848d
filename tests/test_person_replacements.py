"""The variation models re-placing their cycle starts side by side (``search.choose_with_own_timing``): a model
left far behind stops re-placing, and the answer is the one every model's full re-placements give."""

import math

import pytest

from smd_statespace.person import identify_person, search
from smd_statespace.simulation import simulate_bouncing


@pytest.fixture(scope="module")
def record():
    """12 s of a jumps record on which "smooth" trails "independent" by about 60 after the first re-placement."""
    return simulate_bouncing(mass=70, f_b=2.0, f_h=2.5, xi_h=0.3, duration=12, seed=3).record


def counting_fits(patch) -> list:
    """Count ``search.fit_model``'s calls (the quick fits of the re-placements among them) in a list."""
    calls, fit_model = [], search.fit_model
    patch.setattr(search, "fit_model", lambda *args, **kwargs: calls.append(1) or fit_model(*args, **kwargs))
    return calls


@pytest.fixture(scope="module")
def in_full(record):
    """The person with every model's re-placements made in full (no model stops), and its number of fits."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(search, "BEHIND", math.inf)
        fits = counting_fits(patch)
        return identify_person(record, check_change=False, threads=1), len(fits)


def replaced(result) -> dict:
    return {row.variation: row for row in result.comparison if row.timing == "re-placed"}


def test_a_model_far_behind_stops_re_placing_and_the_answer_stays(record, in_full, monkeypatch):
    fits = counting_fits(monkeypatch)
    result = identify_person(record, check_change=False, threads=1)
    in_full, fitted_in_full = in_full
    assert len(fits) < fitted_in_full
    assert result.model.variation == in_full.model.variation == "independent"
    assert (result.f_h, result.xi_h) == (in_full.f_h, in_full.xi_h)
    rows, full = replaced(result), replaced(in_full)
    assert rows["smooth"].loglike < full["smooth"].loglike  # it stopped before its last re-placements
    assert rows["smooth"].aic - rows["independent"].aic > 2 * search.BEHIND


def test_a_stop_behind_a_model_that_is_not_chosen_is_taken_back(record, in_full, monkeypatch):
    """Had the model chosen in the end been stopped behind another, every model re-places in full, as without the
    stop (and in two threads as in one)."""

    def behind_the_worst(chains, clean):
        worst = max(chains, key=lambda chain: chain.best[1]["params"].size - chain.best[1]["loglike"])
        return worst, [chain for chain in chains if chain is not worst and not chain.finished]

    monkeypatch.setattr(search, "_left_behind", behind_the_worst)
    fits = counting_fits(monkeypatch)
    result = identify_person(record, check_change=False, threads=2)
    in_full, fitted_in_full = in_full
    assert len(fits) == fitted_in_full
    assert (result.f_h, result.xi_h) == (in_full.f_h, in_full.xi_h)
    assert [row.loglike for row in result.comparison] == [row.loglike for row in in_full.comparison]
