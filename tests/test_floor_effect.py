"""The floor_mode effect: a person bouncing on a vibrating floor (Section 6)."""

import dataclasses

import numpy as np
import pytest

from smd_statespace import OptionError, signals
from smd_statespace.effects import EFFECTS, FloorMode, make_effect
from smd_statespace.estimators import cycle_data
from smd_statespace.io import G, make_record
from smd_statespace.model import CycleInputs, SMDModel
from smd_statespace.person.effect_adapter import fitted_record, record_search_size
from smd_statespace.identify.runner import CycleRunner
from smd_statespace.simulation import simulate_bouncing
from smd_statespace.simulation.effect_adapter import draw_inputs, for_simulation

from helpers import finite_difference, random_states


# A measured floor: two modes, about 1 mm and 1 cm/s, sampled finely enough that
# linear interpolation between samples is smooth at the test times.
_TIME = np.linspace(0.0, 2.0, 2001)
_Z = 8e-4 * np.sin(2 * np.pi * 3.5 * _TIME + 0.4) + 2e-4 * np.cos(2 * np.pi * 6.1 * _TIME)
_Z_DOT = np.gradient(_Z, _TIME)
MEASURED_INPUTS = CycleInputs(f_b=1.75, t0=0.3, time=_TIME, signals={"floor_disp": _Z, "floor_vel": _Z_DOT})


def modal_states(model, rng, size):
    """Realistic states of a model with an estimated floor mode (z in mm, z_dot in cm/s)."""
    x = random_states(model, rng, size)
    x[:, model.index("z")] = rng.normal(0, 1e-3, size)
    x[:, model.index("z_dot")] = rng.normal(0, 2e-2, size)
    return x


MODELS = {
    "measured-rk4": lambda: SMDModel(effects=[FloorMode()]),
    "measured-euler": lambda: SMDModel(effects=[FloorMode()], discretisation="euler"),
    "modal-rk4": lambda: SMDModel(effects=[FloorMode("modal", frequency=3.48)]),
    "modal-euler": lambda: SMDModel(effects=[FloorMode("modal")], discretisation="euler"),
    "modal-acc-substeps": lambda: SMDModel(effects=[FloorMode("modal")], observation="acc", substeps=2),
    "modal-known": lambda: SMDModel(effects=[FloorMode("modal", frequency=3.48, damping=0.004, mass_ratio=0.04)]),
}


@pytest.mark.parametrize("name", sorted(MODELS))
def test_jacobians_match_finite_differences(name):
    model = MODELS[name]()
    x = modal_states(model, np.random.default_rng(11), 1)[0] if "modal" in name else \
        random_states(model, np.random.default_rng(11), 1)[0]
    t, dt = 0.55, 0.01
    inputs = MEASURED_INPUTS
    for func, jac, atol in (
        (lambda z: model.rate(z, t, inputs), model.rate_jacobian(x, t, inputs), 1e-6),
        (lambda z: model.transition(z, t, dt, inputs), model.transition_jacobian(x, t, dt, inputs), 1e-8),
        (lambda z: model.observe(z, t, inputs), model.observation_jacobian(x, t, inputs), 1e-6),
    ):
        np.testing.assert_allclose(jac, finite_difference(func, x), rtol=1e-6, atol=atol)
    # The floor terms really enter: the acceleration depends on f_h, xi_h through z, z_dot too.
    base = SMDModel(observation=model.observation)
    assert not np.allclose(model.observe(x, t, inputs), base.observe(x[: base.n_state], t, inputs))


def test_modal_mode_is_vectorised():
    model = MODELS["modal-rk4"]()
    cloud = modal_states(model, np.random.default_rng(12), 500)
    moved = model.transition(cloud, 0.2, 0.01, MEASURED_INPUTS)
    jac = model.transition_jacobian(cloud[:4], 0.2, 0.01, MEASURED_INPUTS)
    for i in (0, 3):
        np.testing.assert_allclose(moved[i], model.transition(cloud[i], 0.2, 0.01, MEASURED_INPUTS), rtol=1e-13)
        np.testing.assert_allclose(jac[i], model.transition_jacobian(cloud[i], 0.2, 0.01, MEASURED_INPUTS),
                                   rtol=1e-13)


