"""What a re-fit of a cycle could absorb: sensitivity chains, orthonormal bases, projections removed block by block.

Functions over arrays, used by :meth:`ModelCheck.remove_absorbable
<smd_statespace.diagnostics.check.ModelCheck.remove_absorbable>` and
:meth:`~smd_statespace.diagnostics.check.ModelCheck.remove_force_harmonics`:

- :func:`chain_sensitivity`: ``H_k F_{k-1} ... F_0``, the derivative of each output of a
  simulated path with respect to its starting state;
- :func:`orthonormal_columns`: an orthonormal basis of a matrix's column space;
- :func:`remove_projections`: a signal minus its least-squares projection on a basis, block by block.

What a per-cycle model can and cannot show
------------------------------------------
Each cycle has its own ``f_h``, ``xi_h``, ``1 + 2n`` force coefficients and
starting ``u``, ``u_dot`` (13 numbers for ``n = 4``) for about 50 samples (a
2 Hz cycle at 100 Hz). A
smooth extra term below about ``n f_b`` is largely absorbed into them, so it
barely reaches the residual (measured on synthetic records of
:func:`~smd_statespace.simulation.simulate_bouncing`, 12 s, 1 % BW noise, EKF):

=================== ======================================== ============================================
hidden effect       what reaches the residual                which diagnostic shows it
=================== ======================================== ============================================
``harmonics``       lines at ``(n+1) f_b``, ``(n+2) f_b``:   :meth:`ModelCheck.residual_spectrum`: top
                    fit 95 -> 82-87 %, residual 1.1-1.3 ->   peak "harmonic 5"; candidate
                    3.3-4.6 % BW                             ``harmonics`` (R about 0.9) strongest
``cubic_stiffness`` mostly absorbed (identified ``f_h`` up   :meth:`ModelCheck.cross_correlation`:
                    3-12 %); fit -0.5 to -1.5 points,        ``cubic_stiffness`` strongest, 2-3.5 times
                    residual +0.1-0.3 % BW                   its value without the effect
``floor_mode``      below ``n f_b`` (the article's 3.48 Hz   nothing: fit, residual and correlations as
                    plate): about 99 % absorbed              on a rigid floor. Above ``n f_b`` (a floor
                                                             excited by other sources): candidate
                                                             ``floor_mode`` and a non-harmonic peak
=================== ======================================== ============================================

:attr:`ModelCheck.residual_unabsorbed` (the residual minus everything a small
change of the cycles' identified values could remove) separates estimator
error from model error: on a clean record it is the measurement noise.
"""

from __future__ import annotations

import numpy as np

__all__ = ["chain_sensitivity", "orthonormal_columns", "remove_projections"]


def chain_sensitivity(jacobians, obs_jacobians) -> np.ndarray:
    """Rows ``H_k F_{k-1} ... F_0``: derivative of each output with respect to the first state.

    Parameters
    ----------
    jacobians : ndarray, shape (m - 1, n, n)
        Transition Jacobians ``F_k = d x_{k+1} / d x_k`` along the path.
    obs_jacobians : ndarray, shape (m, n)
        Output Jacobians ``H_k = d y_k / d x_k`` of one output channel.

    Returns
    -------
    ndarray, shape (m, n)
        Row ``k``: ``d y_k / d x_0`` (output unit per state unit).
    """
    m, n = obs_jacobians.shape
    out = np.empty((m, n))
    phi = np.eye(n)
    out[0] = obs_jacobians[0]
    for k in range(1, m):
        phi = jacobians[k - 1] @ phi
        out[k] = obs_jacobians[k] @ phi
    return out


def orthonormal_columns(matrix, rtol=1e-7) -> np.ndarray:
    """Orthonormal basis of the column space of ``matrix`` (columns scaled to unit norm first).

    Parameters
    ----------
    matrix : array_like, shape (m, p)
    rtol : float
        Singular values below ``rtol`` times the largest (of the scaled
        columns) count as zero; zero and non-finite columns are dropped.

    Returns
    -------
    ndarray, shape (m, r)
        ``r`` the numerical rank (0 columns when nothing is usable).
    """
    matrix = np.asarray(matrix, dtype=float)
    norms = np.linalg.norm(matrix, axis=0)
    usable = np.isfinite(norms) & (norms > 0)
    if not usable.any():
        return np.zeros((matrix.shape[0], 0))
    scaled = matrix[:, usable] / norms[usable]
    u, s, _ = np.linalg.svd(scaled, full_matrices=False)
    return u[:, s > rtol * s[0]]


def remove_projections(values, blocks) -> np.ndarray:
    """What is left of a signal after removing, block by block, its least-squares projection on a basis.

    Parameters
    ----------
    values : ndarray, shape (T,) or (T, q)
        The signal(s).
    blocks : iterable of (slice, ndarray)
        Rows of a block and an orthonormal basis of shape (rows, r) (:func:`orthonormal_columns`);
        rows in no block are kept as they are.

    Returns
    -------
    ndarray, same shape as ``values``
        ``x - B (B^T x)`` on every block.
    """
    out = np.array(values, dtype=float)
    for rows, basis in blocks:
        block = out[rows]
        out[rows] = block - basis @ (basis.T @ block)
    return out
