"""The record-level model with effects: one model from the SMD model's effects, checked against independent physics.

- a floor mode (linear dynamics of its own) gives exactly the likelihood of an independent construction: the
  person, the floor and a rotating force phasor as one linear system, discretised by one matrix exponential;
- a nonlinear effect at zero is the base model, whatever path it is linearised about;
- the linearised likelihood of a cubic spring matches the exact one of a deterministic record (nonlinear least
  squares through a fine ODE solution);
- identify --effect from the command line: the effect's parameter with its interval, and bad input in one line.
"""

import dataclasses
import json

import numpy as np
import pytest
from scipy import integrate, linalg, optimize

from helpers import known_disturbance
from smd_statespace.cli import main
from smd_statespace.effects import make_effect
from smd_statespace.io import G
from smd_statespace.model import SMDModel
from smd_statespace.person.discretisation import expm_stack
from smd_statespace.person.dynamics import PersonDynamics
from smd_statespace.person.model import RecordModel
from smd_statespace.person.timing import CycleTiming

FS, F_B = 100.0, 2.0


def regular_timing(duration):
    """Cycle starts every 1 / F_B s from t = 0 (phase 0 at the first sample)."""
    return CycleTiming(np.arange(-1, int(duration * F_B) + 3) / F_B, "template")


def profile_loglike(columns, y):
    """Profile log-likelihood of ``y = columns @ delta + N(0, s^2)`` with ``delta`` and ``s^2`` at their maximum."""
    coef, *_ = np.linalg.lstsq(columns, y, rcond=None)
    rss = float(np.sum((y - columns @ coef) ** 2))
    return -0.5 * y.size * (np.log(2 * np.pi * rss / y.size) + 1.0)


def test_expm_stack_matches_scipy():
    rng = np.random.default_rng(4)
    stack = rng.normal(size=(5, 4, 4)) * np.array([0.1, 3.0, 20.0, 0.01, 1.0])[:, None, None]
    for matrix, expected in zip(expm_stack(stack), (linalg.expm(m) for m in stack)):
        np.testing.assert_allclose(matrix, expected, rtol=1e-12, atol=1e-12)


def test_exponentials_of_the_person_alone_match_scipy_singular_and_negative_stiffness_too():
    """The 2 x 2 path of ``exponentials`` (written out) against scipy's expm of Van Loan's block, for springs of
    positive, zero (a singular A) and negative stiffness, over- and under-damped, at 100 Hz and 1000 Hz."""
    from smd_statespace.person.discretisation import exponentials

    rng = np.random.default_rng(np.random.SeedSequence(46))
    omega = 2 * np.pi * rng.uniform(0.5, 8.0, 40)
    A = np.zeros((40, 2, 2))
    A[:, 0, 1] = 1.0
    A[:, 1, 0] = -omega**2 * np.resize([1.0, 0.0, -0.5, 2.0], 40)
    A[:, 1, 1] = -2.0 * rng.uniform(0.0, 2.0, 40) * omega
    for dt in (0.01, 0.001):
        phi, integral = exponentials(A, dt)
        for matrix, p, w in zip(A, phi, integral):
            block = np.zeros((4, 4))
            block[:2, :2], block[:2, 2:] = matrix * dt, np.eye(2) * dt
            expected = linalg.expm(block)
            np.testing.assert_allclose(p, expected[:2, :2], rtol=1e-12, atol=1e-13)
            np.testing.assert_allclose(w, expected[:2, 2:], rtol=1e-12, atol=1e-13 * dt)


def test_floor_mode_likelihood_equals_an_independent_linear_system():
    """Person + floor + one force harmonic, constant coefficients (a random walk with a vanishing step):
    the record-level likelihood equals the profile likelihood of the exact linear regression on the
    initial state and the template, built from one matrix exponential of the whole continuous system."""
    f_h, xi_h, f_f, xi_f, mu = 2.6, 0.3, 3.7, 0.02, 0.01
    duration = 6.0
    time = np.arange(int(duration * FS)) / FS
    rng = np.random.default_rng(1)
    y = 0.8 * np.sin(2 * np.pi * F_B * time + 0.3) + 0.2 * np.sin(2 * np.pi * 3.7 * time) + rng.normal(0, 0.1,
                                                                                                      time.size)
    floor = make_effect("floor_mode:source=modal")
    dynamics = PersonDynamics(SMDModel(n_harmonics=1, effects=[floor]), time)
    assert dynamics.linear and dynamics.names == ["u", "u_dot", "z", "z_dot"]
    model = RecordModel(time, y, regular_timing(duration), n_harmonics=1, variation="random_walk",
                        dynamics=dynamics)
    named = {"f_h": f_h, "xi_h": xi_h, "f_f": f_f, "xi_f": xi_f, "mass_ratio": mu}
    params = np.array([named.get(name, -40.0) for name in model.param_names])  # log variance e^-40: constant
    w, wf, nu = 2 * np.pi * f_h, 2 * np.pi * f_f, 2 * np.pi * F_B
    # s = [u, u', z, z', a0, p, q], p = a1 cos(theta) + b1 sin(theta), q = -a1 sin(theta) + b1 cos(theta)
    acc = np.array([-w**2, -2 * xi_h * w, w**2, 2 * xi_h * w, G, G, 0.0])  # Section 6: the leg on u - z
    system = np.zeros((7, 7))
    system[0, 1] = 1.0
    system[1] = acc
    system[2, 3] = 1.0
    system[3] = -mu * acc + np.array([0, 0, -wf**2, -2 * xi_f * wf, 0, 0, 0])
    system[5, 6], system[6, 5] = nu, -nu
    step = linalg.expm(system / FS)
    states = np.empty((time.size, 7, 7))
    states[0] = np.eye(7)
    for k in range(1, time.size):
        states[k] = step @ states[k - 1]
    columns = np.einsum("i,kij->kj", acc, states)  # y_k's response to each initial unknown
    assert model.loglike(params) == pytest.approx(profile_loglike(columns, y), abs=1e-6)


