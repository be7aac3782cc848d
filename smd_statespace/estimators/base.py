"""What every estimator shares: the cycle data it consumes, the result it returns, the registry.

An estimator knows filtering and nothing about bouncing: it only calls the
model's ``transition``, ``observe``, their Jacobians, ``prior`` and the noise
defaults (see :mod:`smd_statespace.model`). Swapping estimators is one word::

    result = get_estimator("ukf").run(model, data)

Every estimator returns a :class:`FilterResult` with the same fields, whose
``restart`` lets a repeated pass begin where the last one ended.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from ..errors import CycleError, OptionError
from ..model import CycleInputs, SMDModel


class EstimatorFailure(RuntimeError):
    """A numerical failure inside one cycle (all weights zero, covariance beyond repair, overflow).

    The cycle runner catches it, marks that cycle failed with the message and goes on.
    """


@dataclass(frozen=True)
class CycleData:
    """One cycle's data, as every estimator consumes it.

    Attributes
    ----------
    t : ndarray, shape (m,)
        Sample times (s).
    y : ndarray, shape (m, n_obs)
        Observations in the model's channel order (``model.channels``).
    inputs : CycleInputs
        Bouncing frequency, cycle start and exogenous signals.
    index : int
        Cycle number within its record.
    """

    t: np.ndarray
    y: np.ndarray
    inputs: CycleInputs
    index: int = 0

    @property
    def dt(self) -> float:
        """Sampling interval (s)."""
        return float(np.median(np.diff(self.t)))

    @property
    def f_b(self) -> float:
        """Bouncing frequency (Hz)."""
        return self.inputs.f_b

    def __len__(self):
        return len(self.t)


def cycle_data(model: SMDModel, preprocessed, cycle) -> CycleData:
    """Cut one cycle out of a :class:`~smd_statespace.signals.Preprocessed` record for ``model``.

    Picks the observation channels the model observes and the exogenous
    signals its effects require (raising :class:`~smd_statespace.errors.OptionError`
    naming the missing column otherwise).
    """
    t, y = preprocessed.observations(cycle, channels=model.channels)
    signals = preprocessed.exogenous(cycle)
    missing = [name for name in model.requires if name not in signals]
    if missing:
        needing = [e for e in model.effects if missing[0] in e.requires]
        columns = [c for e in needing for c in e.requires_columns]
        column = f"a {columns[0]!r} column, which the record lacks" if columns else "a column the record lacks"
        raise OptionError(
            f"{getattr(preprocessed, 'source', 'record')}: effect {needing[0].name!r} needs signal {missing[0]!r} "
            f"from {column}"
        )
    inputs = CycleInputs(f_b=cycle.f_b, t0=float(t[0]), time=t, signals={k: signals[k] for k in model.requires})
    return CycleData(t=t, y=y, inputs=inputs, index=cycle.index)


@dataclass(frozen=True)
class GaussianStart:
    """A Gaussian state distribution to start a pass from (mean, covariance).

    With ``carry_over=True`` (how a pass hands over to the next) only the
    parameters are carried; the motion slots restart from the prior
    (see :func:`reset_dynamic`).
    """

    mean: np.ndarray
    cov: np.ndarray
    carry_over: bool = False


@dataclass(frozen=True)
class ParticleStart:
    """A weighted particle cloud handed from one pass to the next.

    ``covariances`` holds the per-particle Kalman covariances of a
    Rao-Blackwellised filter (``None`` for a plain particle filter).
    """

    particles: np.ndarray
    log_weights: np.ndarray
    covariances: np.ndarray | None = None


def dynamic_mask(model: SMDModel) -> np.ndarray:
    """Boolean mask of the model's dynamic (motion) slots."""
    return np.array([slot.kind == "dynamic" for slot in model.slots])


@dataclass
class Setup:
    """Everything a filter needs for one pass, prepared from the model and the data.

    Attributes
    ----------
    prior_mean, prior_cov : ndarray
        Gaussian summary of the start distribution (fixed slots have zero variance).
    q_std : ndarray, shape (n_state,)
        Per-step process-noise standard deviation (zero for fixed slots).
    r_std : ndarray, shape (n_obs,)
        Observation-noise standard deviation.
    prior_std : ndarray, shape (n_state,)
        The model prior's standard deviation: the yardstick of identifiability.
    free : ndarray of bool, shape (n_state,)
        Slots that are estimated (not fixed).
    low, high : ndarray, shape (n_state,)
        Bounds of the parameter slots (infinite for dynamic slots); particle
        filters reflect at them.
    fixed_values : ndarray
        Values of the fixed slots (NaN for free ones).
    """

    prior: object
    prior_mean: np.ndarray
    prior_cov: np.ndarray
    q_std: np.ndarray
    r_std: np.ndarray
    prior_std: np.ndarray
    free: np.ndarray
    low: np.ndarray
    high: np.ndarray
    fixed_values: np.ndarray


