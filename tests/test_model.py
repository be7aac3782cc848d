"""The augmented-state model against the article's equations and analytic solutions."""

import numpy as np
import pytest

from smd_statespace import OptionError
from smd_statespace.effects import CubicStiffness, Harmonics, make_effect
from smd_statespace.io import G
from smd_statespace.model import CycleInputs, SMDModel, blf, c_h, k_h

from helpers import finite_difference, random_states

INPUTS = CycleInputs(f_b=2.1, t0=0.3)


def test_eq17_eq18_article_check_values():
    assert k_h(1.784, 57.4) == pytest.approx(7212.1, abs=0.1)
    assert c_h(0.568, 1.784, 57.4) == pytest.approx(730.9, abs=0.1)
    assert blf(0.3, -0.4) == pytest.approx(0.5)


def test_state_layout_follows_eq7():
    model = SMDModel(n_harmonics=4)
    assert model.state_names == ("u", "u_dot", "f_h", "xi_h", "a0", "a1", "b1", "a2", "b2", "a3", "b3", "a4", "b4")
    assert model.n_state == 13
    assert model.index("f_h") == 2 and model.index("b4") == 12
    assert SMDModel(n_harmonics=2).n_state == 9
    with pytest.raises(OptionError, match="no state slot 'a9'"):
        model.index("a9")


def test_rate_is_eq10_written_out():
    model = SMDModel(n_harmonics=3)
    rng = np.random.default_rng(1)
    x = random_states(model, rng, 4)
    t = 0.77
    u, v, f, xi = x[:, 0], x[:, 1], x[:, 2], x[:, 3]
    w = 2 * np.pi * f
    theta = 2 * np.pi * INPUTS.f_b * (t - INPUTS.t0)
    forcing = x[:, 4] + sum(
        x[:, 3 + 2 * i] * np.cos(i * theta) + x[:, 4 + 2 * i] * np.sin(i * theta) for i in range(1, 4)
    )
    expected_acc = -(w**2) * u - 2 * xi * w * v + G * forcing
    rate = model.rate(x, t, INPUTS)
    np.testing.assert_allclose(rate[:, 0], v)
    np.testing.assert_allclose(rate[:, 1], expected_acc, rtol=1e-12)
    np.testing.assert_array_equal(rate[:, 2:], 0.0)
    np.testing.assert_allclose(model.observe(x, t, INPUTS), np.stack([u, v, expected_acc], axis=1), rtol=1e-12)


def test_euler_transition_is_eq11_12():
    model = SMDModel(discretisation="euler")
    x = random_states(model, np.random.default_rng(2), 3)
    dt = 0.01
    expected = x + dt * model.rate(x, 0.4, INPUTS)
    np.testing.assert_allclose(model.transition(x, 0.4, dt, INPUTS), expected)


MODELS = {
    "base-rk4": lambda: SMDModel(),
    "base-euler": lambda: SMDModel(discretisation="euler"),
    "rk4-substeps": lambda: SMDModel(substeps=3, n_harmonics=2),
    "acc-only": lambda: SMDModel(observation="acc"),
    "effects": lambda: SMDModel(effects=[Harmonics(2), CubicStiffness()]),
}


@pytest.mark.parametrize("name", sorted(MODELS))
def test_jacobians_match_finite_differences(name):
    model = MODELS[name]()
    rng = np.random.default_rng(3)
    x = random_states(model, rng, 1)[0]
    t, dt = 0.55, 0.01
    np.testing.assert_allclose(
        model.rate_jacobian(x, t, INPUTS), finite_difference(lambda z: model.rate(z, t, INPUTS), x),
        rtol=1e-6, atol=1e-6,
    )
    np.testing.assert_allclose(
        model.transition_jacobian(x, t, dt, INPUTS),
        finite_difference(lambda z: model.transition(z, t, dt, INPUTS), x),
        rtol=1e-6, atol=1e-8,
    )
    np.testing.assert_allclose(
        model.observation_jacobian(x, t, INPUTS), finite_difference(lambda z: model.observe(z, t, INPUTS), x),
        rtol=1e-6, atol=1e-6,
    )


