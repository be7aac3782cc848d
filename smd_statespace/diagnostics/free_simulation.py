"""Free simulation of one identified cycle: the model alone, from the starting state that fits the cycle best.

Used by :class:`~smd_statespace.diagnostics.check.ModelCheck` (see
:mod:`smd_statespace.diagnostics.check` for what the free simulation is for):

- :func:`simulate_from`: integrate the model without noise from a state over a cycle's samples;
- :func:`free_simulation`: from the filter's estimate at the cycle's first sample;
- :func:`fit_initial_state`: from the dynamic starting state that fits the cycle best (least squares);
- :func:`path_sensitivity`: derivative of the simulated output with respect to the starting state.

``model`` is an :class:`~smd_statespace.model.SMDModel`, ``data`` a cycle's
:class:`~smd_statespace.estimators.CycleData` (``t`` in s, ``y`` the measured
channels, ``inputs``), states in the model's slot order and SI units.
"""

from __future__ import annotations

import numpy as np

from .subspace import chain_sensitivity

__all__ = ["simulate_from", "free_simulation", "fit_initial_state", "path_sensitivity"]


def simulate_from(model, x, data) -> np.ndarray:
    """Integrate the model without noise from state ``x`` over the cycle's samples.

    Parameters
    ----------
    model : SMDModel
    x : ndarray, shape (n_state,)
        State at the cycle's first sample.
    data : CycleData

    Returns
    -------
    ndarray, shape (m, n_state)
        The states at the cycle's ``m`` samples (:meth:`SMDModel.transition`, no process noise).
    """
    states = np.empty((len(data.t), model.n_state))
    states[0] = x
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(1, len(data.t)):
            x = model.transition(x, data.t[k - 1], data.t[k] - data.t[k - 1], data.inputs)
            states[k] = x
    return states


def free_simulation(model, result, data, dynamic) -> np.ndarray:
    """States of the free simulation of one cycle from the filter's estimate, shape (m, n_state).

    Dynamic slots start from the filtered mean at the cycle's first
    sample, parameters are the final-pass values (``result.final_mean``);
    :func:`simulate_from`.

    Parameters
    ----------
    model : SMDModel
    result : FilterResult
        The cycle's final-pass filter result.
    data : CycleData
    dynamic : ndarray of bool, shape (n_state,)
        Which slots are dynamic (``u``, ``u_dot``, an effect's states).
    """
    x = np.array(result.final_mean, dtype=float)
    x[dynamic] = np.asarray(result.mean)[0, dynamic]
    return simulate_from(model, x, data)


def path_sensitivity(model, states, data, channel) -> np.ndarray:
    """Derivative of the simulated output ``channel`` at every sample with respect to the starting state.

    The chain ``H_k F_{k-1} ... F_0`` (:func:`subspace.chain_sensitivity`)
    of the model's own Jacobians (:meth:`SMDModel.transition_jacobian`,
    :meth:`SMDModel.observation_jacobian`) along ``states`` (Eq. 11-16
    linearised along the free simulation).

    Returns
    -------
    ndarray, shape (m, n_state)
        Row ``k``: ``d y_k / d x_0`` (output unit per state unit).
    """
    steps = np.diff(data.t)
    with np.errstate(over="ignore", invalid="ignore"):
        if steps.size and np.ptp(steps) <= 1e-9 * abs(steps[0]):  # evenly sampled: every step's Jacobian at once
            jacobians = model.transition_jacobian(states[:-1], data.t[:-1], float(steps[0]), data.inputs)
        else:
            jacobians = np.array([model.transition_jacobian(states[k - 1], data.t[k - 1], steps[k - 1], data.inputs)
                                  for k in range(1, len(data.t))])
        jacobians = jacobians.reshape(-1, model.n_state, model.n_state)
        observation = model.observation_jacobian(states, data.t, data.inputs)[:, channel, :]
    return chain_sensitivity(jacobians, observation)


def fit_initial_state(model, states, data, dynamic, keep, channel, iterations=2) -> np.ndarray:
    """Free simulation from the dynamic starting state that best fits the cycle (least squares).

    The parameters stay at their identified values; only the dynamic
    slots' starting values (``u``, ``u_dot``, an estimated floor's ``z``,
    ``z_dot``, ...) change, by Gauss-Newton steps on the measured output
    ``channel`` of the cycle's kept samples, with the sensitivities of
    :func:`path_sensitivity`. One step is exact when the model is linear in
    those slots (every built-in effect but ``cubic_stiffness``).

    Parameters
    ----------
    model : SMDModel
    states : ndarray, shape (m, n_state)
        A first free simulation (:func:`free_simulation`).
    data : CycleData
    dynamic : ndarray of bool, shape (n_state,)
        The slots whose starting values are fitted.
    keep : slice
        The cycle's samples the fit uses.
    channel : int
        The measured channel fitted (``u''``).
    iterations : int
        Gauss-Newton steps.

    Returns
    -------
    ndarray, shape (m, n_state)
        The free simulation from the fitted start (``states`` itself if a step is not finite).
    """
    measured = data.y[keep, channel]
    for _ in range(iterations):
        sensitivity = path_sensitivity(model, states, data, channel)[keep][:, dynamic]
        predicted = model.observe(states, data.t, data.inputs)[keep, channel]
        step, *_ = np.linalg.lstsq(sensitivity, measured - predicted, rcond=None)
        if not np.all(np.isfinite(step)):
            return states
        start = states[0].copy()
        start[dynamic] += step
        states = simulate_from(model, start, data)
    return states