def prepare(model: SMDModel, data: CycleData, fixed: Mapping[str, float] | None = None,
            process_noise_std=None, observation_noise_std=None) -> Setup:
    """Prior, noise levels and bounds for one pass over ``data`` (shared by all estimators).

    Parameters
    ----------
    fixed : mapping, optional
        Slots held at known values, e.g. ``{"f_h": 2.5, "xi_h": 0.3}`` (the
        linear sub-case): zero prior variance, zero process noise.
    process_noise_std, observation_noise_std : array_like, optional
        Overrides of the model's defaults (1 % of nominal per step, 10 % of RMS).
    """
    if len(data) < 3:
        raise CycleError(f"cycle {data.index}: {len(data)} samples; an estimator needs at least 3")
    if data.y.ndim != 2 or data.y.shape[1] != model.n_obs:
        raise OptionError(
            f"cycle {data.index}: observations have shape {data.y.shape}, the model observes {model.channels}"
        )
    bad = ~np.all(np.isfinite(data.y), axis=1)
    if bad.any():
        raise CycleError(f"cycle {data.index}: observation row {int(np.argmax(bad))} is not finite")
    scale = model.data_scale(data.y, data.inputs)
    prior = model.prior(data.y[0], scale)
    q_std = model.process_noise_std(scale) if process_noise_std is None else np.broadcast_to(
        np.asarray(process_noise_std, dtype=float), (model.n_state,)).copy()
    r_std = model.observation_noise_std(scale) if observation_noise_std is None else np.broadcast_to(
        np.asarray(observation_noise_std, dtype=float), (model.n_obs,)).copy()
    mean, cov = prior.mean.copy(), prior.cov.copy()
    free = np.ones(model.n_state, dtype=bool)
    fixed_values = np.full(model.n_state, np.nan)
    for name, value in (fixed or {}).items():
        i = model.index(name)
        free[i] = False
        fixed_values[i] = float(value)
        mean[i] = float(value)
        cov[i, :] = cov[:, i] = 0.0
        q_std[i] = 0.0
    low = np.array([slot.low if slot.kind == "parameter" else -np.inf for slot in model.slots], dtype=float)
    high = np.array([slot.high if slot.kind == "parameter" else np.inf for slot in model.slots], dtype=float)
    return Setup(prior, mean, cov, q_std, r_std, prior.std, free, low, high, fixed_values)


