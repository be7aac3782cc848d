"""The record-level Kalman filter: one compiled pass, with the template concentrated out.

The record-level model (:mod:`smd_statespace.person.model`) is linear and
Gaussian once ``f_h``, ``xi_h`` and the noise levels are fixed. Its state is

``s_k = [x_k (n_x), alpha_k (p), m_k (p, only for variation "both")]``

with ``x = [u, u_dot, ...]`` the dynamic states of the person (and of any
effect with dynamics of its own, such as a floor mode: ``n_x`` of them) and
``alpha`` the force coefficients ``[a0, a1, b1, ..., an, bn]`` (g) in force in
the cycle that contains sample ``k``. Within a cycle only the first ``n_x``
rows move (the exact discretisation of Eq. 2 under the Fourier force, or its
linearisation about a path for a nonlinear effect)::

    x_k = Phi_{k-1} x_{k-1} + Gamma_{k-1} alpha + c_{k-1} + X_tr[k-1] beta + w_k
    y_k = h_x,k x_k + H_k alpha_k + X_obs[k] beta + v_k,   v_k ~ N(0, sigma^2)

(``c`` the known part of a linearised or input-driven effect; ``Phi`` and
``h_x`` are the same at every sample when the dynamics are linear).

and at a cycle boundary the coefficients are drawn again (the "variation
model"): ``alpha := tau + d`` ("independent"), ``alpha := alpha + e``
("random_walk") or ``m := m + e, alpha := m + d`` ("both"), ``d ~ N(0, D)``,
``e ~ N(0, E)``.

The record-level template ``tau`` (or the random walk's start), the initial
dynamic states ``x_0`` and the coefficients ``beta`` of known regressors (effects) have
no prior: they form the vector ``delta`` of length ``q``, which the filter
carries as extra columns (de Jong's augmented Kalman filter, *Ann. Statist.*
19 (1991) 1073-1083): the predicted state is ``a_k + A_k delta`` and the
innovation ``e_k - E_k delta``. At the end ``delta`` is estimated by
generalised least squares and the likelihood is concentrated over it (and over
the scale ``sigma^2``: every variance is given relative to ``sigma^2``).

The pass uses the structure: a step changes only the first ``n_x`` rows of the
state, so a covariance predict costs ``2 n_x m^2`` operations instead of ``2 m^3``.
"""

from __future__ import annotations

import math

import numba
import numpy as np

INDEPENDENT, RANDOM_WALK, BOTH, SMOOTH = 0, 1, 2, 3
"""Codes of the variation models in the compiled pass."""


@numba.njit(cache=True)
def state_size(code, nx, p, n_template):
    """Length of the filter's state for variation ``code``: ``[x (n_x), alpha (p)]``, plus the random walk's base
    ``m`` (p) for :data:`BOTH` or the coefficients' rates (``n_template``) for :data:`SMOOTH`."""
    if code == BOTH:
        return nx + 2 * p
    if code == SMOOTH:
        return nx + p + n_template
    return nx + p


# a cycle boundary's reset runs once a cycle: its arrays in any layout, ``step`` a run-time flag, so that numba
# compiles each reset once rather than once per caller's layouts and literal flags (4 times each: the first identify
# after installing took 28.2 s with them, 23.2 s without)
@numba.njit("void(int64, float64[:, :], int64, float64[:], float64[:], int64, int64, boolean)", cache=True,
            fastmath={"reassoc", "contract"})
def reset_covariance(code, P, p, D, E, o, n_template, step):
    """The covariance's part of a cycle boundary's new draw (in place); the force states start at row ``o``.

    Shared by :func:`_reset` (the augmented pass) and the sensitivity pass of
    :mod:`~smd_statespace.person.score`, which applies it to ``P`` and, being
    linear in ``(P, D, E)``, to every ``(dP_j, dD_j, dE_j)``.
    """
    m = P.shape[0]
    if code == INDEPENDENT or code == SMOOTH:  # alpha := tau + d (SMOOTH: only the timing states)
        for i in range(o + (n_template if code == SMOOTH else 0), o + p):
            for c in range(m):
                P[i, c] = 0.0
                P[c, i] = 0.0
            P[i, i] = D[i - o]
    elif code == RANDOM_WALK:  # alpha := alpha + e
        for i in range(o, o + p):
            P[i, i] += E[i - o]
    else:  # m := m + e, alpha := m + d
        if step:
            for i in range(o + p, o + 2 * p):
                P[i, i] += E[i - o - p]
        for i in range(o, o + p):
            j = i + p
            for c in range(m):
                P[i, c] = P[j, c]
            for c in range(m):
                P[c, i] = P[c, j]
            P[i, i] = P[j, j] + D[i - o]


