"""Identify the person from a whole record: the record-level model.

One ``f_h``, one ``xi_h`` per record; the force's Fourier coefficients vary
from cycle to cycle around the person's template; noise levels by maximum
likelihood. Modules: :mod:`.timing` (force-cycle boundaries), :mod:`.dynamics`
(the person's dynamics from the one SMD model and its effects), :mod:`.model`
(the state-space model), :mod:`.kalman` (the compiled likelihood), :mod:`.score`
(its exact gradient), :mod:`.statespace` (the statsmodels twin), :mod:`.fit`
(:func:`identify_person`), :mod:`.extend` (the person with effects added),
:mod:`.diagnose` (which effect is missing), :mod:`.results` (:class:`PersonResult`).
"""

from .fit import identify_person
from .search import FitError
from .model import RecordModel, Regressor
from .results import PersonResult
from .timing import CycleTiming, estimate_timing

__all__ = ["identify_person", "PersonResult", "RecordModel", "Regressor", "CycleTiming", "estimate_timing",
           "FitError"]
