"""The crowd-load generator: people from Table 2, each one's GRF, the total force, the command."""

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from smd_statespace import OptionError, article
from smd_statespace.cli import main
from smd_statespace.simulation.crowd import (DEFAULT_DURATION, draw_people, fit_table, periodic_grf_minimum, person_seeds,
                                  simulate_crowd)
from smd_statespace.simulation import MASS_DISTRIBUTION, POPULATION_BOUNDS, simulate_bouncing


def truncated_cdf(distribution, low, high):
    """CDF of ``distribution`` truncated to [low, high] (what sample_population's redraws produce)."""
    lo, hi = distribution.cdf(low), distribution.cdf(high)
    return lambda x: (distribution.cdf(np.clip(x, low, high)) - lo) / (hi - lo)


COLUMNS = {"f_h": ("f_h", "f_h"), "xi_h": ("xi_h", "xi_h"), "blf1": ("BLF1", "blf"), "blf2": ("BLF2", "blf"),
           "blf3": ("BLF3", "blf")}


@pytest.fixture(scope="module")
def many_people():
    return draw_people(300, 2.5, seed=11)  # band 2.15-2.55 Hz, no GRFs simulated


def test_people_follow_the_table2_distributions(many_people):
    """KS tests against Table 2's truncated skew-normals of the band holding f_b; the next band is rejected."""
    band = article.band_of(2.5)
    for column, (parameter, limit) in COLUMNS.items():
        cdf = truncated_cdf(article.TABLE2[parameter][band].dist(), *POPULATION_BOUNDS[limit])
        assert stats.kstest(many_people[column], cdf).pvalue > 1e-3, column
    wrong = truncated_cdf(article.TABLE2["f_h"][band + 1].dist(), *POPULATION_BOUNDS["f_h"])
    assert stats.kstest(many_people["f_h"], wrong).pvalue < 1e-6  # the test can tell bands apart
    mass = truncated_cdf(stats.norm(*MASS_DISTRIBUTION), *POPULATION_BOUNDS["mass"])
    assert stats.kstest(many_people["mass"], mass).pvalue > 1e-3
    # Eq. 17-18
    np.testing.assert_allclose(many_people["K_h"], many_people["mass"] * (2 * np.pi * many_people["f_h"]) ** 2)
    np.testing.assert_allclose(many_people["C_h"],
                               2 * many_people["xi_h"] * many_people["mass"] * 2 * np.pi * many_people["f_h"])


def test_a_users_table_is_followed(tmp_path):
    """Own fits (layout of article.table2_frame / the stats command's table2.csv), by band edges."""
    frame = article.table2_frame().reset_index()
    custom = frame.copy()
    row = (custom["parameter"] == "f_h") & (custom["low"] == 2.15)
    custom.loc[row, ["m", "s", "a"]] = (3.2, 0.1, 0.0)  # a = 0: normal, mean 3.2 Hz
    path = tmp_path / "fits.csv"
    custom.to_csv(path, index=False)
    people = draw_people(60, 2.3, seed=5, table=path)
    assert people["f_h"].mean() == pytest.approx(3.2, abs=0.05)
    assert stats.kstest(people["f_h"], stats.norm(3.2, 0.1).cdf).pvalue > 1e-3
    # the article's table written as CSV gives exactly the built-in draws
    frame.to_csv(tmp_path / "article.csv", index=False)
    pd.testing.assert_frame_equal(draw_people(5, 2.3, seed=5, table=tmp_path / "article.csv"),
                                  draw_people(5, 2.3, seed=5))
    # without band edges, 'band' indexes the article's bands; names like blf_1 are accepted
    plain = frame.drop(columns=["low", "high"]).replace({"BLF1": "blf_1"})
    pd.testing.assert_frame_equal(draw_people(5, 2.3, seed=5, table=plain), draw_people(5, 2.3, seed=5))


