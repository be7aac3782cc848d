"""Jacobians that cannot be silently wrong: automatic defaults, checks of analytic ones, verified linearity."""

import warnings

import numpy as np
import pytest

from smd_statespace.effects import make_effect
from smd_statespace.errors import OptionError
from smd_statespace.model.jacobians import check_jacobians, check_linearity, numeric_jacobian
from smd_statespace.model import U, U_DOT, CycleInputs, Effect, Slot, SMDModel


class OnlyAcceleration(Effect):
    """Quadratic damping ``-c_q u'|u'|`` with no Jacobian of its own (the automatic one is used)."""

    name = "only_acceleration"

    def __init__(self, linear=False):
        self.linear = linear

    def slots(self, model):
        return (Slot("c_q", "parameter", "1/m", 0.0, 20.0, nominal=5.0, linear=self.linear),)

    def acceleration(self, model, x, t, inputs):
        v = x[..., U_DOT]
        return -x[..., model.index("c_q")] * v * np.abs(v)


class WrongJacobian(OnlyAcceleration):
    name = "wrong_jacobian"

    def acceleration_jacobian(self, model, x, t, inputs):
        v, c = x[..., U_DOT], x[..., model.index("c_q")]
        jac = np.zeros(x.shape)
        jac[..., U_DOT] = -c * np.abs(v)  # the factor 2 forgotten
        jac[..., model.index("c_q")] = -v * np.abs(v)
        return jac


class LaggedAcceleration(Effect):
    """A dynamic slot ``s`` following the COM acceleration: ``s' = (acc - s) / tau``; no Jacobian given."""

    name = "lagged"

    def slots(self, model):
        return (Slot("s", "dynamic", "m/s^2", nominal=1.0),)

    def slot_rates(self, model, x, t, inputs, acc):
        return ((acc - x[..., model.index("s")]) / 0.2)[..., None]


def test_numeric_jacobian_is_vectorised_over_leading_axes():
    x = np.random.default_rng(0).normal(size=(4, 3, 2))
    jac = numeric_jacobian(lambda z: np.stack([z[..., 0] * z[..., 1], np.sin(z[..., 0])], axis=-1), x)
    assert jac.shape == (4, 3, 2, 2)
    assert np.allclose(jac[..., 0, 0], x[..., 1], rtol=1e-8) and np.allclose(jac[..., 0, 1], x[..., 0], rtol=1e-8)
    assert np.allclose(jac[..., 1, 0], np.cos(x[..., 0]), rtol=1e-8) and np.allclose(jac[..., 1, 1], 0.0)


def test_an_effect_that_gives_only_its_acceleration_gets_the_right_jacobian():
    model = SMDModel(effects=[OnlyAcceleration()])
    x = np.random.default_rng(1).normal(size=(5, model.n_state))
    x[:, model.index("c_q")] = 3.0
    inputs = CycleInputs(f_b=2.0)
    base = SMDModel().acceleration_jacobian(x[:, :-1], 0.1, inputs)
    jac = model.acceleration_jacobian(x, 0.1, inputs)
    v = x[:, U_DOT]
    assert np.allclose(jac[:, U_DOT] - base[:, U_DOT], -2.0 * 3.0 * np.abs(v), rtol=1e-7, atol=1e-9)  # d/du'
    assert np.allclose(jac[:, model.index("c_q")], -v * np.abs(v), rtol=1e-7, atol=1e-9)  # d/dc_q
    assert np.allclose(jac[:, U], base[:, U])
    assert check_jacobians(model)["ok"].all()


def test_check_jacobians_finds_a_wrong_analytic_jacobian_and_passes_the_built_in_ones():
    table = check_jacobians(SMDModel(effects=[WrongJacobian()]))
    assert not table.loc["wrong_jacobian", "ok"] and table.loc["wrong_jacobian", "acceleration"] > 0.1
    for spec in ("harmonics:count=2", "cubic_stiffness", "floor_mode:source=modal"):
        assert check_jacobians(SMDModel(effects=[make_effect(spec)]))["ok"].all(), spec


def test_slot_rates_jacobian_default_applies_the_chain_rule_through_the_acceleration():
    model = SMDModel(effects=[LaggedAcceleration()])
    x = np.random.default_rng(2).normal(size=(3, model.n_state))
    inputs = CycleInputs(f_b=2.0)
    jac = model.rate_jacobian(x, 0.1, inputs)
    s = model.index("s")
    expected = model.acceleration_jacobian(x, 0.1, inputs) / 0.2
    expected[:, s] -= 1.0 / 0.2
    assert np.allclose(jac[:, s, :], expected, rtol=1e-6, atol=1e-6)


def test_a_wrong_linearity_declaration_is_refused_and_a_base_slot_made_nonlinear_is_reported():
    with pytest.raises(OptionError, match="c_q \\(only_acceleration\\) are declared linear"):
        check_linearity(SMDModel(effects=[OnlyAcceleration(linear=True)]))
    assert set(check_linearity(SMDModel(effects=[OnlyAcceleration(linear=False)]))) == {"u_dot"}  # u'|u'|
    assert set(check_linearity(SMDModel(effects=[make_effect("cubic_stiffness")]))) == {"u"}
    assert check_linearity(SMDModel()) == {}
    assert check_linearity(SMDModel(effects=[make_effect("harmonics:count=2")])) == {}


def test_grid_and_rbpf_say_when_their_kalman_part_is_only_approximate():
    from smd_statespace.estimators.linear import _VERIFIED, verify_linear

    model = SMDModel(effects=[make_effect("cubic_stiffness")])
    _VERIFIED.discard(id(model))
    with pytest.warns(UserWarning, match="not linear in u"):
        verify_linear(model, CycleInputs(f_b=2.0))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        verify_linear(model, CycleInputs(f_b=2.0))  # once per model
        verify_linear(SMDModel(), CycleInputs(f_b=2.0))  # the base model is linear: silent