@pytest.mark.parametrize("name", sorted(MODELS))
def test_vectorised_over_leading_axes(name):
    model = MODELS[name]()
    cloud = random_states(model, np.random.default_rng(4), 5000)
    t, dt = 0.2, 0.01
    moved = model.transition(cloud, t, dt, INPUTS)
    observed = model.observe(cloud, t, INPUTS)
    assert moved.shape == cloud.shape and observed.shape == (5000, model.n_obs)
    for i in (0, 1234, 4999):
        np.testing.assert_allclose(moved[i], model.transition(cloud[i], t, dt, INPUTS), rtol=1e-13)
        np.testing.assert_allclose(observed[i], model.observe(cloud[i], t, INPUTS), rtol=1e-13)
    jac = model.transition_jacobian(cloud[:7].reshape(7, 1, -1), t, dt, INPUTS)
    assert jac.shape == (7, 1, model.n_state, model.n_state)
    np.testing.assert_allclose(jac[3, 0], model.transition_jacobian(cloud[3], t, dt, INPUTS), rtol=1e-13)


def free_vibration(f_h, xi, u0, v0, t):
    """Analytic free response of an underdamped oscillator."""
    w = 2 * np.pi * f_h
    wd = w * np.sqrt(1 - xi**2)
    decay = np.exp(-xi * w * t)
    return decay * (u0 * np.cos(wd * t) + (v0 + xi * w * u0) / wd * np.sin(wd * t))


@pytest.mark.parametrize("f_h,xi", [(1.5, 0.1), (3.8, 0.05), (2.5, 0.6)])
def test_discretisations_against_analytic_free_vibration(f_h, xi):
    """RK4 tracks the analytic oscillator closely; Euler (Eq. 11-12) drifts, as the notes warn."""
    dt, steps = 0.01, 100
    t = np.arange(steps + 1) * dt
    exact = free_vibration(f_h, xi, 0.03, 0.0, t)
    errors = {}
    for scheme in ("rk4", "euler"):
        model = SMDModel(discretisation=scheme)
        x = np.zeros(model.n_state)
        x[[0, 2, 3]] = 0.03, f_h, xi
        path = [x[0]]
        for k in range(steps):
            x = model.transition(x, t[k], dt, INPUTS)
            path.append(x[0])
        errors[scheme] = np.max(np.abs(np.array(path) - exact)) / 0.03
    # RK4's phase error per step is about (omega dt)^5 / 120, i.e. 1e-5 .. 2e-4 of the
    # amplitude over these 100 steps; Euler's amplitude error is of order (omega dt)^2 / 2 per step.
    assert errors["rk4"] < 1e-3
    assert errors["euler"] > 100 * errors["rk4"]


def test_rk4_forced_steady_state_matches_frequency_response():
    """Drive with one harmonic; the steady acceleration amplitude is |H| g BLF."""
    f_h, xi, f_b, a1 = 2.5, 0.3, 2.0, 0.2
    inputs = CycleInputs(f_b=f_b)
    model = SMDModel(n_harmonics=1)
    x = np.zeros(model.n_state)
    x[[2, 3, model.index("a1")]] = f_h, xi, a1
    dt = 0.005
    t = np.arange(0, 12, dt)
    acc = []
    for tk in t:
        acc.append(model.acceleration(x, tk, inputs))
        x = model.transition(x, tk, dt, inputs)
    acc = np.array(acc)[t > 8]
    w, wb = 2 * np.pi * f_h, 2 * np.pi * f_b
    expected = abs(-(wb**2) / (w**2 - wb**2 + 2j * xi * w * wb)) * G * a1
    assert np.max(np.abs(acc)) == pytest.approx(expected, rel=2e-3)


def test_zero_magnitude_effects_leave_model_unchanged():
    base = SMDModel()
    extended = base.with_effects(Harmonics(2), CubicStiffness())
    rng = np.random.default_rng(5)
    x_base = random_states(base, rng, 10)
    x_ext = np.concatenate([x_base, np.zeros((10, 5))], axis=1)
    np.testing.assert_allclose(extended.observe(x_ext, 0.3, INPUTS), base.observe(x_base, 0.3, INPUTS))
    np.testing.assert_allclose(
        extended.transition(x_ext, 0.3, 0.01, INPUTS)[:, : base.n_state], base.transition(x_base, 0.3, 0.01, INPUTS)
    )
    assert extended.state_names[base.n_state:] == ("a5", "b5", "a6", "b6", "beta_3")