@dataclass
class FilterResult:
    """One pass of one estimator over one cycle; the same type for every estimator.

    Attributes
    ----------
    estimator : str
        Registry name of the estimator.
    state_names : tuple of str
        Names of the state slots (columns of ``mean`` and ``std``).
    t : ndarray, shape (m,)
        Sample times (s).
    mean, std : ndarray, shape (m, n_state)
        Filtered state mean and standard deviation after each update.
    innovations : ndarray, shape (m, n_obs)
        Measurement minus one-step-ahead predicted measurement.
    innovation_cov : ndarray, shape (m, n_obs, n_obs)
        Predicted covariance of the innovations.
    log_likelihood : float
        ``sum_k log p(y_k | y_0..k-1)``.
    restart : object
        What the next repeated pass starts from (particles, a Gaussian, a grid posterior).
    prior_std : ndarray, shape (n_state,)
        Standard deviation of the model prior, to judge identifiability.
    diagnostics : dict
        Estimator-specific counters (effective sample size, resampling count,
        covariance repairs, ...).
    """

    estimator: str
    state_names: tuple
    t: np.ndarray
    mean: np.ndarray
    std: np.ndarray
    innovations: np.ndarray
    innovation_cov: np.ndarray
    log_likelihood: float
    restart: object
    prior_std: np.ndarray
    diagnostics: dict = field(default_factory=dict)

    def index(self, name: str) -> int:
        """Column of slot ``name``."""
        return self.state_names.index(name)

    @property
    def final_mean(self) -> np.ndarray:
        """State mean after the last sample."""
        return self.mean[-1]

    @property
    def final_std(self) -> np.ndarray:
        """State standard deviation after the last sample."""
        return self.std[-1]

    @property
    def standardised_innovations(self) -> np.ndarray:
        """Innovations divided by their predicted standard deviation, shape (m, n_obs)."""
        sd = np.sqrt(np.maximum(np.diagonal(self.innovation_cov, axis1=1, axis2=2), 1e-300))
        return self.innovations / sd

    def width_ratio(self) -> np.ndarray:
        """Posterior sd over prior sd of every slot: near 1 means the cycle did not determine it."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.prior_std > 0, self.final_std / self.prior_std, np.nan)


class Estimator:
    """Base class of the estimators; subclasses implement :meth:`run`.

    ``__init__`` only stores options (scikit-learn style); :meth:`run` does the work.
    """

    name = "estimator"
    supports_passes = True
    """Whether repeated passes (the article's procedure) make sense for this estimator."""

    def run(self, model: SMDModel, data: CycleData, start=None, rng: np.random.Generator | None = None,
            fixed: Mapping[str, float] | None = None) -> FilterResult:
        """Filter one pass over ``data``.

        Parameters
        ----------
        model : SMDModel
        data : CycleData
        start : GaussianStart or restart object, optional
            Start distribution; ``None`` means the model prior. A previous
            result's ``restart`` continues from where that pass ended.
        rng : numpy.random.Generator, optional
            Random numbers (particle filter only).
        fixed : mapping, optional
            Slots held at known values.
        """
        raise NotImplementedError

    def __repr__(self):
        return f"{type(self).__name__}({', '.join(f'{k}={v!r}' for k, v in vars(self).items())})"


ESTIMATORS: dict[str, type] = {}
"""Registry of estimator classes by name."""


def register_estimator(cls):
    """Register an :class:`Estimator` subclass under ``cls.name`` (usable as a decorator)."""
    ESTIMATORS[cls.name] = cls
    return cls


def get_estimator(name, **options) -> Estimator:
    """Build the estimator registered as ``name`` with ``options``."""
    if isinstance(name, Estimator):
        return name
    if name not in ESTIMATORS:
        raise OptionError(f"unknown estimator {name!r}; choose one of {', '.join(sorted(ESTIMATORS))}")
    try:
        return ESTIMATORS[name](**options)
    except TypeError as exc:
        raise OptionError(f"estimator {name!r}: {exc}") from None


def reset_dynamic(model: SMDModel, setup: Setup, mean: np.ndarray, cov: np.ndarray):
    """Gaussian start for a repeated pass: parameters carried over, motion from the fresh prior.

    The motion (``u``, ``u_dot``, and effects' dynamic slots) at the start of
    the cycle is unrelated to its value at the end of the previous pass, so it
    is reset to the prior; cross-covariances with it are dropped.
    """
    dynamic = dynamic_mask(model)
    mean = mean.copy()
    cov = cov.copy()
    mean[dynamic] = setup.prior_mean[dynamic]
    cov[dynamic, :] = 0.0
    cov[:, dynamic] = 0.0
    cov[np.ix_(dynamic, dynamic)] = setup.prior_cov[np.ix_(dynamic, dynamic)]
    return mean, cov


def gaussian_start(model: SMDModel, setup: Setup, start) -> tuple[np.ndarray, np.ndarray]:
    """Mean and covariance to start a Kalman-type pass from ``start`` (None, GaussianStart, or restart)."""
    if start is None:
        mean, cov = setup.prior_mean.copy(), setup.prior_cov.copy()
    elif isinstance(start, GaussianStart):
        mean, cov = np.array(start.mean, dtype=float), np.array(start.cov, dtype=float)
        if mean.shape != (model.n_state,) or cov.shape != (model.n_state, model.n_state):
            raise OptionError(f"start has shapes {mean.shape}, {cov.shape}; the model has {model.n_state} states")
        if start.carry_over:
            mean, cov = reset_dynamic(model, setup, mean, cov)
    else:
        raise OptionError(f"cannot start a Gaussian filter from {type(start).__name__}")
    fixed = ~setup.free
    mean[fixed] = setup.fixed_values[fixed]
    cov[fixed, :] = 0.0
    cov[:, fixed] = 0.0
    return mean, cov


class FreeState:
    """Map between the full state and the free (estimated) slots of a :class:`Setup`.

    Kalman-type filters work on the free slots only, so a slot held fixed
    (zero variance) never makes a covariance singular.
    """

    def __init__(self, setup: Setup):
        self.free = np.flatnonzero(setup.free)
        self.template = np.where(setup.free, 0.0, setup.fixed_values)

    def embed(self, z):
        """Full states from free-slot values ``z`` of shape ``(..., n_free)``."""
        z = np.asarray(z, dtype=float)
        full = np.broadcast_to(self.template, z.shape[:-1] + self.template.shape).copy()
        full[..., self.free] = z
        return full

    def embed_cov(self, cov):
        """Full covariance (zero rows/columns for fixed slots) from the free block."""
        full = np.zeros((self.template.size, self.template.size))
        full[np.ix_(self.free, self.free)] = cov
        return full


class Trace:
    """Per-sample arrays of one pass (means, sds, innovations), turned into a :class:`FilterResult`.

    Estimators write ``mean[k]``, ``std[k]``, ``innovations[k]``,
    ``innovation_cov[k]`` and add to ``log_likelihood`` as they go.
    """

    def __init__(self, model: SMDModel, data: CycleData):
        m = len(data)
        self.mean = np.empty((m, model.n_state))
        self.std = np.empty((m, model.n_state))
        self.innovations = np.empty((m, model.n_obs))
        self.innovation_cov = np.empty((m, model.n_obs, model.n_obs))
        self.log_likelihood = 0.0

    def result(self, name, model, data, setup, restart, diagnostics) -> FilterResult:
        """The pass as a :class:`FilterResult` (raising :class:`EstimatorFailure` if anything is non-finite)."""
        if not (np.all(np.isfinite(self.mean)) and np.isfinite(self.log_likelihood)):
            raise EstimatorFailure(f"cycle {data.index}: the filter diverged (non-finite state or likelihood)")
        return FilterResult(
            estimator=name,
            state_names=model.state_names,
            t=data.t,
            mean=self.mean,
            std=self.std,
            innovations=self.innovations,
            innovation_cov=self.innovation_cov,
            log_likelihood=float(self.log_likelihood),
            restart=restart,
            prior_std=setup.prior_std,
            diagnostics=diagnostics,
        )


class GaussianTrace(Trace):
    """The trace of a Kalman-type pass: records a Gaussian state and innovation per sample."""

    def record(self, k, free_state: FreeState, x, P, y, S):
        """Store the filtered free-state mean ``x``, covariance ``P``, innovation ``y`` and its covariance ``S``."""
        x = np.ravel(x)
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(P)) and np.all(np.isfinite(S))):
            raise EstimatorFailure(f"non-finite state or covariance at sample {k}; the filter diverged")
        y = np.ravel(y)
        self.mean[k] = free_state.embed(x)
        self.std[k] = np.sqrt(np.maximum(np.diagonal(free_state.embed_cov(P)), 0.0))
        self.innovations[k] = y
        self.innovation_cov[k] = S
        sign, log_det = np.linalg.slogdet(S)
        if sign <= 0:
            raise EstimatorFailure(f"innovation covariance is not positive definite at sample {k}")
        self.log_likelihood += -0.5 * (y @ np.linalg.solve(S, y) + log_det + len(y) * np.log(2.0 * np.pi))


