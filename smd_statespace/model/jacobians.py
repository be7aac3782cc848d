"""Jacobians that cannot be silently wrong: automatic by default, analytic ones checked, linearity verified.

The EKF, the grid reference and the Rao-Blackwellised particle filter use
the derivatives of the model's COM acceleration (Eq. 10) and of effects'
slot rates. An :class:`~smd_statespace.model.Effect` that gives only its
:meth:`~smd_statespace.model.Effect.acceleration` gets its Jacobian by
central differences of that very method (:func:`numeric_jacobian`,
vectorised over every leading axis: particles, sigma points, grid points).
An analytic Jacobian is faster; :func:`check_jacobians` compares it with the
automatic one at states drawn from the prior. :func:`check_linearity`
verifies what the slots declare: an estimator that Kalman-filters the
"linear" slots (grid, rbpf) needs the acceleration and rates to be affine in
them jointly, for fixed values of the others.

Examples
--------
>>> import numpy as np
>>> from smd_statespace.model.jacobians import numeric_jacobian
>>> numeric_jacobian(lambda z: z[..., 0] * z[..., 1], np.array([2.0, 3.0])).round(6)
array([3., 2.])
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..errors import OptionError

__all__ = ["JACOBIAN_STEP", "numeric_jacobian", "expand_time", "check_jacobians", "check_linearity"]

JACOBIAN_STEP = 6e-6
"""Central-difference step, relative to ``max(1, |x_j|)``: about the cube root of the float64
epsilon, which balances truncation (``h^2``) and rounding (``eps / h``) errors (relative error ~1e-10)."""

LINEARITY_TOLERANCE = 1e-6
"""Second difference (relative to the first) below which a function is taken as affine along a direction."""


def expand_time(t):
    """``t`` with an axis added for the perturbations when it is an array (a scalar stays)."""
    return np.asarray(t, dtype=float)[..., None] if np.ndim(t) else t


def numeric_jacobian(func, x):
    """Central-difference Jacobian of ``func`` at ``x``, vectorised over leading axes.

    Parameters
    ----------
    func : callable
        Takes states of shape ``(..., n)`` and returns ``(...)`` (a scalar
        per state) or ``(..., k)``; it is called on ``(..., n, n)``: every
        state perturbed along each coordinate.
    x : ndarray, shape (..., n)

    Returns
    -------
    ndarray
        ``(..., n)`` for a scalar function, ``(..., k, n)`` otherwise.
    """
    x = np.asarray(x, dtype=float)
    n = x.shape[-1]
    step = JACOBIAN_STEP * np.maximum(1.0, np.abs(x))  # (..., n)
    shift = np.eye(n) * step[..., :, None]  # (..., n, n): row j moves coordinate j
    plus = np.asarray(func(x[..., None, :] + shift), dtype=float)
    minus = np.asarray(func(x[..., None, :] - shift), dtype=float)
    difference = plus - minus
    if difference.ndim < x.ndim:  # a scalar function that returned one value for every state (a known constant's)
        difference = np.broadcast_to(difference, x.shape)
    if difference.ndim == x.ndim:  # scalar function: (..., n)
        return difference / (2.0 * step)
    return np.swapaxes(difference, -1, -2) / (2.0 * step[..., None, :])  # (..., k, n)


def _states(model, count, seed, scale):
    """``count`` states from the model's prior (parameters uniform, dynamic slots around zero)."""
    y0 = np.zeros(len(model.channels))
    prior = model.prior(y0, {name: scale for name in _scales(model)})
    return prior.sample(np.random.default_rng(seed), count)


def _scales(model):
    names = {slot.scale for slot in model.slots if slot.scale is not None}
    return names | set(model.channels)


