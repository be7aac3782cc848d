"""Identify the person from a whole record: the record-level model.

One ``f_h``, one ``xi_h`` per record; the force's Fourier coefficients vary
from cycle to cycle around the person's template; noise levels by maximum
likelihood. Modules: :mod:`.timing` (force-cycle boundaries), :mod:`.dynamics`
(the person's dynamics from the one SMD model and its effects), :mod:`.model`
(the state-space model), :mod:`.kalman` (the compiled likelihood), :mod:`.score`
(its exact gradient), :mod:`.statespace` (the statsmodels twin), :mod:`.fit`
(:func:`identify_person`), :mod:`.extend` (the person with effects added),
:mod:`.diagnose` (which effect is missing), :mod:`.results` (:class:`PersonResult`), :mod:`.bouts` (a person
per bout of a session: :func:`identify_bouts`).
"""

from importlib import import_module
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the names as tools that read the source see them (the reference, type checkers)
    from .bouts import BoutAnswer, identify_bouts
    from .fit import identify_person
    from .model import RecordModel, Regressor
    from .results import PersonResult
    from .search import FitError
    from .timing import CycleTiming, estimate_timing

__all__ = ["identify_person", "identify_bouts", "BoutAnswer", "PersonResult", "RecordModel", "Regressor", "CycleTiming",
           "estimate_timing", "FitError"]

_HOMES = {"identify_person": ".fit", "identify_bouts": ".bouts", "BoutAnswer": ".bouts", "FitError": ".search",
          "RecordModel": ".model", "Regressor": ".model", "PersonResult": ".results", "CycleTiming": ".timing",
          "estimate_timing": ".timing"}
"""The module each public name comes from. They are imported when first asked for (PEP 562), so that importing
one light module of the package (the command line's parser reads :mod:`.noise_floor`'s defaults) does not load
the fit, scipy.stats and numba's compiled passes (about 1.7 s)."""


def __getattr__(name):
    if name not in _HOMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(import_module(_HOMES[name], __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
