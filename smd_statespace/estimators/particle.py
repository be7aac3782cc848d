"""Bootstrap particle filter (sequential importance resampling): the article's estimator.

Each of ``N`` particles is a full augmented state (Eq. 7). Per sample:

1. **predict**: move every particle with the model's transition (Eq. 11-12)
   and add Gaussian process noise (Eq. 6; about 1 % of each slot's nominal
   value); parameters that leave their prior range are reflected back;
2. **weight**: multiply each particle's weight by the Gaussian likelihood of
   the observation (Eq. 13; noise 10 % of each channel's RMS), kept as
   log-weights so nothing underflows;
3. **resample** (systematic) when the effective sample size
   ``1 / sum(w^2)`` falls below ``ess_threshold * N``.

The log-likelihood increment of a sample is
``log sum_i w_i p(y_k | x_i)`` with the normalised weights of the previous
sample. The whole cloud moves in one vectorised call of the model.
"""

from __future__ import annotations

import numpy as np

from ..errors import OptionError
from ..model import SMDModel
from . import _pf_kernel
from .base import (CycleData, Estimator, EstimatorFailure, FilterResult, ParticleStart, Trace, dynamic_mask,
                   prepare, register_estimator)

LOG_2PI = np.log(2.0 * np.pi)

ENGINES = ("auto", "numba", "numpy")
"""Values of ``ParticleFilter(engine=...)``."""


