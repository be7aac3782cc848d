"""Does the model fit this record, and if not, what is missing? Does the model apply at all?

======================= ======================================================
module                  what it holds
======================= ======================================================
:mod:`.check`           :class:`ModelCheck` (:func:`check_model`): free
                        simulation against the measurement, residual tests,
                        spectrum, phase profile, correlations, figures
:mod:`.missing`         :func:`diagnose`: refit with every candidate effect
                        and rank them (per-cycle identification)
:mod:`.applicability`   :func:`check_bouncing`: is the record bouncing at all
                        (refusals and warnings in words)
:mod:`.spectra`         Welch spectra, their degrees of freedom, peaks above
                        a false-alarm threshold with harmonic labels
:mod:`.correlation`     correlations of the residual with candidate terms,
                        over lags
:mod:`.phase`           phase-locked averages and the phase profile
:mod:`.subspace`        what a cycle's free force and initial state absorb
:mod:`.residual_tests`  Ljung-Box, Jarque-Bera, variance change, pooled ACF
:mod:`.free_simulation` the model run free from a fitted initial state
:mod:`.cycles`          the checked series, cycle by cycle
:mod:`.fit`             fit % and RMS
:mod:`.report`          the check's summary text
:mod:`.effect_adapter`  what the diagnosis asks of an effect (candidate,
                        score terms, notes), with defaults
======================= ======================================================

The record-level diagnosis is :mod:`smd_statespace.person.diagnose`.
"""

from ..applicability import BouncingCheck, Finding, NotBouncingError, check_bouncing
from .check import INITIAL_STATES, ModelCheck, check_model, fit_percent
from .missing import Candidate, Diagnosis, default_candidates, diagnose

__all__ = ["ModelCheck", "check_model", "fit_percent", "INITIAL_STATES", "Candidate", "Diagnosis",
           "default_candidates", "diagnose", "BouncingCheck", "Finding", "NotBouncingError", "check_bouncing"]
