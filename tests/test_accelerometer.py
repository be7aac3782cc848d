"""A phone at the waist: reading its record, repairing its clock, finding the vertical.

The records are synthetic with a known vertical COM acceleration ``a_true`` (four
harmonics of a 2.2 Hz bounce), a small horizontal acceleration, a phone tilted and
swaying, per-axis bias, noise, time jitter and dropped samples; every test compares
with that truth or with the same record seen differently (tilted or not, in g or in
m/s^2, written by phyphox or plain).
"""

from types import SimpleNamespace

import numpy as np
import pytest

from smd_statespace.accelerometer import (
    MAX_GAP,
    RATE_RANGE,
    STILL_DURATION,
    read_accelerometer,
    resample_uniform,
    vertical_acceleration,
)
from smd_statespace.accelerometer.record import fill_gaps, unmeasured
from smd_statespace.errors import OptionError, RecordError
from smd_statespace.io import G
from smd_statespace.signals import highpass

FB = 2.2
"""Bouncing frequency of the synthetic records (Hz)."""

HARMONICS = ((3.0, 0.0), (2.0, 0.7), (0.8, 1.9), (0.3, 0.4))
"""(amplitude m/s^2, phase rad) of the harmonics k = 1..4 of FB in the vertical acceleration."""

EDGE = 1.0
"""Seconds left out at either end when comparing with the truth."""


def a_true(t):
    """The known vertical COM acceleration (m/s^2, up positive, zero mean)."""
    t = np.asarray(t, dtype=float)[:, None]
    k = np.arange(1, len(HARMONICS) + 1)
    amplitude, phase = np.array(HARMONICS).T
    return (amplitude * np.sin(2 * np.pi * k * FB * t + phase)).sum(axis=1)


def rotation(axis, angle):
    """Rotation matrices (Rodrigues) about ``axis`` by ``angle`` (rad, scalar or (T,)): shape (T, 3, 3)."""
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    angle = np.atleast_1d(np.asarray(angle, dtype=float))
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle)[:, None, None] * k + (1 - np.cos(angle))[:, None, None] * (k @ k)


def synthetic(duration=20.0, fs=200.0, tilt=30.0, tilt_axis=(1.0, 0.5, 0.0), sway=3.0,
              bias=(0.15, -0.2, 0.1), scale=1.0, noise=0.05, jitter=0.3e-3, drop=0.005, seed=0):
    """A phone record: time stamps (s) and the three axes (m/s^2, with gravity), as a phone delivers them.

    The phone is tilted by ``tilt`` degrees about ``tilt_axis`` and sways by ``sway``
    degrees at 0.1 Hz about the world's x axis; the world's specific force is the
    horizontal acceleration plus ``a_true + g`` upwards. The sensor adds a per-axis
    ``bias`` and white ``noise`` (m/s^2) and multiplies by ``scale``; samples are taken
    at jittered instants (sd ``jitter`` s), stamped exactly, and a fraction ``drop`` is
    lost. The same seed gives the same jitter, drops and noise whatever the geometry.
    """
    rng = np.random.default_rng(seed)
    n = int(round(duration * fs))
    t = np.arange(n) / fs + rng.normal(0.0, jitter, n)
    keep = rng.random(n) >= drop
    keep[[0, -1]] = True
    t = t[keep]
    w = 2 * np.pi * FB
    world = np.column_stack([0.3 * np.sin(w * t + 1.0), 0.2 * np.sin(2 * w * t), a_true(t) + G])
    phone_to_world = rotation((1, 0, 0), np.radians(sway) * np.sin(2 * np.pi * 0.1 * t)) @ rotation(
        tilt_axis, np.radians(tilt))
    acc = np.einsum("tji,tj->ti", phone_to_world, world)  # world -> phone: the transpose
    acc = scale * acc + np.asarray(bias) + noise * rng.normal(size=acc.shape)
    return SimpleNamespace(time=t, acc=acc, n_dropped=int(n - keep.sum()))


def pipeline(time, acc, fs=None):
    """Clock and vertical: (uniform time, a_v, clock info, geometry info)."""
    grid, values, clock = resample_uniform(time, acc, fs)
    a_v, geometry = vertical_acceleration(grid, values)
    return grid, a_v, clock, geometry


def interior(time):
    return (time > time[0] + EDGE) & (time < time[-1] - EDGE)


def relative_rms(error, reference):
    return float(np.sqrt(np.mean(error**2)) / np.sqrt(np.mean(reference**2)))


def harmonic_amplitudes(time, x, f, n=4):
    """Least-squares amplitudes of the harmonics 1..n of ``f`` in ``x`` (with a constant)."""
    k = np.arange(1, n + 1)
    phase = 2 * np.pi * f * np.outer(time, k)
    design = np.column_stack([np.ones_like(time), np.sin(phase), np.cos(phase)])
    coef = np.linalg.lstsq(design, x, rcond=None)[0]
    return np.hypot(coef[1 : n + 1], coef[n + 1 :])


def assert_one_line(excinfo, *fragments):
    message = str(excinfo.value)
    assert "\n" not in message
    for fragment in fragments:
        assert fragment in message, (fragment, message)


