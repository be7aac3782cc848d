"""Held-out validation of the record-level model (smd_statespace.person.validation) and its use by diagnose."""

import numpy as np
import pytest

from smd_statespace.person import identify_person
from smd_statespace.person.diagnose import held_out, verdict
from smd_statespace.person.extend import fit_effects
from smd_statespace.person.search import fit_model
from smd_statespace.measures import fit_percent
from smd_statespace.person.validation import (BREAK_MARGIN, break_folds, cross_validated_loglike, halves,
                                              held_out_free_run, held_out_loglike, part)
from smd_statespace.simulation import simulate_bouncing

PERSON = dict(mass=70.0, f_b=2.2, f_h=2.9, xi_h=0.3, duration=30.0, fs=100.0, noise=0.01, seed=5)
MISSING_HARMONICS = {"harmonics": {"blf": [0.0, 0.0, 0.0, 0.0, 0.04, 0.03]}}


@pytest.fixture(scope="module")
def clean():
    return identify_person(simulate_bouncing(**PERSON).record, check_change=False)


@pytest.fixture(scope="module")
def with_harmonics():
    return identify_person(simulate_bouncing(**PERSON, effects=MISSING_HARMONICS).record, check_change=False)


def test_a_part_scored_at_its_own_estimate_gives_its_own_profile_likelihood(clean):
    """The held-out score re-estimates only the initial state and the regressors with the template held: at the
    part's own template and scale this is the profile likelihood's own maximum, to rounding."""
    cut = halves(clean.model)
    assert cut is not None and np.all(cut[0][0] ^ cut[1][0])  # the halves split the samples
    first = part(clean.model, *cut[0])
    fitted = fit_model(first, clean.params, quick=True)
    own = first.filter(fitted["params"])
    assert held_out_loglike(first, fitted["params"], own["delta"], own["sigma2"]) == pytest.approx(
        fitted["loglike"], rel=1e-9)
    # another template is a worse prediction of the same samples
    other = own["delta"].copy()
    other[first.n_dynamic + 1] += 0.05
    assert held_out_loglike(first, fitted["params"], other, own["sigma2"]) < fitted["loglike"] - 1.0


def test_a_missing_effect_predicts_the_held_out_half_better_and_an_absent_one_worse(clean, with_harmonics):
    """Harmonics 5-6 in the force: the person with them predicts the other half better; on a record without
    them the same two extra harmonics (LR 8.6 on the whole record) predict it worse, and diagnose's check
    takes them out of the proposals."""
    missing = fit_effects(with_harmonics, ["harmonics"], timing=False)
    before = cross_validated_loglike(with_harmonics.model, with_harmonics.params)
    after = cross_validated_loglike(missing.model, missing.params)
    assert after["loglike"] > before["loglike"] + 10.0
    assert [fold["end"] <= fold_other["start"] or fold["start"] >= fold_other["end"]
            for fold, fold_other in [after["folds"]]] == [True]

    absent = fit_effects(clean, ["harmonics"], timing=False)
    base = cross_validated_loglike(clean.model, clean.params)
    passed = {"passed": True, "less_white": False, "significant": True}
    row = held_out(passed, base, cross_validated_loglike(absent.model, absent.params), 0.01)
    assert row["held_out"] < row["held_out_before"]
    assert row["held_out_worse"] and not row["significant"]
    kept = held_out(passed, before, after, 0.01)
    assert kept["significant"] and not kept["held_out_worse"]
    assert kept["held_out_one_step_fit"] > kept["held_out_one_step_fit_before"]
    assert held_out(passed, None, after, 0.01) == passed  # cannot halve: not judged
    # less white innovations veto a candidate only where no held-out data judged it (verdict)
    assert held_out({**passed, "less_white": True}, before, after, 0.01)["significant"]
    unjudged = {**passed, "less_white": True, "held_out": float("nan"), "held_out_worse": False,
                "held_out_weak": False}
    assert not verdict(unjudged)["significant"] and verdict({**unjudged, "less_white": False})["significant"]


