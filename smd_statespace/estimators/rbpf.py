"""Rao-Blackwellised particle filter: particles over ``(f_h, xi_h)``, Kalman filters for the rest.

The article's particle filter (:mod:`.particle`) samples all 13 slots of the
augmented state (Eq. 7). Nine of them are Fourier coefficients whose uniform
prior is some twenty times wider than what one cycle leaves of it, so a
cloud of a few thousand particles cannot cover their product space and
collapses onto wrong values (``docs/benchmarks.md`` measures it). Given the
non-linear slots (``f_h``, ``xi_h``), the model is linear and Gaussian in the
others (Eq. 10-16), so each particle can carry an exact Kalman filter for
them instead (the marginalised or Rao-Blackwellised particle filter,
Doucet et al. 2000; Schön, Gustafsson & Nordlund 2005). Sampling happens in
two dimensions only; the Kalman part is the same batched filter the grid
reference uses (:mod:`.linear`).

Known problem (``docs/benchmarks.md``): over the article's repeated passes
its ``f_h`` drifts towards the lower prior edge (one pass is the estimator
closest to the grid reference, 0.05 Hz; eight passes, 0.49 Hz away). The
random walk of ``f_h`` inside the filter drives it; use ``max_passes=1``
with this estimator until that is understood.

Per sample: jitter the non-linear slots (random walk, Eq. 6) and move every
particle's Kalman filter; weight each particle by its filter's predictive
density of the observation; update the filters; resample particles (with
their filters) when the effective sample size drops.
"""

from __future__ import annotations

import numpy as np

from ..errors import OptionError
from ..model import SMDModel
from .base import (CycleData, Estimator, FilterResult, ParticleStart, Trace, dynamic_mask,
                   prepare, register_estimator)
from .linear import ConditionalKalman, mixture_moments, normalised, predictive_mixture, verify_linear
from .particle import check_particle_options, effective_sample_size, reflect, reweight, systematic_resample


@register_estimator
class RaoBlackwellisedFilter(Estimator):
    """Particles over the non-linear slots, one exact Kalman filter per particle for the linear ones.

    Parameters
    ----------
    n_particles : int
        Number of particles (each carries a Kalman filter, so a few hundred suffice).
    ess_threshold : float
        Resample when the effective sample size drops below this fraction.
    process_noise_std, observation_noise_std : array_like, optional
        Override the model's default noise levels.

    Attributes (after :meth:`run`)
    ------------------------------
    particles_ : ndarray, shape (n_particles, n_state)
        Final particles (non-linear slots) with their filters' means (linear slots).
    covariances_ : ndarray, shape (n_particles, n_linear, n_linear)
        Their Kalman covariances.
    log_weights_ : ndarray, shape (n_particles,)
    """

    name = "rbpf"

    def __init__(self, n_particles: int = 300, ess_threshold: float = 0.5,
                 process_noise_std=None, observation_noise_std=None):
        self.n_particles, self.ess_threshold = check_particle_options(n_particles, ess_threshold)
        self.process_noise_std = process_noise_std
        self.observation_noise_std = observation_noise_std

    def _start(self, model, setup, start, rng, nonlinear, linear):
        n = self.n_particles
        prior_block = setup.prior_cov[np.ix_(linear, linear)]
        if start is None:
            x = np.broadcast_to(setup.prior_mean, (n, model.n_state)).copy()
            x[:, nonlinear] = setup.prior.sample(rng, n, columns=nonlinear)
            P = np.broadcast_to(prior_block, (n, linear.size, linear.size)).copy()
            return x, P, np.full(n, -np.log(n))
        if not (isinstance(start, ParticleStart) and start.covariances is not None):
            raise OptionError(f"cannot start a Rao-Blackwellised filter from {type(start).__name__}")
        index = systematic_resample(normalised(start.log_weights), rng)
        x, P = start.particles[index].copy(), start.covariances[index].copy()
        # A new pass: parameters carried over, motion restarts from the prior at the cycle start.
        dynamic = np.flatnonzero(dynamic_mask(model)[linear])
        x[:, linear[dynamic]] = setup.prior_mean[linear[dynamic]]
        P[:, dynamic, :] = 0.0
        P[:, :, dynamic] = 0.0
        P[:, dynamic[:, None], dynamic] = prior_block[np.ix_(dynamic, dynamic)]
        return x, P, np.full(n, -np.log(n))

    def run(self, model: SMDModel, data: CycleData, start=None, rng=None, fixed=None) -> FilterResult:
        rng = np.random.default_rng() if rng is None else rng
        verify_linear(model, data.inputs)
        setup = prepare(model, data, fixed, self.process_noise_std, self.observation_noise_std)
        slots_linear = np.array([slot.linear for slot in model.slots])
        nonlinear = np.flatnonzero(setup.free & ~slots_linear)
        linear = np.flatnonzero(setup.free & slots_linear)
        x, P, log_weights = self._start(model, setup, start, rng, nonlinear, linear)
        fixed_slots = ~setup.free
        x[:, fixed_slots] = setup.fixed_values[fixed_slots]
        kalman = ConditionalKalman(model, setup, linear)
        n, m = self.n_particles, len(data)
        q = setup.q_std[nonlinear]
        trace = Trace(model, data)
        ess_trace = np.empty(m)
        resamples = 0
        with np.errstate(over="ignore", invalid="ignore"):
            for k in range(m):
                if k > 0:
                    x[:, nonlinear] += rng.standard_normal((n, nonlinear.size)) * q
                    x = reflect(x, setup.low, setup.high)
                    x, P = kalman.predict(x, P, data.t[k - 1], data.t[k] - data.t[k - 1], data.inputs)
                predicted, S, H = kalman.predict_observation(x, P, data.t[k], data.inputs)
                predicted_mean, trace.innovation_cov[k] = predictive_mixture(np.exp(log_weights), predicted, S)
                trace.innovations[k] = data.y[k] - predicted_mean
                x, P, log_density = kalman.update(x, P, data.y[k], predicted, S, H, f"cycle {data.index}, sample {k}")
                log_weights, increment = reweight(log_weights, log_density, data, k)
                trace.log_likelihood += increment
                weights = np.exp(log_weights)
                trace.mean[k], trace.std[k] = mixture_moments(weights, x, P, linear)
                ess_trace[k] = effective_sample_size(weights)
                if ess_trace[k] < self.ess_threshold * n and k < m - 1:
                    index = systematic_resample(weights, rng)
                    x, P = x[index], P[index]
                    log_weights = np.full(n, -np.log(n))
                    resamples += 1
        self.particles_, self.covariances_, self.log_weights_ = x, P, log_weights
        return trace.result(self.name, model, data, setup, ParticleStart(x, log_weights, P),
                            {"ess": ess_trace, "resamples": resamples, "n_particles": n})