def test_the_modal_floor_is_searched_beyond_the_per_cycle_prior_and_its_zero_damping_is_a_limit():
    """A light floor (700 kg under a 70 kg person: mass ratio 0.1) lies beyond the per-cycle prior (0.001-0.05);
    the record-level search reaches 0.2 and a damping ratio of 0, where an estimate is an upper limit (a 30 s
    record cannot tell 0.001 from 0.004), not a run-away fit. A range the user gives is searched as given."""
    duration = 4.0
    time = np.arange(int(duration * FS)) / FS
    y = np.sin(2 * np.pi * F_B * time)

    def record_model(spec):
        dynamics = PersonDynamics(SMDModel(n_harmonics=1, effects=[make_effect(spec)]), time)
        return RecordModel(time, y, regular_timing(duration), n_harmonics=1, dynamics=dynamics)

    floor = make_effect("floor_mode:source=modal")
    prior = {slot.name: (slot.low, slot.high) for slot in SMDModel(effects=[floor]).slots if slot.kind == "parameter"}
    assert prior["mass_ratio"] == (0.001, 0.05) and prior["xi_f"] == (0.001, 0.05)  # the per-cycle prior is kept
    model = record_model("floor_mode:source=modal")
    bounds = dict(zip(model.param_names, model.bounds))
    assert bounds["mass_ratio"] == (0.001, 0.2) and bounds["xi_f"] == (0.0, 0.05)
    params = model.start_params()
    where = {name: model.param_names.index(name) for name in ("xi_f", "mass_ratio")}
    for name, value, on_bound in (("xi_f", 0.0, False), ("xi_f", 0.05, True), ("mass_ratio", 0.1, False),
                                  ("mass_ratio", 0.2, True), ("mass_ratio", 0.001, True)):
        trial = params.copy()
        trial[where[name]] = value
        assert model.at_bound(trial, where[name]) is on_bound, (name, value)
    given = record_model("floor_mode:source=modal,mass_ratio_range=0.002/0.03,damping_range=0.005/0.04")
    bounds = dict(zip(given.param_names, given.bounds))
    assert bounds["mass_ratio"] == (0.002, 0.03) and bounds["xi_f"] == (0.005, 0.04)
    trial = params.copy()
    trial[where["xi_f"]] = 0.005
    assert given.at_bound(trial, where["xi_f"])


def test_a_slot_whose_search_range_does_not_hold_its_prior_is_refused():
    from smd_statespace.errors import OptionError
    from smd_statespace.model import Slot

    with pytest.raises(OptionError, match="search range"):
        Slot("k", "parameter", "-", 0.1, 1.0, nominal=0.5, search=(0.2, 2.0))


@pytest.fixture(scope="module")
def cubic_record():
    """A short deterministic record of a person with a cubic spring: one harmonic, constant, small noise."""
    f_h, xi_h, beta, a1 = 2.6, 0.3, 600.0, 0.3
    duration = 5.0
    time = np.arange(int(duration * FS)) / FS
    w = 2 * np.pi * f_h

    def rate(t, s):
        u, v = s
        return [v, -w**2 * (u + beta * u**3) - 2 * xi_h * w * v + G * a1 * np.cos(2 * np.pi * F_B * t)]

    solution = integrate.solve_ivp(rate, (0, time[-1]), [0.0, 0.0], t_eval=time, method="DOP853", rtol=1e-11,
                                   atol=1e-13)
    u, v = solution.y
    acc = -w**2 * (u + beta * u**3) - 2 * xi_h * w * v + G * a1 * np.cos(2 * np.pi * F_B * time)
    y = acc + np.random.default_rng(2).normal(0, 0.02, time.size)
    return time, y, dict(f_h=f_h, xi_h=xi_h, beta_3=beta)


def cubic_model(time, y, nominal=None, beta_range=(-1000.0, 1000.0)):
    effect = make_effect(f"cubic_stiffness:beta_range={beta_range[0]:g}/{beta_range[1]:g}")
    dynamics = PersonDynamics(SMDModel(n_harmonics=1, effects=[effect]), time)
    return RecordModel(time, y, regular_timing(time[-1] + 1 / FS), n_harmonics=1, variation="random_walk",
                       dynamics=dynamics, nominal=nominal)


def params_of(model, **named):
    return np.array([named.get(name, -40.0) for name in model.param_names])


def relinearised_loglike(time, y, truth, beta, times=8):
    """The record-level log-likelihood at ``beta`` after re-linearising about the predicted path ``times`` times."""
    from smd_statespace.person.statespace import nominal_path

    model = cubic_model(time, y, nominal=np.zeros((time.size, 2)))
    params = params_of(model, f_h=truth["f_h"], xi_h=truth["xi_h"], beta_3=beta)
    for _ in range(times):
        model = cubic_model(time, y, nominal=nominal_path(model, params))
    return model.loglike(params)


