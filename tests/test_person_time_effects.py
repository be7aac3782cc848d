"""An effect that changes in time: its ``t`` is the record's own time (s) at every sample, not the first sample's.

Until 2026-11-28 the record-level model evaluated a linear effect's Jacobian at the record's first sample only, so
a stiffness growing as ``k_t t`` was frozen at ``t = t_0`` and ``k_t`` became collinear with ``f_h`` (likelihood
ratio 0.0 on a record where ``f_h`` drifted by 14 %, issue 45).
"""

import numpy as np
import pytest

from helpers import known_disturbance
from smd_statespace.model import U, Effect, SMDModel, Slot
from smd_statespace.person.dynamics import PersonDynamics

FS = 100.0


class GrowingStiffness(Effect):
    """A leg stiffness per unit mass that grows in time: ``-k_t t u`` (m/s^2), ``k_t`` in 1/s^3."""

    name = "growing_stiffness"

    def slots(self, model):
        return (Slot("k_t", "parameter", "1/s^3", -20.0, 20.0, nominal=0.0,
                     description="growth of the stiffness per unit mass"),)

    def acceleration(self, model, x, t, inputs):
        return -model.value(x, "k_t") * np.asarray(t) * x[..., U]


def test_an_effect_that_changes_in_time_is_expanded_at_every_sample():
    time = np.arange(1000) / FS
    growing = PersonDynamics(SMDModel(n_harmonics=1, effects=[GrowingStiffness()]), time)
    assert not growing.linear  # its nominal k_t = 0 would hide the change; the check moves k_t off it
    assert growing.in_state  # linear in the state at every time: its likelihood is exact, and says so
    from smd_statespace.effects import make_effect
    assert not PersonDynamics(SMDModel(n_harmonics=1, effects=[make_effect("cubic_stiffness")]), time).in_state
    lin = growing.linearise(2.5, 0.3, {"k_t": 3.0}, nominal=np.zeros((time.size, 2)))
    w2 = (2 * np.pi * 2.5) ** 2
    np.testing.assert_allclose(lin.A[:, 1, 0], -(w2 + 3.0 * time), rtol=1e-6)  # the stiffness at each sample
    # a known function of time that leaves the Jacobian alone stays one exact linear system
    assert PersonDynamics(SMDModel(n_harmonics=1, effects=[known_disturbance()]), time).linear


@pytest.mark.slow
def test_a_stiffness_growing_in_time_is_recovered():
    """f_h grows from 2.70 to 2.93 Hz over 16 s (k_t = 3 /s^3): the fitted k_t comes back within 3 sd, well
    away from 0."""
    from scipy import stats

    from smd_statespace.person import identify_person
    from smd_statespace.person.calibration import EFFECT_CALIBRATION
    from smd_statespace.person.extend import fit_effects
    from smd_statespace.simulation import simulate_bouncing

    effect = GrowingStiffness()
    sim = simulate_bouncing(mass=70, f_b=2.2, f_h=2.7, xi_h=0.3, duration=16, seed=12,
                            effects=[effect.with_values(k_t=3.0)])
    base = identify_person(sim.record, variation="independent", timing="template", intervals="wald")
    fitted = fit_effects(base, [effect], intervals="wald")
    k_t = fitted.effect_estimates().loc["k_t"]
    assert abs(k_t["value"] - 3.0) < 3 * k_t["sd"] and k_t["value"] > 5 * k_t["sd"], k_t
    assert fitted.effect_test()["lr"] > 20.0
    assert fitted.to_dict()["likelihood"] == "exact" and any("likelihood is exact" in n for n in fitted.notes)
    # the default, calibrated interval: the sd from the information, the interval widened by EFFECT_CALIBRATION
    # (effects' 90 % Wald intervals held the truth on 69-79 % of simulated records)
    calibrated = fit_effects(base, [effect]).effect_estimates().loc["k_t"]
    z = stats.norm.ppf(0.95)
    assert calibrated["sd"] == pytest.approx(k_t["sd"], rel=1e-6)
    assert k_t["high"] - k_t["low"] == pytest.approx(2 * z * k_t["sd"], rel=1e-6)
    assert calibrated["high"] - calibrated["low"] == pytest.approx(2 * z * EFFECT_CALIBRATION * k_t["sd"], rel=1e-6)


class ExtraStiffness(Effect):
    """A constant extra stiffness per unit mass ``-k_s u``: the same as a higher ``f_h``, on any record."""

    name = "extra_stiffness"

    def slots(self, model):
        return (Slot("k_s", "parameter", "1/s^2", -100.0, 100.0, nominal=0.0, description="extra stiffness"),)

    def acceleration(self, model, x, t, inputs):
        return -model.value(x, "k_s") * x[..., U]


def test_an_effect_that_cannot_be_told_from_f_h_is_said_so_in_words():
    from smd_statespace.person import identify_person
    from smd_statespace.person.extend import fit_effects
    from smd_statespace.simulation import simulate_bouncing

    sim = simulate_bouncing(mass=70, f_b=2.2, f_h=2.7, xi_h=0.3, duration=8, seed=3)
    base = identify_person(sim.record, variation="independent", timing="template", intervals="wald")
    said = [w for w in fit_effects(base, [ExtraStiffness()], intervals="wald").warnings
            if w.startswith("k_s is not determined")]
    assert len(said) == 1 and "cannot be told from f_h (correlation -" in said[0], said
    # an effect the record does tell apart (the growing stiffness above) is not said to be confounded
    growing = fit_effects(base, [GrowingStiffness()], intervals="wald").warnings
    assert not any("cannot be told" in w for w in growing)


def test_a_nonlinear_path_that_has_not_settled_is_warned_of(monkeypatch):
    """One linearisation allowed: a cubic spring's path has not settled, and its fit says so (an approximate
    likelihood, a warning)."""
    from smd_statespace.person import extend, identify_person
    from smd_statespace.simulation import simulate_bouncing

    sim = simulate_bouncing(mass=70, f_b=2.2, f_h=2.7, xi_h=0.3, duration=12, seed=4,
                            effects=["cubic_stiffness:beta_3=900"])
    base = identify_person(sim.record, variation="independent", timing="template", intervals="wald")
    monkeypatch.setattr(extend, "NOMINAL_ITERATIONS", 1)
    spring = extend.fit_effects(base, ["cubic_stiffness"], intervals="wald")
    assert not spring.settled and any("had not settled after 1 linearisations" in w for w in spring.warnings)
    assert any(n.startswith("the likelihood is approximate") for n in spring.notes)
