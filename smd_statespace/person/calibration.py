"""The calibration of the record-level person's intervals: factors on the standard errors and model-error floors.

Measured with ``benchmarks/person_calibration.py`` (docs/person-calibration.md); used by
:func:`~smd_statespace.person.answer.person_result` and by
:class:`~smd_statespace.person.results.PersonResult` (the BLF intervals).
"""

from __future__ import annotations

from scipy import stats

__all__ = ["CALIBRATION", "EFFECT_CALIBRATION", "MODEL_ERROR_FLOOR", "model_error_floor", "wald_interval"]


CALIBRATION = {"independent": {"f_h": 2.75, "xi_h": 2.72}, "smooth": {"f_h": 3.29, "xi_h": 1.68},
               "random_walk": {"f_h": 3.01, "xi_h": 2.48}, "both": {"f_h": 3.01, "xi_h": 2.48}}
"""Factors on the standard errors of ``f_h`` and ``xi_h`` for ``intervals="calibrated"`` (the default).

The observed information ignores the error of the cycle timing and what the
model misses, so its intervals are too narrow. Each factor is the 90th
percentile of ``|estimate - truth| / sd`` over simulated records, divided by
1.645, for the variation model that ``variation="auto"`` chose on them, over the
records whose parameter nothing but its sd could leave undetermined (not a misfit,
not an artefact): measured with ``benchmarks/person_calibration.py`` on the rows of
``benchmarks/person_accuracy.py`` runs with all five generators of force variation
(jumps, smooth, coefficients, pulses, tempo), 30 s at 100 Hz, at 1 % BW noise (seed
2027, 40 records each) and 0.3 % BW (seed 2028, 24 each): 504 records, "independent"
chosen on 280, "smooth" on 224 (docs/person-calibration.md).
"random_walk" and "both" were not measured: they take the pooled factors. The factors
before (1.89, 2.63 and 3.21, 1.96) were measured on the jumps and smooth generators
alone at 1 % BW, with an earlier search. The factors multiply the sds of the default covariance
(:data:`~smd_statespace.person.search.WIDER_SANDWICH`: the observed information's, raised to the sandwich's
where that is wider); they were measured on the observed information's, which on these records the sandwich
equals within a few per cent (0.87-1.14 times, median 1.04, on 40 clean records of ``benchmarks/lab_records.py``
seed 4346).
"""


EFFECT_CALIBRATION = 1.6
"""Factor on the standard error of every effect parameter in its ``intervals="calibrated"`` interval (the default).

The effects' parameters had Wald intervals from the observed information alone: on simulated people with a hidden
effect and that effect added as ``identify --effect`` adds it, their 90 % intervals held the truth on 88 of 112
records of seed 92 (79 %) and 79 of 114 of seed 93 (69 %) (``benchmarks/effect_intervals.py --records 6``: a spring
stiffer on one side, damping growing with speed, a cubic spring, a drift and a step of ``f_h``, each small and
large, the ``jumps`` and ``smooth`` generators; records fitted whole with the truth in the search range). The
misses are biased estimates (the large drifts' and steps' z means -0.3 to -1.9, shrunk toward none), not a wrong
curvature: the cycle-clustered sandwich was within about 10 % of the information's sd (median ratio 0.90-1.10 per
row), and for a nonlinear term the curvature with its path settled again at each point equalled the fixed path's.
The factor is the 90th percentile of ``|estimate - truth| / sd`` over the 226 records of both seeds, over 1.645
(1.62 for the time terms, whose likelihood is exact, 1.55 for the nonlinear ones; each seed alone would choose 1.48
and 1.90: the factor is known to about 0.2). With it each seed's intervals hold the truth on 94 % and 86 %.
It widens the interval only: the sd says what the likelihood determines, and ``diagnose``'s rules read it (an
effect within two sds of none is not proposed)."""


MODEL_ERROR_FLOOR = {"independent": {"f_h": 0.035, "xi_h": 0.015}, "smooth": {"f_h": 0.08, "xi_h": 0.08},
                     "random_walk": {"f_h": 0.08, "xi_h": 0.08}, "both": {"f_h": 0.08, "xi_h": 0.08}}
"""Standard deviations added (in quadrature) to the calibrated ones in the intervals, per variation model: relative
to ``f_h`` for ``f_h`` (3.5 % and 8 %), absolute for ``xi_h``.

Only the intervals widen; the standard errors (``result.se``, and whether a parameter is
determined) stay what the record's information says.

The floor stands for the model error of a generator of force variation not yet seen. It
is sized by leaving one generator out at a time: :data:`CALIBRATION`'s factors measured
on the other four, the floor each variation model needs for the left-out generator's
records of it to be covered at 90 % at both noise levels; the largest need over the five
generators is the floor (``person_calibration.held_out_floors``). "independent" needs
3.5 % of ``f_h`` and 0.015 of ``xi_h`` (for the coefficients and jumps generators), "smooth"
8 % and 0.08 (for the smooth generator: the others' smooth fits are better than its own).
A generator unlike all others is not covered by it: with the smooth generator left out,
the floor measured on the other four (none of which asks for a smooth floor) covers its
``f_h`` on 74-79 %. "random_walk" and "both" take the larger floors.

The floor before (6 % and 0.05 for every variation model) was chosen on quiet records of
two generators; on records with 1 % BW noise it made the intervals of the well-fitted
generators too wide (coverage 97-100 %).
"""


def model_error_floor(name: str, f_h: float, variation: str) -> float:
    """The sd :data:`MODEL_ERROR_FLOOR` adds to ``name``'s calibrated one for a fit with ``variation``'s model of
    the force's variation: relative for ``f_h`` (Hz), absolute for ``xi_h``."""
    return MODEL_ERROR_FLOOR[variation][name] * (f_h if name == "f_h" else 1.0)


def wald_interval(estimate, standard_error, level, bounds) -> tuple:
    """Estimate +- z * standard error, cut at the parameter's search bounds.

    A damping ratio cannot be negative, nor ``f_h`` leave its search range: where the
    symmetric interval reaches past a bound, it ends at the bound (the values cut off are
    impossible, so the coverage is unchanged).

    Parameters
    ----------
    estimate, standard_error : float
    level : float
        Confidence level in (0, 1); ``z`` is the standard normal's ``0.5 + level / 2`` quantile.
    bounds : (float, float)
        Lowest and highest possible value.

    Examples
    --------
    >>> wald_interval(0.05, 0.1, 0.9, (1e-3, 3.0))  # doctest: +ELLIPSIS
    (0.001, 0.214...)
    """
    z = stats.norm.ppf(0.5 + level / 2.0)
    low, high = bounds
    return (float(max(low, estimate - z * standard_error)), float(min(high, estimate + z * standard_error)))