def exact_loglike(time, y, truth, beta):
    """Profile log-likelihood of the deterministic nonlinear model: least squares over the initial state and
    the template (a1, b1; a0 is 0, u being the displacement from the static equilibrium) through a fine ODE
    solution."""
    w = 2 * np.pi * truth["f_h"]
    xi = truth["xi_h"]

    def predicted(delta):
        u0, v0, a1, b1 = delta
        a0 = 0.0

        def rate(t, s):
            force = G * (a0 + a1 * np.cos(2 * np.pi * F_B * t) + b1 * np.sin(2 * np.pi * F_B * t))
            return [s[1], -w**2 * (s[0] + beta * s[0] ** 3) - 2 * xi * w * s[1] + force]

        sol = integrate.solve_ivp(rate, (0, time[-1]), [u0, v0], t_eval=time, method="DOP853", rtol=1e-10,
                                  atol=1e-12)
        u, v = sol.y
        force = G * (a0 + a1 * np.cos(2 * np.pi * F_B * time) + b1 * np.sin(2 * np.pi * F_B * time))
        return -w**2 * (u + beta * u**3) - 2 * xi * w * v + force

    fit = optimize.least_squares(lambda d: predicted(d) - y, [0.0, 0.0, 0.3, 0.0], x_scale=[0.01, 0.1, 0.1, 0.1])
    rss = float(np.sum(fit.fun**2))
    return -0.5 * y.size * (np.log(2 * np.pi * rss / y.size) + 1.0)


def test_a_trial_start_is_ranked_about_its_own_path_and_one_that_runs_away_is_never_taken(cubic_record):
    """At the truth, the likelihood about the path predicted from a zero path is far below the one about the
    truth's own path, which ``own_path`` reaches (re-linearised until it settles: the relinearised likelihood); a
    spring so soft that its stiffness turns negative within the bounce gives -inf, not a NaN that ``max`` could keep."""
    from smd_statespace.person.starts import own_path

    time, y, truth = cubic_record
    model = cubic_model(time, y, nominal=np.zeros((time.size, 2)))
    params = params_of(model, **truth)
    loglike, moved, same = own_path(model, params)
    assert same is params and loglike == pytest.approx(moved.loglike(params))
    assert loglike == pytest.approx(relinearised_loglike(time, y, truth, truth["beta_3"], times=12), abs=0.5)
    assert loglike > model.loglike(params) + 10
    assert own_path(model, params_of(model, f_h=2.6, xi_h=0.3, beta_3=-1e7))[0] == -np.inf


def test_a_nonlinear_effect_at_zero_is_the_base_model(cubic_record):
    time, y, truth = cubic_record
    rng = np.random.default_rng(0)
    anywhere = rng.normal(0, 0.03, (time.size, 2))  # any path: at beta_3 = 0 the term and its slope vanish
    with_cubic = cubic_model(time, y, nominal=anywhere)
    base = RecordModel(time, y, regular_timing(time[-1] + 1 / FS), n_harmonics=1, variation="random_walk")
    assert with_cubic.approximate and not base.approximate
    expected = base.loglike(params_of(base, f_h=2.6, xi_h=0.3))
    assert with_cubic.loglike(params_of(with_cubic, f_h=2.6, xi_h=0.3, beta_3=0.0)) == pytest.approx(expected,
                                                                                                       abs=1e-8)


def test_a_nonlinear_effect_does_not_choose_its_own_operating_point(cubic_record):
    """The force's constant a0 (which a linear model cannot tell from the initial displacement) is held at 0 with
    a nonlinear effect, so the likelihood is continuous as beta_3 leaves 0: estimated freely, a0 became
    determined through u^3 the moment beta_3 was not 0, a jump of about one unknown's worth of likelihood."""
    time, y, truth = cubic_record
    anywhere = np.random.default_rng(1).normal(0, 0.03, (time.size, 2))
    model = cubic_model(time, y, nominal=anywhere)
    at = {beta: model.filter(params_of(model, f_h=2.6, xi_h=0.3, beta_3=beta)) for beta in (0.0, 1e-3, 1.0)}
    assert at[1e-3]["rank"] == at[0.0]["rank"] == len(model.delta_names) - 1
    slope = (at[1.0]["loglike"] - at[0.0]["loglike"]) / 1.0
    assert abs(at[1e-3]["loglike"] - at[0.0]["loglike"]) < 1e-3 * max(abs(slope), 1.0)
    assert [model.delta_names[i] for i in model.held_delta] == ["template_a0"]
    assert at[1e-3]["delta"][model.held_delta[0]] == 0.0


def test_a_far_path_keeps_the_force_column_exact():
    """Linearised about a path metres away (where a search may wander), the force still enters with gain 1:
    differences of the rates along that path lost it to rounding (gain 1 + 3 at 100x, an error before)."""
    time = np.arange(300) / FS
    model = cubic_model(time, np.zeros_like(time), nominal=np.zeros((time.size, 2)))
    for scale in (1.0, 100.0):
        far = np.random.default_rng(1).normal(0.0, scale, (time.size, 2)) * [1.0, 10.0]
        system = model.dynamics.linearise(2.6, 0.3, {"beta_3": 900.0}, far)
        assert np.allclose(system.b, [[0.0, 1.0]], rtol=1e-12)  # per g of force
        # and the state columns still follow the spring's slope, -w^2 (1 + 3 beta u^2)
        w2 = (2 * np.pi * 2.6) ** 2
        assert np.allclose(system.A[:, 1, 0], -w2 * (1 + 3 * 900.0 * far[:, 0] ** 2), rtol=1e-5)


