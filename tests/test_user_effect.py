"""A physical effect written by a user in one class, outside the package, known to every command.

The effect is defined here only: a quadratic (velocity-squared) leg damper. The tests check that the
simulator integrates its own term (against an independent ODE solution), that the command line loads it
from a file, that the crowd and the per-cycle model use it, and that the record-level diagnosis ranks it
first on a record simulated with it and the error falls when it is added.
"""

import json
import re

import numpy as np
import pytest
from scipy import integrate

from helpers import zero_force_cycles
from smd_statespace.cli import main
from smd_statespace.simulation.crowd import simulate_crowd
from smd_statespace.effects import EFFECTS, make_effect
from smd_statespace.model.jacobians import check_jacobians
from smd_statespace.model import SMDModel
from smd_statespace.simulation import integrate_response, simulate_bouncing

EFFECT_SOURCE = '''
import numpy as np

from smd_statespace.effects import register_effect
from smd_statespace.model import U_DOT, Effect, Slot


@register_effect
class QuadraticDamping(Effect):
    """Velocity-squared leg damping: adds -c_q r'|r'| to the COM acceleration, r' = u' - z' (c_q in 1/m)."""

    name = "quadratic_damping"
    simulation_defaults = {"c_q": 8.0}

    def __init__(self, c_q_max=20.0):
        self.c_q_max = float(c_q_max)

    def slots(self, model):
        return (Slot("c_q", "parameter", "1/m", 0.0, self.c_q_max, nominal=self.c_q_max / 4,
                     description="quadratic damping coefficient", linear=False),)

    def acceleration(self, model, x, t, inputs):
        rate = x[..., U_DOT] - model.floor_motion(x, t, inputs)[1]
        return -model.value(x, "c_q") * rate * np.abs(rate)
'''


@pytest.fixture
def quadratic_damping():
    """The user's effect, registered for one test and removed after it (other tests' candidates stay the same)."""
    namespace = {}
    exec(compile(EFFECT_SOURCE, "user_effect.py", "exec"), namespace)
    yield namespace["QuadraticDamping"]
    EFFECTS.pop("quadratic_damping", None)


def test_the_simulator_integrates_the_effects_own_term(quadratic_damping):
    f_h, c_q, amplitude = 2.0, 6.0, 0.04
    omega = 2 * np.pi * f_h
    time = np.arange(0, 4.0, 0.005)
    states = integrate_response(zero_force_cycles(4.0), time, f_h=f_h, xi_h=0.0,
                                effects=[f"quadratic_damping:c_q={c_q}"], initial_state=[amplitude, 0.0])

    def free(_, x):  # the same physics written out here, independently of the effect class
        return [x[1], -(omega**2) * x[0] - c_q * x[1] * abs(x[1])]

    exact = integrate.solve_ivp(free, (0, time[-1]), [amplitude, 0.0], t_eval=time, method="DOP853", rtol=1e-11,
                                atol=1e-13)
    assert np.abs(states["u"] - exact.y[0]).max() < 1e-8 * amplitude
    assert np.abs(states["u"].to_numpy()[-200:]).max() < 0.5 * amplitude  # the damper really takes energy


def test_a_known_value_is_a_constant_and_the_jacobians_are_automatic(quadratic_damping):
    effect = make_effect("quadratic_damping:c_q_max=10")
    model = SMDModel(effects=[effect])
    assert model.state_names[-1] == "c_q" and model.n_state == 14
    assert check_jacobians(model)["ok"].all()
    known = SMDModel(effects=[make_effect("quadratic_damping:c_q=5")])
    assert "c_q" not in known.state_names and known.constants == {"c_q": 5.0}
    with pytest.raises(Exception, match="c_qq"):
        make_effect("quadratic_damping:c_qq=5")


def test_the_command_line_loads_the_effect_from_a_file(tmp_path, capsys):
    source = tmp_path / "my_effects.py"
    source.write_text(EFFECT_SOURCE)
    out = tmp_path / "rec.csv"
    try:
        status = main(["--effects", str(source), "simulate", "--out", str(out), "--mass", "70", "--fb", "2",
                       "--fh", "2.5", "--xi", "0.3", "--duration", "8", "--seed", "1",
                       "--effect", "quadratic_damping:c_q=7"])
        assert status == 0, capsys.readouterr().err
        truth = json.loads((tmp_path / "rec_truth.json").read_text())
        assert truth["effects"] == {"quadratic_damping": {"c_q": 7.0}}
        # identify with the effect (one pass is enough to see its column)
        status = main(["--effects", str(source), "identify", str(out), "--mass", "70", "--estimator", "ekf",
                       "--max-passes", "1", "--effect", "quadratic_damping", "--out", str(tmp_path / "id")])
        assert status == 0, capsys.readouterr().err
        assert "c_q" in (tmp_path / "id" / "results.csv").read_text().splitlines()[0]
    finally:
        EFFECTS.pop("quadratic_damping", None)
    capsys.readouterr()
    assert main(["--effects", str(tmp_path / "missing.py"), "simulate", "--out", str(out), "--mass", "70", "--fb",
                 "2", "--fh", "2.5", "--xi", "0.3", "--duration", "8"]) == 2
    assert "--effects" in capsys.readouterr().err and "quadratic_damping" not in EFFECTS


