"""How well a prediction fits a measurement: normalised root-mean-square fit (MATLAB's ``compare``) and RMS."""

from __future__ import annotations

import numpy as np

__all__ = ["fit_percent", "rms"]


def fit_percent(measured, predicted) -> float:
    """Normalised root-mean-square fit (%), as in system identification toolboxes.

    ``100 (1 - ||y - y_hat|| / ||y - mean(y)||)``: 100 for a perfect
    prediction, 0 for predicting the mean, negative for worse.

    Parameters
    ----------
    measured, predicted : array_like, shape (T,)
    """
    y = np.asarray(measured, dtype=float)
    y_hat = np.asarray(predicted, dtype=float)
    spread = np.linalg.norm(y - y.mean())
    if spread == 0:
        return float("nan")
    return float(100.0 * (1.0 - np.linalg.norm(y - y_hat) / spread))


def rms(x) -> float:
    """Root mean square of an array, in its unit."""
    return float(np.sqrt(np.mean(np.square(x))))