def test_floor_at_rest_leaves_predictions_unchanged():
    base = SMDModel()
    x = random_states(base, np.random.default_rng(13), 10)
    t, dt = 0.4, 0.01
    still = CycleInputs(f_b=1.75, t0=0.3, time=_TIME, signals={"floor_disp": 0 * _Z, "floor_vel": 0 * _Z})
    measured = base.with_effects(FloorMode())
    assert measured.n_state == base.n_state
    np.testing.assert_array_equal(measured.observe(x, t, still), base.observe(x, t, still))
    np.testing.assert_array_equal(measured.transition(x, t, dt, still), base.transition(x, t, dt, still))
    np.testing.assert_array_equal(measured.transition_jacobian(x, t, dt, still),
                                  base.transition_jacobian(x, t, dt, still))

    modal = base.with_effects(FloorMode("modal"))
    assert modal.state_names[base.n_state:] == ("z", "z_dot", "f_f", "xi_f", "mass_ratio")
    x_modal = np.concatenate([x, np.zeros((10, 5))], axis=1)
    x_modal[:, modal.index("f_f")], x_modal[:, modal.index("xi_f")] = 3.48, 0.004  # mass_ratio 0
    np.testing.assert_array_equal(modal.observe(x_modal, t, still), base.observe(x, t, still))
    moved = modal.transition(x_modal, t, dt, still)
    np.testing.assert_array_equal(moved[:, : base.n_state], base.transition(x, t, dt, still))
    np.testing.assert_array_equal(moved[:, base.n_state:], x_modal[:, base.n_state:])


def test_modal_slots_priors_and_options():
    effect = make_effect("floor_mode:source=modal,frequency=3.48")
    assert isinstance(effect, FloorMode) and effect.requires == ()
    np.testing.assert_allclose(effect.frequency_range, (3.48 * 0.85, 3.48 * 1.15))
    model = SMDModel(effects=[effect])
    slots = {slot.name: slot for slot in model.slots}
    assert [slots[n].linear for n in ("z", "z_dot", "f_f", "xi_f", "mass_ratio")] == [True, True, False, False, False]
    assert (slots["xi_f"].low, slots["xi_f"].high) == (0.001, 0.05)
    assert (slots["mass_ratio"].low, slots["mass_ratio"].high) == (0.001, 0.05)
    scale = {"u": 0.02, "u_dot": 0.2, "u_ddot": 3.0}
    prior = model.prior(np.array([0.01, 0.1, 2.0]), scale)
    # The unobserved floor state is spread by its own nominal, not the person's 2 cm.
    assert prior.std[model.index("z")] == pytest.approx(1e-3)
    assert prior.std[model.index("z_dot")] == pytest.approx(1e-2)
    assert prior.mean[model.index("f_f")] == pytest.approx(3.48)
    assert model.process_noise_std(scale)[model.index("z")] == pytest.approx(1e-5)

    default = make_effect("floor_mode:source=modal")
    assert default.frequency_range == (2.0, 20.0)
    custom = make_effect("floor_mode:source=modal,frequency_range=3/4,mass_ratio_range=0.01/0.2,displacement=5e-4")
    assert custom.frequency_range == (3.0, 4.0) and custom.mass_ratio_range == (0.01, 0.2)
    assert custom.displacement == 5e-4

    measured = make_effect("floor_mode")
    assert measured.source == "measured" and measured.requires == ("floor_disp", "floor_vel")
    assert measured.requires_columns == ("floor_acc",)
    assert EFFECTS["floor_mode"] is FloorMode and SMDModel(effects=[measured]).requires == ("floor_disp", "floor_vel")


