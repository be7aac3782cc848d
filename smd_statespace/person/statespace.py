"""The record-level model as a statsmodels state-space model.

:class:`RecordStateSpace` is a :class:`statsmodels.tsa.statespace.mlemodel.MLEModel`
whose matrices are those of :class:`~smd_statespace.person.model.RecordModel`
(the same builder, so the two cannot disagree). The maximum-likelihood search
runs on the compiled pass of :mod:`smd_statespace.person.kalman` (measured:
about 2-3 ms per likelihood on a 30 s record at 100 Hz, against tens of ms for
statsmodels' filter with 3000 time-varying transition matrices); statsmodels
then gives, at the estimate, its smoother (the force coefficients of every
cycle) and its residual tests (``test_serial_correlation``, ``test_normality``,
``test_heteroskedasticity``).

The linear unknowns that the compiled pass concentrates out (template,
initial ``u, u_dot``, regressor coefficients) enter here at their estimates:
the template as the state intercept of every cycle's draw, the regressors as
intercepts, the initial state as a known mean. The log-likelihood of
:meth:`RecordStateSpace.loglike` is then exactly the profile likelihood of
:meth:`RecordModel.loglike` (checked by the tests).
"""

from __future__ import annotations

import numpy as np
from statsmodels.tsa.statespace.mlemodel import MLEModel

from .model import RecordModel
from .variation import VARIATIONS, StateSpaceLayout

__all__ = ["RecordStateSpace", "nominal_path"]


