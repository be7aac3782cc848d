"""The floor's own excitation for simulated records with a floor mode: a band of random-phase sines.

The :class:`~smd_statespace.effects.floor_mode.FloorMode` effect's simulation
twin draws it (:meth:`~smd_statespace.effects.floor_mode.FloorMode.draw_simulation_inputs`)
so that a simulated floor vibrates as floors near traffic or machinery do,
independently of the person on it.
"""

from __future__ import annotations

import numpy as np

from ..model import equations

__all__ = ["Multisine", "ambient_floor_excitation", "ambient_line_count"]


class Multisine:
    """A smooth random signal: ``sum_j A_j cos(2 pi f_j t + phi_j)`` (m/s^2)."""

    def __init__(self, frequencies, amplitudes, phases):
        self.omega = 2.0 * np.pi * np.asarray(frequencies, dtype=float)
        self.amplitudes = np.asarray(amplitudes, dtype=float)
        self.phases = np.asarray(phases, dtype=float)

    def scalar(self, t):
        """Value at one time ``t`` (s)."""
        return float(self.amplitudes @ np.cos(self.omega * t + self.phases))

    def __call__(self, t):
        """Values at times ``t`` (s), shape (T,)."""
        return self.amplitudes @ np.cos(np.multiply.outer(self.omega, np.asarray(t, dtype=float))
                                        + self.phases[:, None])


def ambient_floor_excitation(rms, f_f, xi_f, duration, phases):
    """External floor acceleration that makes the bare floor vibrate with RMS acceleration ``rms``.

    White in the band ``0.5 f_f``-``1.5 f_f``: lines ``1 / duration`` apart
    with the given random ``phases`` (rad, one per line, drawn by the caller;
    :func:`ambient_line_count` says how many). The amplitude makes the
    steady-state acceleration of the floor mode alone,
    ``z'' = -w_f^2 z - 2 xi_f w_f z' + e(t)``, have RMS ``rms`` (m/s^2).

    Returns
    -------
    Multisine or None
        None when ``rms`` is 0.
    """
    if rms == 0.0:
        return None
    frequencies = 0.5 * f_f + np.arange(len(phases)) / duration
    gain = np.abs(equations.acceleration_frf(frequencies, f_f, xi_f))  # |z''| per unit e: an SDOF's, as Eq. 2's
    amplitude = rms / np.sqrt(0.5 * np.sum(gain**2))
    return Multisine(frequencies, np.full(frequencies.size, amplitude), phases)


def ambient_line_count(f_f, duration):
    """Number of lines of :func:`ambient_floor_excitation` (band ``f_f`` wide, ``1 / duration`` apart)."""
    return int(np.floor(f_f * duration)) + 1
