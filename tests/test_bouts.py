"""A session of several bouts at several tempos: a person per bout, against its bouncing frequency."""

import json

import numpy as np
import pandas as pd
import pytest

from smd_statespace.cli import main
from smd_statespace.errors import OptionError
from smd_statespace.io import make_record, write_record
from smd_statespace.person import identify_bouts
from smd_statespace.simulation.lab import simulate_lab_record

F_B = (1.9, 2.6)
F_H = 3.0


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    """Two lab trials of one person (standing, bouncing 16 s, standing) at two tempos, one after the other, plus a
    third 'bout' too short to identify (3 s)."""
    times, forces, start = [], [], 0.0
    for k, (f_b, bout) in enumerate(zip((*F_B, 2.2), (16.0, 16.0, 3.0))):
        trial = simulate_lab_record(mass=68.0, f_b=f_b, f_h=F_H, xi_h=0.3, stand_before=3.0, stand_after=2.0,
                                    bout=bout, fs=200.0, hum=(), drift=0.0, seed=70 + k).record
        times.append(trial.time + start)
        forces.append(trial.force)
        start = times[-1][-1] + 1.0 / trial.fs
    path = tmp_path_factory.mktemp("session") / "session.csv"
    write_record(path, make_record(np.concatenate(times), np.concatenate(forces), 68.0, source="session.csv"))
    return path


def test_every_bout_is_a_person_at_its_own_tempo_and_a_short_one_fails_alone(session, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["identify", str(session), "--mass", "68", "--span", "each", "--out", str(out), "--quiet"]) == 1
    captured = capsys.readouterr()
    table = pd.read_csv(out / "bouts.csv")
    ok = table[table["status"] == "ok"]
    assert len(ok) == 2 and ok["f_b"].tolist() == pytest.approx(F_B, rel=0.02)
    assert (ok["f_h_low"] <= F_H).all() and (ok["f_h_high"] >= F_H).all()  # each bout's interval holds the person
    failed = table[table["status"] == "failed"]
    assert len(failed) == 1 and failed["reason"].iloc[0]  # the short bout, with its reason, not the run
    assert captured.err.count("error:") == 1 and "bout 3" in captured.err
    assert "3 bouts of bouncing, a person each" in captured.out and captured.out.count("cycles at f_b") == 3
    assert (out / "person_bouts.png").stat().st_size > 0 and (out / "bout_1" / "person.json").exists()
    assert json.loads((out / "run.json").read_text())["bouts"][0][0] == pytest.approx(ok["start_s"].iloc[0])
    notes = json.loads((out / "bout_1" / "person.json").read_text())["notes"]
    assert any(note.endswith("s fitted, bout 1's steady part") for note in notes)  # not "as given": the user gave none


def test_identify_bouts_takes_no_span(session):
    from smd_statespace.io import read_record

    with pytest.raises(OptionError, match="each bout's steady part is its span"):
        identify_bouts(read_record(session, 68.0), span=(1.0, 5.0))


def test_a_folder_of_sessions_gives_a_row_per_bout_and_a_bout_that_fails_does_not_fail_its_record(session, tmp_path,
                                                                                                  capsys):
    folder = tmp_path / "sessions"
    folder.mkdir()
    (folder / "s1.csv").write_bytes(session.read_bytes())
    assert main(["identify", str(folder), "--mass", "68", "--span", "each", "--out", str(tmp_path / "o"),
                 "--quiet"]) == 0
    table = pd.read_csv(tmp_path / "o" / "results.csv")
    assert table["record"].tolist() == ["s1.csv"] * 3 and table["bout"].tolist() == [1, 2, 3]
    assert table["status"].tolist() == ["ok", "ok", "failed"]
    assert "1 records: 1 identified now" in capsys.readouterr().out and (tmp_path / "o" / "people.png").exists()
    assert main(["identify", str(folder), "--mass", "68", "--span", "2:9", "--out", str(tmp_path / "p")]) == 2
    assert "--span applies to one record; with many, only --span each" in capsys.readouterr().err
