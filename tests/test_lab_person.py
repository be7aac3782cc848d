"""The person from a record as labs export it: the front end's choices in identify, the halves' test, the CLI.

The records come from :func:`~smd_statespace.simulation.simulate_lab_record` (standing, ramps, mains hum, a
drifting zero, 1000 Hz) with the truth known.
"""

import json

import numpy as np
import pandas as pd
import pytest

from smd_statespace.cli import main
from smd_statespace.errors import RecordError
from smd_statespace.io import G, make_record
from smd_statespace.person import identify_person
from smd_statespace.signals import decimate_record, prepare_record, safe_factor
from smd_statespace.simulation import simulate_bouncing, simulate_lab_record

from helpers import lab_export

PERSON = dict(mass=70.0, f_b=2.0, f_h=2.6, xi_h=0.3)


@pytest.fixture(scope="module")
def lab():
    """16 s of bouncing between 4 s of standing, 50 Hz hum (5 N, 2 N at 150 Hz), a 10 N drifting zero, 1000 Hz."""
    return simulate_lab_record(**PERSON, bout=16.0, hum=(5.0, 0.0, 2.0), drift=10.0, seed=5)


def test_a_lab_record_is_fitted_on_its_steady_bouncing_at_a_rate_clear_of_the_hum(lab):
    prepared = prepare_record(lab.record)
    span = lab.truth["span"]
    start, end = prepared.span
    period = 1.0 / PERSON["f_b"]
    assert span["full_start_s"] - period <= start <= span["full_start_s"] + 1.5 * period
    assert span["full_end_s"] - 1.5 * period <= end <= span["full_end_s"] + period
    assert prepared.trimmed and prepared.record.time[0] >= start - 0.02 and prepared.record.time[-1] <= end + 0.02
    # 1000 Hz with 50 Hz hum: every 11th sample (90.9 Hz), so that 50 Hz lies above the new Nyquist frequency
    assert prepared.factor == 11 and prepared.record.fs == pytest.approx(1000.0 / 11)
    assert prepared.hum.found and prepared.hum.frequency == pytest.approx(50.0, abs=0.05)
    said = " ".join(prepared.notes)
    assert f"bouncing {start:.1f}-{end:.1f} s fitted" in said and "standing 0.0-" in said
    assert "mains hum at 50" in said and "fitted at 90.91 Hz rather than 100: so that its Nyquist" in said


def test_a_record_bouncing_end_to_end_is_prepared_as_before():
    """A simulator's record (bouncing from its first sample) is decimated only: the same arrays as before."""
    sim = simulate_bouncing(**PERSON, duration=12, fs=500, seed=2)
    prepared = prepare_record(sim.record)
    before, factor, _ = decimate_record(sim.record)
    assert not prepared.trimmed and prepared.span is None and prepared.factor == factor == 5
    assert np.array_equal(prepared.record.force, before.force) and np.array_equal(prepared.record.time, before.time)


def test_safe_factor_moves_the_nyquist_frequency_off_the_hum(lab):
    hum = prepare_record(lab.record).hum
    for fs, rate, expected in ((1000.0, 100.0, 11), (2000.0, 100.0, 22), (500.0, 100.0, 6), (1200.0, 100.0, 13),
                               (1000.0, 200.0, 6), (1000.0, 90.0, 11), (2000.0, 150.0, 13)):
        factor = safe_factor(fs, rate, hum)
        nyquist = fs / (2 * factor)
        assert factor == expected and np.min(np.abs(nyquist - 50.0 * np.arange(1, 5))) >= 3.0  # off every multiple


def test_standing_that_weighs_other_than_the_mass_is_said(lab):
    heavier = lab.record.__class__(**{**lab.record.__dict__, "mass": 66.0})
    warnings = prepare_record(heavier).warnings
    assert any("given mass is 66 kg" in w and "check --mass" in w for w in warnings), warnings


def test_no_bouncing_part_is_refused_in_words():
    t = np.arange(0.0, 20.0, 0.001)
    rng = np.random.default_rng(1)
    standing = make_record(t, 70 * G + 2.0 * np.sin(2 * np.pi * 0.3 * t) + rng.normal(0, 1, t.size), 70.0,
                           source="stand.csv")
    with pytest.raises(RecordError, match=r"stand.csv: no bouncing found; standing 0.0-20.0 s"):
        prepare_record(standing)


def test_a_span_by_hand_outside_the_record_is_one_line(lab, tmp_path, capsys):
    with pytest.raises(RecordError, match=r"span=\(40, 60\) s reaches outside the record"):
        prepare_record(lab.record, span=(40.0, 60.0))
    path = tmp_path / "lab.csv"
    lab.write(path)
    for span, words in (("40:60", "reaches outside the record"), ("9:3", "START must be below END"),
                        ("soon", "give START:END in s")):
        assert main(["identify", str(path), "--mass", "70", "--span", span, "--out", str(tmp_path / "o")]) == 2
        err = capsys.readouterr().err
        assert len(err.splitlines()) == 1 and words in err, err
    assert not (tmp_path / "o" / "person.json").exists()


