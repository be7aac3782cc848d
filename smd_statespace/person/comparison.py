"""The variation models' comparison: each fit's likelihood, AIC, person, and whether it reached a search bound.

``identify_person`` fits several variation models (:func:`~smd_statespace.person.search.choose_with_own_timing`)
and keeps one; every fit is a row of ``result.comparison`` (:class:`VariationFit`), which the choice, the
intervals that span the models the record cannot rule out
(:func:`~smd_statespace.person.judgement.plausible_variations`) and ``person.json``'s ``variation_models`` read.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

__all__ = ["BOUND_REACH", "VariationFit", "aic", "comparison_row", "reaches_bound"]


BOUND_REACH = 1.645
"""Sds of ``f_h`` within which a search bound counts as reached (:func:`reaches_bound`: a 90 % Wald interval).

On a person bouncing on a 5 Hz floor (``tests/test_floor_measured_physics.py``), at 1 % BW noise,
"smooth" put ``f_h`` at 5.7 Hz (truth 2.5; interval 4.1-6.0 Hz, the bound), its force variation
standing in for the person, and won by AIC over "independent" (2.43 Hz): the same degenerate solution
that the bound rule below catches when it runs onto 6 Hz.
"""


@dataclass(frozen=True)
class VariationFit:
    """One variation model's fit, a row of ``result.comparison`` (``person.json``'s ``variation_models``).

    Attributes
    ----------
    variation : str
        The variation model (:data:`~smd_statespace.person.variation.VARIATIONS`).
    timing : {"first", "re-placed"}
        At which cycle starts: the first timing, or those the model re-placed with its own fit (its best fit
        when it stopped re-placing, for a model left far behind: :data:`~smd_statespace.person.search.BEHIND`).
    loglike : float
        Its log-likelihood.
    n_params : int
        Its searched parameters.
    aic : float
        ``2 n_params - 2 loglike``.
    converged : bool
        Whether its search converged.
    on_bound : bool
        ``f_h`` or ``xi_h`` on a search bound, or ``f_h``'s Wald interval reaching one (:func:`reaches_bound`).
    f_h, xi_h : float
        Its person (Hz, -).
    effects : tuple of str
        The effects in the model (their specs): a fit with effects compares the fits with the same effects only.
    """

    variation: str
    timing: str
    loglike: float
    n_params: int
    aic: float
    converged: bool
    on_bound: bool
    f_h: float
    xi_h: float
    effects: tuple = ()

    def to_dict(self) -> dict:
        """The row as JSON takes it (``effects`` a list)."""
        return {**asdict(self), "effects": list(self.effects)}


def comparison_row(model, fitted, timing, effects=()) -> VariationFit:
    """One variation model's fit in ``result.comparison``: its likelihood, AIC, person, and at which timing
    (:class:`VariationFit`)."""
    named = model.unpack(fitted["params"])
    on_bound = model.person_at_bound(fitted["params"]) or reaches_bound(model, fitted["params"])
    return VariationFit(variation=model.variation, timing=timing, loglike=float(fitted["loglike"]),
                        n_params=len(fitted["params"]), aic=aic(fitted),
                        converged=bool(fitted["converged"]), on_bound=bool(on_bound), f_h=float(named["f_h"]),
                        xi_h=float(named["xi_h"]), effects=tuple(effects))


def aic(fitted) -> float:
    """Akaike's criterion of a fit (``fit_model``'s dict): ``2 n_params - 2 loglike``."""
    return 2 * len(fitted["params"]) - 2 * float(fitted["loglike"])


def reaches_bound(model, params, z=BOUND_REACH) -> bool:
    """Whether ``f_h`` +- ``z`` sds (the profile information at ``params``) reaches a search bound of ``f_h``.

    Such a fit has not located ``f_h`` inside the physical range any more than one that sits on the
    bound: it counts as on it in the choice of variation model (:func:`choose_with_own_timing`). An
    information that cannot be inverted says nothing either way (False).
    """
    from .score import score

    information = score(model, params)["profile_information"]
    if not np.all(np.isfinite(information)):
        return False
    try:
        variance = float(np.linalg.inv(information)[0, 0])
    except np.linalg.LinAlgError:
        return False
    if not variance > 0.0:
        return False
    low, high = model.bound("f_h")
    f_h, reach = float(params[0]), z * math.sqrt(variance)
    return f_h + reach >= high or f_h - reach <= low