def test_an_effect_that_scales_the_force_is_refused_in_one_line():
    """The record-level model takes the force of Eq. 4 as it is: an effect multiplying it is named and refused."""
    from smd_statespace.errors import OptionError
    from smd_statespace.model import Effect, Slot

    class StiffFoot(Effect):
        name = "stiff_foot"

        def slots(self, model):
            return (Slot("k_f", "parameter", "1/m", 0.0, 10.0, nominal=2.0, linear=False),)

        def acceleration(self, model, x, t, inputs):  # force times (1 + k_f u): not Eq. 2's gain of 1
            return model.value(x, "k_f") * x[..., 0] * model.force(x, t, inputs)

    with pytest.raises(OptionError, match="stiff_foot: one changes how the force enters"):
        PersonDynamics(SMDModel(n_harmonics=1, effects=[StiffFoot()]), np.arange(100) / FS)


@pytest.mark.slow
def test_the_linearised_likelihood_of_a_cubic_spring_matches_the_exact_one(cubic_record):
    """Re-linearised about its own predicted path, the likelihood of a deterministic record with a cubic spring
    (stiffness 16 % higher at the 2 cm extremes) agrees with the exact nonlinear least-squares one, and both
    put beta_3 at the truth: the approximation costs far less than the effect is worth."""
    time, y, truth = cubic_record
    betas = (0.0, 300.0, 600.0, 900.0)
    approx = np.array([relinearised_loglike(time, y, truth, b) for b in betas])
    exact = np.array([exact_loglike(time, y, truth, b) for b in betas])
    print(np.c_[betas, approx, exact])
    assert np.argmax(approx) == np.argmax(exact) == 2
    gain = exact[2] - exact[0]  # what the effect is worth, in log-likelihood
    assert gain > 100
    assert np.max(np.abs(approx - exact)) < 0.02 * gain


@pytest.fixture(scope="module")
def floor_record(tmp_path_factory):
    """A 20 s record of a person on the article's plate (mode 1, 3.48 Hz) with its floor accelerometer."""
    folder = tmp_path_factory.mktemp("floor")
    out = folder / "floor.csv"
    assert main(["simulate", "--out", str(out), "--mass", "70", "--fb", "1.75", "--fh", "2.4", "--xi", "0.3",
                 "--duration", "20", "--seed", "5", "--effect", "floor_mode"]) == 0
    return out


def error_line(capsys):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


@pytest.mark.parametrize("spec, message", [
    ("floor_modes", "unknown effect 'floor_modes'"),
    ("cubic_stiffness:beta=3", "beta"),
])
def test_identify_effect_bad_specs_are_one_line_errors(floor_record, tmp_path, capsys, spec, message):
    out = tmp_path / "out"
    assert main(["identify", str(floor_record), "--mass", "70", "--effect", spec, "--out", str(out)]) == 2
    assert message in error_line(capsys) and not out.exists()


@pytest.mark.parametrize("command", [["identify", "--estimator", "ekf"], ["diagnose", "--estimator", "ekf"],
                                     ["identify", "--estimator", "pf", "--jobs", "1"]])
def test_no_floor_with_a_per_cycle_estimator_is_a_one_line_error(floor_record, tmp_path, capsys, command):
    """--no-floor leaves out what the record-level model adds by default; a per-cycle estimator never adds it, so the
    option would do nothing there: refused in one line, nothing written."""
    out = tmp_path / "out"
    target = [str(floor_record)] if command[0] == "diagnose" or "--jobs" not in command else [str(floor_record.parent)]
    assert main([command[0], *target, "--mass", "70", *command[1:], "--no-floor", "--out", str(out)]) == 2
    line = error_line(capsys)
    assert "--no-floor" in line and "--estimator record" in line and not out.exists()


def test_identify_effect_needing_a_missing_column_names_it_and_writes_nothing(tmp_path, capsys):
    plain = tmp_path / "plain.csv"
    assert main(["simulate", "--out", str(plain), "--mass", "70", "--fb", "2", "--fh", "2.5", "--xi", "0.3",
                 "--duration", "10"]) == 0
    capsys.readouterr()
    out = tmp_path / "out"
    assert main(["identify", str(plain), "--mass", "70", "--effect", "floor_mode", "--out", str(out)]) == 2
    line = error_line(capsys)
    assert "floor_acc" in line and "plain.csv" in line and not out.exists()


@pytest.mark.slow
@pytest.mark.parametrize("options", [[], ["--effect", "floor_mode"]])
def test_identify_with_the_measured_floor_from_the_command_line(floor_record, tmp_path, capsys, options):
    """The record-level person with the measured floor: the exact model of the leg on a moving floor, the fit
    without it beside it, and person.json saying so. A record with floor_acc brings its floor by default."""
    out = tmp_path / "out"
    assert main(["identify", str(floor_record), "--mass", "70", *options, "--out", str(out),
                 "--quiet", "--truth", str(floor_record.with_name("floor_truth.json"))]) == 0
    printed = capsys.readouterr().out
    assert "with floor_mode" in printed and "without the effect(s): f_h" in printed
    assert ("note: the record's floor_acc is in the model" in printed) == (not options)
    person = json.loads((out / "person.json").read_text())
    assert person["effects"] == ["floor_mode"] and person["likelihood"] == "exact" and person["lr_df"] == 0
    assert person["log_likelihood"] > person["before"]["log_likelihood"] + 10
    assert abs(person["f_h"] / 2.4 - 1) < 0.05 and person["truth"]["f_h"] == 2.4
    assert json.loads((out / "run.json").read_text())["options"]["effects"] == ["floor_mode"]


