"""The record front end: hum found and removed, bouts of bouncing found, records trimmed, decimation's guard band."""

import numpy as np
import pytest

from smd_statespace.errors import OptionError, RecordError
from smd_statespace.io import G, make_record
from smd_statespace.signals import decimate_record, find_bouts, front_end, mains_hum, remove_hum, trim_record

MASS = 70.0
FB = 2.2


def lab_record(seed=0, hum=(1.5, 0.6), bouncing=True, two=False, drift=4.0, off_at=None, tire=0.0):
    """Standing 4 s, a 2-cycle ramp, bouncing 30 s at 2.2 Hz, a 2-cycle ramp, standing 3 s; hum, drift, noise.

    ``tire``: the bouncing's amplitude falls linearly by this fraction over the 30 s (the person tires).

    Returns the record, the true steady span (s) and the hum-free, noise-free force (N).
    """
    rng = np.random.default_rng(seed)
    t0 = 4.0
    t1, t2 = t0 + 2 / FB, t0 + 2 / FB + 30.0
    t3 = t2 + 2 / FB
    t = np.arange(0.0, t3 + 3.0, 0.001)
    envelope = np.clip((t - t0) / (t1 - t0), 0, 1) * np.clip((t3 - t) / (t3 - t2), 0, 1) * bouncing
    envelope *= 1.0 - tire * np.clip((t - t1) / (t2 - t1), 0, 1)
    if two:  # a pause of about 4 s in the middle: two bouts
        envelope *= np.clip(np.abs(t - (t1 + t2) / 2) - 2.0, 0, 1)
    phase = 2 * np.pi * FB * (t - t0)
    shape = 0.45 * np.sin(phase) + 0.12 * np.sin(2 * phase + 0.4) + 0.04 * np.sin(3 * phase + 0.8)
    sway = 0.006 * np.sin(2 * np.pi * 0.25 * t + 1.0)
    clean = MASS * G * (1 + envelope * shape + sway * (1 - envelope)) + drift * t / t[-1]
    if off_at is not None:
        clean[t > off_at] = 0.0
    hum_wave = hum[0] * np.sin(2 * np.pi * 50 * t + 0.3) + hum[1] * np.sin(2 * np.pi * 150 * t + 1.1)
    force = clean + hum_wave + rng.normal(0.0, 2.0, t.size)
    return make_record(t, force, MASS if off_at is None else MASS * 0.75), (t1, t2), clean


def test_hum_amplitudes_are_recovered_and_its_lines_removed_leaving_the_bouncing_band():
    record, _, clean = lab_record()
    hum = mains_hum(record)
    assert hum.found and hum.frequency == pytest.approx(50.0, abs=0.005)
    np.testing.assert_allclose(hum.amplitudes[[0, 2]], [1.5, 0.6], rtol=0.05)
    assert list(np.flatnonzero(hum.lines)) == [0, 2]  # 50 and 150 Hz; 100 Hz is no line
    cleaned = remove_hum(record, hum)
    t = record.time
    inner = slice(3000, -3000)
    for f, amplitude in ((50.0, 1.5), (150.0, 0.6)):  # what is left at each line: under 5 % of it
        basis = np.exp(-2j * np.pi * f * t[inner])
        assert 2 * abs(np.mean((cleaned.force - clean)[inner] * basis)) < 0.05 * amplitude
    from scipy import signal
    low = signal.butter(8, 30.0, fs=1000.0, output="sos")
    change = signal.sosfiltfilt(low, cleaned.force - record.force)[500:-500]  # this low-pass rings 0.5 s at the ends
    assert np.abs(change).max() < 0.5  # the bouncing band is untouched (< 0.5 N)


def test_no_hum_is_no_hum():
    record, _, _ = lab_record(hum=(0.0, 0.0))
    hum = mains_hum(record)
    assert not hum.found and remove_hum(record, hum) is record
    assert "no mains hum" in hum.describe()


