"""Tests of smd_statespace.signals: Eq. 3, zero-phase high-pass, integration, cycles.

Test signals are built here with known answers (no dependency on the simulator):

* a multi-sine acceleration whose velocity and displacement are known in
  closed form, for the integration round trip;
* a bouncing GRF from a Fourier series with BLF-like harmonic amplitudes, cycle-to-
  cycle frequency jitter and noise, whose true peak times are known, for the
  segmentation.
"""

import re

import numpy as np
import pytest
from scipy import signal

from smd_statespace.errors import CycleError, MassError, OptionError, RecordError, SMDInputError
from smd_statespace.io import G, make_record
from smd_statespace.signals import (
    RATE_SLACK,
    SUPPORTED_FB,
    Cycle,
    Preprocessed,
    com_acceleration,
    decimate_record,
    find_cycles,
    highpass,
    integrate,
    preprocess,
)

MASS = 70.0  # kg


# ---------------------------------------------------------------------------
# Test signal generators
# ---------------------------------------------------------------------------


def multisine(fs, duration=30.0, seed=0, freqs=(1.5, 2.3, 3.7, 5.1, 7.9, 10.2, 14.0)):
    """Acceleration (m/s^2) as a sum of sines, with its exact velocity and displacement.

    Returns t, acc, vel, disp and the components (freqs, amps, phases) so that
    callers can build other exact references.
    """
    rng = np.random.default_rng(seed)
    freqs = np.asarray(freqs, dtype=float)
    amps = rng.uniform(0.5, 2.0, freqs.size)
    phases = rng.uniform(0.0, 2.0 * np.pi, freqs.size)
    t = np.arange(0.0, duration, 1.0 / fs)
    omega = 2.0 * np.pi * freqs[:, None]
    arg = omega * t + phases[:, None]
    acc = (amps[:, None] * np.sin(arg)).sum(0)
    vel = (-amps[:, None] / omega * np.cos(arg)).sum(0)
    disp = (-amps[:, None] / omega**2 * np.sin(arg)).sum(0)
    return t, acc, vel, disp, (freqs, amps, phases)


def trapezoid_gain(freqs, fs):
    """Gain of the trapezoidal rule relative to exact integration: x / tan(x), x = pi f / fs."""
    x = np.pi * np.asarray(freqs) / fs
    return x / np.tan(x)


def bouncing_grf(fb, fs=100.0, duration=20.0, mass=MASS, blf=(0.3, 0.15, 0.05), phases=(0.0, 1.2, 2.5),
                 jitter=0.02, noise=0.01, seed=0):
    """A bouncing GRF (N): body weight times (1 + Fourier series), cycle-by-cycle jittered.

    Each cycle k has its own frequency ``fb * (1 + jitter * N(0, 1))``; noise is
    white with standard deviation ``noise`` body weights. Returns t, force and
    the true times of the waveform's maximum in every cycle.
    """
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration, 1.0 / fs)
    n_cycles = int(duration * fb * 1.5) + 3
    f_cycle = fb * (1.0 + jitter * rng.standard_normal(n_cycles))
    edges = np.concatenate(([0.0], np.cumsum(1.0 / f_cycle)))
    k = np.searchsorted(edges, t, side="right") - 1
    phase = k + (t - edges[k]) * f_cycle[k]

    def waveform(ph):
        return sum(a * np.cos(2 * np.pi * (i + 1) * ph + p) for i, (a, p) in enumerate(zip(blf, phases)))

    force = mass * G * (1.0 + waveform(phase)) + noise * mass * G * rng.standard_normal(t.size)
    grid = np.linspace(0.0, 1.0, 20001)[:-1]
    peak_phase = grid[np.argmax(waveform(grid))]
    peak_times = edges[:-1] + peak_phase / f_cycle
    return t, force, peak_times[peak_times <= t[-1]]


def interior(t, trim):
    """Mask of the samples more than ``trim`` seconds from either end."""
    return (t >= t[0] + trim) & (t <= t[-1] - trim)


def rms(x):
    return float(np.sqrt(np.mean(np.square(x))))


def one_line(exc_info):
    message = str(exc_info.value)
    assert "\n" not in message
    return message


# ---------------------------------------------------------------------------
# Eq. 3
# ---------------------------------------------------------------------------


