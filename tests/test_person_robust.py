"""Likelihood ratios scaled for misspecification (:mod:`smd_statespace.person.robust`).

- the joint information and scores of the searched and the concentrated unknowns, with the concentrated ones
  profiled out, are exactly :func:`~smd_statespace.person.score.score`'s profile information and efficient
  scores, and the concentrated unknowns' scores sum to zero at their estimate;
- a record whose force varies as the model assumes gives weights ``I^-1 J`` near 1 (the plain ratio stands);
  a quiet plate (0.15 % of body weight), where the force's jumps from cycle to cycle are in the innovations,
  gives a cubic term's ratio a weight over 2.5, and ``diagnose``'s row tests the ratio over it.
"""

import numpy as np
import pytest
from scipy import stats

from smd_statespace.person import identify_person
from smd_statespace.person.diagnose import candidate_row
from smd_statespace.person.extend import fit_effects
from smd_statespace.person.robust import MIN_SCALE, added_unknowns, information_and_scores, misspecification_scale
from smd_statespace.person.score import profile_out, score
from smd_statespace.person.screen import generic_library
from smd_statespace.simulation import simulate_bouncing

TERMS = ("u3", "v_abs_v", "f_drift")
"""Generic terms fitted on each record: a cubic spring, a quadratic damper, a drift of ``f_h``."""


def person(noise):
    """The person of a 15 s record (f_b 2.2, f_h 2.8, xi_h 0.3) with plate noise ``noise`` (body weights), fitted as
    measured (no noise floor: the scale is shown on the quiet record itself)."""
    sim = simulate_bouncing(mass=70, f_b=2.2, f_h=2.8, xi_h=0.3, duration=15, seed=7, noise=noise)
    return identify_person(sim.record, variation="independent", noise_floor=None)


def fitted_terms(base) -> dict:
    """Each of :data:`TERMS` fitted with the person at its cycle starts, by term."""
    terms = [term for term in generic_library(base) if term.kind in TERMS]
    return {term.kind: fit_effects(base, [term], timing=False) for term in terms}


@pytest.fixture(scope="module")
def plain():
    return person(0.01)


@pytest.fixture(scope="module")
def quiet():
    return person(0.0015)


def test_joint_information_profiles_to_the_score_pass(plain):
    model, params = plain.model, plain.params
    names, information, scores = information_and_scores(model, params)
    k = params.size
    assert names[:k] == list(model.param_names)
    out = score(model, params)
    effective, efficient = profile_out(information, scores, range(k), range(k, len(names)), 1e-10)
    scale = np.abs(out["profile_information"]).max()
    assert np.allclose(effective, out["profile_information"], rtol=1e-6, atol=1e-8 * scale)
    assert np.allclose(efficient, out["efficient_per_sample"], rtol=1e-6,
                       atol=1e-8 * np.abs(out["efficient_per_sample"]).max())
    # the concentrated unknowns are at their maximum: their scores sum to zero, against a sum of sizes much larger
    delta_sums = scores[:, k:].sum(axis=0)
    assert np.all(np.abs(delta_sums) < 1e-6 * np.abs(scores[:, k:]).sum(axis=0))


def test_scale_is_one_where_the_model_is_right_and_large_on_a_quiet_plate(plain, quiet):
    for kind, fitted in fitted_terms(plain).items():
        weights = misspecification_scale(fitted.model, fitted.params, added_unknowns(fitted, plain))
        assert weights["tested"] == [f"c_{kind}"]
        assert 0.5 < weights["eigenvalues"][0] < 1.5, (kind, weights)
    assert quiet.test_pvalues()["kurtosis"] > 10  # the force's jumps in the innovations
    fitted = fitted_terms(quiet)["u3"]
    weights = misspecification_scale(fitted.model, fitted.params, added_unknowns(fitted, quiet))
    assert weights["scale"] > 2.5
    row = candidate_row(quiet, fitted, 0.01)
    assert row["lr_scale"] == pytest.approx(weights["scale"])
    assert row["p_value"] == pytest.approx(stats.chi2.sf(max(row["lr"], 0.0) / weights["scale"], 1), rel=1e-9)
    assert row["p_value"] > stats.chi2.sf(max(row["lr"], 0.0), 1) or row["lr"] <= 0.0


def test_nothing_to_test_leaves_the_plain_ratio(plain):
    weights = misspecification_scale(plain.model, plain.params, [])
    assert weights["scale"] == MIN_SCALE and weights["tested"] == []