def test_a_searched_floor_frequency_counts_its_trials():
    """diagnose tests a modal floor found as the best of its grid as that many trials (Bonferroni), or as the
    frequencies the record resolves (band x duration) where those are more; a given frequency or a measured floor
    is one."""
    from smd_statespace.person.diagnose import candidate_row

    searched = make_effect("floor_mode:source=modal")
    grid = np.geomspace(2.0, 20.0, searched._trial_count())
    assert np.all(np.diff(np.log(grid)) <= np.log1p(FloorMode.RECORD_FREQUENCY_STEP) + 1e-12)
    assert record_search_size(searched, None) == grid.size + 1 and 200 < grid.size < 260
    assert record_search_size(make_effect("floor_mode:source=modal,frequency=3.48"), None) == 1
    assert record_search_size(make_effect("floor_mode"), None) == 1
    assert record_search_size(make_effect("cubic_stiffness"), None) == 1  # the adapter's default

    class Fit:  # what candidate_row reads of a fit: LR 22 on 5 unknowns, the clean record's false floor
        effects = (searched,)
        sigma, f_h, xi_h, settled, loglike = 1.0, 2.4, 0.3, True, 11.0
        model = type("M", (), {"person_at_bound": staticmethod(lambda params: False), "approximate": False,
                               "exact": True, "n_harmonics": 4, "param_names": ["f_h", "xi_h"],
                               "delta_names": ["u0", "u_dot0"], "held_delta": ()})()
        params = None

        def effect_test(self):
            return {"lr": 22.0, "lr_df": 5, "lr_p": 5e-4}

        def effect_estimates(self):
            import pandas as pd
            return pd.DataFrame({"value": [2.46], "sd": [0.02], "unit": ["Hz"], "on_bound": [False]}, index=["f_f"])

        def test_pvalues(self):
            return {"ljung_box_p": 0.5, "ljung_box_q": 38.0, "ljung_box_lags": 38}

        def template_blf(self):
            return None

    class Base(Fit):
        effects = ()
        record = type("R", (), {"time": np.arange(500) / 100.0})()  # 5 s: the 1 % grid has more trials

    row = candidate_row(Base(), Fit(), 0.01 / 4)
    assert row["trials"] == grid.size + 1
    assert row["p_value"] == pytest.approx(min(1.0, 5.3e-4 * (grid.size + 1)), rel=0.1)
    assert not row["significant"]
    Base.record.time = np.arange(3000) / 100.0  # 30 s resolve 18 Hz / (1 / 29.99 s) = 540 frequencies
    assert searched.record_search_size(fitted_record(Base())) == 540 + 1


def test_option_errors_name_the_problem():
    with pytest.raises(OptionError, match="unknown option 'bogus'"):
        make_effect("floor_mode:bogus=1")
    with pytest.raises(OptionError, match="unknown option 'freq'"):
        FloorMode("modal", freq=3.5)
    with pytest.raises(OptionError, match="source 'floor'"):
        make_effect("floor_mode:source=floor")
    with pytest.raises(OptionError, match="'frequency' applies to source='modal' only"):
        make_effect("floor_mode:source=measured,frequency=3.48")
    assert make_effect("floor_mode:frequency=3.48").source == "modal"  # a modal option implies the modal floor
    with pytest.raises(OptionError, match="frequency_range must satisfy"):
        FloorMode("modal", frequency_range=(5.0, 4.0))
    with pytest.raises(OptionError, match="not both"):
        FloorMode("modal", frequency=3.5, frequency_range=(3.0, 4.0))
    with pytest.raises(OptionError, match="given twice"):
        SMDModel(effects=[FloorMode(), FloorMode("modal")])


def test_known_mode_moves_as_the_estimated_mode_with_those_values():
    """A known mode (constants f_f, xi_f, mass ratio) is the estimated mode with its parameter slots frozen."""
    known = SMDModel(effects=[FloorMode("modal", frequency=6.1, damping=0.005, mass_ratio=0.03)])
    estimated = SMDModel(effects=[FloorMode("modal")])
    assert known.state_names[-2:] == ("z", "z_dot") and known.n_state == estimated.n_state - 3
    x_known = modal_states(known, np.random.default_rng(3), 20)
    x_est = np.concatenate([x_known, np.tile([6.1, 0.005, 0.03], (20, 1))], axis=1)
    inputs = CycleInputs(f_b=1.75)
    for _ in range(30):
        x_known = known.transition(x_known, 0.4, 0.01, inputs)
        x_est = estimated.transition(x_est, 0.4, 0.01, inputs)
    np.testing.assert_allclose(x_known, x_est[:, :known.n_state], rtol=1e-12, atol=1e-15)
    assert np.ptp(x_known[:, known.index("z")]) > 0  # the floor really moved