@pytest.mark.slow
def test_no_floor_leaves_the_measured_floor_out(floor_record, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["identify", str(floor_record), "--mass", "70", "--no-floor", "--out", str(out), "--quiet"]) == 0
    assert "floor_acc is in the model" not in capsys.readouterr().out
    person = json.loads((out / "person.json").read_text())
    assert not person.get("effects") and "before" not in person


def test_a_record_with_floor_acc_brings_its_floor_unless_one_is_given_or_it_is_left_out(floor_record):
    from smd_statespace.io import read_record
    from smd_statespace.person.extend import record_effects

    on_floor = read_record(floor_record, 70.0)
    plain = dataclasses.replace(on_floor, floor_acc=None)
    assert record_effects(on_floor) == ("floor_mode",)
    assert record_effects(on_floor, ["cubic_stiffness"]) == ("floor_mode", "cubic_stiffness")
    assert record_effects(on_floor, ["floor_mode:source=modal"]) == ("floor_mode:source=modal",)
    assert record_effects(on_floor, measured_floor=False) == ()
    assert record_effects(plain, ["harmonics"]) == ("harmonics",)


@pytest.mark.slow
def test_diagnose_prints_the_identify_command_that_adds_the_effect_and_it_runs(tmp_path, capsys, monkeypatch):
    """diagnose (record-level by default) names the hidden extra harmonics, prints the identify command that adds
    them; that command runs as printed and its person has them, with a better likelihood than without."""
    import shlex

    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "--out", "h.csv", "--mass", "70", "--fb", "2.2", "--fh", "2.6", "--xi", "0.3",
                 "--duration", "20", "--seed", "5", "--effect", "harmonics:blf=0.05/0.04"]) == 0
    capsys.readouterr()
    assert main(["diagnose", "h.csv", "--mass", "70", "--candidate", "harmonics", "--quiet", "--out", "d"]) == 0
    printed = capsys.readouterr().out
    assert "verdict: missing effect 'harmonics'" in printed
    command = next(line for line in printed.splitlines() if line.startswith("next: ")).removeprefix("next: ")
    assert command.startswith("smd-statespace identify h.csv --mass 70 --effect harmonics:count=2")
    assert main(shlex.split(command)[1:] + ["--quiet", "--out", "with"]) == 0
    person = json.loads((tmp_path / "with" / "person.json").read_text())
    assert person["n_harmonics"] == 6 and person["lr_df"] == 6 and person["lr_p"] < 1e-6
    assert abs(person["f_h"] / 2.6 - 1) <= abs(person["before"]["f_h"] / 2.6 - 1) + 0.01


@pytest.mark.parametrize("study", ["disturbance", "cubic"])
def test_the_likelihood_ratio_of_an_absent_effect_is_small_and_of_a_present_one_large(study):
    """A clean record: adding a known disturbance of unknown gain (linear, exact likelihood) or a cubic spring
    (nonlinear, its path settled) gives a ratio under chi-square(1)'s 99.9 % point on its one degree of freedom;
    where the disturbance is there its gain comes back. (That the ratio is chi-square(1) over many clean records is
    benchmarks/likelihood_ratio_null.py; measured: docs/person.md.)"""
    from scipy import stats

    from smd_statespace.person import identify_person
    from smd_statespace.person.extend import fit_effects
    from smd_statespace.simulation import simulate_bouncing

    effect = known_disturbance() if study == "disturbance" else make_effect("cubic_stiffness")
    sim = simulate_bouncing(mass=70, f_b=2.2, f_h=2.7, xi_h=0.3, duration=8, seed=2026)
    base = identify_person(sim.record, variation="independent", timing="template", intervals="wald")
    fitted = fit_effects(base, [effect], intervals="wald")
    test = fitted.effect_test()
    assert test["lr_df"] == 1 and fitted.settled and fitted.model.approximate == (study == "cubic")
    assert test["lr"] < stats.chi2(1).ppf(0.999)
    if study == "disturbance":
        sim = simulate_bouncing(mass=70, f_b=2.2, f_h=2.7, xi_h=0.3, duration=10, seed=7,
                                effects=[effect.with_values(c_d=0.3)])
        base = identify_person(sim.record, variation="independent", timing="template", intervals="wald")
        gain = fit_effects(base, [effect], intervals="wald").effect_estimates().loc["c_d"]
        assert abs(gain["value"] - 0.3) < 3 * gain["sd"] and gain["value"] > 5 * gain["sd"]


def test_a_cubic_springs_range_and_starts_read_the_displacement_within_cycles_not_its_wander():
    """A displacement of 1 cm at 2 Hz on a wander of 5 cm (0.05 Hz) and a ramp: the swing is the 2 Hz part's RMS
    (0.71 cm), and the spring's range and trial starts are scaled to it, not to the 3.6 cm RMS of the whole."""
    from smd_statespace.effects.cubic_stiffness import CubicStiffness
    from smd_statespace.model.fitted import FittedRecord

    time = np.arange(3000) / 100.0
    bounce = 0.01 * np.sin(2 * np.pi * 2.0 * time)
    displacement = bounce + 0.05 * np.sin(2 * np.pi * 0.05 * time) + 0.02 * time / 30.0
    fitted = FittedRecord(time, None, predicted_displacement=lambda: displacement, strongest_line=None, f_h=3.0)
    assert fitted.swing == pytest.approx(0.01 / np.sqrt(2), rel=0.03) and np.std(displacement) > 0.03
    spring = CubicStiffness.propose(fitted)
    bound = 100.0 * np.ceil(CubicStiffness.STIFFNESS_CHANGE / (3 * fitted.swing**2) / 100.0)
    assert spring.beta_range == (-bound, bound) and bound == pytest.approx(13333, rel=0.03)  # 2 / (3 * 0.00707^2)
    starts = spring.record_starts(fitted)
    assert starts[0] == {} and len(starts) == len(CubicStiffness.TRIAL_STARTS) + 1
    change, ratio = CubicStiffness.TRIAL_STARTS[1]
    assert starts[2]["f_h"] == pytest.approx(3.0 * ratio)
    assert starts[2]["beta_3"] == pytest.approx(change / (3 * fitted.swing**2))
    assert spring.record_starts(FittedRecord(time, None, lambda: displacement, None, per_cycle=True)) == []


