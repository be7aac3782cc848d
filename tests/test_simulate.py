"""Tests of the forward simulator (smd_statespace.simulation) and the article constants.

The physics is checked against closed forms that the simulator does not use:
the frequency response of Eq. 2, the free decay of a damped oscillator, the
exact period of the undamped cubic oscillator, energy conservation of the
undamped person-floor system, and the two-degree-of-freedom frequency response
solved here from the equations of motion.
"""

import json

import numpy as np
import pandas as pd
import pytest
from scipy import integrate
from scipy.stats import skewnorm

from smd_statespace import article
from smd_statespace.errors import MassError, OptionError
from smd_statespace.io import G, read_record
from helpers import zero_force_cycles
from smd_statespace.simulation import (
    MASS_DISTRIBUTION,
    POPULATION_BOUNDS,
    SAMPLE_SETTINGS,
    integrate_response,
    sample_path,
    sample_population,
    sample_truth_path,
    simulate_bouncing,
    write_sample,
)

EXACT = dict(fb_variation=0.0, coef_variation=0.0, noise=0.0)


def eq2_frf(frequency, f_h, xi_h):
    """u'' per unit g*F of Eq. 2 at ``frequency`` (Hz): H = -w^2 / (w_h^2 - w^2 + 2i xi w_h w)."""
    w, wh = 2 * np.pi * frequency, 2 * np.pi * f_h
    return -(w**2) / (wh**2 - w**2 + 2j * xi_h * wh * w)


def harmonic_fit(time, signal, f_b, t_ref, n):
    """Least-squares complex amplitudes c_i (signal ~ c0 + sum Re(c_i e^{i 2 pi i f_b (t - t_ref)})), and residual."""
    theta = 2 * np.pi * f_b * (time - t_ref)
    orders = np.arange(1, n + 1)
    design = np.column_stack([np.ones_like(time), np.cos(np.outer(theta, orders)), np.sin(np.outer(theta, orders))])
    coef, *_ = np.linalg.lstsq(design, signal, rcond=None)
    residual = signal - design @ coef
    return coef[1 : n + 1] - 1j * coef[n + 1 :], residual


def complex_coefficients(cycles, n):
    row = cycles.iloc[0]
    return np.array([row[f"a{i}"] - 1j * row[f"b{i}"] for i in range(1, n + 1)])


# ---------------------------------------------------------------------------
# physics of the base model


@pytest.mark.parametrize(
    "f_b, f_h, xi_h",
    [(2.0, 2.5, 0.3), (1.5, 2.0, 0.1), (3.2, 2.2, 0.5), (2.5, 4.0, 0.05)],
)
def test_steady_state_harmonics_equal_eq2_frequency_response(f_b, f_h, xi_h):
    sim = simulate_bouncing(f_b=f_b, f_h=f_h, xi_h=xi_h, duration=3.0, fs=200.0, seed=4, **EXACT)
    states, cycles = sim.states, sim.cycles
    # all cycles are equal, so the whole record (from t = 0, inside the first
    # cycle) must be one periodic steady state: no start-up transient
    assert np.allclose(cycles["f_b"], f_b, rtol=0, atol=1e-12)
    time, u_ddot = states["time"].to_numpy(), states["u_ddot"].to_numpy()
    fitted, residual = harmonic_fit(time, u_ddot, f_b, cycles["t_start"][0], 4)
    expected = eq2_frf(np.arange(1, 5) * f_b, f_h, xi_h) * G * complex_coefficients(cycles, 4)
    scale = np.abs(expected).max()
    assert np.abs(fitted - expected).max() < 1e-7 * scale
    assert np.abs(residual).max() < 1e-7 * scale
    # amplitudes: |H(i w)| g BLF_i
    amplitudes = np.abs(eq2_frf(np.arange(1, 5) * f_b, f_h, xi_h)) * G * np.array(sim.truth["blf"])
    assert np.allclose(np.abs(fitted), amplitudes, rtol=1e-7)


def test_free_decay_matches_damped_oscillator():
    f_h, xi_h, u0, v0 = 2.3, 0.12, 0.03, -0.1
    time = np.arange(0, 6.0, 0.01)
    states = integrate_response(zero_force_cycles(6.0), time, f_h=f_h, xi_h=xi_h, initial_state=[u0, v0])
    wh = 2 * np.pi * f_h
    wd = wh * np.sqrt(1 - xi_h**2)
    envelope = np.exp(-xi_h * wh * time)
    u = envelope * (u0 * np.cos(wd * time) + (v0 + xi_h * wh * u0) / wd * np.sin(wd * time))
    assert np.abs(states["u"] - u).max() < 1e-9 * u0
    exact_velocity = envelope * (v0 * np.cos(wd * time) - (wh * u0 + xi_h * v0) * wh / wd * np.sin(wd * time))
    assert np.abs(states["u_dot"] - exact_velocity).max() < 1e-8 * abs(v0) + 1e-9
    assert np.all(states["force_bio"] == 0.0)


def test_grf_is_eq3_and_acceleration_is_second_derivative():
    sim = simulate_bouncing(duration=3.0, fs=1000.0, seed=7, noise=0.0)
    states, mass = sim.states, sim.record.mass
    assert np.allclose(sim.record.force, mass * (G + states["u_ddot"]), rtol=1e-13, atol=0)
    assert sim.record.floor_acc is None
    dt = 1e-3
    u, u_dot, u_ddot = (states[c].to_numpy() for c in ("u", "u_dot", "u_ddot"))
    same_cycle = (states["cycle"].diff().to_numpy()[1:-1] == 0) & (states["cycle"].diff().to_numpy()[2:] == 0)
    second = (u[2:] - 2 * u[1:-1] + u[:-2]) / dt**2
    first = (u[2:] - u[:-2]) / (2 * dt)
    assert np.abs(second - u_ddot[1:-1])[same_cycle].max() < 2e-4 * np.abs(u_ddot).max()
    assert np.abs(first - u_dot[1:-1])[same_cycle].max() < 2e-4 * np.abs(u_dot).max()


