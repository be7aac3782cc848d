"""Lab force-plate records (smd_statespace.simulation.lab): standing, ramps, a tiring bout, hum, drift, noise.

The bouncing part is checked against Eq. 2 solved here, independently, for the force the module's docstring
describes (raised-cosine ramps, linear tiring and slowing, f_h and xi_h drifting or stepping); the standing
parts against the body weight plus the drift; the hum against the record's spectrum.
"""

import json

import numpy as np
import pytest
from scipy import integrate
from scipy.interpolate import CubicSpline

from smd_statespace.cli.main import main
from smd_statespace.errors import OptionError
from smd_statespace.io import G, read_record
from smd_statespace.simulation import (LAB_RANGES, LabRanges, draw_lab_settings, simulate_lab_record,
                                       simulate_typical_lab_record)

QUIET = dict(sway=0.0, hum=(), drift=0.0, noise=0.0)
SHORT = dict(stand_before=1.5, stand_after=1.5, bout=6.0, fs=500.0)


def raised(x):
    """The documented ramp: 0.5 (1 - cos(pi x)), x clipped to [0, 1]."""
    return 0.5 * (1.0 - np.cos(np.pi * np.clip(x, 0.0, 1.0)))


def oracle(truth, t0, t):
    """``(g F(t), f_h(t), xi_h(t))`` of the module docstring, written out here from the truth alone."""
    span = truth["span"]
    on, full, down, off = (span[k] for k in ("bouncing_start_s", "full_start_s", "full_end_s", "bouncing_end_s"))
    length = down - full
    progress = np.clip((t - full) / length, 0.0, 1.0)
    envelope = raised((t - on) / (full - on)) * raised((off - t) / (off - down))
    x = np.clip(t - full, 0.0, length)
    tau = t - truth["slow"] * (x**2 / (2 * length) + np.maximum(t - down, 0.0))  # the person's slowing clock
    theta = 2 * np.pi * truth["f_b_start"] * (tau - t0)
    force = sum(blf * np.cos(i * theta - psi)
                for i, (blf, psi) in enumerate(zip(truth["blf_start"], truth["phases"]), start=1))
    change = truth["change"]
    weight = progress if change["kind"] == "drift" else (t >= (change["time_s"] or np.inf)) * 1.0
    f_h = truth["f_h_start"] + weight * (truth["f_h_end"] - truth["f_h_start"])
    xi_h = truth["xi_h_start"] + weight * (truth["xi_h_end"] - truth["xi_h_start"])
    return G * envelope * (1 - truth["tire"] * progress) * force, f_h, xi_h


@pytest.mark.parametrize("person", [dict(tire=0.25, slow=0.08, f_h_change=0.14),
                                    dict(tire=0.1, change="step", xi_h_change=0.5, f_h_change=-0.1),
                                    dict(tire=0.1, f_h_change=0.14, effects={"cubic_stiffness": {"beta_3": 1500.0}})])
def test_the_bouncing_part_is_eq2_under_the_enveloped_tiring_force(person):
    """Eq. 2 written out here from the truth alone (with a cubic spring's ``-w_h^2 beta_3 u^3``, at the f_h of
    the moment, where the record has one), integrated apart: the record is its GRF (Eq. 3)."""
    lab = simulate_lab_record(fb_variation=0.0, coef_variation=0.0, seed=4, **QUIET, **SHORT, **person)
    truth, time, force = lab.truth, lab.record.time, lab.record.force
    t0 = lab.cycles["t_start"].iloc[0]  # no variation: one phase origin, in the standing part (tau = t there)
    on = truth["span"]["bouncing_start_s"]
    beta = truth["effects"].get("cubic_stiffness", {}).get("beta_3", 0.0)
    assert beta == (1500.0 if "effects" in person else 0.0)

    def eq2(t, x):
        force_g, f_h, xi_h = oracle(truth, t0, t)
        w = 2 * np.pi * f_h
        return [x[1], -w**2 * (x[0] + beta * x[0] ** 3) - 2 * xi_h * w * x[1] + force_g]

    after = time >= on
    exact = integrate.solve_ivp(eq2, (on, time[-1]), [0.0, 0.0], t_eval=time[after], method="DOP853", rtol=1e-11,
                                atol=1e-13)
    force_g, f_h, xi_h = oracle(truth, t0, time[after])
    w = 2 * np.pi * f_h
    u_ddot = -w**2 * (exact.y[0] + beta * exact.y[0] ** 3) - 2 * xi_h * w * exact.y[1] + force_g
    weight = truth["mass"] * G
    assert np.abs(force[after] - truth["mass"] * (G + u_ddot)).max() < 1e-6 * weight  # Eq. 3
    assert np.all(force[~after] == weight)  # standing: the person at rest
    assert np.ptp(force) > 0.5 * weight  # and it really bounced
    assert np.allclose(lab.states["f_h"][after], f_h) and np.allclose(lab.states["xi_h"][after], xi_h)