@pytest.mark.slow
def test_a_large_hardening_spring_is_found_from_where_the_fit_without_it_left_the_person():
    """Fitted without the spring, the person's ``f_h`` is twice the truth and each cycle's mean force absorbs what is
    missed (the predicted displacement wanders by centimetres). Searched from there with the spring absent, it stayed
    absent (``beta_3`` 18, ``f_h`` 4.07, LR 15 before the trial starts of ``CubicStiffness.record_starts``); from the
    default variances with ``f_h`` lowered, the spring is found: ``f_h`` back within 10 % and ``beta_3``'s interval
    holding the truth."""
    from smd_statespace.person import identify_person
    from smd_statespace.person.extend import fit_effects
    from smd_statespace.simulation import simulate_bouncing

    sim = simulate_bouncing(mass=63, f_b=1.7, f_h=2.0, xi_h=0.4, duration=15, seed=3, noise=0.01,
                            effects={"cubic_stiffness": {"beta_3": 1500.0}})
    base = identify_person(sim.record)
    assert base.f_h > 3.0
    fitted = fit_effects(base, ["cubic_stiffness"])
    beta = fitted.effect_estimates().loc["beta_3"]
    assert abs(fitted.f_h / 2.0 - 1) < 0.1 and fitted.effect_test()["lr"] > 100
    assert beta["low"] <= 1500.0 <= beta["high"]


def test_an_effect_added_on_top_of_another_is_tested_against_the_person_with_the_first():
    """diagnose REC --effect A: candidates are fitted on top of A. Adding B to the person with A reaches the same
    likelihood as adding A and B together, its test counts only B's unknowns, and A cannot be added twice."""
    from smd_statespace.errors import OptionError
    from smd_statespace.person import identify_person
    from smd_statespace.person.diagnose import diagnose_person
    from smd_statespace.person.extend import fit_effects
    from smd_statespace.simulation import simulate_bouncing

    disturbance = known_disturbance()
    sim = simulate_bouncing(mass=70, f_b=2.2, f_h=2.7, xi_h=0.3, duration=10, seed=7,
                            effects=[disturbance.with_values(c_d=0.3), "harmonics:blf=0.05"])
    base = identify_person(sim.record, variation="independent", timing="template", intervals="wald")
    with_a = fit_effects(base, [disturbance], intervals="wald")
    on_top = fit_effects(with_a, ["harmonics:count=1"], intervals="wald")
    together = fit_effects(base, [disturbance, "harmonics:count=1"], intervals="wald")
    assert on_top.before is with_a and [e.name for e in on_top.effects] == ["known_disturbance", "harmonics"]
    assert on_top.loglike == pytest.approx(together.loglike, abs=0.05)
    assert on_top.effect_test()["lr_df"] == together.effect_test()["lr_df"] - with_a.effect_test()["lr_df"]
    assert on_top.effect_test()["lr"] == pytest.approx(2 * (on_top.loglike - with_a.loglike))
    assert on_top.effect_estimates().loc["c_d", "value"] == pytest.approx(0.3, abs=4 * on_top.effect_estimates()
                                                                             .loc["c_d", "sd"])
    with pytest.raises(OptionError, match="in the model already"):
        fit_effects(with_a, [disturbance])
    diagnosis = diagnose_person(with_a, candidates=["harmonics:count=1"])
    assert diagnosis.missing == ["harmonics"]
    assert "--effect harmonics:count=1" in diagnosis.command("rec.csv", 70)
    assert diagnosis.command("rec.csv", 70).count("--effect") == 2


@pytest.mark.parametrize("options, message", [
    (["--candidate", "floor_modes"], "unknown effect 'floor_modes'"),
    (["--effect", "harmonics", "--candidate", "harmonics:count=1"], "also given as --effect"),
    (["--estimator", "ekf", "--candidate", "cubic_stiffness:beta=3"], "beta")])
def test_diagnose_bad_candidates_are_one_line_errors(floor_record, capsys, options, message):
    """--effect puts an effect in the model, --candidate names one to try; a bad one is one line, exit 2."""
    assert main(["diagnose", str(floor_record), "--mass", "70", "--quiet", *options]) == 2
    assert message in error_line(capsys)


