"""Given people, their force cycles and rigid-floor GRFs: the crowd generator's engine, public.

:func:`~smd_statespace.simulation.crowd.simulate_crowd` draws its people and then
makes each one's force cycles (Eq. 4 with cycle-to-cycle variation and a phase
offset) and GRF on a rigid floor (Eq. 2-3, exact). These two functions do the
second half for people whose parameters are already known (a ``people.csv``, or
people placed on a structure by :mod:`smd_statespace.structure`), with the same
code, so a person with the same seed gets the same force as in the crowd.
"""

from __future__ import annotations

import numpy as np

from .crowd_forces import _person_cycles, _simulate_forces

__all__ = ["person_cycles", "rigid_floor_grf"]


def person_cycles(seed, f_b, f_h, xi_h, blf, duration, fb_variation=0.02, coef_variation=0.10, phase_spread=1.0):
    """One person's force cycles (Eq. 4), drawn as :func:`~smd_statespace.simulation.crowd.simulate_crowd` draws them.

    Parameters
    ----------
    seed : int or numpy.random.SeedSequence
        The person's force seed (the crowd uses the second of
        :func:`~smd_statespace.simulation.crowd.person_seeds`).
    f_b : float
        Mean bouncing frequency (Hz).
    f_h, xi_h : float
        The person's SMD natural frequency (Hz) and damping ratio (-), Eq. 2
        (they set the force phases that give a realistic GRF shape).
    blf : array_like
        Force harmonics BLF_1..K (g).
    duration : float
        Length the cycles must cover (s).
    fb_variation, coef_variation : float
        Cycle-to-cycle relative SD of the frequency and of the harmonics.
    phase_spread : float
        The first cycle starts a uniform fraction ``[0, phase_spread)`` of a
        cycle before ``t = 0`` (1: unsynchronised people, 0: all in step).

    Returns
    -------
    cycles : pandas.DataFrame
        ``cycle, t_start, t_end, f_b, a0, a1, b1, ...`` (s, Hz, g).
    phase_offset : float
        The drawn fraction of a cycle.
    """
    blf = np.atleast_1d(np.asarray(blf, dtype=float))
    return _person_cycles(np.random.SeedSequence(seed) if isinstance(seed, int) else seed, float(f_b), float(f_h),
                          float(xi_h), blf, float(duration), float(fb_variation), float(coef_variation),
                          float(phase_spread))


def rigid_floor_grf(mass, f_h, xi_h, cycles, time):
    """GRFs (N) of people on a rigid floor under their force cycles: Eq. 2-3 solved exactly, vectorised.

    Parameters
    ----------
    mass, f_h, xi_h : array_like, shape (P,)
        Body masses (kg), SMD natural frequencies (Hz) and damping ratios (-).
    cycles : sequence of pandas.DataFrame
        Each person's cycles (:func:`person_cycles`), covering ``time``.
    time : array_like, shape (T,)
        Sample times (s).

    Returns
    -------
    ndarray, shape (P, T)
        ``M_h (g + u'')`` per person, body weight included.
    """
    parameters = {"mass": np.atleast_1d(np.asarray(mass, dtype=float)),
                  "f_h": np.atleast_1d(np.asarray(f_h, dtype=float)),
                  "xi_h": np.atleast_1d(np.asarray(xi_h, dtype=float))}
    time = np.asarray(time, dtype=float)
    out = np.empty((parameters["mass"].size, time.size))
    _simulate_forces(np.arange(parameters["mass"].size), parameters, list(cycles), time, out)
    return out
