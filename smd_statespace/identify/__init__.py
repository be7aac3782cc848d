"""Per-cycle identification of a record and of many records (the article's method, Section 3.2).

=================== ==========================================================
module              what it holds
=================== ==========================================================
:mod:`.runner`      :class:`CycleRunner`: one record, cycle by cycle, with
                    repeated passes and any estimator
:mod:`.batch`       :func:`run_batch`: many records, resumable, in parallel
:mod:`.plausibility` per-cycle estimates outside physical sense, flagged in words
=================== ==========================================================

The record-level identification of the person is :mod:`smd_statespace.person`.
"""

from .batch import run_batch
from .runner import CycleRunner, identify_cycle

__all__ = ["CycleRunner", "identify_cycle", "run_batch"]
