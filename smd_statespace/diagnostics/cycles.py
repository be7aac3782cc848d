"""The checked cycles' series: measurement, free simulation and one-step prediction, joined in record order.

What :class:`~smd_statespace.diagnostics.check.ModelCheck` is built from:

- :func:`checked_cycle`: one identified cycle's series and what its linearisation needs;
- :func:`checked_series`: every checked cycle, joined (a boundary sample shared by two
  consecutive cycles is kept once, in the earlier cycle, where the free simulation has run longest);
- :func:`absorbable_bases`: per cycle, an orthonormal basis of the output changes a re-fit could make;
- :func:`state_over_record`: a slot of the free simulation's state over the whole record;
- :func:`cycle_harmonic`: a force harmonic of each cycle over the whole record;
- :func:`identified_runner`: the cycle-by-cycle identification a check compares with.

Forces in N (``M_h u''``), times in s. A cycle's *piece* is a dict with
``rows`` (its slice of the joined series), ``samples`` (its record samples),
``keep`` (the slice of them in the joined series), ``data`` (its
:class:`~smd_statespace.estimators.CycleData`), ``free`` (the slots the
identification estimated), ``states`` (the free simulation, shape (m, n_state))
and ``harmonic_basis`` (orthonormal force regressors of Eq. 4 on the kept samples).

Two predictions of the dynamic GRF ``M_h u''`` (N, Eq. 3) are made:

free simulation (:attr:`ModelCheck.simulated`)
    Each cycle is integrated with the model alone (:meth:`SMDModel.transition`,
    no process noise, no measurement update) with the cycle's identified
    parameters held at their final-pass values, from the dynamic starting
    state (``u``, ``u_dot``, an estimated floor's ``z``, ``z_dot``) that fits
    the cycle best in the least-squares sense, as MATLAB's ``compare`` does
    by default (``initial_state="filtered"`` starts from the filter's
    estimate at the first sample instead: for a slot no channel measures,
    such as an estimated floor's motion, that is only its prior). What the
    model cannot produce stays in the residual ``measured - simulated``:
    this is the signal the missing-effect diagnostics look at.
one-step-ahead prediction (:attr:`ModelCheck.one_step`)
    The filter's prediction of each sample from all earlier ones
    (measurement minus innovation). The filter corrects the state at every
    sample, so this fits better and hides model error in the state
    corrections; its standardised innovations are what the serial
    correlation, normality and heteroskedasticity tests examine (as in
    statsmodels).
"""

from __future__ import annotations

import numpy as np

from ..errors import OptionError
from ..io import Record
from ..model import TWO_PI
from .free_simulation import fit_initial_state, free_simulation, path_sensitivity
from .phase import harmonic_regressors
from .subspace import orthonormal_columns

__all__ = ["SERIES", "checked_cycle", "checked_series", "absorbable_bases", "state_over_record", "cycle_harmonic",
           "identified_runner"]

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
        (:func:`free_simulation.fit_initial_state`) or the filter's estimate.

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

    The columns of :func:`free_simulation.path_sensitivity` for the slots
    the identification estimated, on the kept samples, orthonormalised
    (:func:`subspace.orthonormal_columns`).

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


def cycle_harmonic(time, cycles, order) -> np.ndarray:
    """``[cos(k theta), sin(k theta)]`` of each cycle over the whole record, shape (len(time), 2).

    ``theta = 2 pi f_b (t - t_start)`` of the cycle (Eq. 4), ``k = order``;
    zero outside the cycles. A force harmonic the model lacks adds ``g (a_k
    cos + b_k sin)`` to the COM acceleration.

    Parameters
    ----------
    time : array_like, shape (n,)
        The record's sample times (s).
    cycles : list of Cycle
        The cycles (``start``, ``stop``, ``t_start``, ``f_b``).
    order : int
        Harmonic order ``k``.
    """
    time = np.asarray(time, dtype=float)
    out = np.zeros((time.size, 2))
    for cycle in cycles:
        span = slice(cycle.start, cycle.stop + 1)
        theta = TWO_PI * cycle.f_b * (time[span] - cycle.t_start)
        out[span, 0], out[span, 1] = np.cos(order * theta), np.sin(order * theta)
    return out


def identified_runner(preprocessed, model, estimator, runner, runner_options):
    """The finished cycle-by-cycle identification :func:`~smd_statespace.diagnostics.check.check_model` compares with.

    Without ``runner``, a :class:`~smd_statespace.identify.runner.CycleRunner`
    of ``model`` and ``estimator`` with ``runner_options`` (``progress``
    False unless given, ``keep_results`` True) is run on ``preprocessed`` (a
    :class:`~smd_statespace.io.Record` is preprocessed first); a given
    ``runner`` is checked instead.

    Returns
    -------
    CycleRunner
        A runner with ``table_``, ``results_``, ``model`` and ``preprocessed_``.

    Raises
    ------
    OptionError
        Nothing to identify, options for a finished runner, a runner that has
        not run or kept no filter results, or a record it did not identify.
    """
    from ..identify.runner import CycleRunner
    from ..signals import preprocess

    if runner is None:
        if preprocessed is None:
            raise OptionError("check_model needs a preprocessed record or a finished runner")
        if isinstance(preprocessed, Record):
            preprocessed = preprocess(preprocessed)
        runner_options.setdefault("progress", False)
        runner_options["keep_results"] = True
        runner = CycleRunner(model, estimator=estimator, **runner_options)
        runner.run(preprocessed)
    else:
        if runner_options:
            raise OptionError(
                f"check_model: runner options {', '.join(sorted(runner_options))} cannot apply to a finished runner"
            )
        if not hasattr(runner, "table_"):
            raise OptionError("check_model: the runner has not run yet; call runner.run(record) first")
        if not getattr(runner, "results_", None):
            raise OptionError("check_model: the runner kept no filter results; make it with keep_results=True")
        if preprocessed is not None and isinstance(preprocessed, Record):
            raise OptionError("check_model: with a finished runner, pass the Preprocessed it ran on (or nothing)")
        if preprocessed is not None and preprocessed is not runner.preprocessed_:
            raise OptionError("check_model: preprocessed is not the record the runner identified")
    return runner