def test_the_steady_bout_is_found_within_a_cycle_with_the_standing_levels():
    record, (start, end), _ = lab_record(seed=1)
    bouts = find_bouts(remove_hum(record))
    assert len(bouts.bouts) == 1
    bout = bouts.bouts[0]
    assert abs(bout.start - start) < 1 / FB and abs(bout.end - end) < 1 / FB
    assert bout.period == pytest.approx(1 / FB, rel=0.01)
    assert bout.ramp_in is not None and bout.ramp_out is not None  # the ramps are left out of the span
    kinds = [s.kind for s in bouts.segments]
    assert kinds == ["standing", "ramp", "bouncing", "ramp", "standing"]
    assert bouts.mass == pytest.approx(MASS, rel=0.01)  # standing level / g, the sway averaged over 3 s
    assert bouts.drift == pytest.approx(4.0 * (end - 0.0) / record.time[-1], abs=3.0)  # sway limits it
    assert bouts.noise_sd == pytest.approx(2.0, rel=0.1)
    text = bouts.describe()
    assert "\n" not in text and "bouncing" in text and "standing" in text


@pytest.mark.parametrize("seed", [2, 3])
def test_a_tiring_person_is_bouncing_to_the_end_not_ramping_down_for_half_the_bout(seed):
    record, (start, end), _ = lab_record(seed=seed, tire=0.3)  # the amplitude falls 30 % over the 30 s
    bouts = find_bouts(remove_hum(record))
    assert len(bouts.bouts) == 1
    bout = bouts.bouts[0]
    assert abs(bout.end - end) < 1.5 / FB and abs(bout.start - start) < 1.5 / FB
    ramps = [s for s in bouts.segments if s.kind == "ramp"]
    assert ramps and max(s.end - s.start for s in ramps) < 4 / FB  # starting and stopping: a few cycles


def test_two_bouts_are_both_returned():
    record, _, _ = lab_record(seed=2, two=True)
    bouts = find_bouts(remove_hum(record))
    assert len(bouts.bouts) == 2 and bouts.bouts[0].end < bouts.bouts[1].start


def test_no_bouncing_gives_an_empty_result_refused_in_words():
    record, _, _ = lab_record(seed=3, bouncing=False)
    bouts = find_bouts(remove_hum(record))
    assert not bouts.found and bouts.bouts == ()
    assert [s.kind for s in bouts.segments] == ["standing"]
    with pytest.raises(RecordError, match="no bouncing") as info:
        bouts.require()
    assert "\n" not in str(info.value)


def test_stepping_off_is_no_contact():
    record, (start, end), _ = lab_record(seed=4, off_at=30.0)
    bouts = find_bouts(remove_hum(record))
    assert bouts.segments[-1].kind == "no_contact" and bouts.segments[-1].start == pytest.approx(30.0, abs=0.05)
    assert len(bouts.bouts) == 1 and bouts.bouts[0].end <= 30.0


def test_trim_keeps_times_and_every_signal_aligned():
    record, _, _ = lab_record(seed=5)
    record = make_record(record.time, record.force, MASS, floor_acc=np.sin(record.time))
    out = trim_record(record, (10.0, 20.0))
    assert out.time[0] == pytest.approx(10.0) and out.time[-1] == pytest.approx(20.0)
    np.testing.assert_array_equal(out.floor_acc, np.sin(out.time))
    np.testing.assert_array_equal(out.force, record.force[(record.time >= 9.9995) & (record.time <= 20.0005)])


@pytest.mark.parametrize("span, error, words", [((30.0, 60.0), RecordError, "outside the record"),
                                                ((-5.0, 10.0), RecordError, "outside the record"),
                                                ((20.0, 10.0), OptionError, "start < end"),
                                                ("all", OptionError, "pair")])
def test_a_bad_span_is_a_one_line_error_naming_it(span, error, words):
    record, _, _ = lab_record(seed=6)
    with pytest.raises(error, match=words) as info:
        trim_record(record, span)
    assert "span=" in str(info.value) and "\n" not in str(info.value)


