"""Exact discretisation of the person's dynamics over one sample: ``Phi``, ``W`` and the force harmonics' gains.

For continuous dynamics ``x' = A x + b F(t)`` held over a step of ``dt``
seconds (:mod:`smd_statespace.person.dynamics` gives ``A`` and ``b``):

- ``Phi = exp(A dt)`` carries the state, ``W = integral_0^dt exp(A s) ds``
  a constant force (:func:`exponentials`);
- ``(j nu I - A)^-1 (exp(j nu dt) I - Phi) b`` a force harmonic of rate ``nu``
  (:func:`harmonic_gains`).

Both are needed once per sample where an effect is linearised along a path,
thousands of times per fit: for the person alone (2 x 2 ``A``) they are
compiled loops (numba, the GIL released), about 4 times faster than the same
series in numpy. Larger ``A`` (an effect with dynamics of its own) take the
vectorised numpy path.
"""

from __future__ import annotations

import cmath

import numba
import numpy as np

__all__ = ["exponentials", "expm_stack", "harmonic_gains"]

TAYLOR_ORDER = 14
"""Terms of the Taylor series of ``exp`` after scaling to an infinity norm of 1/2 (truncation below 1e-16)."""


def exponentials(A, dt):
    """``Phi = exp(A dt)`` and ``W = integral_0^dt exp(A s) ds`` for one or many ``A`` (shape (K, n, n)).

    Both from one matrix exponential of ``[[A, I], [0, 0]] dt`` (Van Loan),
    which stays right when ``A`` is singular.
    """
    A = np.asarray(A, dtype=float)
    K, n, _ = A.shape
    if n == 2:  # the person alone: the same series on 2 x 2 matrices, compiled
        M = np.ascontiguousarray(A * dt)
        squarings = _halvings(float(np.max(np.abs(M).sum(axis=-1))) + dt if M.size else 0.0)  # [[A dt, I dt], 0]
        return _series_2x2(M, float(dt), squarings, TAYLOR_ORDER)
    block = np.zeros((K, 2 * n, 2 * n))
    block[:, :n, :n] = A * dt
    block[:, :n, n:] = np.eye(n) * dt
    e = expm_stack(block)
    return e[:, :n, :n], e[:, :n, n:]


def _halvings(norm: float) -> int:
    """How many times a matrix of infinity norm ``norm`` is halved before its Taylor series is summed (to 1/2 or
    less): the scaling of :func:`expm_stack` and of the 2 x 2 path alike, so that both give the same numbers."""
    return max(0, int(np.ceil(np.log2(norm / 0.5)))) if norm > 0.5 else 0


@numba.njit(cache=True, nogil=True)
def _series_2x2(M, dt, squarings, order):
    """:func:`exponentials` for 2 x 2 ``A`` (``M = A dt``, shape (K, 2, 2)): the Taylor series of
    :func:`expm_stack` (the same scaling by halving and the same order) summed by Horner's rule, with
    ``W = dt phi_1(A dt)``, ``phi_1(X) = sum X^k / (k + 1)!``, carried through the squarings by
    ``W(2h) = (I + Phi(h)) W(h)``. Singular ``A`` needs no care: no inverse is taken."""
    K = M.shape[0]
    phi = np.empty((K, 2, 2))
    integral = np.empty((K, 2, 2))
    scale = 2.0**squarings
    h = dt / scale
    for k in range(K):
        x00, x01, x10, x11 = M[k, 0, 0] / scale, M[k, 0, 1] / scale, M[k, 1, 0] / scale, M[k, 1, 1] / scale
        e00, e01, e10, e11 = 1.0, 0.0, 0.0, 1.0  # exp: I + X/j (...)
        p00, p01, p10, p11 = 1.0, 0.0, 0.0, 1.0  # phi_1: I + X/(j + 1) (...)
        for j in range(order, 0, -1):
            r = 1.0 / j
            e00, e01, e10, e11 = (1.0 + (x00 * e00 + x01 * e10) * r, (x00 * e01 + x01 * e11) * r,
                                  (x10 * e00 + x11 * e10) * r, 1.0 + (x10 * e01 + x11 * e11) * r)
            r = 1.0 / (j + 1)
            p00, p01, p10, p11 = (1.0 + (x00 * p00 + x01 * p10) * r, (x00 * p01 + x01 * p11) * r,
                                  (x10 * p00 + x11 * p10) * r, 1.0 + (x10 * p01 + x11 * p11) * r)
        w00, w01, w10, w11 = p00 * h, p01 * h, p10 * h, p11 * h
        for _ in range(squarings):
            a00, a11 = 1.0 + e00, 1.0 + e11
            w00, w01, w10, w11 = (a00 * w00 + e01 * w10, a00 * w01 + e01 * w11,
                                  e10 * w00 + a11 * w10, e10 * w01 + a11 * w11)
            e00, e01, e10, e11 = (e00 * e00 + e01 * e10, e00 * e01 + e01 * e11,
                                  e10 * e00 + e11 * e10, e10 * e01 + e11 * e11)
        phi[k, 0, 0], phi[k, 0, 1], phi[k, 1, 0], phi[k, 1, 1] = e00, e01, e10, e11
        integral[k, 0, 0], integral[k, 0, 1], integral[k, 1, 0], integral[k, 1, 1] = w00, w01, w10, w11
    return phi, integral