@pytest.mark.parametrize("change, message", [
    (lambda f: f.drop(columns=["s"]), "missing column"),
    (lambda f: f.drop(columns=["band", "low", "high"]), "band (or low, high)"),
    (lambda f: f[f["parameter"] != "xi_h"], "no row for parameter 'xi_h'"),
    (lambda f: f.assign(m=np.where(f["parameter"] == "BLF2", np.nan, f["m"])), "no fit for 'BLF2'"),
    (lambda f: f.assign(s=-1.0), "must be > 0"),
])
def test_bad_tables_say_what_is_wrong(change, message):
    frame = change(article.table2_frame().reset_index())
    with pytest.raises(OptionError, match=message.replace("(", r"\(").replace(")", r"\)")):
        fit_table(frame, 2.3)


def test_same_seed_same_crowd_and_person_i_whatever_n():
    big = simulate_crowd(6, 2.0, 6.0, seed=3)
    again = simulate_crowd(6, 2.0, 6.0, seed=3)
    pd.testing.assert_frame_equal(big.forces, again.forces)
    pd.testing.assert_frame_equal(big.people, again.people)
    small = simulate_crowd(3, 2.0, 6.0, seed=3)
    for column in ("person_000", "person_001", "person_002"):
        np.testing.assert_array_equal(small.forces[column], big.forces[column])
    pd.testing.assert_frame_equal(small.people, big.people.iloc[:3])
    other = simulate_crowd(3, 2.0, 6.0, seed=4)
    assert not np.allclose(other.forces["person_000"], small.forces["person_000"])
    # a fresh seed is recorded and repeats the crowd
    fresh = simulate_crowd(2, 2.0, 3.0)
    repeat = simulate_crowd(2, 2.0, 3.0, seed=np.random.SeedSequence(fresh.settings["seed"]))
    pd.testing.assert_frame_equal(fresh.forces, repeat.forces)


def test_total_is_the_sum_and_its_mean_the_weight():
    crowd = simulate_crowd(8, 2.5, 20.0, seed=1)
    people = crowd.forces.filter(like="person_")
    assert people.shape[1] == 8
    np.testing.assert_allclose(crowd.total, people.sum(axis=1), rtol=1e-12)
    assert crowd.total.mean() == pytest.approx(crowd.weight, rel=2e-3)  # u'' averages out (Eq. 3)
    assert crowd.weight == pytest.approx(crowd.people["mass"].sum() * 9.80665)
    harmonics = crowd.harmonics()
    assert harmonics.loc[1, "frequency"] == pytest.approx(2.5, abs=0.1)
    assert harmonics.loc[1, "amplitude_N"] > harmonics.loc[3, "amplitude_N"]


def test_each_grf_is_the_ode_simulators():
    """Person i's GRF is simulate_bouncing's (DOP853) with the person's parameters and force seed."""
    crowd = simulate_crowd(4, 1.9, 12.0, fs=150.0, seed=8, coef_variation=0.2)
    for i in (0, 3):
        person = crowd.people.iloc[i]
        reference = simulate_bouncing(mass=person["mass"], f_b=1.9, f_h=person["f_h"], xi_h=person["xi_h"],
                                      blf=(person["blf1"], person["blf2"], person["blf3"]), duration=12.0, fs=150.0,
                                      coef_variation=0.2, noise=0.0,
                                      seed=person_seeds(8, i, person["draw"])[1])
        column = crowd.forces[f"person_00{i}"].to_numpy()
        assert np.max(np.abs(column - reference.record.force)) < 1e-6 * person["weight"]
        pd.testing.assert_frame_equal(crowd.cycles[i][["t_start", "t_end", "f_b", "a1", "b1", "a3", "b3"]],
                                      reference.cycles[["t_start", "t_end", "f_b", "a1", "b1", "a3", "b3"]])


def test_in_step_crowd_adds_up_more_than_an_unsynchronised_one():
    apart = simulate_crowd(20, 2.0, 10.0, seed=2)
    together = simulate_crowd(20, 2.0, 10.0, seed=2, phase_spread=0.0, fb_variation=0.0)
    assert (together.people["phase_offset"] == 0).all() and apart.people["phase_offset"].max() > 0.5
    assert np.std(together.total) > 2.0 * np.std(apart.total)


def test_fifty_people_thirty_seconds_take_seconds():
    crowd = simulate_crowd(50, 2.5, 30.0, fs=200.0, seed=1)
    assert crowd.forces.shape == (6001, 52)
    assert crowd.seconds < 30.0  # measured: about 1-2 s on one shared core (most of it drawing the people)