def test_grf_noise_level():
    clean = simulate_bouncing(duration=10.0, seed=11, noise=0.0)
    noisy = simulate_bouncing(duration=10.0, seed=11, noise=0.02)
    weight = noisy.record.mass * G
    assert np.std(noisy.record.force - clean.record.force) / weight == pytest.approx(0.02, rel=0.05)
    assert np.mean(noisy.record.force) / weight == pytest.approx(1.0, abs=0.01)


def test_cycles_reproduce_force_bio_and_describe_variation():
    sim = simulate_bouncing(duration=15.0, seed=3)
    cycles, states = sim.cycles, sim.states
    n = sim.truth["n_force_harmonics"]
    # contiguous, covering the record, the first one starting at or before t = 0
    assert np.allclose(cycles["t_start"][1:], cycles["t_end"][:-1], rtol=0, atol=0)
    assert cycles["t_start"][0] <= 0.0 < cycles["t_end"][0]
    assert cycles["t_end"].iloc[-1] > states["time"].iloc[-1]
    assert np.allclose(cycles["f_b"], 1 / (cycles["t_end"] - cycles["t_start"]), rtol=1e-12)
    for i in range(1, n + 1):
        assert np.allclose(cycles[f"blf{i}"], np.hypot(cycles[f"a{i}"], cycles[f"b{i}"]), rtol=1e-12)
    # Eq. 4 with each cycle's coefficients, referred to its own start
    index = np.searchsorted(cycles["t_start"].to_numpy(), states["time"].to_numpy(), side="right") - 1
    assert np.array_equal(index, states["cycle"].to_numpy())
    row = cycles.iloc[index]
    theta = 2 * np.pi * row["f_b"].to_numpy() * (states["time"].to_numpy() - row["t_start"].to_numpy())
    force = row["a0"].to_numpy().copy()
    for i in range(1, n + 1):
        force += row[f"a{i}"].to_numpy() * np.cos(i * theta) + row[f"b{i}"].to_numpy() * np.sin(i * theta)
    assert np.allclose(G * force, states["force_bio"], rtol=0, atol=1e-12)
    # the variation is there and of the requested size
    assert np.std(cycles["f_b"]) / 2.0 == pytest.approx(0.02, rel=0.35)
    assert np.std(cycles["blf1"]) / 0.25 == pytest.approx(0.10, rel=0.35)
    assert np.mean(cycles["blf1"]) == pytest.approx(0.25, rel=0.05)


def test_the_harmonics_can_vary_in_phase_alone_and_by_default_vary_alike():
    """``phase_variation`` sets the phases' jitter apart from the amplitudes' (a force that keeps its size and shifts
    its shape); left out, the record is the one ``coef_variation`` alone gives, to the last bit."""
    same = simulate_bouncing(duration=15.0, seed=3, phase_variation=0.10)
    assert np.array_equal(same.record.force, simulate_bouncing(duration=15.0, seed=3).record.force)
    phased = simulate_bouncing(duration=15.0, seed=3, coef_variation=0.0, phase_variation=0.10)
    cycles, blf, phases = phased.cycles, phased.truth["blf"], phased.truth["phases"]
    jitter = []
    for i in range(1, len(blf) + 1):
        assert np.allclose(cycles[f"blf{i}"], blf[i - 1], rtol=1e-12)  # the size kept, cycle after cycle
        angle = np.arctan2(cycles[f"b{i}"], cycles[f"a{i}"]) - phases[i - 1]
        jitter.append(np.angle(np.exp(1j * angle)))
    assert np.std(jitter) == pytest.approx(0.10, rel=0.2)
    assert phased.truth["variations"]["phase_jitter_rad"] == 0.10
    with pytest.raises(OptionError, match="phase_variation is a setting of variation='jumps'"):
        simulate_bouncing(duration=5.0, seed=3, variation="smooth", phase_variation=0.1)
    with pytest.raises(OptionError, match="phase_variation must be 0-1"):
        simulate_bouncing(duration=5.0, seed=3, phase_variation=2.0)


def test_truth_is_json_and_follows_eq17_eq18(tmp_path):
    sim = simulate_bouncing(mass=57.4, f_h=1.784, xi_h=0.568, duration=4.0, seed=1, effects={"floor_mode": {}})
    truth = json.loads(json.dumps(sim.truth))
    assert truth["K_h"] == pytest.approx(article.CHECK_VALUES["K_h"], abs=0.05)
    assert truth["C_h"] == pytest.approx(article.CHECK_VALUES["C_h"], abs=0.05)
    assert truth["effects"]["floor_mode"]["modal_mass"] == 8583.0
    assert truth["n_harmonics"] == 4 and truth["seed"] == 1
    csv_path, truth_path = sim.write(tmp_path / "rec.csv")
    assert truth_path.name == "rec_truth.json"
    written = json.loads(truth_path.read_text())
    assert len(written["cycles"]["a1"]) == len(sim.cycles)
    again = read_record(csv_path, 57.4)
    assert np.allclose(again.force, sim.record.force, atol=1e-6)
    assert np.allclose(again.floor_acc, sim.record.floor_acc, atol=1e-6)


# ---------------------------------------------------------------------------
# effects