@numba.njit("void(int64, float64[:], float64[:, :], float64[:, :], int64, float64[:], float64[:], int64, int64, "
            "boolean)", cache=True, fastmath={"reassoc", "contract"})
def _reset(code, a, A, P, p, D, E, n_free, n_template, step):
    """Draw the force coefficients again at a cycle boundary (in place); they start at row ``n_free``."""
    q = A.shape[1]
    o = n_free
    if code == INDEPENDENT:  # alpha := tau + d: the mean is the template's column of delta
        for i in range(o, o + p):
            a[i] = 0.0
            for c in range(q):
                A[i, c] = 0.0
            if i - o < n_template:
                A[i, i] = 1.0
    elif code == SMOOTH:  # the coefficients run on; only the timing states are drawn again
        for i in range(o + n_template, o + p):
            a[i] = 0.0
            for c in range(q):
                A[i, c] = 0.0
    elif code == BOTH:  # alpha := m + d
        for i in range(o, o + p):
            a[i] = a[i + p]
            for c in range(q):
                A[i, c] = A[i + p, c]
    reset_covariance(code, P, p, D, E, o, n_template, step)


@numba.njit(cache=True, fastmath={"reassoc", "contract"})
def step_rows(T, G, X, out, work):
    """Rows ``0..n_x-1`` of ``out`` become ``[T, G] X[:n_x + p]``: the first ``n_x`` rows of a step's transition
    times ``X``, with ``T`` (n_x, n_x) and ``G`` (n_x, p).

    Each column depends only on its own entries, so the columns are done one
    by one (``work``, length ``n_x``, holds one column's new rows) and
    ``out`` may be ``X`` itself: ``step_rows(T, G, P, P, work)`` is ``T P``
    in place, on ``P.T`` ``(T P) T'``, and on the mean and its
    ``delta``-columns their step.
    """
    nx, p = G.shape
    m = X.shape[1]
    if nx == 2:  # the person alone (the usual case), written out: twice as fast
        for c in range(m):
            v0 = T[0, 0] * X[0, c] + T[0, 1] * X[1, c]
            v1 = T[1, 0] * X[0, c] + T[1, 1] * X[1, c]
            for i in range(p):
                v0 += G[0, i] * X[2 + i, c]
                v1 += G[1, i] * X[2 + i, c]
            out[0, c] = v0
            out[1, c] = v1
        return
    for c in range(m):
        for r in range(nx):
            v = 0.0
            for j in range(nx):
                v += T[r, j] * X[j, c]
            for i in range(p):
                v += G[r, i] * X[nx + i, c]
            work[r] = v
        for r in range(nx):
            out[r, c] = work[r]


@numba.njit(cache=True, fastmath={"reassoc", "contract"})
def rotate_columns(X, n_template, r0, r1, f00, f01, f10, f11):
    """Columns ``r0 + i``, ``r1 + i`` of ``X`` move by the 2 x 2 ``f``, ``i < n_template`` (in place): with
    :func:`rotate_pairs` on the rows, ``S X S'`` for a stack of matrices whose rows are ``X``'s."""
    for c in range(X.shape[0]):
        for i in range(n_template):
            a, b = r0 + i, r1 + i
            x0 = X[c, a]
            x1 = X[c, b]
            X[c, a] = f00 * x0 + f01 * x1
            X[c, b] = f10 * x0 + f11 * x1


@numba.njit(cache=True, fastmath={"reassoc", "contract"})
def rotate_pairs(X, n_template, r0, r1, f00, f01, f10, f11, columns):
    """Rows (and, with ``columns``, then columns) ``r0 + i``, ``r1 + i`` of ``X`` move by the 2 x 2 ``f``,
    ``i < n_template`` (in place): the smooth variation's step of a deviation and its rate."""
    m = X.shape[1]
    for i in range(n_template):
        a, b = r0 + i, r1 + i
        for c in range(m):
            x0 = X[a, c]
            x1 = X[b, c]
            X[a, c] = f00 * x0 + f01 * x1
            X[b, c] = f10 * x0 + f11 * x1
        if columns:
            rotate_columns(X, 1, a, b, f00, f01, f10, f11)


