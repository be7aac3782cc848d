"""The skew-normal distribution of Eq. 19: maximum-likelihood fit and bootstrap intervals."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from scipy.special import log_ndtr

from .. import article
from ..errors import OptionError

__all__ = ["N_BOOTSTRAP", "A_MAX", "SkewNormalResult", "fit_skewnorm", "bootstrap_skewnorm"]


N_BOOTSTRAP = 200
"""Default number of bootstrap resamples for the confidence intervals."""

A_MAX = 50.0
"""Cap on the skew-normal shape ``|a|`` (the likelihood can rise without bound towards the half-normal)."""
_LOG_NORM = np.log(2.0) - 0.5 * np.log(2.0 * np.pi)  # log(2 / sqrt(2 pi)) of Eq. 19
_MAX_SKEW = 0.99  # sample skewness used for the moment start is clipped below skewnorm's limit 0.9953


def _skewnorm_nll(x, theta, derivatives: bool = True):
    """Negative log-likelihood of Eq. 19, with gradient and Hessian in ``(m, log s, a)``.

    ``x`` is ``(B, n)`` (one sample per row) or ``(n,)`` shared by every row of ``theta`` ``(B, 3)``.
    With ``r = phi(u) / Phi(u)`` at ``u = a z``, ``z = (x - m) / s``, the log-density is
    ``log 2 - log s - log sqrt(2 pi) - z^2 / 2 + log Phi(u)``; as ``m``, ``s`` and ``a`` are
    constant along a row, the derivatives need only the row sums below.
    """
    n = x.shape[-1]
    m, tau, a = theta[:, 0:1], theta[:, 1], theta[:, 2]
    s = np.exp(tau)
    z = (x - m) / s[:, None]
    u = z * a[:, None]
    logcdf = log_ndtr(u)
    zz = z * z
    sum_zz = zz.sum(-1)
    nll = -(n * (_LOG_NORM - tau) - 0.5 * sum_zz + logcdf.sum(-1))
    if not derivatives:
        return nll
    r = np.exp(-0.5 * u * u - 0.5 * np.log(2.0 * np.pi) - logcdf)  # phi(u) / Phi(u), stable for u << 0
    dr = -r * (u + r)  # d r / d u
    sum_z, sum_r, sum_dr = z.sum(-1), r.sum(-1), dr.sum(-1)
    sum_zr, sum_zdr, sum_zzdr = (np.einsum("ij,ij->i", z, r), np.einsum("ij,ij->i", z, dr),
                                 np.einsum("ij,ij->i", zz, dr))
    grad = np.stack([(sum_z - a * sum_r) / s, sum_zz - n - a * sum_zr, sum_zr], axis=-1)
    h_mm = (a * a * sum_dr - n) / (s * s)
    h_mt = (a * a * sum_zdr + a * sum_r - 2.0 * sum_z) / s
    h_ma = -(sum_r + a * sum_zdr) / s
    h_tt = a * a * sum_zzdr - 2.0 * sum_zz + a * sum_zr
    h_ta = -(sum_zr + a * sum_zzdr)
    h_aa = sum_zzdr
    hess = np.stack([np.stack([h_mm, h_mt, h_ma], -1), np.stack([h_mt, h_tt, h_ta], -1),
                     np.stack([h_ma, h_ta, h_aa], -1)], axis=-2)
    return nll, -grad, -hess


def _pinned(theta, grad, a_max):
    """Rows whose shape sits at the cap ``|a| = a_max`` with the descent direction pointing further out."""
    return (np.abs(theta[:, 2]) >= a_max) & (grad[:, 2] * theta[:, 2] < 0)


def _minimise(x, theta, a_max: float, max_iter: int = 100):
    """Damped Newton (Levenberg-Marquardt) on :func:`_skewnorm_nll`, vectorised over the rows of ``theta``.

    ``|a|`` is projected onto ``[0, a_max]``; a row whose shape is held at the cap continues in
    ``(m, log s)`` alone. Returns ``(theta, nll, converged)``: converged rows have a (projected)
    gradient under 1e-3 of the curvature's standard deviation in every coordinate.
    """
    with np.errstate(over="ignore", divide="ignore", invalid="ignore", under="ignore"):  # bad trials are rejected
        return _newton(x, theta, a_max, max_iter)


def _newton(x, theta, a_max, max_iter):
    theta = np.array(theta, dtype=float)
    theta[:, 2] = np.clip(theta[:, 2], -a_max, a_max)
    nll, grad, hess = _skewnorm_nll(x, theta)
    damping = np.full(len(theta), 1e-3)
    done = np.zeros(len(theta), dtype=bool)
    eye = np.eye(3)
    for _ in range(max_iter):
        rows = np.flatnonzero(~done)
        if not rows.size:
            break
        xa = x[rows] if x.ndim == 2 else x
        t, g, h = theta[rows], grad[rows].copy(), hess[rows]
        pinned = _pinned(t, g, a_max)
        g[pinned, 2] = 0.0
        scale = np.abs(np.diagonal(h, axis1=-2, axis2=-1)) + 1e-12
        system = h + damping[rows, None, None] * scale[:, :, None] * eye
        system[pinned, 2, :] = 0.0
        system[pinned, :, 2] = 0.0
        system[pinned, 2, 2] = 1.0
        try:
            step = -np.linalg.solve(system, g[..., None])[..., 0]
        except np.linalg.LinAlgError:
            step = -g / scale
        trial = t + step
        trial[:, 2] = np.clip(trial[:, 2], -a_max, a_max)
        f_trial, g_trial, h_trial = _skewnorm_nll(xa, trial)
        better = np.isfinite(f_trial) & (f_trial <= nll[rows])
        moved = np.abs(trial - t).max(axis=-1)
        small = (moved < 1e-10) | (better & (nll[rows] - f_trial <= 1e-12 * (1.0 + np.abs(nll[rows])))
                                   & (damping[rows] < 1.0))
        accepted = rows[better]
        theta[accepted], nll[accepted] = trial[better], f_trial[better]
        grad[accepted], hess[accepted] = g_trial[better], h_trial[better]
        damping[rows] = np.where(better, np.maximum(damping[rows] / 10.0, 1e-9), damping[rows] * 10.0)
        done[rows[small | (damping[rows] > 1e12)]] = True
    curvature = np.sqrt(np.abs(np.diagonal(hess, axis1=-2, axis2=-1))) + 1e-12
    free = np.abs(grad) / curvature  # distance to the optimum in standard deviations, per coordinate
    free[:, 2] = np.where(_pinned(theta, grad, a_max), 0.0, free[:, 2])
    return theta, nll, (free < 1e-3).all(axis=-1)


def _moment_start(z: np.ndarray) -> np.ndarray:
    """Method-of-moments ``(m, log s, a)`` of a standardised sample (mean 0, sd 1)."""
    gamma = float(np.clip(np.mean(z ** 3), -_MAX_SKEW, _MAX_SKEW))
    g23 = abs(gamma) ** (2.0 / 3.0)
    delta = math.copysign(math.sqrt(0.5 * math.pi * g23 / (g23 + (0.5 * (4.0 - math.pi)) ** (2.0 / 3.0))), gamma)
    scale = 1.0 / math.sqrt(1.0 - 2.0 * delta * delta / math.pi)
    return np.array([-scale * delta * math.sqrt(2.0 / math.pi), math.log(scale), delta / math.sqrt(1 - delta ** 2)])


def _start_with_shape(a: float) -> np.ndarray:
    """``(m, log s, a)`` with shape ``a`` and the mean 0 and sd 1 of a standardised sample."""
    delta = a / math.sqrt(1.0 + a * a)
    scale = 1.0 / math.sqrt(1.0 - 2.0 * delta * delta / math.pi)
    return np.array([-scale * delta * math.sqrt(2.0 / math.pi), math.log(scale), a])


@dataclass(frozen=True)
class SkewNormalResult:
    """Maximum-likelihood skew-normal fit (Eq. 19) of one sample.

    Attributes
    ----------
    m, s, a : float
        Location, scale (same unit as the data) and shape (-) of
        ``scipy.stats.skewnorm(a, loc=m, scale=s)``.
    n : int
        Sample size.
    log_likelihood : float
        Maximised log-likelihood.
    se : tuple of float
        Standard errors of ``(m, s, a)`` from the observed information (NaN for ``a`` at its cap).
    at_bound : bool
        ``|a|`` reached ``a_max``: the likelihood still rises towards the half-normal limit.
    converged : bool
        The Newton iteration met its tolerances.
    ci : dict or None
        ``{"m": (low, high), "s": ..., "a": ...}`` bootstrap percentile intervals.
    confidence : float
        Level of ``ci``.
    n_bootstrap : int
        Bootstrap resamples whose fit converged (those behind ``ci``).
    """

    m: float
    s: float
    a: float
    n: int
    log_likelihood: float
    se: tuple = (math.nan, math.nan, math.nan)
    at_bound: bool = False
    converged: bool = True
    ci: dict | None = None
    confidence: float = 0.95
    n_bootstrap: int = 0

    @property
    def params(self) -> article.SkewNormalFit:
        """``(m, s, a)`` as :class:`smd_statespace.article.SkewNormalFit` (the layout of Table 2)."""
        return article.SkewNormalFit(self.m, self.s, self.a)

    def dist(self):
        """The frozen ``scipy.stats.skewnorm`` distribution."""
        return self.params.dist()

    @property
    def mean(self) -> float:
        """Mean of the fitted distribution, ``m + s delta sqrt(2/pi)``, ``delta = a / sqrt(1 + a^2)``."""
        return float(self.dist().mean())

    @property
    def sd(self) -> float:
        """Standard deviation of the fitted distribution, ``s sqrt(1 - 2 delta^2 / pi)``."""
        return float(self.dist().std())

    def summary(self) -> str:
        """One line: ``m, s, a`` with standard errors or intervals."""
        parts = []
        for name in ("m", "s", "a"):
            value = getattr(self, name)
            if self.ci is not None:
                low, high = self.ci[name]
                parts.append(f"{name} = {value:.5g} [{low:.5g}, {high:.5g}]")
            else:
                parts.append(f"{name} = {value:.5g}")
        tail = f" ({self.confidence:.0%} bootstrap, {self.n_bootstrap} resamples)" if self.ci is not None else ""
        bound = f"; |a| at the cap {abs(self.a):g}" if self.at_bound else ""
        return f"skew-normal (Eq. 19), n = {self.n}: " + ", ".join(parts) + tail + bound


def _as_sample(values) -> np.ndarray:
    x = np.asarray(values, dtype=float).ravel()
    x = x[np.isfinite(x)]
    if x.size < 3:
        raise OptionError(f"fit_skewnorm: need at least 3 finite values, got {x.size}")
    if np.ptp(x) == 0:
        raise OptionError(f"fit_skewnorm: all {x.size} values are equal ({x[0]:g}); no spread to fit")
    return x


def fit_skewnorm(values, *, a_max: float = A_MAX) -> SkewNormalResult:
    """Fit Eq. 19 to a sample by maximum likelihood.

    Parameters
    ----------
    values : array_like
        The sample (non-finite values are dropped); at least 3 values, not all equal.
    a_max : float
        Cap on ``|a|`` (default :data:`A_MAX`).

    Returns
    -------
    SkewNormalResult
        ``m, s, a`` (``scipy.stats.skewnorm(a, loc=m, scale=s)``), log-likelihood, standard errors.

    Notes
    -----
    The sample is standardised (the fit is equivariant), the damped Newton iteration is run from
    the method-of-moments estimate and from shapes 0.5, 3 and 20 (signed like the sample skewness)
    at once, and the best converged optimum is kept.
    """
    x = _as_sample(values)
    centre, spread = float(x.mean()), float(x.std())
    z = (x - centre) / spread
    sign = 1.0 if np.mean(z ** 3) >= 0 else -1.0
    starts = np.vstack([_moment_start(z)] + [_start_with_shape(sign * a) for a in (0.5, 3.0, 20.0)])
    theta, nll, ok = _minimise(z, starts, a_max)
    best = int(np.argmin(np.where(ok, nll, np.inf))) if ok.any() else int(np.argmin(nll))
    t = theta[best]
    at_bound = bool(abs(t[2]) >= a_max * (1 - 1e-9))
    _, _, hess = _skewnorm_nll(z, t[None])
    se = (math.nan, math.nan, math.nan)
    try:
        cov = np.linalg.inv(hess[0])
        if np.all(np.diag(cov) > 0):
            sd = np.sqrt(np.diag(cov))
            s_hat = spread * math.exp(t[1])
            se = (spread * sd[0], s_hat * sd[1], math.nan if at_bound else sd[2])  # d s = s d(log s)
    except np.linalg.LinAlgError:
        pass
    return SkewNormalResult(
        m=centre + spread * float(t[0]), s=spread * math.exp(float(t[1])), a=float(t[2]), n=int(x.size),
        log_likelihood=float(-nll[best] - x.size * math.log(spread)), se=tuple(float(v) for v in se),
        at_bound=at_bound, converged=bool(ok[best]),
    )


def bootstrap_skewnorm(values, fit: SkewNormalResult, n_bootstrap: int = N_BOOTSTRAP, rng=None, *,
                       confidence: float = 0.95, a_max: float = A_MAX) -> SkewNormalResult:
    """Bootstrap percentile intervals of ``(m, s, a)`` for a fit of :func:`fit_skewnorm`.

    The sample is resampled with replacement ``n_bootstrap`` times and every resample is refitted,
    all at once (one vectorised Newton iteration started from ``fit``).

    Parameters
    ----------
    values : array_like
        The sample ``fit`` was made on.
    fit : SkewNormalResult
        The point fit.
    n_bootstrap : int
        Resamples (>= 1).
    rng : numpy.random.Generator, int or SeedSequence, optional
        Source of the resampling (:func:`numpy.random.default_rng`).
    confidence : float
        Level of the intervals, in (0, 1).

    Returns
    -------
    SkewNormalResult
        ``fit`` with ``ci``, ``confidence`` and ``n_bootstrap`` (converged resamples) set.
    """
    if not 0 < confidence < 1:
        raise OptionError(f"confidence must be between 0 and 1, got {confidence!r}")
    if int(n_bootstrap) < 1:
        raise OptionError(f"n_bootstrap must be >= 1, got {n_bootstrap!r}")
    x = _as_sample(values)
    rng = np.random.default_rng(rng)
    centre, spread = float(x.mean()), float(x.std())
    z = (x - centre) / spread
    samples = z[rng.integers(0, z.size, size=(int(n_bootstrap), z.size))]
    start = np.array([(fit.m - centre) / spread, math.log(fit.s / spread), fit.a])
    theta, _, ok = _minimise(samples, np.tile(start, (int(n_bootstrap), 1)), a_max)
    theta = theta[ok]
    if not len(theta):
        return dataclasses.replace(fit, ci=None, confidence=confidence, n_bootstrap=0)
    draws = {"m": centre + spread * theta[:, 0], "s": spread * np.exp(theta[:, 1]), "a": theta[:, 2]}
    tail = 50.0 * (1.0 - confidence)
    ci = {name: tuple(float(v) for v in np.percentile(d, [tail, 100.0 - tail])) for name, d in draws.items()}
    return dataclasses.replace(fit, ci=ci, confidence=confidence, n_bootstrap=int(len(theta)))
