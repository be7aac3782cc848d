"""Correlation of a residual with candidate terms: which missing effect does the error look like?

Functions over arrays, used by :meth:`ModelCheck.cross_correlation
<smd_statespace.diagnostics.check.ModelCheck.cross_correlation>`:

- :func:`pearson_correlation` of two series;
- :func:`multiple_correlation` of a series with a least-squares fit of several columns;
- :func:`lagged_correlations` of a series on some samples of a record with a
  candidate over the whole record, shifted by whole-sample lags;
- :func:`cross_correlation_table`: the strongest lag of every candidate, strongest candidate first.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..errors import OptionError

__all__ = ["pearson_correlation", "multiple_correlation", "candidate_columns", "lagged_correlations",
           "cross_correlation_table"]

TABLE_COLUMNS = ["signal", "max_abs_corr", "corr", "lag_s", "corr_at_zero", "explained"]


def pearson_correlation(a, b) -> float:
    """Pearson correlation of two equal-length arrays.

    Parameters
    ----------
    a, b : ndarray, shape (T,)

    Returns
    -------
    float
        In [-1, 1]; NaN when either array is constant.
    """
    a = a - a.mean()
    b = b - b.mean()
    denominator = np.sqrt(np.dot(a, a) * np.dot(b, b))
    return float(np.dot(a, b) / denominator) if denominator > 0 else float("nan")


def multiple_correlation(target, columns) -> float:
    """Multiple correlation of ``target`` with a least-squares fit of ``columns`` (and a constant).

    Parameters
    ----------
    target : ndarray, shape (T,)
    columns : ndarray, shape (T, q)

    Returns
    -------
    float
        ``R = sqrt(1 - RSS / TSS)`` in [0, 1] (``R^2``: the fraction of
        ``target``'s variance the fit removes); NaN when ``target`` is constant.
    """
    design = np.column_stack([np.ones(target.size), columns])
    coefficients, *_ = np.linalg.lstsq(design, target, rcond=None)
    centred = target - target.mean()
    total = float(np.dot(centred, centred))
    if total == 0:
        return float("nan")
    left = target - design @ coefficients
    return float(np.sqrt(max(0.0, 1.0 - float(np.dot(left, left)) / total)))


def candidate_columns(name, values, n_record) -> np.ndarray:
    """A candidate's values over the whole record as columns, shape (n_record, q).

    Raises
    ------
    OptionError
        ``values`` is not of shape ``(n_record,)`` or ``(n_record, q)``, or holds NaN or infinite values.
    """
    values = np.asarray(values, dtype=float)
    columns = values[:, None] if values.ndim == 1 else values
    if columns.ndim != 2 or columns.shape[0] != n_record:
        raise OptionError(
            f"candidate {name!r} has shape {values.shape}; give ({n_record},) or ({n_record}, q): "
            "values over the whole record"
        )
    if not np.all(np.isfinite(columns)):
        raise OptionError(f"candidate {name!r} holds NaN or infinite values")
    return columns


def lagged_correlations(target, columns, sample_index, lags, transform=None) -> np.ndarray:
    """Correlation of ``target`` with ``columns`` shifted by each lag.

    For a lag ``tau`` (samples) the candidate at record sample ``i - tau``
    is paired with the target at record sample ``i`` (``tau > 0``: the
    candidate leads); indices beyond the record's ends are clipped to them.

    Parameters
    ----------
    target : ndarray, shape (T,)
        A series on some samples of a record (e.g. a residual).
    columns : ndarray, shape (n_record, q)
        A candidate over the whole record (:func:`candidate_columns`).
    sample_index : ndarray of int, shape (T,)
        Position of each target sample in the record.
    lags : ndarray of int
        Lags (samples).
    transform : callable, optional
        Applied to each shifted block, shape (T, q), before correlating (e.g.
        the removal of a per-cycle force-basis fit).

    Returns
    -------
    ndarray, shape (len(lags),)
        :func:`pearson_correlation` for one column, :func:`multiple_correlation` for several.
    """
    n_record = columns.shape[0]
    corr = np.empty(len(lags))
    for j, lag in enumerate(lags):
        block = columns[np.clip(sample_index - lag, 0, n_record - 1)]
        if transform is not None:
            block = transform(block)
        corr[j] = pearson_correlation(target, block[:, 0]) if block.shape[1] == 1 else multiple_correlation(target,
                                                                                                            block)
    return corr


def cross_correlation_table(target, candidates, sample_index, n_record, fs, max_lag_s=0.0,
                            transform=None) -> pd.DataFrame:
    """Correlation of a series with every candidate at its strongest lag, strongest candidate first.

    Multi-column candidates are scored by the multiple correlation of a
    least-squares fit of all their columns (``corr`` is then NaN); single
    columns by the Pearson correlation (:func:`lagged_correlations`). The
    lag with the largest absolute correlation, ``|tau| <= max_lag_s``, is
    reported.

    Parameters
    ----------
    target : ndarray, shape (T,)
        A series on some samples of a record (e.g. a residual, N).
    candidates : mapping of str to array_like
        Signals over the whole record, each of shape ``(n_record,)`` or ``(n_record, q)``.
    sample_index : ndarray of int, shape (T,)
        Position of each target sample in the record.
    n_record : int
        Number of samples of the record.
    fs : float
        Sampling frequency (Hz).
    max_lag_s : float
        Largest lag (s).
    transform : callable, optional
        Applied to each shifted candidate block (see :func:`lagged_correlations`).

    Returns
    -------
    pandas.DataFrame
        One row per candidate, strongest first: ``signal``,
        ``max_abs_corr``, ``corr`` (signed value there, NaN for
        multi-column candidates), ``lag_s`` (s), ``corr_at_zero`` (no
        lag) and ``explained`` (``max_abs_corr^2``: fraction of the
        target's variance a least-squares multiple of the candidate
        removes).

    Raises
    ------
    OptionError
        A negative ``max_lag_s`` or a candidate of the wrong shape (:func:`candidate_columns`).
    """
    max_lag = int(np.floor(float(max_lag_s) * fs + 1e-9))
    if max_lag < 0:
        raise OptionError(f"max_lag_s must be >= 0, got {max_lag_s!r}")
    lags = np.arange(-max_lag, max_lag + 1)
    rows = []
    for name, values in candidates.items():
        columns = candidate_columns(name, values, n_record)
        corr = lagged_correlations(target, columns, sample_index, lags, transform)
        if np.all(np.isnan(corr)):
            best, value = max_lag, float("nan")
        else:
            best = int(np.nanargmax(np.abs(corr)))
            value = float(corr[best])
        rows.append({"signal": name, "max_abs_corr": abs(value), "corr": value if columns.shape[1] == 1 else np.nan,
                     "lag_s": lags[best] / fs, "corr_at_zero": float(corr[max_lag]), "explained": value**2})
    frame = pd.DataFrame(rows, columns=TABLE_COLUMNS)
    return frame.sort_values("max_abs_corr", ascending=False, na_position="last").reset_index(drop=True)
