"""From a measured ground reaction force to centre-of-mass motion, cycle by cycle.

This module is the pre-processing stage of Wang, Chen & Nagayama (2019),
Sections 3.2 and 4. It turns one person's vertical ground reaction force (GRF)
into the observations the estimators need, ``Y = [u, u_dot, u_ddot]`` (Eq. 13),
and splits the record into bouncing cycles:

1. **COM acceleration** (Eq. 3): ``u_ddot = (GRF - M_h g) / M_h`` with the body
   mass ``M_h`` measured beforehand (:func:`com_acceleration`).
2. **High-pass** the acceleration at 0.5 Hz with a zero-phase Butterworth filter
   (:func:`highpass`), removing the offset left by an imprecise mass or a
   drifting insole.
3. **Integrate** once for the velocity ``u_dot`` and again for the displacement
   ``u``: cumulative trapezoidal rule, each followed by the same zero-phase
   high-pass to remove the integration constants and drift (:func:`integrate`).
   Pipeline: ``acc --highpass--> acc_hp --integrate--> vel --integrate--> disp``.
4. **Cycles**: the record is split at GRF peaks, one cycle from one peak to the
   next (:func:`find_cycles`); consecutive cycles share their boundary sample.

Every estimator works at most at about :data:`RECORD_RATE`: a faster record is
low-pass filtered and decimated first (:func:`decimate_record`). The record-level
model (:mod:`smd_statespace.person`) then takes the force itself.

:func:`preprocess` runs all four steps on a :class:`~smd_statespace.io.Record`
and returns a :class:`Preprocessed` holding every intermediate signal, so that
each step can be inspected, tabulated and plotted. A floor acceleration, when
the record has one, is high-passed and integrated the same way (it drives the
moving-floor model of Section 6).

A lab's export (standing before and after, ramps, mains hum, a drifting zero) is made ready by
:mod:`.frontend` (:func:`mains_hum`, :func:`remove_hum`, :func:`find_bouts`, :func:`trim_record`,
:func:`front_end`); :mod:`.preparation` (:func:`prepare_record`) is what the record-level fit does with it.

Modules: :mod:`.decimation` (:func:`decimate_record`, :data:`RECORD_RATE`), :mod:`.filters`
(Eq. 3, :func:`highpass`, :func:`integrate`, :func:`motion`), :mod:`.cycles` (:func:`find_cycles`,
:class:`Cycle`), :mod:`.pipeline` (:func:`preprocess`, :class:`Preprocessed`); every public name
is importable from ``smd_statespace.signals``.

Two numerical facts worth knowing, both measured on synthetic records:

* **Record ends.** ``scipy.signal.sosfiltfilt`` with its default padding (odd
  reflection of 15 samples) leaves start-up transients that decay with the
  filter's slowest pole (time constant about 0.8 s at a 0.5 Hz cut-off). On
  synthetic bouncing records at 1.5-3.5 Hz, 2 s from either end, that left
  velocity errors of 15-45 % and displacement errors of 60-200 % of their RMS
  (still 6-25 % for the displacement 5 s in). The default
  ``padding="predict"`` instead removes the linear trend and extends each end
  by linear prediction (a Yule-Walker autoregressive model fitted to the
  nearest 10 s), which brings these to at most 0.4 % and 2.2 % at 2 s, and
  1.2 % and 4.6 % at 1 s. :func:`preprocess` flags the cycles closer than
  ``edge_margin`` (default 2 s) to either end.
* **Trapezoidal integration** scales a component of frequency ``f`` by
  ``x / tan(x)``, ``x = pi f / fs``: at 100 Hz sampling it loses 0.4 % at
  3.5 Hz and 6.6 % at 14 Hz per integration (the phase is exact).
"""

from .cycles import MIN_FORCE_RANGE, PEAK_PROMINENCE, PEAK_SPACING, PERIOD_RATIO_LIMITS, SUPPORTED_FB, Cycle, find_cycles
from .decimation import (GUARD_BAND, RATE_SLACK, RECORD_RATE, check_rate, decimate_record, decimation_factor,
                         decimation_note)
from .frontend import (ACTIVE_LEVEL, HUM_HIGHPASS, HUM_WINDOW, LINE_RATIO, MAINS, MAX_RAMP_CYCLES,
                       MIN_BOUT_CYCLES, STEADY_SWING, Bout, Bouts, FrontEnd, Hum, Span, find_bouts, front_end,
                       mains_hum, remove_hum, trim_record)
from .filters import PADDINGS, com_acceleration, highpass, integrate, motion
from .pipeline import OBSERVATION_CHANNELS, Preprocessed, preprocess
from .preparation import HUM_MARGIN, MASS_TOLERANCE, PreparedRecord, parse_span, prepare_record, safe_factor

__all__ = [
    "SUPPORTED_FB",
    "RECORD_RATE",
    "check_rate",
    "decimate_record",
    "decimation_factor",
    "decimation_note",
    "RATE_SLACK",
    "GUARD_BAND",
    "MAX_RAMP_CYCLES",
    "Hum",
    "Span",
    "Bout",
    "Bouts",
    "FrontEnd",
    "mains_hum",
    "remove_hum",
    "find_bouts",
    "trim_record",
    "HUM_MARGIN",
    "MASS_TOLERANCE",
    "PreparedRecord",
    "parse_span",
    "prepare_record",
    "safe_factor",
    "front_end",
    "MAINS",
    "LINE_RATIO",
    "HUM_WINDOW",
    "HUM_HIGHPASS",
    "ACTIVE_LEVEL",
    "STEADY_SWING",
    "MIN_BOUT_CYCLES",
    "OBSERVATION_CHANNELS",
    "PADDINGS",
    "Cycle",
    "Preprocessed",
    "com_acceleration",
    "highpass",
    "integrate",
    "motion",
    "find_cycles",
    "preprocess",
    "PEAK_PROMINENCE",
    "PEAK_SPACING",
    "MIN_FORCE_RANGE",
    "PERIOD_RATIO_LIMITS",
]
