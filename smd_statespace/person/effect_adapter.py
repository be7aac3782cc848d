"""How the record-level person uses an effect: as force harmonics, its trial starts, the size of its search.

An :class:`~smd_statespace.model.Effect` declares slots and terms only. The
record-level estimator proposes it as a candidate where the per-cycle
diagnosis does (:func:`~smd_statespace.model.fitted.propose`, given
:func:`fitted_record` of the fit without it) and needs three more things of
it; each has a default here, and an effect that knows better implements the
method the matching ``Protocol`` names:

========================== ===================== =====================================================
function                   protocol              default
========================== ===================== =====================================================
:func:`record_harmonics`   :class:`RecordHarmonics`   0 (the effect's parameters are estimated)
:func:`record_starts`      :class:`RecordStarts`      none (0 where the range holds 0, else the nominal)
:func:`record_search_size` :class:`RecordSearchSize`  1 (one search, no multiple testing)
:func:`record_grid_start`  :class:`RecordStartGrid`   None (every trial start's likelihood is computed)
========================== ===================== =====================================================

The extra harmonics enter as more harmonics of the force's template
(``record_harmonics``), the estimated floor mode starts from a grid of
frequencies and counts them (``record_starts``, ``record_search_size``); the frequencies are an ordered grid
(``record_grid_start``), so the search computes the likelihood at every other one and then around the best.

What an effect reads of the fit without it is a :class:`~smd_statespace.model.fitted.FittedRecord`
(:func:`fitted_record`), not the :class:`~smd_statespace.person.results.PersonResult`: the functions here
take the result and hand the effect that view.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol, runtime_checkable

from ..model.fitted import FittedRecord

if TYPE_CHECKING:  # annotations only
    from ..model import Effect, SMDModel
    from .results import PersonResult

__all__ = ["RecordHarmonics", "RecordSearchSize", "RecordStartGrid", "RecordStarts", "fitted_record",
           "record_grid_start", "record_harmonics", "record_search_size", "record_starts"]


@runtime_checkable
class RecordHarmonics(Protocol):
    """An effect that is more harmonics of the force: the record-level model takes them into its template."""

    def record_harmonics(self, model: "SMDModel") -> int:
        """How many harmonics of the force's template (varying from cycle to cycle like the others) it adds."""


@runtime_checkable
class RecordStarts(Protocol):
    """An effect whose parameters need trial starts (a floor mode's frequency over a grid)."""

    def record_starts(self, fitted: FittedRecord) -> list:
        """Candidate starting values of the effect's parameters, each a dict by slot name."""


@runtime_checkable
class RecordStartGrid(Protocol):
    """An effect whose trial starts end in an ordered grid of one parameter: neighbours give close likelihoods."""

    def record_grid_start(self) -> int:
        """Index, in :meth:`RecordStarts.record_starts`' list, of the grid's first point (the trials before it are
        one-off starts, each computed)."""


@runtime_checkable
class RecordSearchSize(Protocol):
    """An effect whose search tries many values of a parameter and keeps the best."""

    def record_search_size(self, fitted: FittedRecord | None) -> int:
        """How many separate trials the search makes (``diagnose`` multiplies the p-value by it)."""


def fitted_record(result: "PersonResult | FittedRecord") -> FittedRecord:
    """What an effect may read of ``result``, the person fitted without it (``result`` itself if it is one)."""
    if isinstance(result, FittedRecord):
        return result
    record = result.record
    return FittedRecord(time=record.time, floor_acc=getattr(record, "floor_acc", None),
                        predicted_displacement=lambda: result.predicted_path()[:, 0],
                        strongest_line=lambda: result.innovation_line(), f_h=float(result.f_h))


def record_harmonics(effect: "Effect", model: "SMDModel") -> int:
    """Force harmonics ``effect`` adds to the record-level model of ``model`` instead of parameters (default 0)."""
    return int(effect.record_harmonics(model)) if isinstance(effect, RecordHarmonics) else 0


def record_starts(effect: "Effect", result: "PersonResult") -> list:
    """Candidate starting values of ``effect``'s parameters for the record-level search (default: none).

    ``result`` is the :class:`~smd_statespace.person.results.PersonResult`
    without the effect. Each candidate is a dict of parameter values; the
    search starts from the one with the highest likelihood. Parameters not
    given start at 0 when their range holds 0 (the effect absent), else at
    their slot's nominal value.
    """
    return effect.record_starts(fitted_record(result)) if isinstance(effect, RecordStarts) else []


def record_grid_start(effect: "Effect") -> int | None:
    """Where the ordered grid begins in ``effect``'s trial starts (:func:`record_starts`), or None: no grid.

    On a grid the search computes the likelihood at every other point and then at the neighbours of the
    best of those (:func:`~smd_statespace.person.starts.grid_best`) instead of at every point.
    """
    return int(effect.record_grid_start()) if isinstance(effect, RecordStartGrid) else None


def record_search_size(effect: "Effect", result: "PersonResult") -> int:
    """How many separate trials the record-level search of ``effect``'s parameters makes (default 1).

    An effect whose parameter is found by trying many values (a floor
    mode's frequency over a grid) takes the best of them, so its likelihood
    ratio is the largest of that many: ``diagnose`` multiplies its p-value
    by this number (Bonferroni over the trials) before the test.
    """
    if not isinstance(effect, RecordSearchSize):
        return 1
    return int(effect.record_search_size(None if result is None else fitted_record(result)))
