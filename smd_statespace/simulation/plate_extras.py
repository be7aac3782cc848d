"""The plate's extras of a simulated lab record: a standing person's sway, mains hum, a drifting zero.

Each is drawn from its own random stream (:data:`smd_statespace.simulation.lab.STREAMS`) and added to the
person's force; each returns its path (N) and its truth.
"""

from __future__ import annotations

import numpy as np

from ..errors import OptionError

__all__ = ["SWAY_BAND", "SWAY_COMPONENTS", "HUM_MODULATION_BAND", "DRIFT_DEGREE", "DRIFT_SHAPES", "SETTLING_SECONDS",
           "WALK_SMOOTHING", "sway_force", "hum_force", "drift_path"]

SWAY_BAND = (0.1, 1.5)
"""Frequencies (Hz) of a standing person's sway: :data:`SWAY_COMPONENTS` sinusoids drawn uniformly in it."""

SWAY_COMPONENTS = 8
"""Sinusoids in the sway force."""

HUM_MODULATION_BAND = (0.02, 0.2)
"""Frequencies (Hz) of the slow sinusoidal modulation of the hum's amplitude (``hum_variation``)."""

DRIFT_DEGREE = 3
"""Degree of the random (Legendre) polynomial of the plate's drifting zero (``drift_shape="cubic"``)."""

DRIFT_SHAPES = ("cubic", "settling", "walk", "steps")
"""Shapes of the plate's drifting zero (:func:`drift_path`)."""

SETTLING_SECONDS = (5.0, 15.0)
"""Range of the time constant (s) of a settling zero (``drift_shape="settling"``)."""

WALK_SMOOTHING = 2.0
"""Width (s) of the moving average that smooths a wandering zero (``drift_shape="walk"``)."""


def sway_force(rng, time, rms, envelope):
    """A standing person's sway force (N): sinusoids in :data:`SWAY_BAND`, RMS ``rms``, faded by ``envelope``."""
    frequencies = rng.uniform(*SWAY_BAND, SWAY_COMPONENTS)
    weights = rng.rayleigh(1.0, SWAY_COMPONENTS)
    phases = rng.uniform(0.0, 2.0 * np.pi, SWAY_COMPONENTS)
    weights = rms * weights / np.sqrt(0.5 * np.sum(weights**2))  # RMS of a sum of sinusoids
    sway = weights @ np.cos(2.0 * np.pi * np.outer(frequencies, time) + phases[:, None])
    truth = {"rms_n": rms, "band_hz": list(SWAY_BAND), "frequencies_hz": frequencies.tolist(),
             "amplitudes_n": weights.tolist(), "phases_rad": phases.tolist()}
    return sway * (1.0 - envelope), truth


def hum_force(rng, time, frequency, amplitudes, variation):
    """Mains hum (N): harmonics ``k frequency`` of ``amplitudes``, amplitude modulated by ``variation``."""
    phases = rng.uniform(0.0, 2.0 * np.pi, amplitudes.size)
    f_mod, phase_mod = rng.uniform(*HUM_MODULATION_BAND), rng.uniform(0.0, 2.0 * np.pi)
    modulation = 1.0 + variation * np.sin(2.0 * np.pi * f_mod * time + phase_mod)
    orders = np.arange(1, amplitudes.size + 1)
    hum = modulation * (amplitudes @ np.cos(2.0 * np.pi * frequency * np.outer(orders, time) + phases[:, None]))
    truth = {"frequency_hz": frequency, "amplitudes_n": amplitudes.tolist(), "phases_rad": phases.tolist(),
             "variation": variation, "modulation_hz": float(f_mod)}
    return hum, truth


def drift_path(rng, time, size, shape="cubic"):
    """The plate's drifting zero (N), 0 at ``t = 0``, ``max |drift| = size``, of one of :data:`DRIFT_SHAPES`.

    ``"cubic"``: a random Legendre polynomial of degree :data:`DRIFT_DEGREE`; ``"settling"``: ``1 - exp(-t / tau)``
    of either sign, ``tau`` drawn in :data:`SETTLING_SECONDS` (a plate or amplifier warming up); ``"walk"``: a
    random walk smoothed over :data:`WALK_SMOOTHING` s (a zero that wanders); ``"steps"``: 2-4 steps at random
    times, of random signs and sizes (a cable knocked, a charge amplifier's jump).
    """
    x = 2.0 * time / time[-1] - 1.0
    if shape == "cubic":
        path = np.polynomial.legendre.legval(x, np.concatenate([[0.0], rng.standard_normal(DRIFT_DEGREE)]))
    elif shape == "settling":
        path = rng.choice([-1.0, 1.0]) * (1.0 - np.exp(-(time - time[0]) / rng.uniform(*SETTLING_SECONDS)))
    elif shape == "walk":
        steps = np.cumsum(rng.standard_normal(time.size))
        width = max(1, int(round(WALK_SMOOTHING / (time[1] - time[0]))))
        path = np.convolve(np.pad(steps, width, mode="edge"), np.ones(width) / width, mode="same")[width:-width]
    elif shape == "steps":
        at = rng.uniform(time[0], time[-1], int(rng.integers(2, 5)))
        sizes = rng.choice([-1.0, 1.0], at.size) * rng.uniform(0.3, 1.0, at.size)
        path = (time[:, None] >= at[None, :]).astype(float) @ sizes
    else:
        raise OptionError(f"simulate_lab_record: drift_shape must be one of {', '.join(map(repr, DRIFT_SHAPES))}, "
                          f"got {shape!r}")
    path = path - path[0]
    peak = np.abs(path).max()
    drift = size * path / peak if peak > 0 else np.zeros_like(time)
    truth = {"max_abs_n": size, "shape": shape, "start_n": float(drift[0]), "end_n": float(drift[-1]),
             "min_n": float(drift.min()), "max_n": float(drift.max())}
    if shape == "cubic":
        truth["degree"] = DRIFT_DEGREE
    return drift, truth


