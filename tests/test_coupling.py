"""The person-floor coupling of ``model/coupling.py`` against the closed form of one person on one floor mode.

One person (Eq. 2 on ``u - z``) on a single-degree-of-freedom floor whose mode has the ordinate ``phi`` at the
person, written out by hand in ``x = [u, u', q, q']``::

    u'' = -k (u - phi q) - c (u' - phi q') + g F,      k = w_h^2, c = 2 xi_h w_h
    q'' = -w_f^2 q - 2 xi_f w_f q' - mu u'',           mu = M_h phi / m_f

The coupling's own numbers and its three users (``simulation.floor.system_matrices``, ``structure.coupled``'s state
matrix after reordering its states, the ``floor_mode`` effect's linearisation) must equal it: all four are built on
the one coupling, so a wrong coupling (a sign, a missing ``phi``, the reaction on the wrong mass) would move them all
away from the closed form together.
"""

import numpy as np

from smd_statespace.effects import FloorMode
from smd_statespace.model import SMDModel, coupling
from smd_statespace.model.inputs import CycleInputs
from smd_statespace.simulation.floor import FloorModel, system_matrices
from smd_statespace.structure.coupled import Coupling, state_matrix
from smd_statespace.structure.modes import ModalModel

MASS, F_H, XI_H = 70.0, 2.8, 0.3
F_F, XI_F, M_F, PHI = 4.0, 0.01, 2000.0, 0.8


def closed_form(mass=MASS, f_h=F_H, xi_h=XI_H, f_f=F_F, xi_f=XI_F, m_f=M_F, phi=PHI):
    """``(A, B)`` of the module docstring's 2-DOF system (``x' = A x + B g F``), each element by hand."""
    w_h, w_f = 2 * np.pi * f_h, 2 * np.pi * f_f
    k, c, mu = w_h**2, 2 * xi_h * w_h, mass * phi / m_f
    a_matrix = np.array([[0.0, 1.0, 0.0, 0.0],
                         [-k, -c, k * phi, c * phi],
                         [0.0, 0.0, 0.0, 1.0],
                         [mu * k, mu * c, -w_f**2 - mu * k * phi, -2 * xi_f * w_f - mu * c * phi]])
    return a_matrix, np.array([0.0, 1.0, 0.0, -mu])


def assert_close(actual, expected, name):
    np.testing.assert_allclose(actual, expected, rtol=1e-12, atol=1e-12 * np.max(np.abs(expected)), err_msg=name)


def test_the_coupling_is_eq2_on_u_minus_z_and_the_reaction_on_the_modes():
    rng = np.random.default_rng(np.random.SeedSequence(7))
    u, v, z, z_dot, force = (rng.normal(0.0, scale, 40) for scale in (0.02, 0.2, 1e-3, 1e-2, 3.0))
    f_h, xi_h = rng.uniform(1.5, 4.5, 40), rng.uniform(0.05, 0.6, 40)
    w_h = 2 * np.pi * f_h
    assert_close(coupling.leg_acceleration(u, v, z, z_dot, f_h, xi_h, force),
                 -w_h**2 * (u - z) - 2 * xi_h * w_h * (v - z_dot) + force, "leg")
    assert_close(coupling.modal_force(np.array([0.8, -0.3]), MASS, force[:, None]),
                 -np.array([0.8, -0.3]) * MASS * force[:, None], "reaction")
    derivatives = coupling.leg_derivatives(u, v, z, z_dot, f_h, xi_h)
    analytic = {"u": -w_h**2, "u_dot": -2 * xi_h * w_h, "z": w_h**2, "z_dot": 2 * xi_h * w_h, "force_g": 1.0,
                "f_h": 2 * np.pi * (-2 * w_h * (u - z) - 2 * xi_h * (v - z_dot)), "xi_h": -2 * w_h * (v - z_dot)}
    assert derivatives.keys() == analytic.keys()
    for name, value in analytic.items():
        assert_close(derivatives[name], np.broadcast_to(value, (40,)), name)


def test_modal_coupling_is_the_closed_form_of_one_person_on_one_mode():
    a_matrix, b_vector = closed_form()
    links = coupling.modal_coupling([MASS], [F_H], [XI_H], [[PHI]])
    rows = {"u": a_matrix[1, 0], "u_dot": a_matrix[1, 1], "force_g": b_vector[1], "q": a_matrix[1, 2],
            "q_dot": a_matrix[1, 3], "drive": b_vector[3] * M_F}  # the reaction per unit u'' (kg): -M_h phi
    assert links.keys() == rows.keys()
    for name, value in rows.items():
        assert_close(links[name], np.reshape(value, np.shape(links[name])), name)


def test_the_three_users_of_the_coupling_are_the_two_dof_closed_form():
    """``system_matrices`` and ``structure``'s state matrix (states ``[q, u, q', u']`` reordered) on a mode with
    ``phi = 0.8``; the ``floor_mode`` effect's linearisation in ``u, u', z, z'`` (its ``z`` is ``phi q``: ``phi = 1``
    with the mass ratio ``M_h phi^2 / m_f``, :meth:`FloorModel.as_effect`)."""
    a_matrix, b_vector = closed_form()
    floor = FloorModel(frequency=(F_F,), damping=(XI_F,), modal_mass=(M_F,), shape=(PHI,))
    ours_a, ours_b = system_matrices(MASS, F_H, XI_H, floor)
    assert_close(ours_a, a_matrix, "system_matrices A")
    assert_close(ours_b, b_vector, "system_matrices B")

    structure = ModalModel(np.array([F_F]), np.array([XI_F]), np.array([M_F]), ("P",), np.zeros((1, 2)),
                           np.array([[PHI]]))
    order = [1, 3, 0, 2]  # [q, u, q', u'] -> [u, u', q, q']
    assert_close(state_matrix(Coupling(structure, [0], [MASS], [F_H], [XI_H]))[np.ix_(order, order)], a_matrix,
                 "structure.coupled.state_matrix")

    effect = floor.as_effect(MASS)
    model = SMDModel(effects=[effect])
    time = np.linspace(0.0, 0.5, 11)
    x = np.zeros((time.size, model.n_state))
    x[:, model.index("f_h")], x[:, model.index("xi_h")] = F_H, XI_H
    x[:, model.index("z")] = 1e-3 * np.sin(9 * time)
    states = [model.index(name) for name in ("u", "u_dot", "z", "z_dot")]
    jacobian = model.rate_jacobian(x, time, CycleInputs(f_b=2.0, time=time))[:, states][:, :, states]
    a_effect, _ = closed_form(mass=MASS * PHI, m_f=M_F / PHI, phi=1.0)  # mu = M_h phi^2 / m_f, z = phi q
    for moment in jacobian:
        assert_close(moment, a_effect, "floor_mode effect")