def test_floor_mode_undamped_energy_is_conserved():
    mass, f_h, modal_mass, f_f, beta = 70.0, 2.4, 900.0, 3.0, 300.0
    effects = {
        "floor_mode": {"frequency": f_f, "damping": 0.0, "modal_mass": modal_mass},
        "cubic_stiffness": {"beta_3": beta},
    }
    time = np.arange(0, 10.0, 0.01)
    states = integrate_response(
        zero_force_cycles(10.0), time, f_h=f_h, xi_h=0.0, mass=mass, effects=effects,
        initial_state=[0.03, 0.0, -0.001, 0.0],
    )
    k_h, k_f = mass * (2 * np.pi * f_h) ** 2, modal_mass * (2 * np.pi * f_f) ** 2
    rel = states["u"] - states["z"]
    energy = (
        0.5 * mass * states["u_dot"] ** 2
        + 0.5 * modal_mass * states["z_dot"] ** 2
        + k_h * (0.5 * rel**2 + 0.25 * beta * rel**4)
        + 0.5 * k_f * states["z"] ** 2
    )
    assert np.ptp(energy) < 1e-8 * energy[0]
    assert np.ptp(states["z"]) > 1e-3  # the floor really moves (energy is exchanged)


def test_floor_mode_response_matches_two_dof_frequency_response():
    mass, f_b, f_h, xi_h = 70.0, 1.75, 1.81, 0.33  # Table 4 rigid floor; 2nd harmonic near the 3.48 Hz mode
    sim = simulate_bouncing(mass=mass, f_b=f_b, f_h=f_h, xi_h=xi_h, duration=4.0, fs=200.0, seed=2,
                            effects={"floor_mode": {}}, **EXACT)
    floor = sim.truth["effects"]["floor_mode"]
    assert (floor["frequency"], floor["damping"], floor["modal_mass"]) == (3.48, 0.0037, 8583.0)  # Table 3, mode 1
    states, cycles = sim.states, sim.cycles
    assert np.array_equal(sim.record.floor_acc, states["z_ddot"].to_numpy())
    assert np.allclose(sim.record.force, mass * (G + states["u_ddot"]), rtol=1e-13)
    wf, mf = 2 * np.pi * floor["frequency"], floor["modal_mass"]
    wh = 2 * np.pi * f_h
    coefficients = complex_coefficients(cycles, 4)
    expected_u, expected_z = [], []
    for i, c in enumerate(coefficients, start=1):
        w = 2 * np.pi * i * f_b
        d_h = wh**2 + 2j * xi_h * wh * w
        # person: -w^2 U = -d_h (U - Z) + g C ; floor: (k_f - m_f w^2 + i w c_f) Z = M w^2 U
        matrix = np.array([[d_h - w**2, -d_h], [-mass * w**2, mf * (wf**2 - w**2 + 2j * floor["damping"] * wf * w)]])
        u_amp, z_amp = np.linalg.solve(matrix, [G * c, 0.0])
        expected_u.append(-(w**2) * u_amp)
        expected_z.append(-(w**2) * z_amp)
    time, t_ref = states["time"].to_numpy(), cycles["t_start"][0]
    fitted_z, residual_z = harmonic_fit(time, states["z_ddot"].to_numpy(), f_b, t_ref, 4)
    fitted_u, _ = harmonic_fit(time, states["u_ddot"].to_numpy(), f_b, t_ref, 4)
    assert np.abs(fitted_z - expected_z).max() < 1e-7 * np.abs(expected_z).max()
    assert np.abs(residual_z).max() < 1e-7 * np.abs(expected_z).max()  # steady state from the start
    assert np.abs(fitted_u - expected_u).max() < 1e-7 * np.abs(expected_u).max()
    # the 2nd harmonic dominates the floor response (near resonance), and HSI changes the person's response
    assert np.argmax(np.abs(expected_z)) == 1
    rigid = eq2_frf(np.arange(1, 5) * f_b, f_h, xi_h) * G * coefficients
    assert np.abs(fitted_u[1] - rigid[1]) > 1e-3 * np.abs(rigid[1])


def test_floor_mode_starts_in_the_coupled_steady_state():
    # 2nd harmonic (3.5 Hz) next to the 3.48 Hz, 0.37 %-damped mode (decay time ~12 s): a start-up
    # transient would make the floor amplitude grow or shrink over the record
    sim = simulate_bouncing(mass=70.0, f_b=1.75, f_h=1.8, xi_h=0.33, duration=30.0, seed=1,
                            effects={"floor_mode": {}}, **EXACT)
    time, z_ddot = sim.states["time"].to_numpy(), sim.states["z_ddot"].to_numpy()
    first = np.sqrt(np.mean(z_ddot[time < 5.0] ** 2))
    last = np.sqrt(np.mean(z_ddot[time > time[-1] - 5.0] ** 2))
    assert first > 0.5  # the floor responds strongly
    assert abs(first / last - 1.0) < 0.01


def _zero_crossing_period(time, signal):
    sign_change = np.nonzero((signal[:-1] > 0) & (signal[1:] <= 0))[0]
    crossings = time[sign_change] + signal[sign_change] / (signal[sign_change] - signal[sign_change + 1]) * (
        time[sign_change + 1] - time[sign_change]
    )
    return np.mean(np.diff(crossings))


def test_cubic_stiffness_changes_the_natural_frequency_the_right_way():
    f_h, amplitude = 2.0, 0.04
    time = np.arange(0, 5.0, 0.0005)
    wh = 2 * np.pi * f_h
    periods = {}
    for beta in (400.0, 0.0, -150.0):
        effects = {"cubic_stiffness": {"beta_3": beta}}
        states = integrate_response(zero_force_cycles(5.0), time, f_h=f_h, xi_h=0.0, effects=effects,
                                    initial_state=[amplitude, 0.0])
        periods[beta] = _zero_crossing_period(time, states["u"].to_numpy())
        # exact period of the undamped oscillator u'' = -w_h^2 (u + beta u^3) released from rest at A
        exact, _ = integrate.quad(
            lambda phi: 4 / (wh * np.sqrt(1 + beta * amplitude**2 * (1 + np.sin(phi) ** 2) / 2)), 0, np.pi / 2
        )
        assert periods[beta] == pytest.approx(exact, rel=1e-6)
    assert periods[400.0] < periods[0.0] < periods[-150.0]
    assert periods[0.0] == pytest.approx(1 / f_h, rel=1e-7)


