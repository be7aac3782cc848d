"""The model check's array tools (smd_statespace.diagnostics: spectra, correlation, phase, subspace, residual tests)
against results known in closed form."""

import numpy as np
import pytest

from smd_statespace.diagnostics.correlation import cross_correlation_table, multiple_correlation, pearson_correlation
from smd_statespace.diagnostics.phase import harmonic_regressors, phase_locked, phase_profile
from smd_statespace.diagnostics.residual_tests import (cycle_numbers, default_lags, ljung_box_table, pooled_acf,
                                                       split_cycles)
from smd_statespace.diagnostics.spectra import residual_spectrum, welch_dof
from smd_statespace.diagnostics.subspace import chain_sensitivity, orthonormal_columns, remove_projections
from smd_statespace.errors import OptionError


def test_a_sinusoid_in_white_noise_is_the_top_peak_at_its_frequency():
    rng = np.random.default_rng(0)
    fs, f_b, n = 100.0, 2.0, 6000
    t = np.arange(n) / fs
    x = 0.5 * np.sin(2 * np.pi * 7.3 * t) + 0.1 * rng.standard_normal(n)
    freq, psd, peaks = residual_spectrum(x, fs, f_b)
    assert freq[1] - freq[0] == pytest.approx(f_b / 6, rel=0.01)  # six cycles per segment
    assert peaks.loc[0, "frequency"] == pytest.approx(7.3, abs=0.05)
    assert peaks.loc[0, "label"] == "non-harmonic"
    x = 0.5 * np.sin(2 * np.pi * 3 * f_b * t) + 0.1 * rng.standard_normal(n)
    assert residual_spectrum(x, fs, f_b)[2].loc[0, "label"] == "harmonic 3"
    # white noise alone: no peak at the 1 % false-alarm level, most of the time
    assert len(residual_spectrum(0.1 * rng.standard_normal(n), fs, f_b)[2]) <= 1


def test_welch_dof_is_two_per_segment_without_overlap_correction_for_one_segment():
    assert welch_dof(100, 100) == pytest.approx(2.0)
    assert 2 * 3 > welch_dof(200, 100) > 2 * 2  # three overlapping segments: between 4 and 6


def test_correlations_of_a_known_linear_combination():
    rng = np.random.default_rng(1)
    a, b = rng.standard_normal((2, 500))
    assert pearson_correlation(a, 3 * a + 1) == pytest.approx(1.0)
    assert pearson_correlation(a, -a) == pytest.approx(-1.0)
    assert np.isnan(pearson_correlation(a, np.ones(500)))
    assert multiple_correlation(2 * a - b, np.column_stack([a, b])) == pytest.approx(1.0)
    # half the variance from a: R^2 = 1/2
    assert multiple_correlation(a + b, a[:, None]) ** 2 == pytest.approx(0.5, abs=0.08)


def test_cross_correlation_table_finds_a_lagged_candidate():
    rng = np.random.default_rng(2)
    record = rng.standard_normal(400)
    sample_index = np.arange(50, 350)
    target = record[sample_index - 3]  # the candidate leads by 3 samples
    table = cross_correlation_table(target, {"lead": record, "noise": rng.standard_normal(400)}, sample_index, 400,
                                    fs=100.0, max_lag_s=0.05)
    assert table.loc[0, "signal"] == "lead"
    assert table.loc[0, "corr"] == pytest.approx(1.0)
    assert table.loc[0, "lag_s"] == pytest.approx(0.03)
    with pytest.raises(OptionError, match="shape"):
        cross_correlation_table(target, {"short": record[:10]}, sample_index, 400, fs=100.0)


def test_phase_locked_part_and_profile_of_a_signal_locked_to_the_phase():
    rng = np.random.default_rng(3)
    phase = np.tile(np.linspace(0.0, 1.0, 50, endpoint=False), 20)
    locked = 2.0 * np.cos(2 * np.pi * 2 * phase)
    noise = 0.1 * rng.standard_normal(phase.size)
    fitted = phase_locked(locked + noise, phase, orders=4)
    assert np.sqrt(np.mean((fitted - locked) ** 2)) < 0.03
    profile = phase_profile(locked, phase, weight=100.0, n_cycles=20, bins=10)
    assert profile["n"].sum() == phase.size
    assert profile["mean"].to_numpy() == pytest.approx(
        [locked[(phase >= lo) & (phase < hi)].mean() for lo, hi in zip(profile["phase_low"], profile["phase_high"])])
    assert profile["mean_bw"].to_numpy() == pytest.approx(profile["mean"].to_numpy())  # weight 100 N: % = N
    with pytest.raises(OptionError):
        phase_profile(locked, phase, 100.0, 20, bins=0)


def test_removing_the_harmonic_basis_leaves_only_what_it_cannot_fit():
    theta = np.linspace(0, 2 * np.pi, 60, endpoint=False)
    basis = orthonormal_columns(harmonic_regressors(theta, [1, 2]))
    assert basis.shape == (60, 5)
    assert basis.T @ basis == pytest.approx(np.eye(5))
    signal = 1.0 + np.cos(theta) - 0.5 * np.sin(2 * theta)
    other = np.cos(5 * theta)
    left = remove_projections(np.r_[signal + other, signal], [(slice(0, 60), basis)])
    assert left[:60] == pytest.approx(other, abs=1e-12)
    assert left[60:] == pytest.approx(signal)  # rows in no block are kept
    assert orthonormal_columns(np.zeros((4, 2))).shape == (4, 0)


def test_chain_sensitivity_of_a_linear_system_is_its_impulse_response():
    a = np.array([[0.9, 0.1], [0.0, 0.8]])
    h = np.array([1.0, 0.0])
    m = 6
    rows = chain_sensitivity(np.repeat(a[None], m - 1, axis=0), np.repeat(h[None], m, axis=0))
    assert rows == pytest.approx(np.array([h @ np.linalg.matrix_power(a, k) for k in range(m)]))


def test_ljung_box_per_cycle_pieces_add_up():
    rng = np.random.default_rng(4)
    cycle_index = np.repeat([3, 4, 5], 60)
    values = rng.standard_normal(cycle_index.size)
    pieces = split_cycles(values, cycle_index)
    assert [p.size for p in pieces] == [60, 60, 60]
    assert cycle_numbers(cycle_index) == [3, 4, 5]
    assert default_lags(pieces) == 15
    table = ljung_box_table(pieces, cycle_numbers(cycle_index), 10)
    assert list(table.index) == [3, 4, 5, "combined"]
    assert table.loc["combined", "lb_stat"] == pytest.approx(table["lb_stat"].iloc[:3].sum())
    assert table.loc["combined", "lags"] == 30
    acf = pooled_acf(pieces, 5)
    assert acf[0] == pytest.approx(1.0) and np.all(np.abs(acf[1:]) < 0.2)