def test_the_smooth_variation_is_integrated_through_the_lab_clock():
    lab = simulate_lab_record(variation="smooth", fb_variation=0.0, tire=0.2, slow=0.1, f_h_change=0.2, seed=11,
                              **QUIET,
                              **dict(SHORT, fs=2000.0))
    states, truth = lab.states, lab.truth
    on = truth["span"]["bouncing_start_s"]
    time = states["time"].to_numpy()
    force = CubicSpline(time, states["force_bio"].to_numpy())  # the force it reports, smooth: a spline holds it

    def eq2(t, x):
        w = 2 * np.pi * np.interp(t, time, states["f_h"].to_numpy())
        return [x[1], -w**2 * x[0] - 2 * truth["xi_h_start"] * w * x[1] + force(t)]

    after = time >= on
    exact = integrate.solve_ivp(eq2, (on, time[-1]), [0.0, 0.0], t_eval=time[after], method="DOP853", rtol=1e-10,
                                atol=1e-12)
    u = states["u"].to_numpy()[after]
    assert np.abs(u - exact.y[0]).max() < 1e-5 * np.abs(u).max()
    cycles = lab.cycles[(lab.cycles["t_start"] > truth["span"]["full_start_s"])
                        & (lab.cycles["t_end"] < truth["span"]["full_end_s"])]
    rate = np.polyfit(cycles["t_start"], cycles["f_b"], 1)[0] * truth["span"]["bout_s"] / truth["f_b_start"]
    assert rate == pytest.approx(-truth["slow"], abs=0.005)  # f_b slows by 10 % over the bout
    level = np.polyfit(0.5 * (cycles["t_start"] + cycles["t_end"]), cycles["scale"], 1)[0] * truth["span"]["bout_s"]
    assert level == pytest.approx(-truth["tire"], abs=1e-6)  # the BLFs' factor falls by `tire`


def test_standing_is_body_weight_plus_drift_and_the_person_comes_to_rest():
    lab = simulate_lab_record(sway=0.0, hum=(8.0, 0.0, 3.0), drift=25.0, noise=1.5, seed=21, **SHORT)
    truth, states, time, force = lab.truth, lab.states, lab.record.time, lab.record.force
    span, fs = truth["span"], truth["fs"]
    drift = states["drift"].to_numpy()
    for lo, hi in ((0.0, span["bouncing_start_s"]), (span["bouncing_end_s"] + 1.0, time[-1])):
        n = int((hi - lo) * 50) * int(fs / 50)  # whole cycles of the 50 Hz hum
        window = slice(int(np.ceil(lo * fs)), int(np.ceil(lo * fs)) + n)
        expected = truth["mass"] * G + drift[window].mean()
        assert force[window].mean() == pytest.approx(expected, abs=4 * 1.5 / np.sqrt(n))
    assert np.abs(states["u_ddot"][time > span["bouncing_end_s"] + 1.0]).max() < 1e-2  # at rest again
    assert drift[0] == 0 and np.abs(drift).max() == pytest.approx(25.0)
    cubic = np.polyval(np.polyfit(time, drift, 3), time)
    assert truth["drift"]["end_n"] == drift[-1] and np.abs(drift - cubic).max() < 1e-9  # a slow, smooth path
    residual = force - truth["mass"] * (G + states["u_ddot"]) - drift - states["hum"]
    assert np.std(residual) == pytest.approx(1.5, rel=0.05)


