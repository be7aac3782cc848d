"""The noise floor (person/noise_floor.py): a quiet record is fitted with white noise added up to 1 % BW."""

import numpy as np
import pytest

from smd_statespace.cli.main import main
from smd_statespace.errors import OptionError
from smd_statespace.io import G
from smd_statespace.person import identify_person
from smd_statespace.person.noise_floor import (NOISE_FLOOR, check_noise_floor, measured_label, measured_noise,
                                               noise_added, raise_to_floor)
from smd_statespace.simulation import simulate_bouncing


def _bouncing_like(fs, noise_sd, seed=0, seconds=30.0):
    """Harmonics of 2.3 Hz up to 14 Hz (m/s^2) and white noise of ``noise_sd``."""
    t = np.arange(int(seconds * fs)) / fs
    signal = sum(a * np.sin(2 * np.pi * 2.3 * k * t + k) for k, a in ((1, 4.0), (2, 2.0), (3, 0.6), (4, 0.3), (6, 0.1)))
    return signal + noise_sd * np.random.default_rng(seed).standard_normal(t.size)


@pytest.mark.parametrize("fs", [100.0, 90.91, 200.0])
def test_measured_noise_is_the_white_noise_under_a_bouncing_force(fs):
    for sd in (0.005, 0.1):
        assert measured_noise(_bouncing_like(fs, sd), fs) == pytest.approx(sd, rel=0.05)
    assert measured_noise(_bouncing_like(fs, 0.0), fs) < 1e-3  # the force's harmonics do not leak into the band


def test_raise_to_floor_adds_what_is_missing_reproducibly_and_nothing_above_it():
    fs, target = 100.0, NOISE_FLOOR * G
    quiet = _bouncing_like(fs, 0.01)
    raised, notes = raise_to_floor(quiet, None, fs, NOISE_FLOOR)
    assert np.std(raised - quiet) == pytest.approx(np.sqrt(target**2 - 0.01**2), rel=0.03)
    assert measured_noise(raised, fs) == pytest.approx(target, rel=0.05)
    assert len(notes) == 1 and "--noise-floor 0" in notes[0] and "0.1 % BW" in notes[0]
    again, _ = raise_to_floor(quiet.copy(), None, fs, NOISE_FLOOR)
    assert np.array_equal(raised, again)  # seeded by the record: the same record, the same draw
    louder = 1.5 * quiet  # another record, another draw
    other, _ = raise_to_floor(louder, None, fs, NOISE_FLOOR)
    assert not np.allclose(other - louder, raised - quiet)
    # the record as a CSV at 6 decimals gives it back (the draw is seeded by rounded summaries, not the bytes)
    copy, _ = raise_to_floor(np.round(quiet, 6), None, fs, NOISE_FLOOR)
    assert np.allclose(copy - np.round(quiet, 6), raised - quiet, atol=0)
    raw = np.arange(5.0)  # seeded by other samples (identify_person: the force as read), the same ones, the same draw
    seeded = raise_to_floor(quiet, None, fs, NOISE_FLOOR, seed_from=raw)[0]
    assert np.array_equal(seeded, raise_to_floor(quiet, None, fs, NOISE_FLOOR, seed_from=raw.copy())[0])
    assert not np.allclose(seeded, raised)
    noisy = _bouncing_like(fs, 1.2 * target)
    assert raise_to_floor(noisy, None, fs, NOISE_FLOOR)[0] is noisy
    assert raise_to_floor(quiet, None, fs, 0.0) == (quiet, [])


def test_bad_noise_floor_is_refused_in_words():
    assert check_noise_floor(None) == 0.0
    for bad in (-0.01, 0.2, "1 %", True, float("nan")):
        with pytest.raises(OptionError, match="noise_floor"):
            check_noise_floor(bad)
    rec = simulate_bouncing(duration=10.0, seed=2).record
    with pytest.raises(OptionError, match="noise_floor"):
        identify_person(rec, noise_floor=0.5)


def test_cli_noise_floor_bad_value_exits_2(tmp_path, capsys):
    assert main(["identify", str(tmp_path / "none.csv"), "--mass", "70", "--noise-floor", "2"]) == 2
    assert "--noise-floor" in capsys.readouterr().err


def test_a_quiet_record_is_fitted_at_the_floor_and_as_measured_without_it():
    sim = simulate_bouncing(mass=70, f_b=2.2, f_h=2.8, xi_h=0.3, duration=12.0, noise=0.001, seed=5)
    floored = identify_person(sim.record, check_change=False)
    assert floored.sigma == pytest.approx(NOISE_FLOOR * G, rel=0.1)
    assert any("white noise of" in note for note in floored.notes) and noise_added(floored.notes)
    assert measured_label(floored.notes) == "measured + the noise floor's noise"  # the figures' legend
    measured = identify_person(sim.record, check_change=False, noise_floor=None)
    assert measured.sigma < 0.3 * NOISE_FLOOR * G  # the record as measured (its noise and the model's misfit)
    assert not noise_added(measured.notes) and measured_label(measured.notes) == "measured"