def test_com_acceleration_of_body_weight_is_zero():
    force = np.full(500, MASS * G)
    np.testing.assert_allclose(com_acceleration(force, MASS), 0.0, atol=1e-12)


def test_com_acceleration_known_values():
    # Eq. 3: twice the body weight accelerates the COM upwards at g; no force is free fall.
    acc = com_acceleration([2 * MASS * G, 0.0, 1.5 * MASS * G], MASS)
    np.testing.assert_allclose(acc, [G, -G, 0.5 * G], rtol=1e-12)


def test_com_acceleration_is_vectorised_over_people():
    masses = np.array([[50.0], [80.0]])
    force = masses * G * np.array([[1.0, 1.2, 0.7]])
    acc = com_acceleration(force, masses)
    assert acc.shape == (2, 3)
    np.testing.assert_allclose(acc, np.tile([0.0, 0.2 * G, -0.3 * G], (2, 1)), atol=1e-12)


@pytest.mark.parametrize("mass", [0.0, -70.0, np.nan, np.inf])
def test_com_acceleration_rejects_bad_mass(mass):
    with pytest.raises(MassError) as info:
        com_acceleration([700.0, 710.0], mass)
    assert "mass" in one_line(info)


# ---------------------------------------------------------------------------
# High-pass
# ---------------------------------------------------------------------------


def test_highpass_removes_offset_and_drift_and_keeps_the_band():
    fs = 100.0
    t = np.arange(0.0, 30.0, 1.0 / fs)
    band = np.sin(2 * np.pi * 2.0 * t) + 0.4 * np.sin(2 * np.pi * 6.3 * t + 1.0)
    drift = 5.0 + 0.5 * t + 0.3 * np.sin(2 * np.pi * 0.05 * t)
    out = highpass(band + drift, fs)
    mask = interior(t, 2.0)
    assert np.max(np.abs(out[mask] - band[mask])) < 5e-3 * rms(band)


def test_highpass_response_at_cutoff_is_half():
    # sosfiltfilt squares the Butterworth magnitude: 1/sqrt(2) twice gives 1/2.
    fs, cutoff = 100.0, 0.5
    t = np.arange(0.0, 120.0, 1.0 / fs)
    out = highpass(np.sin(2 * np.pi * cutoff * t), fs, cutoff=cutoff)
    mask = interior(t, 20.0)
    amplitude = np.sqrt(2.0) * rms(out[mask])
    assert amplitude == pytest.approx(0.5, rel=0.02)


def test_highpass_is_zero_phase():
    # Components close to the cut-off, where a causal high-pass shifts the phase most.
    fs = 100.0
    t = np.arange(0.0, 20.0, 1.0 / fs)
    x = sum(np.sin(2 * np.pi * f * t + p) for f, p in [(0.7, 0.3), (1.0, 2.0), (1.5, 4.0)])
    lags = signal.correlation_lags(x.size, x.size)
    near = np.abs(lags) <= 50

    def lag_of(y):
        return lags[near][np.argmax(signal.correlate(y, x)[near])]

    assert lag_of(highpass(x, fs)) == 0
    # The same filter run once, causally, leads: the test can tell the difference.
    causal = signal.sosfilt(signal.butter(4, 0.5, "highpass", fs=fs, output="sos"), x)
    assert lag_of(causal) < -5


def test_highpass_impulse_response_is_symmetric():
    # Zero phase means a real, even frequency response: a pulse stays centred and symmetric.
    fs = 100.0
    t = np.arange(-10.0, 10.0 + 0.5 / fs, 1.0 / fs)
    pulse = np.exp(-0.5 * (t / 0.05) ** 2)
    out = highpass(pulse, fs)
    centre = t.size // 2
    assert np.argmax(out) == centre
    np.testing.assert_allclose(out, out[::-1], rtol=0, atol=1e-8)


def test_highpass_filters_along_the_given_axis():
    fs = 100.0
    _, a, *_ = multisine(fs, duration=10.0, seed=1)
    _, b, *_ = multisine(fs, duration=10.0, seed=2)
    stacked = np.stack([a, b], axis=1)  # time along axis 0
    out = highpass(stacked, fs, axis=0)
    assert out.shape == stacked.shape
    np.testing.assert_allclose(out[:, 0], highpass(a, fs), atol=1e-12)
    np.testing.assert_allclose(out[:, 1], highpass(b, fs), atol=1e-12)