class RecordStateSpace(MLEModel):
    """statsmodels' view of a :class:`RecordModel` with its linear unknowns fixed.

    Parameters
    ----------
    model : RecordModel
        The record-level model.
    delta : ndarray, shape (q,)
        ``[initial dynamic states (n_x), template (p), regressor coefficients (r)]``
        at which the linear unknowns are fixed (from :meth:`RecordModel.filter`).

    Notes
    -----
    State ``[x, alpha]`` with ``x = [u, u_dot, ...]`` the ``n_x`` dynamic states (``[x, alpha, m]`` for variation
    "both", ``[x, alpha, alpha_dot]`` for "smooth"); observation ``y = [h_x, H_k] state + X_obs beta + d + v`` with the
    scale ``sigma^2`` concentrated out (``concentrate_scale=True``), so every
    variance is relative to it, as in the compiled pass.
    """

    def __init__(self, model: RecordModel, delta):
        self.record_model = model
        self.delta = np.asarray(delta, dtype=float)
        p, nx = model.n_force_states, model.n_dynamic
        k_states = VARIATIONS[model.variation].state_size(nx, p, model.n_coefficients)
        super().__init__(np.where(model.observed, model.y, np.nan), k_states=k_states, k_posdef=k_states)  # missing
        self.ssm.filter_concentrated = True
        self.ssm["selection"] = np.eye(k_states)
        self.ssm["obs_cov", 0, 0] = 1.0

    @property
    def param_names(self):
        """Names of the parameters, as the record-level model has them (statsmodels' ``param_names``)."""
        return list(self.record_model.param_names)

    @property
    def start_params(self):
        """Starting values of the parameters: the record-level model's (statsmodels' ``start_params``)."""
        return self.record_model.start_params()

    def update(self, params, **kwargs):
        """Fill the state-space matrices for ``params`` (in the order of ``param_names``).

        Parameters
        ----------
        params : array_like
            ``f_h``, ``xi_h`` and the log variance ratios.
        **kwargs
            Passed to :meth:`statsmodels.tsa.statespace.mlemodel.MLEModel.update`.

        Returns
        -------
        ndarray
            The parameters.
        """
        params = super().update(params, **kwargs)
        model = self.record_model
        sys = model.system(params)
        n, nx, m = model.y.size, model.n_dynamic, self.k_states
        n_template, r = model.n_coefficients, sys.X_obs.shape[1]
        x0, beta = self.delta[:nx], self.delta[nx + n_template:nx + n_template + r]
        tau = np.zeros(model.n_force_states)  # the phase and rate errors, if any, have mean zero
        tau[:n_template] = self.delta[nx:nx + n_template]
        # statsmodels' time t maps the state at sample t to sample t + 1: a cycle starting
        # at sample k draws its coefficients in the transition of time k - 1
        layout = StateSpaceLayout(nx, model.n_force_states, n_template, np.flatnonzero(sys.reset) - 1)
        transition, intercept, state_cov = self._dynamics_matrices(sys, beta, layout, m, n)
        mean_force, cov_force = VARIATIONS[model.variation].fill_statespace(sys, tau, layout, transition, intercept,
                                                                            state_cov)
        design = np.zeros((1, m, n))
        design[0, :nx, :] = np.broadcast_to(sys.hx, (n, nx)).T
        design[0, layout.alpha, :] = sys.H.T
        self.ssm["design"] = design
        self.ssm["obs_intercept"] = (sys.y_known + ((sys.X_obs @ beta) if r else 0.0))[None, :]
        self.ssm["transition"] = transition
        self.ssm["state_intercept"] = intercept
        self.ssm["state_cov"] = state_cov
        mean, cov = np.zeros(m), np.zeros((m, m))
        mean[:nx], mean[nx:] = x0, mean_force
        cov[nx:, nx:] = cov_force
        self.ssm.initialize_known(mean, cov)
        return params

    @staticmethod
    def _dynamics_matrices(sys, beta, layout, m, n) -> tuple:
        """Transition, state intercept and state covariance of the dynamics and the per-sample drift (Eq. 2, 17)."""
        nx, alpha = layout.nx, layout.alpha
        transition = np.repeat(np.eye(m)[:, :, None], n, axis=2)
        transition[:nx, :nx, :] = np.broadcast_to(sys.Phi, (n, nx, nx)).transpose(1, 2, 0)
        transition[:nx, alpha, :] = sys.Gam.transpose(1, 2, 0)
        intercept = np.zeros((m, n))
        intercept[:nx, :] = sys.offset.T + ((sys.X_tr @ beta).T if beta.size else 0.0)
        state_cov = np.zeros((m, m, n))
        state_cov[:nx, :nx, :] = sys.Qx[:, :, None]
        state_cov[alpha, alpha, :] += np.diag(sys.drift)[:, :, None]
        return transition, intercept, state_cov

    def smoothed_state(self, params) -> np.ndarray:
        """The smoothed state means at ``params``, shape ``(k_states, N)``: the smoother's state pass alone.

        The same means as ``self.smooth(params).smoothed_state``, from the same matrices, by the compiled
        filter and state smoothing recursion of :mod:`~smd_statespace.person.smoother` (no smoothed
        covariances, disturbances or results' copies of the matrices). The re-placement of the cycle starts
        (:func:`~smd_statespace.person.search.corrected_timing`) calls it six times per record. Every variance
        being relative to ``sigma^2``, the means do not depend on the concentrated scale.
        """
        from .smoother import smoothed_state_means

        self.update(params)
        ssm, n = self.ssm, self.nobs
        init = ssm.initialization

        def per_sample(array):  # statsmodels keeps a time-invariant matrix with a last axis of 1
            return np.broadcast_to(array, array.shape[:-1] + (n,))

        observed = np.broadcast_to(np.asarray(self.record_model.observed, dtype=bool), (n,))
        return smoothed_state_means(self.record_model.y, observed,
                                    per_sample(ssm["design"])[0], per_sample(ssm["obs_intercept"])[0],
                                    float(np.asarray(ssm["obs_cov"]).ravel()[0]), per_sample(ssm["transition"]),
                                    per_sample(ssm["state_intercept"]), per_sample(ssm["state_cov"]),
                                    init.constant, init.stationary_cov)


def nominal_path(model: RecordModel, params) -> np.ndarray:
    """The one-step predicted dynamic states ``x_{t|t-1}``, shape ``(N, n_x)``, of ``model`` at ``params``.

    The path a nonlinear effect is linearised about. It is causal: the value
    at sample ``t`` depends on the measurements before ``t`` only, so the
    linearised model's one-step predictions are predictions, and its
    likelihood is a prediction-error likelihood (at the fixed point of the
    re-linearisations, that of an extended Kalman filter). The smoothed path,
    which the fit first used, depends on the measurement it predicts: on clean
    records the re-linearised fit then ran away from the physics (a cubic
    spring with likelihood ratio 184, ``f_h`` 2.30 -> 1.40 Hz, truth 2.36),
    where about the predicted path the same record gives 1.8.
    """
    view = RecordStateSpace(model, model.filter(params)["delta"])
    view.update(params)
    kalman = view.ssm
    # the predicted means alone: no covariances, gains or filtered states kept (a third to a half of the time of
    # MLEModel.filter on a 30 s record), the same numbers
    for output in ("filtered", "filtered_cov", "predicted_cov", "forecast_cov", "gain", "smoothing", "std_forecast"):
        setattr(kalman, f"memory_no_{output}", True)
    return kalman.filter().predicted_state[:model.n_dynamic, :-1].T
