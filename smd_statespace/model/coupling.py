"""A person on a moving floor (Section 6): how the leg joins the COM to the floor's modes, written once.

The leg's spring and damper (Eq. 2) act on the COM motion relative to the floor under the person, and by
Newton's third law the person pushes each mode with the reaction of their dynamic GRF::

    u''   = -w_h^2 (u - z) - 2 xi_h w_h (u' - z') + g F        (Eq. 2 on u - z; z = sum_k phi_k q_k)
    f_k   = -phi_k M_h u''                                      (modal force on mode k)

``u`` is the absolute COM displacement (m), so ``M_h (g + u'')`` stays the GRF of Eq. 3; the static weight only
sets the floor's static deflection.

================================ ==================================================
function                         what it says
================================ ==================================================
:func:`leg_acceleration`         ``u''`` with Eq. 2's spring and damper on ``u - z``
:func:`modal_force`              the reaction on each mode, ``-phi_k M_h u''``
:func:`leg_derivatives`          the derivatives of :func:`leg_acceleration`, taken from it
:func:`modal_coupling`           both as linear maps on modal coordinates ``q_k``, taken from them
================================ ==================================================

Every model of a person on a floor uses these: the ``floor_mode`` effect
(:class:`smd_statespace.effects.FloorMode`), the exact person on ``r`` floor modes
(:func:`smd_statespace.simulation.floor.system_matrices`) and a crowd on a structure's modes
(:class:`smd_statespace.structure.coupled.Coupling`). Eq. 2 itself comes from
:func:`~smd_statespace.model.equations.smd_acceleration` (``tests/test_equation_once.py`` changes either and
checks that every user follows).
"""

from __future__ import annotations

import numpy as np

from . import equations

__all__ = ["leg_acceleration", "modal_force", "leg_derivatives", "modal_coupling"]


def leg_acceleration(u, u_dot, z, z_dot, f_h, xi_h, force_g=0.0):
    """COM acceleration of a person on a moving floor: Eq. 2's spring and damper act on ``u - z``.

    ``u'' = -w_h^2 (u - z) - 2 xi_h w_h (u' - z') + g F`` (Section 6), from
    :func:`~smd_statespace.model.equations.smd_acceleration`.

    Parameters
    ----------
    u, u_dot : float or ndarray
        Absolute COM displacement (m) and velocity (m/s).
    z, z_dot : float or ndarray
        Floor displacement (m) and velocity (m/s) under the person, upward.
    f_h, xi_h : float or ndarray
        SMD natural frequency (Hz) and damping ratio (-).
    force_g : float or ndarray, optional
        The force per unit mass ``g F`` (m/s^2). Arrays broadcast.

    Returns
    -------
    ndarray
        ``u''`` (m/s^2), absolute.
    """
    return equations.smd_acceleration(u - z, u_dot - z_dot, f_h, xi_h, force_g)  # Eq. 2 on the relative motion


def modal_force(shape, mass, u_ddot):
    """The force of a person's GRF reaction on each floor mode: ``-phi_k M_h u''``.

    The person pushes the floor down with the GRF ``M_h (g + u'')`` (Eq. 3); its dynamic part drives mode ``k``
    through the mode's ordinate ``phi_k`` at the person.

    Parameters
    ----------
    shape : float or ndarray
        Mode-shape ordinates ``phi_k`` at the person (-).
    mass : float or ndarray
        Body mass ``M_h`` (kg); a mass ratio ``M_h / m_k`` gives the force per unit modal mass (m/s^2).
    u_ddot : float or ndarray
        COM acceleration ``u''`` (m/s^2). Arrays broadcast.

    Returns
    -------
    ndarray
        Modal force (N), or modal acceleration (m/s^2) for a mass ratio.
    """
    return -np.asarray(shape) * mass * u_ddot


def leg_derivatives(u, u_dot, z, z_dot, f_h, xi_h) -> dict:
    """Derivatives of :func:`leg_acceleration`, taken from it rather than written again.

    It is linear in ``u``, ``u'``, ``z``, ``z'`` and ``g F``: their coefficients are its values at unit inputs;
    its derivatives in ``f_h`` and ``xi_h`` are complex steps
    (:func:`~smd_statespace.model.equations.linear_derivatives`).

    Parameters
    ----------
    u, u_dot, z, z_dot : float or ndarray
        COM and floor displacement (m) and velocity (m/s).
    f_h, xi_h : float or ndarray
        SMD natural frequency (Hz) and damping ratio (-). Arrays broadcast.

    Returns
    -------
    dict
        ``u``, ``z`` (1/s^2), ``u_dot``, ``z_dot`` (1/s), ``force_g`` (-), ``f_h`` (m/s^2 per Hz) and ``xi_h``
        (m/s^2): the partial derivatives of ``u''``.
    """
    point = {"u": u, "u_dot": u_dot, "z": z, "z_dot": z_dot, "force_g": 0.0}
    return equations.linear_derivatives(leg_acceleration, point, f_h=f_h, xi_h=xi_h)


def modal_coupling(mass, f_h, xi_h, shape) -> dict:
    """People on a floor's modes as linear maps: :func:`leg_acceleration` and :func:`modal_force` on unit inputs.

    Person ``i`` stands where the floor moves ``z_i = sum_k phi_ik q_k``; then
    ``u_i'' = a_i u_i + b_i u_i' + sum_k (A_ik q_k + B_ik q_k') + e_i g F_i`` and the reaction on mode ``k`` is
    ``D_ik u_i''``.

    Parameters
    ----------
    mass, f_h, xi_h : array_like, shape (N,)
        Body masses ``M_h`` (kg), SMD natural frequencies (Hz) and damping ratios (-).
    shape : array_like, shape (N, m)
        Mode-shape ordinates ``phi_ik`` (-) of the ``m`` modes at each person.

    Returns
    -------
    dict
        ``u`` (``a``, 1/s^2), ``u_dot`` (``b``, 1/s) and ``force_g`` (``e``, -), shape (N,); ``q`` (``A``,
        1/s^2), ``q_dot`` (``B``, 1/s) and ``drive`` (``D``, N per m/s^2: kg), shape (N, m).

    Examples
    --------
    A 70 kg person at 2 Hz where mode 1 has the ordinate 0.5: ``A = w_h^2 phi``, ``D = -M_h phi``.

    >>> links = modal_coupling([70.0], [2.0], [0.3], [[0.5]])
    >>> round(float(links["q"][0, 0] / links["u"][0]), 12), float(links["drive"][0, 0])
    (-0.5, -35.0)
    """
    shape = np.asarray(shape, dtype=float)
    leg = leg_derivatives(0.0, 0.0, 0.0, 0.0, f_h, xi_h)  # at rest: the coefficients are all that is used
    return {"u": leg["u"], "u_dot": leg["u_dot"], "force_g": leg["force_g"],
            "q": leg["z"][..., None] * shape, "q_dot": leg["z_dot"][..., None] * shape,  # z = sum_k phi_k q_k
            "drive": modal_force(shape, np.asarray(mass, dtype=float)[..., None], 1.0)}
