"""Trends of a parameter against the bouncing frequency (Section 5): OLS polynomials and the "preferred frequency"."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np
import pandas as pd

from ..errors import OptionError
from .results import PARAMETERS

__all__ = ["TREND_DEGREES", "TrendResult", "fit_trend"]


TREND_DEGREES = MappingProxyType({"f_h": 1, "xi_h": 2, "K_h": 1, "C_h": 1, "BLF1": 2, "BLF2": 1, "BLF3": 1})
"""Polynomial degree in ``f_b`` of each trend (Section 5: ``f_h`` linear, ``xi_h`` and BLF1 parabolic)."""


@dataclass
class TrendResult:
    """Polynomial trend of one parameter in the bouncing frequency, ``y = b0 + b1 f_b (+ b2 f_b^2)``.

    Attributes
    ----------
    parameter : str
        Name in :data:`PARAMETERS`.
    degree : int
        1 (linear) or 2 (quadratic).
    n : int
        Cycles in the regression.
    params, bse, pvalues : numpy.ndarray
        Coefficients ``b0, b1[, b2]`` (units of the parameter per Hz^k), standard errors and
        two-sided p-values (t-tests, ``cov_type`` covariance).
    conf_int : numpy.ndarray
        ``(degree + 1, 2)`` confidence intervals of the coefficients.
    rsquared : float
        Coefficient of determination.
    cov_type : str
        statsmodels covariance type (default ``"HC3"``, robust to the spread growing with ``f_b``).
    vertex : float or None
        Quadratics: ``f* = -b1 / (2 b2)`` (Hz), the "preferred frequency"; None for lines.
    vertex_kind : str
        ``"minimum"`` (``b2 > 0``) or ``"maximum"``; empty for lines.
    vertex_se, vertex_ci_delta : float, (float, float)
        Delta-method standard error and interval of ``f*``.
    vertex_ci_bootstrap : (float, float) or None
        Bootstrap percentile interval of ``f*`` (cycles resampled), None without bootstrap.
    f_b_range : (float, float)
        Range of the bouncing frequencies fitted (Hz).
    ols : statsmodels RegressionResults
        The full statsmodels result (``.summary()``, ``.get_prediction``).
    """

    parameter: str
    degree: int
    n: int
    params: np.ndarray
    bse: np.ndarray
    pvalues: np.ndarray
    conf_int: np.ndarray
    rsquared: float
    cov_type: str
    confidence: float
    f_b_range: tuple
    ols: object = field(repr=False)
    vertex: float | None = None
    vertex_kind: str = ""
    vertex_se: float = math.nan
    vertex_ci_delta: tuple | None = None
    vertex_ci_bootstrap: tuple | None = None
    n_bootstrap: int = 0

    @property
    def terms(self) -> list[str]:
        """Coefficient names: ``const``, ``f_b``, ``f_b^2``."""
        return ["const", "f_b", "f_b^2"][: self.degree + 1]

    def predict(self, f_b, confidence: float | None = None):
        """Trend and confidence band of the mean at ``f_b`` (Hz): ``(mean, low, high)`` arrays."""
        f = np.atleast_1d(np.asarray(f_b, dtype=float))
        design = np.vander(f, self.degree + 1, increasing=True)
        prediction = self.ols.get_prediction(design)
        frame = prediction.summary_frame(alpha=1.0 - (confidence or self.confidence))
        return (frame["mean"].to_numpy(), frame["mean_ci_lower"].to_numpy(), frame["mean_ci_upper"].to_numpy())

    def to_frame(self) -> pd.DataFrame:
        """One row per coefficient (and one for the vertex of a quadratic)."""
        pct = f"{self.confidence:.0%}"
        rows = [{"parameter": self.parameter, "term": term, "estimate": self.params[k], "se": self.bse[k],
                 "ci_low": self.conf_int[k, 0], "ci_high": self.conf_int[k, 1], "p_value": self.pvalues[k],
                 "method": f"OLS {self.cov_type} ({pct})"} for k, term in enumerate(self.terms)]
        if self.vertex is not None:
            low, high = self.vertex_ci_delta
            rows.append({"parameter": self.parameter, "term": f"vertex ({self.vertex_kind})", "estimate": self.vertex,
                         "se": self.vertex_se, "ci_low": low, "ci_high": high, "p_value": math.nan,
                         "method": f"delta method ({pct})"})
            if self.vertex_ci_bootstrap is not None:
                low, high = self.vertex_ci_bootstrap
                rows.append({"parameter": self.parameter, "term": f"vertex ({self.vertex_kind})",
                             "estimate": self.vertex, "se": math.nan, "ci_low": low, "ci_high": high,
                             "p_value": math.nan, "method": f"bootstrap percentile, {self.n_bootstrap} ({pct})"})
        frame = pd.DataFrame(rows)
        frame["n"] = self.n
        frame["r_squared"] = self.rsquared
        return frame

    def summary(self) -> str:
        """A few lines: the fitted polynomial, coefficients with intervals and p-values, the vertex."""
        unit = PARAMETERS[self.parameter].unit
        kind = "linear" if self.degree == 1 else "quadratic"
        lines = [f"{self.parameter} ({unit}) {kind} in f_b, n = {self.n}, R^2 = {self.rsquared:.3f}, "
                 f"{self.cov_type} covariance, f_b {self.f_b_range[0]:.2f}-{self.f_b_range[1]:.2f} Hz"]
        for k, term in enumerate(self.terms):
            lines.append(f"  {term:<6} {self.params[k]: .5g}  [{self.conf_int[k, 0]: .5g}, {self.conf_int[k, 1]: .5g}]"
                         f"  p = {self.pvalues[k]:.3g}")
        if self.vertex is not None:
            where = ("inside" if self.f_b_range[0] <= self.vertex <= self.f_b_range[1] else "outside")
            low, high = self.vertex_ci_delta
            line = f"  vertex ({self.vertex_kind}) f* = {self.vertex:.3f} Hz, delta method [{low:.3f}, {high:.3f}]"
            if self.vertex_ci_bootstrap is not None:
                line += f", bootstrap [{self.vertex_ci_bootstrap[0]:.3f}, {self.vertex_ci_bootstrap[1]:.3f}]"
            lines.append(line + f" ({where} the data)")
        return "\n".join(lines)


def _trend_shortfall(f: np.ndarray, degree: int, noun: str = "cycles") -> str:
    """Why ``f`` (one bouncing frequency per row, ``noun``) cannot carry a polynomial trend of ``degree`` (empty when it can)."""
    distinct = np.unique(f[np.isfinite(f)]).size
    if f.size < degree + 3 or distinct < degree + 1:
        return (f"too few {noun}: need {degree + 3} at {degree + 1} or more distinct bouncing frequencies, "
                f"got {f.size} at {distinct}")
    return ""


def _no_spread(y: np.ndarray) -> str:
    """``"no spread: all n values equal v"`` when ``y`` is constant (R^2 is then undefined), else empty."""
    y = y[np.isfinite(y)]
    if y.size and np.ptp(y) == 0:
        return f"no spread: all {y.size} values equal {y[0]:.4g}"
    return ""


def fit_trend(f_b, values, degree: int, *, parameter: str = "f_h", n_bootstrap: int = 0, rng=None,
              confidence: float = 0.95, cov_type: str = "HC3") -> TrendResult:
    """Fit ``values`` as a polynomial of degree 1 or 2 in ``f_b`` by OLS (statsmodels).

    Parameters
    ----------
    f_b : array_like
        Bouncing frequencies (Hz), one per cycle.
    values : array_like
        The parameter, one per cycle (unit of the parameter); not all equal (a constant has no
        trend and no R^2: an OptionError says "no spread").
    degree : int
        1 (linear) or 2 (quadratic, with the vertex).
    parameter : str
        Name of the parameter (labels only).
    n_bootstrap : int
        Case-resampling bootstrap resamples for the vertex interval (0: delta method only).
    rng : numpy.random.Generator, int or SeedSequence, optional
        Source of the resampling.
    confidence : float
        Level of the intervals.
    cov_type : str
        statsmodels covariance type: ``"HC3"`` (default), ``"nonrobust"``, ``"HC0"``...

    Returns
    -------
    TrendResult
    """
    import statsmodels.api as sm
    from scipy.stats import norm

    if degree not in (1, 2):
        raise OptionError(f"trend degree must be 1 or 2, got {degree!r}")
    f = np.asarray(f_b, dtype=float)
    y = np.asarray(values, dtype=float)
    keep = np.isfinite(f) & np.isfinite(y)
    f, y = f[keep], y[keep]
    shortfall = _trend_shortfall(f, degree) or _no_spread(y)
    if shortfall:
        raise OptionError(f"{parameter} trend: {shortfall}")
    design = np.vander(f, degree + 1, increasing=True)
    ols = sm.OLS(y, design).fit(cov_type=cov_type)
    alpha = 1.0 - confidence
    result = TrendResult(parameter=parameter, degree=degree, n=int(f.size), params=np.asarray(ols.params),
                         bse=np.asarray(ols.bse), pvalues=np.asarray(ols.pvalues),
                         conf_int=np.asarray(ols.conf_int(alpha=alpha)), rsquared=float(ols.rsquared),
                         cov_type=cov_type, confidence=confidence, f_b_range=(float(f.min()), float(f.max())), ols=ols)
    if degree == 2:
        b1, b2 = result.params[1], result.params[2]
        vertex = -b1 / (2.0 * b2)
        cov = np.asarray(ols.cov_params())[1:, 1:]
        gradient = np.array([-1.0 / (2.0 * b2), b1 / (2.0 * b2 * b2)])
        se = float(np.sqrt(gradient @ cov @ gradient))
        half = norm.ppf(1.0 - alpha / 2.0) * se
        result.vertex, result.vertex_se = float(vertex), se
        result.vertex_kind = "minimum" if b2 > 0 else "maximum"
        result.vertex_ci_delta = (float(vertex - half), float(vertex + half))
        if n_bootstrap:
            rng = np.random.default_rng(rng)
            index = rng.integers(0, f.size, size=(int(n_bootstrap), f.size))
            xb, yb = design[index], y[index]
            gram = np.einsum("bni,bnj->bij", xb, xb)
            coef = np.linalg.solve(gram, np.einsum("bni,bn->bi", xb, yb)[..., None])[..., 0]
            vertices = -coef[:, 1] / (2.0 * coef[:, 2])
            tail = 50.0 * alpha
            result.vertex_ci_bootstrap = tuple(float(v) for v in np.percentile(vertices, [tail, 100.0 - tail]))
            result.n_bootstrap = int(n_bootstrap)
    return result
