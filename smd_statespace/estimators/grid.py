"""Exact reference: Kalman filters on a grid over ``(f_h, xi_h)``.

Given ``f_h`` and ``xi_h``, the rest of the augmented state (``u``, ``u_dot``
and the Fourier coefficients, Eq. 7) moves and is observed linearly
(Eq. 10-16), with Gaussian noise: a Kalman filter then gives the exact
likelihood ``p(y | f_h, xi_h)`` of a cycle and the exact Gaussian posterior
of the coefficients. Evaluated on a grid (all grid points in one vectorised
filter), this gives the posterior of ``(f_h, xi_h)`` within the cycle under
the model's own assumptions, up to two approximations that are stated:

* the uniform priors of the linear slots are replaced by Gaussians of the same
  mean and variance, and ``f_h``, ``xi_h`` are held constant within the cycle
  (no random walk);
* with effects that are not linear in the other slots (``cubic_stiffness``),
  the filter linearises around its mean (an EKF per grid point), so the
  reference is no longer exact.

A flat posterior along ``f_h`` or ``xi_h`` is the direct picture of a cycle
that does not determine that parameter.
"""

from __future__ import annotations

import numpy as np

from ..errors import OptionError
from ..model import SMDModel
from .base import (CycleData, Estimator, EstimatorFailure, FilterResult, GaussianStart, Trace, gaussian_start,
                   prepare, register_estimator)
from .linear import (ConditionalKalman, mixture_covariance, mixture_moments, normalised, predictive_mixture,
                     verify_linear)


def _cell_centres(low, high, count):
    edges = np.linspace(low, high, count + 1)
    return 0.5 * (edges[:-1] + edges[1:])


@register_estimator
class GridReference(Estimator):
    """Exact posterior of ``(f_h, xi_h)`` on a grid, coefficients by Kalman filtering.

    Parameters
    ----------
    f_h_points, xi_h_points : int
        Grid cells along ``f_h`` and ``xi_h`` (cell centres over the prior range).
    f_h_range, xi_h_range : (float, float), optional
        Grid ranges; default the model's prior ranges.
    process_noise_std, observation_noise_std : array_like, optional
        Override the model's default noise levels.

    Attributes (after :meth:`run`)
    ------------------------------
    f_h_grid_, xi_h_grid_ : ndarray
        Grid axes (Hz, -).
    posterior_ : ndarray, shape (f_h_points, xi_h_points)
        Posterior probability of every grid cell.
    log_likelihood_grid_ : ndarray, same shape
        ``log p(y | f_h, xi_h)`` of every cell.
    """

    name = "grid"
    supports_passes = False

    def __init__(self, f_h_points: int = 61, xi_h_points: int = 41, f_h_range=None, xi_h_range=None,
                 process_noise_std=None, observation_noise_std=None):
        for label, value in (("f_h_points", f_h_points), ("xi_h_points", xi_h_points)):
            if isinstance(value, bool) or int(value) != value or value < 1:
                raise OptionError(f"{label} must be a whole number >= 1, got {value!r}")
        self.f_h_points = int(f_h_points)
        self.xi_h_points = int(xi_h_points)
        self.f_h_range = f_h_range
        self.xi_h_range = xi_h_range
        self.process_noise_std = process_noise_std
        self.observation_noise_std = observation_noise_std

    def run(self, model: SMDModel, data: CycleData, start=None, rng=None, fixed=None) -> FilterResult:
        fixed = dict(fixed or {})
        verify_linear(model, data.inputs)
        setup = prepare(model, data, fixed, self.process_noise_std, self.observation_noise_std)
        i_f, i_xi = model.index("f_h"), model.index("xi_h")
        f_axis = np.array([fixed["f_h"]]) if "f_h" in fixed else _cell_centres(
            *(self.f_h_range or model.options["f_h_range"]), self.f_h_points)
        xi_axis = np.array([fixed["xi_h"]]) if "xi_h" in fixed else _cell_centres(
            *(self.xi_h_range or model.options["xi_h_range"]), self.xi_h_points)
        f_grid, xi_grid = np.meshgrid(f_axis, xi_axis, indexing="ij")
        n_grid = f_grid.size
        if not (start is None or isinstance(start, GaussianStart)):
            raise OptionError(f"the grid reference starts from the prior or a GaussianStart, not {type(start).__name__}")
        mean0, cov0 = gaussian_start(model, setup, start)
        linear = np.setdiff1d(np.flatnonzero(setup.free), [i_f, i_xi])
        x = np.broadcast_to(mean0, (n_grid, model.n_state)).copy()
        x[:, i_f], x[:, i_xi] = f_grid.ravel(), xi_grid.ravel()
        P = np.broadcast_to(cov0[np.ix_(linear, linear)], (n_grid, linear.size, linear.size)).copy()
        kalman = ConditionalKalman(model, setup, linear)
        m = len(data)
        log_lik = np.zeros(n_grid)
        trace = Trace(model, data)
        with np.errstate(over="ignore", invalid="ignore"):
            for k in range(m):
                if k > 0:
                    x, P = kalman.predict(x, P, data.t[k - 1], data.t[k] - data.t[k - 1], data.inputs)
                predicted, S, H = kalman.predict_observation(x, P, data.t[k], data.inputs)
                # Predictive mixture over the grid, weighted by the posterior so far.
                predicted_mean, trace.innovation_cov[k] = predictive_mixture(normalised(log_lik), predicted, S)
                trace.innovations[k] = data.y[k] - predicted_mean
                x, P, log_density = kalman.update(x, P, data.y[k], predicted, S, H, f"cycle {data.index}, sample {k}")
                log_lik += log_density
                trace.mean[k], trace.std[k] = mixture_moments(normalised(log_lik), x, P, linear)
        if not np.all(np.isfinite(log_lik)):
            raise EstimatorFailure(f"cycle {data.index}: the grid Kalman filters diverged (non-finite likelihood)")
        from scipy.special import logsumexp  # imported here: scipy.special takes 0.2 s (not needed to start)

        trace.log_likelihood = float(logsumexp(log_lik) - np.log(n_grid))
        posterior = normalised(log_lik)
        self.f_h_grid_, self.xi_h_grid_ = f_axis, xi_axis
        self.posterior_ = posterior.reshape(f_grid.shape)
        self.log_likelihood_grid_ = log_lik.reshape(f_grid.shape)
        restart = GaussianStart(trace.mean[-1], mixture_covariance(posterior, x, P, linear), carry_over=True)
        return trace.result(self.name, model, data, setup, restart,
                            {"f_h_grid": f_axis, "xi_h_grid": xi_axis, "posterior": self.posterior_,
                             "grid_points": n_grid})
