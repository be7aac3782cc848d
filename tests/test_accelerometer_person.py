"""The person from a phone at the waist: the simulated phone, the record the person model reads, the command line.

The phone's record of a simulated person (:func:`~smd_statespace.simulation.phone.simulate_phone`) is read as
a user's file (:func:`~smd_statespace.accelerometer.accelerometer_record`) and identified by the same
record-level model as a force plate's; a tilted phone must give the answer of a level one.
"""

import json

import numpy as np
import pytest

from smd_statespace.accelerometer import UNKNOWN_MASS, accelerometer_record
from smd_statespace.cli.main import main
from smd_statespace.io import G
from smd_statespace.person import identify_person
from smd_statespace.simulation.phone import simulate_phone

PERSON = dict(mass=65.0, f_b=2.1, f_h=2.8, xi_h=0.3, duration=16.0)
"""The simulated person (kg, Hz, Hz, -, s)."""


@pytest.fixture(scope="module")
def phones(tmp_path_factory):
    """The same person and phone draws (seed 21), the phone level and tilted 30 degrees: the written files.

    A quiet sensor (0.01 m/s^2): the phone-frame noise projects differently on a tilted vertical, so the two
    records' noise is not the same draw; quiet, it moves the estimates by little against their sds."""
    folder = tmp_path_factory.mktemp("phone")
    out = {}
    for tilt in (0.0, 30.0):
        phone = simulate_phone(**PERSON, tilt=tilt, bias=0.2, noise=0.01, seed=21)
        out[tilt] = (phone, phone.write(folder / f"tilt{tilt:g}.csv")[0])
    return out


@pytest.fixture(scope="module")
def people(phones):
    """The record-level person of each phone's file, without a body mass."""
    # fitted as measured (no noise floor): the two phones' answers are compared, and the floor's added noise,
    # drawn from each record's own samples, would differ between them
    return {tilt: identify_person(accelerometer_record(path), noise_floor=None) for tilt, (_, path) in phones.items()}


def test_the_phone_sees_the_persons_com_acceleration(phones):
    """Read back, clock repaired and projected on the record's own vertical, the phone's file gives the person's
    true COM acceleration to within the sensor's noise (0.05 m/s^2)."""
    for phone, path in phones.values():
        record = accelerometer_record(path)
        assert record.extra["sensor"] == "accelerometer" and not record.extra["mass_known"]
        assert record.mass == UNKNOWN_MASS
        a_v = record.force / record.mass - G
        truth = np.interp(record.time + phone.time[0], phone.time, phone.vertical)
        inner = slice(int(record.fs), -int(record.fs))
        error = float(np.sqrt(np.mean((a_v - truth)[inner] ** 2)))
        assert error < 1.3 * phone.truth["phone"]["noise"] + 0.005, error  # the noise, the interpolation
        assert abs(record.extra["geometry"]["tilt_deg"] - phone.truth["phone"]["tilt_deg"]) < 3.0


def test_a_tilted_phone_gives_the_answer_of_a_level_one(people):
    """Same person, same clock and sensor draws, the phone level or tilted 30 degrees: the same f_h, xi_h and
    BLF1 (a vertical taken wrongly, the z axis of a tilted phone, would scale the signal by cos 30 = 0.87: BLF1
    13 % off)."""
    level, tilted = people[0.0], people[30.0]
    # within half their sds: besides the noise, the horizontal motion and the biases project differently on the
    # two phones' verticals (measured at 0.01 m/s^2 noise: f_h 0.27 sd, xi_h 0.41 sd; xi_h 0.72 sd at 0.05); a
    # wrong vertical is caught by BLF1 below (13 % off)
    assert abs(tilted.f_h - level.f_h) < 0.5 * level.se[0]
    assert abs(tilted.xi_h - level.xi_h) < 0.5 * level.se[1]
    blf = tilted.template_blf().loc[1], level.template_blf().loc[1]
    assert abs(blf[0]["blf"] - blf[1]["blf"]) < 0.5 * blf[1]["sd"] and abs(blf[0]["blf"] / blf[1]["blf"] - 1) < 0.05
    low, high = tilted.intervals["f_h"]
    assert low < PERSON["f_h"] < high