def test_decimated_white_noise_stays_white_and_a_line_at_the_new_nyquist_frequency_is_kept_off():
    rng = np.random.default_rng(np.random.SeedSequence(9))
    t = np.arange(0.0, 300.0, 0.001)
    out, _, _ = decimate_record(make_record(t, MASS * G + rng.normal(0.0, 5.0, t.size), MASS), 100.0)
    x = out.force - out.force.mean()
    lags = np.array([np.dot(x[:-k], x[k:]) / np.dot(x, x) for k in range(1, 21)])
    assert np.abs(lags).max() < 0.02  # sd of one lag's estimate: 0.006
    line, _, _ = decimate_record(make_record(t[:30000], MASS * G + np.sin(2 * np.pi * 50 * t[:30000] + 0.7), MASS))
    left = line.force[300:-300] - MASS * G  # 3 s in from the ends
    assert np.sqrt(np.mean(left ** 2)) < 0.1  # an ideal filter at 50 Hz itself: 0.25 (alternating every sample)


def test_front_end_gives_the_steady_part_hum_free_and_decimated():
    record, (start, end), _ = lab_record(seed=7)
    result = front_end(record)
    steady = result.steady()
    assert result.factor == 10 and steady.fs == pytest.approx(100.0)
    assert abs(steady.time[0] - start) < 1 / FB and abs(steady.time[-1] - end) < 1 / FB
    assert result.hum.found and "mains hum at 50.0" in result.hum.describe()


def test_a_jump_is_movement_and_flight_not_bouncing():
    # standing, a countermovement (down, push), 0.5 s of flight, landing, standing: as BMClab's jump1.txt
    t = np.arange(0.0, 10.0, 1 / 450)
    weight = MASS * G
    force = weight * (1 - 0.6 * np.exp(-((t - 3.3) / 0.15) ** 2) + 1.2 * np.exp(-((t - 3.75) / 0.12) ** 2))
    force[(t > 4.0) & (t < 4.5)] = 0.0
    force += weight * 2.0 * np.exp(-((t - 4.6) / 0.06) ** 2) * (t >= 4.5)
    force += np.random.default_rng(10).normal(0.0, 2.0, t.size)
    bouts = find_bouts(make_record(t, force, MASS * 0.95))
    kinds = [s.kind for s in bouts.segments]
    assert not bouts.found and kinds == ["standing", "movement", "no_contact", "movement", "standing"]
    assert bouts.segments[2].start == pytest.approx(4.0, abs=0.03) and bouts.segments[2].end == pytest.approx(4.5, abs=0.03)


@pytest.mark.parametrize("blf_1, flight", [(0.235, False), (0.30, True)])
def test_a_deep_bounce_near_zero_keeps_contact_and_one_through_zero_does_not(blf_1, flight):
    """Bouncing near resonance (f_b 2.40, f_h 2.50 Hz, xi_h 0.105) dips to 3 % of body weight each cycle and stays on
    the plate: one bout, no "no contact" (the noise takes it under 5 % for 0.03 s); a force that would have to pass
    through zero (blf_1 0.30 g) is contact lost."""
    from smd_statespace.applicability import check_bouncing
    from smd_statespace.simulation import simulate_bouncing

    record = simulate_bouncing(mass=MASS, f_b=2.4, f_h=2.5, xi_h=0.105, duration=30.0, noise=0.01, seed=3,
                               blf=[blf_1, 0.05, 0.02], fb_variation=0.0, coef_variation=0.0).record
    bouts = find_bouts(record)
    kinds = [s.kind for s in bouts.segments]
    refusals = {f.kind for f in check_bouncing(record).refusals}
    if flight:
        assert "no_contact" in kinds and "contact_lost" in refusals
    else:
        assert record.force.min() < 0.05 * MASS * G  # the dips are there
        assert kinds == ["ramp", "bouncing", "ramp"] and not refusals