@pytest.mark.slow
def test_identify_effect_re_places_the_cycle_starts_with_the_effect_and_tests_it_where_the_person_was_fitted():
    """identify --effect estimates the cycle starts and the variation model again with the effect in the model
    (the starts placed by a model missing large harmonics are not the best for the model that has them); the
    likelihood ratio stays the one at the person's own starts, what diagnose screens with."""
    from smd_statespace.person import identify_person
    from smd_statespace.person.extend import fit_effects
    from smd_statespace.simulation import simulate_bouncing

    sim = simulate_bouncing(mass=70, f_b=2.0, f_h=2.6, xi_h=0.3, duration=15, seed=12,
                            effects={"harmonics": {"blf": (0.06, 0.045)}})
    fitted = identify_person(sim.record, intervals="wald", effects=["harmonics:count=2"])  # identify --effect
    base = fitted.before
    screened = fit_effects(base, ["harmonics:count=2"], intervals="wald", timing=False)
    assert np.array_equal(screened.model.timing.boundaries, base.model.timing.boundaries)
    moved = np.abs(fitted.model.timing.boundaries - base.model.timing.boundaries)
    assert moved.max() > 0.002 and fitted.loglike > screened.loglike + 1.0
    assert fitted.effect_test() == pytest.approx(screened.effect_test())
    assert {row.variation for row in fitted.comparison} == {row.variation for row in base.comparison}
    assert all(row.effects == ("harmonics:count=2",) for row in fitted.comparison)
    assert fitted.model.variation == min((row for row in fitted.comparison if not row.on_bound),
                                         key=lambda row: row.aic).variation


def test_a_candidate_whose_terms_are_all_near_zero_is_not_evidence():
    """Issue 45's record: harmonics 5-6 of 0.0004 +- 0.0003 g were proposed; terms of no size are not proposed."""
    from types import SimpleNamespace

    import pandas as pd

    from smd_statespace.person.diagnose import indistinguishable_from_zero

    def fits(blf, sd, estimates):
        base = SimpleNamespace(model=SimpleNamespace(n_harmonics=4))
        template = pd.DataFrame({"blf": [0.3, 0.15, 0.05, 0.02, *blf], "sd": [0.01] * 4 + list(sd)},
                                index=range(1, 5 + len(blf)))
        fitted = SimpleNamespace(model=SimpleNamespace(n_harmonics=4 + len(blf)), template_blf=lambda: template)
        return base, fitted, pd.DataFrame(estimates, columns=["value", "sd"])

    assert indistinguishable_from_zero(*fits([0.0004, 0.0002], [0.0003, 0.0003], []))
    assert not indistinguishable_from_zero(*fits([0.04, 0.0002], [0.003, 0.0003], []))  # one harmonic is there
    assert indistinguishable_from_zero(*fits([], [], [[3.0, 2.0]]))  # c_q 3 +- 2: within 2 sd of none
    assert not indistinguishable_from_zero(*fits([], [], [[9.0, 1.0]]))


def test_harmonic_gains_of_the_person_alone_match_a_linear_solve():
    """The compiled 2 x 2 gains (Cramer's rule) against numpy's solve of ``(j nu I - A) g = (exp(j nu dt) I - Phi) b``,
    with one ``A`` shared by every cycle rate and with an ``A`` per sample."""
    from smd_statespace.person.discretisation import exponentials, harmonic_gains

    rng = np.random.default_rng(np.random.SeedSequence(47))
    K, dt = 30, 0.01
    A = np.zeros((K, 2, 2))
    A[:, 0, 1] = 1.0
    A[:, 1, 0] = -(2 * np.pi * rng.uniform(1.0, 5.0, K)) ** 2
    A[:, 1, 1] = -rng.uniform(0.5, 8.0, K)
    b = np.column_stack([np.zeros(K), np.ones(K)]) + rng.normal(0, 0.1, (K, 2))
    nu = 2 * np.pi * rng.uniform(1.5, 3.5, K)[:, None] * np.arange(1, 5)
    phi, _ = exponentials(A, dt)
    for shared in (True, False):
        a, p, bb = (A[:1], phi[:1], b[:1]) if shared else (A, phi, b)
        gains = harmonic_gains(a, p, bb, nu, dt)
        for k in range(K):
            r = 0 if shared else k
            for i in range(nu.shape[1]):
                lhs = 1j * nu[k, i] * np.eye(2) - a[r]
                rhs = (np.exp(1j * nu[k, i] * dt) * np.eye(2) - p[r]) @ bb[r]
                np.testing.assert_allclose(gains[k, i], np.linalg.solve(lhs, rhs), rtol=1e-12, atol=1e-15)


def test_a_grid_of_trial_starts_is_computed_coarse_to_fine():
    """grid_best computes every other grid point, then the neighbours of the best of those: a peak between two
    coarse points is found at about half the cost; a lone spike whose neighbours are low is missed (the grid must be
    fine enough that a peak spans neighbours, as the floor's 1 % grid is)."""
    from smd_statespace.person.starts import GRID_KEEP, grid_best

    grid = np.geomspace(2.0, 20.0, 232)
    peak = 2.0 + 25.0 / (1.0 + (np.log(grid / 3.53) / 0.012) ** 2)  # a floor's narrow peak at 3.53 Hz
    values = np.r_[0.0, peak + 0.5 * np.sin(grid)]  # the innovations' line first, then the grid
    computed = []

    def counted(i):
        computed.append(i)
        return values[i]

    best = grid_best(counted, range(values.size), leading=1)
    assert best == int(np.argmax(values)) and best % 2 == 0  # between the coarse points 1, 3, 5, ...
    assert len(computed) == len(set(computed)) <= values.size // 2 + 1 + 2 * GRID_KEEP
    spike = np.zeros(values.size)
    spike[100], spike[1::2] = 5.0, 1.0 + np.arange(1, values.size, 2) * 1e-3
    assert grid_best(spike.__getitem__, range(spike.size), leading=1) != 100


