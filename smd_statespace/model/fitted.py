"""What an effect may read of the person fitted without it: :class:`FittedRecord`.

An effect configures itself for a record from the fit of the person without it: a cubic spring scales its
search range to the displacement that fit predicts, an estimated floor mode starts its frequency search at the
innovations' strongest line and counts the frequencies the record's duration resolves. The estimator hands it
this view, not its own result object, so that what an effect reads is declared here, in the layer below the
effects, and an estimator's results can change without breaking an effect (a user's too). The record-level
person builds it with :func:`smd_statespace.person.effect_adapter.fitted_record`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable

import numpy as np

__all__ = ["FittedRecord"]


@dataclass(frozen=True)
class FittedRecord:
    """The record and the fit of the person without the effect, as far as an effect reads them.

    Parameters
    ----------
    time : ndarray, shape (N,)
        The fitted samples' times (s), on the record's own time axis.
    floor_acc : ndarray, shape (N,), or None
        The floor's measured vertical acceleration at those samples (m/s^2, upward positive), when the record
        has one.
    predicted_displacement : callable
        ``() -> ndarray (N,)``: the COM displacement ``u`` (m, Eq. 2) the fit predicts at the samples;
        called once, when an effect first asks (:attr:`displacement`).
    strongest_line : callable
        ``() -> float``: the frequency (Hz) of the strongest line of the fit's innovations, what the model
        misses most; called once (:attr:`innovation_line`).
    """

    time: np.ndarray
    floor_acc: np.ndarray | None
    predicted_displacement: Callable[[], np.ndarray] = field(repr=False)
    strongest_line: Callable[[], float] = field(repr=False)

    @property
    def duration(self) -> float:
        """The fitted span's length (s)."""
        return float(self.time[-1] - self.time[0])

    @cached_property
    def displacement(self) -> np.ndarray:
        """The COM displacement ``u`` (m) the fit without the effect predicts at the samples."""
        return np.asarray(self.predicted_displacement(), dtype=float)

    @cached_property
    def innovation_line(self) -> float:
        """The frequency (Hz) of the strongest line of the fit's innovations."""
        return float(self.strongest_line())