def expm_stack(M, order: int = TAYLOR_ORDER):
    """``exp(M)`` of a stack of small matrices (shape (K, n, n)), vectorised over the stack.

    Scaling and squaring with a Taylor polynomial: ``M`` is halved ``s`` times
    until every matrix has an infinity norm of at most 1/2, the series of
    ``exp`` is summed to ``order`` terms (truncation below 1e-16 relative)
    and the result squared ``s`` times. scipy's ``expm`` loops over a stack in
    Python (measured: 80 ms for 3000 matrices of 4 x 4, against about 2 ms here).
    """
    squarings = _halvings(float(np.max(np.abs(M).sum(axis=-1))) if M.size else 0.0)
    X = M / 2.0**squarings
    eye = np.eye(M.shape[-1])
    result = eye + X
    term = X
    for k in range(2, order + 1):
        term = term @ X / k
        result = result + term
    for _ in range(squarings):
        result = result @ result
    return result


def harmonic_gains(A, Phi, b, nu, dt):
    """Change of ``x`` over a step under the input ``exp(j nu s) b``: ``(j nu I - A)^-1 (exp(j nu dt) I - Phi) b``.

    ``A``, ``Phi``: shape (K, n, n) or (1, n, n) (the same at every row of ``nu``); ``b``: (K, n) or (1, n);
    ``nu``: (K, h) rates (rad/s). Returns shape (K, h, n), complex.
    """
    n = A.shape[-1]
    if n == 2:  # the person alone: the 2 x 2 inverse written out, compiled
        return _gains_2x2(np.ascontiguousarray(A, dtype=float), np.ascontiguousarray(Phi, dtype=float),
                          np.ascontiguousarray(b, dtype=float), np.ascontiguousarray(nu, dtype=float), float(dt))
    eye = np.eye(n)
    lhs = 1j * nu[..., None, None] * eye - A[:, None]
    rhs = ((np.exp(1j * nu * dt)[..., None, None] * eye - Phi[:, None]) @ b[:, None, :, None])[..., 0]
    return np.linalg.solve(lhs, rhs[..., None])[..., 0]


@numba.njit(cache=True, nogil=True)
def _gains_2x2(A, Phi, b, nu, dt):
    """:func:`harmonic_gains` for 2 x 2 ``A``: Cramer's rule on ``j nu I - A`` at every row and rate."""
    K, n_rates = nu.shape
    out = np.empty((K, n_rates, 2), dtype=np.complex128)
    shared = A.shape[0] == 1
    for k in range(K):
        a = 0 if shared else k
        a00, a01, a10, a11 = A[a, 0, 0], A[a, 0, 1], A[a, 1, 0], A[a, 1, 1]
        p00, p01, p10, p11 = Phi[a, 0, 0], Phi[a, 0, 1], Phi[a, 1, 0], Phi[a, 1, 1]
        b0, b1 = b[a, 0], b[a, 1]
        for i in range(n_rates):
            jnu = 1j * nu[k, i]
            rotation = cmath.exp(jnu * dt)
            m00, m11 = jnu - a00, jnu - a11
            r0 = (rotation - p00) * b0 - p01 * b1
            r1 = (rotation - p11) * b1 - p10 * b0
            det = m00 * m11 - a01 * a10
            out[k, i, 0] = (m11 * r0 + a01 * r1) / det
            out[k, i, 1] = (m00 * r1 + a10 * r0) / det
    return out