def test_cubic_stiffness_in_a_record_and_zero_beta_changes_nothing():
    base = simulate_bouncing(duration=3.0, seed=5)
    zero = simulate_bouncing(duration=3.0, seed=5, effects={"cubic_stiffness": {"beta_3": 0.0}})
    hard = simulate_bouncing(duration=3.0, seed=5, effects={"cubic_stiffness": {}}, **EXACT)
    linear = simulate_bouncing(duration=3.0, seed=5, **EXACT)
    assert np.allclose(zero.record.force, base.record.force, rtol=0, atol=1e-9)
    # a hardening spring stiffens the person: smaller COM excursions, periodic steady state from the start
    assert np.ptp(hard.states["u"]) < np.ptp(linear.states["u"])
    c = hard.cycles
    period_samples = int(round(hard.record.fs / c["f_b"][0]))
    u = hard.states["u"].to_numpy()
    assert np.abs(u[period_samples:] - u[:-period_samples]).max() < 1e-6 * np.ptp(u)
    assert 1e-3 * np.ptp(u) < np.abs(u - linear.states["u"].to_numpy()).max()


def test_harmonics_effect_puts_energy_at_higher_harmonics():
    f_b, f_h, xi_h = 2.0, 2.5, 0.3
    extra = simulate_bouncing(f_b=f_b, duration=3.0, fs=200.0, seed=6, effects={"harmonics": {}}, **EXACT)
    plain = simulate_bouncing(f_b=f_b, duration=3.0, fs=200.0, seed=6, **EXACT)
    assert extra.truth["n_harmonics"] == 4 and extra.truth["n_force_harmonics"] == 6
    assert {"a5", "b5", "a6", "b6", "blf6"} <= set(extra.cycles.columns)
    time, t_ref = extra.states["time"].to_numpy(), extra.cycles["t_start"][0]
    fitted, residual = harmonic_fit(time, extra.states["u_ddot"].to_numpy(), f_b, t_ref, 7)
    expected = eq2_frf(np.arange(5, 7) * f_b, f_h, xi_h) * G * complex_coefficients(extra.cycles, 6)[4:]
    assert np.abs(fitted[4:6] - expected).max() < 1e-7 * np.abs(expected).max()
    amplitudes = np.abs(eq2_frf(np.arange(5, 7) * f_b, f_h, xi_h)) * G * np.array([0.04, 0.03])
    assert np.allclose(np.abs(expected), amplitudes, rtol=1e-12)
    assert abs(fitted[6]) < 1e-8
    plain_fit, _ = harmonic_fit(time, plain.states["u_ddot"].to_numpy(), f_b, t_ref, 6)
    assert np.abs(plain_fit[4:]).max() < 1e-8
    assert np.allclose(plain_fit[:4], fitted[:4], rtol=1e-9)


def test_zero_extra_harmonics_leave_a_noisy_varying_record_unchanged():
    base = simulate_bouncing(duration=3.0, seed=8, effects={"floor_mode": {}})
    zero = simulate_bouncing(duration=3.0, seed=8, effects={"floor_mode": {}, "harmonics": {"blf": (0.0, 0.0)}})
    assert np.allclose(zero.record.force, base.record.force, rtol=0, atol=1e-9)
    assert np.allclose(zero.record.floor_acc, base.record.floor_acc, rtol=0, atol=1e-9)
    assert np.allclose(zero.cycles["a1"], base.cycles["a1"], rtol=0, atol=0)


def test_floor_noise_defaults_to_noise_fraction_of_rms():
    clean = simulate_bouncing(f_b=1.75, duration=10.0, seed=9, noise=0.0, effects={"floor_mode": {}})
    noisy = simulate_bouncing(f_b=1.75, duration=10.0, seed=9, noise=0.0, effects={"floor_mode": {"noise": 0.05}})
    rms = np.sqrt(np.mean(clean.record.floor_acc**2))
    assert np.array_equal(clean.record.floor_acc, clean.states["z_ddot"].to_numpy())
    assert np.std(noisy.record.floor_acc - clean.record.floor_acc) / rms == pytest.approx(0.05, rel=0.08)


# ---------------------------------------------------------------------------
# randomness


def test_seeds_make_records_reproducible():
    first = simulate_bouncing(duration=2.0, seed=42)
    again = simulate_bouncing(duration=2.0, seed=np.random.SeedSequence(42))
    other = simulate_bouncing(duration=2.0, seed=43)
    from_generator = simulate_bouncing(duration=2.0, seed=np.random.default_rng(42))
    assert np.array_equal(first.record.force, again.record.force)
    assert np.array_equal(first.record.force, from_generator.record.force)
    assert not np.allclose(first.record.force, other.record.force)
    fresh = simulate_bouncing(duration=2.0)
    replay = simulate_bouncing(duration=2.0, seed=fresh.truth["seed"])
    assert np.array_equal(fresh.record.force, replay.record.force)
    assert from_generator.truth["seed"] is None


def test_default_grf_shape_is_a_plausible_bouncing_force():
    for f_b in (1.5, 2.5, 3.5):
        sim = simulate_bouncing(f_b=f_b, duration=4.0, seed=1, noise=0.0)
        body_weights = sim.record.force / (sim.record.mass * G)
        assert 1.3 < body_weights.max() < 1.9
        assert 0.3 < body_weights.min() < 0.75
        # one main peak per cycle, at the start of the cycle (where the article starts its cycles)
        for j in range(1, len(sim.cycles) - 1):
            inside = (sim.states["cycle"] == j).to_numpy()
            start, end = sim.cycles["t_start"][j], sim.cycles["t_end"][j]
            t_peak = sim.record.time[inside][np.argmax(body_weights[inside])]
            assert min(t_peak - start, end - t_peak) < 0.12 * (end - start)


# ---------------------------------------------------------------------------
# population (Table 2)


