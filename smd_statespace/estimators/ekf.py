"""Extended Kalman filter: filterpy's ``ExtendedKalmanFilter`` with the model's analytic Jacobians.

filterpy's EKF predicts linearly (``x = F x + B u``). ``_ModelEKF`` (in
:mod:`._filterpy`, imported when the filter runs) overrides ``predict_x`` so
that the state moves by the model's nonlinear
:meth:`~smd_statespace.model.SMDModel.transition` (Eq. 11-12) while ``F``,
the transition's Jacobian at the previous estimate, propagates the
covariance. The update uses the observation (Eq. 14-16) and its Jacobian.
"""

from __future__ import annotations

import numpy as np

from ..model import SMDModel
from .base import (CycleData, CovarianceGuard, Estimator, FreeState, GaussianStart, GaussianTrace, gaussian_start,
                   prepare, register_estimator)


@register_estimator
class ExtendedFilter(Estimator):
    """filterpy's EKF with the model's nonlinear transition and analytic Jacobians.

    Parameters
    ----------
    process_noise_std, observation_noise_std : array_like, optional
        Override the model's default noise levels.

    Attributes (after :meth:`run`)
    ------------------------------
    filter_ : filterpy.kalman.ExtendedKalmanFilter
        The filterpy object after the last sample (``x``, ``P``, ``F``, ``y``, ``S``, ``K``).
    """

    name = "ekf"

    def __init__(self, process_noise_std=None, observation_noise_std=None):
        self.process_noise_std = process_noise_std
        self.observation_noise_std = observation_noise_std

    def run(self, model: SMDModel, data: CycleData, start=None, rng=None, fixed=None):
        from ._filterpy import _ModelEKF  # here, not at the top: filterpy loads scipy.stats (0.7 s)

        setup = prepare(model, data, fixed, self.process_noise_std, self.observation_noise_std)
        free_state = FreeState(setup)
        mean, cov = gaussian_start(model, setup, start)
        free = free_state.free
        ekf = _ModelEKF(model, data, free_state)
        ekf.x = mean[free][:, None]
        ekf.P = cov[np.ix_(free, free)]
        ekf.Q = np.diag(setup.q_std[free] ** 2)
        ekf.R = np.diag(setup.r_std**2)
        guard = CovarianceGuard()
        trace = GaussianTrace(model, data)
        with np.errstate(over="ignore", invalid="ignore"):  # divergence is reported by GaussianTrace
            for k in range(len(data)):
                if k > 0:
                    ekf.t, ekf.step = data.t[k - 1], data.t[k] - data.t[k - 1]
                    ekf.predict()
                    ekf.P = guard.repair(ekf.P)
                ekf.update(data.y[k][:, None], ekf.h_jacobian, ekf.h, args=(data.t[k],), hx_args=(data.t[k],))
                ekf.P = guard.repair(ekf.P)
                trace.record(k, free_state, ekf.x, ekf.P, ekf.y, ekf.S)
        self.filter_ = ekf
        restart = GaussianStart(trace.mean[-1], free_state.embed_cov(ekf.P), carry_over=True)
        return trace.result(self.name, model, data, setup, restart, {"covariance_repairs": guard.repairs})