def test_without_a_mass_k_and_c_are_left_out_and_said_so(people):
    result = people[30.0]
    row = result.to_dict()
    assert "k_h" not in row and "c_h" not in row and row["mass_known"] is False
    assert row["sensor"] == "accelerometer" and row["accelerometer"]["geometry_tilt_deg"] > 20
    assert "not computed without the body mass" in result.summary()
    assert result.record_arguments().endswith("--accelerometer")


def test_identify_and_diagnose_an_accelerometer_from_the_command_line(phones, tmp_path, capsys):
    """``simulate --accelerometer`` writes phyphox's format; ``identify --accelerometer`` without a mass writes
    person.json with the sensor and without K_h; with a mass K_h comes back (Eq. 17)."""
    path = tmp_path / "phone.csv"
    assert main(["simulate", "--out", str(path), "--mass", "70", "--fb", "2", "--fh", "2.6", "--xi", "0.3",
                 "--duration", "12", "--seed", "4", "--accelerometer", "--tilt", "20"]) == 0
    assert path.read_text().startswith('"Time (s)","Acceleration x (m/s^2)"')
    assert "identify it with: smd-statespace identify" in capsys.readouterr().out
    out = tmp_path / "out"
    assert main(["identify", str(path), "--accelerometer", "--out", str(out), "--quiet"]) == 0
    person = json.loads((out / "person.json").read_text())
    assert person["sensor"] == "accelerometer" and "k_h" not in person
    assert json.loads((out / "run.json").read_text())["mass"] is None
    with_mass = tmp_path / "with_mass"
    assert main(["identify", str(path), "--accelerometer", "--mass", "70", "--out", str(with_mass), "--quiet"]) == 0
    again = json.loads((with_mass / "person.json").read_text())
    assert again["f_h"] == pytest.approx(person["f_h"], rel=1e-6)
    assert again["k_h"] == pytest.approx(70 * (2 * np.pi * again["f_h"]) ** 2, rel=1e-9)


@pytest.mark.parametrize("arguments, message", [
    (["identify", "{phone}", "--accelerometer", "--estimator", "ekf"], "--accelerometer works with the record-level"),
    (["identify", "{phone}", "--units", "g", "--mass", "70"], "--units applies to an accelerometer record"),
    (["identify", "{phone}"], "it holds accelerations ('Acceleration x (m/s^2)', 'Acceleration y (m/s^2)', "
                              "'Acceleration z (m/s^2)'): a phone's or accelerometer's record is read with "
                              "--accelerometer"),
    (["diagnose", "{phone}", "--accelerometer", "--estimator", "ekf"], "--accelerometer works with the record-level"),
    (["simulate", "--out", "{out}", "--mass", "70", "--fb", "2", "--fh", "2.6", "--xi", "0.3", "--duration", "5",
      "--tilt", "10"], "--tilt applies to a phone's record"),
    (["simulate", "--out", "{out}", "--mass", "70", "--fb", "2", "--fh", "2.6", "--xi", "0.3", "--duration", "5",
      "--accelerometer", "--phone-rate", "1000"], "outside 50-500 Hz"),
])
def test_bad_accelerometer_options_are_one_line_errors(phones, tmp_path, capsys, arguments, message):
    phone = phones[0.0][1]
    out = tmp_path / "written.csv"
    arguments = [a.format(phone=phone, out=out) for a in arguments]
    assert main(arguments + ["--out", str(tmp_path / "o")] if arguments[0] != "simulate" else arguments) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not out.exists() and not (tmp_path / "o" / "person.json").exists()