def _truncated_moments(fit, low, high):
    dist = skewnorm(fit.a, loc=fit.m, scale=fit.s)
    mass = dist.cdf(high) - dist.cdf(low)
    mean = integrate.quad(lambda x: x * dist.pdf(x), low, high, limit=200)[0] / mass
    second = integrate.quad(lambda x: (x - mean) ** 2 * dist.pdf(x), low, high, limit=200)[0] / mass
    return mean, np.sqrt(second)


@pytest.mark.parametrize("band", range(len(article.BANDS)))
def test_population_moments_match_table2(band):
    low, high = article.BANDS[band]
    f_b = 0.5 * (low + high)
    people = sample_population(3000, f_b, seed=band)
    for parameter, column, limit in (("f_h", "f_h", "f_h"), ("xi_h", "xi_h", "xi_h"), ("BLF1", "blf1", "blf"),
                                     ("BLF2", "blf2", "blf"), ("BLF3", "blf3", "blf")):
        values = people[column].to_numpy()
        lo, hi = POPULATION_BOUNDS[limit]
        assert values.min() >= lo and values.max() <= hi
        mean, sd = _truncated_moments(article.TABLE2[parameter][band], lo, hi)
        assert abs(values.mean() - mean) < 5 * sd / np.sqrt(values.size), parameter
        assert np.std(values) == pytest.approx(sd, rel=0.08), parameter
    masses = people["mass"].to_numpy()
    assert masses.min() >= 45 and masses.max() <= 100
    assert masses.mean() == pytest.approx(MASS_DISTRIBUTION[0], abs=1.0)
    assert np.allclose(people["K_h"], masses * (2 * np.pi * people["f_h"]) ** 2)
    assert np.allclose(people["C_h"], 2 * people["xi_h"] * masses * 2 * np.pi * people["f_h"])


def test_population_uses_the_band_of_f_b_and_rejects_other_frequencies():
    below = sample_population(2000, 1.7499, seed=1)["f_h"].mean()
    above = sample_population(2000, 1.75, seed=1)["f_h"].mean()
    assert below == pytest.approx(_truncated_moments(article.TABLE2["f_h"][0], 1, 6)[0], abs=0.03)
    assert above == pytest.approx(_truncated_moments(article.TABLE2["f_h"][1], 1, 6)[0], abs=0.03)
    assert np.array_equal(sample_population(5, 2.0, seed=3), sample_population(5, 2.0, seed=3))
    for f_b in (1.2, 3.8, float("nan")):
        with pytest.raises(OptionError, match="f_b"):
            sample_population(10, f_b)
    with pytest.raises(OptionError, match="n must"):
        sample_population(0, 2.0)
    with pytest.raises(OptionError, match="bounds"):
        sample_population(10, 2.0, bounds={"fh": (1, 4)})


# ---------------------------------------------------------------------------
# article constants


def test_article_constants():
    check = article.CHECK_VALUES
    w = 2 * np.pi * check["f_h"]
    assert check["mass"] * w**2 == pytest.approx(check["K_h"], abs=0.05)  # Eq. 17
    assert 2 * check["xi_h"] * check["mass"] * w == pytest.approx(check["C_h"], abs=0.05)  # Eq. 18
    assert len(article.BANDS) == 6 and all(hi - lo == pytest.approx(0.4) for lo, hi in article.BANDS)
    frequencies = (1.35, 1.5, 1.75, 3.35, 3.75, 1.34, 3.76, None)
    assert [article.band_of(f) for f in frequencies] == [0, 0, 1, 5, 5, None, None, None]
    for parameter in article.TABLE2_PARAMETERS:
        assert len(article.TABLE2[parameter]) == 6
    assert article.TABLE3[0].frequency == 3.48 and article.TABLE3[0].damping == pytest.approx(0.0037)
    assert article.table2_frame().loc[("BLF2", 0), "a"] == 0.7517
    rigid, plate = article.TABLE4["rigid_floor"], article.TABLE4["vibrating_plate"]
    for key, change in article.TABLE4["difference"].items():
        assert plate[key] / rigid[key] - 1 == pytest.approx(change, abs=0.002)
    with pytest.raises(TypeError):
        article.TABLE2["f_h"] = ()


# ---------------------------------------------------------------------------
# shipped sample


def test_shipped_sample_is_current(tmp_path):
    assert sample_path().stat().st_size < 200_000
    truth = json.loads(sample_truth_path().read_text())
    for key, value in SAMPLE_SETTINGS.items():
        assert truth[key] == value
    shipped = read_record(sample_path(), truth["mass"])
    regenerated = write_sample(tmp_path)
    assert np.allclose(shipped.time, regenerated.record.time, atol=1e-9)
    assert np.allclose(shipped.force, regenerated.record.force, atol=2e-6)
    assert json.loads((tmp_path / "sample_truth.json").read_text())["cycles"] == truth["cycles"]


# ---------------------------------------------------------------------------
# input validation