@pytest.mark.parametrize("kwargs, message", [
    ({"n": 0}, "whole number >= 1"),
    ({"f_b": 4.0}, "outside the article's bands"),
    ({"fs": 20.0}, "too low"),
    ({"duration": 0.1}, "shorter than one bouncing cycle"),
    ({"fb_variation": 0.5}, "fb_variation must be in 0-0.2"),
    ({"phase_spread": 1.5}, "phase_spread must be in 0-1"),
    ({"seed": -1}, "seed must be"),
])
def test_bad_arguments_raise_option_errors(kwargs, message):
    arguments = dict(n=3, f_b=2.0, duration=5.0) | kwargs
    with pytest.raises(OptionError, match=message):
        simulate_crowd(**arguments)


def test_command_writes_forces_people_and_figure(tmp_path, capsys):
    out = tmp_path / "crowd.csv"
    assert main(["crowd", "--people", "4", "--fb", "2.5", "--duration", "6", "--out", str(out), "--seed", "1",
                 "--fs", "100"]) == 0
    forces = pd.read_csv(out)
    assert list(forces.columns) == ["time", "person_000", "person_001", "person_002", "person_003", "total"]
    assert len(forces) == 601 and forces["time"].iloc[-1] == pytest.approx(6.0)
    np.testing.assert_allclose(forces["total"], forces.filter(like="person_").sum(axis=1), atol=0.01)
    people = pd.read_csv(tmp_path / "crowd_people.csv")
    assert len(people) == 4 and {"mass", "f_h", "xi_h", "blf1", "blf2", "blf3", "K_h", "C_h",
                                 "phase_offset"} <= set(people.columns)
    assert (tmp_path / "crowd.png").stat().st_size > 10_000
    printed = capsys.readouterr().out
    assert "4 people bouncing at 2.5 Hz" in printed and "crowd_people.csv" in printed
    # the same seed writes the same file
    again = tmp_path / "again.csv"
    assert main(["crowd", "--people", "4", "--fb", "2.5", "--duration", "6", "--out", str(again), "--seed", "1",
                 "--fs", "100", "--figure", str(tmp_path / "f.png")]) == 0
    assert again.read_bytes() == out.read_bytes()


