"""The record-level model's arrays: its known inputs, its system at one parameter vector, exact steps.

:class:`Regressor` is a known signal whose coefficient enters the person's
acceleration; :class:`RecordSystem` holds the arrays of the compiled passes
at one parameter vector (:meth:`~smd_statespace.person.model.RecordModel.system`
builds it); the functions discretise exactly over one sample: a 2 x 2
matrix exponential in closed form, the Matern-3/2 step of the smooth
variation, the covariance of a white force (Van Loan) and the trapezoidal
hold of known inputs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import linalg

__all__ = ["RecordSystem", "Regressor", "expm2", "integrated_white_noise", "matern32_step", "regressor_steps",
           "step_mean"]


@dataclass(frozen=True)
class RecordSystem:
    """The record-level model's arrays at one parameter vector: what the compiled passes take.

    ``N`` samples, ``n_x`` dynamic states, ``p = 2 n + 1`` force coefficients, ``r``
    regressors (effects' known signals), ``K`` = 1 for linear dynamics (``Phi`` and ``hx``
    the same at every sample) or ``N``. Accelerations in m/s^2, every variance relative
    to the scale ``sigma^2`` (:mod:`~smd_statespace.person.kalman`).

    Attributes
    ----------
    hx : ndarray, shape (K, n_x)
        Observation row of the dynamic states.
    H : ndarray, shape (N, p)
        Observation row of the force coefficients (the Fourier basis in the cycle's phase).
    Phi : ndarray, shape (K, n_x, n_x)
        Transition of the dynamic states over one sample.
    Gam : ndarray, shape (N, n_x, p)
        Transition gain of the force coefficients.
    Qx : ndarray, shape (n_x, n_x)
        Process covariance of the dynamic states (zero without process noise).
    offset : ndarray, shape (N, n_x)
        Known part of the step (a linearised or input-driven effect).
    y_known : ndarray, shape (N,)
        Known part of the observation, subtracted from ``y`` before a pass.
    X_obs : ndarray, shape (N, r)
        Regressors in the observation.
    X_tr : ndarray, shape (N, n_x, r)
        Regressors in the step.
    reset : ndarray of bool, shape (N,)
        Whether a cycle starts at the sample (the coefficients are drawn again).
    code : int
        The variation model (:data:`~smd_statespace.person.kalman.INDEPENDENT`, ...).
    D, E, drift : ndarray, shape (p,)
        Variances of the coefficients' deviation per cycle, of their random walk per cycle
        and of their drift per sample.
    smooth_phi, smooth_q, smooth_p0 : ndarray, shape (2, 2)
        The Matern-3/2 step, its process covariance and its stationary covariance (variation
        "smooth"; zeros otherwise).
    observed : ndarray of bool, shape (N,)
        False at a missing sample (the passes predict over it and make no update).
    """

    hx: np.ndarray
    H: np.ndarray
    Phi: np.ndarray
    Gam: np.ndarray
    Qx: np.ndarray
    offset: np.ndarray
    y_known: np.ndarray
    X_obs: np.ndarray
    X_tr: np.ndarray
    reset: np.ndarray
    code: int
    D: np.ndarray
    E: np.ndarray
    drift: np.ndarray
    smooth_phi: np.ndarray
    smooth_q: np.ndarray
    smooth_p0: np.ndarray
    observed: np.ndarray

    def pass_arguments(self, y, n_template) -> tuple:
        """The positional arguments of :func:`~smd_statespace.person.kalman.augmented_pass` for the measured
        ``y`` (the known part subtracted) and ``n_template`` template coefficients; the first ones of
        :func:`~smd_statespace.person.sensitivity.sensitivity_pass` too.

        Every array is C-contiguous (:func:`contiguous`): the compiled passes are compiled once per layout of
        their arguments."""
        return contiguous(y - self.y_known, self.hx, self.H, self.Phi, self.Gam, self.Qx, self.offset, self.X_obs,
                          self.X_tr, self.reset, self.code, self.D, self.E, self.drift, n_template, self.smooth_phi,
                          self.smooth_q, self.smooth_p0, self.observed)


def contiguous(*arguments) -> tuple:
    """``arguments`` with every array C-contiguous (copied only where it is not), the rest as given.

    numba compiles a function once per layout of its array arguments: a transposed or sliced array (layout "A")
    beside the usual C one made the two largest passes compile twice, about 25 s of a fresh installation's first
    fit (the cache then holds both)."""
    return tuple(np.ascontiguousarray(a) if isinstance(a, np.ndarray) else a for a in arguments)


@dataclass(frozen=True)
class Regressor:
    """A known signal whose unknown coefficient enters the person's acceleration.

    An effect that is linear in one unknown coefficient ``c`` adds
    ``c x(t)`` to ``u''`` (Eq. 2): for example the measured floor acceleration
    (the leg acts on the motion relative to the floor) or ``u^3`` evaluated on
    the smoothed displacement (a cubic spring, linearised about the fitted
    path). The coefficient is estimated with the template, by generalised
    least squares, so it costs no search dimension.

    Attributes
    ----------
    name : str
        Name of the coefficient (its key in ``person.json``).
    values : ndarray, shape (N,)
        The signal at the samples (m/s^2 per unit coefficient).
    unit : str
        Unit of the coefficient.
    dynamic : bool
        True (default): a term of the person's acceleration, so it moves
        ``u`` and ``u'`` too. False: a term of the measurement only (a force
        offset, a wrong body mass), which the COM does not feel.
    observed : bool
        True (default): the term is part of the measured ``GRF / M_h - g``.
        False: it moves the state but is not measured (the floor's
        acceleration when ``u`` is read relative to the floor).
    """

    name: str
    values: np.ndarray
    unit: str = "-"
    dynamic: bool = True
    observed: bool = True


def expm2(a, t):
    """``exp(a t)`` of a real 2 x 2 matrix in closed form.

    ``exp(a t) = exp(s t) [cosh(q t) I + sinh(q t) / q (a - s I)]`` with
    ``s = tr(a) / 2`` and ``q^2 = s^2 - det(a)`` (complex for an
    under-damped oscillator); scipy's general ``expm`` costs about 1000 times
    more on this size.
    """
    s = 0.5 * (a[0, 0] + a[1, 1])
    det = a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]
    q = np.sqrt(complex(s * s - det))
    qt = q * t
    cosh = np.cosh(qt)
    sinhc = t * (1.0 + qt * qt / 6.0 + qt**4 / 120.0) if abs(qt) < 1e-4 else np.sinh(qt) / q
    shifted = a - s * np.eye(2)
    return (np.exp(s * t) * (cosh * np.eye(2) + sinhc * shifted)).real


def matern32_step(length_scale, dt):
    """One sample of a unit-variance Matern-3/2 process and its rate: ``(Phi, Q, P_inf)``.

    The process ``d'' = -2 lambda d' - lambda^2 d + w``, ``lambda = sqrt(3) /
    length_scale`` (s), has the stationary covariance ``P_inf = diag(1,
    lambda^2)`` of ``(d, d')`` and the autocorrelation ``(1 + lambda tau)
    exp(-lambda tau)``; over a step ``dt`` (s) the transition is
    ``Phi = exp(A dt)`` and the process covariance ``Q = P_inf - Phi P_inf Phi'``
    (exact for a stationary linear system).
    """
    lam = np.sqrt(3.0) / float(length_scale)
    a_c = np.array([[0.0, 1.0], [-lam * lam, -2.0 * lam]])
    phi = expm2(a_c, dt)
    p_inf = np.diag([1.0, lam * lam])
    q = p_inf - phi @ p_inf @ phi.T
    return phi, 0.5 * (q + q.T), p_inf


def integrated_white_noise(a_c, b, dt):
    """Covariance over one step of a unit-intensity white force entering through ``b`` (Van Loan's method)."""
    n = a_c.shape[0]
    block = np.zeros((2 * n, 2 * n))
    block[:n, :n] = -a_c
    block[:n, n:] = np.outer(b, b)
    block[n:, n:] = a_c.T
    e = linalg.expm(block * dt)
    phi = e[n:, n:].T
    return phi @ e[:n, n:]


def step_mean(values):
    """Mean of each sample's value and the next one's (the last held): a value over the step from each sample."""
    return 0.5 * (values + np.concatenate([values[1:], values[-1:]]))


def regressor_steps(g0, x_obs):
    """Effect of the regressors' acceleration terms on the dynamic states over a step (trapezoidal hold).

    ``g0`` (shape (K, n_x)) is the change of the states over a step under a
    unit constant acceleration input.
    """
    if x_obs.shape[1] == 0:
        return np.zeros((x_obs.shape[0], g0.shape[1], 0))
    return step_mean(x_obs)[:, None, :] * g0[:, :, None]