@pytest.mark.parametrize("shape", ["settling", "walk", "steps"])
def test_the_zero_drifts_in_other_shapes_than_a_cubic_and_leaves_the_person_alone(shape):
    """A settling zero (1 - exp(-t / tau), tau 5-15 s), a wandering one (a walk smoothed over 2 s) and one that
    steps 2-4 times: 0 at the start, reaching the size given, not a cubic, and the person's force unchanged."""
    cubic = simulate_lab_record(drift=20.0, seed=4, **SHORT)
    lab = simulate_lab_record(drift=20.0, drift_shape=shape, seed=4, **SHORT)
    drift, time = lab.states["drift"].to_numpy(), lab.record.time
    assert drift[0] == 0 and np.abs(drift).max() == pytest.approx(20.0) and lab.truth["drift"]["shape"] == shape
    if shape != "settling":  # (over 11 s a settling zero is close to a cubic)
        assert np.abs(drift - np.polyval(np.polyfit(time, drift, 3), time)).max() > 1.0  # not a cubic
    assert np.array_equal(lab.states["u_ddot"], cubic.states["u_ddot"])
    jumps = np.abs(np.diff(drift))
    if shape == "steps":
        assert 2 <= np.count_nonzero(jumps > 1e-9) <= 4
    else:  # continuous: no sample moves by more than a few hundredths of the size
        assert jumps.max() < 0.05 * 20.0
    if shape == "settling":
        rest = drift[time > 0.8 * time[-1]]
        assert np.ptp(rest) < 0.4 * 20.0 and np.all(np.sign(drift[1:]) == np.sign(drift[-1]))
    with pytest.raises(OptionError, match="drift_shape must be one of 'cubic', 'settling', 'walk', 'steps'"):
        simulate_lab_record(drift_shape="sine", seed=4, **SHORT)


