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
from filterpy.kalman import MerweScaledSigmaPoints, UnscentedKalmanFilter, unscented_transform

from ..model import SMDModel
from .base import (CycleData, CovarianceGuard, Estimator, FreeState, GaussianStart, GaussianTrace, gaussian_start,
                   prepare, register_estimator)


class _BatchUKF(UnscentedKalmanFilter):
    """filterpy's UKF whose sigma points go through ``fx`` and ``hx`` in one vectorised call each.

    filterpy calls ``fx`` and ``hx`` once per sigma point in Python loops, and
    sums the cross-covariance in a third; the model's transition and
    observation take all ``2n + 1`` points at once, and the cross-covariance
    is one matrix product. ``predict`` is filterpy's own; ``update`` is
    filterpy's, line for line, with the loop over ``hx`` replaced. The numbers
    are the same (``tests/test_estimators.py``).
    """

    def compute_process_sigmas(self, dt, fx=None, **fx_args):
        fx = self.fx if fx is None else fx
        self.sigmas_f = fx(self.points_fn.sigma_points(self.x, self.P), dt, **fx_args)

    def cross_variance(self, x, z, sigmas_f, sigmas_h):
        if self.residual_x is not np.subtract or self.residual_z is not np.subtract:
            return super().cross_variance(x, z, sigmas_f, sigmas_h)
        return (self.Wc[:, None] * (sigmas_f - x)).T @ (sigmas_h - z)

    def update(self, z, R=None, UT=None, hx=None, **hx_args):
        if z is None:
            return super().update(z, R, UT, hx, **hx_args)
        hx = self.hx if hx is None else hx
        R = self.R if R is None else (np.eye(self._dim_z) * R if np.isscalar(R) else R)
        UT = unscented_transform if UT is None else UT
        self.sigmas_h = np.atleast_2d(hx(self.sigmas_f, **hx_args))
        zp, self.S = UT(self.sigmas_h, self.Wm, self.Wc, R, self.z_mean, self.residual_z)
        self.SI = self.inv(self.S)
        Pxz = self.cross_variance(self.x, zp, self.sigmas_f, self.sigmas_h)
        self.K = Pxz @ self.SI
        self.y = self.residual_z(z, zp)
        self.x = self.state_add(self.x, self.K @ self.y)
        self.P = self.P - self.K @ (self.S @ self.K.T)
        self.z = np.array(z, copy=True)
        self.x_post = self.x.copy()
        self.P_post = self.P.copy()
        self._log_likelihood = None
        self._likelihood = None
        self._mahalanobis = None


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