@pytest.mark.parametrize(
    "kwargs, error, match",
    [
        (dict(mass=5.0), MassError, "mass"),
        (dict(mass="heavy"), MassError, "mass"),
        (dict(f_h=0.0), OptionError, "f_h"),
        (dict(xi_h=-0.1), OptionError, "xi_h"),
        (dict(xi_h=0.0), OptionError, "xi_h"),
        (dict(f_b=float("nan")), OptionError, "f_b"),
        (dict(duration=0.0), OptionError, "duration"),
        (dict(duration=0.2), OptionError, "duration"),
        (dict(fs=-100.0), OptionError, "fs"),
        (dict(fs=20.0), OptionError, "fs"),
        (dict(f_b=3.5, fs=50.0), OptionError, "fs"),
        (dict(blf=(0.2, -0.1)), OptionError, "blf"),
        (dict(blf=()), OptionError, "blf"),
        (dict(phases=(0.0, 1.0)), OptionError, "phases"),
        (dict(fb_variation=0.5), OptionError, "fb_variation"),
        (dict(coef_variation=-0.1), OptionError, "coef_variation"),
        (dict(noise=-0.01), OptionError, "noise"),
        (dict(seed=-1), OptionError, "seed"),
        (dict(seed="abc"), OptionError, "seed"),
        (dict(effects=42), OptionError, "effects must be"),
        (dict(effects={"flor_mode": {}}), OptionError, "flor_mode.*floor_mode"),
        (dict(effects={"floor_mode": {"freq": 3.0}}), OptionError, "'freq'.*frequency"),
        (dict(effects={"floor_mode": {"modal_mass": 0}}), OptionError, "modal_mass"),
        (dict(effects={"harmonics": {"blf": (0.1,), "phases": (0.0, 1.0)}}), OptionError, "phases"),
        (dict(effects={"cubic_stiffness": {"beta_3": "x"}}), OptionError, "beta_3"),
        (dict(effects={"cubic_stiffness": 400}), OptionError, "cubic_stiffness"),
    ],
)
def test_bad_inputs_raise_one_line_errors(kwargs, error, match):
    with pytest.raises(error, match=match) as info:
        simulate_bouncing(**{"duration": 2.0, **kwargs})
    assert "\n" not in str(info.value)


def test_integrate_response_rejects_bad_inputs():
    cycles = zero_force_cycles(2.0)
    with pytest.raises(OptionError, match="initial_state"):
        integrate_response(cycles, np.arange(0, 1, 0.01), f_h=2.0, xi_h=0.1, initial_state=[0.0, 0.0, 0.0])
    with pytest.raises(OptionError, match="cycles must cover"):
        integrate_response(cycles, np.arange(-1, 1, 0.01), f_h=2.0, xi_h=0.1)
    with pytest.raises(OptionError, match="harmonics"):
        integrate_response(cycles, np.arange(0, 1, 0.01), f_h=2.0, xi_h=0.1, effects={"harmonics": {}})


