"""What an effect may read of the person fitted without it (:class:`FittedRecord`), and how it proposes itself.

An effect configures itself for a record from the fit of the person without it: a cubic spring scales its
search range to the displacement that fit predicts, a floor mode is the measured floor where the record has
one and otherwise a mode at the line the fit misses. The estimator hands it this view, not its own result
object, so that what an effect reads is declared here, in the layer below the effects, and an estimator's
results can change without breaking an effect (a user's too). The record-level person builds it with
:func:`smd_statespace.person.effect_adapter.fitted_record`, the per-cycle check with
:func:`smd_statespace.diagnostics.effect_adapter.fitted_record`.

:func:`propose` is the one place where an effect becomes a candidate, for both diagnoses (the
record-level :func:`~smd_statespace.person.diagnose.diagnose_person` and the per-cycle
:func:`~smd_statespace.diagnostics.missing.diagnose`) and for ``identify --effect NAME``: the effect's
own :meth:`Proposes.propose` where it has one, else the effect with its default options.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Callable, Protocol, runtime_checkable

import numpy as np

if TYPE_CHECKING:  # annotations only
    from .effect import Effect

__all__ = ["FittedRecord", "Proposes", "propose"]


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
        ``() -> float``: the frequency (Hz) of the strongest line of what the fit misses that is not locked
        to the bouncing cycle (a floor's own motion), NaN when there is none; called once
        (:attr:`innovation_line`).
    per_cycle : bool
        The fit is the article's per-cycle method (every parameter a state estimated cycle by cycle), not
        the record-level person: what must be one value for the record (a floor's frequency) cannot be
        searched and is read off the record instead.
    f_h : float
        The natural frequency ``f_h`` (Hz) of the person fitted without the effect; NaN where the fit has none for
        the whole record (the per-cycle method: one per cycle).
    """

    time: np.ndarray
    floor_acc: np.ndarray | None
    predicted_displacement: Callable[[], np.ndarray] = field(repr=False)
    strongest_line: Callable[[], float] = field(repr=False)
    per_cycle: bool = False
    f_h: float = float("nan")

    @property
    def duration(self) -> float:
        """The fitted span's length (s)."""
        return float(self.time[-1] - self.time[0])

    @cached_property
    def displacement(self) -> np.ndarray:
        """The COM displacement ``u`` (m) the fit without the effect predicts at the samples."""
        return np.asarray(self.predicted_displacement(), dtype=float)

    SLOW_WANDER = 0.3
    """Frequency (Hz) below which the predicted displacement's motion is a slow wander, not bouncing (the model's
    bouncing frequencies start at 1 Hz)."""

    @cached_property
    def swing(self) -> float:
        """The RMS (m) of the predicted displacement about its slow wander: how far the body moves within cycles.

        A fit that puts what it misses into the cycles' mean force predicts a displacement that wanders by
        centimetres: with a hidden hardening spring, 4.7 cm RMS where the simulated body moved 0.64 cm. Without
        what it predicts below :data:`SLOW_WANDER` (a zero-phase high-pass, second order) the same fit gives
        0.64 cm, and 0.80 cm (truth 0.80) where it wanders not.
        """
        from scipy import signal  # here: the CLI starts without scipy.signal (docs/performance.md, "Imports")

        u = self.displacement
        if u.size < 16 or self.duration <= 0:
            return float(np.sqrt(np.mean(u**2))) if u.size else 0.0
        sos = signal.butter(2, self.SLOW_WANDER, "highpass", fs=(u.size - 1) / self.duration, output="sos")
        return float(np.std(signal.sosfiltfilt(sos, u - u.mean())))

    @cached_property
    def innovation_line(self) -> float:
        """The frequency (Hz) of the strongest line the fit misses that is not locked to the bouncing cycle
        (NaN: none)."""
        return float(self.strongest_line())


@runtime_checkable
class Proposes(Protocol):
    """An effect class that configures itself as a candidate for a record (a cubic spring's range scaled to
    the displacement, the measured floor or a mode at the missed line), or leaves itself out."""

    def propose(self, fitted: FittedRecord) -> "Effect | None":
        """The effect as a candidate for the record ``fitted`` describes, or None to leave it out."""


def propose(effect_class: type, fitted: FittedRecord) -> "Effect | None":
    """``effect_class`` as a candidate for the record of ``fitted`` (the fit without it), or None.

    Its :meth:`Proposes.propose` where it has one; else the effect with its default options.
    """
    return effect_class.propose(fitted) if isinstance(effect_class, Proposes) else effect_class()
