"""Batched Kalman filters on the conditionally linear slots of the model.

Once the non-linear slots (``f_h``, ``xi_h``, see ``Slot.linear``) are fixed,
the SMD model (Eq. 10-16) is linear and Gaussian in the others (``u``,
``u_dot``, the Fourier coefficients). :class:`ConditionalKalman` runs one
Kalman filter per value of the non-linear slots, all at once: a batch of
grid points (:mod:`.grid`) or of particles (:mod:`.rbpf`). The matrices are
the model's own Jacobians, so the filter is exact when the model is linear in
those slots and an extended Kalman filter otherwise.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..model import SMDModel
from .base import EstimatorFailure, Setup

LOG_2PI = np.log(2.0 * np.pi)


_VERIFIED: set = set()
"""Models (by ``id``) whose linearity has been checked in this process."""


def verify_linear(model: SMDModel, inputs) -> dict:
    """Check once per model that its rate is linear in the slots the Kalman part filters.

    A wrong declaration by an effect raises
    :class:`~smd_statespace.errors.OptionError`
    (:func:`~smd_statespace.model.jacobians.check_linearity`); a base slot made
    non-linear by an effect (``u`` under a cubic spring) gives a warning: the
    conditional Kalman filter then linearises, like an EKF, and its posterior
    is approximate. Returns the failures.
    """
    if id(model) in _VERIFIED:
        return {}
    from ..model.jacobians import check_linearity

    failures = check_linearity(model, inputs, t=inputs.t0 + 0.1)
    _VERIFIED.add(id(model))
    if failures:
        warnings.warn(f"the model is not linear in {', '.join(sorted(failures))} (an effect's term is non-linear "
                      "in them): the Kalman part of this estimator linearises there, like an EKF, so its posterior "
                      "is approximate", stacklevel=3)
    return failures


class ConditionalKalman:
    """Kalman filters over the linear slots, batched over values of the non-linear ones.

    Parameters
    ----------
    model : SMDModel
    setup : Setup
        Noise levels from :func:`~.base.prepare`.
    linear : ndarray of int
        Positions of the slots the filters estimate.

    Notes
    -----
    States ``x`` have shape ``(B, n_state)``: the non-linear slots hold the
    batch's values, the linear slots the filters' means. Covariances ``P``
    have shape ``(B, n_linear, n_linear)``.
    """

    def __init__(self, model: SMDModel, setup: Setup, linear):
        self.model = model
        self.linear = np.asarray(linear)
        self.Q = np.diag(setup.q_std[self.linear] ** 2)
        self.R = np.diag(setup.r_std**2)
        self.eye = np.eye(self.linear.size)

    def predict(self, x, P, t, dt, inputs):
        """Move means by the model's transition, covariances by its Jacobian (Eq. 11-12)."""
        lin = self.linear
        x, jacobian = self.model.transition_and_jacobian(x, t, dt, inputs)
        F = jacobian[:, lin][:, :, lin]
        return x, F @ P @ F.transpose(0, 2, 1) + self.Q

    def predict_observation(self, x, P, t, inputs):
        """Predicted observation, its covariance ``S`` and the observation Jacobian ``H`` (Eq. 14-16)."""
        H = self.model.observation_jacobian(x, t, inputs)[:, :, self.linear]
        predicted = self.model.observe(x, t, inputs)
        S = H @ P @ H.transpose(0, 2, 1) + self.R
        return predicted, S, H

    def update(self, x, P, y, predicted, S, H, where=""):
        """Kalman update of every filter with observation ``y``.

        Returns the updated ``x``, ``P`` (Joseph form) and every filter's
        log predictive density ``log N(y; predicted, S)``, shape ``(B,)``.
        An innovation covariance that is not positive definite raises
        :class:`~smd_statespace.estimators.base.EstimatorFailure` naming
        ``where`` (e.g. ``"cycle 3, sample 12"``).
        """
        residual = y - predicted
        try:
            chol = np.linalg.cholesky(S)
        except np.linalg.LinAlgError:
            raise EstimatorFailure(f"{where}: innovation covariance not positive definite") from None
        solved = np.linalg.solve(chol, residual[..., None])[..., 0]
        log_det = 2.0 * np.sum(np.log(np.diagonal(chol, axis1=1, axis2=2)), axis=1)
        log_density = -0.5 * (np.sum(solved**2, axis=1) + log_det + residual.shape[-1] * LOG_2PI)
        gain = np.linalg.solve(S, H @ P).transpose(0, 2, 1)  # K = P H' S^-1, S symmetric
        x = x.copy()
        x[:, self.linear] += (gain @ residual[..., None])[..., 0]
        I_KH = self.eye - gain @ H
        P = I_KH @ P @ I_KH.transpose(0, 2, 1) + gain @ self.R @ gain.transpose(0, 2, 1)
        return x, P, log_density


def normalised(log_weights):
    """Weights summing to one from log-weights."""
    from scipy.special import logsumexp  # imported here: scipy.special takes 0.2 s (not needed to start)

    return np.exp(log_weights - logsumexp(log_weights))


def mixture_moments(weights, x, P, linear):
    """Mean and standard deviation of a weighted mixture of Gaussians (law of total variance)."""
    mean = weights @ x
    second = weights @ (x - mean) ** 2
    second[linear] += weights @ np.diagonal(P, axis1=1, axis2=2)
    return mean, np.sqrt(np.maximum(second, 0.0))


def mixture_covariance(weights, x, P, linear):
    """Full covariance of a weighted mixture of Gaussians."""
    spread = x - weights @ x
    cov = (weights[:, None] * spread).T @ spread
    cov[np.ix_(linear, linear)] += np.einsum("g,gij->ij", weights, P)
    return cov


def predictive_mixture(weights, predicted, S):
    """Mean and covariance of the observation predicted by a weighted mixture of filters."""
    mean = weights @ predicted
    spread = predicted - mean
    return mean, np.einsum("g,gij->ij", weights, S) + (weights[:, None] * spread).T @ spread