# ---------------------------------------------------------------------------
# Recovery of the vertical
# ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "tilt,tilt_axis,expected_tilt",
    [(0.0, (1, 0, 0), 0.0), (30.0, (1, 0.5, 0), 30.0), (100.0, (1, 0.2, 0), 100.0)],
    ids=["flat", "tilted-30", "upright-in-pocket"],
)
def test_recovers_the_vertical_acceleration(tilt, tilt_axis, expected_tilt):
    rec = synthetic(tilt=tilt, tilt_axis=tilt_axis)
    grid, a_v, clock, geometry = pipeline(rec.time, rec.acc)
    inside = interior(grid)
    truth = a_true(grid)
    # the sensor noise alone (0.05 m/s^2 along the vertical) is 1.9 % of a_true's RMS (2.6 m/s^2)
    assert relative_rms(a_v[inside] - truth[inside], truth[inside]) < 0.03
    assert relative_rms(a_v - truth, truth) < 0.03  # the ends too
    assert abs(np.mean(a_v)) < 0.02
    assert geometry["tilt_deg"] == pytest.approx(expected_tilt, abs=2.0)  # the bias tilts it by < 1.2 deg
    assert geometry["direction_change_deg"] == pytest.approx(3.0, abs=0.5)  # the 3 deg sway
    assert geometry["still_start"] == geometry["still_end"] == 0.0
    assert clock["fs_nominal"] == pytest.approx(200.0, rel=1e-3)


def test_tilted_phone_gives_the_same_vertical_as_an_upright_one():
    level = synthetic(tilt=0.0, sway=0.0)
    tilted = synthetic(tilt=30.0, sway=3.0)  # same seed: same jitter, drops and noise
    grid, a_level, _, _ = pipeline(level.time, level.acc)
    grid_t, a_tilted, _, _ = pipeline(tilted.time, tilted.acc)
    np.testing.assert_array_equal(grid, grid_t)
    truth = a_true(grid)
    assert relative_rms(a_tilted - a_level, truth) < 0.03
    # what a wrong vertical would give: the phone's z axis minus g is off by > 10 %
    _, z_axis, _ = resample_uniform(tilted.time, tilted.acc[:, 2])
    assert relative_rms(z_axis - np.median(z_axis) - a_level, truth) > 0.10


def test_bias_does_not_change_the_bouncing_harmonics():
    clean = synthetic(bias=(0.0, 0.0, 0.0))
    biased = synthetic(bias=(-0.2, 0.2, 0.2))  # 0.31 m/s^2 of it along the vertical of the tilted phone
    grid, a_clean, _, _ = pipeline(clean.time, clean.acc)
    _, a_biased, _, info = pipeline(biased.time, biased.acc)
    inside = interior(grid)
    clean_amplitudes = harmonic_amplitudes(grid[inside], a_clean[inside], FB)
    biased_amplitudes = harmonic_amplitudes(grid[inside], a_biased[inside], FB)
    assert biased_amplitudes[0] == pytest.approx(clean_amplitudes[0], rel=1e-3)  # at f_b
    # the higher harmonics too, but for the documented mixing-in of |b_across| / g = 1.6 % of the horizontal
    # acceleration (0.3 and 0.2 m/s^2 at f_b and 2 f_b) through the direction the bias tilts by 0.9 deg
    np.testing.assert_allclose(biased_amplitudes, clean_amplitudes, atol=0.01)
    np.testing.assert_allclose(clean_amplitudes, [amplitude for amplitude, _ in HARMONICS], rtol=0.02)
    # the bias moves the record's gravity but, removed with it, leaves no offset
    assert info["gravity"] - G == pytest.approx(0.31, abs=0.03)  # subtracting 9.81 would leave this offset
    assert abs(np.mean(a_biased)) < 0.02


@pytest.mark.parametrize("scale", [0.97, 1.03])
def test_scale_error_leaves_no_offset(scale):
    rec = synthetic(scale=scale)
    grid, a_v, _, info = pipeline(rec.time, rec.acc)
    assert info["gravity"] == pytest.approx(scale * G, rel=0.01)
    assert abs(np.mean(a_v)) < 0.02  # subtracting 9.81 would leave 0.3 m/s^2
    amplitude = harmonic_amplitudes(grid[interior(grid)], a_v[interior(grid)], FB)[0]
    assert amplitude == pytest.approx(scale * HARMONICS[0][0], rel=0.01)  # documented: not corrected


def test_gains_differing_between_axes_leave_no_slow_drift_as_the_phone_tilts():
    # per-axis gains of +-3 % and a 0.5 m/s^2 bias make |g| depend on the orientation: a 10 deg sway at 0.1 Hz
    # then moves it by ~0.1 m/s^2; subtracting one |g| for the record left that drift in a_v (0.097 m/s^2 rms
    # below 0.5 Hz), enough for the "smooth" variation model to absorb it (issue 44); the tracked |g(t)| does not
    rec = synthetic(duration=30.0, scale=np.array([1.03, 0.97, 1.0]), bias=(0.5, -0.5, 0.3), sway=10.0)
    grid, a_v, _, _ = pipeline(rec.time, rec.acc)
    error = a_v - a_true(grid)
    slow = error - highpass(error, 1.0 / np.diff(grid).mean(), 0.5, 4)
    assert np.sqrt(np.mean(slow**2)) < 0.01  # 0.0043 measured; the sensor noise is 0.05 m/s^2 over all bands
    assert relative_rms(error, a_true(grid)) < 0.03


def test_a_gap_of_the_stamps_does_not_bump_the_vertical_around_it():
    # two bursts of 0.25 s without samples: the line across each is up to 5 m/s^2 off a bouncing record, and
    # the gravity low-pass spreads that over seconds; subtracting the low-passed |g(t)| itself put it into a_v
    # (measured: rms 0.069, largest 0.38 m/s^2 on the measured samples); the orientation's fit leaves the noise
    rec = synthetic(duration=30.0)
    keep = ~((rec.time > 10.0) & (rec.time < 10.25)) & ~((rec.time > 20.1) & (rec.time < 20.35))
    grid, values, clock = resample_uniform(rec.time[keep], rec.acc[keep])
    missing = unmeasured(rec.time[keep], grid, clock["fs_nominal"])
    assert 90 < missing.sum() < 102  # two gaps of 50 samples at 200 Hz
    a_v, _ = vertical_acceleration(grid, values, measured=~missing)
    error = (a_v - a_true(grid))[~missing]
    assert np.sqrt(np.mean(error**2)) < 0.055 and np.abs(error).max() < 0.25  # noise 0.05: 0.050, 0.19 measured