@pytest.mark.parametrize(
    "kwargs, word",
    [
        (dict(cutoff=0.0), "cutoff"),
        (dict(cutoff=-0.5), "cutoff"),
        (dict(cutoff=50.0), "cutoff"),  # = fs/2
        (dict(cutoff=80.0), "cutoff"),
        (dict(cutoff=np.nan), "cutoff"),
        (dict(order=0), "order"),
        (dict(order=2.5), "order"),
        (dict(padding="zeros"), "padding"),
        (dict(fs=0.0), "fs"),
    ],
)
def test_highpass_rejects_bad_options(kwargs, word):
    options = dict(fs=100.0, cutoff=0.5)
    options.update(kwargs)
    with pytest.raises(OptionError) as info:
        highpass(np.ones(1000), **options)
    assert word in one_line(info)


def test_highpass_rejects_a_signal_too_short_for_the_padding():
    with pytest.raises(OptionError) as info:
        highpass(np.ones(10), 100.0)
    message = one_line(info)
    assert "10 samples" in message and "padding" in message


def test_highpass_rejects_nan():
    x = np.ones(500)
    x[100] = np.nan
    with pytest.raises(RecordError):
        highpass(x, 100.0)


def test_errors_belong_to_the_input_error_family():
    with pytest.raises(SMDInputError):
        highpass(np.ones(1000), 100.0, cutoff=60.0)
    with pytest.raises(ValueError):
        find_cycles(np.arange(100) / 100.0, np.full(100, MASS * G))


def test_predictive_padding_shrinks_edge_errors():
    # The same 20 s of bouncing, processed alone and inside a 100 s record whose
    # middle is free of edge effects: the difference near the ends is the edge error.
    fs = 100.0
    t, force, _ = bouncing_grf(2.5, fs=fs, duration=100.0, seed=5)
    acc = com_acceleration(force, MASS)

    def displacement(a, padding):
        return integrate(integrate(highpass(a, fs, padding=padding), fs, padding=padding), fs, padding=padding)

    part = slice(int(40 * fs), int(60 * fs))
    reference = displacement(acc, "predict")[part]
    first_2s = slice(0, int(2 * fs))
    errors = {
        padding: np.max(np.abs(displacement(acc[part], padding) - reference)[first_2s]) / rms(reference)
        for padding in ("predict", "odd")
    }
    assert errors["predict"] < 0.1
    assert errors["odd"] > 5 * errors["predict"]


# ---------------------------------------------------------------------------
# Integration: the signal-level round trip acc -> vel -> disp
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("seed", [0, 1])
def test_integration_round_trip_matches_analytic_at_1000hz(seed):
    fs = 1000.0
    t, acc, vel, disp, _ = multisine(fs, seed=seed)
    acc_hp = highpass(acc, fs)
    vel_est = integrate(acc_hp, fs)
    disp_est = integrate(vel_est, fs)
    mask = interior(t, 2.0)
    assert np.max(np.abs(vel_est - vel)[mask]) < 0.01 * rms(vel)
    assert np.max(np.abs(disp_est - disp)[mask]) < 0.02 * rms(disp)
    deep = interior(t, 5.0)
    assert np.max(np.abs(vel_est - vel)[deep]) < 2e-3 * rms(vel)
    assert np.max(np.abs(disp_est - disp)[deep]) < 5e-3 * rms(disp)


@pytest.mark.parametrize("frequency", [1.5, 5.0, 14.0])
def test_velocity_gain_is_trapezoid_rule_times_filter_gain(frequency):
    # One sine at 100 Hz sampling: the velocity amplitude must be exactly the
    # trapezoid gain x/tan(x) (0.9347 at 14 Hz) times the zero-phase high-pass
    # gain 1/(1 + (fc/f)^8), applied twice (acceleration, then velocity).
    fs = 100.0
    t = np.arange(0.0, 20.0, 1.0 / fs)
    omega = 2 * np.pi * frequency
    vel_est = integrate(highpass(np.sin(omega * t), fs), fs)
    amplitude = np.sqrt(2.0) * rms(vel_est[interior(t, 2.0)]) * omega
    filter_gain = 1.0 / (1.0 + (0.5 / frequency) ** 8)
    assert amplitude == pytest.approx(trapezoid_gain(frequency, fs) * filter_gain**2, rel=2e-4)


