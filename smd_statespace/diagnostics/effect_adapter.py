"""How the per-cycle diagnosis uses an effect: what it reads of the check, its score terms, its notes.

An :class:`~smd_statespace.model.Effect` declares slots and terms only. The
per-cycle diagnosis (:func:`~smd_statespace.diagnostics.missing.diagnose`,
:class:`~smd_statespace.diagnostics.ModelCheck`) proposes it as a candidate
where the record-level one does (:func:`~smd_statespace.model.fitted.propose`,
given :func:`fitted_record` of the check) and needs two more things of it;
each has a default here, derived from the effect's term, and an effect that
knows better implements the method the matching ``Protocol`` names (the floor
mode explains what the residual cannot say about a floor):

======================= ========================= ===============================================
function                protocol                  default
======================= ========================= ===============================================
:func:`score_terms`     (none: derived)           derivative of the acceleration in each parameter
:func:`diagnosis_notes` :class:`DiagnosisNotes`   none
======================= ========================= ===============================================
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

from ..model.fitted import FittedRecord
from ..model.jacobians import expand_time, numeric_jacobian

if TYPE_CHECKING:  # annotations only
    from ..model import CycleInputs, Effect, SMDModel
    from .check import ModelCheck

__all__ = ["DiagnosisNotes", "diagnosis_notes", "fitted_record", "score_terms", "unlocked_line"]


@runtime_checkable
class DiagnosisNotes(Protocol):
    """An effect class with something to say when the diagnosis does not find it."""

    def diagnosis_notes(self, base: "ModelCheck", judged: list) -> list:
        """Plain-word notes: ``base`` is the base model's check, ``judged`` the candidates' refits."""


def fitted_record(check: "ModelCheck") -> FittedRecord:
    """What an effect may read of the per-cycle fit without it (``per_cycle``): the record's samples, its
    measured floor, the free simulation's COM displacement and the residual's strongest line that is not
    locked to the bouncing cycle (:func:`unlocked_line`)."""
    pre = check.preprocessed
    floor = getattr(pre, "floor_acc", None)
    return FittedRecord(time=np.asarray(pre.time, dtype=float),
                        floor_acc=None if floor is None else np.asarray(floor, dtype=float),
                        predicted_displacement=lambda: check.simulated_state("u"),
                        strongest_line=lambda: unlocked_line(check), per_cycle=True)


def unlocked_line(check: "ModelCheck") -> float:
    """The frequency (Hz) of the residual's strongest line that is not locked to the bouncing cycle; NaN if none.

    A floor excited by anything but this person moves at its own frequency with
    no fixed phase to the bouncing cycle. The residual's phase-locked part
    (:meth:`~smd_statespace.diagnostics.ModelCheck.phase_locked`: missing
    harmonics, a nonlinearity) is removed first, so that such a line is found
    even next to a multiple of ``f_b``; a peak is taken only where at least half
    of the residual's power is unlocked. Weak lines at ``(k + 1/2) f_b`` come
    from cycle-to-cycle variation of the force: one is taken only when it is
    stronger than every harmonic line of the residual.
    """
    freq, psd, whole = check.residual_spectrum()
    _, psd_unlocked, peaks = check.residual_spectrum(values=check.residual - check.phase_locked())
    bins = np.clip(np.searchsorted(freq, peaks["frequency"]), 0, freq.size - 1)
    mostly_unlocked = psd_unlocked[bins] >= 0.5 * psd[bins]
    half = (peaks["f_over_fb"] % 1.0 - 0.5).abs() < 0.1
    harmonic_power = whole.loc[whole["label"] != "non-harmonic", "power"].max()
    dominant = peaks["power"] > (0.0 if np.isnan(harmonic_power) else harmonic_power)
    other = peaks[mostly_unlocked & (~half | dominant)]
    return float(other["frequency"].iloc[0]) if len(other) else float("nan")  # peaks: strongest first


def diagnosis_notes(effect_class: type, base: "ModelCheck", judged: list) -> list:
    """Plain-word notes for :func:`~smd_statespace.diagnostics.missing.diagnose` when ``effect_class`` is not
    found (default none)."""
    return effect_class.diagnosis_notes(base, judged) if isinstance(effect_class, DiagnosisNotes) else []


def score_terms(effect: "Effect", model: "SMDModel", x, t, inputs: "CycleInputs") -> dict:
    """The terms ``effect`` would add to ``u''``, one per unknown coefficient (m/s^2 per unit).

    The derivative of the effect's acceleration in each of its parameter
    slots at ``x`` (the score direction of the missing-effect test), or,
    for an effect with no parameter slots (a measured input), its
    acceleration itself. ``x`` has the effect's parameters at their null
    values (usually 0); terms that vanish everywhere (an effect whose term
    needs its own dynamic state) are left out.

    Returns
    -------
    dict of str to ndarray, each of shape ``x.shape[:-1]``
        Keyed ``"NAME:parameter"`` (or ``"NAME"`` for a measured input).
    """
    x = np.asarray(x, dtype=float)
    where = model.effect_slice(effect)
    names = [slot.name for slot in model.slots[where] if slot.kind == "parameter"]
    if not names:
        term = effect.acceleration(model, x, t, inputs)
        return {effect.name: term} if np.any(term != 0) else {}
    jac = numeric_jacobian(lambda z: effect.acceleration(model, z, expand_time(t), inputs), x)
    out = {}
    for name in names:
        term = jac[..., model.index(name)]
        if np.any(term != 0):
            out[f"{effect.name}:{name}"] = term
    return out
