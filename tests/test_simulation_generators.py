"""The generators of force variation beyond "jumps" and "smooth": coefficients, pulses, tempo."""

import json

import numpy as np
import pytest

from smd_statespace.errors import OptionError
from smd_statespace.io import G
from smd_statespace.simulation import VARIATIONS, simulate_bouncing
from smd_statespace.simulation.generators import PULSE_CONTACT_RATIO

NEW = ("coefficients", "pulses", "tempo")


@pytest.fixture(scope="module")
def long_records():
    """One 40 s record per new generator (fb_variation 3 %, as the issue asks), noise-free force in ``states``."""
    return {name: simulate_bouncing(duration=40.0, seed=11, variation=name, fb_variation=0.03) for name in NEW}


def _whole_cycles(sim):
    """The rows of the cycles table that lie wholly inside the record."""
    cycles = sim.cycles
    return cycles[(cycles["t_start"] >= 0.0) & (cycles["t_end"] <= sim.truth["duration"])]


def _fitted_coefficients(sim, n):
    """Least-squares Fourier coefficients ``(a, b)`` (g) of the noise-free force over each whole cycle."""
    time, force = sim.states["time"].to_numpy(), sim.states["force_bio"].to_numpy() / G
    a, b = [], []
    for row in _whole_cycles(sim).itertuples():
        inside = (time >= row.t_start) & (time < row.t_end)
        angle = 2.0 * np.pi * np.outer((time[inside] - row.t_start) * row.f_b, np.arange(1, n + 1))
        basis = np.column_stack([np.ones(inside.sum()), np.cos(angle), np.sin(angle)])
        solution = np.linalg.lstsq(basis, force[inside], rcond=None)[0]
        a.append(solution[1 : n + 1])
        b.append(solution[n + 1 :])
    return np.array(a), np.array(b)


def test_jumps_and_smooth_are_unchanged():
    # Regression pin: GRF samples (N) computed on the original code, commit de04b45, before the new generators.
    pins = {
        "jumps": [611.2302456422264, 654.138347051207, 475.2239939578524, 625.3653305114669],
        "smooth": [615.6646077762069, 624.7427473139714, 526.7194008291352, 601.0617857714843],
    }
    for variation, values in pins.items():
        force = simulate_bouncing(duration=6.0, seed=1, variation=variation).record.force
        np.testing.assert_allclose(force[[0, 100, 357, 600]], values, rtol=1e-12, atol=0)


@pytest.mark.parametrize("name", NEW)
def test_new_generator_is_reproducible_and_shaped_like_the_others(name):
    assert name in VARIATIONS
    first = simulate_bouncing(duration=5.0, seed=4, variation=name)
    again = simulate_bouncing(duration=5.0, seed=4, variation=name)
    other = simulate_bouncing(duration=5.0, seed=5, variation=name)
    jumps = simulate_bouncing(duration=5.0, seed=4)
    assert np.array_equal(first.record.force, again.record.force)
    assert not np.allclose(first.record.force, other.record.force)
    assert list(first.states.columns) == list(jumps.states.columns)
    assert first.record.force.shape == jumps.record.force.shape
    assert json.loads(json.dumps(first.truth)) == first.truth
    assert first.truth["variations"]["generator"] == name
    assert first.truth["n_cycles"] == len(first.cycles)
    assert {"t_start", "t_end", "f_b", "a1", "b1", "blf4"} <= set(first.cycles.columns)
    assert np.allclose(first.cycles["t_start"].to_numpy()[1:], first.cycles["t_end"].to_numpy()[:-1])