def test_known_mode_options_are_checked():
    with pytest.raises(OptionError, match="needs both frequency"):
        make_effect("floor_mode:source=modal,damping=0.01")
    with pytest.raises(OptionError, match="damping_range is a prior range"):
        make_effect("floor_mode:source=modal,frequency=3,damping=0.01,damping_range=0.01/0.02")
    with pytest.raises(OptionError, match="damping must be a ratio below 1"):
        make_effect("floor_mode:source=modal,frequency=3,damping=1.5")
    with pytest.raises(OptionError, match="'damping' applies to source='modal' only"):
        make_effect("floor_mode:source=measured,damping=0.01")


def _floor_record(seed, **options):
    return simulate_bouncing(mass=70, f_b=1.75, f_h=1.8, xi_h=0.33, duration=14, seed=seed,
                             effects={"floor_mode": options})


def test_measured_mode_needs_a_floor_acc_column():
    synthetic = _floor_record(seed=4)
    bare = make_record(synthetic.record.time, synthetic.record.force, 70.0, source="bare.csv")
    pre = signals.preprocess(bare)
    model = SMDModel(effects=[FloorMode()])
    with pytest.raises(OptionError, match="floor_acc"):
        cycle_data(model, pre, pre.valid_cycles[0])
    with pytest.raises(OptionError, match="floor_acc"):
        CycleRunner(model, estimator="ekf", progress=False).run(pre)
    # The automatic choice: a record without the column gets the estimated mode.
    assert FloorMode.for_record(bare).source == "modal"
    assert FloorMode.for_record(synthetic.record).source == "measured"


def test_modal_free_vibration_conserves_coupled_energy():
    """No force, no damping: person + floor exchange energy, their sum stays put (RK4)."""
    mu, f_h, f_f = 0.05, 2.0, 3.0
    model = SMDModel(n_harmonics=1, effects=[FloorMode("modal", mass_ratio_range=(0.001, 0.1))])
    x = np.zeros(model.n_state)
    x[model.index("u")], x[model.index("f_h")] = 0.02, f_h
    x[model.index("f_f")], x[model.index("mass_ratio")] = f_f, mu  # xi_h = xi_f = 0, coefficients 0
    mass = 70.0
    m_f, k_h, k_f = mass / mu, mass * (2 * np.pi * f_h) ** 2, mass / mu * (2 * np.pi * f_f) ** 2

    def energy(state):
        u, v, z, w = (state[model.index(n)] for n in ("u", "u_dot", "z", "z_dot"))
        return 0.5 * mass * v**2 + 0.5 * m_f * w**2 + 0.5 * k_h * (u - z) ** 2 + 0.5 * k_f * z**2

    def floor_energy(state):
        z, w = state[model.index("z")], state[model.index("z_dot")]
        return 0.5 * m_f * w**2 + 0.5 * k_f * z**2

    e0, dt = energy(x), 0.005
    energies, floor_share = [], []
    for k in range(2000):
        x = model.transition(x, k * dt, dt, CycleInputs(f_b=1.75))
        energies.append(energy(x))
        floor_share.append(floor_energy(x) / e0)
    assert max(floor_share) > 0.02  # the floor really takes part
    np.testing.assert_allclose(energies, e0, rtol=5e-4)


