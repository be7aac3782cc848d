"""Estimators against exact Kalman filtering on the linear sub-case, and recovery of known truth."""

import numpy as np
import pytest

from smd_statespace.errors import CycleError, OptionError
from smd_statespace.estimators import CycleData, EstimatorFailure, GaussianStart, get_estimator
from smd_statespace.estimators.particle import reflect, systematic_resample
from smd_statespace.io import G
from smd_statespace.model import SMDModel

from helpers import FIXED, linear_case, synthesize, textbook_kalman, truth_state, well_excited_cycle

def test_grid_equals_textbook_kalman_filter_on_linear_subcase():
    model, data = linear_case("euler")
    grid = get_estimator("grid")
    result = grid.run(model, data, fixed=FIXED)
    from smd_statespace.estimators.base import prepare

    setup = prepare(model, data, FIXED)
    x, P, total = textbook_kalman(model, data, setup.prior_mean, setup.prior_cov, setup.q_std, setup.r_std, FIXED)
    free = [i for i, name in enumerate(model.state_names) if name not in FIXED]
    np.testing.assert_allclose(result.final_mean[free], x, rtol=1e-7, atol=1e-10)
    np.testing.assert_allclose(result.final_std[free], np.sqrt(np.diag(P)), rtol=1e-6)
    assert result.log_likelihood == pytest.approx(total, rel=1e-9)