@pytest.mark.parametrize("seed", [4, 5])
def test_integration_round_trip_at_100hz(seed):
    # At the insoles' 100 Hz the reference is the analytic answer with the
    # trapezoid gain applied per component (the exact one differs by ~1.5 %).
    fs = 100.0
    t, acc, vel, disp, (freqs, amps, phases) = multisine(fs, seed=seed)
    gain = trapezoid_gain(freqs, fs)[:, None]
    omega = 2 * np.pi * freqs[:, None]
    arg = omega * t + phases[:, None]
    vel_trap = (-gain * amps[:, None] / omega * np.cos(arg)).sum(0)
    disp_trap = (-(gain**2) * amps[:, None] / omega**2 * np.sin(arg)).sum(0)

    vel_est = integrate(highpass(acc, fs), fs)
    disp_est = integrate(vel_est, fs)
    mask = interior(t, 2.0)
    assert np.max(np.abs(vel_est - vel_trap)[mask]) < 0.006 * rms(vel)
    assert np.max(np.abs(disp_est - disp_trap)[mask]) < 0.015 * rms(disp)


def test_integrating_a_constant_gives_zero():
    # The integral of a constant is a ramp: pure drift, removed entirely.
    out = integrate(np.full(3000, 3.0), 100.0)
    np.testing.assert_allclose(out, 0.0, atol=1e-9)


# ---------------------------------------------------------------------------
# Cycles
# ---------------------------------------------------------------------------


def check_peaks_match(t, peaks, true_times, fb, tolerance=0.05):
    """Every true peak away from the record ends is found, and nothing else."""
    period = 1.0 / fb
    inner = true_times[(true_times > t[0] + 0.25 * period) & (true_times < t[-1] - 0.25 * period)]
    found = t[peaks]
    nearest_found = np.min(np.abs(inner[:, None] - found[None, :]), axis=1)
    assert np.all(nearest_found < tolerance), "a true GRF peak was missed"
    nearest_true = np.min(np.abs(found[:, None] - true_times[None, :]), axis=1)
    assert np.all(nearest_true < tolerance), "a peak was found where there is none"
    assert inner.size <= peaks.size <= inner.size + 2


@pytest.mark.parametrize("fb", [1.5, 2.0, 2.5, 3.0, 3.5])
@pytest.mark.parametrize("phases", [(0.0, 1.2, 2.5), (0.5, 2.0, 4.0), (0.0, 3.0, 1.0)])
def test_find_cycles_on_realistic_bouncing(fb, phases):
    t, force, true_times = bouncing_grf(fb, phases=phases, seed=int(fb * 10))
    peaks, cycles = find_cycles(t, force)
    check_peaks_match(t, peaks, true_times, fb)
    assert len(cycles) == peaks.size - 1
    f_b = np.array([c.f_b for c in cycles])
    assert np.median(f_b) == pytest.approx(fb, rel=0.03)
    assert all(c.valid and c.reason == "" for c in cycles)


def test_cycle_fields_are_consistent():
    t, force, _ = bouncing_grf(2.0, duration=10.0)
    peaks, cycles = find_cycles(t, force)
    for k, cycle in enumerate(cycles):
        assert isinstance(cycle, Cycle)
        assert cycle.index == k
        assert (cycle.start, cycle.stop) == (peaks[k], peaks[k + 1])
        assert cycle.n_samples == cycle.stop - cycle.start + 1
        assert (cycle.t_start, cycle.t_end) == (t[cycle.start], t[cycle.stop])
        assert cycle.f_b == pytest.approx(1.0 / (cycle.t_end - cycle.t_start))
    for before, after in zip(cycles, cycles[1:]):
        assert before.stop == after.start  # the boundary sample is shared
    with pytest.raises(Exception):
        cycles[0].start = 3  # frozen


def test_find_cycles_at_force_plate_rate():
    t, force, true_times = bouncing_grf(2.25, fs=1000.0, duration=10.0, seed=11)
    peaks, cycles = find_cycles(t, force)
    check_peaks_match(t, peaks, true_times, 2.25, tolerance=0.03)