def test_modal_steady_state_matches_two_dof_frequency_response():
    """A harmonic force on the coupled system: acceleration and floor amplitudes of the 2-DOF FRF."""
    mass, f_h, xi_h, f_f, xi_f, mu = 70.0, 2.0, 0.3, 3.5, 0.04, 0.04
    f_b, a1 = 3.3, 0.1
    model = SMDModel(n_harmonics=1, effects=[FloorMode("modal", frequency=3.5)])
    x = np.zeros(model.n_state)
    for name, value in (("f_h", f_h), ("xi_h", xi_h), ("f_f", f_f), ("xi_f", xi_f), ("mass_ratio", mu),
                        ("a1", a1)):
        x[model.index(name)] = value
    inputs = CycleInputs(f_b=f_b)
    dt = 0.004
    t = np.arange(0, 15, dt)
    acc, z = np.empty(t.size), np.empty(t.size)
    for k, tk in enumerate(t):
        acc[k], z[k] = model.acceleration(x, tk, inputs), x[model.index("z")]
        x = model.transition(x, tk, dt, inputs)

    # m_f z'' + c_f z' + k_f z = -M u'' with M u'' = -K_h (u - z) - C_h (u' - z') + M g F(t)
    m_f = mass / mu
    w_h, w_f, w = 2 * np.pi * f_h, 2 * np.pi * f_f, 2 * np.pi * f_b
    k_hum, c_hum = mass * w_h**2, 2 * xi_h * mass * w_h
    k_fl, c_fl = m_f * w_f**2, 2 * xi_f * m_f * w_f
    stiffness = np.array([[k_hum, -k_hum], [-k_hum, k_hum + k_fl]])
    damping = np.array([[c_hum, -c_hum], [-c_hum, c_hum + c_fl]])
    masses = np.diag([mass, m_f])
    load = mass * G * a1 * np.array([1.0, -1.0])
    u_hat, z_hat = np.linalg.solve(stiffness + 1j * w * damping - w**2 * masses, load)
    late = t > 12
    assert np.max(np.abs(acc[late])) == pytest.approx(abs(w**2 * u_hat), rel=3e-3)
    assert np.max(np.abs(z[late])) == pytest.approx(abs(z_hat), rel=3e-3)
    # The floor changes the response substantially here, so the check has teeth.
    rigid = abs(-(w**2) / (w_h**2 - w**2 + 2j * xi_h * w_h * w)) * G * a1
    assert abs(abs(w**2 * u_hat) / rigid - 1) > 0.1


def test_measured_floor_explains_the_recorded_acceleration():
    """With the true parameters and force, the preprocessed floor signals account for the GRF."""
    synthetic = _floor_record(seed=1)
    pre = signals.preprocess(synthetic.record)
    truth, cycles = synthetic.truth, synthetic.cycles
    inner = (pre.time > 2.0) & (pre.time < pre.time[-1] - 2.0)
    errors = {}
    for label, model in (("base", SMDModel()), ("floor", SMDModel(effects=[FloorMode()]))):
        residual = []
        for _, cycle in cycles.iterrows():
            span = inner & (pre.time >= cycle.t_start) & (pre.time < cycle.t_end)
            inputs = CycleInputs(f_b=cycle.f_b, t0=cycle.t_start, time=pre.time,
                                 signals={"floor_disp": pre.floor_disp, "floor_vel": pre.floor_vel})
            x = np.zeros((span.sum(), model.n_state))
            x[:, 0], x[:, 1] = pre.disp[span], pre.vel[span]
            x[:, 2], x[:, 3] = truth["f_h"], truth["xi_h"]
            for name in model.coefficient_names:
                x[:, model.index(name)] = cycle[name]
            predicted = np.array([model.acceleration(xk, tk, inputs) for xk, tk in zip(x, pre.time[span])])
            residual.append(pre.acc[span] - predicted)
        errors[label] = float(np.sqrt(np.mean(np.concatenate(residual) ** 2)))
    # base about 0.25 m/s^2 (the floor term), floor about 0.12 (GRF noise 0.1 and integration error)
    assert errors["floor"] < 0.6 * errors["base"]


