"""The compiled state smoother: smoothed state means of a time-varying state-space model, one scalar observation.

:meth:`~smd_statespace.person.statespace.RecordStateSpace.smoothed_state` (the cycle starts' re-placement,
:func:`~smd_statespace.person.search.corrected_timing`, six times per record) needs the smoothed state means
alone. statsmodels' smoother computes them from the twin's matrices in 39 ms ("independent", 13 states) and 95 ms
("smooth", 22 states) on a 30 s record; this pass computes the same means from the same matrices, in statsmodels'
conventions, in 17 and 58 ms (measured side by side, the machine shared).

The model (statsmodels' time ``t`` maps the state at sample ``t`` to sample ``t + 1``)::

    y_t = Z_t a_t + d_t + eps_t,            eps_t ~ N(0, h)        (missing where not observed)
    a_{t+1} = T_t a_t + c_t + eta_t,        eta_t ~ N(0, Q_t)
    a_0 ~ N(a_init, P_init)

The forward pass is the Kalman filter; it keeps the predicted covariances ``P_t``, the innovations ``v_t``,
their variances ``F_t`` and ``M_t = P_t Z_t'``. The backward pass is the state smoothing recursion of
Durbin and Koopman (2012, *Time series analysis by state space methods*, 2nd ed., Sect. 4.4.4)::

    r_{t-1} = Z_t' v_t / F_t + L_t' r_t,    L_t = T_t (I - M_t Z_t / F_t),    r_{n-1} = 0
    a_hat_t = a_t + P_t r_{t-1}

(``r_{t-1} = T_t' r_t`` at a missing sample), which needs no inverse of ``P_t``.

The record-level model's transition is the identity but in a few rows (the dynamics' rows, and the force
coefficients' rows at a cycle start or a smooth step): ``T P T'`` is computed over those rows only, which
:func:`smoothed_state_means` finds once per call.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["smoothed_state_means"]


def smoothed_state_means(y, observed, design, obs_intercept, obs_var, transition, intercept, state_cov, mean0, cov0):
    """Smoothed state means ``E[a_t | y_0..y_{n-1}]``, shape ``(m, n)``.

    Parameters
    ----------
    y : ndarray, shape (n,)
        Observations (any value where not observed).
    observed : ndarray of bool, shape (n,)
        Whether each sample is observed.
    design : ndarray, shape (m, n)
        ``Z_t`` (statsmodels' ``design[0]``).
    obs_intercept : ndarray, shape (n,)
        ``d_t``.
    obs_var : float
        ``h``, the observation noise variance.
    transition : ndarray, shape (m, m, n)
        ``T_t``.
    intercept : ndarray, shape (m, n)
        ``c_t``.
    state_cov : ndarray, shape (m, m, n)
        ``Q_t`` (the selection matrix is the identity).
    mean0, cov0 : ndarray, shapes (m,), (m, m)
        The known initial state's mean and covariance.

    Returns
    -------
    ndarray, shape (m, n)
    """
    # statsmodels keeps its matrices in Fortran order: reversing the axes gives time-major C-ordered views
    # (``transition.T[t, j, i]`` is ``T_t[i, j]``) without a copy
    row_start, rows, entry_start, columns, values = _sparse_rows(np.ascontiguousarray(transition.T))
    q_start, q_rows, q_columns, q_values = _sparse_entries(np.ascontiguousarray(state_cov.T))
    return _smooth(np.ascontiguousarray(y, dtype=float), np.ascontiguousarray(observed, dtype=np.bool_),
                   np.ascontiguousarray(design.T), np.ascontiguousarray(obs_intercept, dtype=float), float(obs_var),
                   row_start, rows, entry_start, columns, values, np.ascontiguousarray(intercept.T),
                   q_start, q_rows, q_columns, q_values, np.ascontiguousarray(mean0, dtype=float),
                   np.ascontiguousarray(cov0, dtype=float)).T


@numba.njit(cache=True, nogil=True)
def _sparse_rows(TT):
    """The rows of ``T_t`` that are not the identity's, and their nonzero entries, in time order.

    ``TT[t, j, i]`` is ``T_t[i, j]``. Returns ``(row_start, rows, entry_start, columns, values)``: at time ``t``
    the rows ``rows[row_start[t]:row_start[t + 1]]``; row ``e`` of that list has the entries
    ``values[entry_start[e]:entry_start[e + 1]]`` in ``columns[...]``.
    """
    n, m, _ = TT.shape
    moving = np.zeros(m, dtype=np.bool_)
    count = np.zeros(m, dtype=np.int64)
    row_start = np.zeros(n + 1, dtype=np.int64)
    n_entries = 0
    for t in range(n):  # first pass: how many rows and entries
        _scan_rows(TT[t], moving, count)
        row_start[t + 1] = row_start[t]
        for i in range(m):
            if moving[i]:
                row_start[t + 1] += 1
                n_entries += count[i]
    rows = np.empty(row_start[n], dtype=np.int64)
    entry_start = np.zeros(row_start[n] + 1, dtype=np.int64)
    columns = np.empty(n_entries, dtype=np.int64)
    values = np.empty(n_entries)
    slot = np.empty(m, dtype=np.int64)
    e = 0
    for t in range(n):  # second pass: fill them
        _scan_rows(TT[t], moving, count)
        for i in range(m):
            slot[i] = -1
            if moving[i]:
                rows[e] = i
                slot[i] = entry_start[e]
                entry_start[e + 1] = entry_start[e] + count[i]
                e += 1
        for j in range(m):
            for i in range(m):
                if slot[i] >= 0 and TT[t, j, i] != 0.0:
                    columns[slot[i]] = j
                    values[slot[i]] = TT[t, j, i]
                    slot[i] += 1
    return row_start, rows, entry_start, columns, values


@numba.njit(cache=True, nogil=True)
def _scan_rows(TTt, moving, count):
    """Which rows of ``T_t`` (``TTt[j, i]`` is ``T_t[i, j]``) are not the identity's, and their nonzero entries'
    count (into ``moving``, ``count``)."""
    m = TTt.shape[0]
    moving[:] = False
    count[:] = 0
    for j in range(m):
        for i in range(m):
            value = TTt[j, i]
            if value != (1.0 if i == j else 0.0):
                moving[i] = True
            if value != 0.0:
                count[i] += 1


@numba.njit(cache=True, nogil=True)
def _sparse_entries(QT):
    """The nonzero entries of ``Q_t`` (``QT[t, j, i]`` is ``Q_t[i, j]``) in time order: ``(start, rows, columns,
    values)``, time ``t``'s entries at ``start[t]:start[t + 1]``."""
    n, m, _ = QT.shape
    start = np.zeros(n + 1, dtype=np.int64)
    for t in range(n):
        start[t + 1] = start[t]
        for j in range(m):
            for i in range(m):
                if QT[t, j, i] != 0.0:
                    start[t + 1] += 1
    rows = np.empty(start[n], dtype=np.int64)
    columns = np.empty(start[n], dtype=np.int64)
    values = np.empty(start[n])
    k = 0
    for t in range(n):
        for j in range(m):
            for i in range(m):
                if QT[t, j, i] != 0.0:
                    rows[k], columns[k], values[k] = i, j, QT[t, j, i]
                    k += 1
    return start, rows, columns, values


@numba.njit(cache=True, nogil=True)
def _smooth(y, observed, Z, d, h, row_start, rows, entry_start, columns, values, c, q_start, q_rows, q_columns,
            q_values, a0, P0):
    """The filter forward, the state smoothing recursion backward (time on the first axis of every array).

    ``T_t`` is the identity but in rows ``rows[row_start[t]:row_start[t + 1]]``; row ``rows[e]`` has the entries
    ``values[entry_start[e]:entry_start[e + 1]]`` in ``columns[...]``; ``Q_t`` has the entries
    ``q_values[q_start[t]:q_start[t + 1]]`` at ``(q_rows, q_columns)``.
    """
    n, m = Z.shape
    a_pred = np.empty((n, m))
    P_pred = np.empty((n, m, m))
    M = np.zeros((n, m))
    v = np.zeros(n)
    F = np.ones(n)
    a = a0.copy()
    P = P0.copy()
    TP = np.empty((m, m))
    moved = np.empty(m)
    # copies by loops: a slice assignment compiles numba's shape-mismatch error (string formatting), seconds of
    # compilation at a package's first use
    for t in range(n):
        for i in range(m):
            a_pred[t, i] = a[i]
            for j in range(m):
                P_pred[t, i, j] = P[i, j]
        if observed[t]:
            f = h
            e = y[t] - d[t]
            for i in range(m):
                total = 0.0
                for j in range(m):
                    total += P[i, j] * Z[t, j]
                M[t, i] = total
                f += Z[t, i] * total
                e -= Z[t, i] * a[i]
            v[t] = e
            F[t] = f
            for i in range(m):
                gain = M[t, i] / f
                a[i] += gain * e
                for j in range(m):
                    P[i, j] -= gain * M[t, j]
        # predict: a <- T a + c, P <- T P T' + Q, over the moving rows' entries only
        first, last = row_start[t], row_start[t + 1]
        for i in range(m):
            for j in range(m):
                TP[i, j] = P[i, j]
        for e in range(first, last):
            i = rows[e]
            total = 0.0
            for j in range(m):
                TP[i, j] = 0.0
            for k in range(entry_start[e], entry_start[e + 1]):
                total += values[k] * a[columns[k]]
                for j in range(m):
                    TP[i, j] += values[k] * P[columns[k], j]
            moved[i] = total
        for e in range(first, last):
            a[rows[e]] = moved[rows[e]]
        for i in range(m):
            for j in range(m):
                P[i, j] = TP[i, j]
        for e in range(first, last):
            i = rows[e]
            for j in range(m):
                P[j, i] = 0.0
            for k in range(entry_start[e], entry_start[e + 1]):
                for j in range(m):
                    P[j, i] += TP[j, columns[k]] * values[k]
        for i in range(m):
            a[i] += c[t, i]
        for k in range(q_start[t], q_start[t + 1]):
            P[q_rows[k], q_columns[k]] += q_values[k]
    return _backward(row_start, rows, entry_start, columns, values, Z, observed, v, F, M, a_pred, P_pred)


@numba.njit(cache=True, nogil=True)
def _backward(row_start, rows, entry_start, columns, values, Z, observed, v, F, M, a_pred, P_pred):
    """The state smoothing recursion from the filter's stored output: ``a_hat_t = a_t + P_t r_{t-1}``."""
    n, m = Z.shape
    u = np.empty(m)
    r = np.zeros(m)
    out = np.empty((n, m))
    for t in range(n - 1, -1, -1):
        # u = T_t' r_t; then r_{t-1} = u + Z_t' (v_t - M_t' u) / F_t
        for j in range(m):
            u[j] = r[j]
        for e in range(row_start[t], row_start[t + 1]):
            u[rows[e]] = 0.0
        for e in range(row_start[t], row_start[t + 1]):
            for k in range(entry_start[e], entry_start[e + 1]):
                u[columns[k]] += values[k] * r[rows[e]]
        if observed[t]:
            scale = v[t]
            for j in range(m):
                scale -= M[t, j] * u[j]
            scale /= F[t]
            for j in range(m):
                r[j] = u[j] + Z[t, j] * scale
        else:
            for j in range(m):
                r[j] = u[j]
        for i in range(m):
            total = a_pred[t, i]
            for j in range(m):
                total += P_pred[t, i, j] * r[j]
            out[t, i] = total
    return out