@pytest.mark.parametrize("fb", [1.5, 2.0])
def test_find_cycles_ignores_the_second_hump_of_a_double_hump(fb):
    # A strong 2nd harmonic in phase gives each cycle a second hump half a period
    # after the main peak, 0.33 s apart at 1.5 Hz: further apart than the
    # shortest supported period (0.25 s), so peak spacing alone cannot hide it.
    t, force, true_times = bouncing_grf(fb, blf=(0.1, 0.2, 0.03), phases=(0.0, 0.0, 0.0), seed=7)
    span = np.percentile(force, 99) - np.percentile(force, 1)
    every_hump, _ = signal.find_peaks(force, prominence=0.2 * span)
    assert every_hump.size > 1.8 * true_times.size  # the humps are real, prominent peaks
    peaks, cycles = find_cycles(t, force)
    check_peaks_match(t, peaks, true_times, fb)
    assert np.median([c.f_b for c in cycles]) == pytest.approx(fb, rel=0.03)


def missed_peak_grf(fb):
    """A noise-free GRF whose 6th peak is replaced by a straight line between its troughs."""
    t, force, true_times = bouncing_grf(fb, duration=10.0, jitter=0.0, noise=0.0)
    half = 0.5 / fb
    a, b = np.searchsorted(t, [true_times[5] - half, true_times[5] + half])
    a = a - 10 + int(np.argmin(force[a - 10 : a + 10]))
    b = b - 10 + int(np.argmin(force[b - 10 : b + 10]))
    force = force.copy()
    force[a : b + 1] = np.linspace(force[a], force[b], b - a + 1)
    return t, force


def test_a_missed_peak_is_flagged_not_dropped():
    t, force = missed_peak_grf(2.0)
    peaks, cycles = find_cycles(t, force)
    invalid = [c for c in cycles if not c.valid]
    assert len(invalid) == 1
    merged = invalid[0]
    assert merged.f_b == pytest.approx(1.0, rel=0.02)
    assert "f_b 1.00 Hz" in merged.reason and "missed peak" in merged.reason
    assert len(cycles) == peaks.size - 1  # nothing removed


def test_a_merged_cycle_inside_the_range_is_still_flagged():
    # At 3 Hz two merged cycles give 1.5 Hz, a supported frequency: only the
    # duration relative to the median gives it away.
    t, force = missed_peak_grf(3.0)
    _, cycles = find_cycles(t, force)
    invalid = [c for c in cycles if not c.valid]
    assert len(invalid) == 1
    assert SUPPORTED_FB[0] <= invalid[0].f_b <= SUPPORTED_FB[1]
    assert "2.00 x the median" in invalid[0].reason


def test_flat_force_has_no_peaks():
    t = np.arange(0.0, 10.0, 0.01)
    with pytest.raises(CycleError) as info:
        find_cycles(t, np.full(t.size, MASS * G), source="flat.csv")
    message = one_line(info)
    assert message.startswith("flat.csv: ") and "no GRF peaks" in message


def test_standing_still_is_not_bouncing():
    t = np.arange(0.0, 10.0, 0.01)
    sway = MASS * G * (1.0 + 0.005 * np.random.default_rng(0).standard_normal(t.size))
    with pytest.raises(CycleError) as info:
        find_cycles(t, sway, source="stand.csv")
    assert "no GRF peaks" in one_line(info) and "stand.csv" in str(info.value)


def test_record_shorter_than_one_cycle():
    t, force, _ = bouncing_grf(2.0, duration=0.6)
    with pytest.raises(CycleError) as info:
        find_cycles(t, force, source="short.csv")
    message = one_line(info)
    assert "short.csv" in message and "shorter than one" in message


@pytest.mark.parametrize("frequency", [0.5, 6.0])
def test_unsupported_bouncing_frequency(frequency):
    t = np.arange(0.0, 20.0, 0.01)
    force = MASS * G * (1.0 + 0.3 * np.sin(2 * np.pi * frequency * t))
    with pytest.raises(CycleError) as info:
        find_cycles(t, force, source="odd.csv")
    message = one_line(info)
    assert "odd.csv" in message and "1.2-4 Hz" in message
    value = float(re.search(r"frequency (\d+\.\d+) Hz", message).group(1))
    assert value == pytest.approx(frequency, rel=0.05)


def test_fb_range_is_honoured():
    t, force, _ = bouncing_grf(2.0)
    with pytest.raises(CycleError) as info:
        find_cycles(t, force, fb_range=(2.5, 4.0))
    assert "2.5-4 Hz" in one_line(info)