def test_the_free_run_of_a_held_out_half_reproduces_a_record_without_variation():
    """A force the same in every cycle and almost no noise: the model's free run (template in every cycle, the
    half's own initial state estimated) reproduces the held-out half; the same run with f_h 10 % off does not
    (fitted as measured: the noise floor would add 1 % BW to the record the run is compared with)."""
    steady = simulate_bouncing(**{**PERSON, "noise": 0.001, "fb_variation": 0.0, "coef_variation": 0.0}).record
    result = identify_person(steady, check_change=False, noise_floor=None)
    delta = result.filtered["delta"]
    assert fit_percent(result.model.y, result.model.free_run(result.params, delta)) > 99.0
    second = part(result.model, *halves(result.model)[1])
    assert fit_percent(second.y, held_out_free_run(second, result.params, delta)) > 99.0
    wrong = result.params.copy()
    wrong[result.model.position("f_h")] *= 1.1
    assert fit_percent(second.y, held_out_free_run(second, wrong, delta)) < 70.0
    runs = result.model.free_run(result.params, np.c_[delta, 2.0 * delta])  # columns are runs
    assert np.allclose(runs[:, 0], result.model.free_run(result.params, delta))


def test_a_change_in_time_is_judged_by_folds_fitted_across_it(clean):
    """A step at the middle: two folds, each fitted on a part that holds it, cut a sixth of the record after it (and
    as far before it) at the nearest cycle start, each holding out the rest; several breaks all on the fitted side;
    a step near the record's end leaves one fold; breaks that leave no such cut with enough cycles held out, none."""
    time = clean.model.time
    length = time[-1] - time[0]

    def cut(fold):  # where the fitted and the held-out parts meet
        (fit, _), (held, _) = fold
        return time[held][0] if time[held][0] > time[fit][0] else time[fit][0]

    at = time[0] + 0.5 * length
    folds = break_folds(clean.model, [at])
    assert len(folds) == 2
    for fold in folds:
        (fit, _), (held, _) = fold
        assert np.all(fit ^ held) and time[fit][0] < at < time[fit][-1]  # every sample once; fitted across it
        assert BREAK_MARGIN * length <= abs(cut(fold) - at) < BREAK_MARGIN * length + 1.0  # the nearest cycle start
    assert time[folds[0][1][0]][0] > at and time[folds[1][1][0]][-1] < at  # the end held out, then the start
    for breaks in ([time[0] + 0.3 * length, time[0] + 0.6 * length], [time[0] + 0.55 * length]):
        for fold in break_folds(clean.model, breaks):
            assert np.all(np.abs(cut(fold) - np.array(breaks)) >= BREAK_MARGIN * length)
            assert np.all(np.array(breaks) > cut(fold)) or np.all(np.array(breaks) < cut(fold))
    assert len(break_folds(clean.model, [time[0] + 0.75 * length])) == 1  # only the start can be held out
    assert break_folds(clean.model, [time[0] + f * length for f in (0.2, 0.8)]) == []
    assert break_folds(clean.model, [time[0] + f * length for f in (0.2, 0.5, 0.8)]) == []


@pytest.mark.slow
def test_a_step_is_judged_by_the_folds_fitted_across_it():
    """f_h 30 % higher (w_h^2) after the middle: the folds fitted across the step predict the rest of the record
    better with the step than without. (On the middle cut each half sees one side of the step only, where the step's
    term is a constant confounded with f_h: what it says depends on where each half's search stops along that
    ridge.)"""
    from smd_statespace.effects.generic import GenericTerm

    step = GenericTerm("f_step", scale=PERSON["duration"], at=0.5)
    sim = simulate_bouncing(**PERSON, effects=[step.with_values(c_f_step=0.3)])
    base = identify_person(sim.record, check_change=False)
    fitted = fit_effects(base, [step], timing=False)
    before = cross_validated_loglike(base.model, base.params, step.breaks)
    after = cross_validated_loglike(fitted.model, fitted.params, step.breaks)
    assert len(after["folds"]) == 2 and after["cuts"] == before["cuts"]
    for fold, cut in zip(after["folds"], after["cuts"][::-1]):  # the end held out first, then the start
        assert fold["start"] < step.breaks[0] < fold["end"]  # fitted across the step
        assert abs(cut - step.breaks[0]) >= BREAK_MARGIN * PERSON["duration"] - 1.0
    assert after["loglike"] > before["loglike"] + 10.0
    middle = (fitted.model.time >= after["cuts"][0]) & (fitted.model.time < after["cuts"][1])
    assert np.isnan(after["free_run"][middle]).all() and np.isfinite(after["free_run"][~middle]).all()


