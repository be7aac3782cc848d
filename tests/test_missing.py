"""diagnose on records with a hidden effect and on clean ones (false alarms are as bad as misses)."""

import json

import pytest

from smd_statespace.cli import main
from smd_statespace.missing import diagnose
from smd_statespace.signals import preprocess
from smd_statespace.simulate import simulate_bouncing


def record(seed, f_b, f_h, xi_h, effects=None, duration=12.0):
    return preprocess(simulate_bouncing(mass=72.0, f_b=f_b, f_h=f_h, xi_h=xi_h, duration=duration, seed=seed,
                                        effects=effects).record)


@pytest.mark.parametrize("seed,f_b,f_h,xi_h,blf", [(31, 2.0, 2.5, 0.3, (0.04, 0.03)), (32, 2.6, 3.1, 0.4, (0.05, 0.02))])
def test_hidden_harmonics_are_found_and_adding_them_lowers_the_residual(seed, f_b, f_h, xi_h, blf):
    result = diagnose(record(seed, f_b, f_h, xi_h, {"harmonics": {"blf": blf}}), max_passes=3)
    assert not result.adequate
    best = result.missing[0]
    assert best.name == "harmonics"
    assert best.check.residual_rms < (2 / 3) * result.base.residual_rms
    report = result.report()
    assert report["missing_effects"][0]["effect"] == "harmonics"
    assert set(report["missing_effects"][0]["params"]) >= {"a5", "b5", "a6", "b6"}


@pytest.mark.parametrize("seed,f_b,f_h,xi_h", [(41, 1.8, 2.2, 0.35), (42, 2.9, 3.3, 0.25)])
def test_clean_records_are_adequate(seed, f_b, f_h, xi_h):
    result = diagnose(record(seed, f_b, f_h, xi_h), max_passes=3)
    assert result.adequate, result.table()
    assert result.report()["missing_effects"] == []


def test_diagnose_cli_json_and_before_after(tmp_path, capsys):
    rec = tmp_path / "h.csv"
    assert main(["simulate", "--out", str(rec), "--mass", "70", "--fb", "2.2", "--fh", "2.6", "--xi", "0.3",
                 "--duration", "10", "--seed", "5", "--effect", "harmonics"]) == 0
    report_path = tmp_path / "report.json"
    assert main(["diagnose", str(rec), "--mass", "70", "--max-passes", "2", "--quiet", "--out", str(tmp_path / "d"),
                 "--json", str(report_path)]) == 0
    report = json.loads(report_path.read_text())
    assert set(report) == {"fit_percent", "residual_rms", "whiteness_pvalue", "effects_in_model", "adequate",
                           "missing_effects"}
    assert report["adequate"] is False and report["missing_effects"][0]["effect"] == "harmonics"
    assert (tmp_path / "d" / "diagnostics.png").exists() and (tmp_path / "d" / "fit.png").exists()
    capsys.readouterr()
    assert main(["diagnose", str(rec), "--mass", "70", "--max-passes", "2", "--quiet", "--out", str(tmp_path / "e"),
                 "--effect", "harmonics"]) == 0
    printed = capsys.readouterr().out
    assert "fit without and with harmonics" in printed
    assert (tmp_path / "e" / "before_after.png").exists()


def test_diagnose_bad_effect_is_one_line(tmp_path, capsys):
    rec = tmp_path / "c.csv"
    assert main(["simulate", "--out", str(rec), "--mass", "70", "--fb", "2.2", "--fh", "2.6", "--xi", "0.3",
                 "--duration", "8", "--seed", "6"]) == 0
    capsys.readouterr()
    assert main(["diagnose", str(rec), "--mass", "70", "--effect", "floor_mode"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "floor_acc" in err[0]
