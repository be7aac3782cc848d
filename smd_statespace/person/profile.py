"""Profile-likelihood intervals of ``f_h`` and ``xi_h`` (``intervals="profile"`` of
:func:`~smd_statespace.person.fit.identify_person`): the other parameters re-maximised at each trial value."""

from __future__ import annotations

import numpy as np
from scipy import optimize, stats

from .model import RecordModel

__all__ = ["profile_interval"]


def profile_interval(model: RecordModel, params, loglike, which, se, level=0.9):
    """Profile-likelihood interval of ``f_h`` (``which=0``) or ``xi_h`` (``which=1``).

    At each trial value the other parameters are re-maximised (warm start);
    the interval's ends are where twice the fall of the profile likelihood
    equals the chi-square(1) quantile of ``level``, found by bracketing and
    linear interpolation. An end that reaches the search bound is returned as
    the bound (the record does not exclude it).

    Returns
    -------
    tuple of float
        ``(low, high)``.
    """
    target = stats.chi2.ppf(level, 1) / 2.0
    bounds = model.bounds
    lo_bound, hi_bound = bounds[which]
    others = [i for i in range(len(params)) if i != which]
    sub_bounds = [bounds[i] for i in others]
    step = se if np.isfinite(se) and se > 0 else 0.05 * abs(params[which]) + 0.01
    ends = []
    for sign in (-1.0, 1.0):
        warm = np.asarray(params, dtype=float)[others]
        previous_value, previous_drop = params[which], 0.0
        value = params[which]
        found = None
        for k in range(12):
            value = float(np.clip(params[which] + sign * step * (1.2 + 0.6 * k), lo_bound, hi_bound))

            def negative(sub, v=value):
                full = np.empty(len(params))
                full[which] = v
                full[others] = sub
                out = model.loglike(full)
                return -out if np.isfinite(out) else 1e300

            res = optimize.minimize(negative, warm, method="L-BFGS-B", bounds=sub_bounds, options={"maxiter": 60})
            warm = res.x
            drop = loglike + res.fun
            if drop >= target:
                frac = (target - previous_drop) / max(drop - previous_drop, 1e-12)
                found = previous_value + frac * (value - previous_value)
                break
            if value in (lo_bound, hi_bound):
                found = value
                break
            previous_value, previous_drop = value, drop
        ends.append(found if found is not None else value)
    return tuple(ends)