def test_the_crowd_knows_the_effect(quadratic_damping):
    exact = simulate_crowd(2, 2.0, duration=4.0, seed=3)
    zero = simulate_crowd(2, 2.0, duration=4.0, seed=3, effects=["quadratic_damping:c_q=0"])
    damped = simulate_crowd(2, 2.0, duration=4.0, seed=3, effects=["quadratic_damping:c_q=8"])
    people = exact.forces.columns[1:-1]
    assert np.abs(zero.forces[people] - exact.forces[people]).to_numpy().max() < 1e-5  # N, ODE vs exact solution
    assert np.abs(damped.forces[people] - exact.forces[people]).to_numpy().max() > 5.0
    assert damped.settings["effects"] == ["quadratic_damping:c_q=8"]  # the truth every person had, as a spec
    assert make_effect(damped.settings["effects"][0]).values == {"c_q": 8.0}


@pytest.mark.parametrize("spec", [
    "harmonics", "harmonics:count=3", "harmonics:count=2,blf=0.04/0.03,phases=0.1/2.5,a5=0.012",
    "cubic_stiffness", "cubic_stiffness:beta_range=-500/750.25,beta_3=412.123456789",
    "floor_mode", "floor_mode:source=modal,f_f=3.2", "floor_mode:frequency=3.48,damping=0.02,modal_mass=8583",
    "floor_mode:frequency_range=2/9,noise=0.1,ambient=0.01",
    "quadratic_damping", "quadratic_damping:c_q_max=10", "quadratic_damping:c_q_max=12.5,c_q=0.1",
])
def test_an_effect_round_trips_through_its_spec(quadratic_damping, spec):
    """make_effect(e.spec) builds the same effect: the same options, the same known values; a user's effect written
    as docs/effects.md shows (no spec of its own) too."""
    effect = make_effect(spec)
    again = make_effect(effect.spec)
    assert type(again) is type(effect) and again.spec == effect.spec and again.values == effect.values
    same = {key: value for key, value in vars(effect).items() if not key.startswith("_")}
    assert {key: value for key, value in vars(again).items() if not key.startswith("_")}.keys() == same.keys()
    for key, value in same.items():
        assert np.array_equal(np.asarray(getattr(again, key), dtype=object), np.asarray(value, dtype=object)), key
    twin = effect.with_values(**{name: 0.3125 for name in list(effect.values)[:1]})
    assert make_effect(twin.spec).values == twin.values


def test_an_option_a_spec_cannot_carry_is_refused_in_words():
    from smd_statespace.model import Effect

    class Labelled(Effect):
        name = "labelled"

        def __init__(self, label="knee", stiff=False):
            self.label, self.stiff = label, stiff

    assert Labelled("hip", stiff=True).spec == "labelled:label=hip,stiff=true" and Labelled().spec == "labelled"
    with pytest.raises(Exception, match=r"option label='a,b' cannot be written in a spec"):
        Labelled(label="a,b").spec  # noqa: B018 - the property raises


def test_effects_file_is_accepted_after_the_command_too(tmp_path, capsys):
    source = tmp_path / "my_effects.py"
    source.write_text(EFFECT_SOURCE)
    try:
        assert main(["simulate", "--effects", str(source), "--out", str(tmp_path / "rec.csv"), "--mass", "70",
                     "--fb", "2", "--fh", "2.5", "--xi", "0.3", "--duration", "8", "--seed", "1",
                     "--effect", "quadratic_damping:c_q=7"]) == 0, capsys.readouterr().err
        assert json.loads((tmp_path / "rec_truth.json").read_text())["effects"] == {"quadratic_damping": {"c_q": 7.0}}
    finally:
        EFFECTS.pop("quadratic_damping", None)


