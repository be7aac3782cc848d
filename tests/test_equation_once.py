"""Eq. 2 and the person-floor coupling are written once: changed in ``model/``, every path that uses them follows.

The change is a leg 1.1 times as fast (``f_h`` -> 1.1 ``f_h`` inside Eq. 2 only). Every path, run with the change
at ``f_h``, must then give what it gives without the change at 1.1 ``f_h``: a path that wrote Eq. 2 (or its
derivative, its frequency response, the floor's spring and damper on ``u - z``) again would not follow.
``simulation.floor.coupled_frf`` is left out on purpose: it is the independent route (the second-order matrices
from ``K_h``, ``C_h`` of Eq. 17, 18) that the tests check the state-space route against.

The coupling of ``model/coupling.py`` (Section 6) is changed the same way, once in each of its two parts: the leg
on ``u - z`` 1.1 times as fast (``leg_acceleration``; the same as 1.1 ``f_h`` for every coupled path) and the
reaction on the modes 1.1 times as strong (``modal_force``; the same as modal masses 1.1 times lighter). The
``floor_mode`` effect, ``simulation.floor.system_matrices`` and ``structure.coupled`` must follow both.
"""

import numpy as np
import pytest

from smd_statespace.effects import FloorMode, make_effect
from smd_statespace.model import SMDModel, coupling, equations
from smd_statespace.model.inputs import CycleInputs
from smd_statespace.person.dynamics import PersonDynamics
from smd_statespace.simulation import simulate_bouncing, simulate_lab_record
from smd_statespace.simulation.floor import FloorModel, coupled_frf, system_matrices
from smd_statespace.structure.coupled import Coupling, occupied_eigenvalues, person_coefficients, state_matrix
from smd_statespace.structure.modes import ModalModel, sdof

F_H, XI_H, FASTER = 2.5, 0.3, 1.1


def _paths(f_h):
    """What each path gives at ``f_h``: arrays by name."""
    rng = np.random.default_rng(np.random.SeedSequence(2))
    model = SMDModel(effects=[make_effect("floor_mode:source=measured")])
    time = np.linspace(0.0, 2.0, 201)
    inputs = CycleInputs(f_b=2.0, time=time, signals={"floor_disp": 1e-3 * np.sin(9 * time),
                                                      "floor_vel": 9e-3 * np.cos(9 * time)})
    x = np.zeros((time.size, model.n_state))
    x[:, model.index("u")], x[:, model.index("u_dot")] = rng.normal(0, 0.02, time.size), rng.normal(0, 0.2, time.size)
    x[:, model.index("f_h")], x[:, model.index("xi_h")], x[:, model.index("a0")] = f_h, XI_H, 0.1
    floor = FloorModel(frequency=(5.0,), damping=(0.02,), modal_mass=(1000.0,), shape=(1.0,))
    person = PersonDynamics(SMDModel(n_harmonics=2), time).linearise(f_h, XI_H)
    cubic = PersonDynamics(SMDModel(n_harmonics=2, effects=[make_effect("cubic_stiffness")]), time)
    nominal = np.column_stack([0.02 * np.sin(13 * time), 0.26 * np.cos(13 * time)])
    plain = simulate_bouncing(mass=70, f_b=2.0, f_h=f_h, xi_h=XI_H, duration=4, seed=3)
    lab = simulate_lab_record(mass=70, f_b=2.0, f_h=f_h, xi_h=XI_H, bout=4, stand_before=1, stand_after=1, seed=3)
    return {
        "model acceleration (every per-cycle estimator, with the floor effect)": model.acceleration(x, time, inputs),
        "model Jacobian (EKF)": model.acceleration_jacobian(x, time, inputs)[:, [model.index(name) for name in (
            "u", "u_dot", "f_h", "xi_h", "a0", "a1")]],
        "record-level A, h_x": np.concatenate([person.A.ravel(), person.hx.ravel()]),
        "record-level, a nonlinear effect along a path": cubic.linearise(f_h, XI_H, {"beta_3": 800.0}, nominal).A,
        "frequency response": equations.acceleration_frf(np.linspace(0.5, 8, 40), f_h, XI_H),
        "person on a floor: matrices": np.concatenate([m.ravel() for m in system_matrices(70, f_h, XI_H, floor)]),
        "a crowd on a structure's modes": state_matrix(Coupling(sdof(), [0, 0], [70.0, 80.0], [f_h, 2 * f_h],
                                                                [XI_H, 0.4])),
        "simulator": plain.record.force,
        "lab export simulator": lab.record.force,
    }