def test_candidates_are_ranked_by_their_held_out_gain_per_held_out_sample():
    """Judged on the same folds, +40 on 1000 held-out samples predicts better than +72 on 3000, and is ranked
    first; a candidate that failed its test comes last whatever its gain."""
    from smd_statespace.person.diagnose import PersonDiagnosis

    def row(name, gain, samples, significant=True, log_p=-50.0):
        return {"effect": name, "significant": significant, "held_out_before": 1000.0, "held_out": 1000.0 + gain,
                "held_out_samples": samples, "log_p": log_p}

    rows = [row("harmonics", 72.0, 3000), row("term:f_step@0.5", 40.0, 1000), row("cubic", 500.0, 3000, False, -90)]
    diagnosis = PersonDiagnosis(base=None, fits={}, rows=rows, failed={}, alpha=0.01)
    assert list(diagnosis.table().index) == ["term:f_step@0.5", "harmonics", "cubic"]
    rows[1]["held_out_samples"] = 3000  # the same gain on as many samples as the harmonics': they come first
    assert list(PersonDiagnosis(base=None, fits={}, rows=rows, failed={}, alpha=0.01).table().index)[0] == "harmonics"


def test_candidates_judged_on_different_folds_are_ranked_by_their_tests():
    """A step judged on its own folds and a drift on the halves: their held-out gains are on different samples and do
    not compare, so the stronger test (the drift's, p e^-40 against e^-30) comes first though the step gained more
    per held-out sample; on the same folds the gain decides."""
    from smd_statespace.person.diagnose import PersonDiagnosis

    rows = [{"effect": "term:f_step@0.5", "significant": True, "held_out_before": 1000.0, "held_out": 1100.0,
             "held_out_samples": 2000, "log_p": -30.0},
            {"effect": "term:f_drift", "significant": True, "held_out_before": 1000.0, "held_out": 1010.0,
             "held_out_samples": 3000, "log_p": -40.0}]
    halves_folds = {"folds": [{"start": 0.0, "end": 15.0}, {"start": 15.0, "end": 30.0}]}
    step_folds = {"folds": [{"start": 0.0, "end": 20.0}, {"start": 10.0, "end": 30.0}]}
    validation = {"term:f_step@0.5": step_folds, "term:f_drift": halves_folds}
    diagnosis = PersonDiagnosis(base=None, fits={}, rows=rows, failed={}, alpha=0.01, validation=validation)
    assert list(diagnosis.table().index) == ["term:f_drift", "term:f_step@0.5"]
    validation["term:f_step@0.5"] = halves_folds
    assert list(diagnosis.table().index) == ["term:f_step@0.5", "term:f_drift"]


@pytest.mark.parametrize("kurtosis, scale, noted", [(15.9, 3.2, True), (3.1, 1.0, False)])
def test_heavy_tailed_innovations_are_said_to_overstate_the_ratios(kurtosis, scale, noted):
    """A person whose innovations have a kurtosis of 15.9 (a quiet lab plate's) gets the note that the likelihood
    ratios assume Gaussian innovations, and a candidate whose ratio is scaled by 3.2 the note that says by how much
    the likelihood overstates it; one near a Gaussian's 3 with a plain ratio gets neither."""
    from types import SimpleNamespace

    from smd_statespace.person.diagnose import PersonDiagnosis

    base = SimpleNamespace(test_pvalues=lambda: {"kurtosis": kurtosis, "ljung_box_p": 1e-60})
    row = {"effect": "term:f_drift", "significant": True, "held_out_before": 1000.0, "held_out": 1010.0,
           "held_out_samples": 3000, "log_p": -20.0, "on_bound": False, "zero": False, "less_white": False,
           "held_out_worse": False, "settled": True, "likelihood": "exact", "f_h": 2.5, "xi_h": 0.3,
           "held_out_free_run_fit": 80.0, "held_out_free_run_fit_before": 79.0, "lr_scale": scale,
           "held_out_weak": False}
    notes = PersonDiagnosis(base=base, fits={}, rows=[row], failed={}, alpha=0.01).notes()
    assert any(note.startswith("the person's innovations are heavy-tailed (kurtosis 15.9") for note in notes) == noted
    assert any("overstates the evidence for a candidate by up to 3.2 times (term:f_drift)" in note
               for note in notes) == noted