def test_a_gap_is_filled_from_the_cycle_before_not_by_a_straight_line():
    # the samples inside a 0.25 s gap of a bouncing record: the line across is 1.2 m/s^2 off here (up to 5),
    # a period earlier (found from the record) they are what the bounce repeats; the measured samples are kept
    rec = synthetic(duration=20.0, sway=0.0, noise=0.0, jitter=0.0, drop=0.0)
    keep = ~((rec.time > 10.0) & (rec.time < 10.25))
    grid, values, clock = resample_uniform(rec.time[keep], rec.acc[keep])
    missing = unmeasured(rec.time[keep], grid, clock["fs_nominal"])
    filled = fill_gaps(values, missing, clock["fs"])
    np.testing.assert_array_equal(filled[~missing], values[~missing])
    truth = synthetic(duration=20.0, sway=0.0, noise=0.0, jitter=0.0, drop=0.0)
    exact = resample_uniform(truth.time, truth.acc)[1][: grid.size]
    line_error = np.abs(values[missing] - exact[missing]).max()
    fill_error = np.abs(filled[missing] - exact[missing]).max()
    assert line_error > 1.0 and fill_error < 0.05 * line_error, (line_error, fill_error)  # 1.21, 0.041
    assert fill_gaps(values, np.zeros(grid.size, bool), clock["fs"]) is not values  # a copy, untouched
    np.testing.assert_array_equal(fill_gaps(values, np.zeros(grid.size, bool), clock["fs"]), values)


@pytest.mark.parametrize("sign", [1.0, -1.0], ids=["axis-up", "axis-down"])
def test_single_vertical_channel(sign):
    rec = synthetic(tilt=0.0, sway=0.0)
    grid, acc, _ = resample_uniform(rec.time, sign * rec.acc[:, 2])
    a_v, info = vertical_acceleration(grid, acc)
    truth = a_true(grid)
    assert relative_rms(a_v - truth, truth) < 0.03
    assert abs(np.mean(a_v)) < 0.02  # the raw median would leave ~0.7 m/s^2
    assert info["tilt_deg"] is None and info["gravity"] == pytest.approx(G + 0.1, abs=0.02)


def test_still_stretch_at_the_start_is_reported_not_refused():
    rec = synthetic(duration=20.0)
    still = rec.time < 3.0
    quiet = np.array([0.0, 0.0, G]) + np.array([0.15, -0.2, 0.1])
    rec.acc[still] = quiet + 0.02 * np.random.default_rng(5).normal(size=(still.sum(), 3))
    _, _, _, info = pipeline(rec.time, rec.acc)
    assert info["still_start"] == pytest.approx(3.0, abs=0.1)
    assert info["still_end"] == 0.0


# ---------------------------------------------------------------------------
# Clock
# ---------------------------------------------------------------------------


def test_resample_repairs_an_irregular_clock():
    rec = synthetic(duration=10.0, jitter=0.4e-3)
    time, acc = rec.time.copy(), rec.acc.copy()
    # two duplicated stamps (the second with other values), one pair out of order
    time = np.insert(time, [100, 500], time[[100, 500]])
    acc = np.insert(acc, [100, 500], acc[[100, 500]] + 1.0, axis=0)
    time[[800, 801]] = time[[801, 800]]
    acc[[800, 801]] = acc[[801, 800]]
    ramp = 3.0 * time - 1.0  # linear interpolation reproduces a straight line exactly
    grid, values, info = resample_uniform(time, np.column_stack([acc, ramp]))
    assert info["n_duplicates"] == 2
    assert info["n_backwards"] == 1
    assert info["n_dropped"] == rec.n_dropped
    assert info["fs"] == info["fs_nominal"] == pytest.approx(200.0, rel=1e-5)  # the median: 4e-4 off
    assert info["jitter_sd"] == pytest.approx(0.4e-3, rel=0.1)
    assert info["largest_gap"] < MAX_GAP
    np.testing.assert_allclose(np.diff(grid), 1 / info["fs"], rtol=1e-9)
    assert grid[0] == info["start"] == np.min(time) and grid[-1] <= np.max(time)
    np.testing.assert_allclose(values[:, 3], 3.0 * grid - 1.0, atol=1e-9)


def test_samples_taken_on_time_but_stamped_late_or_early_are_read_on_the_regular_clock():
    # a phone that samples on its clock (3 % of the samples dropped) and stamps each sample 1 ms off at random:
    # read at the stamps, every value is read at the wrong instant (0.027 m/s^2 rms here, half the sensor's
    # noise); numbered on the regular clock, the samples are where they were taken. The rate comes out right
    # although the median interval is 1 % long (the dropped samples; the clock fitted from it was 0.9 % off)
    rec = synthetic(duration=30.0, jitter=0.0, drop=0.03, noise=0.0, sway=0.0, seed=5)
    stamps = rec.time + np.random.default_rng(6).normal(0.0, 1e-3, rec.time.size)  # in the file's order
    grid, values, info = resample_uniform(stamps, rec.acc)
    assert info["samples_at"] == "regular clock"
    assert grid[0] == info["start"] == pytest.approx(rec.time[0], abs=1e-4)  # the first stamp is 1 ms off at random
    assert info["fs_nominal"] == pytest.approx(200.0, rel=1e-5)
    assert info["n_dropped"] == rec.n_dropped
    exact = np.column_stack([np.interp(grid, rec.time, rec.acc[:, k]) for k in range(3)])
    at_stamps = np.column_stack([np.interp(grid, np.sort(stamps), rec.acc[np.argsort(stamps), k]) for k in range(3)])
    inside = interior(grid)
    error, stamps_error = (np.sqrt(np.mean((v - exact)[inside] ** 2)) for v in (values, at_stamps))
    assert stamps_error > 0.02 and error < 0.25 * stamps_error, (error, stamps_error)  # 0.0043, 0.0255 measured:
    # 3 of the 180 drops placed a sample off


