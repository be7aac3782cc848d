"""Unscented Kalman filter: filterpy's ``UnscentedKalmanFilter`` on the shared model.

The filter runs on the free slots of the augmented state (Eq. 7); its ``fx``
and ``hx`` are the model's :meth:`~smd_statespace.model.SMDModel.transition`
and :meth:`~smd_statespace.model.SMDModel.observe` (Eq. 11-16). Sigma points
are ``MerweScaledSigmaPoints``. filterpy factorises the covariance with a
Cholesky decomposition that fails when rounding makes it indefinite
(filterpy issues 31, 62, 218); a :class:`~.base.CovarianceGuard` is passed as
``sqrt_fn`` and also cleans ``P`` after every step, and the number of repairs
is reported in ``diagnostics["covariance_repairs"]``.
"""

from __future__ import annotations

import numpy as np

from ..model import SMDModel
from .base import (CycleData, CovarianceGuard, Estimator, FreeState, GaussianStart, GaussianTrace, gaussian_start,
                   prepare, register_estimator)


@register_estimator
class UnscentedFilter(Estimator):
    """filterpy's UKF with the model's transition and observation.

    Parameters
    ----------
    alpha, beta, kappa : float
        ``MerweScaledSigmaPoints`` parameters; ``kappa=None`` means ``3 - n``.
    vectorised : bool
        Move and observe all sigma points in one call of the model's
        transition and observation each (default) instead of filterpy's loops
        over them; the numbers are the same, about ten times faster
        (docs/performance.md).
    process_noise_std, observation_noise_std : array_like, optional
        Override the model's default noise levels.

    Attributes (after :meth:`run`)
    ------------------------------
    filter_ : filterpy.kalman.UnscentedKalmanFilter
        The filterpy object after the last sample (``x``, ``P``, ``y``, ``S``, ``K``).
    """

    name = "ukf"

    def __init__(self, alpha: float = 1.0, beta: float = 2.0, kappa: float | None = None, vectorised: bool = True,
                 process_noise_std=None, observation_noise_std=None):
        self.vectorised = bool(vectorised)
        self.alpha = float(alpha)
        self.beta = float(beta)
        self.kappa = kappa
        self.process_noise_std = process_noise_std
        self.observation_noise_std = observation_noise_std

    def run(self, model: SMDModel, data: CycleData, start=None, rng=None, fixed=None):
        # here, not at the top: filterpy loads scipy.stats (0.7 s), which the record-level model may not need
        from filterpy.kalman import MerweScaledSigmaPoints, UnscentedKalmanFilter

        from ._filterpy import _BatchUKF

        setup = prepare(model, data, fixed, self.process_noise_std, self.observation_noise_std)
        free_state = FreeState(setup)
        mean, cov = gaussian_start(model, setup, start)
        n = free_state.free.size
        guard = CovarianceGuard()
        kappa = 3.0 - n if self.kappa is None else float(self.kappa)
        points = MerweScaledSigmaPoints(n, alpha=self.alpha, beta=self.beta, kappa=kappa, sqrt_method=guard.sqrt)

        def fx(z, dt, t):
            return model.transition(free_state.embed(z), t, dt, data.inputs)[..., free_state.free]

        def hx(z, t):
            return model.observe(free_state.embed(z), t, data.inputs)

        ukf = (_BatchUKF if self.vectorised else UnscentedKalmanFilter)(dim_x=n, dim_z=model.n_obs, dt=data.dt, hx=hx, fx=fx, points=points,
                                    sqrt_fn=guard.sqrt)
        ukf.x = mean[free_state.free]
        ukf.P = cov[np.ix_(free_state.free, free_state.free)]
        ukf.Q = np.diag(setup.q_std[free_state.free] ** 2)
        ukf.R = np.diag(setup.r_std**2)
        trace = GaussianTrace(model, data)
        with np.errstate(over="ignore", invalid="ignore"):  # divergence is reported by GaussianTrace
            for k in range(len(data)):
                if k == 0:
                    ukf.sigmas_f = points.sigma_points(ukf.x, ukf.P)
                else:
                    ukf.predict(dt=data.t[k] - data.t[k - 1], t=data.t[k - 1])
                    ukf.P = guard.repair(ukf.P)
                ukf.update(data.y[k], t=data.t[k])
                ukf.P = guard.repair(ukf.P)
                trace.record(k, free_state, ukf.x, ukf.P, ukf.y, ukf.S)
        self.filter_ = ukf
        restart = GaussianStart(trace.mean[-1], free_state.embed_cov(ukf.P), carry_over=True)
        return trace.result(self.name, model, data, setup, restart,
                            {"covariance_repairs": guard.repairs, "sigma_points": 2 * n + 1})