def test_the_hum_is_read_back_from_the_spectrum_and_the_sway_is_slow():
    lab = simulate_lab_record(hum=(6.0, 0.0, 2.5), hum_frequency=50, sway=3.0, noise=1.0, seed=5, **SHORT)
    fs, force = lab.truth["fs"], lab.record.force
    n = int(len(force) // fs * fs)  # whole seconds: 50 Hz and its harmonics fall on bins
    amplitude = 2 * np.abs(np.fft.rfft(force[:n])) / n
    frequency = np.fft.rfftfreq(n, 1 / fs)
    for order, expected in enumerate((6.0, 0.0, 2.5), start=1):
        assert amplitude[np.argmin(abs(frequency - 50 * order))] == pytest.approx(expected, abs=0.15)
    assert lab.truth["hum"]["amplitudes_n"] == [6.0, 0.0, 2.5]
    sway, time = lab.states["sway"].to_numpy(), lab.record.time
    standing = time < lab.truth["span"]["bouncing_start_s"]
    told = lab.truth["sway"]
    amplitudes, frequencies = np.array(told["amplitudes_n"]), np.array(told["frequencies_hz"])
    path = amplitudes @ np.cos(2 * np.pi * np.outer(frequencies, time) + np.array(told["phases_rad"])[:, None])
    assert np.allclose(sway[standing], path[standing])  # the truth describes the sway
    assert np.sqrt(0.5 * np.sum(amplitudes**2)) == pytest.approx(3.0) and frequencies.max() < 1.5
    span = lab.truth["span"]
    assert np.all(sway[(time >= span["full_start_s"]) & (time <= span["full_end_s"])] == 0)  # none in the bout


def test_the_same_seed_gives_the_same_record_and_the_streams_are_independent():
    one = simulate_lab_record(seed=8, **SHORT)
    assert np.array_equal(one.record.force, simulate_lab_record(seed=8, **SHORT).record.force)
    assert not np.array_equal(one.record.force, simulate_lab_record(seed=9, **SHORT).record.force)
    quiet = simulate_lab_record(seed=8, hum=(0.0,), drift=3.0, **SHORT)  # other extras, the same person
    assert np.array_equal(one.states["u_ddot"], quiet.states["u_ddot"])
    assert one.truth["seed"] == 8


def test_the_truth_holds_the_change_the_span_and_eq17_18(tmp_path):
    lab = simulate_lab_record(change="step", f_h_change=0.1, xi_h_change=-0.2, tire=0.3, slow=0.05, seed=2,
                              **SHORT)
    truth = lab.truth
    span = truth["span"]
    assert span["full_start_s"] - span["bouncing_start_s"] == pytest.approx(2.0 / 2.0)  # 2 cycles at 2 Hz
    assert span["bouncing_end_s"] - span["full_end_s"] == pytest.approx(2.0 / (2.0 * 0.95))
    assert truth["change"] == {"kind": "step", "f_h": 0.1, "xi_h": -0.2,
                               "time_s": pytest.approx(span["full_start_s"] + 3.0)}
    assert truth["f_h"] == pytest.approx(2.5 * 1.05) and truth["xi_h"] == pytest.approx(0.3 * 0.9)  # bout means
    assert truth["K_h"] == pytest.approx(truth["mass"] * (2 * np.pi * truth["f_h"]) ** 2)  # Eq. 17
    assert truth["C_h"] == pytest.approx(2 * truth["xi_h"] * truth["mass"] * 2 * np.pi * truth["f_h"])  # Eq. 18
    assert truth["blf_end"] == pytest.approx(np.array(truth["blf_start"]) * 0.7)
    csv_path, truth_path = lab.write(tmp_path / "lab.csv")
    assert np.allclose(read_record(csv_path, mass=truth["mass"]).force, lab.record.force, atol=1e-6)
    assert json.loads(truth_path.read_text())["span"] == span


def test_typical_settings_cover_the_ranges_and_can_hold_combinations_out():
    drawn = [draw_lab_settings(seed) for seed in range(40)]
    assert {s["variation"] for s in drawn} == {"jumps", "smooth"}
    assert {s["change"] for s in drawn} == {"drift", "step"} and any(s["f_h_change"] == 0 for s in drawn)
    for s in drawn:
        assert LAB_RANGES.mass[0] <= s["mass"] <= LAB_RANGES.mass[1] and s["fs"] in LAB_RANGES.fs
        assert LAB_RANGES.bout[0] <= s["bout"] <= LAB_RANGES.bout[1]
    steps = LabRanges(change=("step",), variation=("smooth",))
    held = [draw_lab_settings(seed, steps, f_b=2.0) for seed in range(10)]
    assert all(s["change"] == "step" and s["variation"] == "smooth" and s["f_b"] == 2.0 for s in held)
    assert draw_lab_settings(3, mass=80.0)["f_h"] == draw_lab_settings(3)["f_h"]  # fixing one moves no other
    shapes = [draw_lab_settings(seed, LabRanges(drift_shape=("settling", "walk"))) for seed in range(10)]
    assert {s["drift_shape"] for s in shapes} == {"settling", "walk"} and {s["drift_shape"] for s in drawn} == {"cubic"}
    assert [s["f_h"] for s in shapes] == [s["f_h"] for s in drawn[:10]]  # the shape is drawn after the others
    with pytest.raises(OptionError, match="unknown setting 'weight'"):
        draw_lab_settings(1, weight=3)
    lab = simulate_typical_lab_record(6, bout=4.0, stand_before=1.0, stand_after=1.0, fs=500.0)
    again = simulate_typical_lab_record(6, bout=4.0, stand_before=1.0, stand_after=1.0, fs=500.0)
    assert np.array_equal(lab.record.force, again.record.force)
    assert lab.truth["typical"]["fixed"] == ["bout", "fs", "stand_after", "stand_before"]


def test_the_command_line_writes_a_lab_record(tmp_path, capsys):
    out = tmp_path / "rec.csv"
    argv = ["simulate", "--lab", "--out", str(out), "--mass", "70", "--fb", "2", "--fh", "2.5", "--xi", "0.3",
            "--fs", "500", "--bout", "4", "--stand", "1,2", "--hum", "60", "--hum-amplitude", "4,0,1",
            "--fh-change", "0.14", "--tire", "0.2", "--seed", "3"]
    assert main(argv) == 0
    assert "lab's force-plate export" in capsys.readouterr().out
    truth = json.loads((tmp_path / "rec_truth.json").read_text())
    assert truth["hum"]["frequency_hz"] == 60 and truth["f_h_end"] == pytest.approx(2.85)
    assert truth["span"]["stand_before_s"] == 1.0 and truth["span"]["stand_after_s"] == 2.0
    assert read_record(out, mass=70).fs == pytest.approx(500.0)


@pytest.mark.parametrize("argv,pattern", [
    (["--hum", "55"], "--hum must be 50 or 60"),
    (["--fs", "100"], "--fs 100 Hz is outside 200-10000 Hz"),
    (["--tire", "0.95"], "--tire must be 0 to 0.9"),
    (["--variation", "tempo"], "--variation must be one of 'jumps', 'smooth'"),
    (["--change", "jump"], "--change must be one of 'drift', 'step'"),
    (["--ramp", "1,2,3"], "--ramp takes one or two numbers"),
    (["--duration", "30"], "--duration does not apply to --lab"),
    (["--noise", "0.01"], "--noise does not apply to --lab"),
    (["--change", "step", "--fh-change", "0.1", "--change-time", "1"], "--change-time 1.0 s must lie in the bout"),
])
def test_bad_lab_options_are_one_line_errors(tmp_path, capsys, argv, pattern):
    base = ["simulate", "--lab", "--out", str(tmp_path / "r.csv"), "--mass", "70", "--fb", "2", "--fh", "2.5",
            "--xi", "0.3"]
    assert main(base + argv) == 2
    err = capsys.readouterr().err.strip()
    assert pattern in err and "\n" not in err
    assert list(tmp_path.iterdir()) == []


def test_a_lab_record_takes_effects_in_the_equation_of_motion_and_refuses_the_others(tmp_path, capsys):
    """``simulate --lab --effect`` writes the spring into the record and its truth; a floor mode (states of its
    own) or force harmonics are refused in one line, and so is an effect on a phone's record of a trial."""
    out = tmp_path / "r.csv"
    base = ["simulate", "--lab", "--out", str(out), "--mass", "70", "--fb", "2", "--fh", "2.5", "--xi", "0.3",
            "--bout", "6", "--seed", "3"]
    assert main(base + ["--effect", "cubic_stiffness:beta_3=1500"]) == 0
    assert "effects cubic_stiffness:beta_3=1500" in capsys.readouterr().out
    truth = json.loads((tmp_path / "r_truth.json").read_text())
    assert truth["effects"] == {"cubic_stiffness": {"beta_3": 1500.0}}
    plain = simulate_lab_record(mass=70, f_b=2, f_h=2.5, xi_h=0.3, bout=6, seed=3)
    assert np.abs(read_record(out, mass=70).force - plain.record.force).max() > 5.0  # N: the spring is in it
    for effect in ("floor_mode", "harmonics"):
        assert main(base + ["--effect", effect]) == 2
        err = capsys.readouterr().err.strip()
        assert f"effect '{effect}' adds force harmonics or states of its own" in err and "\n" not in err
    assert main(base + ["--accelerometer", "--effect", "cubic_stiffness"]) == 2
    assert "--effect does not apply to --lab --accelerometer" in capsys.readouterr().err


def test_lab_options_need_lab_and_the_person_needs_its_options(tmp_path, capsys):
    out = str(tmp_path / "r.csv")
    assert main(["simulate", "--out", out, "--mass", "70", "--fb", "2", "--fh", "2.5", "--xi", "0.3",
                 "--duration", "5", "--tire", "0.1"]) == 2
    assert "--tire applies to a lab's record (--lab)" in capsys.readouterr().err
    assert main(["simulate", "--lab", "--out", out, "--mass", "70"]) == 2
    assert "--lab needs --fb, --fh, --xi (or --typical to draw them)" in capsys.readouterr().err