def test_changing_eq2_in_one_place_changes_every_path(monkeypatch):
    unchanged = _paths(FASTER * F_H)
    original = equations.smd_acceleration
    monkeypatch.setattr(equations, "smd_acceleration",
                        lambda u, u_dot, f_h, xi_h, force_g: original(u, u_dot, FASTER * np.asarray(f_h), xi_h,
                                                                      force_g))
    changed = _paths(F_H)
    for name, value in changed.items():
        expected = unchanged[name]
        if name == "model Jacobian (EKF)":  # d/df_h: the chain rule's factor of the faster leg
            expected = expected * np.array([1, 1, FASTER, 1, 1, 1])
        np.testing.assert_allclose(value, expected, rtol=1e-7, atol=1e-9 * np.max(np.abs(expected)), err_msg=name)


def test_the_derivatives_taken_from_eq2_are_its_analytic_ones():
    rng = np.random.default_rng(np.random.SeedSequence(3))
    u, v = rng.normal(0, 0.02, 50), rng.normal(0, 0.3, 50)
    f_h, xi_h = rng.uniform(1.5, 4.5, 50), rng.uniform(0.05, 0.6, 50)
    omega = 2 * np.pi * f_h
    derivatives = equations.acceleration_derivatives(u, v, f_h, xi_h)
    np.testing.assert_allclose(derivatives["u"], -omega**2, rtol=1e-14)
    np.testing.assert_allclose(derivatives["u_dot"], -2 * xi_h * omega, rtol=1e-14)
    np.testing.assert_allclose(derivatives["f_h"], 2 * np.pi * (-2 * omega * u - 2 * xi_h * v), rtol=1e-12)
    np.testing.assert_allclose(derivatives["xi_h"], -2 * omega * v, rtol=1e-12)
    np.testing.assert_array_equal(derivatives["force_g"], 1.0)
    frequency = np.linspace(0.2, 9, 30)
    w = 2 * np.pi * frequency
    np.testing.assert_allclose(equations.acceleration_frf(frequency, 2.5, 0.3),
                               -w**2 / ((2 * np.pi * 2.5) ** 2 - w**2 + 2j * 0.3 * 2 * np.pi * 2.5 * w), rtol=1e-13)


def test_the_change_is_seen_where_a_path_keeps_its_own_copy(monkeypatch):
    """The negative case: ``coupled_frf`` builds the person on a floor from ``K_h``, ``C_h`` (Eq. 17, 18), not from
    Eq. 2; it does not follow the change, and the comparison of the first test says so."""
    floor = FloorModel(frequency=(5.0,), damping=(0.02,), modal_mass=(1000.0,), shape=(1.0,))
    frequency = np.linspace(0.5, 8, 40)
    unchanged = coupled_frf(frequency, 70, FASTER * F_H, XI_H, floor)["u_ddot"]
    original = equations.smd_acceleration
    monkeypatch.setattr(equations, "smd_acceleration",
                        lambda u, u_dot, f_h, xi_h, force_g: original(u, u_dot, FASTER * np.asarray(f_h), xi_h,
                                                                      force_g))
    with pytest.raises(AssertionError):
        np.testing.assert_allclose(coupled_frf(frequency, 70, F_H, XI_H, floor)["u_ddot"], unchanged, rtol=1e-7)


def _coupled_paths(f_h, lighter):
    """What each user of ``model.coupling`` gives at ``f_h`` on floor modes ``lighter`` times lighter, by name."""
    rng = np.random.default_rng(np.random.SeedSequence(4))
    time = np.linspace(0.0, 2.0, 101)
    inputs = CycleInputs(f_b=2.0, time=time)
    floor = FloorMode("modal", frequency=3.48, damping=0.004, mass_ratio=0.01 * lighter)
    model = SMDModel(effects=[floor])
    x = rng.normal(0.0, [0.02, 0.2] + [0.0] * (model.n_state - 4) + [1e-3, 1e-2], (time.size, model.n_state))
    x[:, model.index("f_h")], x[:, model.index("xi_h")], x[:, model.index("a0")] = f_h, XI_H, 0.1
    acc, acc_jacobian = rng.normal(0.0, 3.0, time.size), rng.normal(0.0, 3.0, (time.size, model.n_state))
    modes = FloorModel(frequency=(5.0, 7.5), damping=(0.02, 0.01), modal_mass=(1000.0 / lighter, 3000.0 / lighter),
                       shape=(0.9, -0.5))
    structure = ModalModel(np.array(modes.frequency), np.array(modes.damping), np.array(modes.modal_mass), ("a", "b"),
                           np.zeros((2, 2)), np.array([[0.9, -0.5], [0.4, 0.8]]))
    crowd = Coupling(structure, [0, 1, 1], [70.0, 80.0, 60.0], [f_h, 1.3 * f_h, 0.8 * f_h], [XI_H, 0.4, 0.2])
    return {
        "floor_mode effect: the floor's pull on the COM": floor.acceleration(model, x, time, inputs),
        "floor_mode effect: its Jacobian (EKF)": floor.acceleration_jacobian(model, x, time, inputs),
        "floor_mode effect: the floor's rates": floor.slot_rates(model, x, time, inputs, acc),
        "floor_mode effect: their Jacobian": floor.slot_rates_jacobian(model, x, time, inputs, acc, acc_jacobian),
        "person on floor modes: system_matrices": np.concatenate([m.ravel() for m in system_matrices(
            70.0, f_h, XI_H, modes)]),
        "crowd on modes: state_matrix": state_matrix(crowd),
        "crowd on modes: person_coefficients": np.concatenate(person_coefficients(crowd.f_h, crowd.xi_h)),
        "crowd on modes: occupied eigenvalues (Newton on det D)": occupied_eigenvalues(crowd),
    }


