"""When the record-level answer is not to be read as a number: the thresholds and rules, with their evidence.

A parameter is *determined* when its sd is a small fraction of a yardstick
(:data:`PRIOR_SD`, :data:`DETERMINED_FRACTION`); the model *misfits* when a
measurable share of the signal is left predictable in its innovations
(:data:`MISFIT_SHARE`); a resonance at the bouncing frequency or one of its
multiples can stand in for the force (:func:`stands_in_for_force`); variation
models the record cannot rule out may disagree (:data:`VARIATION_AIC_CLOSE`,
:data:`VARIATION_DISAGREEMENT`). :class:`~smd_statespace.person.results.PersonResult`
applies them; its report (:mod:`~smd_statespace.person.report`) says them in words.
"""

from __future__ import annotations

import numpy as np

from ..determined import DETERMINED_FRACTION

__all__ = ["DETERMINED_FRACTION", "F_B_COINCIDENCE", "MISFIT_SHARE", "PRIOR_SD", "STARTING_RANGE",
           "VARIATION_AIC_CLOSE", "VARIATION_DISAGREEMENT", "WHITENESS_ALPHA", "XI_H_RESONANCE_MIMIC",
           "mimicked_harmonic", "narrowed", "plausible_variations", "stands_in_for_force", "variation_disagreement"]

STARTING_RANGE = {"f_h": (1.0, 4.0), "xi_h": (0.0, 1.0)}
"""The article's uniform initial ranges of ``f_h`` (Hz) and ``xi_h`` (its estimation settings, Sections 3.2 and 4;
:class:`~smd_statespace.model.SMDModel`'s default ``f_h_range`` and ``xi_h_range``)."""

PRIOR_SD = {name: (high - low) / np.sqrt(12.0) for name, (low, high) in STARTING_RANGE.items()}
"""Yardstick widths: the sd of the article's uniform initial ranges (:data:`STARTING_RANGE`)."""


def narrowed(sd: float, name: str) -> bool:
    """True when the sd of ``f_h`` or ``xi_h`` is below :data:`DETERMINED_FRACTION` of its yardstick
    (:data:`PRIOR_SD`): the record narrowed what was known before it fourfold (:mod:`smd_statespace.determined`)."""
    return bool(np.isfinite(sd) and sd < DETERMINED_FRACTION * PRIOR_SD[name])


WHITENESS_ALPHA = 0.01
"""Level at which the Ljung-Box test's rejection is reported as a warning."""

F_B_COINCIDENCE = 0.05
"""With the smooth variation, an ``f_h`` within this fraction of the bouncing frequency is not determined.

A person resonating at ``f_b`` with little damping turns white noise into a
slow modulation of the force's first harmonic: the same signal as a smooth
drift of that harmonic. On the smooth generator (docs/person-benchmark.md,
seed 2024) 10 of 50 estimates ended within 5 % of ``f_b`` with a median error
of 16 % (none of the true values was there; the other 40 records: 7 %); on
records whose force jumps per cycle this did not happen (1 of 50, error 1 %).

With any variation model, a lightly damped ``f_h`` there or at a multiple ``i f_b`` (``xi_h``
below :data:`XI_H_RESONANCE_MIMIC`) is not determined either: an undamped resonance then
stands in for the force's harmonic ``i`` (its BLF near 0). On a
record from a generator outside this project (truth ``f_h`` 2.91 Hz = 1.19
``f_b``, ``xi_h`` 0.44) both variation models ended at ``f_h`` 2.44-2.52 Hz,
``xi_h`` 0.001-0.04, ``BLF1`` 0.002-0.007 g against 0.17 g
(``../shared/findings/person-unseen-records.md``).
"""

MISFIT_SHARE = 0.003
"""Size of what the model misses, as a share of the signal, above which ``f_h`` and ``xi_h`` are not determined.

The share (:attr:`PersonResult.misfit_share`) is the RMS of the part of the one-step
innovations that their own past predicts (a least-squares autoregression over one
cycle's lags, its R² less the L/N an autoregression reaches on white noise), over
the RMS of the measured acceleration. A model that misses part of the force or
of the physics puts it into ``f_h`` and ``xi_h`` (a hidden cubic spring:
``f_h`` +24 %, docs/tutorial-missing-physics.md), and its information-based
interval does not know it; their intervals then take the yardstick's width
until the missing effect is in the model.

Why a size and not the Ljung-Box p-value: on a quiet clean record of the
jumps generator (40 s, 0.2 % BW noise) Ljung-Box gives p 1e-23 with ``f_h``
3.6 % off, and the share is 0; on pulse-train records (``f_h`` 22-52 % off)
it was 1.3-3.1 %, with the tutorial's hidden cubic spring (``f_h`` +24 %)
0.4 %, on clean records of 1 % BW noise 0 (R² at the chance level: at 1 % BW
noise, a share at the chance correction's edge is about 0.2 %). Chosen on
these few records; checked on 117 others (docs/person-benchmark-generators.md,
24 per generator): pulse trains 24 of 24 above it (``f_h`` coverage 46 -> 92 %),
jittered coefficients 6 of 24, the jumps, smooth and tempo generators none (largest
0.30 %: the threshold sits at the top of what the model's own generators give).
"""