@pytest.mark.parametrize("name", NEW)
def test_mean_force_is_body_weight_and_mean_cycle_blf1_is_the_truth(name, long_records):
    sim = long_records[name]
    weight = sim.truth["mass"] * G
    assert np.mean(sim.record.force) / weight == pytest.approx(1.0, abs=0.003)
    whole = _whole_cycles(sim)
    time, force = sim.states["time"].to_numpy(), sim.states["force_bio"].to_numpy() / G
    inside = (time >= whole["t_start"].iloc[0]) & (time < whole["t_end"].iloc[-1])
    assert abs(np.mean(force[inside])) < 0.005  # the dynamic part has zero mean (a0 = 0)
    a, b = _fitted_coefficients(sim, 4)
    assert np.hypot(a[:, 0].mean(), b[:, 0].mean()) == pytest.approx(sim.truth["blf"][0], rel=0.03)
    # the cycles table says what the force is, cycle by cycle
    assert np.allclose(a[:, 0], whole["a1"], atol=0.01) and np.allclose(b[:, 0], whole["b1"], atol=0.01)


def test_coefficients_jitter_each_coefficient_and_start_from_rest(long_records):
    sim, truth = long_records["coefficients"], long_records["coefficients"].truth
    cycles, c = sim.cycles, truth["variations"]["coef_variation"]
    nominal_a = np.array(truth["blf"]) * np.cos(truth["phases"])
    nominal_b = np.array(truth["blf"]) * np.sin(truth["phases"])
    ratio_a = cycles[[f"a{i}" for i in range(1, 5)]].to_numpy() / nominal_a - 1.0
    ratio_b = cycles[[f"b{i}" for i in range(1, 5)]].to_numpy() / nominal_b - 1.0
    for ratio in (ratio_a, ratio_b):
        assert np.std(ratio) == pytest.approx(c, rel=0.15)
        assert abs(np.mean(ratio)) < 0.3 * c
    assert abs(np.corrcoef(ratio_a.ravel(), ratio_b.ravel())[0, 1]) < 0.2  # a and b jitter independently
    frequency = cycles["f_b"].to_numpy() / truth["f_b"] - 1.0
    assert np.std(frequency) == pytest.approx(0.03, rel=0.2)
    assert cycles["t_start"].iloc[0] == 0.0
    assert sim.states["u"].iloc[0] == 0.0 and sim.states["u_dot"].iloc[0] == 0.0
    assert truth["variations"]["initial_state"] == "rest"


def test_pulses_stay_positive_and_vary_in_width(long_records):
    sim = long_records["pulses"]
    cycles, c = _whole_cycles(sim), sim.truth["variations"]["coef_variation"]
    assert np.min(1.0 + sim.states["force_bio"].to_numpy() / G) > 0.5
    assert np.min(sim.record.force) > 0.0
    assert sim.truth["variations"]["requested_blf"][0] == pytest.approx(sim.truth["blf"][0], rel=1e-9)
    assert sim.truth["phases"][0] == pytest.approx(np.pi)  # the mean pulse is centred in its cycle
    widths = cycles["pulse_width"].to_numpy()
    assert np.std(widths) / PULSE_CONTACT_RATIO == pytest.approx(c, rel=0.3)
    # the width seen in the force: the share of a cycle's samples above its baseline
    time, force = sim.states["time"].to_numpy(), sim.states["force_bio"].to_numpy() / G
    seen = []
    for row in cycles.itertuples():
        inside = force[(time >= row.t_start) & (time < row.t_end)]
        seen.append(np.mean(inside > inside.min() + 1e-9))
    assert np.allclose(seen, widths, atol=0.06)
    assert np.corrcoef(seen, widths)[0, 1] > 0.8


def test_tempo_drifts_slowly(long_records):
    sim = long_records["tempo"]
    frequency = _whole_cycles(sim)["f_b"].to_numpy()
    assert np.corrcoef(frequency[:-1], frequency[1:])[0, 1] > 0.8
    fb_sd_of_jumps = 0.03 * sim.truth["f_b"]
    assert np.ptp(frequency) > 3.0 * fb_sd_of_jumps
    assert np.allclose(sim.cycles["a1"], sim.cycles["a1"].iloc[0])  # no coefficient jitter
    assert sim.truth["variations"]["coef_variation"] == 0.0
    force = sim.states["force_bio"].to_numpy() / G
    assert np.max(np.abs(np.diff(force))) < 0.15  # continuous: no jump at the cycle boundaries