@pytest.mark.parametrize("extra, message", [
    (["--people", "0"], "--people: must be a whole number >= 1"),
    (["--fb", "5"], "outside the article's bands"),
    (["--fb", "-2"], "--fb: must be a positive number"),
    (["--fs", "10"], "too low"),
    (["--phase-spread", "2"], "phase_spread must be in 0-1"),
    (["--table", "missing.csv"], "no such file"),
    (["--out", "no/such/dir/c.csv"], "does not exist"),
    (["--seed", "1.5"], "non-negative whole number"),
])
def test_command_bad_options_are_one_line_and_status_2(extra, message, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv = {"--people": "3", "--fb": "2.0", "--duration": "5", "--out": "c.csv"}
    for flag, value in zip(extra[::2], extra[1::2]):
        argv[flag] = value
    assert main(["crowd"] + [item for pair in argv.items() for item in pair]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and message in err and err.startswith("smd-statespace: error:")


def test_command_reports_a_bad_table(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    article.table2_frame().reset_index().drop(columns=["a"]).to_csv(bad, index=False)
    assert main(["crowd", "--people", "2", "--fb", "2", "--duration", "4", "--out", str(tmp_path / "c.csv"),
                 "--table", str(bad)]) == 2
    assert "missing column(s) a" in capsys.readouterr().err


BAND_CENTRES = [round((low + high) / 2, 2) for low, high in article.BANDS]


@pytest.mark.parametrize("f_b", BAND_CENTRES)
def test_nobody_pulls_on_the_floor(f_b):
    """1000 people per band of the article: every GRF sample >= 0; those whose first draw would pull are redrawn."""
    crowd = simulate_crowd(1000, f_b, 4.0, fs=50.0, seed=2019)
    people, settings = crowd.people, crowd.settings
    assert crowd.forces.filter(like="person_").to_numpy().min() >= 0.0
    assert (people["grf_min"] >= 0).all()
    blf = people[["blf1", "blf2", "blf3"]].to_numpy()
    assert (periodic_grf_minimum(f_b, people["f_h"], people["xi_h"], blf) >= 0).all()
    # the problem is real: some of Table 2's first draws pull on the floor in their steady state, and were redrawn
    first = draw_people(1000, f_b, seed=2019)
    pulling = periodic_grf_minimum(f_b, first["f_h"], first["xi_h"], first[["blf1", "blf2", "blf3"]].to_numpy()) < 0
    assert pulling.any() and (people.loc[pulling, "draw"] > 0).all()
    kept = people["draw"] == 0
    pd.testing.assert_frame_equal(people.loc[kept, first.columns], first[kept])
    # the counts add up
    assert settings["redrawn"] == int((people["draw"] > 0).sum()) > 0
    assert (people["draw"] == people["rejected_steady"] + people["rejected_cycles"]).all()
    assert settings["rejected_steady"] == people["rejected_steady"].sum() >= pulling.sum()
    assert settings["rejected_cycles"] == people["rejected_cycles"].sum()
    assert f"contact: {settings['redrawn']} of 1000 people redrawn" in crowd.summary()


def test_periodic_minimum_is_the_steady_simulated_minimum():
    """Without cycle-to-cycle variation the simulated GRF is the steady periodic one: same minimum."""
    crowd = simulate_crowd(12, 2.35, 3.0, fs=2000.0, seed=4, fb_variation=0.0, coef_variation=0.0)
    people = crowd.people
    closed = periodic_grf_minimum(2.35, people["f_h"], people["xi_h"], people[["blf1", "blf2", "blf3"]].to_numpy())
    simulated = (people["grf_min"] / people["weight"]).to_numpy()
    np.testing.assert_allclose(simulated, closed, atol=2e-4)
    assert (simulated >= closed - 1e-5).all()  # sampled minima cannot be below the true one
    assert closed.min() < 0.5  # some people come close to leaving the floor


def test_redraws_are_reproducible_and_person_i_stays_person_i():
    big = simulate_crowd(30, 3.15, 5.0, fs=60.0, seed=7)
    assert big.settings["redrawn"] > 0
    again = simulate_crowd(30, 3.15, 5.0, fs=60.0, seed=7)
    pd.testing.assert_frame_equal(big.people, again.people)
    pd.testing.assert_frame_equal(big.forces, again.forces)
    small = simulate_crowd(12, 3.15, 5.0, fs=60.0, seed=7)
    pd.testing.assert_frame_equal(small.people, big.people.iloc[:12])
    # a redrawn person's seeds are their draw's: the force is simulate_bouncing's with them
    i = int(np.flatnonzero(big.people["draw"].to_numpy() > 0)[0])
    person = big.people.iloc[i]
    reference = simulate_bouncing(mass=person["mass"], f_b=3.15, f_h=person["f_h"], xi_h=person["xi_h"],
                                  blf=(person["blf1"], person["blf2"], person["blf3"]), duration=5.0, fs=60.0,
                                  noise=0.0, seed=person_seeds(7, i, person["draw"])[1])
    assert np.max(np.abs(big.forces.iloc[:, 1 + i].to_numpy() - reference.record.force)) < 1e-6 * person["weight"]


def test_command_duration_defaults_and_output_says_who_was_redrawn(tmp_path, capsys):
    out = tmp_path / "c.csv"
    assert main(["crowd", "--people", "6", "--fb", "3.2", "--out", str(out), "--seed", "1", "--fs", "60"]) == 0
    forces = pd.read_csv(out)
    assert forces["time"].iloc[-1] == pytest.approx(DEFAULT_DURATION)
    people = pd.read_csv(tmp_path / "c_people.csv")
    assert {"grf_min", "draw", "rejected_steady", "rejected_cycles"} <= set(people.columns)
    assert (forces.filter(like="person_") >= 0).all().all()
    printed = capsys.readouterr().out
    assert "contact: " in printed
    redrawn = int((people["draw"] > 0).sum())
    assert (f"{redrawn} of 6 people redrawn" in printed) if redrawn else ("first draw" in printed)