def test_a_phone_that_leaves_the_ground_is_refused_in_the_phones_words(tmp_path, capsys):
    """A person jumping: the phone's specific force is ~0 in each flight (0.15 s of free fall per 0.5 s hop).
    ``identify --accelerometer`` refuses in one line, speaking of the phone and the ground (not of a plate), and
    writes nothing."""
    fs, f_jump = 200.0, 2.0
    t = np.arange(0.0, 20.0, 1.0 / fs)
    phase = (t * f_jump) % 1.0
    contact = phase < 0.7
    # a half-sine of 1/0.7 of a bounce during contact (mean force = body weight over the cycle), 0 in flight
    specific = np.where(contact, G * np.pi / 2 / 0.7 * np.sin(np.pi * phase / 0.7), 0.0)
    noise = np.random.default_rng(5).normal(0.0, 0.05, (t.size, 3))
    path = tmp_path / "jumping.csv"
    table = np.column_stack([t, noise[:, 0], noise[:, 1], specific + noise[:, 2]])
    np.savetxt(path, table, delimiter=",", header="time,ax,ay,az", comments="")
    out = tmp_path / "out"
    assert main(["identify", str(path), "--accelerometer", "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not a bouncing record (contact_lost)" in err[0], err
    assert "free fall" in err[0] and "plate" not in err[0], err
    assert not (out / "person.json").exists()


def test_a_folder_of_phone_records_is_one_batch(phones, people, tmp_path, capsys):
    """``identify FOLDER --accelerometer`` (no mass): one person per phone, the same as each file alone, with the
    sensor in results.csv and run.json; ``--resume`` takes them back without recomputing."""
    import pandas as pd

    folder = tmp_path / "phones"
    folder.mkdir()
    for tilt, (_, path) in phones.items():
        (folder / path.name).write_bytes(path.read_bytes())
    out = tmp_path / "batch"
    # --noise-floor 0: as the single files were fitted (the people fixture)
    assert main(["identify", str(folder), "--accelerometer", "--out", str(out), "--quiet", "--noise-floor", "0"]) == 0
    table = pd.read_csv(out / "results.csv")
    assert list(table["status"]) == ["ok", "ok"] and list(table["sensor"]) == ["accelerometer"] * 2
    assert table["mass"].isna().all() and "k_h" not in table
    row = table.set_index("record").loc[phones[30.0][1].name]
    assert row["f_h"] == pytest.approx(people[30.0].f_h, rel=1e-9)
    run = json.loads((out / "run.json").read_text())
    assert {r["sensor"] for r in run["records"]} == {"accelerometer"}
    capsys.readouterr()
    assert main(["identify", str(folder), "--accelerometer", "--out", str(out), "--quiet", "--resume",
                 "--noise-floor", "0"]) == 0
    assert "2 taken from the earlier run" in capsys.readouterr().out


def test_the_plate_through_the_sensors_filter_sees_what_the_phone_sees():
    """A phone with a perfect clock and the plate read through the same sensor filter at the same rate see the
    same vertical acceleration (the comparison of like with like in docs/phone.md); unfiltered, the plate leads
    by the filter's delay (about 2.8 ms at 80 Hz: several per cent of the signal)."""
    phone = simulate_phone(mass=65.0, f_b=2.1, f_h=2.8, xi_h=0.3, duration=6.0, fs=200.0, jitter=0.0, drop=0.0,
                           noise=0.0, seed=8)
    filtered = phone.plate_record(fs=200.0, noise=0.0, filtered=True)
    raw = phone.plate_record(fs=200.0, noise=0.0)
    assert filtered.time.size == phone.vertical.size
    assert np.allclose(filtered.force / filtered.mass - G, phone.vertical, atol=1e-9)
    lag = np.sqrt(np.mean((raw.force / raw.mass - G - phone.vertical) ** 2)) / np.std(phone.vertical)
    assert lag > 0.01, lag
