"""The compiled forward sensitivity pass: the Kalman filter at known ``delta`` and its derivatives.

:func:`sensitivity_pass` carries, next to the filter's state mean and
covariance, their derivatives with respect to every parameter (Harvey 1989,
*Forecasting, structural time series models and the Kalman filter*, Sect.
3.4.5); :func:`~smd_statespace.person.score.score` turns them into the
gradient, the per-sample scores and the information of the record-level
log-likelihood.

*Fixed ``delta``.* With ``delta`` known the augmented (de Jong) filter of
:func:`~smd_statespace.person.kalman.augmented_pass` is an ordinary
Kalman filter whose state mean is ``a_k + A_k delta``: the initial
dynamic states, the template (entering at the resets, the smooth step and
the start) and the regressors' coefficients (``X_tr beta`` in the step,
``X_obs beta`` in the observation) are known inputs. The pass here runs
that filter (mean ``x``, covariance ``P``: no ``delta`` columns) and for
each parameter ``j`` the derivatives ``dx_j``, ``dP_j`` of every step:

- predict ``x <- T x + c``, ``P <- T P T' + Q`` with ``T`` the identity
  but in its first ``n_x`` rows ``[Phi, Gam]``:
  ``dP <- T dP T' + dT P T' + T P dT' + dQ`` (``dT`` has the same rows
  only), ``dx <- T dx + dT x + dc``;
- the smooth variation's step (pairs of a deviation and its rate) the
  same way, with ``dD_i Q_s + D_i dQ_s`` and the template's input
  ``tau_i [1 - phi_00, -phi_10]``;
- the drift and the resets of each variation model are linear in
  ``(x, P, D, E)``: the same operations on ``(dx, dP, dD, dE)``, with the
  template (a known input) contributing nothing;
- update: ``s = P h``, ``f = 1 + h's``, ``v = y - y_known - h'x -
  X_obs beta``, ``ds = dP h + P dh``, ``df = h' dP h + 2 dh' s``,
  ``dv = -dy_known - dh' x - h' dx``,
  ``dx <- dx + (ds / f - s df / f^2) v + s dv / f``,
  ``dP <- dP - g s' - s g'`` with ``g = ds / f - s df / (2 f^2)``.

The score of a sample is then ``dl_k = -0.5 [df_k / f_k (1 - v_k^2 /
(sigma^2 f_k)) + 2 v_k dv_k / (sigma^2 f_k)]``.

The pass is one loop over the samples, written out in one function: split
into compiled steps the same arithmetic ran 20-40 % slower (measured
2026-11-27, the two versions side by side in one process on a 30 s record
with nine parameters: 11.5 -> 16.3 ms as functions of their own, 11.9 ->
15.5 ms inlined by numba's ``inline="always"``), and this pass is most of
the record-level search's time.
"""

from __future__ import annotations

import numba
import numpy as np

from .kalman import (BOTH, INDEPENDENT, RANDOM_WALK, SMOOTH, reset_covariance, rotate_columns, rotate_pairs, state_size,
                     step_rows)

__all__ = ["sensitivity_pass"]

FASTMATH = {"contract"}
"""Floating-point licence of the pass: ``a * b + c`` may be fused (no reordering of sums)."""


@numba.njit("void(int64, float64[:], float64[:, :], float64[:], float64[:], int64, int64, int64, float64[:], boolean)",
            cache=True, fastmath=FASTMATH)  # once a cycle: compiled once for every layout (kalman.reset_covariance)
def _reset(code, x, P, D, E, p, o, n_template, tau, step):
    """:func:`kalman._reset` on a state mean ``x`` at known ``delta`` (``tau``: the template, or 0 for a derivative).

    Every operation is linear in ``(x, P, D, E)`` and the template: applied
    to ``(dx_j, dP_j, dD_j, dE_j)`` with ``tau = 0`` it is the reset's
    derivative. The covariance's part is the augmented pass's own
    (:func:`kalman.reset_covariance`).
    """
    if code == INDEPENDENT:
        for i in range(o, o + p):
            x[i] = tau[i - o] if i - o < n_template else 0.0
    elif code == SMOOTH:
        for i in range(o + n_template, o + p):
            x[i] = 0.0
    elif code == BOTH:
        for i in range(o, o + p):
            x[i] = x[i + p]
    reset_covariance(code, P, p, D, E, o, n_template, step)


