"""The estimators' subclasses of filterpy's filters, in a module of their own.

filterpy imports ``scipy.stats`` (about 0.7 s together); :mod:`.ekf` and :mod:`.ukf`
import this module when a filter runs, so that the command line and the record-level
model (which use neither) do not load filterpy.
"""

from __future__ import annotations

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter, UnscentedKalmanFilter

from ..model import SMDModel
from .base import CycleData, FreeState


class _ModelEKF(ExtendedKalmanFilter):
    """filterpy EKF whose prediction runs the model's nonlinear transition."""

    def __init__(self, model: SMDModel, data: CycleData, free_state: FreeState):
        super().__init__(dim_x=free_state.free.size, dim_z=model.n_obs)
        self.model, self.data, self.free_state = model, data, free_state
        self.t, self.step = data.t[0], data.dt

    def predict_x(self, u=0):
        full = self.free_state.embed(self.x[:, 0])
        free = self.free_state.free
        moved, jacobian = self.model.transition_and_jacobian(full, self.t, self.step, self.data.inputs)
        self.F, self.x = jacobian[np.ix_(free, free)], moved[free][:, None]

    def h_jacobian(self, x, t):
        full = self.free_state.embed(x[:, 0])
        return self.model.observation_jacobian(full, t, self.data.inputs)[:, self.free_state.free]

    def h(self, x, t):
        return self.model.observe(self.free_state.embed(x[:, 0]), t, self.data.inputs)[:, None]


class _BatchUKF(UnscentedKalmanFilter):
    """filterpy's UKF whose sigma points go through ``fx`` and ``hx`` in one vectorised call each.

    filterpy calls ``fx`` and ``hx`` once per sigma point in Python loops, and
    sums the cross-covariance in a third; the model's transition and
    observation take all ``2n + 1`` points at once, and the cross-covariance
    is one matrix product. ``predict`` and ``update`` are filterpy's own
    (``update`` is handed the rows of one vectorised ``hx`` call); the numbers
    are those of the plain filterpy UKF (``tests/test_estimators.py``).
    """

    def compute_process_sigmas(self, dt, fx=None, **fx_args):
        fx = self.fx if fx is None else fx
        self.sigmas_f = fx(self.points_fn.sigma_points(self.x, self.P), dt, **fx_args)

    def cross_variance(self, x, z, sigmas_f, sigmas_h):
        if self.residual_x is not np.subtract or self.residual_z is not np.subtract:
            return super().cross_variance(x, z, sigmas_f, sigmas_h)
        return (self.Wc[:, None] * (sigmas_f - x)).T @ (sigmas_h - z)

    def update(self, z, R=None, UT=None, hx=None, **hx_args):
        """filterpy's own update, with the measurement sigma points computed in one vectorised call.

        filterpy's ``update`` asks ``hx`` for one sigma point at a time; it is given
        a function that hands back the rows of the batch already computed, in order.
        """
        if z is None:
            return super().update(z, R, UT, hx, **hx_args)
        batch = np.atleast_2d((self.hx if hx is None else hx)(self.sigmas_f, **hx_args))
        if batch.shape[0] != self.sigmas_f.shape[0]:
            raise ValueError(f"hx gave {batch.shape[0]} rows for {self.sigmas_f.shape[0]} sigma points")
        rows = iter(batch)
        return super().update(z, R, UT, lambda _sigma, **_args: next(rows))