@pytest.mark.parametrize("name", NEW)
def test_effects_work_with_the_new_generators(name):
    effects = {"cubic_stiffness": {"beta_3": 400}, "floor_mode": {"frequency": 3.48}}
    sim = simulate_bouncing(duration=3.0, seed=2, variation=name, effects=effects)
    assert {"z", "z_dot", "z_ddot"} <= set(sim.states.columns) and sim.record.floor_acc is not None
    assert set(sim.truth["effects"]) == {"cubic_stiffness", "floor_mode"}
    if name == "pulses":
        with pytest.raises(OptionError, match="harmonics effect") as info:
            simulate_bouncing(duration=3.0, seed=2, variation=name, effects=["harmonics:blf=0.04/0.03"])
        assert "\n" not in str(info.value)
    else:
        sim = simulate_bouncing(duration=3.0, seed=2, variation=name, effects=["harmonics:blf=0.04/0.03"])
        assert "blf6" in sim.cycles.columns and sim.truth["n_force_harmonics"] == 6


def test_bad_options_of_the_new_generators_are_one_line_errors():
    cases = [
        (dict(variation="pulses", phases=[0.0, 0.0, 0.0, 0.0]), "phases"),
        (dict(variation="pulses", blf=[1.2, 0.1]), "blf"),
        (dict(variation="pulses", blf=[0.6, 0.1], f_h=3.0), "GRF falls below zero"),
        (dict(variation="tempo", fb_variation=0.15), "fb_variation"),
    ]
    for kwargs, word in cases:
        with pytest.raises(OptionError, match=word) as info:
            simulate_bouncing(duration=3.0, seed=1, **kwargs)
        assert "\n" not in str(info.value)


def test_command_line_names_every_generator(tmp_path, capsys):
    from smd_statespace.cli import main

    argv = ["simulate", "--mass", "70", "--fb", "2", "--fh", "2.5", "--xi", "0.3", "--duration", "3", "--seed", "1",
            "--out", str(tmp_path / "r.csv")]
    for name in ("jumps", "pulses"):
        assert main(argv + ["--variation", name]) == 0
        assert f"{name} variation" in capsys.readouterr().out
        assert json.loads((tmp_path / "r_truth.json").read_text())["variations"]["generator"] == name


def test_matern_generator_has_the_record_models_covariance_and_smooth_keeps_its_own():
    # the processes of "matern" (exponential kernel) have the Matern-3/2 autocorrelation (1 + x) exp(-x) of the
    # record-level model's smooth variation at the correlation time of "smooth"; "smooth" keeps exp(-tau^2 / C^2)
    from smd_statespace.simulation.variation import (MATERN_E_FOLD, SMOOTH_CORRELATION_CYCLES, SMOOTH_GRID,
                                                     _smooth_normals)
    knots = np.random.default_rng(np.random.SeedSequence(17)).standard_normal((40000, 1))
    lags = np.array([1, 2, 3])  # cycles (one knot per mean cycle)
    x = lags * MATERN_E_FOLD / SMOOTH_CORRELATION_CYCLES
    expected = {"exponential": (1 + x) * np.exp(-x), "gaussian": np.exp(-(lags / SMOOTH_CORRELATION_CYCLES) ** 2)}
    for kernel, reach in (("exponential", 14), ("gaussian", 8)):
        values = _smooth_normals(knots, reach, kernel)[:, 0]
        measured = np.array([np.corrcoef(values[:-k], values[k:])[0, 1] for k in lags * SMOOTH_GRID])
        np.testing.assert_allclose(measured, expected[kernel], atol=0.03)
    assert abs(expected["exponential"][0] - expected["gaussian"][0]) > 0.05  # the two shapes are told apart
    sim = simulate_bouncing(duration=5.0, seed=4, variation="matern")
    assert sim.truth["variations"]["generator"] == "matern"
    assert sim.truth["variations"]["correlation_cycles"] == SMOOTH_CORRELATION_CYCLES
    assert not np.allclose(sim.record.force, simulate_bouncing(duration=5.0, seed=4, variation="smooth").record.force)
