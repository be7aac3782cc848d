"""Frequency weighting of vertical whole-body vibration: ``W_b`` (BS 6841:1987) and ``W_k`` (ISO 2631-1:1997).

The guidance on floors and grandstands judges the *weighted* acceleration (the vibration dose value of BS 6472-1
and BS 6841 is of ``W_b``-weighted acceleration; ISO 2631-1 weights vertical vibration by ``W_k``). Both weightings
are products of four analogue filters (ISO 2631-1:1997 Annex A; BS 6841:1987), with ``s = i 2 pi f``:

- band limiting, second-order Butterworth (``Q = 1/sqrt 2``): high pass at ``f1``,
  ``s^2 / (s^2 + w1 s / Q + w1^2)``, and low pass at ``f2``, ``w2^2 / (s^2 + w2 s / Q + w2^2)``;
- acceleration-velocity transition: ``(1 + s / w3) / (1 + s / (Q4 w4) + s^2 / w4^2)``;
- upward step: ``(s^2 + w5 s / Q5 + w5^2) / (s^2 + w6 s / Q6 + w6^2)`` (gain ``(f5 / f6)^2`` at low frequency,
  1 at high);

times a gain ``K``: 1 for ``W_k``; 1.024 for ``W_b`` (ISO 2631-4's form of it), which makes its low-frequency gain
0.4 as in BS 6841. A bouncing crowd's 1.5-10 Hz lies where both weightings are between about 0.5 and 1.05.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import OptionError

__all__ = ["Weighting", "WEIGHTINGS", "weighting_gain", "weighted"]

BUTTERWORTH_Q = 1.0 / np.sqrt(2.0)
"""Quality factor of the band-limiting filters."""


@dataclass(frozen=True)
class Weighting:
    """Corner frequencies (Hz), quality factors (-) and gain (-) of one weighting (see the module docstring)."""

    name: str
    f1: float
    f2: float
    f3: float
    f4: float
    q4: float
    f5: float
    q5: float
    f6: float
    q6: float
    gain: float
    source: str


WEIGHTINGS = {
    "Wb": Weighting("Wb", 0.4, 100.0, 16.0, 16.0, 0.55, 2.5, 0.9, 4.0, 0.95, 1.024,
                    "BS 6841:1987 (as ISO 2631-4:2001 writes it); BS 6472-1:2008's weighting for vertical vibration "
                    "in buildings"),
    "Wk": Weighting("Wk", 0.4, 100.0, 12.5, 12.5, 0.63, 2.37, 0.91, 3.35, 0.91, 1.0,
                    "ISO 2631-1:1997, vertical whole-body vibration"),
}
"""The weightings by name."""


def _weighting(name) -> Weighting:
    if name not in WEIGHTINGS:
        raise OptionError(f"weighting {name!r}: give one of {', '.join(WEIGHTINGS)}")
    return WEIGHTINGS[name]


def weighting_gain(frequency, name="Wb"):
    """The weighting's complex gain at ``frequency`` (Hz), ``H(i 2 pi f)``.

    Parameters
    ----------
    frequency : array_like
        Hz.
    name : {"Wb", "Wk"}

    Returns
    -------
    complex ndarray
        Dimensionless; ``|H|`` is the weighting factor tabulated by the standards.
    """
    w = _weighting(name)
    s = 2j * np.pi * np.asarray(frequency, dtype=float)
    omega = {key: 2.0 * np.pi * getattr(w, key) for key in ("f1", "f2", "f3", "f4", "f5", "f6")}
    high = s**2 / (s**2 + omega["f1"] * s / BUTTERWORTH_Q + omega["f1"] ** 2)
    low = omega["f2"] ** 2 / (s**2 + omega["f2"] * s / BUTTERWORTH_Q + omega["f2"] ** 2)
    transition = (1.0 + s / omega["f3"]) / (1.0 + s / (w.q4 * omega["f4"]) + s**2 / omega["f4"] ** 2)
    step = ((s**2 + omega["f5"] * s / w.q5 + omega["f5"] ** 2)
            / (s**2 + omega["f6"] * s / w.q6 + omega["f6"] ** 2))
    return w.gain * high * low * transition * step


def weighted(acceleration, fs, name="Wb"):
    """Accelerations weighted by ``W_b`` or ``W_k``: the filter applied in the frequency domain.

    The record is padded with zeros to at least twice its length before the FFT, so that its end does not wrap
    onto its start; the filter then acts as on a record that starts and ends at rest.

    Parameters
    ----------
    acceleration : array_like, shape (..., T)
        Vertical accelerations (m/s^2) sampled at ``fs`` Hz.
    fs : float
        Sampling frequency (Hz).
    name : {"Wb", "Wk"}

    Returns
    -------
    ndarray, shape (..., T)
        Weighted accelerations (m/s^2).
    """
    a = np.asarray(acceleration, dtype=float)
    length = a.shape[-1]
    size = 1 << int(np.ceil(np.log2(max(2 * length, 2))))
    spectrum = np.fft.rfft(a, n=size, axis=-1) * weighting_gain(np.fft.rfftfreq(size, 1.0 / float(fs)), name)
    return np.fft.irfft(spectrum, n=size, axis=-1)[..., :length]