@numba.njit(cache=True, fastmath=FASTMATH)
def _corner(T, G, Y, r, c):
    """``(Y [T, G]')[r, c]``: row ``r`` of ``Y`` times row ``c`` of the step's transition."""
    nx, p = G.shape
    v = 0.0
    for j in range(nx):
        v += Y[r, j] * T[c, j]
    for i in range(p):
        v += Y[r, nx + i] * G[c, i]
    return v


@numba.njit(cache=True, fastmath=FASTMATH)
def _write_rows(T, G, Y, U, X, corner):
    """``X`` becomes the symmetric matrix whose first ``n_x`` rows are ``Y T'`` (+ the transpose of ``U T'`` in
    the ``n_x x n_x`` corner when ``U`` is given, ``has U``); columns ``0..n_x-1`` mirror the rows.

    With ``Y = T X`` (rows) this is ``T X T'`` for a symmetric ``X`` whose
    rows and columns beyond ``n_x`` the step leaves alone; with ``Y = T dP +
    dT P`` and ``U = dT P`` it is ``T dP T' + dT P T' + T P dT'``.
    """
    nx = G.shape[0]
    m = X.shape[0]
    for r in range(nx):
        for c in range(nx):
            v = _corner(T, G, Y, r, c)
            if corner:
                v += _corner(T, G, U, c, r)
            X[r, c] = v
    for r in range(nx):
        for c in range(nx, m):
            X[r, c] = Y[r, c]
            X[c, r] = Y[r, c]


