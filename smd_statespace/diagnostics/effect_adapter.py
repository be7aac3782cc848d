"""How the per-cycle diagnosis uses an effect: as a candidate, its score terms, its notes.

An :class:`~smd_statespace.model.Effect` declares slots and terms only. The
per-cycle diagnosis (:func:`~smd_statespace.diagnostics.missing.diagnose`,
:class:`~smd_statespace.diagnostics.ModelCheck`) needs three more things of
it; each has a default here, derived from the effect's term, and an effect
that knows better implements the method the matching ``Protocol`` names (the
floor mode picks its candidate from the residual's spectrum and explains
what the residual cannot say about a floor):

======================= ========================= ===============================================
function                protocol                  default
======================= ========================= ===============================================
:func:`candidate`       :class:`CandidateSetup`        the effect with its default options
:func:`score_terms`     (none: derived)           derivative of the acceleration in each parameter
:func:`diagnosis_notes` :class:`DiagnosisNotes`   none
======================= ========================= ===============================================
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

from ..model.jacobians import expand_time, numeric_jacobian

if TYPE_CHECKING:  # annotations only
    from ..model import CycleInputs, Effect, SMDModel
    from .check import ModelCheck

__all__ = ["CandidateSetup", "DiagnosisNotes", "candidate", "diagnosis_notes", "score_terms"]


@runtime_checkable
class CandidateSetup(Protocol):
    """An effect class that configures itself as a candidate for a record (a floor mode at a residual's line)."""

    def candidate(self, check: "ModelCheck") -> "Effect | None":
        """The effect configured for the record of ``check`` (the model without it), or None to leave it out."""


@runtime_checkable
class DiagnosisNotes(Protocol):
    """An effect class with something to say when the diagnosis does not find it."""

    def diagnosis_notes(self, base: "ModelCheck", judged: list) -> list:
        """Plain-word notes: ``base`` is the base model's check, ``judged`` the candidates' refits."""


def candidate(effect_class: type, check: "ModelCheck") -> "Effect | None":
    """``effect_class`` configured as a candidate for the record of ``check``, or None to leave it out.

    ``check`` is the :class:`~smd_statespace.diagnostics.ModelCheck` of the
    model without it. Default: the effect with its default options.
    """
    return effect_class.candidate(check) if isinstance(effect_class, CandidateSetup) else effect_class()


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