def test_samples_taken_at_scattered_instants_are_read_at_their_stamps():
    # the other way round: the instants scatter by 1 ms and the stamps are true; read on a regular clock the
    # values would be as wrong as above, read at the stamps they are right
    rec = synthetic(duration=30.0, jitter=1e-3, drop=0.03, noise=0.0, sway=0.0, seed=5)
    grid, values, info = resample_uniform(rec.time, rec.acc)
    assert info["samples_at"] == "stamps"
    order = np.argsort(rec.time)  # 1 ms of scatter at 200 Hz puts a few samples out of order
    exact = np.column_stack([np.interp(grid, rec.time[order], rec.acc[order, k]) for k in range(3)])
    np.testing.assert_allclose(values, exact, atol=1e-9)


def test_a_clock_whose_rate_drifts_slowly_is_not_called_scattered():
    # a phone's intervals 10.046 ms at the start and 10.044 ms at the end (as a real phyphox record of 300 s): the
    # stamps bend up to 5 ms away from one line through the record, but each lies on its own clock; the scatter
    # reported (and named in the phone's warning) is the local one, not the bend (the line's sd: 2.2 ms; the old
    # code reported 2.0 ms)
    steps = np.linspace(10.046e-3, 10.044e-3, 29999)
    time = np.concatenate([[0.0], np.cumsum(steps)])
    acc = np.column_stack([np.sin(2 * np.pi * 2.2 * time), np.zeros(time.size), np.full(time.size, G)])
    _, _, info = resample_uniform(time, acc)
    line = np.polyval(np.polyfit(np.arange(time.size), time, 1), np.arange(time.size))
    assert np.std(time - line) > 1e-3 and info["jitter_sd"] < 1e-5
    assert info["samples_at"] == "stamps"


def test_linear_interpolation_loss_is_the_documented_sinc_squared():
    # a 10 Hz cosine sampled at 50 Hz, read onto a 50.5 Hz grid that drifts across the samples
    t = np.arange(0, 20, 1 / 50)
    grid, values, _ = resample_uniform(t, np.cos(2 * np.pi * 10 * t), fs=50.5)
    amplitude = harmonic_amplitudes(grid, values, 10.0, n=1)[0]
    x = np.pi * 10 / 50
    assert amplitude == pytest.approx((np.sin(x) / x) ** 2, abs=0.005)  # 0.875: 12.5 % lost
    assert amplitude < np.sinc(10 / 50) - 0.05  # ... more than a single sinc (a wrong formula)


def test_given_rate_changes_the_grid_only():
    rec = synthetic(duration=10.0)
    grid, values, info = resample_uniform(rec.time, rec.acc, fs=100)
    assert info["fs"] == 100.0 and info["fs_nominal"] == pytest.approx(200.0, rel=1e-3)
    np.testing.assert_allclose(np.diff(grid), 0.01, rtol=1e-9)
    a_v, _ = vertical_acceleration(grid, values)
    truth = a_true(grid)
    assert relative_rms(a_v - truth, truth) < 0.03


# ---------------------------------------------------------------------------
# Reading files
# ---------------------------------------------------------------------------


def java_e(x):
    """A number as phyphox writes it (Java DecimalFormat "0.000000000E0"): 9.806650000E0, -1.5E-1 style."""
    mantissa, exponent = f"{x:.9E}".split("E")
    return f"{mantissa}E{int(exponent)}"


def write_phyphox(path, time, acc, delimiter=",", decimal=".", absolute=True, names=None):
    """Write a CSV file as phyphox's "Acceleration with g" export does."""
    names = names or ["Time (s)", "Acceleration x (m/s^2)", "Acceleration y (m/s^2)", "Acceleration z (m/s^2)"]
    columns = [time, *acc.T]
    if absolute:
        names = [*names, "Absolute acceleration (m/s^2)"]
        columns.append(np.linalg.norm(acc, axis=1))
    lines = [delimiter.join(f'"{name}"' for name in names)]
    for row in zip(*columns):
        lines.append(delimiter.join(java_e(value).replace(".", decimal) for value in row))
    path.write_text("\n".join(lines) + "\n")
    return path