@pytest.mark.parametrize("fb_range", [(4.0, 1.2), (0.0, 4.0), (1.2,), "fast"])
def test_bad_fb_range(fb_range):
    t, force, _ = bouncing_grf(2.0, duration=5.0)
    with pytest.raises(OptionError) as info:
        find_cycles(t, force, fb_range=fb_range)
    assert "fb_range" in one_line(info)


# ---------------------------------------------------------------------------
# The whole pipeline
# ---------------------------------------------------------------------------


def com_motion_record(fb=2.0, fs=100.0, duration=20.0, floor=False):
    """A record whose COM displacement u(t) is known: GRF = M (g + u_ddot) by Eq. 3.

    u is a sum of four harmonics of fb (the steady state of an SMD under a
    Fourier force is such a sum). Returns the record and exact (u, u_dot, u_ddot)
    with the trapezoid gain of 100 Hz sampling applied to u_dot and u.
    """
    t = np.arange(0.0, duration, 1.0 / fs)
    harmonics = np.arange(1, 5)
    amps = np.array([0.020, 0.006, 0.0015, 0.0005])  # m
    phases = np.array([0.3, 1.9, 4.0, 0.8])
    omega = 2 * np.pi * fb * harmonics[:, None]
    arg = omega * t + phases[:, None]
    gain = trapezoid_gain(fb * harmonics, fs)[:, None]
    disp = (gain**2 * amps[:, None] * np.cos(arg)).sum(0)
    vel = (-gain * amps[:, None] * omega * np.sin(arg)).sum(0)
    acc = (-amps[:, None] * omega**2 * np.cos(arg)).sum(0)
    force = MASS * (G + acc)
    floor_acc = 0.05 * np.sin(2 * np.pi * 3.48 * t) if floor else None
    record = make_record(t, force, MASS, floor_acc=floor_acc, source="person.csv")
    return record, disp, vel, acc


def test_preprocess_round_trip_recovers_com_motion():
    record, disp, vel, acc = com_motion_record()
    result = preprocess(record)
    assert isinstance(result, Preprocessed)
    np.testing.assert_allclose(result.acc_raw, (record.force - MASS * G) / MASS, atol=1e-12)  # Eq. 3
    mask = interior(record.time, 2.0)
    assert np.max(np.abs(result.acc - acc)[mask]) < 1e-3 * rms(acc)
    assert np.max(np.abs(result.vel - vel)[mask]) < 5e-3 * rms(vel)
    assert np.max(np.abs(result.disp - disp)[mask]) < 1e-2 * rms(disp)
    assert result.fs == pytest.approx(100.0)
    assert result.cutoff == 0.5 and result.mass == MASS
    assert result.floor_acc is None and result.floor_vel is None and result.floor_disp is None


def test_preprocess_integrates_the_floor_the_same_way():
    record, *_ = com_motion_record(floor=True)
    result = preprocess(record)
    t = record.time
    omega = 2 * np.pi * 3.48
    gain = trapezoid_gain(3.48, 100.0)
    mask = interior(t, 2.0)
    np.testing.assert_allclose(result.floor_acc[mask], record.floor_acc[mask], atol=1e-3 * 0.05)
    expected_disp = -(gain**2) * 0.05 / omega**2 * np.sin(omega * t)
    assert np.max(np.abs(result.floor_disp - expected_disp)[mask]) < 0.01 * 0.05 / omega**2


def test_preprocess_flags_cycles_near_the_record_ends():
    record, *_ = com_motion_record(duration=10.0)
    result = preprocess(record, edge_margin=1.0)
    t0, t1 = record.time[0], record.time[-1]
    for cycle in result.cycles:
        near = cycle.t_start - t0 < 1.0 or t1 - cycle.t_end < 1.0
        assert cycle.valid == (not near)
        assert ("record end" in cycle.reason) == near
    assert 0 < len(result.valid_cycles) < len(result.cycles)
    assert all(c.valid for c in preprocess(record, edge_margin=0.0).cycles)


