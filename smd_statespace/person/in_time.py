"""The person over the record when a term lets ``f_h`` or ``xi_h`` change in time: its values at each end and
either side of a step, with intervals.

With a time term in the model (``term:f_step``, ``term:f_drift``, ``term:xi_step``, ``term:xi_drift``:
:mod:`~smd_statespace.effects.generic`) the fitted ``f_h`` and ``xi_h`` are the middle of what the record
holds: ``w_h^2 (1 + c m(t))`` with ``m`` from -1/2 to +1/2 over the record (a step: -1/2 before it, +1/2 after).
A user who reads the fitted ``f_h`` alone reads neither person: on a simulated lab export whose ``f_h`` steps
from 2.90 to 3.33 Hz at 19.9 s, the printed ``f_h`` was 3.30 Hz, which is the middle of the fitted 3.10 and 3.49 Hz.
:func:`person_in_time` gives the values the model holds at those times:

    f_h(t)  = f_h  sqrt(1 + sum_k c_k m_k(t))     over the terms of f_h
    xi_h(t) = xi_h (1 + sum_k c_k m_k(t))         over the terms of xi_h (its damping, at the middle f_h)

Their intervals are by the delta method, with the covariance of ``f_h`` and ``xi_h`` scaled to the intervals
the result gives them (calibrated and widened as the result's own: :attr:`PersonResult.intervals`) and the
terms' coefficients at their observed-information sds. A value of a parameter the result does not call
determined is not determined at any time either.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats

__all__ = ["time_terms", "person_in_time", "in_time_words"]


def time_terms(effects) -> list:
    """The effects that let ``f_h`` or ``xi_h`` change in time (their ``changes`` names the parameter)."""
    return [effect for effect in effects if getattr(effect, "changes", None)]


def _times(result, terms) -> list:
    """``(time, side)``: the fitted span's ends, and each step's time from either side (``side`` -1, +1; 0 at an
    end)."""
    time = result.model.time
    points = [(float(time[0]), 0)]
    for at in sorted({b for term in terms for b in term.breaks if time[0] < b < time[-1]}):
        points += [(at, -1), (at, +1)]
    return points + [(float(time[-1]), 0)]


def person_in_time(result) -> pd.DataFrame:
    """``f_h`` and ``xi_h`` at the fitted span's ends and either side of each step, as the time terms among
    ``result.effects`` make them (empty without such terms).

    Returns
    -------
    pandas.DataFrame
        One row per time: ``time_s``, ``side`` (``"start"``, ``"end"``, ``"before"`` or ``"after"`` a step),
        and per parameter ``name`` in (``f_h``, ``xi_h``) the columns ``name``, ``name_sd``, ``name_low``,
        ``name_high`` (at ``result.level``) and ``name_determined``.
    """
    terms = time_terms(result.effects)
    if not terms:
        return pd.DataFrame()
    model, named = result.model, result.model.unpack(result.params)
    z = stats.norm.ppf(0.5 + result.level / 2.0)
    names = ["f_h", "xi_h"] + [term.coefficient for term in terms]
    index = [model.position(name) for name in names]
    cov = np.array(result.cov)[np.ix_(index, index)]
    # f_h and xi_h as uncertain as the intervals the result gives them (calibrated, widened); correlations kept
    honest = np.array([(result.intervals[name][1] - result.intervals[name][0]) / (2.0 * z) for name in names[:2]])
    raw = np.sqrt(np.diag(cov)[:2])
    scale = np.ones(len(names))
    scale[:2] = np.where(raw > 0, honest / np.where(raw > 0, raw, 1.0), 1.0)
    cov = cov * np.outer(scale, scale)
    coefficients = np.array([named[term.coefficient] for term in terms])
    rows = []
    for at, side in _times(result, terms):
        row = {"time_s": at, "side": {0: "start" if at == float(model.time[0]) else "end", -1: "before",
                                      +1: "after"}[side]}
        # a step is evaluated just before (side -1) or at (side +1) its time, as the model's H(t - t_s)
        t = np.nextafter(at, -np.inf) if side < 0 else at
        for parameter in ("f_h", "xi_h"):
            moments = np.array([float(term.moment(t)) if term.changes == parameter else 0.0 for term in terms])
            relative = 1.0 + float(moments @ coefficients)
            gradient = np.zeros(len(names))
            if parameter == "f_h":  # f_h sqrt(1 + sum c m)
                value = named["f_h"] * np.sqrt(max(relative, 0.0))
                gradient[0] = np.sqrt(max(relative, 0.0))
                gradient[2:] = named["f_h"] * moments / (2.0 * np.sqrt(max(relative, 1e-12)))
            else:  # xi_h (1 + sum c m)
                value = named["xi_h"] * relative
                gradient[1] = relative
                gradient[2:] = named["xi_h"] * moments
            sd = float(np.sqrt(max(gradient @ cov @ gradient, 0.0)))
            row.update({parameter: float(value), f"{parameter}_sd": sd, f"{parameter}_low": float(value - z * sd),
                        f"{parameter}_high": float(value + z * sd),
                        f"{parameter}_determined": bool(result.determined(parameter))})
            if parameter == "xi_h":
                row["xi_h_low"] = max(row["xi_h_low"], 0.0)
        rows.append(row)
    return pd.DataFrame(rows)


def _spans(table, parameter) -> list:
    """Consecutive rows of one value of ``parameter`` joined: ``(first time, last time, row)``."""
    spans = []
    for _, row in table.iterrows():
        if spans and np.isclose(spans[-1][2][parameter], row[parameter], rtol=1e-12, atol=0.0):
            spans[-1] = (spans[-1][0], row["time_s"], spans[-1][2])
        else:
            spans.append((row["time_s"], row["time_s"], row))
    return spans


def in_time_words(result, digits=(2, 3)) -> list:
    """Lines for the printout: each parameter a time term changes, its values over the record with intervals
    (a step: ``f_h in time (90 % intervals): 3.10 Hz (2.77-3.43) in 4.81-19.93 s, 3.49 Hz (3.13-3.85) in
    19.93-35.21 s; ...``; a drift: its values at the span's ends)."""
    table = person_in_time(result)
    if table.empty:
        return []
    pct = int(round(100 * result.level))
    lines = []
    for parameter, unit, places in (("f_h", " Hz", digits[0]), ("xi_h", "", digits[1])):
        if not any(term.changes == parameter for term in time_terms(result.effects)):
            continue
        parts = []
        for first, last, row in _spans(table, parameter):
            when = f"in {first:.2f}-{last:.2f} s" if last > first else f"at {first:.2f} s"
            parts.append(f"{row[parameter]:.{places}f}{unit} ({row[f'{parameter}_low']:.{places}f}-"
                         f"{row[f'{parameter}_high']:.{places}f}) {when}")
        drift = any(term.changes == parameter and not term.breaks for term in time_terms(result.effects))
        between = f", {'linearly in w_h^2' if parameter == 'f_h' else 'linearly'} between" if drift else ""
        determined = "" if table[f"{parameter}_determined"].iloc[0] else "; NOT DETERMINED"
        middle = result.model.unpack(result.params)[parameter]
        lines.append(f"  {parameter} in time ({pct} % intervals): {', '.join(parts)}{between}; the single {parameter} "
                     f"({middle:.{places + 1}f}{unit}) is the record's middle value{determined}")
    return lines
