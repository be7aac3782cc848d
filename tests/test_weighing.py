"""A record read without a body mass is weighed on the plate: standing first, whole bouncing cycles otherwise."""

import json
import re
from dataclasses import replace

import numpy as np
import pytest

from smd_statespace.cli import main
from smd_statespace.errors import MassError, RecordError
from smd_statespace.io import make_record, read_record, write_record
from smd_statespace.signals.weighing import weigh_record
from smd_statespace.simulation import simulate_bouncing
from smd_statespace.simulation.lab import simulate_lab_record


def unweighed(record, tmp_path, name="rec.csv"):
    """``record`` written as a CSV and read back without a mass."""
    path = tmp_path / name
    write_record(path, record)
    return read_record(path)


def test_a_lab_trial_is_weighed_on_its_standing_before_bouncing(tmp_path):
    synthetic = simulate_lab_record(mass=82.0, f_b=2.2, f_h=2.8, stand_before=4.0, stand_after=3.0, bout=12.0,
                                    fs=500.0, seed=11)
    read = unweighed(synthetic.record, tmp_path)
    assert read.extra["weigh"] and read.mass != 82.0  # provisional: the loaded force's median over g
    record = weigh_record(read)
    assert record.mass == pytest.approx(82.0, rel=0.005)
    note = record.extra["reading"][-1]
    assert note.startswith(f"body mass {record.mass:.1f} kg weighed on the plate: standing 0.0-")
    assert "(no mass given)" in note and not record.extra["weigh"]
    assert weigh_record(record) is record  # weighed once
    given = read_record(tmp_path / "rec.csv", 82.0)
    assert weigh_record(given) is given and given.mass == 82.0


def test_a_record_bouncing_end_to_end_is_weighed_on_its_whole_cycles(tmp_path):
    """No standing: over whole cycles the body's momentum returns, so the mean GRF is the weight."""
    synthetic = simulate_bouncing(mass=64.0, f_b=2.4, f_h=3.0, xi_h=0.3, duration=15.0, fs=200.0, seed=4)
    record = weigh_record(unweighed(synthetic.record, tmp_path))
    assert record.mass == pytest.approx(64.0, rel=0.005)
    assert "whole bouncing cycles" in record.extra["reading"][-1]
    assert "no standing of 0.3 s or more before bouncing; a drift of the plate's zero since it was set is in it: " \
        "give --mass if you know it" in record.extra["reading"][-1]


def test_what_cannot_be_weighed_is_refused_in_one_line(tmp_path):
    t = np.arange(0, 10, 0.01)
    rows = "\n".join(f"{tk:.2f},{1 + 0.3 * np.sin(2 * np.pi * 2 * tk):.5f}" for tk in t)
    (tmp_path / "bw.csv").write_text("time,force\n" + rows + "\n")  # a force in body weights, not N
    with pytest.raises(MassError, match=r"bw.csv: no body mass given, and the plate's force \(median 1 N = 0.1"
                                        r".* no person's weight \(20-250 kg\); give it with --mass KG"):
        read_record(tmp_path / "bw.csv")
    rows = "\n".join(f"{tk:.2f},{300 * np.sin(2 * np.pi * 2 * tk):.5f}" for tk in t)
    (tmp_path / "zeroed.csv").write_text("time,force\n" + rows + "\n")  # the plate zeroed with the person on it
    with pytest.raises(MassError, match="it swings about 0 .*: the body weight looks subtracted"):
        read_record(tmp_path / "zeroed.csv")
    rng = np.random.default_rng(3)  # neither still nor rhythmic: slow random movement of 30 % of the weight
    moving = 700 * (1 + 0.3 * np.convolve(rng.standard_normal(t.size + 49), np.ones(50) / 7, "valid"))
    read = unweighed(make_record(t, moving, 70.0), tmp_path, "moving.csv")
    with pytest.raises(RecordError, match="neither standing nor bouncing to weigh the person on; give the body "
                                          r"mass with --mass KG"):
        weigh_record(replace(read, source="moving.csv"))


def test_identify_without_mass_weighs_a_lab_export_and_says_so(tmp_path, capsys):
    synthetic = simulate_lab_record(mass=75.0, f_b=2.3, f_h=3.0, stand_before=3.0, stand_after=3.0, bout=14.0,
                                    fs=500.0, seed=5)
    path = tmp_path / "trial.csv"
    write_record(path, synthetic.record)
    assert main(["identify", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    out = capsys.readouterr().out
    said = re.search(r"note: body mass (\d+\.\d) kg weighed on the plate: standing 0\.0-", out)
    assert said and float(said.group(1)) == pytest.approx(75.0, rel=0.005), out
    run = json.loads((tmp_path / "out" / "run.json").read_text())
    assert run["mass"] == pytest.approx(float(said.group(1)), abs=0.05)