def test_preprocess_tables():
    record, *_ = com_motion_record(floor=True)
    result = preprocess(record)
    frame = result.to_frame()
    assert list(frame.columns) == [
        "time", "force", "acc_raw", "acc", "vel", "disp", "floor_acc", "floor_vel", "floor_disp",
    ]
    assert len(frame) == record.time.size
    np.testing.assert_array_equal(frame["disp"].to_numpy(), result.disp)

    plain = preprocess(com_motion_record()[0]).to_frame()
    assert list(plain.columns) == ["time", "force", "acc_raw", "acc", "vel", "disp"]

    table = result.cycle_table()
    assert list(table.columns) == ["cycle", "t_start", "t_end", "n_samples", "f_b", "valid", "reason"]
    assert len(table) == len(result.cycles)
    assert table["f_b"].median() == pytest.approx(2.0, rel=0.01)
    assert table["n_samples"].tolist() == [c.n_samples for c in result.cycles]


def test_observations_shapes_and_channel_order():
    record, *_ = com_motion_record()
    result = preprocess(record)
    cycle = result.cycles[5]
    t, y = result.observations(cycle)
    assert t.shape == (cycle.n_samples,)
    assert y.shape == (cycle.n_samples, 3)
    np.testing.assert_array_equal(t, record.time[cycle.start : cycle.stop + 1])
    np.testing.assert_array_equal(y[:, 0], result.disp[cycle.start : cycle.stop + 1])
    np.testing.assert_array_equal(y[:, 1], result.vel[cycle.start : cycle.stop + 1])
    np.testing.assert_array_equal(y[:, 2], result.acc[cycle.start : cycle.stop + 1])

    t2, y2 = result.observations(5, channels=("u_ddot", "u"))  # by index, reordered
    np.testing.assert_array_equal(t2, t)
    np.testing.assert_array_equal(y2, y[:, [2, 0]])

    with pytest.raises(OptionError) as info:
        result.observations(cycle, channels=("u", "acc"))
    assert "'acc'" in one_line(info) and "u_ddot" in str(info.value)
    with pytest.raises(OptionError) as info:
        result.observations(len(result.cycles))
    assert "does not exist" in one_line(info)


def test_exogenous_floor_signals():
    result = preprocess(com_motion_record()[0])
    assert result.exogenous(3) == {}
    with_floor = preprocess(com_motion_record(floor=True)[0])
    cycle = with_floor.cycles[3]
    floor = with_floor.exogenous(cycle)
    assert set(floor) == {"floor_disp", "floor_vel", "floor_acc"}
    span = slice(cycle.start, cycle.stop + 1)
    np.testing.assert_array_equal(floor["floor_acc"], with_floor.floor_acc[span])
    np.testing.assert_array_equal(floor["floor_vel"], with_floor.floor_vel[span])
    np.testing.assert_array_equal(floor["floor_disp"], with_floor.floor_disp[span])


def test_summary_reports_the_record():
    result = preprocess(com_motion_record()[0])
    text = result.summary()
    assert "\n" not in text
    assert text.startswith("person.csv: ")
    assert f"{len(result.cycles)} bouncing cycles" in text
    assert "median 2.00" in text and "100 Hz" in text
    for unit in ("m/s^2", "m/s,", " m."):
        assert unit in text


def test_plot_returns_a_figure_and_writes_png(tmp_path):
    from matplotlib.figure import Figure

    result = preprocess(com_motion_record(floor=True, duration=12.0)[0])
    path = tmp_path / "steps.png"
    fig = result.plot(path)
    assert isinstance(fig, Figure)
    assert len(fig.axes) == 6 * 2  # five steps plus the part the high-pass removed, whole record and zoom
    assert all(ax.get_ylabel() for ax in fig.axes[::2])
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

    short = preprocess(com_motion_record(duration=2.0)[0], edge_margin=0.0)
    assert len(short.plot().axes) == 5  # too few cycles to zoom: one column


def test_preprocess_errors_name_the_record():
    t = np.arange(0.0, 20.0, 0.01)
    fast = make_record(t, MASS * G * (1.0 + 0.3 * np.sin(2 * np.pi * 6.0 * t)), MASS, source="fast.csv")
    with pytest.raises(CycleError) as info:
        preprocess(fast)
    assert one_line(info).startswith("fast.csv: ")

    record = com_motion_record()[0]
    with pytest.raises(OptionError) as info:
        preprocess(record, cutoff=80.0)
    message = one_line(info)
    assert message.startswith("person.csv: ") and "cutoff" in message


def test_find_cycles_rejects_nan():
    t, force, _ = bouncing_grf(2.0, duration=5.0)
    force[50] = np.nan
    with pytest.raises(RecordError) as info:
        find_cycles(t, force, source="gap.csv")
    assert "gap.csv" in one_line(info)