def test_measured_mode_on_a_simulated_floor_record():
    """End to end with the EKF: the measured floor moves the median f_h towards the truth.

    Measured on seeds 1-3 (3 passes): f_h medians base 2.068 / 2.020 / 2.087 Hz, floor
    2.061 / 1.968 / 2.056 Hz (truth 1.8; flipping the floor term's sign gives 2.070 / 2.057).
    xi_h medians and the acceleration innovations do not improve (the Fourier
    coefficients absorb most of the floor term within a cycle), so they are not asserted.
    """
    pre = signals.preprocess(_floor_record(seed=2).record)
    tables = {}
    for label, model in (("base", SMDModel()), ("floor", SMDModel(effects=[FloorMode()]))):
        tables[label] = CycleRunner(model, estimator="ekf", max_passes=3, progress=False).run(pre)
    ok = {label: table[table.status == "ok"] for label, table in tables.items()}
    assert len(ok["floor"]) == len(ok["base"]) == len(pre.valid_cycles)
    error = {label: abs(table.f_h.median() - 1.8) for label, table in ok.items()}
    assert error["floor"] < error["base"] - 0.02


def test_drawing_a_floors_ambient_excitation_returns_a_new_floor():
    """An effect is immutable: its random simulation inputs come in a copy, the floor it was drawn for is unchanged."""
    person = SMDModel(n_harmonics=1)
    floor = for_simulation(make_effect("floor_mode:frequency=3.48,ambient=0.5"), person, 70.0)
    drawn = draw_inputs(floor, np.random.default_rng(1), 10.0)
    assert drawn is not floor and drawn.values == floor.values
    rates = []
    for effect in (floor, drawn, floor):
        model = SMDModel(n_harmonics=1, effects=[effect])
        x = np.zeros(model.n_state)
        x[model.index("f_h")], x[model.index("xi_h")] = 2.5, 0.3
        rates.append(effect.slot_rates(model, x, 1.3, CycleInputs(f_b=2.0), 0.0))
    assert np.all(rates[0] == 0.0) and np.array_equal(rates[0], rates[2])  # at rest, before and after the draw
    assert rates[1][1] != 0.0  # the drawn copy's floor is shaken by its ambient excitation
    plain = make_effect("cubic_stiffness:beta_3=400")
    assert draw_inputs(plain, np.random.default_rng(1), 10.0) is plain  # nothing to draw: the adapter's default


def test_diagnoses_floor_candidate_is_the_measured_floor_or_else_the_estimated_mode():
    """A record with floor_acc gets the measured floor as diagnose's candidate; one without it the estimated floor
    mode (a person on a vibrating floor without an accelerometer was otherwise read as missing harmonics)."""
    from smd_statespace.effects.floor_mode import FloorMode
    from smd_statespace.model.fitted import FittedRecord

    def fitted(floor_acc):  # all an effect may read of the fit without it; these two are never called here
        return FittedRecord(np.arange(10) / 100.0, floor_acc, predicted_displacement=None, strongest_line=None)

    with_accelerometer, without = fitted(np.zeros(10)), fitted(None)
    assert FloorMode.propose(with_accelerometer).source == "measured"
    assert FloorMode.propose(without).spec == "floor_mode:source=modal"  # as the verdict prints it


def test_a_floor_parameter_held_at_its_search_bound_is_said_so_not_given_an_sd_of_nan():
    """``diagnose``'s row of an estimated floor whose mass ratio ended on its search bound read "mass_ratio 0.001 ±
    nan -" (a lab export whose f_h drifts): a parameter held at a bound has no sd, and the words say where it is."""
    from types import SimpleNamespace

    import pandas as pd

    from smd_statespace.person.diagnose import _parameters_text

    same = SimpleNamespace(model=SimpleNamespace(n_harmonics=4))
    estimates = pd.DataFrame([{"parameter": "f_f", "unit": "Hz", "value": 9.135, "sd": 0.067, "on_bound": False},
                              {"parameter": "mass_ratio", "unit": "-", "value": 0.001, "sd": np.nan, "on_bound": True}]
                             ).set_index("parameter")
    assert _parameters_text(same, same, estimates) == "f_f 9.135 ± 0.067 Hz; mass_ratio 0.001 (on its search bound)"


