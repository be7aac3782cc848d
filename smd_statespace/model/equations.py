"""The closed-form equations of the SMD model (Eq. 2, 5, 17, 18): no state layout, no effects.

================================ ==================================================
function                         what it computes
================================ ==================================================
:func:`smd_acceleration`         the COM acceleration of Eq. 2, the one place it is written
:func:`acceleration_derivatives` its derivatives, taken from it (unit inputs, a complex step)
:func:`linear_derivatives`       those two rules for any function linear in its inputs
:func:`acceleration_frf`         Eq. 2's frequency response from force to acceleration, taken from it
:func:`k_h`, :func:`c_h`         leg stiffness and damping (Eq. 17, 18)
:func:`blf`                      biomechanical load factor (Eq. 5)
================================ ==================================================

All but :func:`linear_derivatives` are re-exported by :mod:`smd_statespace.model.core` and
:mod:`smd_statespace.model`.

Every other place that needs Eq. 2 calls :func:`smd_acceleration` through this module
(``equations.smd_acceleration``), its derivatives and frequency response included, so that a change
made here reaches every path: the per-cycle estimators' model and Jacobian, the record-level model,
the simulators (on a rigid floor, a lab's export), the person-floor coupling of
:mod:`~smd_statespace.model.coupling` (and through it the floor effect, a person on floor modes and a
crowd on a structure) and the plausibility rules (``tests/test_equation_once.py`` changes it here and
checks each of them). Only the particle filter's compiled kernel keeps a twin, tested against it.
"""

from __future__ import annotations

import numpy as np

from .inputs import TWO_PI


def k_h(f_h, mass):
    """Leg stiffness ``K_h = M_h (2 pi f_h)^2`` in N/m (Eq. 17).

    Parameters
    ----------
    f_h : float or ndarray
        SMD natural frequency (Hz).
    mass : float or ndarray
        Body mass ``M_h`` (kg).
    """
    return np.asarray(mass) * (TWO_PI * np.asarray(f_h)) ** 2


def c_h(xi_h, f_h, mass):
    """Leg damping ``C_h = 2 xi_h M_h (2 pi f_h)`` in N s/m (Eq. 18).

    Parameters
    ----------
    xi_h : float or ndarray
        SMD damping ratio (-).
    f_h : float or ndarray
        SMD natural frequency (Hz).
    mass : float or ndarray
        Body mass ``M_h`` (kg).
    """
    return 2.0 * np.asarray(xi_h) * np.asarray(mass) * TWO_PI * np.asarray(f_h)


def smd_acceleration(u, u_dot, f_h, xi_h, force_g):
    """COM acceleration of the SMD, Eq. 2: the one place the equation is written.

    ``u'' = -omega_h^2 u - 2 xi_h omega_h u' + g F``, ``omega_h = 2 pi f_h``.
    :meth:`SMDModel.acceleration` (every estimator), the record-level model
    (through the model's rates) and the simulator
    (:mod:`smd_statespace.simulation.dynamics`; relative to the floor in
    :func:`smd_statespace.model.coupling.leg_acceleration`) all call it; only
    the compiled particle-filter kernel keeps a tested twin.

    Parameters
    ----------
    u, u_dot : float or ndarray
        COM displacement (m) and velocity (m/s).
    f_h : float or ndarray
        SMD natural frequency (Hz).
    xi_h : float or ndarray
        SMD damping ratio (-).
    force_g : float or ndarray
        The force per unit mass ``F_bio / M_h = g F`` (m/s^2). Arrays broadcast.

    Returns
    -------
    ndarray
        ``u''`` (m/s^2).
    """
    omega = TWO_PI * np.asarray(f_h)
    return -omega**2 * u - 2.0 * np.asarray(xi_h) * omega * u_dot + force_g  # Eq. 2


COMPLEX_STEP = 1e-20
"""Imaginary step of :func:`acceleration_derivatives` (exact to rounding: no difference is taken)."""


