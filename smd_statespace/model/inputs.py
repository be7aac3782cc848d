"""A cycle's known inputs: its bouncing frequency, its start and any measured signals (the model's exogenous side).

Kept apart from :mod:`~smd_statespace.model.core` so that the effects' automatic Jacobians
(:mod:`~smd_statespace.model.jacobians`) build inputs without importing the model.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from ..errors import OptionError

__all__ = ["TWO_PI", "CycleInputs"]

TWO_PI = 2.0 * np.pi


@dataclass(frozen=True)
class CycleInputs:
    """Known inputs of one cycle: what the model needs besides the state.

    Parameters
    ----------
    f_b : float
        Bouncing frequency of the cycle (Hz); sets the Fourier basis (Eq. 4).
    t0 : float
        Cycle start (s). The Fourier basis is referred to it,
        ``cos(2 pi i f_b (t - t0))``, so coefficients of different cycles
        share a phase origin (the GRF peak that starts the cycle).
    time : ndarray, optional
        Sample times (s) of the exogenous signals.
    signals : mapping of str to ndarray, optional
        Exogenous signals sampled at ``time`` (e.g. a measured floor
        displacement ``"floor_disp"``), linearly interpolated between samples.
    """

    f_b: float
    t0: float = 0.0
    time: np.ndarray | None = None
    signals: Mapping[str, np.ndarray] = field(default_factory=dict)

    def signal(self, name: str, t):
        """Exogenous signal ``name`` at time(s) ``t``."""
        if name not in self.signals:
            raise OptionError(
                f"input signal {name!r} is not available; this cycle has {sorted(self.signals) or 'none'}"
            )
        return np.interp(t, self.time, self.signals[name])

    def phase(self, t):
        """Bouncing phase ``2 pi f_b (t - t0)`` (rad)."""
        return TWO_PI * self.f_b * (np.asarray(t, dtype=float) - self.t0)