def test_hardening_spring_raises_restoring_force():
    model = SMDModel(effects=[CubicStiffness()])
    x = np.zeros(model.n_state)
    x[[0, 2, 3]] = 0.05, 2.0, 0.0
    linear = model.acceleration(x, 0.0, INPUTS)
    x[model.index("beta_3")] = 400.0
    hard = model.acceleration(x, 0.0, INPUTS)
    assert hard == pytest.approx(linear * (1 + 400.0 * 0.05**2))


def test_duplicate_states_and_bad_options_are_clear_errors():
    with pytest.raises(OptionError, match="given twice"):
        SMDModel(effects=[Harmonics(1), Harmonics(2)])
    with pytest.raises(OptionError, match="discretisation 'trapezoid' is unknown"):
        SMDModel(discretisation="trapezoid")
    with pytest.raises(OptionError, match="n_harmonics"):
        SMDModel(n_harmonics=0)
    with pytest.raises(OptionError, match="unknown effect 'floor'"):
        make_effect("floor")
    with pytest.raises(OptionError, match="unknown option 'size'"):
        make_effect("harmonics:size=2")
    assert make_effect("harmonics:count=3").count == 3


def test_noise_defaults_and_prior():
    model = SMDModel()
    rng = np.random.default_rng(6)
    y = rng.normal(size=(60, 3)) * [0.02, 0.2, 3.0]
    scale = model.data_scale(y, INPUTS)
    np.testing.assert_allclose(model.observation_noise_std(scale), 0.1 * np.sqrt(np.mean(y**2, axis=0)))
    q = model.process_noise_std(scale)
    assert q[model.index("f_h")] == pytest.approx(0.01 * 2.5)
    assert q[model.index("xi_h")] == pytest.approx(0.01 * 0.5)
    assert q[model.index("a3")] == pytest.approx(0.01 * 0.2)
    assert q[model.index("u")] == pytest.approx(0.01 * scale["u"])
    prior = model.prior(y[0], scale)
    draws = prior.sample(rng, 20000)
    assert draws[:, 2].min() >= 1.0 and draws[:, 2].max() <= 4.0
    assert draws[:, model.index("b2")].min() < -0.35 and draws[:, model.index("b2")].max() > 0.35
    assert np.all(np.abs(draws.mean(axis=0) - prior.mean) < 4 * prior.std / np.sqrt(20000))
    np.testing.assert_allclose(draws.std(axis=0), prior.std, rtol=0.03)
    assert prior.mean[0] == pytest.approx(y[0, 0])
    custom = SMDModel(coefficient_range=(0.0, 0.4), f_h_range=(1.5, 3.0))
    assert custom.prior(y[0], scale).mean[custom.index("a1")] == pytest.approx(0.2)


def test_derived_quantities_from_states():
    model = SMDModel(n_harmonics=2)
    x = np.zeros((2, model.n_state))
    x[:, 2], x[:, 3] = [1.784, 2.0], [0.568, 0.3]
    x[:, model.index("a1")], x[:, model.index("b1")] = 0.3, 0.4
    out = model.derived(x, 57.4)
    assert out["k_h"][0] == pytest.approx(7212.1, abs=0.1)
    assert out["c_h"][0] == pytest.approx(730.9, abs=0.1)
    np.testing.assert_allclose(out["blf_1"], 0.5)
    np.testing.assert_allclose(out["blf_2"], 0.0)


@pytest.mark.parametrize("text", ["harmonics", "harmonics:count=3", "cubic_stiffness:beta_range=-500/1500",
                                  "floor_mode", "floor_mode:source=modal,frequency_range=3/4.5",
                                  "floor_mode:source=modal,frequency=9.187,damping=0.01,mass_ratio=0.02"])
def test_effect_spec_builds_the_same_effect(text):
    """``effect.spec`` is what ``--effect`` needs to rebuild it (the diagnosis prints it as the next command)."""
    effect = make_effect(text)
    again = make_effect(effect.spec)
    assert type(again) is type(effect) and repr(again) == repr(effect)
    assert SMDModel(effects=[again]).state_names == SMDModel(effects=[effect]).state_names
    assert again.constants == effect.constants


def test_known_floor_mode_reports_its_constants():
    effect = make_effect("floor_mode:source=modal,frequency=9.2,damping=0.01,mass_ratio=0.02")
    assert effect.constants == {"f_f": 9.2, "xi_f": 0.01, "mass_ratio": 0.02}
    assert make_effect("floor_mode:source=modal,frequency=9.2").constants == {}