def systematic_resample(weights: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Indices of a systematic resample of normalised ``weights``.

    One uniform draw places ``N`` evenly spaced pointers on the cumulative
    weights (as ``filterpy.monte_carlo.systematic_resample``, but drawing from
    the given ``Generator`` instead of the global ``np.random``).
    """
    n = len(weights)
    positions = (rng.random() + np.arange(n)) / n
    cumulative = np.cumsum(weights)
    cumulative[-1] = 1.0
    return np.searchsorted(cumulative, positions, side="right").clip(0, n - 1)


def effective_sample_size(weights: np.ndarray) -> float:
    """``1 / sum(w^2)`` of normalised weights."""
    return 1.0 / float(np.sum(weights**2))


def check_particle_options(n_particles, ess_threshold) -> tuple[int, float]:
    """Validated ``(n_particles, ess_threshold)`` of a particle filter."""
    if isinstance(n_particles, bool) or int(n_particles) != n_particles or n_particles < 2:
        raise OptionError(f"n_particles must be a whole number >= 2, got {n_particles!r}")
    if not 0.0 < float(ess_threshold) <= 1.0:
        raise OptionError(f"ess_threshold must be in (0, 1], got {ess_threshold!r}")
    return int(n_particles), float(ess_threshold)


def reweight(log_weights: np.ndarray, log_likelihood: np.ndarray, data, k: int):
    """Multiply normalised weights by the likelihoods (in logs); return the new ones and ``log p(y_k | y_<k)``.

    Non-finite likelihoods count as zero. Raises :class:`EstimatorFailure` when every weight vanishes.
    """
    from scipy.special import logsumexp  # imported here: scipy.special takes 0.2 s (not needed to start)

    log_weights = log_weights + np.where(np.isfinite(log_likelihood), log_likelihood, -np.inf)
    increment = logsumexp(log_weights)
    if not np.isfinite(increment):
        raise EstimatorFailure(
            f"cycle {data.index}: all particle weights vanished at sample {k} (t = {data.t[k]:.3f} s); "
            "the observation is far outside the cloud"
        )
    return log_weights - increment, float(increment)


def reflect(values: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """Fold values back into ``[low, high]`` per column (infinite bounds leave a column alone).

    Values inside their range are left exactly as they are; only those outside are folded.
    """
    finite = np.isfinite(low) & np.isfinite(high)
    if not finite.any():
        return values
    lo, hi = low[finite], high[finite]
    block = values[:, finite]
    outside = (block < lo) | (block > hi)
    if not outside.any():
        return values
    width = hi - lo
    shifted = np.mod(block - lo, 2.0 * width)
    folded = lo + np.where(shifted > width, 2.0 * width - shifted, shifted)
    values[:, finite] = np.where(outside, folded, block)
    return values


def noise_generator(rng: np.random.Generator) -> np.random.Generator:
    """The particle filter's own stream, seeded from ``rng``: an SFC64 generator.

    A pass draws ``n_state`` normal variates per particle and sample; SFC64 makes
    them about a third cheaper than the default PCG64 (docs/performance.md). The
    stream is a pure function of ``rng``'s state, so a seeded run stays reproducible.
    """
    return np.random.Generator(np.random.SFC64(rng.integers(0, 2**63, size=4)))


@register_estimator
class ParticleFilter(Estimator):
    """Sequential importance resampling particle filter (the article's method, Section 3.2).

    Parameters
    ----------
    n_particles : int
        Number of particles (the article: 5000).
    ess_threshold : float
        Resample when the effective sample size drops below this fraction of
        ``n_particles``; 1.0 resamples at every sample.
    process_noise_std, observation_noise_std : array_like, optional
        Override the model's default noise levels.
    engine : {"auto", "numba", "numpy"}
        ``"numba"``: one compiled pass per cycle (:mod:`._pf_kernel`; the base
        ``SMDModel`` without effects). ``"numpy"``: whole-cloud calls of the
        model's methods (any model). ``"auto"`` (default) takes the compiled pass
        whenever it applies. Both draw the same random numbers in the same order
        and agree to rounding; the compiled one is about fifteen times faster
        (docs/performance.md).

    Attributes (after :meth:`run`)
    ------------------------------
    particles_ : ndarray, shape (n_particles, n_state)
        The final cloud.
    log_weights_ : ndarray, shape (n_particles,)
        Its normalised log-weights.

    Notes
    -----
    Random numbers: the filter draws from an SFC64 generator seeded from the
    ``rng`` it is given (:func:`noise_generator`), so a seeded run is reproducible.
    """

    name = "pf"

    def __init__(self, n_particles: int = 5000, ess_threshold: float = 0.5,
                 process_noise_std=None, observation_noise_std=None, engine: str = "auto"):
        self.n_particles, self.ess_threshold = check_particle_options(n_particles, ess_threshold)
        self.process_noise_std = process_noise_std
        self.observation_noise_std = observation_noise_std
        if engine not in ENGINES:
            raise OptionError(f"engine must be one of {', '.join(ENGINES)}, got {engine!r}")
        self.engine = engine

    def engine_for(self, model: SMDModel) -> str:
        """The engine a pass on ``model`` uses: ``"numba"`` for the base model when available, else ``"numpy"``."""
        compiled = type(model) is SMDModel and not model.effects and _pf_kernel.available()
        if self.engine == "numba" and not compiled:
            raise OptionError("engine='numba' needs numba and the base SMDModel without effects; use 'auto' or 'numpy'")
        return "numba" if self.engine in ("auto", "numba") and compiled else "numpy"

    def _initial_cloud(self, model, setup, start, rng):
        n = self.n_particles
        if start is None:
            particles = setup.prior.sample(rng, n)
            log_weights = np.full(n, -np.log(n))
        elif isinstance(start, ParticleStart):
            if start.particles.shape[1] != model.n_state:
                raise OptionError(f"restart cloud has {start.particles.shape[1]} states, the model {model.n_state}")
            index = systematic_resample(np.exp(start.log_weights), rng) if len(start.particles) != n else None
            particles = start.particles[index] if index is not None else start.particles.copy()
            log_weights = np.full(n, -np.log(n)) if index is not None else start.log_weights.copy()
            # Motion restarts from the prior at the cycle start; parameters are carried over.
            dynamic = dynamic_mask(model)
            particles[:, dynamic] = setup.prior.sample(rng, n, columns=dynamic)
        elif hasattr(start, "mean") and hasattr(start, "cov"):
            particles = rng.multivariate_normal(np.asarray(start.mean, float), np.asarray(start.cov, float), size=n,
                                                method="eigh")
            log_weights = np.full(n, -np.log(n))
        else:
            raise OptionError(f"cannot start a particle filter from {type(start).__name__}")
        fixed = ~setup.free
        particles[:, fixed] = setup.fixed_values[fixed]
        return particles, log_weights

    def run(self, model: SMDModel, data: CycleData, start=None, rng=None, fixed=None) -> FilterResult:
        rng = noise_generator(np.random.default_rng() if rng is None else rng)
        setup = prepare(model, data, fixed, self.process_noise_std, self.observation_noise_std)
        particles, log_weights = self._initial_cloud(model, setup, start, rng)
        engine = self.engine_for(model)
        if rng.bit_generator.state.get("has_uint32", 0):  # a half-used 32-bit draw: only numpy can continue it
            engine = "numpy"
        passes = self._run_numba if engine == "numba" else self._run_numpy
        trace, particles, log_weights, ess_trace, resamples = passes(model, data, setup, particles, log_weights, rng)
        self.particles_, self.log_weights_ = particles, log_weights
        return trace.result(self.name, model, data, setup, ParticleStart(particles, log_weights),
                            {"ess": ess_trace, "resamples": resamples, "n_particles": self.n_particles,
                             "engine": engine})

    def _run_numba(self, model, data, setup, particles, log_weights, rng):
        """The compiled pass (base model only): the same steps and draws as :meth:`_run_numpy`."""
        rk4 = model.discretisation == "rk4"
        steps, move_basis, obs_basis = _pf_kernel.force_rows(model, data, model.substeps, rk4)
        noisy = np.flatnonzero(setup.q_std > 0)
        bounded = np.isfinite(setup.low) & np.isfinite(setup.high)
        quiet = np.flatnonzero(bounded & (setup.q_std <= 0))  # bounded slots without noise (fixed ones)
        low, high = np.where(bounded, setup.low, -np.inf), np.where(bounded, setup.high, np.inf)
        trace = Trace(model, data)
        ess_trace = np.empty(len(data))
        generator_state = rng.bit_generator.state
        state = generator_state["state"]["state"].copy()
        status, sample, log_likelihood, resamples, cloud, log_weights = _pf_kernel.kernel()(
            np.ascontiguousarray(particles.T, dtype=float), np.ascontiguousarray(log_weights, dtype=float),
            np.ascontiguousarray(data.y, dtype=float), steps, move_basis, obs_basis, model.index("a0"), rk4,
            model.observation == "full", noisy, setup.q_std[noisy], low[noisy], high[noisy], quiet, low[quiet],
            high[quiet], np.ascontiguousarray(setup.r_std, dtype=float), self.ess_threshold, state, trace.mean,
            trace.std, trace.innovations, trace.innovation_cov, ess_trace)
        particles = np.ascontiguousarray(cloud.T)
        generator_state["state"]["state"] = state
        rng.bit_generator.state = generator_state
        if status == 1:
            raise EstimatorFailure(
                f"cycle {data.index}: all particle weights vanished at sample {sample} (t = {data.t[sample]:.3f} s); "
                "the observation is far outside the cloud"
            )
        trace.log_likelihood = log_likelihood
        return trace, particles, log_weights, ess_trace, int(resamples)

    def _run_numpy(self, model, data, setup, particles, log_weights, rng):
        """The reference pass: whole-cloud numpy calls of the model's own methods (any model, any effect)."""
        n, m = self.n_particles, len(data)
        noisy = np.flatnonzero(setup.q_std > 0)
        q = setup.q_std[noisy]
        r = setup.r_std
        log_norm = -0.5 * model.n_obs * LOG_2PI - np.sum(np.log(r))
        trace = Trace(model, data)
        ess_trace = np.empty(m)
        resamples = 0
        with np.errstate(over="ignore", invalid="ignore"):
            for k in range(m):
                if k > 0:
                    particles = model.transition(particles, data.t[k - 1], data.t[k] - data.t[k - 1], data.inputs)
                    particles[:, noisy] += rng.standard_normal((n, noisy.size)) * q
                    particles = reflect(particles, setup.low, setup.high)
                predicted = model.observe(particles, data.t[k], data.inputs)
                weights = np.exp(log_weights)
                predicted_mean = weights @ predicted
                spread = predicted - predicted_mean
                trace.innovations[k] = data.y[k] - predicted_mean
                trace.innovation_cov[k] = (weights[:, None] * spread).T @ spread + np.diag(r**2)
                residual = (data.y[k] - predicted) / r
                log_weights, increment = reweight(log_weights, log_norm - 0.5 * np.sum(residual**2, axis=1), data, k)
                trace.log_likelihood += increment
                weights = np.exp(log_weights)
                trace.mean[k] = weights @ particles
                trace.std[k] = np.sqrt(np.maximum(weights @ (particles - trace.mean[k]) ** 2, 0.0))
                ess_trace[k] = effective_sample_size(weights)
                if ess_trace[k] < self.ess_threshold * n and k < m - 1:
                    particles = particles[systematic_resample(weights, rng)]
                    log_weights = np.full(n, -np.log(n))
                    resamples += 1
        return trace, particles, log_weights, ess_trace, resamples
