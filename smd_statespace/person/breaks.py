"""When does the person change? A step of ``f_h`` or ``xi_h`` placed at every sample, score-tested from one pass.

The library's step terms (``f_step``, ``xi_step`` of :data:`~smd_statespace.effects.generic.TERMS`) need a time.
At a fixed time (a third, a half, two thirds of the record) a true step a fraction of a cycle away is found only
in part: in the cycle between the two times the model's leg has the wrong stiffness while it is compressed, and
that one cycle's misfit is as large as the step. On a lab export whose ``f_h`` steps 16 % (``benchmarks/
person_effects.py``, seed 92, ``term_f_step`` large, record 2), the step tested 82 ms after the truth scored
LM 131 against 369 at the truth, and its quick fit's misspecification scale
(:func:`~smd_statespace.person.robust.robust_scale`) was 19.8, one cycle's scores dominating the rest: the
step's evidence divided by 20.

:func:`step_scan` tests a step at every sample of the middle of the record instead (Andrews 1993,
*Econometrica* 61, 821-856: the supremum of the LM statistics over the candidate times, here as score tests at
the fitted person). It costs one forward-sensitivity pass for all of them: at ``c = 0`` the derivative of the
system's arrays with respect to a step's coefficient at sample ``k`` is, at every sample, the derivative of a
change of stiffness (damping) over the whole record, ``-1/2`` of it before ``k`` and ``+1/2`` from ``k`` on
(Eq. 2's spring ``w_h^2 r`` or damper ``2 xi_h w_h r'`` times ``H(t - t_k) - 1/2``). Two reference
derivatives (a step at 0.3 and at 0.7 of the record, each between two samples) give that per-sample derivative
exactly, every sample covered by one of them, and the pass carries a column per candidate time
(:func:`~smd_statespace.person.score.score` with given ``derivatives``). Each column is the score test of
:func:`~smd_statespace.person.screen.score_test` at that time, to rounding (tested).

The largest statistic is not chi-square(1): it is the largest of many. Its p-value is that of the supremum of a
squared standardised Brownian bridge over the trimmed fractions ``[trim, 1 - trim]`` (Andrews 1993), in the
closed form of Estrella (2003, *Econometric Theory* 19, 1128-1143, after DeLong 1981):
:func:`~smd_statespace.person.supremum.sup_p_value`.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..effects.generic import GenericTerm
from .extend import at_zero
from .score import cycle_sums, profile_out, score, system_derivatives
from .supremum import sup_p_value

__all__ = ["TRIM", "CHUNK", "STRIDE", "PEAKS", "step_scan", "located_step", "fitted_span", "short_fraction"]

TRIM = 0.15
"""A step is looked for from this fraction of the fitted record to one minus it (Andrews' trimming, ``pi_0``):
nearer an end, too few cycles are on one side to tell a step from the start or end of the record."""

CHUNK = 96
"""Candidate times per sensitivity pass (each pass holds their derivative arrays: about 0.6 MB each on a 30 s
record at 100 Hz)."""

STRIDE = 4
"""The scan tests a step at every this many samples first, then at every sample around its :data:`PEAKS` largest
statistics (a step a sample from the truth scores 10-25 % less, one a cycle away several times less)."""

PEAKS = 3
"""How many of the first pass's largest statistics are looked at sample by sample."""

_ARRAYS = ("d_hx", "d_Phi", "d_Gam", "d_offset", "d_X_tr", "d_y")
"""The per-sample derivative arrays of :func:`~smd_statespace.person.score.system_derivatives` a step changes."""

_TRANSITIONS = ("d_Phi", "d_Gam", "d_offset", "d_X_tr")
"""Those of them that take sample ``i`` to ``i + 1``: the path-linearised dynamics use the rates' Jacobians at both
ends (:mod:`~smd_statespace.person.dynamics`), so a step at a sample gives the interval before it half of each
side's derivative (0); the others are at the sample."""


def _reference(result, kind, at_sample) -> tuple:
    """``(model, params, j, derivatives, t_s)``: the model with a ``kind`` step halfway between sample
    ``at_sample`` and the next, at ``c = 0``, and the derivatives of its arrays."""
    time = result.model.time
    start, length = float(time[0]), float(time[-1] - time[0])
    moment = 0.5 * (time[at_sample] + time[at_sample + 1])
    model, params, j = at_zero(result, GenericTerm(kind, scale=length, start=start, at=(moment - start) / length))
    return model, params, j, system_derivatives(model, params), moment


def _unit_derivatives(result, kind) -> tuple:
    """The model of a ``kind`` step at ``c = 0``, its parameters, the step's index and derivatives, and the
    per-sample derivative of the arrays for a change of the stiffness (damping) over the whole record (twice a
    step's after it, minus twice before)."""
    time = result.model.time
    references = [_reference(result, kind, int(round(fraction * (time.size - 2)))) for fraction in (0.3, 0.7)]
    model, params, j, derivatives, _ = references[0]
    if np.any(derivatives["d_Qx"][j]):
        raise ValueError(f"{kind}: the process noise changes with the step; the scan takes a noise that does not")
    unit = {}
    for key in _ARRAYS:
        parts = []
        for _, _, jr, der, moment in references:
            sign = np.where(time >= moment, 2.0, -2.0).reshape((-1,) + (1,) * (der[key].ndim - 2))
            parts.append(sign * der[key][der["dyn"][jr]])
        straddled = np.flatnonzero((time[:-1] < references[0][4]) & (time[1:] > references[0][4]))
        parts[0][straddled] = parts[1][straddled]  # where the first reference's step falls inside a sample
        unit[key] = parts[0]
    return model, params, j, derivatives, unit


def _chunk_derivatives(derivatives, j, unit, samples, time) -> dict:
    """``derivatives`` with parameter ``j`` replaced by one step per sample of ``samples`` (at that sample's
    time, the sample itself after it, the interval before it half on each side: :data:`_TRANSITIONS`)."""
    keep = [i for i in range(derivatives["dyn"].size) if i != j]
    dynamic = [derivatives["dyn"][i] for i in keep if derivatives["dyn"][i] >= 0]
    n_dynamic, m = len(dynamic), len(samples)
    out = {key: np.concatenate([value[keep], np.zeros((m,) + value.shape[1:])])
           for key, value in derivatives.items() if key not in _ARRAYS and key != "dyn"}
    out["dyn"] = np.concatenate([np.cumsum(derivatives["dyn"][keep] >= 0) - 1, n_dynamic + np.arange(m)])
    out["dyn"][:len(keep)][derivatives["dyn"][keep] < 0] = -1
    after = np.where(np.arange(time.size)[None, :] >= np.asarray(samples)[:, None], 0.5, -0.5)  # (m, N)
    interval = 0.5 * (after + np.concatenate([after[:, 1:], after[:, -1:]], axis=1))
    for key in _ARRAYS:
        moment = interval if key in _TRANSITIONS else after
        steps = moment.reshape(moment.shape + (1,) * (unit[key].ndim - 1)) * unit[key][None]
        out[key] = np.ascontiguousarray(np.concatenate([derivatives[key][dynamic], steps]))
    return out


def step_scan(result, kind: str = "f_step", trim: float = TRIM, stride: int = STRIDE) -> pd.DataFrame:
    """The score test of a ``kind`` step (``"f_step"`` or ``"xi_step"``) between ``trim`` and ``1 - trim`` of the
    fitted record of ``result``: at every ``stride``-th sample, then at every sample within ``stride`` of the
    :data:`PEAKS` largest statistics, from one pass per :data:`CHUNK` times (module docstring).

    Returns
    -------
    pandas.DataFrame
        One row per time tested, in time order: ``time_s`` (the step's time, s on the record's time axis: that
        sample is the first after it), ``at`` (its fraction of the record,
        :class:`~smd_statespace.effects.generic.GenericTerm`'s ``at``), ``lm`` (the score statistic, profile
        information), ``lm_robust`` (cycle-clustered and centred, as
        :func:`~smd_statespace.person.screen.score_test`'s).
    """
    time = result.model.time
    start, length = float(time[0]), float(time[-1] - time[0])
    inside = np.flatnonzero((time >= start + trim * length) & (time <= start + (1.0 - trim) * length))
    model, params, j, derivatives, unit = _unit_derivatives(result, kind)
    others = [i for i in range(params.size) if i != j]
    nuisance = [position for position, i in enumerate(others) if not model.at_bound(params, i)]
    fitted = model.filter(params)

    def tested(samples):
        rows = []
        for first in range(0, samples.size, CHUNK):
            chunk = samples[first:first + CHUNK]
            out = score(model, params, fitted=fitted,
                        derivatives=_chunk_derivatives(derivatives, j, unit, chunk, time))
            columns = list(range(len(others), len(others) + chunk.size))
            information, efficient = profile_out(out["profile_information"], out["efficient_per_sample"], columns,
                                                 nuisance, 1e-10)
            per_cycle = cycle_sums(model, efficient)
            cycles = per_cycle.shape[0]
            spread = np.sum((per_cycle - per_cycle.mean(axis=0)) ** 2, axis=0) * cycles / max(cycles - 1, 1)
            rows.append(pd.DataFrame({"sample": chunk, "time_s": time[chunk], "at": (time[chunk] - start) / length,
                                      "lm": out["gradient"][columns] ** 2 / np.diag(information),
                                      "lm_robust": efficient.sum(axis=0) ** 2 / spread}))
        return pd.concat(rows, ignore_index=True)

    coarse = tested(inside[::max(int(stride), 1)])
    near = np.concatenate([np.arange(k - stride + 1, k + stride) for k in coarse.nlargest(PEAKS, "lm")["sample"]])
    near = np.setdiff1d(np.intersect1d(near, inside), coarse["sample"])
    scan = pd.concat([coarse, tested(near)], ignore_index=True) if near.size else coarse
    return scan.sort_values("time_s").drop(columns="sample").reset_index(drop=True)


def fitted_span(time) -> tuple:
    """``(start, length)`` of a fitted span (s), to the nanosecond: what a time term's ``start`` and ``scale`` are, so
    that the ``--effect`` spec diagnose prints reads ``scale=30.404``, not ``scale=30.403999999999996``."""
    return round(float(time[0]), 9), round(float(time[-1] - time[0]), 9)


def short_fraction(low: float, high: float, start: float, length: float) -> float:
    """The fraction ``at`` of the fewest decimals whose time ``start + at * length`` lies strictly between ``low``
    and ``high`` (s): a step's place in a spec a user can read (``at=0.49747``), on the same side of every sample."""
    middle = (0.5 * (low + high) - start) / length
    for digits in range(2, 16):
        at = round(middle, digits)
        if low < start + at * length < high and 0.0 < at < 1.0:
            return at
    return middle


def located_step(result, kind: str = "f_step", trim: float = TRIM) -> GenericTerm:
    """The ``kind`` step at the time :func:`step_scan`'s LM statistic is largest (the step's least-squares time;
    the sample it names is the first after it), with the scan on it: ``scan`` = ``{"trim": trim, "lm_robust":``
    the largest robust statistic of the scan, ``"p": ``its :func:`sup_p_value```, "time_s": ``the step's time``,
    "table": ``the scan's table``}``, which :func:`~smd_statespace.person.screen.screen` and ``diagnose`` test it by
    and ``diagnose``'s figure of the scan draws."""
    scan = step_scan(result, kind, trim)
    best = scan.loc[scan["lm"].idxmax()]
    time = result.model.time
    start, length = fitted_span(time)
    sample = int(np.searchsorted(time, float(best["time_s"])))
    # in the second half of the interval before the sample, so that the sample is on the side after the step, and
    # the rates' evaluations inside the interval (at its middle) on the side before, as the scan's statistic has them
    low = float(time[sample]) - 0.5 * (float(time[sample]) - float(time[sample - 1]))
    term = GenericTerm(kind, scale=length, start=start, at=short_fraction(low, float(time[sample]), start, length))
    sup = float(scan["lm_robust"].max())
    term.scan = {"trim": trim, "lm_robust": sup, "p": sup_p_value(sup, trim), "time_s": float(best["time_s"]),
                 "table": scan}
    return term