VARIATION_DISAGREEMENT = 0.10
"""Relative difference of ``f_h`` between the variation models (at the final cycle starts) that is reported."""

VARIATION_AIC_CLOSE = 10.0
"""AIC difference below which a variation model is not ruled out by the record (Burnham & Anderson: above 10,
essentially no support)."""

XI_H_RESONANCE_MIMIC = 0.08
"""Below this damping ratio an ``f_h`` within :data:`F_B_COINCIDENCE` of ``f_b`` is not determined, whatever
the variation model (bouncing people show 0.1-0.6, the article's Table 2)."""


def mimicked_harmonic(f_h, xi_h, f_b, n_harmonics) -> int:
    """The force harmonic ``i`` (1 ... ``n_harmonics``) an undamped resonance at ``f_h`` stands in for, 0 when none:
    ``f_h`` within :data:`F_B_COINCIDENCE` of ``i f_b`` with ``xi_h`` below :data:`XI_H_RESONANCE_MIMIC`."""
    if xi_h >= XI_H_RESONANCE_MIMIC:
        return 0
    order = int(round(f_h / f_b))
    return order if 1 <= order <= n_harmonics and abs(f_h / (order * f_b) - 1.0) < F_B_COINCIDENCE else 0


def stands_in_for_force(f_h, xi_h, f_b, n_harmonics, variation) -> bool:
    """True where a resonance cannot be told from the force: ``f_h`` within :data:`F_B_COINCIDENCE` of ``f_b``
    with the smooth variation, or a mimicked harmonic (:func:`mimicked_harmonic`) with any."""
    near = abs(f_h / f_b - 1.0) < F_B_COINCIDENCE
    return (near and variation == "smooth") or mimicked_harmonic(f_h, xi_h, f_b, n_harmonics) > 0


def variation_disagreement(result) -> str:
    """In words, when variation models fitted at the final cycle starts that the record cannot rule out (AIC
    within :data:`VARIATION_AIC_CLOSE` of the best) put ``f_h`` more than :data:`VARIATION_DISAGREEMENT` apart
    (empty otherwise): the answer then depends on how the force is assumed to vary."""
    rows = result.plausible_variations()
    if len(rows) < 2:
        return ""
    values = [row.f_h for row in rows]
    if max(values) <= (1.0 + VARIATION_DISAGREEMENT) * min(values):
        return ""
    best = min(row.aic for row in rows)
    parts = ", ".join(f"{row.variation} {row.f_h:.3g} Hz (AIC {row.aic - best:+.1f})" for row in rows)
    spans = " (the interval spans them)" if result.interval_method.startswith("calibrated") else ""
    return (f"the variation models disagree on f_h: {parts}; f_h depends on how the force is assumed to vary "
            f"between cycles, which the record does not settle{spans}: read the interval, not the value, or "
            "fix the model with --variation")


def plausible_variations(result) -> list:
    """The variation models' fits at the final cycle starts (rows of the result's ``comparison``) the record cannot
    rule out: converged, ``f_h`` and ``xi_h`` off their search bounds and not a resonance standing in for
    the force (as the result's ``at_bouncing_frequency``), AIC within :data:`VARIATION_AIC_CLOSE` of the best of them.
    For a fit with effects, the fits with the same effects only (none when its cycle starts were kept from
    the person without them: :func:`~smd_statespace.person.extend.fit_effects` with ``timing=False``)."""
    specs = tuple(effect.spec for effect in result.effects)
    f_b = float(np.median(result.model.timing.f_b))
    rows = [row for row in result.comparison if row.timing == "re-placed" and row.converged and row.effects == specs
            and not row.on_bound and row.xi_h <= 1.0
            and not stands_in_for_force(row.f_h, row.xi_h, f_b, result.model.n_harmonics, row.variation)]
    best = min((row.aic for row in rows), default=0.0)
    return [row for row in rows if row.aic - best < VARIATION_AIC_CLOSE]
