"""What engineers check: peak acceleration, maximum 1 s running RMS, VDV, and the frequency response.

Of the vertical acceleration as computed (unweighted) and weighted by ``W_b`` (BS 6841:1987,
:mod:`~smd_statespace.structure.weighting`), the weighting BS 6472-1:2008 applies to vertical vibration in
buildings. Published limits on them, with where each number was read, are :mod:`~smd_statespace.structure.limits`.

- ``peak``: ``max |a(t)|`` (m/s^2);
- ``rms_1s_max``: the largest RMS over a 1 s window sliding one sample at a
  time (m/s^2; windows lie wholly inside the record);
- ``vdv``: the vibration dose value of BS 6841 / ISO 2631-1,
  ``(integral a^4 dt)^(1/4)`` (m/s^1.75), by the rectangle rule (exact for a
  sampled sinusoid over whole cycles: ``(3 T / 8)^(1/4) A``);
- ``rms_1s_max_wb``, ``vdv_wb``: the same of the ``W_b``-weighted acceleration (for a bouncing crowd's
  1.5-3.5 Hz, ``W_b`` is 0.4-0.85; 1.02 at 5-8 Hz).
"""

from __future__ import annotations

import numpy as np

from .coupled import Coupling
from .weighting import weighted

__all__ = ["running_rms", "measures", "accelerance"]

MEASURES = ("peak", "rms_1s_max", "vdv", "rms_1s_max_wb", "vdv_wb")
"""The names :func:`measures` returns."""


def running_rms(acceleration, fs, window=1.0):
    """RMS over a window of ``window`` s ending at each sample from the first full window on.

    Parameters
    ----------
    acceleration : array_like, shape (..., T)
        Accelerations (m/s^2) sampled at ``fs`` Hz.
    fs : float
        Sampling frequency (Hz).
    window : float
        Window length (s); ``round(window fs)`` samples.

    Returns
    -------
    ndarray, shape (..., T - n + 1)
        m/s^2; empty when the record is shorter than the window.
    """
    a = np.asarray(acceleration, dtype=float)
    n = max(1, int(round(float(window) * float(fs))))
    if a.shape[-1] < n:
        return np.empty(a.shape[:-1] + (0,))
    total = np.cumsum(np.concatenate([np.zeros(a.shape[:-1] + (1,)), a * a], axis=-1), axis=-1)
    return np.sqrt(np.maximum(total[..., n:] - total[..., :-n], 0.0) / n)


def measures(acceleration, fs) -> dict:
    """:data:`MEASURES` of accelerations (m/s^2) at ``fs`` Hz, each of shape ``(...)``.

    Parameters
    ----------
    acceleration : array_like, shape (..., T)
    fs : float
        Sampling frequency (Hz).
    """
    a = np.asarray(acceleration, dtype=float)
    out = {"peak": np.max(np.abs(a), axis=-1)}
    for suffix, values in (("", a), ("_wb", weighted(a, fs, "Wb"))):
        rms = running_rms(values, fs)
        out[f"rms_1s_max{suffix}"] = rms.max(axis=-1) if rms.shape[-1] else np.sqrt(np.mean(values**2, axis=-1))
        out[f"vdv{suffix}"] = (np.sum(values**4, axis=-1) / float(fs)) ** 0.25
    return out


def accelerance(coupling: Coupling, point, frequency, occupied=True):
    """Driving-point accelerance at ``point``: acceleration per unit vertical force there (m/s^2/N).

    ``-w^2 phi_p^T D(i w)^-1 phi_p`` for the occupied structure, with ``D_0``
    for the empty one.

    Parameters
    ----------
    coupling : Coupling
    point : int
        Row of the point in the shapes.
    frequency : array_like, shape (F,)
        Hz.
    occupied : bool
        With the people (``D``) or empty (``D_0``).

    Returns
    -------
    complex ndarray, shape (F,)
    """
    s = 2j * np.pi * np.asarray(frequency, dtype=float)
    phi = coupling.model.shapes[int(point)]
    if occupied:
        stiffness = coupling.dynamic_stiffness(s)
        response = np.linalg.solve(stiffness, np.broadcast_to(phi.astype(complex), s.shape + phi.shape)[..., None])
        return s**2 * (response[..., 0] @ phi)
    return s**2 * ((phi**2) / coupling.empty_stiffness(s)).sum(axis=-1)
