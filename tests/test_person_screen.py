"""Score tests of candidate effects at the fitted person (person.screen): exact at c = 0, the gradient the
likelihood's slope, a drift found and ranked first, no alarm on a clean record over the whole library."""

import numpy as np
import pytest

from smd_statespace.effects import TERMS, GenericTerm, make_effect
from smd_statespace.effects.generic import label
from smd_statespace.errors import OptionError
from smd_statespace.person import identify_person
from smd_statespace.person.extend import effect_model
from smd_statespace.person.screen import generic_library, holm, score_test, score_tests, screen
from smd_statespace.simulation import simulate_bouncing

PERSON = dict(mass=70, f_b=2.2, f_h=2.7, xi_h=0.3, duration=20)


@pytest.fixture(scope="module")
def clean():
    return identify_person(simulate_bouncing(**PERSON, seed=5).record)


def test_at_zero_the_candidate_is_the_fitted_person_and_its_gradient_the_likelihood_slope(clean):
    effect = generic_library(clean, ["u_abs_u"])[0]
    test = score_test(clean, effect)
    assert test["loglike"] == pytest.approx(clean.loglike, abs=1e-6)
    model = effect_model(clean, [effect])
    named = clean.model.unpack(clean.params)
    params = np.array([named.get(name, 0.0) for name in model.param_names])
    j, h = model.position("c_u_abs_u"), 1e-4
    up, down = params.copy(), params.copy()
    up[j], down[j] = h, -h
    slope = (model.loglike(up) - model.loglike(down)) / (2 * h)
    assert test["gradient"] == pytest.approx(slope, rel=1e-3, abs=1e-3)


def test_the_library_sharing_derivative_passes_gives_each_terms_own_test(clean):
    """score_tests puts terms with different coefficients in one derivative pass (the three steps of a kind, which
    share a name, in three; a candidate that adds harmonics alone): every number is the term's own test."""
    library = generic_library(clean) + [make_effect("harmonics:count=1")]
    shared = score_tests(clean, library, threads=2)
    for effect, test in zip(library, shared):
        alone = score_test(clean, effect)
        assert test["parameter"] == alone["parameter"]
        for key in ("gradient", "lm", "lm_robust", "sd_robust", "loglike"):
            assert test[key] == pytest.approx(alone[key], rel=1e-7, abs=1e-9), (effect.spec, key)
        np.testing.assert_allclose(test["cycle_scores"], alone["cycle_scores"], rtol=1e-7, atol=1e-9)


def test_a_term_screened_on_top_of_an_effect_is_tested_in_the_model_that_has_it(clean):
    """diagnose REC --effect cubic_stiffness screens the library on top of the spring, at the cycle starts the fit
    with the spring re-placed: at c = 0 the model is that fit (until 2026-12-01 the spring was left out and the
    starts were the person's without it: 1236.8 against 1238.1 here, 921 against 1213 on a record with a large
    spring), and a term fitted on top of it is tested against it at its own starts."""
    from smd_statespace.person.extend import fit_effects

    spring = fit_effects(clean, ["cubic_stiffness"])
    assert spring.model.timing is not clean.model.timing  # its own starts, re-placed with the spring
    term = generic_library(spring, ["u_abs_u"])[0]
    assert score_test(spring, term)["loglike"] == pytest.approx(spring.loglike, abs=1e-3)
    assert score_tests(spring, [term])[0]["loglike"] == pytest.approx(spring.loglike, abs=1e-3)
    on_top = fit_effects(spring, [term], timing=False)
    assert on_top.model.timing is spring.model.timing and on_top.model.variation == spring.model.variation
    assert [e.name for e in on_top.effects] == ["cubic_stiffness", term.name] and on_top.effect_test()["lr"] >= 0.0


def test_a_drifting_f_h_is_ranked_first_and_a_clean_record_raises_no_alarm(clean):
    table = screen(clean)
    assert len(table) == len(generic_library(clean)) > len(TERMS)  # a step at each of STEPS
    assert table["p_holm"].min() > 0.01  # no false alarm over the 15 candidates
    library = {effect.kind: effect for effect in generic_library(clean)}
    drift = library["f_drift"].with_values(c_f_drift=0.3)  # w_h^2 rises by 30 % over the 20 s
    drifting = identify_person(simulate_bouncing(**PERSON, seed=5, effects=[drift]).record)
    table = screen(drifting)
    assert table.index[0].startswith("term:kind=f_drift") and table["p_holm"].iloc[0] < 1e-3
    assert table.loc[table.index[0], "physics"] == TERMS["f_drift"][1]


