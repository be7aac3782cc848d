"""Exact gradient of the record-level log-likelihood: the Kalman filter's forward sensitivity recursion.

:func:`score` returns the gradient of the profile log-likelihood of a
:class:`~smd_statespace.person.model.RecordModel`, the per-sample scores and
the expected information (conditional on the linear unknowns, and with them
profiled out), from one compiled pass that carries, next to the filter's
state mean and covariance, their derivatives with respect to every parameter
(Harvey 1989, *Forecasting, structural time series models and the Kalman
filter*, Sect. 3.4.5).

*Envelope theorem.* The profile log-likelihood is ``L(theta) = max over
delta, sigma^2 of l(theta, delta, sigma^2)`` with ``l = sum_k l_k``,
``l_k = -0.5 [log(2 pi sigma^2 f_k) + v_k^2 / (sigma^2 f_k)]``,
``v_k = e_k - Ev_k delta`` the innovation and ``f_k`` its variance
relative to ``sigma^2``. At the maximiser ``(delta_hat, sigma2_hat)``
(:meth:`RecordModel.filter`) ``dL/dtheta = dl/dtheta`` at fixed
``delta = delta_hat`` and ``sigma^2 = sigma2_hat``; the ``dl_k/dtheta``
are the per-sample scores (their sum the gradient), the quantities
:func:`~smd_statespace.person.search._cluster_scores` builds by central
differences of :meth:`RecordModel.sample_loglike`.

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

(Koopman & Shephard 1992, *Biometrika* 79, 823-826, give the exact score
from one smoothing pass, whose cost does not grow with the number of
parameters; it needs the derivatives of the system arrays all the same
and the smoother of the augmented filter, and is not used here.)

*Derivatives of the system arrays* (:func:`system_derivatives`). The log
variance ratios enter as ``exp``: the derivative of ``D``, ``E``, the drift
and the process noise ``Qx`` is the value itself on the entries the
parameter sets. ``log_smooth_time`` enters through the
Matern-3/2 step (:func:`~smd_statespace.person.model.matern32_step`),
differentiated in closed form. ``f_h``, ``xi_h`` and the effects'
parameters change the dynamics (``Phi``, ``Gam``, ``offset``, ``X_tr``,
``hx``, ``y_known``, ``Qx``): with linear dynamics (the person, a floor
mode) through the discretisation (the Van Loan block exponential for
``Phi`` and ``W``, the harmonic gains' derivative; only the small
continuous ``A, b`` are differenced), else (a path-linearised effect)
by central differences of :meth:`RecordModel.system` with a relative
step of :data:`DYNAMICS_STEP`. The analytic arrays are 100-1000 times
closer to a Richardson extrapolation than the differenced ones, and
cheaper (3.0 against 4.9 ms below).

*Information.* :func:`score` gives Harvey's expected information at fixed
``delta`` and ``sigma^2`` (``expected_information``) and with them as nuisance
parameters (``profile_information``: the Schur complement, with
``d v / d delta = -Ev``, the augmented filter's regression). The first
is *not* usable for ``f_h`` and ``xi_h``: the template absorbs much of a
change of the dynamics, and it gives standard errors 0.1-0.2 times those
of the observed information (the Hessian of
:func:`~smd_statespace.person.search.information`). The second agrees with
the observed information: ratios of the ``f_h``, ``xi_h`` standard
errors 0.98, 0.94 on the fitted sample record (``data/sample.csv``,
"independent"), 0.84-1.06 on six simulated 12 s records, 0.75-1.16 with
variation "smooth".

*Cost* (``benchmarks/person_score.py``: 30 s at 100 Hz, variation
"independent" with a phase template and the offset, 9 parameters, one
thread, fastest of 7 runs on a shared two-core machine). ``model.loglike``
3.9 ms (``system`` 1.0, the compiled pass 2.2); :func:`score` 19 ms (5 likelihoods: ``filter`` 3.9, ``system`` 1.0,
:func:`system_derivatives` 3.0, :func:`sensitivity_pass` 10.5),
against 37 ms for the ``k + 1`` likelihoods of L-BFGS-B's forward
differences and 66 ms for ``2 k`` central ones: about half and a third.
The pass costs 1.4 ms for the filter itself, then about 0.8 ms per
variance parameter and 1.4 ms per dynamics parameter, against 2.2 +
1.7 ms per likelihood evaluation, so the saving grows slowly with the
parameters. Where it counts most (and where
:mod:`~smd_statespace.person.fit` uses it): the search, by Fisher scoring
with the exact gradient and ``profile_information`` (a handful of passes per
search where L-BFGS-B with differences needed hundreds of likelihoods); the
per-sample (per-cycle) scores of the robust covariance (exact, one pass;
73 ms by central differences before); the observed information (central
differences of the exact gradient, ``2 k`` passes; the numerical Hessian of
the likelihood took ``2 k^2`` likelihoods, 610 ms).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .kalman import (BOTH, INDEPENDENT, RANDOM_WALK, SMOOTH, reset_covariance, rotate_columns, rotate_pairs, state_size,
                     step_rows)
from .model import RecordModel

__all__ = ["DYNAMICS_STEP", "score", "system_derivatives", "sensitivity_pass"]

DYNAMICS_STEP = 1e-6
"""Relative step of the central differences of :meth:`RecordModel.system` in ``f_h``, ``xi_h`` and the effects'
parameters (times ``max(|value|, scale)``, ``scale`` from :attr:`RecordModel.scales`)."""


# ---------------------------------------------------------------------------------------------- compiled pass
@numba.njit(cache=True, fastmath={"contract"})
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


@numba.njit(cache=True, fastmath={"contract"})
def _corner(T, G, Y, r, c):
    """``(Y [T, G]')[r, c]``: row ``r`` of ``Y`` times row ``c`` of the step's transition."""
    nx, p = G.shape
    v = 0.0
    for j in range(nx):
        v += Y[r, j] * T[c, j]
    for i in range(p):
        v += Y[r, nx + i] * G[c, i]
    return v


@numba.njit(cache=True, fastmath={"contract"})
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


@numba.njit(cache=True, fastmath={"contract"})
def sensitivity_pass(y, hx, H, Phi, Gam, Qx, offset, X_obs, X_tr, reset, code, D, E, drift, n_template,
                     smooth_phi, smooth_q, smooth_p0, delta,
                     dyn, d_hx, d_Phi, d_Gam, d_offset, d_X_tr, d_y,
                     d_Qx, d_D, d_E, d_drift, d_sphi, d_sq, d_sp0):
    """The Kalman filter at known ``delta`` and its forward derivatives with respect to ``k`` parameters.

    Parameters
    ----------
    y, hx, H, Phi, Gam, Qx, offset, X_obs, X_tr, reset, code, D, E, drift, n_template, smooth_phi, smooth_q, smooth_p0
        As :func:`~smd_statespace.person.kalman.augmented_pass` (``y`` less
        the known part of the observation).
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


# ------------------------------------------------------------------------------------ system derivatives
DYNAMIC_ARRAYS = ("hx", "Phi", "Gam", "offset", "X_tr", "y_known", "Qx")
"""Arrays of :meth:`RecordModel.system` that change with the person's (and the effects') dynamics."""


def _matern32_derivatives(length_scale, dt):
    """Derivatives of :func:`~smd_statespace.person.model.matern32_step`'s ``(Phi, Q, P_inf)`` w.r.t. ``log ell``.

    ``lambda = sqrt(3) / ell``, so ``d lambda / d log ell = -lambda``;
    ``Phi = exp(-lambda dt) [[1 + lambda dt, dt], [-lambda^2 dt, 1 - lambda dt]]``,
    ``P_inf = diag(1, lambda^2)``, ``Q = P_inf - Phi P_inf Phi'``.
    """
    lam = np.sqrt(3.0) / float(length_scale)
    decay = np.exp(-lam * dt)
    phi = decay * np.array([[1.0 + lam * dt, dt], [-lam * lam * dt, 1.0 - lam * dt]])
    dphi_dlam = -dt * phi + decay * np.array([[dt, 0.0], [-2.0 * lam * dt, -dt]])
    p_inf = np.diag([1.0, lam * lam])
    dp_dlam = np.diag([0.0, 2.0 * lam])
    dq_dlam = dp_dlam - dphi_dlam @ p_inf @ phi.T - phi @ dp_dlam @ phi.T - phi @ p_inf @ dphi_dlam.T
    dq_dlam = 0.5 * (dq_dlam + dq_dlam.T)
    return -lam * dphi_dlam, -lam * dq_dlam, -lam * dp_dlam


def _linearise(model: RecordModel, params):
    """``model.dynamics.linearise`` at ``params``, as :meth:`RecordModel.system` calls it."""
    named = model.unpack(params)
    return model.dynamics.linearise(named["f_h"], named["xi_h"],
                                    {name: named[name] for name in model.effect_parameters}, model.nominal)


class _Discretisation:
    """The parts of :meth:`RecordModel.system` that linear dynamics' derivatives are built from, at one point.

    ``lin`` (the continuous ``A, b, c, h_x, d``), ``integral`` (``W``,
    shape (1, n_x, n_x)), the harmonic gains' matrices ``lhs = j nu I - A``
    (J, n_h, n_x, n_x), ``gains`` (J, n_h, n_x) and the inputs' rotation
    ``exp(j nu dt) I - Phi``.
    """

    def __init__(self, model: RecordModel, params):
        from .dynamics import exponentials, harmonic_gains

        self.lin = lin = _linearise(model, params)
        dt = model.dt
        self.phi, self.integral = exponentials(lin.A, dt)
        orders = np.arange(1, model.n_harmonics + 1)
        nu = model.timing_rates()[:, None] * orders  # (J, n_h)
        eye = np.eye(lin.A.shape[-1])
        self.gains = harmonic_gains(lin.A, self.phi, lin.b, nu, dt)  # (J, n_h, n_x)
        self.lhs = 1j * nu[..., None, None] * eye - lin.A[:, None]
        self.turn = np.exp(1j * nu * dt)[..., None, None] * eye - self.phi[:, None]


def _dynamics_derivative(model: RecordModel, params, j, h, base: _Discretisation, rate) -> dict:
    """Derivatives of the dynamics' arrays of :meth:`RecordModel.system` w.r.t. parameter ``j``, linear dynamics.

    The continuous ``A, b, c, h_x, d`` of the dynamics are differenced
    centrally (step ``h``: small arrays); the rest is differentiated
    through :meth:`RecordModel.system`'s own construction:

    - ``Phi = exp(A dt)``, ``W = int_0^dt exp(A s) ds``: the derivative of
      ``exp(M)``, ``M = [[A dt, I dt], [0, 0]]``, in the direction ``dM`` is
      the upper right block of ``exp([[M, dM], [0, M]])`` (Van Loan 1978,
      *IEEE Trans. Automat. Control* 23, 395-404);
    - the harmonic gains ``g = L^-1 r``, ``L = j nu I - A``,
      ``r = (exp(j nu dt) I - Phi) b``:
      ``dg = L^-1 (dA g - dPhi b + (exp(j nu dt) I - Phi) db)``;
    - the constant force's ``g0 = W b``, the phase template's columns, the
      regressors' steps and the offset ``W c`` by the product rule;
    - the process noise (``rate`` times two small matrix exponentials) by
      central differences.
    """
    from ..io import G
    from .dynamics import expm_stack
    from .model import _integrated_white_noise, _regressor_steps, _step_mean

    up, down = params.copy(), params.copy()
    up[j] += h
    down[j] -= h
    lin, plus, minus = base.lin, _linearise(model, up), _linearise(model, down)

    def diff(name):  # an effect's known term is None where it is zero (a gain of 0): its derivative need not be
        a, b = getattr(plus, name), getattr(minus, name)
        if a is None and b is None:
            return None
        a = np.zeros_like(b) if a is None else a
        return (a - (np.zeros_like(a) if b is None else b)) / (2.0 * h)

    A, b, dA, db = lin.A, lin.b, diff("A"), diff("b")
    n = A.shape[-1]
    dt = model.dt
    block = np.zeros((1, 4 * n, 4 * n))
    for at in (0, 2 * n):
        block[0, at:at + n, at:at + n] = A[0] * dt
        block[0, at:at + n, at + n:at + 2 * n] = np.eye(n) * dt
    block[0, :n, 2 * n:3 * n] = dA[0] * dt
    e = expm_stack(block)
    d_phi, d_integral = e[:, :n, 2 * n:3 * n], e[:, :n, 3 * n:]
    integral = base.integral
    d_g0 = np.einsum("kij,kj->ki", d_integral, b) + np.einsum("kij,kj->ki", integral, db)
    rhs = (dA[:, None] @ base.gains[..., None])[..., 0] - (d_phi[:, None] @ b[:, None, :, None])[..., 0] + (
        base.turn @ db[:, None, :, None])[..., 0]
    d_gains = np.linalg.solve(base.lhs, rhs[..., None])[..., 0]  # (J, n_h, n_x)
    per_sample = d_gains[model._phase[0]] * model._rotation[..., None]
    N = model.time.size
    gam = np.empty((N, n, model.n_coefficients))
    gam[:, :, 0] = d_g0
    gam[:, :, 1::2] = per_sample.real.transpose(0, 2, 1)
    gam[:, :, 2::2] = per_sample.imag.transpose(0, 2, 1)
    gam *= G
    if model._timing_columns is not None:
        gam = np.concatenate([gam, d_g0[:, :, None] * model._timing_columns[1][:, None, :]], axis=2)
    d_qx = np.zeros((n, n)) if rate == 0 else rate * (
        _integrated_white_noise(plus.A.mean(axis=0), plus.b.mean(axis=0), dt)
        - _integrated_white_noise(minus.A.mean(axis=0), minus.b.mean(axis=0), dt)) / (2.0 * h)
    dynamic = np.array([r.dynamic for r in model.regressors], dtype=bool)
    d_c, d_d = diff("c"), diff("d")
    d_offset = np.zeros((N, n))
    if lin.c is not None:
        d_offset += np.einsum("kij,kj->ki", d_integral, _step_mean(lin.c))
    if d_c is not None:
        d_offset += np.einsum("kij,kj->ki", integral, _step_mean(d_c))
    return {"hx": diff("hx"), "Phi": d_phi, "Gam": gam, "offset": d_offset,
            "X_tr": _regressor_steps(d_g0, model._X * dynamic),
            "y_known": np.zeros(N) if d_d is None else d_d, "Qx": d_qx}


def _variance_entries(model: RecordModel, j):
    """Which of ``D``, ``E``, the drift (per force state) and the process noise parameter ``j`` (a log variance)
    sets: ``(which, mask)``, from :attr:`RecordModel._variance_index` (the one map :meth:`RecordModel._variances`
    fills them by)."""
    index = model._variance_index
    if index["log_var_w"] == j:
        return "w", np.zeros(model.n_force_states, dtype=bool)
    for kind, which in (("log_var_d", "D"), ("log_var_e", "E"), ("log_var_s", "drift")):
        if index[kind] is not None and np.any(index[kind] == j):
            return which, index[kind] == j
    raise ValueError(f"parameter {model.param_names[j]!r} is no log variance of the model")


def system_derivatives(model: RecordModel, params, system=None, step=DYNAMICS_STEP, method="auto") -> dict:
    """Derivatives of the arrays of :meth:`RecordModel.system` with respect to every parameter.

    Parameters
    ----------
    model : RecordModel
    params : ndarray, shape (k,)
    system : dict, optional
        ``model.system(params)`` when already made.
    step : float
        Relative step of the central differences in the dynamics' parameters
        (times ``max(|value|, scale)``, ``scale`` from :attr:`RecordModel.scales`).
    method : {"auto", "analytic", "difference"}
        How the arrays that ``f_h``, ``xi_h`` and the effects' parameters
        change are differentiated: ``"difference"``, central differences of
        :meth:`RecordModel.system` (two calls per parameter; any dynamics);
        ``"analytic"``, through the discretisation (:func:`_dynamics_derivative`:
        only the small continuous ``A, b, c, h_x, d`` are differenced; linear
        dynamics only); ``"auto"`` (default), analytic when the dynamics are
        linear. Measured against Richardson-extrapolated differences: the
        analytic ``Gam`` is within 1e-9 (the person) to 1e-7 (a floor mode's
        damping) of the arrays' size, the differenced one within 1e-7 to 1e-4.

    Returns
    -------
    dict
        ``dyn`` (k,) int: each parameter's index in the stacks of the
        dynamics' derivatives (-1: not a dynamics parameter); those stacks
        ``d_hx``, ``d_Phi``, ``d_Gam``, ``d_offset``, ``d_X_tr`` and ``d_y``
        (the derivative of ``-y_known``); and for every parameter ``d_Qx``
        (k, n_x, n_x), ``d_D``, ``d_E``, ``d_drift`` (k, p), ``d_sphi``,
        ``d_sq``, ``d_sp0`` (k, 2, 2).
    """
    params = np.asarray(params, dtype=float)
    if method not in ("auto", "analytic", "difference"):
        raise ValueError(f"method {method!r} is not one of: auto, analytic, difference")
    if method == "analytic" and not model.dynamics.linear:
        raise ValueError("analytic derivatives of the system need linear dynamics (a path-linearised effect: "
                         "use method='difference')")
    analytic = method == "analytic" or (method == "auto" and model.dynamics.linear)
    sys = model.system(params) if system is None else system
    names = model.param_names
    k = len(names)
    dynamic = ["f_h", "xi_h"] + list(model.effect_parameters)
    dyn = np.full(k, -1, dtype=np.int64)
    stacks = {name: [] for name in DYNAMIC_ARRAYS}
    p = sys.D.size
    nx = model.n_dynamic
    out = {"d_Qx": np.zeros((k, nx, nx)), "d_D": np.zeros((k, p)), "d_E": np.zeros((k, p)),
           "d_drift": np.zeros((k, p)), "d_sphi": np.zeros((k, 2, 2)), "d_sq": np.zeros((k, 2, 2)),
           "d_sp0": np.zeros((k, 2, 2))}
    scales = model.scales
    values = {"D": sys.D, "E": sys.E, "drift": sys.drift}
    rate = float(np.exp(params[names.index("log_var_w")])) if "log_var_w" in names else 0.0
    base = _Discretisation(model, params) if analytic and any(name in dynamic for name in names) else None
    for j, name in enumerate(names):
        if name in dynamic:
            h = step * max(abs(params[j]), scales[j])
            if analytic:
                derivative = _dynamics_derivative(model, params, j, h, base, rate)
                for key in DYNAMIC_ARRAYS:
                    stacks[key].append(derivative[key])
            else:
                up, down = params.copy(), params.copy()
                up[j] += h
                down[j] -= h
                plus, minus = model.system(up), model.system(down)
                for key in DYNAMIC_ARRAYS:
                    stacks[key].append((getattr(plus, key) - getattr(minus, key)) / (2.0 * h))
            out["d_Qx"][j] = stacks["Qx"][-1]
            dyn[j] = len(stacks["hx"]) - 1
        elif name == "log_smooth_time":
            out["d_sphi"][j], out["d_sq"][j], out["d_sp0"][j] = _matern32_derivatives(np.exp(params[j]), model.dt)
        elif name.startswith("log_var_"):  # exp(log variance): the derivative is the value where it enters
            which, mask = _variance_entries(model, j)
            if which == "w":
                out["d_Qx"][j] = sys.Qx
            else:
                out[f"d_{which}"][j] = np.where(mask, values[which], 0.0)
        else:
            raise ValueError(f"no derivative of the system arrays with respect to {name!r}")
    n_dyn = len(stacks["hx"])
    K = sys.Phi.shape[0]
    N = model.time.size
    r = sys.X_tr.shape[2]

    def stack(key, shape):
        return np.ascontiguousarray(np.array(stacks[key])) if n_dyn else np.zeros((0,) + shape)

    out.update(dyn=dyn, d_hx=stack("hx", (K, nx)), d_Phi=stack("Phi", (K, nx, nx)),
               d_Gam=stack("Gam", (N, nx, p)), d_offset=stack("offset", (N, nx)),
               d_X_tr=stack("X_tr", (N, nx, r)), d_y=-stack("y_known", (N,)))
    return out


# ------------------------------------------------------------------------------------------------ score
def score(model: RecordModel, params, fitted=None, method="auto") -> dict:
    """Exact gradient of the profile log-likelihood, per-sample scores and the expected information.

    One compiled pass of the Kalman filter at the estimated ``delta`` and
    ``sigma^2`` with the forward derivatives of its mean and covariance
    (the module's docstring; Harvey 1989, Sect. 3.4.5). By the envelope
    theorem the derivatives at fixed ``delta``, ``sigma^2`` are those of the
    profile log-likelihood :meth:`RecordModel.loglike`.

    Parameters
    ----------
    model : RecordModel
    params : ndarray, shape (k,)
        Parameters in the order of :attr:`RecordModel.param_names`.
    fitted : dict, optional
        ``model.filter(params)`` when already made (its ``delta``, ``sigma2``, ``loglike``,
        ``innovation_regression``, ``delta_cov_unscaled``).
    method : {"auto", "analytic", "difference"}
        How the dynamics' arrays are differentiated (:func:`system_derivatives`).

    Returns
    -------
    dict
        ``loglike`` (float): the profile log-likelihood;
        ``sample_loglike`` (N,): the per-sample log-densities at fixed
        ``delta``, ``sigma^2`` (:meth:`RecordModel.sample_loglike`; their sum
        is ``loglike``);
        ``gradient`` (k,): ``d loglike / d params``;
        ``per_sample`` (N, k): the per-sample scores (sum over samples: the gradient);
        ``efficient_per_sample`` (N, k): the same with ``delta`` and ``sigma^2``
        profiled out, ``s_theta - I_td I_dd^-1 s_delta - I_ts I_ss^-1 s_sigma``
        with ``s_delta = v Ev / (sigma^2 f)``, the scores a sandwich of the
        profile likelihood's information needs (the raw ones carry what the
        template absorbs: summed per cycle they gave f_h variances 4-700 times
        too large);
        ``expected_information`` (k, k): Harvey's (1989, Sect. 3.4.5) expected information
        ``sum_k [0.5 df_i df_j / f^2 + dv_i dv_j / (sigma^2 f)]`` from the
        derivatives of the innovations ``v`` and of their variances
        ``sigma^2 f``. It is *conditional* on ``delta`` and ``sigma^2``
        (held at their estimates, not profiled out): it ignores the
        information the parameters share with the template, the initial
        state, the regressors and the scale, so it is not the information of
        the profile likelihood and *not usable as the observed information*:
        on fitted records its standard errors of ``f_h`` and ``xi_h`` are
        0.1-0.2 times those of the observed information (the numerical
        Hessian of :func:`~smd_statespace.person.search.information`);
        ``profile_information`` (k, k): the same expected information of
        ``(theta, delta, sigma^2)`` with ``delta`` and ``sigma^2`` as
        nuisance parameters, ``I_tt - I_td I_dd^-1 I_dt - I_ts I_ss^-1 I_st``
        (``d v / d delta = -Ev``, ``I_dd = S / sigma^2``, ``I_ss = N / (2 sigma^4)``):
        its ``f_h``, ``xi_h`` standard errors are within about 15-25 % of the
        observed information's (0.98 and 0.94 on the fitted sample record);
        ``innovations`` (N,), ``variances`` (N,) (``sigma^2 f``),
        ``d_innovations`` (N, k), ``d_log_variances`` (N, k) (derivatives of
        ``v`` and of ``log f``); ``delta``, ``sigma2``.
    """
    params = np.asarray(params, dtype=float)
    fitted = model.filter(params) if fitted is None else fitted
    sys = model.system(params)
    k = params.size
    N = model.time.size
    if not np.isfinite(fitted["loglike"]):
        nan = np.full(k, np.nan)
        return {"loglike": fitted["loglike"], "sample_loglike": np.full(N, np.nan), "gradient": nan,
                "per_sample": np.full((N, k), np.nan), "efficient_per_sample": np.full((N, k), np.nan),
                "expected_information": np.full((k, k), np.nan),
                "profile_information": np.full((k, k), np.nan),
                "innovations": np.full(N, np.nan), "variances": np.full(N, np.nan),
                "d_innovations": np.full((N, k), np.nan), "d_log_variances": np.full((N, k), np.nan),
                "delta": fitted["delta"], "sigma2": fitted["sigma2"]}
    der = system_derivatives(model, params, sys, method=method)
    delta, sigma2 = np.asarray(fitted["delta"], dtype=float), float(fitted["sigma2"])
    v, f, dv, df = sensitivity_pass(
        *sys.pass_arguments(model.y, model.n_coefficients), delta,
        der["dyn"], der["d_hx"], der["d_Phi"], der["d_Gam"], der["d_offset"], der["d_X_tr"], der["d_y"],
        der["d_Qx"], der["d_D"], der["d_E"], der["d_drift"], der["d_sphi"], der["d_sq"], der["d_sp0"])
    variance = sigma2 * f
    standard2 = v**2 / variance
    sample = -0.5 * (np.log(2.0 * math.pi * variance) + standard2)
    relative = df / f[:, None]  # d log f
    per_sample = -0.5 * (relative * (1.0 - standard2)[:, None]) - (v / variance)[:, None] * dv
    weighted = dv / variance[:, None]
    info = 0.5 * relative.T @ relative + weighted.T @ dv
    info = 0.5 * (info + info.T)
    # delta and sigma^2 as nuisance parameters: d v / d delta = -Ev, d log(sigma^2 f) / d sigma^2 = 1 / sigma^2
    cross = -weighted.T @ fitted["innovation_regression"]  # (k, q)
    total = relative.sum(axis=0)
    profile = info - cross @ (sigma2 * fitted["delta_cov_unscaled"]) @ cross.T - 0.5 * np.outer(total, total) / N
    # the per-sample scores with delta and sigma^2 profiled out (the efficient scores): what is left of each
    # parameter's score once the template, initial state and scale have taken their share (sandwich covariances)
    delta_scores = (v / variance)[:, None] * fitted["innovation_regression"]
    efficient = (per_sample - delta_scores @ (sigma2 * fitted["delta_cov_unscaled"]) @ cross.T
                 + 0.5 * np.outer(1.0 - standard2, total) / N)
    return {"loglike": float(fitted["loglike"]), "sample_loglike": sample, "gradient": per_sample.sum(axis=0),
            "per_sample": per_sample, "efficient_per_sample": efficient, "expected_information": info,
            "profile_information": 0.5 * (profile + profile.T),
            "innovations": v, "variances": variance, "d_innovations": dv, "d_log_variances": relative,
            "delta": delta, "sigma2": sigma2}
