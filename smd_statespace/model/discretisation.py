"""The model's time discretisation (Eq. 11-12): one forward-Euler or Runge-Kutta step and its exact Jacobian.

:meth:`SMDModel.transition <smd_statespace.model.core.SMDModel.transition>`
and :meth:`~smd_statespace.model.core.SMDModel.transition_jacobian` chain
``substeps`` of these steps over a sample interval. Both read only the model's
``discretisation`` (``"euler"`` or ``"rk4"``) and its continuous-time
:meth:`~smd_statespace.model.core.SMDModel.rate` and
:meth:`~smd_statespace.model.core.SMDModel.rate_jacobian`.
"""

from __future__ import annotations


def step(model, x, t, h, inputs):
    """State after one step of length ``h`` from state(s) ``x`` at time ``t``, without process noise.

    Parameters
    ----------
    model : SMDModel
        Its ``discretisation`` chooses the scheme; its ``rate`` is ``dX/dt``.
    x : ndarray, shape (..., n_state)
        State(s) at ``t``.
    t : float
        Time (s).
    h : float
        Step (s).
    inputs : CycleInputs
        The cycle's known inputs.

    Returns
    -------
    ndarray, shape x.shape
        ``x + h A(x, t) x`` (Euler, Eq. 11-12) or the classical fourth-order
        Runge-Kutta step.
    """
    if model.discretisation == "euler":
        return x + h * model.rate(x, t, inputs)  # Eq. 11-12: A_d = I + A dt
    k1 = model.rate(x, t, inputs)
    k2 = model.rate(x + 0.5 * h * k1, t + 0.5 * h, inputs)
    k3 = model.rate(x + 0.5 * h * k2, t + 0.5 * h, inputs)
    k4 = model.rate(x + h * k3, t + h, inputs)
    return x + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


def step_jacobian(model, x, t, h, inputs, eye):
    """One step (:func:`step`) and its exact derivative with respect to ``x`` (chain rule through the stages).

    Parameters
    ----------
    model : SMDModel
        Its ``discretisation`` chooses the scheme; ``rate_and_jacobian``
        gives ``dX/dt`` and its derivative.
    x : ndarray, shape (..., n_state)
        State(s) at ``t``.
    t : float
        Time (s).
    h : float
        Step (s).
    inputs : CycleInputs
        The cycle's known inputs.
    eye : ndarray, shape (..., n_state, n_state)
        The identity, broadcast to ``x.shape + (n_state,)``.

    Returns
    -------
    x_next : ndarray, shape x.shape
        The state after the step, as :func:`step` gives it.
    jacobian : ndarray, shape x.shape + (n_state,)
        ``d x_next / d x``: for Euler ``I + A h``, the ``A_d`` of Eq. 12.
    """
    if model.discretisation == "euler":
        rate, jacobian = model.rate_and_jacobian(x, t, inputs)
        return x + h * rate, eye + h * jacobian
    stages = []
    increment, increment_jac = 0.0, 0.0
    for c, weight in ((0.0, 1.0), (0.5, 2.0), (0.5, 2.0), (1.0, 1.0)):
        if stages:
            k_prev, dk_prev = stages[-1]
            point = x + c * h * k_prev
            point_jac = eye + c * h * dk_prev
        else:
            point, point_jac = x, eye
        k, dk = model.rate_and_jacobian(point, t + c * h, inputs)
        dk = dk @ point_jac
        stages.append((k, dk))
        increment = increment + weight * k
        increment_jac = increment_jac + weight * dk
    return x + (h / 6.0) * increment, eye + (h / 6.0) * increment_jac
