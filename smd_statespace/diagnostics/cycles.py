"""The checked cycles' series: measurement, free simulation and one-step prediction, joined in record order.

What :class:`~smd_statespace.diagnostics.check.ModelCheck` is built from:

- :func:`checked_cycle`: one identified cycle's series and what its linearisation needs;
- :func:`checked_series`: every checked cycle, joined (a boundary sample shared by two
  consecutive cycles is kept once, in the earlier cycle, where the free simulation has run longest);
- :func:`absorbable_bases`: per cycle, an orthonormal basis of the output changes a re-fit could make;
- :func:`state_over_record`: a slot of the free simulation's state over the whole record.

Forces in N (``M_h u''``), times in s. A cycle's *piece* is a dict with
``rows`` (its slice of the joined series), ``samples`` (its record samples),
``keep`` (the slice of them in the joined series), ``data`` (its
:class:`~smd_statespace.estimators.CycleData`), ``free`` (the slots the
identification estimated), ``states`` (the free simulation, shape (m, n_state))
and ``harmonic_basis`` (orthonormal force regressors of Eq. 4 on the kept samples).
"""

from __future__ import annotations

import numpy as np

from ..model import TWO_PI
from .free_simulation import fit_initial_state, free_simulation, path_sensitivity
from .phase import harmonic_regressors
from .subspace import orthonormal_columns

__all__ = ["SERIES", "checked_cycle", "checked_series", "absorbable_bases", "state_over_record"]

SERIES = ("time", "cycle", "sample", "phase", "measured", "simulated", "one_step", "innovations")
"""Names of the per-sample series of :func:`checked_series`."""


def checked_cycle(model, preprocessed, cycle, result, keep, initial_state="estimate"):
    """One identified cycle: its series on the kept samples and the free simulation behind them.

    Parameters
    ----------
    model : SMDModel
        The identified model.
    preprocessed : Preprocessed
        The record.
    cycle : Cycle
        The cycle.
    result : FilterResult
        Its final-pass filter result.
    keep : slice
        The cycle's samples to keep (all, or all but a first sample shared with the previous cycle).
    initial_state : {"estimate", "filtered"}
        Start of the free simulation: fitted by least squares
        (:func:`~.free_simulation.fit_initial_state`) or the filter's estimate.

    Returns
    -------
    series : dict of str to ndarray
        :data:`SERIES` on the kept samples: times (s), cycle number, record
        sample, phase in [0, 1], measured, simulated and one-step predicted
        ``M_h u''`` (N), standardised innovations of ``u''``.
    piece : dict
        The cycle's piece (see the module docstring) without ``rows``.
    n_free : int
        Parameter slots (not dynamic) the identification estimated.
    n_filtered : int
        Samples the filter saw.
    """
    from ..estimators import cycle_data

    channel = model.channels.index("u_ddot")
    dynamic = np.array([slot.kind == "dynamic" for slot in model.slots])
    mass = float(preprocessed.mass)
    data = cycle_data(model, preprocessed, cycle)
    std = np.asarray(result.std)
    free = dynamic | np.any(std > 0, axis=0) if std.ndim == 2 and std.size else np.ones(model.n_state, bool)
    states = free_simulation(model, result, data, dynamic)
    if initial_state == "estimate":
        states = fit_initial_state(model, states, data, dynamic, keep, channel)
    predicted = model.observe(states, data.t, data.inputs)[:, channel]
    samples = np.arange(cycle.start, cycle.stop + 1)
    kept = samples[keep]
    acc = data.y[keep, channel]
    series = {"time": data.t[keep], "cycle": np.full(kept.size, cycle.index), "sample": kept,
              "phase": (data.t[keep] - cycle.t_start) / (cycle.t_end - cycle.t_start), "measured": mass * acc,
              "simulated": mass * predicted[keep], "one_step": mass * (acc - result.innovations[keep, channel]),
              "innovations": result.standardised_innovations[keep, channel]}
    theta = TWO_PI * cycle.f_b * (np.asarray(data.t[keep], dtype=float) - cycle.t_start)
    piece = {"samples": samples, "keep": keep, "data": data, "free": free, "states": states,
             "harmonic_basis": orthonormal_columns(harmonic_regressors(theta, model.harmonic_orders()))}
    return series, piece, int(np.sum(free & ~dynamic)), len(data)


def checked_series(model, preprocessed, cycles, results, initial_state="estimate"):
    """Every checked cycle's series (:func:`checked_cycle`), joined in record order.

    Parameters
    ----------
    model, preprocessed, initial_state
        As in :func:`checked_cycle`.
    cycles : list of Cycle
        The cycles, in record order.
    results : mapping of int to FilterResult
        Final-pass filter result of each cycle, by cycle number.

    Returns
    -------
    joined : dict of str to ndarray
        :data:`SERIES`, each of shape (T,).
    pieces : list of dict
        Each cycle's piece (see the module docstring).
    n_parameters : int
        Estimated parameter slots summed over the cycles.
    nobs : int
        Filtered samples summed over the cycles (boundaries counted in both).
    """
    parts = {name: [] for name in SERIES}
    pieces, free_counts, nobs, previous_stop, position = [], [], 0, None, 0
    for cycle in cycles:
        keep = slice(1, None) if cycle.start == previous_stop else slice(None)
        series, piece, n_free, n_filtered = checked_cycle(model, preprocessed, cycle, results[cycle.index], keep,
                                                          initial_state)
        previous_stop = cycle.stop
        for name in SERIES:
            parts[name].append(series[name])
        size = series["sample"].size
        pieces.append({"rows": slice(position, position + size), **piece})
        position += size
        nobs += n_filtered
        free_counts.append(n_free)
    joined = {name: np.concatenate(values) for name, values in parts.items()}
    return joined, pieces, int(sum(free_counts)), int(nobs)


def absorbable_bases(model, pieces) -> list:
    """Per cycle, an orthonormal basis of the changes of the simulated ``u''`` a re-fit of the cycle could make.

    The columns of :func:`~.free_simulation.path_sensitivity` for the slots
    the identification estimated, on the kept samples, orthonormalised
    (:func:`~.subspace.orthonormal_columns`).

    Returns
    -------
    list of ndarray
        One (kept samples, rank) array per piece.
    """
    channel = model.channels.index("u_ddot")
    bases = []
    for piece in pieces:
        sensitivity = path_sensitivity(model, piece["states"], piece["data"], channel)[:, piece["free"]]
        bases.append(orthonormal_columns(sensitivity[piece["keep"]]))
    return bases


def state_over_record(pieces, index, n_record, fill=None) -> np.ndarray:
    """Slot ``index`` of the free simulation's state over a whole record, shape (n_record,).

    On each piece's samples the simulated value (a later piece overwrites a
    shared sample); elsewhere ``fill`` (e.g. the pipeline's ``disp``), or
    without it the median over pieces of the slot's last simulated value.
    """
    if fill is None:
        values = np.full(n_record, float(np.median([p["states"][-1, index] for p in pieces])))
    else:
        values = np.array(fill, dtype=float)
    for piece in pieces:
        values[piece["samples"]] = piece["states"][:, index]
    return values