@numba.njit(cache=True, nogil=True, fastmath=FASTMATH)
def sensitivity_pass(y, hx, H, Phi, Gam, Qx, offset, X_obs, X_tr, reset, code, D, E, drift, n_template,
                     smooth_phi, smooth_q, smooth_p0, observed, delta,
                     dyn, d_hx, d_Phi, d_Gam, d_offset, d_X_tr, d_y,
                     d_Qx, d_D, d_E, d_drift, d_sphi, d_sq, d_sp0):
    """The Kalman filter at known ``delta`` and its forward derivatives with respect to ``k`` parameters.

    Parameters
    ----------
    y, hx, H, Phi, Gam, Qx, offset, X_obs, X_tr, reset, code, D, E, drift, n_template, smooth_phi, smooth_q, \
smooth_p0, observed
        As :func:`~smd_statespace.person.kalman.augmented_pass` (``y`` less
        the known part of the observation; a missing sample's innovation and its derivatives are 0, its
        variance 1 and its derivatives 0).
    delta : ndarray, shape (q,)
        The linear unknowns ``[x_0 (n_x), template (n_template), beta (r)]``, held fixed.
    dyn : ndarray of int, shape (k,)
        For each parameter, its index in the ``d_hx .. d_y`` stacks (a
        parameter of the dynamics), or -1 (those arrays do not depend on it).
    d_hx, d_Phi, d_Gam, d_offset, d_X_tr : ndarray
        Derivatives of ``hx``, ``Phi``, ``Gam``, ``offset``, ``X_tr`` with
        respect to the dynamic parameters, stacked on a first axis.
    d_y : ndarray, shape (n_dyn, N)
        Derivatives of ``y`` (minus those of the known part of the observation).
    d_Qx, d_D, d_E, d_drift, d_sphi, d_sq, d_sp0 : ndarray
        Derivatives of ``Qx``, ``D``, ``E``, ``drift``, ``smooth_phi``,
        ``smooth_q``, ``smooth_p0`` with respect to every parameter (first axis ``k``).

    Returns
    -------
    v : ndarray, shape (N,)
        Innovations ``y_k - E[y_k | y_1..y_{k-1}, delta]`` (m/s^2).
    f : ndarray, shape (N,)
        Their variances relative to ``sigma^2``.
    dv, df : ndarray, shape (N, k)
        Their derivatives with respect to the parameters.
    """
    N, p = H.shape
    nx = Phi.shape[1]
    k = dyn.size
    varying = Phi.shape[0] > 1
    r = X_obs.shape[1]
    m = state_size(code, nx, p, n_template)
    tau = delta[nx:nx + n_template].copy()
    zero = np.zeros(n_template)
    beta = delta[nx + n_template:].copy()
    has_smooth_d = np.zeros(k, dtype=np.bool_)
    for j in range(k):
        for a in range(2):
            for b in range(2):
                if d_sphi[j, a, b] != 0.0 or d_sq[j, a, b] != 0.0:
                    has_smooth_d[j] = True
    x = np.zeros(m)
    P = np.zeros((m, m))
    dx = np.zeros((k, m))
    dP = np.zeros((m, k, m))  # dP[:, j, :]: the derivative of P w.r.t. parameter j (rows of all j together)
    km = k * m
    dPf = dP.reshape((m, km))
    dPc = dP.reshape((km, m))
    for i in range(nx):
        x[i] = delta[i]
    # the start, as augmented_pass's
    if code == INDEPENDENT:
        _reset(code, x, P, D, E, p, nx, n_template, tau, True)
        for j in range(k):
            _reset(code, dx[j], dP[:, j, :], d_D[j], d_E[j], p, nx, n_template, zero, True)
    elif code == RANDOM_WALK:
        for i in range(n_template):
            x[nx + i] = tau[i]
    elif code == SMOOTH:
        for i in range(n_template):
            x[nx + i] = tau[i]
            a, b = nx + i, nx + p + i
            P[a, a] = D[i] * smooth_p0[0, 0]
            P[a, b] = D[i] * smooth_p0[0, 1]
            P[b, a] = D[i] * smooth_p0[1, 0]
            P[b, b] = D[i] * smooth_p0[1, 1]
            for j in range(k):
                dP[a, j, a] = d_D[j, i] * smooth_p0[0, 0] + D[i] * d_sp0[j, 0, 0]
                dP[a, j, b] = d_D[j, i] * smooth_p0[0, 1] + D[i] * d_sp0[j, 0, 1]
                dP[b, j, a] = d_D[j, i] * smooth_p0[1, 0] + D[i] * d_sp0[j, 1, 0]
                dP[b, j, b] = d_D[j, i] * smooth_p0[1, 1] + D[i] * d_sp0[j, 1, 1]
        _reset(code, x, P, D, E, p, nx, n_template, tau, True)
        for j in range(k):
            _reset(code, dx[j], dP[:, j, :], d_D[j], d_E[j], p, nx, n_template, zero, True)
    else:
        for i in range(n_template):
            x[nx + p + i] = tau[i]
        _reset(code, x, P, D, E, p, nx, n_template, tau, False)
        for j in range(k):
            _reset(code, dx[j], dP[:, j, :], d_D[j], d_E[j], p, nx, n_template, zero, False)
    v_out = np.empty(N)
    f_out = np.empty(N)
    dv_out = np.empty((N, k))
    df_out = np.empty((N, k))
    Y = np.zeros((nx, k, m))
    Yf = Y.reshape((nx, km))
    U = np.zeros((nx, m))
    Z = np.zeros((nx, nx))
    Yb = np.zeros((nx, m))
    column = np.zeros(nx)  # step_rows' scratch column
    xn = np.zeros(nx)
    h = np.zeros(m)
    s = np.zeros(m)
    tf = np.zeros(km)
    tk = tf.reshape((k, m))
    gk = np.zeros((k, m))
    ds = np.zeros(m)
    dh = np.zeros(nx)
    Vs = np.zeros((m, m))
    T = Phi[0]
    row = hx[0]
    for kk in range(N):
        if kk > 0:
            G = Gam[kk - 1]
            if varying:
                T = Phi[kk - 1]
            # ---- predict the dynamic rows; derivatives first (they need the old x, P)
            # rows 0..n_x-1 of T dP for every parameter at once: Y = [Phi, Gam] dP[:n_x + p]
            for a in range(nx):
                for c in range(km):
                    Yf[a, c] = 0.0
                for i in range(nx + p):
                    coef = T[a, i] if i < nx else G[a, i - nx]
                    for c in range(km):
                        Yf[a, c] += coef * dPf[i, c]
            for j in range(k):
                d = dyn[j]
                if d >= 0:  # the transition moves too: + dT P (rows) and its transpose
                    dT = d_Phi[d, kk - 1] if varying else d_Phi[d, 0]
                    dG = d_Gam[d, kk - 1]
                    step_rows(dT, dG, P, U, column)
                    for a in range(nx):
                        for c in range(m):
                            Y[a, j, c] += U[a, c]
                    # the mean: T dx + dT x + d offset + d X_tr beta
                    for a in range(nx):
                        v = d_offset[d, kk - 1, a]
                        for c in range(nx):
                            v += T[a, c] * dx[j, c] + dT[a, c] * x[c]
                        for i in range(p):
                            v += G[a, i] * dx[j, nx + i] + dG[a, i] * x[nx + i]
                        for i in range(r):
                            v += d_X_tr[d, kk - 1, a, i] * beta[i]
                        xn[a] = v
                else:
                    for a in range(nx):
                        v = 0.0
                        for c in range(nx):
                            v += T[a, c] * dx[j, c]
                        for i in range(p):
                            v += G[a, i] * dx[j, nx + i]
                        xn[a] = v
                # the n_x x n_x corner: (Y T')[a, b] (+ (U T')[b, a]) + dQx
                for a in range(nx):
                    for b in range(nx):
                        v = d_Qx[j, a, b]
                        for c in range(nx):
                            v += Y[a, j, c] * T[b, c]
                        for i in range(p):
                            v += Y[a, j, nx + i] * G[b, i]
                        if d >= 0:
                            for c in range(nx):
                                v += U[b, c] * T[a, c]
                            for i in range(p):
                                v += U[b, nx + i] * G[a, i]
                        Z[a, b] = v
                for a in range(nx):
                    dx[j, a] = xn[a]
                    for b in range(nx):
                        dP[a, j, b] = Z[a, b]
                    for c in range(nx, m):
                        dP[a, j, c] = Y[a, j, c]
                        dP[c, j, a] = Y[a, j, c]
            step_rows(T, G, P, Yb, column)
            _write_rows(T, G, Yb, U, P, False)
            for a in range(nx):
                for c in range(nx):
                    P[a, c] += Qx[a, c]
            for a in range(nx):
                v = offset[kk - 1, a]
                for c in range(nx):
                    v += T[a, c] * x[c]
                for i in range(p):
                    v += G[a, i] * x[nx + i]
                for i in range(r):
                    v += X_tr[kk - 1, a, i] * beta[i]
                xn[a] = v
            for a in range(nx):
                x[a] = xn[a]
            if code == SMOOTH:  # the coefficients' smooth deviations: pairs (nx + i, nx + p + i)
                f00, f01, f10, f11 = smooth_phi[0, 0], smooth_phi[0, 1], smooth_phi[1, 0], smooth_phi[1, 1]
                # S dP_j S' for every parameter at once: the pairs' rows of dP (contiguous over all j), then
                # their columns (the rows of dP seen as (m k, m))
                rotate_pairs(dPf, n_template, nx, nx + p, f00, f01, f10, f11, False)
                rotate_columns(dPc, n_template, nx, nx + p, f00, f01, f10, f11)
                for j in range(k):
                    e00, e01, e10, e11 = d_sphi[j, 0, 0], d_sphi[j, 0, 1], d_sphi[j, 1, 0], d_sphi[j, 1, 1]
                    if has_smooth_d[j]:  # dS P S' + S P dS' (dS: the pairs' rows only), dS x, the template's input
                        Vs[:, :] = 0.0
                        for i in range(n_template):
                            a, b = nx + i, nx + p + i
                            for c in range(m):
                                Vs[a, c] = e00 * P[a, c] + e01 * P[b, c]
                                Vs[b, c] = e10 * P[a, c] + e11 * P[b, c]
                        rotate_pairs(Vs.T, n_template, nx, nx + p, f00, f01, f10, f11, False)  # (dS P) S'
                    rotate_pairs(dx[j].reshape((m, 1)), n_template, nx, nx + p, f00, f01, f10, f11, False)
                    if has_smooth_d[j]:
                        for a in range(m):
                            for c in range(m):
                                dP[a, j, c] += Vs[a, c] + Vs[c, a]
                        for i in range(n_template):
                            a, b = nx + i, nx + p + i
                            x0, x1 = x[a], x[b]
                            dx[j, a] += e00 * x0 + e01 * x1 - e00 * tau[i]
                            dx[j, b] += e10 * x0 + e11 * x1 - e10 * tau[i]
                    for i in range(n_template):
                        a, b = nx + i, nx + p + i
                        dP[a, j, a] += d_D[j, i] * smooth_q[0, 0] + D[i] * d_sq[j, 0, 0]
                        dP[a, j, b] += d_D[j, i] * smooth_q[0, 1] + D[i] * d_sq[j, 0, 1]
                        dP[b, j, a] += d_D[j, i] * smooth_q[1, 0] + D[i] * d_sq[j, 1, 0]
                        dP[b, j, b] += d_D[j, i] * smooth_q[1, 1] + D[i] * d_sq[j, 1, 1]
                rotate_pairs(P, n_template, nx, nx + p, f00, f01, f10, f11, True)
                rotate_pairs(x.reshape((m, 1)), n_template, nx, nx + p, f00, f01, f10, f11, False)
                for i in range(n_template):
                    a, b = nx + i, nx + p + i
                    x[a] += (1.0 - f00) * tau[i]
                    x[b] -= f10 * tau[i]
                    P[a, a] += D[i] * smooth_q[0, 0]
                    P[a, b] += D[i] * smooth_q[0, 1]
                    P[b, a] += D[i] * smooth_q[1, 0]
                    P[b, b] += D[i] * smooth_q[1, 1]
            for i in range(p):
                P[nx + i, nx + i] += drift[i]
                for j in range(k):
                    dP[nx + i, j, nx + i] += d_drift[j, i]
                if code == BOTH:
                    P[nx + p + i, nx + p + i] += drift[i]
                    for j in range(k):
                        dP[nx + p + i, j, nx + p + i] += d_drift[j, i]
            if reset[kk]:
                _reset(code, x, P, D, E, p, nx, n_template, tau, True)
                for j in range(k):
                    _reset(code, dx[j], dP[:, j, :], d_D[j], d_E[j], p, nx, n_template, zero, True)
        # ---- update with y_k
        if varying:
            row = hx[kk]
        if not observed[kk]:  # a missing sample: predicted over, no update
            v_out[kk] = 0.0
            f_out[kk] = 1.0
            for j in range(k):
                dv_out[kk, j] = 0.0
                df_out[kk, j] = 0.0
            continue
        for i in range(nx):
            h[i] = row[i]
        for i in range(p):
            h[nx + i] = H[kk, i]
        f = 1.0
        v = y[kk]
        for a in range(m):
            w = 0.0
            for c in range(m):
                w += P[a, c] * h[c]
            s[a] = w
        for a in range(m):
            f += h[a] * s[a]
            v -= h[a] * x[a]
        for i in range(r):
            v -= X_obs[kk, i] * beta[i]
        inv_f = 1.0 / f
        v_out[kk] = v
        f_out[kk] = f
        # dP h for every parameter at once: dP is symmetric, so its columns: sum_c h_c dP[c, j, :]
        for i in range(km):
            tf[i] = 0.0
        for c in range(m):
            hc = h[c]
            if hc != 0.0:
                for i in range(km):
                    tf[i] += hc * dPf[c, i]
        for j in range(k):
            d = dyn[j]
            dv = 0.0
            df = 0.0
            for a in range(m):
                dv -= h[a] * dx[j, a]
                df += h[a] * tk[j, a]
            if d >= 0:
                dv += d_y[d, kk]
                drow = d_hx[d, kk] if varying else d_hx[d, 0]
                for i in range(nx):
                    dh[i] = drow[i]
                    dv -= dh[i] * x[i]
                    df += 2.0 * dh[i] * s[i]
                for a in range(m):
                    w = tk[j, a]
                    for i in range(nx):
                        w += P[a, i] * dh[i]
                    ds[a] = w
            else:
                for a in range(m):
                    ds[a] = tk[j, a]
            dv_out[kk, j] = dv
            df_out[kk, j] = df
            # dx += dK v + K dv, dK = ds / f - s df / f^2; dP -= g s' + s g', g = ds / f - s df / (2 f^2)
            c1 = df * inv_f * inv_f
            for a in range(m):
                dx[j, a] += (ds[a] * inv_f - s[a] * c1) * v + s[a] * inv_f * dv
                gk[j, a] = ds[a] * inv_f - 0.5 * s[a] * c1
        for a in range(m):
            sa = s[a]
            for j in range(k):
                ga = gk[j, a]
                for c in range(m):
                    dP[a, j, c] -= ga * s[c] + sa * gk[j, c]
        for a in range(m):
            K = s[a] * inv_f
            x[a] += K * v
            for c in range(m):
                P[a, c] -= K * s[c]
    return v_out, f_out, dv_out, df_out