def _band_limited(t):
    """A bouncing-like force (N): 2.2 Hz and two harmonics up to 30 Hz, all below 0.4 of 100 Hz."""
    return MASS * G * (1.0 + 0.3 * np.sin(2 * np.pi * 2.2 * t + 0.3) + 0.05 * np.sin(2 * np.pi * 13.1 * t)
                       + 0.015 * np.sin(2 * np.pi * 30.0 * t))


def test_decimation_keeps_the_bouncing_band_and_removes_what_would_fold_onto_it():
    t = np.arange(0.0, 20.0, 0.001)
    high = 20.0 * np.sin(2 * np.pi * 80.0 * t)  # 80 Hz: kept every 10th sample it would fold onto 20 Hz
    floor = 0.1 * np.sin(2 * np.pi * 9.5 * t)
    record = make_record(t, _band_limited(t) + high, MASS, floor_acc=floor + 0.05 * np.sin(2 * np.pi * 80.0 * t))
    regressor = np.sin(2 * np.pi * 5.0 * t)
    out, factor, (decimated,) = decimate_record(record, 100.0, [regressor])
    assert factor == 10 and out.fs == pytest.approx(100.0) and out.time.size == 2000
    np.testing.assert_array_equal(out.time, t[::10])
    inside = slice(20, -20)  # 0.2 s from either end: the filter's end effects
    assert np.abs(out.force - _band_limited(out.time))[inside].max() < 0.01 * 20.0  # the 80 Hz part: < 1 %
    assert np.abs(record.force[::10] - _band_limited(out.time))[inside].max() > 0.9 * 20.0  # plain subsampling folds it
    assert np.abs(out.floor_acc - 0.1 * np.sin(2 * np.pi * 9.5 * out.time))[inside].max() < 2e-4
    assert np.abs(decimated - np.sin(2 * np.pi * 5.0 * out.time))[inside].max() < 2e-3  # 0.2 % passband ripple
    assert out.mass == MASS and out.source == record.source


@pytest.mark.parametrize("fs, rate, factor", [(1000.0, 100.0, 10), (2000.0, 100.0, 20), (250.0, 100.0, 2),
                                              (150.0, 100.0, 1), (100.0, 100.0, 1), (1000.0, None, 1),
                                              (199.9996, 100.0, 2), (399.98, 100.0, 4), (199.0, 100.0, 1)])
def test_decimation_keeps_the_rate_between_rate_and_twice_it(fs, rate, factor):
    # a phone's measured rate a little under its nominal 200 or 400 Hz (its clock) is decimated as the nominal one;
    # 199 Hz, 0.5 % under, is not
    t = np.arange(0.0, 10.0, 1.0 / fs)
    record = make_record(t, _band_limited(t), MASS)
    out, got, _ = decimate_record(record, rate)
    assert got == factor
    if factor == 1:
        assert out is record
    else:
        assert (1.0 - RATE_SLACK) * rate <= out.fs < 2 * rate


@pytest.mark.parametrize("rate", [0.0, -5.0, float("nan"), "100"])
def test_decimation_rate_must_be_a_positive_number(rate):
    t = np.arange(0.0, 10.0, 0.001)
    with pytest.raises(OptionError, match="rate="):
        decimate_record(make_record(t, _band_limited(t), MASS), rate)


def test_decimation_keeps_white_noise_white():
    # The record-level model assumes white measurement noise and tests its innovations for it
    # (Ljung-Box): a filter that droops below the new Nyquist frequency colours the noise (a
    # Kaiser FIR gave lag-1 to lag-4 autocorrelations of +0.04, -0.03, +0.035, -0.033 here).
    t = np.arange(0.0, 300.0, 0.001)
    noise = np.random.default_rng(np.random.SeedSequence(8)).normal(0.0, 5.0, t.size)
    out, factor, _ = decimate_record(make_record(t, MASS * G + noise, MASS), 100.0)
    x = out.force - out.force.mean()
    lags = np.array([np.dot(x[:-k], x[k:]) / np.dot(x, x) for k in range(1, 6)])
    assert np.abs(lags).max() < 0.02  # sd of one lag's estimate from 30000 samples: 0.006
    assert x.var() == pytest.approx(25.0 / factor, rel=0.03)  # a tenth of the band: a tenth of the power
