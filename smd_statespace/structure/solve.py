"""Time histories of the coupled and the force-only structure, solved in the frequency domain.

With the decomposition of :mod:`.coupled`, the structure's modal
coordinates obey ``D(s) Q = P`` (coupled) and ``D_0(s) Q_0 = P`` (force-only),
``P`` the active people's dynamic rigid-floor GRFs on the modes. Both start at
rest when the crowd starts (``t = 0``), so the load jumps from zero there
(and back to zero after the last sample): the first and last samples are
halved, the band-limited value at a jump, and the direct response ``P / m_j``
of the half put back, which makes the start exact to the sampling (without
it the error was 1/fs, 0.8 % RMS at 200 Hz on the plate). The loads are zero-padded by the time
the slowest coupled mode needs to decay to ``1e-8`` of its size, transformed
(real FFT), and at every frequency the ``m x m`` system is solved; the crowd
enters through one matrix product per block of frequencies, ``(F x N)`` apparent
masses times ``(N x m^2)`` outer products of the people's shapes, so the cost is
``O(F N m^2)`` with no ``(2m + 2N)``-state matrix formed. The sampled loads are
read as band-limited (the FFT's interpolation); measured against the exact
one-person solution of :mod:`smd_statespace.simulation.floor` the floor
acceleration agrees to the figures in docs/tutorial-structure.md.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import fft as sp_fft

from ..errors import OptionError
from .coupled import Coupling, occupied_eigenvalues, transmissibility

__all__ = ["Solution", "solve", "DECAY", "MAX_SAMPLES"]

DECAY = 1e-8
"""Fraction of the slowest mode's amplitude left at the end of the zero padding (wrap-around error)."""

MAX_SAMPLES = 2**23
"""Longest padded record (samples); a structure too lightly damped to decay within it is refused."""

BLOCK = 2_000_000
"""Frequencies x people evaluated at once (memory about 32 bytes each)."""


@dataclass
class Solution:
    """Modal accelerations of the coupled and the force-only structure (:func:`solve`).

    Attributes
    ----------
    time : ndarray, shape (T,)
        Sample times (s).
    coupled, force_only : ndarray, shape (m, T)
        Modal accelerations ``q_j''`` (m/s^2 per unit ``phi``).
    frequency : ndarray, shape (F,)
        Frequencies of the padded transform (Hz).
    modal_spectrum : complex ndarray, shape (F, m)
        ``Q(i w)`` of the coupled structure (for the people's own motion).
    padded : int
        Length of the padded record (samples).
    """

    time: np.ndarray
    coupled: np.ndarray
    force_only: np.ndarray
    frequency: np.ndarray
    modal_spectrum: np.ndarray
    padded: int

    def at(self, shapes):
        """Accelerations (m/s^2) at points with mode-shape rows ``shapes`` (P, m): ``(coupled, force_only)``, (P, T)."""
        shapes = np.atleast_2d(shapes)
        return shapes @ self.coupled, shapes @ self.force_only

    def person_floor_response(self, coupling: Coupling, people):
        """``v_i''`` (m/s^2): each person's extra COM acceleration caused by the floor's motion, shape (len, T).

        The person's GRF on the structure is ``M_i (g + r_i'' + v_i'')``, ``r_i``
        the rigid-floor motion (module docstring of :mod:`.coupled`).
        """
        people = np.atleast_1d(np.asarray(people, dtype=int))
        s = 2j * np.pi * self.frequency
        out = np.empty((people.size, self.time.size))
        for start in range(0, people.size, 64):
            chunk = people[start:start + 64]
            floor = self.modal_spectrum @ coupling.phi[chunk].T  # (F, len)
            spectrum = s[:, None] ** 2 * transmissibility(s[:, None], coupling.k[chunk], coupling.c[chunk]) * floor
            out[start:start + chunk.size] = sp_fft.irfft(spectrum, n=self.padded, axis=0)[:self.time.size].T
        return out


def _slowest_decay(coupling: Coupling, occupied=None) -> float:
    """Smallest decay rate (1/s) among the empty modes, the occupied ones and the people's own."""
    model = coupling.model
    rates = [model.damping * model.omega]
    if coupling.n_people:
        rates.append(-(occupied_eigenvalues(coupling) if occupied is None else np.asarray(occupied)).real)
        omega = 2 * np.pi * coupling.f_h
        xi = coupling.xi_h
        slow = np.where(xi < 1, xi * omega, omega * (xi - np.sqrt(np.maximum(xi**2 - 1, 0.0))))
        rates.append(0.8 * slow)  # a person's mode moves a little when coupled
    return float(np.min(np.concatenate([np.atleast_1d(r) for r in rates])))


def solve(coupling: Coupling, loads, fs, occupied=None) -> Solution:
    """Coupled and force-only modal accelerations under the modal loads ``loads`` (structure at rest at ``t = 0``).

    Parameters
    ----------
    coupling : Coupling
        The structure and every person on it (active and passive).
    loads : array_like, shape (m, T)
        Modal loads ``P_j(t)`` (N) at ``t = k / fs``: the force-only load of
        :meth:`~smd_statespace.structure.people.Occupants.modal_loads`.
    fs : float
        Sampling frequency (Hz); every mode must be below ``fs / 2``.
    occupied : complex array_like, optional
        The occupied eigenvalues if known (:func:`~.coupled.occupied_eigenvalues`), for the padding.

    Returns
    -------
    Solution
    """
    loads = np.atleast_2d(np.asarray(loads, dtype=float))
    model, fs = coupling.model, float(fs)
    if loads.shape[0] != model.n_modes:
        raise OptionError(f"solve: loads need {model.n_modes} rows (one per mode), got {loads.shape[0]}")
    model.check_rate(fs)
    samples = loads.shape[1]
    decay = _slowest_decay(coupling, occupied)
    padded = sp_fft.next_fast_len(samples + int(np.ceil(np.log(1 / DECAY) / decay * fs)), real=True)
    if padded > MAX_SAMPLES:
        raise OptionError(f"structure: the slowest mode decays at {decay:.3g} 1/s, too slowly for the frequency-domain "
                          f"solution ({padded} samples); give the modes more damping (zeta)")
    frequency = sp_fft.rfftfreq(padded, 1.0 / fs)
    s = 2j * np.pi * frequency
    ends = loads.copy()
    ends[:, [0, -1]] *= 0.5  # the load jumps there (from and to zero): the band-limited value at a jump is its middle
    spectrum = sp_fft.rfft(ends, n=padded, axis=1).T  # (F, m)
    coupled = np.empty_like(spectrum)
    block = max(1, BLOCK // max(coupling.n_people, 1))
    for start in range(0, frequency.size, block):
        part = slice(start, start + block)
        stiffness = coupling.dynamic_stiffness(s[part])
        coupled[part] = np.linalg.solve(stiffness, spectrum[part][..., None])[..., 0]
    empty = spectrum / coupling.empty_stiffness(s)
    acceleration = (s**2)[:, None]

    def back(modal):
        out = sp_fft.irfft(acceleration * modal, n=padded, axis=0)[:samples].T
        out[:, [0, -1]] += 0.5 * loads[:, [0, -1]] / model.modal_mass[:, None]  # the sides of the jumps in the record
        return out

    return Solution(np.arange(samples) / fs, back(coupled), back(empty), frequency, coupled, padded)