def test_two_bouts_fit_the_longest_and_name_the_other():
    first = simulate_lab_record(**PERSON, bout=8.0, stand_before=3.0, stand_after=3.0, hum=(), drift=0.0, seed=1)
    second = simulate_lab_record(**PERSON, bout=14.0, stand_before=3.0, stand_after=3.0, hum=(), drift=0.0, seed=2)
    t1, t2 = first.record.time, second.record.time
    record = make_record(np.r_[t1, t1[-1] + 0.001 + t2], np.r_[first.record.force, second.record.force], 70.0,
                         source="two.csv")
    prepared = prepare_record(record)
    assert prepared.span[0] > t1[-1]  # the second, longer bout
    note = next(n for n in prepared.notes if "2 bouts of bouncing" in n)
    assert "the longest is fitted" in note and "--span" in note


@pytest.fixture(scope="module")
def lab_person(lab):
    """The person of :func:`lab` as identify_person gives it from the record in memory."""
    return identify_person(lab.record)


@pytest.mark.slow
def test_the_person_of_a_lab_record_is_found_where_the_whole_record_misleads(lab, lab_person):
    truth = lab.truth["f_h"]
    person = lab_person
    whole = identify_person(lab.record, span=None, check=False, check_change=False)
    assert person.f_h == pytest.approx(truth, rel=0.08)
    assert person.intervals["f_h"][0] <= truth <= person.intervals["f_h"][1]
    assert abs(whole.f_h / truth - 1) > 2 * abs(person.f_h / truth - 1)
    assert [r.name for r in person.model.regressors][:3] == ["offset", "zero_drift_1", "zero_drift_2"]
    assert person.change is not None and person.change["changed"] == []  # one person from end to end


@pytest.mark.slow
def test_a_zero_that_wanders_is_followed_by_a_denser_drift_and_a_slow_one_is_not(lab, lab_person):
    """The person is first fitted with the slow drift of the zero (a degree per 10 s); a likelihood-ratio test at it
    asks whether a degree every 2 s fits better. A zero that wanders (a random walk smoothed over 2 s, 25 N) is
    fitted again with it, and a note says so; the lab fixture's slow cubic zero is not."""
    wandering = simulate_lab_record(**PERSON, bout=16.0, hum=(5.0, 0.0, 2.0), drift=25.0, drift_shape="walk", seed=5)
    person = identify_person(wandering.record)
    said = [note for note in person.notes if note.startswith("the plate's zero moves faster than a slow drift")]
    assert len(said) == 1 and "fitted again with its drift of a degree every 2 s" in said[0]
    drift_names = [r.name for r in person.model.regressors if r.name.startswith("zero_drift")]
    assert len(drift_names) >= 8  # a fitted span of about 16 s, a degree every 2 s
    truth = wandering.truth["f_h"]
    assert person.intervals["f_h"][0] <= truth <= person.intervals["f_h"][1]
    assert not any("moves faster" in note for note in lab_person.notes)


def half(start, end, f_h, f_h_sd, xi_h=0.3, xi_h_sd=0.03):
    """A half's summary as change_test gives it (90 % intervals)."""
    return {"start": start, "end": end, "f_h": f_h, "f_h_sd": f_h_sd, "f_h_low": f_h - 1.645 * f_h_sd,
            "f_h_high": f_h + 1.645 * f_h_sd, "xi_h": xi_h, "xi_h_sd": xi_h_sd, "xi_h_low": xi_h - 1.645 * xi_h_sd,
            "xi_h_high": xi_h + 1.645 * xi_h_sd}


def test_halves_that_determine_f_h_and_differ_name_a_person_who_changes():
    from smd_statespace.person.change import compare_halves
    from smd_statespace.person.report import change_words

    changed = compare_halves([half(4.0, 19.0, 2.40, 0.05), half(19.0, 34.0, 2.75, 0.06)])  # 4.5 sd apart
    assert changed["changed"] == ["f_h"] and changed["z"]["f_h"] == pytest.approx(0.35 / np.hypot(0.05, 0.06))
    words = change_words(changed)
    assert words.startswith("the person changes during the record: f_h 2.4 Hz (2.32-2.48) in 4.0-19.0 s, 2.75 Hz")
    assert "--span START:END" in words
    assert "(term:f_step, term:f_drift)" in words and "xi_step" not in words  # what diagnose tries for it
    # the same difference where a half does not determine f_h (sd over a quarter of the yardstick), or too small
    assert compare_halves([half(4.0, 19.0, 2.40, 0.05), half(19.0, 34.0, 2.75, 0.30)])["changed"] == []
    assert compare_halves([half(4.0, 19.0, 2.40, 0.001), half(19.0, 34.0, 2.45, 0.001)])["changed"] == []
    assert change_words(compare_halves([half(4.0, 19.0, 2.4, 0.05), half(19.0, 34.0, 2.42, 0.05)])) == ""