@numba.njit(cache=True, fastmath={"reassoc", "contract"})
def _smooth_step(a, A, P, p, n_template, smooth_phi, smooth_q, D, nx):
    """Advance every coefficient's smooth deviation one sample (in place, variation "smooth").

    The pair ``(alpha_i - tau_i, alpha_dot_i)`` (rows ``n_x + i`` and
    ``n_x + p + i``) moves by ``smooth_phi``; ``tau_i`` (the column
    ``n_x + i`` of ``delta``) stays, so ``alpha_i`` gains ``(1 - phi_00) tau_i``
    and ``alpha_dot_i`` loses ``phi_10 tau_i``; the step adds the process
    covariance ``D_i smooth_q``.
    """
    f00, f01, f10, f11 = smooth_phi[0, 0], smooth_phi[0, 1], smooth_phi[1, 0], smooth_phi[1, 1]
    rotate_pairs(P, n_template, nx, nx + p, f00, f01, f10, f11, True)  # T P T'
    rotate_pairs(A, n_template, nx, nx + p, f00, f01, f10, f11, False)
    for i in range(n_template):
        r0 = nx + i
        r1 = nx + p + i
        x0 = a[r0]
        x1 = a[r1]
        a[r0] = f00 * x0 + f01 * x1
        a[r1] = f10 * x0 + f11 * x1
        A[r0, nx + i] += 1.0 - f00
        A[r1, nx + i] -= f10
        P[r0, r0] += D[i] * smooth_q[0, 0]
        P[r0, r1] += D[i] * smooth_q[0, 1]
        P[r1, r0] += D[i] * smooth_q[1, 0]
        P[r1, r1] += D[i] * smooth_q[1, 1]


@numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def augmented_pass(y, hx, H, Phi, Gam, Qx, offset, X_obs, X_tr, reset, code, D, E, drift, n_template,
                   smooth_phi, smooth_q, smooth_p0, observed):
    """Run the augmented Kalman filter over one record.

    Parameters
    ----------
    y : ndarray, shape (N,)
        Observations (m/s^2), less any known part of the observation.
    hx : ndarray, shape (K, n_x)
        Observation row of the dynamic states ``x = [u, u_dot, ...]``: at
        every sample (``K = N``) or the same for all (``K = 1``).
    H : ndarray, shape (N, p)
        Observation rows of the force coefficients (``g`` times the Fourier basis).
    Phi : ndarray, shape (K, n_x, n_x)
        Transition of ``x`` over the step from ``k`` (``K = N``), or over every step (``K = 1``).
    Gam : ndarray, shape (N, n_x, p)
        Effect of the coefficients on ``x`` over the step from ``k``.
    Qx : ndarray, shape (n_x, n_x)
        Process noise of ``x`` per step, relative to ``sigma^2``.
    offset : ndarray, shape (N, n_x)
        Known change of ``x`` over the step from ``k`` (a measured input, or
        the constant part of a linearised effect).
    X_obs : ndarray, shape (N, r)
        Known regressors of the observation (their coefficients are in ``delta``).
    X_tr : ndarray, shape (N, n_x, r)
        Known regressors of the ``x`` step from ``k``.
    reset : ndarray of bool, shape (N,)
        True where a new force cycle starts at sample ``k`` (``k >= 1``).
    code : int
        Variation model: :data:`INDEPENDENT`, :data:`RANDOM_WALK`, :data:`BOTH`
        or :data:`SMOOTH`.
    D, E : ndarray, shape (p,)
        Variances of the independent draws and of the random-walk steps,
        relative to ``sigma^2``; with :data:`SMOOTH`, ``D`` holds the
        stationary variances of the coefficients' smooth deviations (and of
        the timing states' draws).
    drift : ndarray, shape (p,)
        Variance of a per-sample random walk of the coefficients, relative to
        ``sigma^2`` (0: coefficients constant within a cycle).
    n_template : int
        The first ``n_template`` force states have an unknown record-level
        mean (a column of ``delta``); the others have mean zero.
    smooth_phi, smooth_q, smooth_p0 : ndarray, shape (2, 2)
        Variation :data:`SMOOTH` only: transition over one sample of a
        deviation and its rate (a Matern-3/2 process), its process covariance
        and its stationary covariance, for a unit stationary variance.
    observed : ndarray of bool, shape (N,)
        False where the sample is missing (a gap in a phone's clock): the filter predicts over it and
        makes no update; its innovation, regression and variance are returned as 0, 0 and 1, so that it
        adds nothing to ``S``, ``s``, ``ee`` or the sum of ``log f``.

    Returns
    -------
    e : ndarray, shape (N,)
        Innovations with ``delta = 0``.
    Ev : ndarray, shape (N, q)
        Their regression on ``delta``: the innovation is ``e - Ev @ delta``.
    f : ndarray, shape (N,)
        Innovation variances relative to ``sigma^2``.
    S : ndarray, shape (q, q)
        ``sum Ev' Ev / f``.
    s : ndarray, shape (q,)
        ``sum Ev' e / f``.
    ee : float
        ``sum e^2 / f``.
    """
    N, p = H.shape
    nx = Phi.shape[1]
    varying = Phi.shape[0] > 1
    r = X_obs.shape[1]
    m = state_size(code, nx, p, n_template)
    n_free = nx  # delta = [x0 (n_x), template (p), beta (r)]
    q = nx + n_template + r
    a = np.zeros(m)
    A = np.zeros((m, q))
    P = np.zeros((m, m))
    work = np.zeros(nx)
    T = Phi[0].copy()
    row = hx[0].copy()
    has_offset = np.any(offset != 0.0)
    for i in range(nx):
        A[i, i] = 1.0
    if code == INDEPENDENT:
        _reset(code, a, A, P, p, D, E, n_free, n_template, True)
    elif code == RANDOM_WALK:
        for i in range(n_template):
            A[nx + i, n_free + i] = 1.0
    elif code == SMOOTH:  # stationary start: deviation variance D, rate variance D lambda^2
        for i in range(n_template):
            A[nx + i, n_free + i] = 1.0
            P[nx + i, nx + i] = D[i] * smooth_p0[0, 0]
            P[nx + i, nx + p + i] = D[i] * smooth_p0[0, 1]
            P[nx + p + i, nx + i] = D[i] * smooth_p0[1, 0]
            P[nx + p + i, nx + p + i] = D[i] * smooth_p0[1, 1]
        _reset(code, a, A, P, p, D, E, n_free, n_template, True)
    else:
        for i in range(n_template):
            A[nx + p + i, n_free + i] = 1.0
        _reset(code, a, A, P, p, D, E, n_free, n_template, False)
    e_out = np.empty(N)
    Ev_out = np.empty((N, q))
    f_out = np.empty(N)
    h = np.zeros(m)
    Ph = np.zeros(m)
    Ev = np.zeros(q)
    n_obs = nx + p  # the observation sees x and alpha only (not the smooth rates nor the random walk's base)
    for k in range(N):
        if k > 0:
            # predict the dynamic rows: x = Phi x + Gam alpha + offset (+ X_tr beta)
            G = Gam[k - 1]
            if varying:
                T = Phi[k - 1]
            step_rows(T, G, P, P, work)  # T P
            step_rows(T, G, P.T, P.T, work)  # (T P) T'
            for i in range(nx):
                for j in range(nx):
                    P[i, j] += Qx[i, j]
            step_rows(T, G, a.reshape((m, 1)), a.reshape((m, 1)), work)  # the mean
            if has_offset:
                for i in range(nx):
                    a[i] += offset[k - 1, i]
            step_rows(T, G, A, A, work)  # and its delta-columns
            for j in range(r):  # known regressors: the state's dependence on beta
                for i in range(nx):
                    A[i, nx + n_template + j] += X_tr[k - 1, i, j]
            if code == SMOOTH:
                _smooth_step(a, A, P, p, n_template, smooth_phi, smooth_q, D, nx)
            for i in range(p):
                P[nx + i, nx + i] += drift[i]
                if code == BOTH:
                    P[nx + p + i, nx + p + i] += drift[i]
            if reset[k]:
                _reset(code, a, A, P, p, D, E, n_free, n_template, True)
        # update with y_k
        if varying:
            row = hx[k]
        if not observed[k]:  # a missing sample: predicted over, no update
            e_out[k] = 0.0
            f_out[k] = 1.0
            for c in range(q):
                Ev_out[k, c] = 0.0
            continue
        for i in range(nx):
            h[i] = row[i]
        for i in range(p):
            h[nx + i] = H[k, i]
        for c in range(m):
            v = 0.0
            for i in range(n_obs):
                v += P[c, i] * h[i]
            Ph[c] = v
        f = 1.0
        e = y[k]
        for i in range(n_obs):
            f += h[i] * Ph[i]
            e -= h[i] * a[i]
        for c in range(q):
            Ev[c] = 0.0
        for i in range(n_obs):
            hi = h[i]
            for c in range(q):
                Ev[c] += hi * A[i, c]
        for j in range(r):
            Ev[nx + n_template + j] += X_obs[k, j]
        inv_f = 1.0 / f
        e_out[k] = e
        f_out[k] = f
        for c in range(q):
            Ev_out[k, c] = Ev[c]
        for i in range(m):
            K = Ph[i] * inv_f
            a[i] += K * e
            for c in range(q):
                A[i, c] -= K * Ev[c]
            for c in range(i, m):  # P is symmetric: the upper triangle, mirrored
                v = P[i, c] - K * Ph[c]
                P[i, c] = v
                P[c, i] = v
    # the sums of the concentrated likelihood, after the pass (one product instead of q^2 per sample)
    weighted = Ev_out / f_out.reshape((N, 1))
    S = weighted.T @ Ev_out
    s = weighted.T @ e_out
    ee = np.sum(e_out * e_out / f_out)
    return e_out, Ev_out, f_out, S, s, ee