def test_a_candidate_the_record_cannot_judge_on_held_out_data_is_not_proposed_and_said_so():
    """A floor mode that passed its test (LR 41) on a bout too short to halve: not significant, and the note says
    why; the same row judged and gaining clearly on the held-out halves is proposed."""
    from types import SimpleNamespace

    from smd_statespace.person.diagnose import PersonDiagnosis

    base = SimpleNamespace(test_pvalues=lambda: {"kurtosis": 3.0, "ljung_box_p": 0.5}, change=None)  # no change tests
    row = {"effect": "floor_mode", "passed": True, "held_out_before": np.nan, "held_out": np.nan,
           "held_out_samples": np.nan, "log_p": -10.9, "lr": 41.3, "on_bound": False, "zero": False,
           "less_white": False, "held_out_worse": False, "held_out_weak": False, "settled": True, "likelihood": "exact",
           "f_h": 2.96, "xi_h": 0.14, "held_out_free_run_fit": np.nan, "held_out_free_run_fit_before": np.nan,
           "lr_scale": 1.0}
    assert verdict(row)["significant"]  # before the held-out check: its test and whiteness
    unjudged = verdict({**row, "held_out_unjudged": True})
    assert not unjudged["significant"]
    diagnosis = PersonDiagnosis(base=base, fits={}, rows=[unjudged], failed={}, alpha=0.01)
    assert diagnosis.adequate and any(note.startswith("floor_mode: it passes its test (LR 41.3), but it could not be "
                                                      "judged on held-out data (the record is too short to halve")
                                      for note in diagnosis.notes())
    # a person identify found to change, and no candidate here passed: identify's warning is said to stand
    changing = SimpleNamespace(test_pvalues=base.test_pvalues, change={"changed": ["f_h", "xi_h"]})
    notes = PersonDiagnosis(base=changing, fits={}, rows=[unjudged], failed={}, alpha=0.01).notes()
    assert any(note.startswith("identify found that the person changes during the record (f_h, xi_h not determined)")
               and "--span START:END" in note for note in notes)
    assert not any(note.startswith("identify found that") for note in diagnosis.notes())
    judged = verdict({**row, "held_out_before": 300.0, "held_out": 330.0, "held_out_samples": 400})
    assert judged["significant"]


@pytest.mark.parametrize("q_before, q_after, lags, less", [(62.0, 80.0, 39, True), (62.0, 70.0, 39, False),
                                                          (377.0, 388.0, 39, False), (377.0, 420.0, 39, True)])
def test_less_white_is_a_rise_of_q_beyond_its_own_spread(q_before, q_after, lags, less):
    """Ljung-Box Q rising by more than the sd of a non-central chi-square with Q as its mean: 13 at Q 62 (p 0.01 on
    39 lags), 38 at Q 377 (a quiet plate's misfit, p 1e-57), where a true drift raised Q by 11 (p 7.9e-57 ->
    5.2e-59) and a rule on p-values had called it less white."""
    from smd_statespace.person.diagnose import less_white

    before = {"ljung_box_q": q_before, "ljung_box_lags": lags}
    assert less_white(before, {"ljung_box_q": q_after}) == less


def test_a_candidate_given_twice_is_refused(long_fit):
    from smd_statespace.errors import OptionError
    from smd_statespace.person.diagnose import diagnose_person

    with pytest.raises(OptionError, match="candidate 'floor_mode' is given twice"):
        diagnose_person(long_fit, candidates=["floor_mode", "floor_mode:source=modal"])