def test_an_effect_of_the_wrong_shape_is_told_which_shape(tmp_path, capsys):
    source = tmp_path / "bad_effects.py"
    source.write_text(EFFECT_SOURCE.replace('name = "quadratic_damping"', 'name = "flat_damping"').replace(
        "return -model.value(x, \"c_q\") * rate * np.abs(rate)",
        "return (-model.value(x, \"c_q\") * rate * np.abs(rate))[..., None]"))
    try:
        assert main(["--effects", str(source), "simulate", "--out", str(tmp_path / "rec.csv"), "--mass", "70",
                     "--fb", "2", "--fh", "2.5", "--xi", "0.3", "--duration", "4", "--effect", "flat_damping"]) == 2
    finally:
        EFFECTS.pop("flat_damping", None)
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert re.search(r"effect 'flat_damping': acceleration returned shape \(\d*,? ?1\), expected \(\d*,?\)", err), err


@pytest.mark.slow
def test_diagnose_ranks_the_users_effect_first_and_the_error_falls(quadratic_damping):
    from smd_statespace.person import identify_person
    from smd_statespace.person.diagnose import diagnose_person

    sim = simulate_bouncing(mass=70, f_b=2.0, f_h=2.5, xi_h=0.3, duration=20, seed=3,
                            effects=["quadratic_damping:c_q=8"])
    base = identify_person(sim.record)
    # the damper against the built-in that imitates it best (every registered effect: benchmarks/person_effects.py)
    result = diagnose_person(base, candidates=["harmonics", "quadratic_damping"])
    table = result.table()
    print(table[["df", "lr", "p_value", "noise_change_%", "f_h_before", "f_h", "parameters"]])
    assert result.missing[0] == "quadratic_damping"
    row = table.loc["quadratic_damping"]
    assert row["noise_change_%"] < 0 and row["df"] == 1 and row["likelihood"] == "approximate"
    assert abs(row["f_h"] / 2.5 - 1) <= abs(row["f_h_before"] / 2.5 - 1) + 0.01  # the person's error does not grow
    c_q = result.fits["quadratic_damping"].effect_estimates().loc["c_q"]
    assert c_q["value"] > 2 * c_q["sd"] and c_q["low"] <= 8.0 <= c_q["high"]  # the truth: c_q 8 1/m


@pytest.mark.slow
def test_the_loop_carries_the_users_effect_with_its_options(tmp_path, capsys):
    """diagnose (--effects after the command) proposes the candidate with the options it was fitted with; the next:
    command it prints runs as printed, person.json keeps the spec, and the printed likelihood ratio is the one of
    the two printed log-likelihoods, on the unknowns the effect added (c_q: one)."""
    import shlex

    source = tmp_path / "my_effects.py"
    source.write_text(EFFECT_SOURCE)
    record = tmp_path / "rec.csv"
    try:
        assert main(["simulate", "--effects", str(source), "--out", str(record), "--mass", "70", "--fb", "2",
                     "--fh", "2.5", "--xi", "0.3", "--duration", "20", "--seed", "3",
                     "--effect", "quadratic_damping:c_q=8"]) == 0
        assert main(["diagnose", str(record), "--mass", "70", "--effects", str(source), "--quiet",
                     "--candidate", "quadratic_damping:c_q_max=15", "--out", str(tmp_path / "d")]) == 0
        printed = capsys.readouterr().out
        command = next(line for line in printed.splitlines() if line.startswith("next: "))
        assert "--effect quadratic_damping:c_q_max=15" in command and f"--effects {source}" in command
        argv = shlex.split(command[len("next: smd-statespace "):]) + ["--quiet", "--out", str(tmp_path / "id")]
        assert main(argv) == 0
    finally:
        EFFECTS.pop("quadratic_damping", None)
    printed = capsys.readouterr().out
    person = json.loads((tmp_path / "id" / "person.json").read_text())
    assert person["effects"] == ["quadratic_damping:c_q_max=15"]
    line = next(line for line in printed.splitlines() if "without the effect(s)" in line)
    before = float(re.search(r"without the effect\(s\):.*?log-likelihood (-?[\d.]+)", line).group(1))
    ratio = next(line for line in printed.splitlines() if line.lstrip().startswith("likelihood ratio"))
    lr, df, tested, without = re.search(r"likelihood ratio (-?[\d.]+) on (\d+) parameter.*= 2 x \((-?[\d.]+) with - "
                                        r"(-?[\d.]+) without\)", ratio).groups()
    assert float(without) == before and float(tested) == pytest.approx(person["loglike_tested"], abs=0.05)
    assert float(lr) == pytest.approx(2 * (float(tested) - before), abs=0.2) and int(df) == person["lr_df"] == 1