def concentrate(S, s, ee, f, n_obs, held=()):
    """Estimate ``delta`` and ``sigma^2`` by GLS and return the concentrated log-likelihoods.

    Parameters
    ----------
    S, s, ee, f : as returned by :func:`augmented_pass`.
    n_obs : int
        Number of observations ``N``.
    held : sequence of int
        Entries of ``delta`` held at 0, not estimated (their rows and columns
        of ``delta_cov_unscaled`` are 0).

    Returns
    -------
    dict
        ``delta`` (q,), ``delta_cov_unscaled`` (q, q) (multiply by ``sigma2``),
        ``sigma2`` (the maximum-likelihood scale, ``RSS / N``), ``rss``,
        ``loglike`` (the profile log-likelihood: ``delta`` and ``sigma^2`` at
        their maximum), ``loglike_diffuse`` (de Jong's diffuse likelihood with
        the scale at its own maximum) and ``rank`` (numerical rank of ``S``).
    """
    if not (np.all(np.isfinite(S)) and np.all(np.isfinite(s)) and np.isfinite(ee)):
        # the pass broke down (parameters far out, an unstable linearisation): no likelihood, nothing estimated
        q = s.size
        return {"delta": np.full(q, np.nan), "delta_cov_unscaled": np.full((q, q), np.nan), "sigma2": np.nan,
                "rss": np.nan, "loglike": -math.inf, "loglike_diffuse": -math.inf, "rank": 0}
    if len(held):
        free = np.setdiff1d(np.arange(s.size), held)
        out = concentrate(S[np.ix_(free, free)], s[free], ee, f, n_obs)
        delta, cov = np.zeros(s.size), np.zeros((s.size, s.size))
        delta[free], cov[np.ix_(free, free)] = out["delta"], out["delta_cov_unscaled"]
        return {**out, "delta": delta, "delta_cov_unscaled": cov}
    scale = np.sqrt(np.maximum(np.diag(S), 1e-300))
    Sn = S / np.outer(scale, scale)
    w, V = np.linalg.eigh(Sn)
    keep = w > w.max() * 1e-12
    inv = (V[:, keep] / w[keep]) @ V[:, keep].T
    S_inv = inv / np.outer(scale, scale)
    delta = S_inv @ s
    rss = max(float(ee - s @ delta), 1e-300)
    rank = int(keep.sum())
    if np.all(f > 0.0) and np.all(np.isfinite(f)):
        sum_log_f = float(np.sum(np.log(f)))
    else:  # the pass lost the covariance's positivity (parameters far out, an unstable linearisation): no likelihood
        sum_log_f = math.inf
    sigma2 = rss / n_obs
    loglike = -0.5 * (n_obs * (math.log(2.0 * math.pi * sigma2) + 1.0) + sum_log_f)
    dof = n_obs - rank
    sigma2_d = rss / dof
    log_det = float(np.sum(np.log(w[keep]))) + 2.0 * float(np.sum(np.log(scale)))
    loglike_diffuse = -0.5 * (dof * (math.log(2.0 * math.pi * sigma2_d) + 1.0) + sum_log_f + log_det)
    return {
        "delta": delta,
        "delta_cov_unscaled": S_inv,
        "sigma2": sigma2,
        "rss": rss,
        "loglike": loglike,
        "loglike_diffuse": loglike_diffuse,
        "rank": rank,
    }