def test_a_held_out_gain_made_by_a_few_samples_is_weak_and_one_spread_over_the_cycles_is_clear():
    """``held_out_gain``: the same total gain (+20) from one sample is under the sds of its noise from cycle to cycle
    that a test at level 0.01 / 18 asks (``held_out_z``, 3.26), from every cycle well over it; diagnose proposes
    only the second."""
    from smd_statespace.person.diagnose import held_out_z
    from smd_statespace.person.validation import held_out_gain
    from smd_statespace.person.verdict import CLEAR_GAIN

    rng = np.random.default_rng(np.random.SeedSequence(45))
    cycle = np.repeat(np.arange(60), 40)
    before = {"sample_loglike": rng.normal(1.0, 0.3, cycle.size), "cycle": cycle, "loglike": 0.0,
              "one_step": np.zeros(cycle.size), "one_step_fit": 50.0, "free_run_fit": 40.0}
    before["sample_loglike"][:100] = np.nan  # samples no fold predicts
    before["loglike"] = float(np.nansum(before["sample_loglike"]))
    spiked, spread = dict(before), dict(before)
    spiked["sample_loglike"] = before["sample_loglike"] + rng.normal(0.0, 0.3, cycle.size)
    spiked["sample_loglike"][500] += 20.0 - np.nansum(spiked["sample_loglike"] - before["sample_loglike"])
    spread["sample_loglike"] = before["sample_loglike"] + 20.0 / np.isfinite(before["sample_loglike"]).sum()
    for case in (spiked, spread):
        case["loglike"] = float(np.nansum(case["sample_loglike"]))
        assert held_out_gain(before, case)["gain"] == pytest.approx(20.0)
    level = 0.01 / 18
    assert held_out_z(level) == pytest.approx(3.26, abs=0.01)
    assert held_out_gain(before, spiked)["z"] < held_out_z(level) < held_out_gain(before, spread)["z"]
    assert held_out_gain(before, spread)["cycles"] == 58  # the first 2.5 cycles are not predicted
    passed = {"passed": True, "less_white": False, "significant": True}
    weak = held_out(passed, before, spiked, level)
    assert weak["held_out_weak"] and not weak["held_out_worse"] and not weak["significant"]
    assert held_out(passed, before, spread, level)["significant"]
    # innovations near Gaussian: the densities are a fair measure, and a gain of one sd of its noise is enough
    z = held_out_gain(before, spiked)["z"]
    assert CLEAR_GAIN < z < held_out_z(level)
    assert held_out(passed, before, spiked, level, heavy_tailed=False)["significant"]
    # ... but not one within it: the same noise with +5 in one sample is under a sd of the cycles' gains
    small = dict(spiked, sample_loglike=spiked["sample_loglike"].copy())
    small["sample_loglike"][500] -= 15.0
    small["loglike"] = float(np.nansum(small["sample_loglike"]))
    assert held_out_gain(before, small)["gain"] == pytest.approx(5.0)
    assert 0.0 < held_out_gain(before, small)["z"] < CLEAR_GAIN
    weak = held_out(passed, before, small, level, heavy_tailed=False)
    assert weak["held_out_weak"] and not weak["held_out_worse"] and not weak["significant"]
    # a change in time predicts the other half by extrapolating its course: there a positive gain is enough
    assert held_out(passed, before, small, level, heavy_tailed=False, in_time=True)["significant"]


@pytest.mark.parametrize("name, noted", [("term:v2", True), ("term:f_drift", False)])
def test_a_proposed_term_even_in_the_motion_gets_the_note_on_cycle_starts(name, noted):
    """A proposed v2 (damping that differs up and down) is said to take up cycle starts a few milliseconds off where
    the force changes abruptly (docs/effects.md: the source of the false alarms on clean simulated records); a
    proposed drift of f_h is not."""
    from types import SimpleNamespace

    from smd_statespace.person.diagnose import PersonDiagnosis

    base = SimpleNamespace(test_pvalues=lambda: {"kurtosis": 3.0, "ljung_box_p": 0.5}, change=None)
    row = verdict({"effect": name, "passed": True, "held_out_before": 1000.0, "held_out": 1030.0,
                   "held_out_samples": 1500, "held_out_z": 3.0, "log_p": -12.0, "lr": 30.0, "on_bound": False,
                   "zero": False, "less_white": False, "held_out_worse": False, "held_out_weak": False,
                   "settled": True, "likelihood": "approximate", "f_h": 2.8, "xi_h": 0.3,
                   "held_out_free_run_fit": 80.0, "held_out_free_run_fit_before": 80.0, "lr_scale": 1.0})
    diagnosis = PersonDiagnosis(base=base, fits={}, rows=[row], failed={}, alpha=0.01)
    assert diagnosis.missing == [name]
    assert any(note.startswith(f"{name}: a term even in the motion also takes up cycle starts")
               for note in diagnosis.notes()) == noted
