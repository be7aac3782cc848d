"""The p-value of the largest of many statistics: a step tested at every time and the largest kept.

A step of ``f_h`` or ``xi_h`` placed where its score statistic is largest (:mod:`~smd_statespace.person.breaks`)
is the largest of many tests, and is not chi-square(1): under "no step", the LM statistic of a step at the
fraction ``pi`` of the record behaves as ``B(pi)^2 / (pi (1 - pi))`` with ``B`` a Brownian bridge, and its
largest over the fractions ``[trim, 1 - trim]`` has the distribution Andrews (1993, *Econometrica* 61, 821-856)
tabulates. Its tail has the closed form of Estrella (2003, *Econometric Theory* 19, 1128-1143, after DeLong 1981)::

    P(sup > c^2) ~ c phi(c) [(1 - 1/c^2) log(lambda) + 4/c^2],   lambda = ((1 - trim) / trim)^2

which gives Andrews' 5 % point at trim 0.15, 8.85, where chi-square(1)'s is 3.84 (checked against simulated
bridges in ``tests/test_person_breaks.py``). Every test of such a step (its score test, its quick fit, its full
fit in ``diagnose``) refers to it: :func:`log_p_value` knows the effects a scan placed by their ``scan``.
"""

from __future__ import annotations

import math

from scipy import optimize, stats

__all__ = ["log_sup_p_value", "sup_p_value", "log_p_value", "scan_trim", "critical_value"]


def log_sup_p_value(statistic, trim: float) -> float:
    """Log of the asymptotic p-value of the largest of the LM (or likelihood-ratio) statistics of one
    coefficient's step over the times between ``trim`` and ``1 - trim`` of the record (Andrews 1993, one
    restriction): ``P(sup > c^2) ~ c phi(c) [(1 - 1/c^2) log(lambda) + 4/c^2]`` with
    ``lambda = ((1 - trim) / trim)^2`` (Estrella 2003); at most 0."""
    statistic = float(statistic)
    if not statistic > 1.0:  # below 1 the expansion is no longer a probability; such a maximum is no evidence
        return 0.0
    c = math.sqrt(statistic)
    bracket = (1.0 - 1.0 / statistic) * math.log(((1.0 - trim) / trim) ** 2) + 4.0 / statistic
    return min(math.log(c) + float(stats.norm.logpdf(c)) + math.log(bracket), 0.0)


def sup_p_value(statistic, trim: float) -> float:
    """:func:`log_sup_p_value` as a p-value.

    >>> round(sup_p_value(8.85, 0.15), 3)  # Andrews' (1993) 5 % critical value at trim 0.15
    0.05
    """
    return math.exp(log_sup_p_value(statistic, trim))


def log_p_value(statistic, df: int, effects) -> float:
    """Log p-value of a (scaled) likelihood-ratio or score ``statistic`` on ``df`` for adding ``effects``:
    chi-square(``df``), or for one step whose time a scan found (``effect.scan``) the largest of the scan's
    (:func:`log_sup_p_value`)."""
    trim = scan_trim(effects)
    if not math.isnan(trim) and df == 1:
        return log_sup_p_value(statistic, trim)
    return float(stats.chi2.logsf(max(float(statistic), 0.0), max(int(df), 1)))


def scan_trim(effects) -> float:
    """The trimming of the scan that placed a step among ``effects`` (NaN when none did): what
    :func:`critical_value` and :func:`log_p_value` need to know of them."""
    scanned = [effect.scan["trim"] for effect in effects if getattr(effect, "scan", None)]
    return float(scanned[0]) if scanned else math.nan


def critical_value(p: float, df: int = 1, trim: float = math.nan) -> float:
    """The statistic whose p-value is ``p``: chi-square(``df``)'s ``1 - p`` point, or with a scan's ``trim``
    (:func:`scan_trim`; one parameter) the largest-of-the-scan's (Andrews' 5 % point 8.85 at trim 0.15, where
    chi-square(1)'s is 3.84).

    >>> round(critical_value(0.05), 2), round(critical_value(0.05, trim=0.15), 1)
    (3.84, 8.9)
    """
    if math.isnan(trim) or df != 1:
        return float(stats.chi2.isf(p, max(int(df), 1)))
    target = math.log(p)
    return float(optimize.brentq(lambda x: log_sup_p_value(x, trim) - target, 1.0 + 1e-9, 1e4))