@pytest.mark.slow
def test_a_spring_stiffer_on_one_side_is_ranked_first_by_its_quick_fit_though_its_score_is_small(clean, monkeypatch):
    """|u| linearised about the path of the person without it is nearly a change of stiffness: its score test
    passes the library's level but ranks it below terms that imitate it; linearised again about its own path,
    its quick fit ranks it first, its coefficient near the truth. A clean record: nothing passes. The term's fit
    goes on from its quick fit's end (``diagnose``) to where a search from its trial starts ends."""
    from smd_statespace.person import extend

    assert (screen(clean, alpha=0.01)["p_quick_holm"] > 0.01).all()
    library = {effect.kind: effect for effect in generic_library(clean)}
    stiffer = library["abs_u"].with_values(c_abs_u=-0.3)
    record = simulate_bouncing(**PERSON, seed=5, effects=[stiffer]).record
    person = identify_person(record, check_change=False)
    ends = {}
    table = screen(person, alpha=0.01, ends=ends)
    ranked_by_score = list(table.sort_values("p_robust")["label"])
    assert table["label"].iloc[0] == "term:abs_u" and ranked_by_score.index("term:abs_u") > 0
    assert -0.45 < table["estimate"].iloc[0] < -0.15  # -w_h^2 c |u|: c is the stiffness's asymmetry, -0.3
    term = next(effect for effect in generic_library(person) if effect.spec == table.index[0])
    searched = extend.fit_effects(person, [term], timing=False)
    starts, counted = extend.search_starts, []
    monkeypatch.setattr(extend, "search_starts", lambda *args: counted.append(1) or starts(*args))
    went_on = extend.fit_effects(person, [term], timing=False, start=ends[term.spec])
    assert counted == [] and went_on.loglike == pytest.approx(searched.loglike, abs=0.05)
    assert went_on.f_h == pytest.approx(searched.f_h, abs=0.1 * searched.se[0])


@pytest.mark.slow
def test_a_step_in_f_h_is_found_by_its_quick_fit_where_its_score_is_small(clean):
    """w_h^2 steps up by 30 % at the record's middle: the person without it is fitted far off (f_h 2.27 Hz for
    2.49 and 2.90 Hz), where the step's score is small (robust LM 6.7, below the library's level); its quick fit
    passes it and ranks it first, the step's size near the truth."""
    library = {label(effect): effect for effect in generic_library(clean)}
    step = library["term:f_step@0.5"].with_values(c_f_step=0.3)
    person = identify_person(simulate_bouncing(**PERSON, seed=5, effects=[step]).record)
    table = screen(person, alpha=0.01)
    assert table["label"].iloc[0] == "term:f_step@0.5" and table["p_holm"].iloc[0] > 0.01
    assert table["p_quick_holm"].iloc[0] < 1e-6 and 0.2 < table["estimate"].iloc[0] < 0.4


def test_holm_and_the_term_options():
    np.testing.assert_allclose(holm([0.01, 0.04, 0.03, 0.5]), [0.04, 0.09, 0.09, 0.5])
    assert make_effect("term:kind=v_abs_v,scale=0.15").spec == "term:kind=v_abs_v,scale=0.15"
    for spec, fragment in [("term:kind=u9,scale=1", "give one of abs_u"), ("term:kind=u3,scale=0", "scale=0"),
                           ("term", "kind"), ("term:kind=f_step,scale=20,at=1.5", "between 0 and 1")]:
        with pytest.raises(OptionError, match=fragment):
            make_effect(spec)
    assert GenericTerm("f_drift", scale=20.0, start=4.0).physics == TERMS["f_drift"][1]