def test_two_people_and_stepping_off_are_refused_saying_what_was_found(lab, tmp_path, capsys):
    record = lab.record
    doubled = record.__class__(**{**record.__dict__, "force": 2 * record.force, "source": "two.csv"})
    with pytest.raises(RecordError, match=r"two.csv: standing, the plate reads \d+ N = 1[34]\d\.\d kg at g, "
                                          r"(1\.9\d|2\.0\d) times the given mass \(70 kg\): two people on the plate"):
        prepare_record(doubled)
    off = np.asarray(record.force).copy()
    stand = record.time > lab.truth["span"]["bouncing_end_s"] + 0.5
    off[stand & (record.time < record.time[-1] - 1.0)] = 0.0  # steps off after bouncing, back on for the last 1 s
    stepped = record.__class__(**{**record.__dict__, "force": off, "source": "off.csv"})
    with pytest.raises(RecordError, match=r"off.csv: the person leaves the plate at .* and comes back"):
        prepare_record(stepped)
    path = tmp_path / "clipped.csv"  # a record as read, clipped by the plate's range (flat tops at 1000 N)
    pd.DataFrame({"time": record.time, "force": np.minimum(record.force, 1000.0)}).to_csv(path, index=False)
    assert main(["identify", str(path), "--mass", "70", "--out", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "clipped" in err and not (tmp_path / "c" / "person.json").exists()


def test_a_trimmed_records_sds_are_the_wider_of_the_information_and_the_sandwich(long_fit):
    """A lab's export gets the rule every record gets: the calibrated sd of f_h and xi_h is the calibration factor
    times the wider of the observed information's sd and the cycle-clustered sandwich's (no factor of its own:
    the sandwich sees what a lab record's model misses, 1.9 times the information's sd at the median on seed 4346's
    lab records, 1.04 on their clean records)."""
    from types import SimpleNamespace

    from smd_statespace.person.answer import person_result
    from smd_statespace.person.calibration import CALIBRATION
    from smd_statespace.person.search import information

    fitted = {"params": long_fit.params, "loglike": long_fit.loglike, "n_evaluations": 0, "converged": True}
    plain = person_result(long_fit.record, long_fit.model, fitted, prepared=SimpleNamespace(trimmed=False))
    lab = person_result(long_fit.record, long_fit.model, fitted, prepared=SimpleNamespace(trimmed=True))
    oim = np.sqrt(np.diag(information(long_fit.model, long_fit.params, "oim")[0])[:2])
    sandwich = np.sqrt(np.diag(information(long_fit.model, long_fit.params, "robust")[0])[:2])
    factors = CALIBRATION[long_fit.model.variation]
    for i, name in enumerate(("f_h", "xi_h")):
        assert lab.sd(name) == pytest.approx(plain.sd(name), rel=1e-12)
        assert lab.sd(name) == pytest.approx(factors[name] * max(oim[i], sandwich[i]), rel=1e-9)


@pytest.mark.slow
def test_compare_puts_the_person_identify_gives_beside_the_cycles_on_a_lab_export(lab, lab_person, tmp_path, capsys):
    """compare's record row is the person identify fits from the record as read (1000 Hz, hum found and removed
    at that rate, the bout trimmed), not a person of the record compare decimated to --rate for its cycles
    (on this record, when it was found: 2.594 Hz there against identify's 2.637 Hz)."""
    from smd_statespace.io import read_record

    path = tmp_path / "lab.csv"
    lab.write(path)
    assert main(["compare", str(path), "--mass", str(lab.record.mass), "--estimators", "record", "--quiet",
                 "--out", str(tmp_path / "c")]) == 0
    capsys.readouterr()
    row = pd.read_csv(tmp_path / "c" / "compare_table.csv", index_col=0).loc["record"]
    person = identify_person(read_record(path, lab.record.mass))
    assert row["f_h"] == pytest.approx(person.f_h, rel=1e-9)
    assert (row["f_h_low"], row["f_h_high"]) == pytest.approx(person.intervals["f_h"], rel=1e-9)
    # the record read back from the CSV is the person of the record in memory: the noise floor's draw is seeded by
    # the record's rounded summaries, not by the bytes the CSV's 6 decimals change (2.48 against 2.64 Hz before)
    assert person.f_h == pytest.approx(lab_person.f_h, rel=1e-6)


def test_a_kept_bout_that_is_refused_says_what_the_front_end_kept():
    """A gentle bouncer (a swing about 3 % of body weight in RMS; ``lab_records.py --people lab``, seed 4363, lab row
    17) bounces for 30 s, but the front end found only two 3 s bouts in it, and the refusal of the one it kept
    said "2.9 force cycles of 0.61 s in 3.1 s" of a 42 s record. It now says which part that was, what else was
    found, why so few cycles count, and how to choose another part."""
    from smd_statespace.applicability import NotBouncingError

    lab = lab_export("gentle_bouncer")
    with pytest.raises(NotBouncingError, match=r"(?s)not_rhythmic.*gentler than that.*the front end kept.*bouncing "
                                               r"8\.4-11\.4 s.*--span START:END"):
        identify_person(lab.record)
