"""The one rule for calling a parameter *determined*, whichever estimator answers.

A record determines a parameter when it has narrowed what was known before it at least fourfold: the
parameter's sd is below :data:`DETERMINED_FRACTION` of its prior sd. Per bouncing cycle
(:mod:`smd_statespace.identify.runner`) the sd is the filter's posterior sd and the prior sd the
initial ensemble's (their ratio is the table's ``*_width_ratio``); for the record-level person
(:mod:`smd_statespace.person.judgement`) the sd is the standard error and the prior sd that of the
article's uniform initial range (``PRIOR_SD``: ``f_h`` 1-4 Hz, ``xi_h`` 0-1). A parameter that is not
determined is printed with its interval and said to be not determined, never as a bare number.
"""

from __future__ import annotations

__all__ = ["DETERMINED_FRACTION"]

DETERMINED_FRACTION = 0.25
"""A parameter is determined when its sd is below this fraction of its prior sd."""