def acceleration_derivatives(u, u_dot, f_h, xi_h) -> dict:
    """Derivatives of :func:`smd_acceleration` (Eq. 2), taken from it rather than written again.

    Eq. 2 is linear in ``u``, ``u'`` and ``g F``: their coefficients are its values at unit inputs. Its
    derivatives in ``f_h`` and ``xi_h`` are complex steps (``Im f(p + i h) / h``, Squire & Trapp 1998),
    exact to rounding. Both by :func:`linear_derivatives`.

    Parameters
    ----------
    u, u_dot : float or ndarray
        COM displacement (m) and velocity (m/s).
    f_h, xi_h : float or ndarray
        SMD natural frequency (Hz) and damping ratio (-). Arrays broadcast.

    Returns
    -------
    dict
        ``u`` (1/s^2), ``u_dot`` (1/s), ``force_g`` (-), ``f_h`` (m/s^2 per Hz) and ``xi_h`` (m/s^2): the
        partial derivatives of ``u''``.
    """
    return linear_derivatives(smd_acceleration, {"u": u, "u_dot": u_dot, "force_g": 0.0}, f_h=f_h, xi_h=xi_h)


def linear_derivatives(function, inputs: dict, **parameters) -> dict:
    """Partial derivatives of ``function(**inputs, **parameters)``, a function linear in ``inputs``.

    Its coefficients on the inputs are its values at unit inputs (exact: it is linear in them); its derivatives in
    the parameters are complex steps (``Im f(p + i h) / h``, Squire & Trapp 1998), exact to rounding. Eq. 2
    (:func:`acceleration_derivatives`) and the leg on a moving floor
    (:func:`smd_statespace.model.coupling.leg_derivatives`) take theirs from here.

    Parameters
    ----------
    function : callable
        Called with keywords: the names of ``inputs`` and of ``parameters``; linear in the inputs.
    inputs : dict
        The point: each input's value (float or ndarray).
    **parameters : float or ndarray
        The parameters (arrays broadcast), converted to float arrays.

    Returns
    -------
    dict
        The derivative in each input, then in each parameter, by name.
    """
    parameters = {name: np.asarray(value, dtype=float) for name, value in parameters.items()}
    zeros = dict.fromkeys(inputs, 0.0)
    out = {name: function(**{**zeros, name: 1.0}, **parameters) for name in inputs}
    for name, value in parameters.items():
        stepped = {**parameters, name: value + 1j * COMPLEX_STEP}
        out[name] = np.imag(function(**inputs, **stepped)) / COMPLEX_STEP
    return out


def acceleration_frf(frequency, f_h, xi_h):
    """Frequency response of Eq. 2 from force (in g) to COM acceleration (in g).

    From the coefficients of :func:`smd_acceleration` (``u'' = k u + c u' + e g F``): ``u = U e^{i w t}``
    gives ``-w^2 U = k U + i w c U + e g C``.

    Parameters
    ----------
    frequency : float or array_like
        Excitation frequency (Hz).
    f_h : float or array_like
        SMD natural frequency (Hz).
    xi_h : float or array_like
        SMD damping ratio (-) (arrays broadcast with ``frequency``).

    Returns
    -------
    complex ndarray
        ``H = -w^2 / (w_h^2 - w^2 + 2 i xi_h w_h w)``: the harmonic
        ``g C e^{i w t}`` of ``g F`` produces ``H g C e^{i w t}`` in ``u''``.
    """
    omega = 2.0 * np.pi * np.asarray(frequency, dtype=float)
    k = smd_acceleration(1.0, 0.0, f_h, xi_h, 0.0)  # -w_h^2
    c = smd_acceleration(0.0, 1.0, f_h, xi_h, 0.0)  # -2 xi_h w_h
    e = smd_acceleration(0.0, 0.0, f_h, xi_h, 1.0)  # 1
    return -(omega**2) * e / (-k - omega**2 - 1j * c * omega)


def blf(a, b):
    """Biomechanical load factor ``BLF_i = sqrt(a_i^2 + b_i^2)`` in g (Eq. 5)."""
    return np.hypot(a, b)
