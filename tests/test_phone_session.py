"""A phone's record of a whole trial (simulation.phone_session) and the phone path's front end on it."""

import numpy as np
import pytest

from smd_statespace.cli.main import main
from smd_statespace.errors import OptionError
from smd_statespace.io import G
from smd_statespace.simulation.phone_session import simulate_phone_session

PERSON = dict(mass=70.0, f_b=2.2, f_h=2.9, xi_h=0.3, bout=20.0, seed=4)


def test_worn_the_phone_reads_the_persons_specific_force_in_its_own_frame():
    """Without handling, every sample is the world's specific force ``[0, 0, g + u_ddot]`` turned by the worn
    tilt, plus the bias and noise: its norm is ``|g + a_v|`` within the noise, its component along the worn
    "up" axis is ``g + a_v``, and the person's truth is the lab simulator's."""
    rec = simulate_phone_session(**PERSON, pick_up=0.0, take_off=0.0, noise=0.0, bias=0.0)
    session = rec.truth["session"]
    assert session["worn"] == pytest.approx([0.0, rec.time[-1]], abs=1.0 / session["fs"])  # the last sample
    np.testing.assert_allclose(np.linalg.norm(rec.acc, axis=1), G + rec.vertical, rtol=1e-12)
    heading = np.asarray(session["tilt_axis"])
    tilt = np.radians(80.0)  # world "up" seen from the phone: turned back by the tilt about the heading (Rodrigues)
    up = np.array([0.0, 0.0, np.cos(tilt)]) - np.cross(heading, [0.0, 0.0, 1.0]) * np.sin(tilt)
    np.testing.assert_allclose(rec.acc @ up, G + rec.vertical, atol=1e-4)  # the truth rounds the axis to 1e-6
    assert rec.truth["f_h"] == pytest.approx(2.9)
    assert session["bouncing"][0] == pytest.approx(rec.truth["span"]["bouncing_start_s"])


def test_handling_turns_the_phone_and_moves_it_only_before_and_after():
    rec = simulate_phone_session(**PERSON, noise=0.0, bias=0.0)
    session = rec.truth["session"]
    t = rec.time
    on_table = t < session["table_before"][1] - 0.05
    np.testing.assert_allclose(rec.acc[on_table], np.tile([0.0, 0.0, G], (on_table.sum(), 1)), atol=1e-9)
    carried = (t > session["table_before"][1] + 0.5) & (t < session["pick_up"][1] - 0.5)
    assert np.std(np.linalg.norm(rec.acc[carried], axis=1)) > 0.5  # the hand's acceleration
    worn = (t >= session["worn"][0]) & (t <= session["worn"][1])
    np.testing.assert_allclose(np.linalg.norm(rec.acc[worn], axis=1), G + rec.vertical[worn], rtol=1e-12)
    with pytest.raises(OptionError, match="pick_up 0.5 s must be 0 or at least 2 s"):
        simulate_phone_session(**PERSON, pick_up=0.5)


def test_identify_fits_only_the_bouncing_of_a_handled_phone_record(tmp_path, capsys):
    """Picked up, worn standing, bouncing, taken off: until 2026-11-28 the still standing between handling and
    bouncing was refused ("was the phone put down?"); now the front end fits the steady bouncing and says what
    it left out, in a phone's words."""
    csv = tmp_path / "session.csv"
    assert main(["simulate", "--lab", "--accelerometer", "--out", str(csv), "--mass", "70", "--fb", "2.2", "--fh",
                 "2.9", "--xi", "0.3", "--bout", "20", "--seed", "4"]) == 0
    out = tmp_path / "person"
    assert main(["identify", str(csv), "--accelerometer", "--out", str(out), "--quiet"]) == 0
    printed = capsys.readouterr().out
    truth = __import__("json").loads((tmp_path / "session_truth.json").read_text())["session"]
    note = next(line for line in printed.splitlines() if line.startswith("note: bouncing"))
    start, end = (float(v) for v in note.split()[2].split("-"))
    assert truth["bouncing"][0] <= start and end <= truth["bouncing"][1] + 0.5
    assert end - start > 0.8 * (truth["full_bouncing"][1] - truth["full_bouncing"][0])
    assert "the phone handled" in note and "plate" not in note
    assert (out / "person.json").exists()


@pytest.mark.parametrize("options, message", [
    (["--drift", "3"], "--drift does not apply to a phone's record"),
    (["--handling", "0.5"], "--handling 0.5 s must be 0 or at least 2 s"),
    (["--phone-rate", "900"], "--phone-rate 900.0 Hz is outside 50-500 Hz"),
    (["--jitter", "0.001"], "--jitter does not apply to --lab --accelerometer"),
])
def test_simulate_session_bad_options_are_one_line_errors(tmp_path, capsys, options, message):
    argv = ["simulate", "--lab", "--accelerometer", "--out", str(tmp_path / "s.csv"), "--mass", "70", "--fb", "2.2",
            "--fh", "2.9", "--xi", "0.3", "--bout", "20"] + options
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and message in err
    assert not (tmp_path / "s.csv").exists()


def test_handling_needs_the_phone(tmp_path, capsys):
    argv = ["simulate", "--lab", "--out", str(tmp_path / "s.csv"), "--mass", "70", "--fb", "2.2", "--fh", "2.9",
            "--xi", "0.3", "--bout", "20", "--handling", "3"]
    assert main(argv) == 2
    assert "--handling applies to a phone's record" in capsys.readouterr().err