class CovarianceGuard:
    """Keeps a covariance matrix symmetric positive definite, counting every repair.

    Symmetrises; if a Cholesky factorisation fails, adds growing jitter; if
    that fails too, clips the eigenvalues. ``repairs`` counts the times it
    had to act beyond symmetrising (filterpy issues 31, 62, 218).
    """

    def __init__(self, floor: float = 1e-12):
        self.floor = floor
        self.repairs = 0

    def repair(self, P):
        """Return a symmetric positive definite version of ``P``."""
        P = 0.5 * (P + P.T)
        if not np.all(np.isfinite(P)):
            raise EstimatorFailure("covariance has non-finite entries and cannot be repaired")
        try:
            np.linalg.cholesky(P)
            return P
        except np.linalg.LinAlgError:
            pass
        self.repairs += 1
        scale = max(float(np.max(np.abs(np.diag(P)))), self.floor)
        for exponent in (-12, -10, -8):
            candidate = P + np.eye(len(P)) * scale * 10.0**exponent
            try:
                np.linalg.cholesky(candidate)
                return candidate
            except np.linalg.LinAlgError:
                continue
        values, vectors = np.linalg.eigh(P)
        values = np.maximum(values, scale * 1e-9)
        return (vectors * values) @ vectors.T

    def sqrt(self, P):
        """Upper Cholesky factor of the repaired ``P`` (a ``sqrt_fn`` for filterpy's sigma points)."""
        return np.linalg.cholesky(self.repair(P)).T