def test_ambient_floor_vibration_has_the_requested_rms_and_leaves_the_rest_unchanged():
    # A floor far heavier than the person: its vibration is the ambient excitation's alone.
    target = 0.3
    heavy = {"floor_mode": {"ambient": target, "modal_mass": 1e9}}
    sim = simulate_bouncing(duration=60.0, seed=3, noise=0.0, effects=heavy)
    z_ddot = sim.states["z_ddot"].to_numpy()
    assert np.sqrt(np.mean(z_ddot[z_ddot.size // 2:] ** 2)) == pytest.approx(target, rel=0.1)
    # Same seed with and without ambient vibration: the same force cycles and noise draws.
    quiet = simulate_bouncing(duration=5.0, seed=4, effects={"floor_mode": {}})
    lively = simulate_bouncing(duration=5.0, seed=4, effects={"floor_mode": {"ambient": 0.5}})
    pd.testing.assert_frame_equal(quiet.cycles, lively.cycles)
    assert not np.allclose(quiet.record.floor_acc, lively.record.floor_acc)
    with pytest.raises(OptionError, match="ambient"):
        simulate_bouncing(duration=5.0, effects={"floor_mode": {"ambient": -1.0}})


# ---------------------------------------------------------------------------
# smooth cycle-to-cycle variation (variation="smooth")

SMOOTH = dict(variation="smooth")


def table_force(cycles, states):
    """Eq. 4 with each sample's cycle row, referred to the cycle's own start (g)."""
    n = sum(1 for column in cycles.columns if column.startswith("blf"))
    time = states["time"].to_numpy()
    row = cycles.iloc[states["cycle"].to_numpy()]
    theta = 2 * np.pi * row["f_b"].to_numpy() * (time - row["t_start"].to_numpy())
    force = row["a0"].to_numpy().copy()
    for i in range(1, n + 1):
        force += row[f"a{i}"].to_numpy() * np.cos(i * theta) + row[f"b{i}"].to_numpy() * np.sin(i * theta)
    return force


def fourth_order_derivative(signal, dt):
    """Central 4th-order difference at samples 2..T-3."""
    return (-signal[4:] + 8 * signal[3:-1] - 8 * signal[1:-3] + signal[:-4]) / (12 * dt)


def test_smooth_variation_is_reproducible_and_jumps_stay_the_default():
    first = simulate_bouncing(duration=4.0, seed=21, **SMOOTH)
    again = simulate_bouncing(duration=4.0, seed=np.random.SeedSequence(21), **SMOOTH)
    assert np.array_equal(first.record.force, again.record.force)
    pd.testing.assert_frame_equal(first.cycles, again.cycles)
    assert first.truth["variations"]["generator"] == "smooth"
    assert first.truth["variations"]["correlation_cycles"] == 2.5
    default = simulate_bouncing(duration=4.0, seed=21)
    jumps = simulate_bouncing(duration=4.0, seed=21, variation="jumps")
    assert np.array_equal(default.record.force, jumps.record.force)
    pd.testing.assert_frame_equal(default.cycles, jumps.cycles)
    assert default.truth["variations"]["generator"] == "jumps"
    assert not np.allclose(first.record.force, default.record.force)
    assert list(first.states.columns) == list(default.states.columns)
    assert list(first.cycles.columns) == list(default.cycles.columns)
    json.dumps(first.truth)


def test_smooth_force_has_no_jumps_at_cycle_boundaries():
    fs, f_b, blf = 1000.0, 2.0, np.array([0.25, 0.15, 0.05, 0.02])
    smooth = simulate_bouncing(f_b=f_b, duration=6.0, fs=fs, seed=3, noise=0.0, **SMOOTH)
    jumps = simulate_bouncing(f_b=f_b, duration=6.0, fs=fs, seed=3, noise=0.0)
    # second difference of a smooth force: at most F'' / fs^2, harmonic i bounded by BLF_i (1 + 3 cv) (w_i / fs)^2
    bound = np.sum(blf * 1.3 * (2 * np.pi * np.arange(1, 5) * f_b * 1.1 / fs) ** 2)
    curvature = {name: np.abs(np.diff(sim.states["force_bio"].to_numpy() / G, 2)).max()
                 for name, sim in (("smooth", smooth), ("jumps", jumps))}
    assert curvature["smooth"] < bound < 0.1 * curvature["jumps"]
    # the smooth force at the cycle boundaries: the same on both sides (sample before vs sample after)
    force = smooth.states["force_bio"].to_numpy() / G
    boundary = np.nonzero(np.diff(smooth.states["cycle"].to_numpy()))[0]
    steps = np.abs(force[boundary + 1] - force[boundary])
    assert steps.max() < np.abs(np.diff(force)).max() + 1e-12  # no larger than anywhere else
    assert steps.max() < 2 * np.pi * np.sum(np.arange(1, 5) * 1.1 * f_b * blf * 1.3) / fs


def test_smooth_states_satisfy_eq2_across_cycle_boundaries():
    f_h, xi_h, fs = 2.5, 0.3, 1000.0
    for variation, tolerance in (("smooth", 1e-6), ("jumps", None)):
        sim = simulate_bouncing(f_h=f_h, xi_h=xi_h, duration=6.0, fs=fs, seed=5, noise=0.0, variation=variation)
        u, u_dot, u_ddot, force = (sim.states[c].to_numpy() for c in ("u", "u_dot", "u_ddot", "force_bio"))
        wh = 2 * np.pi * f_h
        assert np.allclose(u_ddot + 2 * xi_h * wh * u_dot + wh**2 * u, force, rtol=0, atol=1e-12)  # Eq. 2
        # u' and u'' (from Eq. 2 with the recorded force) are the derivatives of the integrated u and u'
        velocity_error = np.abs(fourth_order_derivative(u, 1 / fs) - u_dot[2:-2]).max() / np.abs(u_dot).max()
        acceleration_error = np.abs(fourth_order_derivative(u_dot, 1 / fs) - u_ddot[2:-2]).max() / np.abs(u_ddot).max()
        if tolerance is not None:
            assert velocity_error < tolerance and acceleration_error < tolerance
        else:  # the jumps' force is discontinuous, so u'' is too: the same check fails at the boundaries
            assert acceleration_error > 1e-3


def test_smooth_cycles_are_phase_cycles_whose_coefficients_reproduce_the_force():
    sim = simulate_bouncing(duration=30.0, fs=400.0, seed=2, noise=0.0, **SMOOTH)
    cycles, states = sim.cycles, sim.states
    time = states["time"].to_numpy()
    assert np.allclose(cycles["t_start"][1:], cycles["t_end"][:-1], rtol=0, atol=0)
    assert cycles["t_start"][0] <= 0.0 < cycles["t_end"][0]
    assert cycles["t_end"].iloc[-1] > time[-1]
    assert np.array_equal(cycles["cycle"], np.arange(len(cycles))) and sim.truth["n_cycles"] == len(cycles)
    assert np.allclose(cycles["f_b"], 1 / (cycles["t_end"] - cycles["t_start"]), rtol=1e-12)
    index = np.searchsorted(cycles["t_start"].to_numpy(), time, side="right") - 1
    assert np.array_equal(index, states["cycle"].to_numpy())
    for i in range(1, 5):
        assert np.allclose(cycles[f"blf{i}"], np.hypot(cycles[f"a{i}"], cycles[f"b{i}"]), rtol=1e-12)
    # each cycle's Eq. 4 reproduces the force up to the drift within the cycle: far better than the
    # mean cycle, and better than the neighbouring cycles' coefficients
    force = states["force_bio"].to_numpy() / G
    residual = np.sqrt(np.mean((table_force(cycles, states) - force) ** 2))
    mean_cycle = cycles.copy()
    shifted = cycles.copy()
    for column in cycles.columns:
        if column[0] in "ab" and column[1:].isdigit():
            mean_cycle[column] = cycles[column].mean()
            shifted[column] = np.roll(cycles[column].to_numpy(), 1)
    variation = np.sqrt(np.mean((table_force(mean_cycle, states) - force) ** 2))
    neighbour = np.sqrt(np.mean((table_force(shifted, states) - force) ** 2))
    assert residual < 0.35 * variation
    assert residual < 0.7 * neighbour
    # without variation the smooth force is periodic and every row reproduces it exactly
    still = simulate_bouncing(duration=5.0, fs=400.0, seed=2, noise=0.0, fb_variation=0.0, coef_variation=0.0,
                              **SMOOTH)
    assert np.allclose(still.cycles["f_b"], 2.0, rtol=1e-12)
    assert np.allclose(still.cycles["a1"], still.cycles["a1"][0], rtol=1e-12)
    assert np.abs(table_force(still.cycles, still.states) - still.states["force_bio"] / G).max() < 1e-12
    plain = simulate_bouncing(duration=5.0, fs=400.0, seed=2, noise=0.0, fb_variation=0.0, coef_variation=0.0)
    assert np.allclose(still.cycles[["a1", "b1", "a4", "b4"]], plain.cycles[["a1", "b1", "a4", "b4"]], atol=1e-12)


def test_smooth_cycle_coefficients_are_averages_over_the_cycle():
    # At a constant frequency a cycle's least-squares Fourier fit of the force is close to the average of
    # the drifting coefficients over the cycle (the value at its middle), not to the value at its start
    # (about half a cycle's change away).
    sim = simulate_bouncing(duration=20.0, fs=400.0, seed=3, noise=0.0, fb_variation=0.0, **SMOOTH)
    cycles, states = sim.cycles, sim.states
    time, force = states["time"].to_numpy(), states["force_bio"].to_numpy() / G
    names = [f"{kind}{i}" for kind in "ab" for i in range(1, 5)]
    ratios = []
    for j in range(1, len(cycles) - 1):
        inside = (states["cycle"] == j).to_numpy()
        fitted, _ = harmonic_fit(time[inside], force[inside], 2.0, cycles["t_start"][j], 4)
        table = cycles.loc[j, names].to_numpy(dtype=float)
        change = np.abs(cycles.loc[j + 1, names].to_numpy(dtype=float) - table).max()
        ratios.append(np.abs(np.concatenate([fitted.real, -fitted.imag]) - table).max() / change)
    assert np.median(ratios) < 0.35


def test_smooth_variation_has_the_jumps_spread_but_is_correlated_over_cycles():
    f_b, spread = 2.0, {"smooth": [], "jumps": []}
    for variation in spread:
        for seed in range(4 if variation == "smooth" else 2):
            cycles = simulate_bouncing(f_b=f_b, duration=30.0, seed=seed, noise=0.0, variation=variation).cycles
            deviation = cycles["f_b"].to_numpy() / f_b - 1
            blf1 = cycles["blf1"].to_numpy() / 0.25 - 1
            lag1 = np.corrcoef(deviation[:-1], deviation[1:])[0, 1]
            spread[variation].append((np.mean(deviation**2), np.mean(blf1**2), lag1, np.mean(blf1)))
    smooth, jumps = np.array(spread["smooth"]), np.array(spread["jumps"])
    assert np.sqrt(smooth[:, 0].mean()) == pytest.approx(0.02, rel=0.25)
    assert np.sqrt(smooth[:, 1].mean()) == pytest.approx(0.10, rel=0.25)
    assert abs(smooth[:, 3].mean()) < 0.03
    assert np.sqrt(jumps[:, 0].mean()) == pytest.approx(0.02, rel=0.25)
    # a correlation time of 2.5 cycles: neighbouring cycles alike (about 0.85), unlike the jumps' (about 0)
    assert smooth[:, 2].mean() > 0.6 and abs(jumps[:, 2].mean()) < 0.3


def test_smooth_variation_with_effects_keeps_the_other_random_numbers():
    base = simulate_bouncing(f_b=1.75, duration=4.0, seed=8, **SMOOTH)
    extra = simulate_bouncing(f_b=1.75, duration=4.0, seed=8, effects={"harmonics": {}}, **SMOOTH)
    floor = simulate_bouncing(f_b=1.75, duration=4.0, seed=8, effects={"floor_mode": {"ambient": 0.2}}, **SMOOTH)
    hard = simulate_bouncing(f_b=1.75, duration=4.0, seed=8, effects={"cubic_stiffness": {}}, **SMOOTH)
    columns = ["t_start", "t_end", "f_b", "a1", "b1", "a4", "b4"]
    for other in (extra, floor, hard):
        pd.testing.assert_frame_equal(other.cycles[columns], base.cycles[columns])
        noise = other.record.force - other.record.mass * (G + other.states["u_ddot"].to_numpy())
        assert np.allclose(noise, base.record.force - base.record.mass * (G + base.states["u_ddot"].to_numpy()),
                           rtol=0, atol=1e-9)
    # the extra harmonics vary smoothly too; the floor and the cubic spring change the response
    assert extra.truth["n_force_harmonics"] == 6 and np.ptp(extra.cycles["blf5"]) > 0
    assert floor.record.floor_acc is not None and np.abs(floor.states["z_ddot"]).max() > 0.05
    assert not np.allclose(hard.states["u"], base.states["u"])


def test_smooth_record_starts_without_a_transient(monkeypatch):
    from smd_statespace.simulation import variation as module

    settings = dict(f_h=2.5, xi_h=0.1, duration=3.0, seed=12, noise=0.0, **SMOOTH)
    started = simulate_bouncing(**settings)
    monkeypatch.setattr(module, "SMOOTH_RUN_IN_DECAYS", 10.0)  # twice the run-in: the same force over the record
    longer = simulate_bouncing(**settings)
    pd.testing.assert_frame_equal(started.cycles, longer.cycles)
    u_ddot = started.states["u_ddot"].to_numpy()
    assert np.abs(u_ddot - longer.states["u_ddot"].to_numpy()).max() < 2e-4 * np.ptp(u_ddot)
    monkeypatch.setattr(module, "SMOOTH_RUN_IN_DECAYS", 0.0)  # no run-in (but the grid's one or two cycles)
    abrupt = simulate_bouncing(**settings)
    assert np.abs(abrupt.states["u_ddot"].to_numpy() - longer.states["u_ddot"].to_numpy()).max() > 2e-3 * np.ptp(u_ddot)


def test_variation_is_checked_and_on_the_command_line(tmp_path, capsys):
    from smd_statespace.cli import main

    for bad in ("smoth", None, 1):
        with pytest.raises(OptionError, match=r"variation must be one of 'jumps', 'smooth', 'coefficients', 'pulses', 'tempo', 'matern', got") as info:
            simulate_bouncing(duration=2.0, variation=bad)
        assert repr(bad) in str(info.value) and "\n" not in str(info.value)
    argv = ["simulate", "--mass", "70", "--fb", "2", "--fh", "2.5", "--xi", "0.3", "--duration", "3", "--seed", "1",
            "--out", str(tmp_path / "r.csv")]
    assert main(argv + ["--variation", "smoth"]) == 2
    error = capsys.readouterr().err.strip().splitlines()
    assert len(error) == 1 and "--variation" in error[0] and "'jumps', 'smooth'" in error[0]
    assert main(argv + ["--variation", "smooth"]) == 0
    assert "smooth variation" in capsys.readouterr().out
    truth = json.loads((tmp_path / "r_truth.json").read_text())
    assert truth["variations"]["generator"] == "smooth"
    expected = simulate_bouncing(mass=70, f_b=2, f_h=2.5, xi_h=0.3, duration=3, seed=1, **SMOOTH)
    assert np.allclose(read_record(tmp_path / "r.csv", 70).force, expected.record.force, atol=1e-6)
