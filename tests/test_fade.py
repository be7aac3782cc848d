"""A person who tires: the force's harmonics fading over the record, estimated with the person."""

import numpy as np
import pytest

from smd_statespace.cli import main
from smd_statespace.errors import OptionError
from smd_statespace.io import G
from smd_statespace.person import identify_person
from smd_statespace.person.fade import NOTE_TAIL, fade_regressor, fade_table
from smd_statespace.simulation import simulate_bouncing
from smd_statespace.simulation.lab import simulate_lab_record


def true_fade(lab, result) -> float:
    """The simulator's ``c`` over the fitted span: its force is ``1 - tire p(t)`` times the template, ``p`` the
    progress over the full bout; the model's is ``1 + c s(t)``, ``s`` from -1 to 1 over the span."""
    span = lab.truth["span"]
    start, end = span["full_start_s"], span["full_end_s"]
    time = result.record.time

    def scale(t):
        return 1.0 - lab.truth["tire"] * min(max((t - start) / (end - start), 0.0), 1.0)

    first, last = scale(time[0]), scale(time[-1])
    return (last - first) / (last + first)


def test_the_regressor_is_the_templates_harmonics_scaled_from_minus_one_to_one():
    time = np.linspace(0.0, 2.0, 201)
    theta = 2 * np.pi * 2.0 * time
    basis = np.column_stack([np.ones_like(time), np.cos(theta), np.sin(theta), np.cos(2 * theta), np.sin(2 * theta)])
    template = np.array([0.7, 0.3, -0.1, 0.05, 0.02])  # a0 does not fade: the mean force is the body weight
    regressor = fade_regressor(time, basis, template)
    harmonics = 0.3 * np.cos(theta) - 0.1 * np.sin(theta) + 0.05 * np.cos(2 * theta) + 0.02 * np.sin(2 * theta)
    np.testing.assert_allclose(regressor.values, (time - 1.0) * G * harmonics, atol=1e-12)
    assert regressor.name == "fade" and regressor.dynamic and regressor.observed


@pytest.mark.slow
def test_a_tiring_person_is_determined_with_the_fade_and_a_steady_one_shows_none():
    """A lab export whose force loses 30 % over the bout: with the fade (the default on a trimmed record) its size
    comes back within 3 sds and f_h is determined and covered; without it (fade=False) the fading force is read
    as the person changing and f_h is not determined. The same person bouncing steadily: a fade within its noise."""
    lab = simulate_lab_record(mass=70, f_b=2.56, f_h=2.917, xi_h=0.193, bout=25, tire=0.3, seed=1)
    person = identify_person(lab.record)
    table = fade_table(person)
    c, sd = table["c"].iloc[0], table["c_sd"].iloc[0]
    assert abs(c - true_fade(lab, person)) < 3 * sd and c < -0.1
    assert table.loc[1, "end"] < table.loc[1, "middle"] < table.loc[1, "start"]
    low, high = person.intervals["f_h"]
    assert person.determined("f_h") and low < 2.917 < high
    note = next(n for n in person.notes if n.startswith("the force fades over the record"))
    assert f"BLF1 {table.loc[1, 'start']:.3f} g at its start" in note
    cycles = person.cycles  # the cycles' load factors carry the fade: the first ones above the last ones
    assert cycles["blf_1"].iloc[:5].mean() > 1.2 * cycles["blf_1"].iloc[-5:].mean()
    without = identify_person(lab.record, fade=False)
    assert "fade" not in without.model.delta_names and not without.determined("f_h")
    steady = identify_person(simulate_lab_record(mass=70, f_b=2.56, f_h=2.917, xi_h=0.193, bout=25, seed=1).record)
    table = fade_table(steady)
    assert abs(table["c"].iloc[0]) < 3 * table["c_sd"].iloc[0]
    assert any(n.startswith("the force's fade over the record is within its noise") for n in steady.notes)


def test_a_record_bouncing_end_to_end_has_no_fade_unless_asked_and_a_bad_value_is_one_line(tmp_path, capsys):
    sim = simulate_bouncing(mass=70, f_b=2.0, f_h=2.5, xi_h=0.3, duration=10, seed=3)
    plain = identify_person(sim.record, variation="independent", check_change=False)
    assert "fade" not in plain.model.delta_names and fade_table(plain).empty
    asked = identify_person(sim.record, variation="independent", check_change=False, fade=True)
    assert asked.model.delta_names[-1] == "fade" and asked.loglike >= plain.loglike - 1e-6
    # with an effect added, the note is the final fit's (the fit without the effect had its own)
    extended = identify_person(sim.record, variation="independent", check_change=False, fade=True,
                               effects=["harmonics:count=1"])
    notes, table = [n for n in extended.notes if NOTE_TAIL in n], fade_table(extended)
    assert len(notes) == 1 and f"BLF1 {table.loc[1, 'start']:.3f} g at its start" in notes[0]
    with pytest.raises(OptionError, match="fade='yes' is not one of"):
        identify_person(sim.record, fade="yes")
    path = tmp_path / "rec.csv"
    sim.write(path)
    assert main(["identify", str(path), "--mass", "70", "--fade", "sometimes"]) == 2
    assert "--fade: invalid choice" in capsys.readouterr().err
    assert main(["identify", str(path), "--mass", "70", "--estimator", "ekf", "--fade", "on"]) == 2
    assert "--fade on applies to the record-level model" in capsys.readouterr().err
    # asked for where there is no template to fade (cycle starts from a fixed timing): said, not silently left out
    with pytest.raises(OptionError, match="fade=True needs timing='model'"):
        identify_person(sim.record, fade=True, timing="peaks")
    refused = ["identify", str(path), "--mass", "70", "--fade", "on", "--timing", "template", "--out"]
    assert main(refused + [str(tmp_path / "runs" / "first")]) == 2
    assert "fade=True needs timing='model'" in capsys.readouterr().err
    # the output folder the command made before the fit refused the options is taken back; nothing else is
    assert not (tmp_path / "runs").exists()
    (tmp_path / "kept").mkdir()
    (tmp_path / "kept" / "note.txt").write_text("mine")
    assert main(refused + [str(tmp_path / "kept" / "new")]) == 2
    assert (tmp_path / "kept" / "note.txt").read_text() == "mine" and not (tmp_path / "kept" / "new").exists()


def test_diagnoses_next_command_repeats_the_persons_options_given():
    """The printed identify command fits the person diagnosed: options given away from their defaults go with it."""
    from smd_statespace.cli.diagnose import person_options
    from smd_statespace.cli.main import build_parser

    parser = build_parser()
    args = parser.parse_args(["diagnose", "rec.csv", "--mass", "70", "--fade", "off", "--span", "4.5:33",
                              "--noise-floor", "0", "--no-floor"])
    assert person_options(args) == "--span 4.5:33 --noise-floor 0 --fade off --no-floor "
    assert person_options(parser.parse_args(["diagnose", "rec.csv", "--mass", "70"])) == ""
    assert person_options(parser.parse_args(["diagnose", "rec.csv", "--mass", "70", "--span", "all"])) == (
        "--span all ")