def _change_the_coupling(monkeypatch, part):
    """Change ``part`` of ``model.coupling``: the leg 1.1 times as fast or the reaction 1.1 times as strong."""
    if part == "leg":
        leg = coupling.leg_acceleration
        monkeypatch.setattr(coupling, "leg_acceleration", lambda u, u_dot, z, z_dot, f_h, xi_h, force_g=0.0: leg(
            u, u_dot, z, z_dot, FASTER * np.asarray(f_h), xi_h, force_g))
    else:
        reaction = coupling.modal_force
        monkeypatch.setattr(coupling, "modal_force", lambda shape, mass, u_ddot: FASTER * reaction(shape, mass, u_ddot))


@pytest.mark.parametrize("part", ["leg", "reaction"])
def test_changing_the_coupling_in_one_place_changes_its_three_users(monkeypatch, part):
    """The floor effect, the person on floor modes and the crowd on a structure all follow a change of either part of
    the one coupling: the leg's change is 1.1 ``f_h`` for them (not for the model's own Eq. 2), the reaction's change
    modal masses 1.1 times lighter (a mass ratio 1.1 times larger)."""
    unchanged = _coupled_paths(FASTER * F_H, 1.0) if part == "leg" else _coupled_paths(F_H, FASTER)
    original = _coupled_paths(F_H, 1.0)
    _change_the_coupling(monkeypatch, part)
    changed = _coupled_paths(F_H, 1.0)
    model = SMDModel(effects=[FloorMode("modal", frequency=3.48, damping=0.004)])
    chain = np.ones(model.n_state)
    chain[model.index("f_h")] = FASTER if part == "leg" else 1.0  # d/df_h: the chain rule's factor of the faster leg
    moved = 0
    for name, value in changed.items():
        expected = unchanged[name] * (chain if name == "floor_mode effect: its Jacobian (EKF)" else 1.0)
        np.testing.assert_allclose(value, expected, rtol=1e-7, atol=1e-9 * np.max(np.abs(expected)), err_msg=name)
        moved += not np.allclose(value, original[name], rtol=1e-7, atol=0.0)
    # the leg moves everything but the floor's own rates; the reaction moves those and the matrices, not the leg
    assert moved == (6 if part == "leg" else 5)


@pytest.mark.parametrize("part", ["leg", "reaction"])
def test_a_path_that_writes_the_coupling_itself_does_not_follow(monkeypatch, part):
    """The negative case: ``coupled_frf`` writes the person on floor modes out from ``K_h``, ``C_h`` (Eq. 17, 18) and
    its own ``u - z``; it does not follow the change of the coupling (``system_matrices``, on the same floor, does),
    and the comparison above says so."""
    modes = FloorModel(frequency=(5.0,), damping=(0.02,), modal_mass=(1000.0,), shape=(0.9,))
    lighter = FloorModel(frequency=(5.0,), damping=(0.02,), modal_mass=(1000.0 / FASTER,), shape=(0.9,))
    frequency = np.linspace(0.5, 8, 40)
    f_h, floor = (FASTER * F_H, modes) if part == "leg" else (F_H, lighter)
    frf, matrix = coupled_frf(frequency, 70, f_h, XI_H, floor)["u_ddot"], system_matrices(70, f_h, XI_H, floor)[0]
    _change_the_coupling(monkeypatch, part)
    np.testing.assert_allclose(system_matrices(70, F_H, XI_H, modes)[0], matrix, rtol=1e-12,
                               atol=1e-12 * np.max(np.abs(matrix)))
    with pytest.raises(AssertionError):
        np.testing.assert_allclose(coupled_frf(frequency, 70, F_H, XI_H, modes)["u_ddot"], frf, rtol=1e-7)