@pytest.mark.parametrize("name", ["ukf", "ekf"])
@pytest.mark.parametrize("discretisation", ["rk4", "euler"])
def test_kalman_type_filters_match_exact_filter_on_linear_subcase(name, discretisation):
    model, data = linear_case(discretisation)
    exact = get_estimator("grid").run(model, data, fixed=FIXED)
    result = get_estimator(name).run(model, data, fixed=FIXED)
    assert result.log_likelihood == pytest.approx(exact.log_likelihood, rel=1e-6)
    np.testing.assert_allclose(result.mean, exact.mean, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(result.std, exact.std, rtol=1e-5, atol=1e-12)
    np.testing.assert_allclose(result.innovations, exact.innovations, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(result.innovation_cov, exact.innovation_cov, rtol=1e-6, atol=1e-12)


def test_particle_filter_log_likelihood_agrees_within_monte_carlo_error():
    """Bootstrap PF vs exact Kalman filter on a linear sub-case (u, u_dot, a1 free; both from one Gaussian start).

    The particle estimate of the likelihood is unbiased, so the log of it is
    biased low by about half its variance: compare ``mean + var / 2`` with the
    exact value, within three standard errors. (With more free coefficients the
    bootstrap filter degenerates after one step and needs far more particles:
    docs/benchmarks.md.)
    """
    model = SMDModel(n_harmonics=1)
    x0 = truth_state(model, coefficients=(0.01, 0.2, -0.05))
    data, _ = synthesize(model, x0, seed=4, r_std=np.array([0.002, 0.02, 0.4]))
    fixed = dict(FIXED, a0=0.01, b1=-0.05)
    from smd_statespace.estimators.base import prepare

    noise = dict(observation_noise_std=[0.004, 0.04, 0.8])
    setup = prepare(model, data, fixed, **noise)
    start = GaussianStart(setup.prior_mean, setup.prior_cov)
    exact = get_estimator("grid", **noise).run(model, data, fixed=fixed, start=start)
    pf = get_estimator("pf", n_particles=20000, **noise)
    runs = [pf.run(model, data, start=start, fixed=fixed, rng=np.random.default_rng(s)) for s in range(8)]
    values = np.array([r.log_likelihood for r in runs])
    corrected = values.mean() + values.var(ddof=1) / 2
    standard_error = values.std(ddof=1) / np.sqrt(len(values))
    assert values.std(ddof=1) < 2.0, values
    assert abs(corrected - exact.log_likelihood) < 3 * standard_error + 0.05, (values, exact.log_likelihood)
    means = np.array([r.final_mean for r in runs])
    free = [model.index(n) for n in ("u", "u_dot", "a1")]
    error = np.abs(means.mean(axis=0) - exact.final_mean)[free]
    assert np.all(error < 4 * means.std(axis=0, ddof=1)[free] / np.sqrt(len(runs)) + 0.2 * exact.final_std[free])


RECOVERY = [("grid", {}, 4), ("ukf", {}, 4), ("ekf", {}, 4), ("rbpf", {"n_particles": 300}, 4)]


@pytest.mark.parametrize("name,options,harmonics", RECOVERY)
@pytest.mark.parametrize("f_h,xi_h,seed", [(2.6, 0.25, 3), (1.8, 0.45, 5)])
def test_recovers_known_parameters_on_well_excited_cycle(name, options, harmonics, f_h, xi_h, seed):
    model, data, truth = well_excited_cycle(seed=seed, f_h=f_h, xi_h=xi_h, n_harmonics=harmonics)
    estimator = get_estimator(name, **options)
    result = estimator.run(model, data, rng=np.random.default_rng(7))
    for p in range(3 if estimator.supports_passes else 0):
        result = estimator.run(model, data, start=result.restart, rng=np.random.default_rng(8 + p))
    i_f, i_xi = model.index("f_h"), model.index("xi_h")
    assert abs(result.final_mean[i_f] - truth[i_f]) < 0.1 * truth[i_f]
    assert abs(result.final_mean[i_xi] - truth[i_xi]) < 0.1
    assert result.width_ratio()[i_f] < 0.3


# The article's plain particle filter samples every slot; with n = 4 harmonics its 13-dimensional
# cloud collapses onto wrong coefficients (docs/benchmarks.md measures it), so its recovery is
# tested where a bootstrap filter is expected to work: one harmonic, 7 slots. Even there a run is
# a draw: over 30 seeds, 5000 particles recovered f_h within 10 % in about half of the runs, 20000
# particles in 75-85 % (docs/performance.md). So: most of six seeded runs must recover.
@pytest.mark.parametrize("f_h,xi_h,seed", [(2.6, 0.25, 3), (1.8, 0.45, 5)])
def test_particle_filter_recovers_known_parameters_in_most_runs(f_h, xi_h, seed):
    model, data, truth = well_excited_cycle(seed=seed, f_h=f_h, xi_h=xi_h, n_harmonics=1)
    pf = get_estimator("pf", n_particles=20000)
    i_f, i_xi = model.index("f_h"), model.index("xi_h")
    recovered = 0
    for run in range(6):
        result = pf.run(model, data, rng=np.random.default_rng(7 + 100 * run))
        for p in range(3):
            result = pf.run(model, data, start=result.restart, rng=np.random.default_rng(8 + p + 100 * run))
        recovered += bool(abs(result.final_mean[i_f] - truth[i_f]) < 0.1 * truth[i_f]
                          and abs(result.final_mean[i_xi] - truth[i_xi]) < 0.1 and result.width_ratio()[i_f] < 0.3)
    assert recovered >= 3, recovered


def test_grid_posterior_concentrates_at_truth():
    model, data, truth = well_excited_cycle()
    grid = get_estimator("grid", f_h_points=81, xi_h_points=61)
    result = grid.run(model, data)
    best = np.unravel_index(np.argmax(grid.posterior_), grid.posterior_.shape)
    assert abs(grid.f_h_grid_[best[0]] - truth[2]) < 0.05
    assert abs(grid.xi_h_grid_[best[1]] - truth[3]) < 0.05
    assert grid.posterior_.sum() == pytest.approx(1.0)
    z = (result.final_mean[2] - truth[2]) / result.final_std[2]
    assert abs(z) < 3


def test_periodic_cycle_does_not_determine_f_h():
    """A cycle at exact steady state: the free force absorbs f_h (notes: 'not identifiable')."""
    model = SMDModel(n_harmonics=2)
    f_h, xi_h, f_b = 2.5, 0.3, 2.0
    a = np.array([0.2, 0.1])
    w, wb = 2 * np.pi * f_h, 2 * np.pi * f_b
    # Steady-state displacement of each harmonic, u = Re[U e^{i k wb t}], force g a_k cos(k wb t).
    U = [G * a[k] / (w**2 - ((k + 1) * wb) ** 2 + 2j * xi_h * w * (k + 1) * wb) for k in range(2)]
    u0 = sum(np.real(U))
    v0 = sum(np.real(1j * (k + 1) * wb * U[k]) for k in range(2))
    x0 = truth_state(model, f_h, xi_h, u0, v0, coefficients=(0.0, a[0], 0.0, a[1], 0.0))
    data, _ = synthesize(model, x0, f_b=f_b, samples=51, seed=2, r_std=np.array([2e-4, 3e-3, 0.05]))
    result = get_estimator("grid").run(model, data)
    assert result.width_ratio()[model.index("f_h")] > 0.5
    well_model, well_data, _ = well_excited_cycle()
    assert get_estimator("grid").run(well_model, well_data).width_ratio()[2] < 0.2


def test_same_seed_same_result_and_different_seed_differs():
    model, data, _ = well_excited_cycle()
    for name in ("pf", "rbpf"):
        check_seeded(get_estimator(name, n_particles=200), model, data)


def check_seeded(pf, model, data):
    first = pf.run(model, data, rng=np.random.default_rng(11))
    second = pf.run(model, data, rng=np.random.default_rng(11))
    third = pf.run(model, data, rng=np.random.default_rng(12))
    np.testing.assert_array_equal(first.mean, second.mean)
    assert first.log_likelihood == second.log_likelihood
    assert not np.array_equal(first.mean, third.mean)


def test_all_estimators_return_the_same_result_type():
    model, data, _ = well_excited_cycle(samples=30)
    shapes = set()
    for name in ("pf", "ukf", "ekf", "rbpf", "grid"):
        r = get_estimator(name, **({"n_particles": 300} if "pf" in name else {})).run(
            model, data, rng=np.random.default_rng(0))
        shapes.add((r.mean.shape, r.std.shape, r.innovations.shape, r.innovation_cov.shape, r.estimator == name))
        assert np.isfinite(r.log_likelihood)
    assert shapes == {((30, 13), (30, 13), (30, 3), (30, 3, 3), True)}


class DivergingModel(SMDModel):
    """A model whose predictions overflow from t = 0.1 s on (a diverging cycle)."""

    def observe(self, x, t, inputs):
        predicted = super().observe(x, t, inputs)
        return predicted * (np.inf if t >= 0.1 - 1e-9 else 1.0)


@pytest.mark.parametrize("name", ["pf", "rbpf", "ukf", "ekf", "grid"])
def test_numerical_failure_is_a_contained_estimator_failure(name):
    _, data, _ = well_excited_cycle(samples=20)
    options = {"n_particles": 50} if "pf" in name else {}
    with pytest.raises(EstimatorFailure, match="sample 10|diverged|non-finite|not positive definite"):
        get_estimator(name, **options).run(DivergingModel(), data, rng=np.random.default_rng(0))


def test_non_finite_observations_are_rejected():
    model, data, _ = well_excited_cycle(samples=20)
    broken = CycleData(t=data.t, y=data.y.copy(), inputs=data.inputs)
    broken.y[10, 2] = np.nan
    with pytest.raises(CycleError, match="row 10"):
        get_estimator("ekf").run(model, broken)


def test_resampling_edge_cases():
    rng = np.random.default_rng(0)
    equal = systematic_resample(np.full(8, 1 / 8), rng)
    np.testing.assert_array_equal(np.sort(equal), np.arange(8))
    one = np.zeros(8)
    one[5] = 1.0
    np.testing.assert_array_equal(systematic_resample(one, rng), np.full(8, 5))
    values = np.array([[1.2, -0.1], [4.3, 1.05], [0.7, 0.5]])
    out = reflect(values.copy(), np.array([1.0, 0.0]), np.array([4.0, 1.0]))
    np.testing.assert_allclose(out, [[1.2, 0.1], [3.7, 0.95], [1.3, 0.5]])


def test_bad_estimator_options():
    with pytest.raises(OptionError, match="unknown estimator 'kf'"):
        get_estimator("kf")
    with pytest.raises(OptionError, match="n_particles"):
        get_estimator("pf", n_particles=0)
    with pytest.raises(OptionError, match="n_particles"):
        get_estimator("pf", n_particles=-5)
    with pytest.raises(OptionError, match="unexpected keyword"):
        get_estimator("ukf", particles=5)


def test_vectorised_ukf_equals_filterpy_loop():
    model, data, _ = well_excited_cycle(samples=30)
    looped = get_estimator("ukf", vectorised=False).run(model, data)
    batched = get_estimator("ukf").run(model, data)
    np.testing.assert_allclose(batched.mean, looped.mean, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(batched.std, looped.std, rtol=1e-10, atol=1e-14)
    assert batched.log_likelihood == pytest.approx(looped.log_likelihood, rel=1e-12)


@pytest.mark.parametrize("name", ["pf", "ukf", "ekf", "grid", "rbpf"])
def test_cycle_too_short_for_the_model_is_a_clear_error(name):
    model, data, _ = well_excited_cycle(samples=20)
    short = CycleData(t=data.t[:2], y=data.y[:2], inputs=data.inputs, index=7)
    with pytest.raises(CycleError, match="cycle 7: 2 samples; an estimator needs at least 3"):
        get_estimator(name, **({"n_particles": 20} if "pf" in name else {})).run(model, short)