@pytest.mark.slow
def test_diagnose_fits_the_screened_term_and_names_its_physics(clean, tmp_path, capsys):
    """The record's f_h drifts: ``diagnose`` screens the library, fits the flagged term and proposes it, in words."""
    from smd_statespace.cli.main import main

    path = tmp_path / "drift.csv"
    assert main(["simulate", "--out", str(path), "--mass", "70", "--fb", "2.2", "--fh", "2.7", "--xi", "0.3",
                 "--duration", "20", "--seed", "5", "--effect", "term:kind=f_drift,scale=20,c_f_drift=0.3"]) == 0
    assert main(["diagnose", str(path), "--mass", "70", "--out", str(tmp_path / "d"), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "verdict: missing effect 'term:f_drift' = a leg stiffness (f_h) that drifts over the record" in out
    assert "--effect term:kind=f_drift,scale=20" in out and "score-tested at the fitted person" in out
    assert "term:u3 " not in out  # cubic_stiffness is a candidate: its twin is not screened again (SAME_AS)
    for figure in ("person_candidates.png", "person_spectrum.png", "person_compare.png", "person_held_out.png",
                   "person_step_scan.png"):
        assert (tmp_path / "d" / figure).stat().st_size > 10_000


def test_u3_is_the_cubic_spring_in_another_unit(clean):
    """``SAME_AS``: the generic ``u3`` with coefficient ``c`` is ``cubic_stiffness`` with ``beta_3 = c / r_0^2``, the
    same likelihood, so diagnose screens one of them."""
    from smd_statespace.effects.generic import SAME_AS

    assert SAME_AS["u3"] == "cubic_stiffness"
    term = generic_library(clean, ["u3"])[0]
    spring = make_effect("cubic_stiffness:beta_range=-100000/100000")
    named = clean.model.unpack(clean.params)
    likelihoods = []
    for effect, name, value in ((term, "c_u3", 0.2), (spring, "beta_3", 0.2 / term.scale**2)):
        model = effect_model(clean, [effect])
        params = np.array([named.get(n, 0.0) for n in model.param_names])
        params[model.position(name)] = value
        likelihoods.append(model.loglike(params))
    assert likelihoods[0] == pytest.approx(likelihoods[1], abs=1e-6 * abs(likelihoods[0]))
    assert likelihoods[0] != pytest.approx(clean.loglike, abs=1.0)  # the term is not nothing at this size


def test_the_screened_terms_header_says_how_many_are_fitted():
    """The line above the screened terms counts those fitted above: it said "the 2 largest ... are fitted above"
    on a phone record where none was significant (Holm p 0.19 for all)."""
    import pandas as pd

    from smd_statespace.cli.diagnose import screened_header

    none = screened_header(pd.DataFrame({"p_quick_holm": [0.19, 0.19, 1.0]}), 0.01)
    assert none.endswith("none is significant over the library (Holm), so none is fitted above")
    one = screened_header(pd.DataFrame({"p_quick_holm": [1e-5, 0.2]}), 0.01)
    assert "the 1 largest quick likelihood ratio (" in one and ") is fitted above" in one
    many = screened_header(pd.DataFrame({"p_quick_holm": [1e-9, 1e-7, 1e-5]}), 0.01)
    assert "the 2 largest quick likelihood ratios (" in many and "at most 2) are fitted above" in many
    assert screened_header(pd.DataFrame({"lm_robust": [3.0]}), 0.01).endswith("so none is fitted above")


def test_the_candidates_figure_marks_fitted_only_the_screened_terms_diagnose_fits(tmp_path):
    """Three generic terms pass their quick fits; diagnose fits SCREENED (two) of them: the figure colours those
    two, not the third (until 2026-11-29 it coloured every term that passed); of the candidates, the proposal alone
    is blue (it coloured every one that passed, all called "proposed")."""
    import pandas as pd
    from types import SimpleNamespace
    from matplotlib.colors import to_hex
    from smd_statespace.person.diagnose import SCREENED, fitted_terms
    from smd_statespace.plotting.person import plot_candidates

    screened = pd.DataFrame({"label": ["term:u2", "term:abs_u", "term:v2", "term:u_v"],
                             "lm_robust": [40.0, 30.0, 20.0, 1.0], "p_quick_holm": [1e-8, 1e-6, 1e-4, 1.0],
                             "scan_trim": np.nan}, index=["term:kind=u2", "term:kind=abs_u", "term:kind=v2",
                                                          "term:kind=u_v"])
    assert SCREENED == 2 and fitted_terms(screened, 0.01) == ["term:kind=u2", "term:kind=abs_u"]
    screened["fitted"] = screened.index.isin(fitted_terms(screened, 0.01))  # as diagnose_person marks them
    candidates = pd.DataFrame({"lr_robust": [200.0, 120.0, 3.0], "significant": [True, True, False], "df": 1,
                               "trials": 1.0, "scan_trim": np.nan}, index=["term:u2", "term:abs_u", "harmonics"])
    diagnosis = SimpleNamespace(screened=screened, alpha=0.01, table=lambda: candidates, level=0.001,
                                base=SimpleNamespace(record=SimpleNamespace(source="rec.csv")))
    figure = plot_candidates(diagnosis, tmp_path / "candidates.png")
    blue, light, grey = to_hex("tab:blue"), to_hex("lightsteelblue"), to_hex("0.6")
    colours = [[to_hex(bar.get_facecolor()) for bar in axes.patches[::-1]] for axes in figure.axes[:2]]  # top first
    assert colours[0] == [blue, blue, light, grey]  # the screened terms: two fitted, one passed, one not
    assert colours[1] == [blue, light, grey]  # the candidates: the proposal, one that also passes, one that fails
    assert (tmp_path / "candidates.png").stat().st_size > 10_000