def test_a_spring_and_a_floor_together_rank_the_springs_starts_alone_about_their_paths(long_fit, monkeypatch):
    """A cubic spring fitted with an estimated floor mode (``diagnose``'s joint fit of its two best): the spring's
    trials are each judged about their own path, the floor at its first frequency there (every combination of the
    two, each about its own path, took over 10 minutes); from the fit without them the floor's grid is searched
    with the spring absent. Two starts: from the person (the grid's best) and the best of the spring's trials."""
    from smd_statespace.person import extend, starts as starts_module
    from smd_statespace.person.effect_adapter import record_starts

    spring = extend.configured_for_record("cubic_stiffness", long_fit)
    floor = extend.configured_for_record("floor_mode:source=modal", long_fit)
    judged = []
    own_path = starts_module.own_path
    monkeypatch.setattr(starts_module, "own_path", lambda model, params: judged.append(params) or own_path(model,
                                                                                                           params))
    model = extend.effect_model(long_fit, [spring, floor])
    starts = starts_module.search_starts(model, long_fit, long_fit, [spring, floor])
    assert len(starts) == 2 and len(judged) == len(record_starts(spring, long_fit))
    first_frequency = record_starts(floor, long_fit)[0]["f_f"]
    assert all(params[model.position("f_f")] == first_frequency for params in judged)
    assert starts[0][1][model.position("beta_3")] == 0.0  # from the person: the spring absent, the floor searched


def test_a_refit_started_at_the_screened_fit_ends_where_a_search_from_the_trial_starts_ends(long_fit, monkeypatch):
    """``diagnose`` refits the candidate it proposes as ``identify --effect`` does (cycle starts re-placed), started
    at its screened fit (``start``): the same person as searching the trial starts again, without searching them;
    a ``start`` of other effects is not used."""
    from smd_statespace.person import extend

    spring = extend.configured_for_record("cubic_stiffness", long_fit)
    screened = extend.fit_effects(long_fit, [spring], timing=False)
    again = extend.fit_effects(long_fit, [spring])
    searched = []
    starts = extend.search_starts
    monkeypatch.setattr(extend, "search_starts", lambda *args: searched.append(1) or starts(*args))
    refit = extend.fit_effects(long_fit, [spring], start=screened)
    assert searched == [] and refit.f_h == pytest.approx(again.f_h, abs=0.1 * again.se[0])
    assert refit.loglike == pytest.approx(again.loglike, abs=0.05)
    extend.fit_effects(long_fit, ["harmonics"], timing=False, start=screened)
    assert searched == [1]


def test_the_modal_floor_starts_where_its_whole_grid_does(long_fit):
    """The floor mode's trial frequencies are an ordered grid after the innovations' line: the search's start is
    the whole grid's best start by likelihood, from about 130 of its 233 likelihoods."""
    from smd_statespace.person import extend
    from smd_statespace.person.effect_adapter import record_grid_start, record_starts

    floor = extend.configured_for_record("floor_mode:source=modal", long_fit)
    trials = record_starts(floor, long_fit)
    frequencies = [trial["f_f"] for trial in trials]
    assert record_grid_start(floor) == 1 and np.all(np.diff(frequencies[1:]) > 0)
    model = extend.effect_model(long_fit, [floor])
    counted, seen, j = extend.effect_model(long_fit, [floor]), [], model.position("f_f")
    counted.loglike = lambda params: seen.append(params[j]) or model.loglike(params)
    start = extend.search_starts(counted, long_fit, long_fit, [floor])[0][1]
    assert len(seen) < 0.6 * len(frequencies)  # 136 of 233 here
    every = [model.loglike(np.r_[start[:j], f, start[j + 1:]]) for f in frequencies]
    assert start[j] == frequencies[int(np.argmax(every))]


@pytest.mark.slow
def test_effect_on_the_command_line_is_configured_for_the_record_as_in_the_library(tmp_path, monkeypatch, capsys):
    """``identify REC --effect cubic_stiffness`` and ``diagnose REC --effect cubic_stiffness`` search the spring's
    range scaled to the record, as ``identify_person(record, effects=["cubic_stiffness"])`` does: until 2026-12-01
    the command line made the effect with its class's default (+-1000 1/m^2), on which a strong spring ends (the
    interval of a spring of 1500 read 652 to 1000)."""
    import json

    from smd_statespace.io import read_record
    from smd_statespace.person import identify_person

    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "--out", "s.csv", "--mass", "70", "--fb", "2.2", "--fh", "2.9", "--xi", "0.3",
                 "--duration", "15", "--seed", "5", "--effect", "cubic_stiffness:beta_3=1500"]) == 0
    library = identify_person(read_record("s.csv", 70.0), effects=["cubic_stiffness"])
    spec = library.effects[0].spec
    assert spec.startswith("cubic_stiffness:beta_range=") and library.effects[0].beta_range[1] > 1000.0
    assert main(["identify", "s.csv", "--mass", "70", "--effect", "cubic_stiffness", "--quiet", "--out", "a"]) == 0
    person = json.loads((tmp_path / "a" / "person.json").read_text())
    assert person["effects"] == [spec] and person["beta_3"] == pytest.approx(library.effect_estimates().loc[
        "beta_3", "value"])
    capsys.readouterr()
    assert main(["diagnose", "s.csv", "--mass", "70", "--effect", "cubic_stiffness", "--candidate", "harmonics",
                 "--quiet", "--out", "d"]) == 0
    assert capsys.readouterr().out.splitlines()[0] == f"s.csv: record-level model with {spec}"