def check_jacobians(model, inputs=None, t=0.1, states=8, seed=0, scale=1.0) -> pd.DataFrame:
    """Compare every analytic Jacobian of ``model`` with the automatic one at states from its prior.

    Parameters
    ----------
    model : SMDModel
    inputs : CycleInputs, optional
        The cycle's known inputs (default: ``f_b`` = 2 Hz, no signals; give
        the signals an effect requires).
    t : float
        Time (s) within the cycle.
    states : int
        States drawn from the prior (``seed``).
    scale : float
        Data scale of the dynamic slots' prior spread.

    Returns
    -------
    pandas.DataFrame
        One row per term (``model`` and each effect): ``acceleration`` and
        ``slot_rates`` columns hold the largest ``|analytic - automatic|``
        relative to ``1 + |automatic|`` (about 1e-8 when they agree), and
        ``ok`` is True when both are below 1e-5.
    """
    from .inputs import CycleInputs

    inputs = CycleInputs(f_b=2.0) if inputs is None else inputs
    x = _states(model, states, seed, scale)
    te = expand_time(t)
    rows = []

    def relative(analytic, automatic):
        return float(np.max(np.abs(analytic - automatic) / (1.0 + np.abs(automatic)))) if analytic.size else 0.0

    total = model.acceleration_jacobian(x, t, inputs)
    automatic = numeric_jacobian(lambda z: model.acceleration(z, te, inputs), x)
    rows.append({"term": "model (total)", "acceleration": relative(total, automatic),
                 "slot_rates": relative(model.rate_jacobian(x, t, inputs),
                                        numeric_jacobian(lambda z: model.rate(z, te, inputs), x))})
    for effect in model.effects:
        analytic = effect.acceleration_jacobian(model, x, t, inputs)
        automatic = numeric_jacobian(lambda z, e=effect: e.acceleration(model, z, te, inputs), x)
        rows.append({"term": effect.name, "acceleration": relative(analytic, automatic), "slot_rates": float("nan")})
    table = pd.DataFrame(rows).set_index("term")
    table["ok"] = table[["acceleration", "slot_rates"]].fillna(0.0).max(axis=1) < 1e-5
    return table


def check_linearity(model, inputs=None, t=0.1, states=4, seed=0, scale=1.0, raise_error=True) -> dict:
    """Verify that the model's rate is affine, jointly, in the slots declared linear.

    For states from the prior, the second difference ``r(x + d) - 2 r(x) +
    r(x - d)`` of the rate along each linear slot, and the mixed difference
    of each effect's linear slot with every other linear slot, must vanish
    (relative to the first difference plus ``|r(x)|``). The Kalman part of the grid
    reference and of the RBPF is exact only then; otherwise it linearises,
    like an EKF.

    Returns
    -------
    dict
        ``{slot_name: worst relative second difference}`` for every linear
        slot along which the rate is not affine (empty when the declaration
        holds). A base slot (``u``) appears when an effect's term is
        non-linear in it (a cubic spring): the estimators then say that their
        Kalman part is approximate.

    Raises
    ------
    OptionError
        With ``raise_error``, when an effect declares one of its own slots
        linear and the rate is not affine in it: the declaration is wrong.
    """
    from .inputs import CycleInputs

    inputs = CycleInputs(f_b=2.0) if inputs is None else inputs
    x = _states(model, states, seed, scale)
    linear = np.flatnonzero([slot.linear for slot in model.slots])
    size = np.maximum(1.0, np.abs(x).max(axis=0))
    owners = {slot.name: effect.name for effect in model.effects for slot in effect.slots(model)}
    names = [slot.name for slot in model.slots]
    mid = model.rate(x, t, inputs)

    def step(j):
        d = np.zeros(model.n_state)
        d[j] = 0.5 * size[j]
        return d

    def worst(second, first):
        return float(np.max(np.abs(second) / (np.abs(first) + np.abs(mid) + 1e-12)))

    failures = {}
    for j in linear:  # along one slot: r(x + d) - 2 r(x) + r(x - d)
        up, down = model.rate(x + step(j), t, inputs), model.rate(x - step(j), t, inputs)
        value = worst(up - 2.0 * mid + down, up - down)
        if value > LINEARITY_TOLERANCE:
            failures[names[j]] = value
    for j in (j for j in linear if names[j] in owners):  # an effect's slot times another linear slot
        for k in linear:
            if k == j:
                continue
            a, b = step(j), step(k)
            rates = [model.rate(x + sa * a + sb * b, t, inputs) for sa, sb in ((1, 1), (1, -1), (-1, 1), (-1, -1))]
            value = worst(rates[0] - rates[1] - rates[2] + rates[3], rates[0] - rates[3])
            if value > LINEARITY_TOLERANCE:
                failures[names[j]] = max(value, failures.get(names[j], 0.0))
    declared = [name for name in failures if name in owners]
    if declared and raise_error:
        named = ", ".join(f"{name} ({owners[name]})" for name in declared)
        raise OptionError(f"slot(s) {named} are declared linear but the model's rate is not linear in them (a term "
                          "such as c u'|u'| multiplies two linear slots); declare them linear=False")
    return failures
