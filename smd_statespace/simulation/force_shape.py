"""The default shape of the biomechanical force: its harmonics' amplitudes and the phases of a realistic GRF.

Phase convention: harmonic ``i`` of a cycle is
``a_i cos(i theta) + b_i sin(i theta) = BLF_i cos(i theta - psi_i)`` with
``theta = 2 pi f_b (t - t_start)``, i.e. ``a_i = BLF_i cos psi_i`` and
``b_i = BLF_i sin psi_i``; ``phases`` are the ``psi_i`` (rad).
:func:`default_phases` chooses them so that the GRF on a rigid floor has the
shape of :func:`steady_grf_shape`. Used by
:func:`~smd_statespace.simulation.simulate_bouncing` and the crowd
(:mod:`smd_statespace.simulation.crowd`); re-exported by
:mod:`smd_statespace.simulation.bouncing`.
"""

from __future__ import annotations

import math

import numpy as np

from ..model import acceleration_frf

DEFAULT_BLF = (0.25, 0.15, 0.05, 0.02)
"""Default harmonic amplitudes ``BLF_1..BLF_4`` of the biomechanical force (g)."""

GRF_PHASE_LAG = math.pi / 4
"""Phase lag (rad) of every GRF harmonic in the default force shape.

With ``phases=None`` the force phases are chosen so that, on a rigid floor in
steady state, harmonic ``i`` of the dynamic GRF is
``A_i cos(i theta - pi/4)`` (then shifted so that the main peak is at the
cycle start): a sharp main peak with a fast rise and a slower fall, between
the symmetric all-cosine shape (peak 1.5-1.7 BW, shallow double trough) and a
sawtooth (all-sine, peak-to-trough range largest).
"""


def steady_grf_shape(grf_amplitude, points):
    """Dynamic GRF over one cycle from its harmonics' amplitudes, with the phases of :func:`default_phases`.

    Harmonic ``k`` contributes ``A_k cos(k theta - pi/4)`` (:data:`GRF_PHASE_LAG`).

    Parameters
    ----------
    grf_amplitude : array_like, shape (..., K)
        Amplitudes ``A_k = |H(k f_b)| BLF_k`` of harmonics 1..K (body weights, or g).
    points : int
        Phases ``theta`` per cycle.

    Returns
    -------
    theta : ndarray, shape (points,)
        Cycle phases (rad), from 0, not reaching ``2 pi``.
    shape : ndarray, shape (..., points)
        The dynamic GRF at each phase, in the amplitudes' unit.
    """
    grf_amplitude = np.asarray(grf_amplitude, dtype=float)
    orders = np.arange(1, grf_amplitude.shape[-1] + 1)
    theta = np.linspace(0.0, 2.0 * np.pi, int(points), endpoint=False)
    return theta, grf_amplitude @ np.cos(np.outer(orders, theta) - GRF_PHASE_LAG)


def default_phases(blf, f_b, f_h, xi_h, extra_blf=()):
    """Force phases that give a realistic GRF shape on a rigid floor.

    The phases ``psi_i`` (rad, see the module docstring for the convention) are
    chosen so that in steady state harmonic ``i`` of the dynamic GRF is
    ``|H_i| BLF_i cos(i (theta + theta_p) - pi/4)``, ``H_i`` the response of
    Eq. 2 at ``i f_b`` (:func:`acceleration_frf`) and ``theta_p`` the shift
    that puts the main GRF peak of the base harmonics at the start of each
    cycle (``theta = 0``), where the article starts its cycles.

    Parameters
    ----------
    blf : array_like, shape (n,)
        Base harmonic amplitudes (g).
    f_b, f_h, xi_h : float
        Bouncing frequency (Hz), SMD natural frequency (Hz), damping ratio.
    extra_blf : array_like, shape (m,), optional
        Amplitudes of harmonics ``n+1..n+m`` (the ``harmonics`` effect); they
        get phases by the same rule without changing ``theta_p``.

    Returns
    -------
    base : ndarray, shape (n,)
        Phases of harmonics 1..n (rad, in (-pi, pi]).
    extra : ndarray, shape (m,)
        Phases of harmonics n+1..n+m (rad).
    """
    blf = np.asarray(blf, dtype=float)
    extra_blf = np.asarray(extra_blf, dtype=float).reshape(-1)
    n = blf.size
    orders = np.arange(1, n + extra_blf.size + 1)
    response = acceleration_frf(orders * f_b, f_h, xi_h)
    grf_amplitude = np.abs(response[:n]) * blf
    theta, shape = steady_grf_shape(grf_amplitude, 4096)
    theta_peak = float(theta[np.argmax(shape)]) if np.any(grf_amplitude > 0) else 0.0
    grf_phase = GRF_PHASE_LAG - orders * theta_peak
    force_phase = grf_phase + np.angle(response)
    wrapped = np.pi - np.mod(np.pi - force_phase, 2.0 * np.pi)
    return wrapped[:n], wrapped[n:]