def write_plain(path, header, time, acc, fmt="{:.10g}"):
    lines = [header] + [",".join(fmt.format(v) for v in (t, *a)) for t, a in zip(time, acc)]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize(
    "delimiter,decimal,absolute",
    [(",", ".", True), (",", ".", False), (";", ".", True), ("\t", ".", True), (";", ",", True), ("\t", ",", False)],
    ids=["comma", "comma-3-columns", "semicolon", "tab", "semicolon-decimal-comma", "tab-decimal-comma"],
)
def test_reads_phyphox_exports(tmp_path, delimiter, decimal, absolute):
    rec = synthetic(duration=4.0)
    path = write_phyphox(tmp_path / "Raw Data.csv", rec.time, rec.acc, delimiter, decimal, absolute)
    assert path.read_text().startswith('"Time (s)"' + delimiter + '"Acceleration x (m/s^2)"')
    record = read_accelerometer(path)
    assert (record.format, record.units_read, record.source) == ("phyphox", "m/s^2", str(path))
    assert record.acc.shape == (rec.time.size, 3)
    np.testing.assert_allclose(record.time, rec.time, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(record.acc, rec.acc, rtol=1e-9)


def test_phyphox_file_gives_the_vertical(tmp_path):
    rec = synthetic()
    record = read_accelerometer(write_phyphox(tmp_path / "phone.csv", rec.time, rec.acc))
    grid, a_v, _, _ = pipeline(record.time, record.acc)
    truth = a_true(grid)
    assert relative_rms(a_v - truth, truth) < 0.03


def test_units_g_and_metres_per_second_squared_agree(tmp_path):
    rec = synthetic(duration=8.0)
    in_ms2 = write_plain(tmp_path / "ms2.csv", "Time,AX,AY,AZ", rec.time, rec.acc)
    in_g = write_plain(tmp_path / "g.csv", "t, ax, ay, az", rec.time, rec.acc / G)
    auto_ms2, auto_g = read_accelerometer(in_ms2), read_accelerometer(in_g)
    assert (auto_ms2.format, auto_ms2.units_read, auto_g.units_read) == ("plain", "m/s^2", "g")
    np.testing.assert_allclose(auto_g.acc, auto_ms2.acc, rtol=1e-8)
    np.testing.assert_allclose(read_accelerometer(in_g, units="g").acc, auto_ms2.acc, rtol=1e-8)
    np.testing.assert_allclose(read_accelerometer(in_ms2, units="m/s^2").acc, rec.acc, rtol=1e-9)
    _, a_ms2, _, _ = pipeline(auto_ms2.time, auto_ms2.acc)
    _, a_g, _, _ = pipeline(auto_g.time, auto_g.acc)
    np.testing.assert_allclose(a_g, a_ms2, atol=1e-6)


@pytest.mark.parametrize("header,sign", [("time,acc", -1.0), ("TIME,az", 1.0)])
def test_reads_a_single_vertical_channel(tmp_path, header, sign):
    rec = synthetic(duration=8.0, tilt=0.0, sway=0.0)
    record = read_accelerometer(write_plain(tmp_path / "v.csv", header, rec.time, sign * rec.acc[:, 2:] / G),
                                units="auto")
    assert (record.format, record.units_read, record.acc.shape) == ("vertical", "g", (rec.time.size, 1))
    grid, a_v, _, _ = pipeline(record.time, record.acc)
    truth = a_true(grid)
    assert relative_rms(a_v - truth, truth) < 0.03


@pytest.mark.parametrize("names,scale,extra", [
    (['"Time (s)"', '"X (m/s^2)"', '"Y (m/s^2)"', '"Z (m/s^2)"'], 1.0, ()),  # phyphox's export of a sensor
    (["epoc (ms)", "timestamp (-0500)", "elapsed (s)", "x-axis (g)", "y-axis (g)", "z-axis (g)"], G, (
        lambda t: f"{1573761902571 + 1000 * t:.0f}", lambda t: "2019-11-14T15:05:02.571")),  # MetaWear's
    (["Time (ms)", "Accel_X (m/s^2)", "Accel_Y (m/s^2)", "Accel_Z (m/s^2)"], 1.0, ()),
], ids=["phyphox-sensor", "metawear", "milliseconds"])
def test_reads_headers_that_name_the_axes_and_their_units(tmp_path, names, scale, extra):
    # real exports seen in public repositories: the time and three axes named with their units, other columns
    # (an epoch, a date) not read; the units are the header's (g here read as g although --units says auto)
    rec = synthetic(duration=4.0)
    time = rec.time * (1000.0 if "ms" in names[0] and "epoc" not in names[0] else 1.0)
    lines = [",".join(names)] + [",".join([*(f(t) for f in extra), f"{tt:.9g}", *(f"{v:.9g}" for v in a / scale)])
                                 for t, tt, a in zip(rec.time, time, rec.acc)]
    path = tmp_path / "export.csv"
    path.write_text("\n".join(lines) + "\n")
    record = read_accelerometer(path)
    assert (record.format, record.units_read) == ("labelled", "g" if scale == G else "m/s^2")
    np.testing.assert_allclose(record.time, rec.time, rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(record.acc, rec.acc, rtol=1e-7)


def test_reads_sensor_loggers_export_with_its_axes_in_reverse(tmp_path):
    # the Sensor Logger app: an epoch in ns without a unit ("time"), seconds_elapsed, and the axes z, y, x named
    # ACCELEROMETER Z (m/s²); its "Accelerometer" files seen in public repositories had no gravity and are refused
    rec = synthetic(duration=4.0)
    lines = ["time,seconds_elapsed,ACCELEROMETER Z (m/s²),ACCELEROMETER Y (m/s²),ACCELEROMETER X (m/s²)"] + [
        f"{1700000000000000000 + int(t * 1e9)},{t:.9g},{a[2]:.9g},{a[1]:.9g},{a[0]:.9g}"
        for t, a in zip(rec.time, rec.acc)]
    path = tmp_path / "Accelerometer.csv"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    record = read_accelerometer(path)
    assert (record.format, record.units_read) == ("labelled", "m/s^2")
    np.testing.assert_allclose(record.time, rec.time, rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(record.acc, rec.acc, rtol=1e-7)
    linear = tmp_path / "linear.csv"
    bounce = 2.0 * np.sin(2 * np.pi * FB * rec.time)  # the body's acceleration alone, without gravity
    rows = [f"{int(t * 1e9)},{t:.9g},{z:.9g},0.1,0.0" for t, z in zip(rec.time, bounce)]
    linear.write_text("\n".join([lines[0]] + rows) + "\n", encoding="utf-8")
    with pytest.raises(RecordError, match="never see gravity"):
        read_accelerometer(linear)


def test_reads_sensorlogs_export_and_physics_toolboxs_g_force_meter_with_its_clock_times(tmp_path):
    """Two common phone apps: SensorLog (iOS; accelerometerAccelerationX(G), its time since the phone's reboot, the
    gravity-free motionUserAcceleration columns beside, not read) and Physics Toolbox Sensor Suite's g-force meter
    (time,gFx,gFy,gFz,TgF in g; its iPhone export writes the time as a clock, MM:SS.fff, with semicolons; its
    multi-record export adds wx, Bx, ... columns)."""
    rec = synthetic(duration=4.0)
    g = rec.acc / G
    names = ["loggingTime(txt)", "loggingSample(N)", "accelerometerTimestamp_sinceReboot(s)",
             "accelerometerAccelerationX(G)", "accelerometerAccelerationY(G)", "accelerometerAccelerationZ(G)",
             "motionUserAccelerationX(G)", "motionUserAccelerationY(G)", "motionUserAccelerationZ(G)"]
    rows = [f"2026-12-01 10:00:{t:06.3f} +0000,{k},{62608 + t:.9f},{a[0]:.9g},{a[1]:.9g},{a[2]:.9g},0.01,0.02,0.03"
            for k, (t, a) in enumerate(zip(rec.time, g))]
    (tmp_path / "sensorlog.csv").write_text("\n".join([",".join(names), *rows]) + "\n")
    record = read_accelerometer(tmp_path / "sensorlog.csv")
    assert (record.format, record.units_read) == ("labelled", "g")
    np.testing.assert_allclose(record.time - record.time[0], rec.time - rec.time[0], atol=1e-8)
    np.testing.assert_allclose(record.acc, rec.acc, rtol=1e-7)
    clock = [f"{int(t // 60):02d}:{t % 60:09.6f}" for t in rec.time]  # microseconds, so that the test is exact
    rows = [f"{c};{a[0]:.9g};{a[1]:.9g};{a[2]:.9g};{np.linalg.norm(a):.9g}" for c, a in zip(clock, g)]
    (tmp_path / "ptb.csv").write_text("\n".join(["time;gFx;gFy;gFz;gFTotal", *rows]) + "\n")
    record = read_accelerometer(tmp_path / "ptb.csv")
    assert (record.format, record.units_read) == ("physics toolbox", "g")
    np.testing.assert_allclose(record.time, rec.time, atol=1e-6)
    np.testing.assert_allclose(record.acc, rec.acc, rtol=1e-7)
    millis = np.round(1000 * rec.time).astype(int)
    hours = [f"10:{59 + m // 60000:02d}:{m // 1000 % 60:02d}:{m % 1000:03d}" for m in millis]
    rows = [f"{h},{a[0]:.9g},{a[1]:.9g},{a[2]:.9g},0,0,0,1,2,3" for h, a in zip(hours, g)]
    (tmp_path / "multi.csv").write_text("\n".join(["time,gFx,gFy,gFz,wx,wy,wz,Bx,By,Bz", *rows]) + "\n")
    multi = read_accelerometer(tmp_path / "multi.csv")  # HH:MM:SS:fff, milliseconds after a colon
    np.testing.assert_allclose(multi.time - multi.time[0], rec.time - rec.time[0], atol=6e-4)
    rows[5] = "later," + rows[5].split(",", 1)[1]
    (tmp_path / "multi.csv").write_text("\n".join(["time,gFx,gFy,gFz,wx,wy,wz,Bx,By,Bz", *rows]) + "\n")
    with pytest.raises(RecordError, match="column 'time' row 6 holds 'later'; its first row is a clock time"):
        read_accelerometer(tmp_path / "multi.csv")
    bounce = 0.2 * np.sin(2 * np.pi * FB * rec.time)  # its linear accelerometer: no gravity, said so
    rows = [f"{t:.4f};0.01;{z:.5f};0.02;{abs(z):.5f}" for t, z in zip(rec.time, bounce)]
    (tmp_path / "linear.csv").write_text("\n".join(["time;ax;ay;az;aT", *rows]) + "\n")
    with pytest.raises(RecordError, match="never see gravity .*: a linear-acceleration export"):
        read_accelerometer(tmp_path / "linear.csv")


@pytest.mark.parametrize("header", ["Time (s),X (rad/s),Y (rad/s),Z (rad/s)", "Time (s),X (m/s^2),Y (m/s^2)",
                                    "Time (s),X (m/s^2),Y (g),Z (m/s^2)"],
                         ids=["gyroscope", "two-axes", "mixed-units"])
def test_headers_that_name_no_acceleration_of_three_axes_are_refused(tmp_path, header):
    rec = synthetic(duration=2.0)
    width = header.count(",")
    path = write_plain(tmp_path / "other.csv", header, rec.time, rec.acc[:, :width])
    with pytest.raises(RecordError) as excinfo:
        read_accelerometer(path)
    assert_one_line(excinfo, str(path), "is not an accelerometer record", "accepted headers")


# ---------------------------------------------------------------------------
# Bad input: one line naming the file, column or option
# ---------------------------------------------------------------------------


def test_unknown_header(tmp_path):
    rec = synthetic(duration=2.0)
    path = write_plain(tmp_path / "odd.csv", "time,x,y,z", rec.time, rec.acc)
    with pytest.raises(RecordError) as excinfo:
        read_accelerometer(path)
    assert_one_line(excinfo, str(path), "'time,x,y,z'", "accepted headers", "time,ax,ay,az", "time,acc",
                    '"Acceleration x (m/s^2)"')


@pytest.mark.parametrize("names", [None, ["Time (s)", "Linear Acceleration x (m/s^2)",
                                          "Linear Acceleration y (m/s^2)", "Linear Acceleration z (m/s^2)"]],
                         ids=["same-header", "linear-header"])
def test_linear_acceleration_export_is_refused(tmp_path, names):
    rec = synthetic(duration=4.0, tilt=0.0, sway=0.0, bias=(0, 0, 0))
    linear = rec.acc - np.array([0.0, 0.0, G])
    path = write_phyphox(tmp_path / "linear.csv", rec.time, linear, names=names)
    with pytest.raises(RecordError) as excinfo:
        read_accelerometer(path)
    assert_one_line(excinfo, str(path), "linear-acceleration export", "'Acceleration with g'")
    if names is None:
        assert "never see gravity (|mean a| 0.0" in str(excinfo.value)


def test_linear_acceleration_in_a_plain_file_is_refused(tmp_path):
    rec = synthetic(duration=4.0, tilt=0.0, sway=0.0, bias=(0, 0, 0))
    path = write_plain(tmp_path / "lin.csv", "time,ax,ay,az", rec.time, rec.acc - np.array([0.0, 0.0, G]))
    for units in ("auto", "m/s^2"):
        with pytest.raises(RecordError) as excinfo:
            read_accelerometer(path, units=units)
        assert_one_line(excinfo, str(path), "never see gravity")


@pytest.mark.parametrize(
    "header,row,column,value",
    [("time,ax,ay,az", 5, 2, "abc"), ("time,ax,ay,az", 1, 0, ""), ("time,acc", 7, 1, "nan")],
)
def test_non_numeric_cell(tmp_path, header, row, column, value):
    rec = synthetic(duration=2.0)
    width = header.count(",") + 1
    lines = [header] + [",".join(f"{v:.8g}" for v in (t, *a[: width - 1])) for t, a in zip(rec.time, rec.acc)]
    cells = lines[row].split(",")
    cells[column] = value
    lines[row] = ",".join(cells)
    path = tmp_path / "bad.csv"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(RecordError) as excinfo:
        read_accelerometer(path)
    assert_one_line(excinfo, str(path), f"column '{header.split(',')[column]}' row {row}")


def test_non_numeric_cell_with_decimal_commas(tmp_path):
    rec = synthetic(duration=2.0)
    path = write_phyphox(tmp_path / "de.csv", rec.time, rec.acc, ";", ",")
    lines = path.read_text().splitlines()
    lines[3] = lines[3].replace(";", ";x", 1)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(RecordError) as excinfo:
        read_accelerometer(path)
    assert_one_line(excinfo, str(path), "column 'Acceleration x (m/s^2)' row 3", "decimal commas read as points")


def test_decimal_commas_with_comma_delimiter(tmp_path):
    path = tmp_path / "comma.csv"
    path.write_text("time,ax,ay,az\n0,0,0,1,2,9,8\n")
    with pytest.raises(RecordError) as excinfo:
        read_accelerometer(path)
    assert_one_line(excinfo, str(path), "data row 1 has 7 fields, the header has 4", "semicolon or tab")


def test_units(tmp_path):
    rec = synthetic(duration=2.0)
    path = write_plain(tmp_path / "half.csv", "time,ax,ay,az", rec.time, rec.acc * 0.4)  # |mean a| ~ 3.9
    with pytest.raises(RecordError) as excinfo:
        read_accelerometer(path)
    assert_one_line(excinfo, str(path), "neither about 1 (g) nor about 9.81 (m/s^2)", "units='g'")
    with pytest.raises(RecordError) as excinfo:
        read_accelerometer(write_plain(tmp_path / "g.csv", "time,ax,ay,az", rec.time, rec.acc / G), units="m/s^2")
    assert_one_line(excinfo, "g.csv", "g with units='m/s^2'", "looks like g: give units='g'")
    with pytest.raises(OptionError) as excinfo:
        read_accelerometer(path, units="G's")
    assert_one_line(excinfo, "units=\"G's\"", "auto, m/s^2, g")
    with pytest.raises(OptionError) as excinfo:
        read_accelerometer(write_phyphox(tmp_path / "p.csv", rec.time, rec.acc), units="g")
    assert_one_line(excinfo, "p.csv", "units='g', but the header says m/s^2")


def test_missing_and_empty_files(tmp_path):
    with pytest.raises(RecordError) as excinfo:
        read_accelerometer(tmp_path / "none.csv")
    assert_one_line(excinfo, "none.csv: no such file")
    (tmp_path / "empty.csv").write_text("")
    with pytest.raises(RecordError) as excinfo:
        read_accelerometer(tmp_path / "empty.csv")
    assert_one_line(excinfo, "empty.csv: file is empty")
    (tmp_path / "space.csv").write_text("time ax ay az\n0 0 0 9.8\n")
    with pytest.raises(RecordError) as excinfo:
        read_accelerometer(tmp_path / "space.csv")
    assert_one_line(excinfo, "space.csv", "space-separated", "commas, semicolons or tabs")


def test_long_gap_is_refused():
    rec = synthetic(duration=10.0)
    gap = (rec.time > 6.0) & (rec.time < 6.5)
    with pytest.raises(RecordError) as excinfo:
        resample_uniform(rec.time[~gap], rec.acc[~gap], source="phone.csv")
    assert_one_line(excinfo, "phone.csv", "no samples for 0.5", "after t = 6", f"longer than {MAX_GAP:g} s")
    grid, _, info = resample_uniform(rec.time[~gap], rec.acc[~gap], max_gap=0.6)  # allowed when asked
    assert info["largest_gap"] == pytest.approx(0.5, abs=0.01)
    assert info["largest_gap_at"] == pytest.approx(6.0, abs=0.01)


def test_clock_reset_is_refused():
    rec = synthetic(duration=6.0)
    time = np.concatenate([rec.time[:600], rec.time[600:] - 2.5])
    with pytest.raises(RecordError) as excinfo:
        resample_uniform(time, rec.acc, source="phone.csv")
    assert_one_line(excinfo, "phone.csv", "time jumps back by 2.49", "row 601")


def test_a_clock_that_runs_backwards_or_repeats_is_refused():
    rec = synthetic(duration=6.0)
    with pytest.raises(RecordError) as excinfo:
        resample_uniform(rec.time[-1] - rec.time, rec.acc, source="phone.csv")  # counts down
    assert_one_line(excinfo, "phone.csv", "time runs backwards", f"{rec.time.size - 1} of {rec.time.size - 1} steps")
    pairs = rec.time.copy()
    pairs[1::2] = pairs[0::2][: pairs[1::2].size]  # every stamp twice: a clock coarser than the samples
    with pytest.raises(RecordError) as excinfo:
        resample_uniform(pairs, rec.acc, source="phone.csv")
    assert_one_line(excinfo, "phone.csv", "time stamps repeat", "50 %", "stuck or coarser")
    # a phone's few duplicates (1 %) are merged, not refused
    few = rec.time.copy()
    few[1:-1:100] = few[0:-2:100]
    _, _, info = resample_uniform(few, rec.acc)
    assert info["n_duplicates"] == few[1:-1:100].size


@pytest.mark.parametrize("fs", [20.0, 1000.0])
def test_record_rate_out_of_range(fs):
    rec = synthetic(duration=6.0, fs=fs, jitter=0.0, drop=0.0)
    with pytest.raises(RecordError) as excinfo:
        resample_uniform(rec.time, rec.acc, source="phone.csv")
    assert_one_line(excinfo, "phone.csv", f"sampled at {fs:g} Hz", f"{RATE_RANGE[0]:g}-{RATE_RANGE[1]:g} Hz")


@pytest.mark.parametrize("fs", [50.0, 500.0])
def test_rates_at_the_ends_of_the_range_are_accepted(fs):
    # the median interval of this jittered phone at 50 Hz gives 49.97 Hz: accepted (RATE_TOLERANCE)
    rec = synthetic(duration=20.0, fs=fs)
    grid, a_v, clock, _ = pipeline(rec.time, rec.acc)
    assert clock["fs_nominal"] == pytest.approx(fs, rel=1e-4)
    assert clock["n_dropped"] == rec.n_dropped
    truth = a_true(grid)
    assert relative_rms(a_v - truth, truth) < 0.03


@pytest.mark.parametrize("fs", [1000, 10.0, float("nan"), "200", True])
def test_rate_option_out_of_range(fs):
    rec = synthetic(duration=2.0)
    with pytest.raises(OptionError) as excinfo:
        resample_uniform(rec.time, rec.acc, fs=fs)
    assert_one_line(excinfo, f"fs={fs!r}", "from 50 to 500")


def test_a_phone_put_down_halfway_is_reported_not_refused():
    """A still stretch between movements (the phone put down, or worn by a person standing between handling and
    bouncing) is reported in ``info["still"]`` for the front end, which fits the longest bout (until 2026-11-28 it
    was refused, and with it every phone record picked up before a standing start)."""
    rec = synthetic(duration=24.0)
    down = (rec.time >= 8.0) & (rec.time < 16.0)
    on_table = np.array([0.15, -0.2, G + 0.1])  # flat, screen up, with the sensor's bias
    rec.acc[down] = on_table + 0.05 * np.random.default_rng(3).normal(size=(down.sum(), 3))
    grid, acc, _ = resample_uniform(rec.time, rec.acc)
    _, info = vertical_acceleration(grid, acc, source="phone.csv")
    assert len(info["still"]) == 1
    assert info["still"][0] == pytest.approx([8.0, 16.0], abs=0.05)
    assert info["still_start"] == info["still_end"] == 0.0
    # shorter than STILL_DURATION: not a still stretch
    rec = synthetic(duration=24.0)
    pause = (rec.time >= 8.0) & (rec.time < 8.0 + 0.8 * STILL_DURATION)
    rec.acc[pause] = on_table
    grid, acc, _ = resample_uniform(rec.time, rec.acc)
    _, info = vertical_acceleration(grid, acc)
    assert info["still_start"] == info["still_end"] == 0.0 and info["still"] == []


def test_vertical_needs_a_uniform_record_in_metres_per_second_squared():
    rec = synthetic(duration=6.0)
    with pytest.raises(RecordError) as excinfo:
        vertical_acceleration(rec.time, rec.acc, source="phone.csv")
    assert_one_line(excinfo, "phone.csv", "time is not uniform", "resample_uniform first")
    grid, acc, _ = resample_uniform(rec.time, rec.acc)
    with pytest.raises(RecordError) as excinfo:
        vertical_acceleration(grid, acc / G, source="phone.csv")
    assert_one_line(excinfo, "phone.csv", "gravity magnitude 0.99", "m/s^2 and include gravity")
    with pytest.raises(RecordError) as excinfo:
        vertical_acceleration(grid[:400], acc[:400], source="phone.csv")
    assert_one_line(excinfo, "phone.csv", "lasts 1.99 s", "at least 3.33 s")
    with pytest.raises(OptionError) as excinfo:
        vertical_acceleration(grid, acc, cutoff=1.5)
    assert_one_line(excinfo, "cutoff=1.5", "(0, 0.6] Hz")
    with pytest.raises(RecordError) as excinfo:
        vertical_acceleration(grid, acc[:, :2], source="phone.csv")
    assert_one_line(excinfo, "phone.csv", "2 columns")