def test_floor_share_is_the_persons_steady_response_to_a_sinusoidal_floor():
    """The body's acceleration a floor moving as z'' = A sin(w t) drives through the person's leg: after the start's
    transient, A |H(iw)| sin(w t + arg H(iw)) with H(s) = (2 xi w_h s + w_h^2) / (s^2 + 2 xi w_h s + w_h^2)
    (u'' = -w_h^2 (u - z) - 2 xi w_h (u' - z')); at the person's own frequency it is larger and lags the floor."""
    from smd_statespace.person.timing import floor_share

    f_h, xi_h, f = 3.0, 0.3, 3.0
    time = np.arange(0.0, 20.0, 0.001)
    w_h, w = 2 * np.pi * f_h, 2 * np.pi * f
    gain = (2j * xi_h * w_h * w + w_h**2) / (-(w**2) + 2j * xi_h * w_h * w + w_h**2)
    share = floor_share(time, 0.5 * np.sin(w * time), f_h, xi_h)
    steady = time > 10.0
    expected = 0.5 * np.abs(gain) * np.sin(w * time + np.angle(gain))
    np.testing.assert_allclose(share[steady], expected[steady], atol=1e-4)
    assert np.abs(gain) > 1.5 and np.angle(gain) < 0  # at resonance: 1.94 times the floor, lagging it


FLOOR_RESONANCE = dict(mass=88.0, f_b=3.5, f_h=3.65, xi_h=0.47, blf=(0.29, 0.11, 0.04, 0.02), duration=20, seed=2,
                       effects={"floor_mode": {"modal_mass": 2000.0}})
"""A person bouncing at a floor's resonance (f_b 3.5 Hz, the floor 3.48 Hz, 2000 kg), truth f_h 3.65 Hz."""


@pytest.mark.slow
def test_cycle_starts_placed_again_without_the_floors_share_put_the_person_right_at_the_floors_resonance():
    """The force's harmonics jump and its rate jitters from cycle to cycle: the starts placed on the GRF, whose
    peaks the floor's resonance moves, are up to half a cycle off, and from them the fit with the floor was
    worse than without it (likelihood ratio -107.8, f_h 3.031 Hz: -17 %). Placed again on the force less the
    floor's share, the starts give f_h within 2 % and a ratio in the floor's favour, and the note says both."""
    from smd_statespace.person import identify_person

    result = identify_person(simulate_bouncing(**FLOOR_RESONANCE).record)
    note = next(n for n in result.notes if n.startswith("the cycle starts were placed again"))
    assert "the fit from the new starts is kept" in note
    assert abs(result.f_h / 3.65 - 1) < 0.02 and result.effect_test()["lr"] > 50
    assert not any("makes the fit worse" in w for w in result.record_warnings)
    first = float(note.split("log-likelihood ")[1].split(" from them, ")[1].split(" ")[0])
    assert result.loglike > first + 100  # from the GRF's starts the fit was far worse


@pytest.mark.slow
def test_a_floor_acc_with_its_sign_flipped_fits_worse_than_no_floor_and_is_warned_of_with_f_h_either_way():
    """The same person, its force's rate jittering only: the measured floor puts f_h near the truth. With the
    floor's acceleration negated (an accelerometer mounted upside down) the fit with it is worse than without it
    by more than FLOOR_WORSE (AIC; the same unknowns): a warning says so, asks for the sign and gives f_h both
    ways."""
    from smd_statespace.person import identify_person
    from smd_statespace.person.fit import FLOOR_WORSE

    record = simulate_bouncing(coef_variation=0.0, **FLOOR_RESONANCE).record
    worse = identify_person(dataclasses.replace(record, floor_acc=-record.floor_acc))
    lr = worse.effect_test()["lr"]
    assert lr < FLOOR_WORSE
    warning = next(w for w in worse.record_warnings if "floor_acc makes the fit worse" in w)
    assert f"likelihood ratio {lr:.1f}" in warning and "upward positive" in warning
    assert f"{worse.f_h:.3f} Hz with the floor" in warning
    assert f"{worse.before.f_h:.3f} Hz without it (--no-floor)" in warning
