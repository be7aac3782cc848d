"""The cycle runner: a record -> cycles -> repeated passes of one estimator -> a table.

The article identifies the SMD model cycle by cycle (Section 3.2): the record
is split at GRF peaks, parameters are assumed constant within a cycle, and
the filter runs over the same cycle again and again, each pass starting from
where the previous one ended, until no parameter changes by more than ±5 %
between passes. :class:`CycleRunner` does exactly that with any estimator::

    runner = CycleRunner(SMDModel(), estimator="ukf")
    table = runner.run(preprocessed)          # one row per cycle
    runner.history_[3]                        # per-pass estimates of cycle 3

A caution, measured in ``docs/benchmarks.md``: a repeated pass reuses the
same samples, so it narrows the reported intervals without adding
information; with the article's passes the Kalman-type filters cover the
true ``f_h`` in about 70 % of cycles instead of 90 %. ``max_passes=1``
reports the single-pass posterior.

Each cycle's random numbers come from ``SeedSequence(seed, spawn_key=(record_key, cycle))``,
so results do not depend on the order in which cycles run, or on how many
run in parallel (any ``concurrent.futures.Executor``). A numerical failure in
one cycle marks that row ``status="failed"`` with the reason; the run goes on.

Estimates that cannot be true (``xi_h < 0``, ``f_h`` on or beyond the edge of
the model's prior, a force beyond physical sense: see
:mod:`smd_statespace.identify.plausibility`) stay ``status="ok"`` but get
``implausible=True`` with the reason in ``implausible_reason``, and every
``*_determined`` flag of that cycle is False: a number that describes no
person is never presented as determined.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..determined import DETERMINED_FRACTION
from ..errors import OptionError
from ..estimators import ESTIMATORS, EstimatorFailure, FilterResult, cycle_data, get_estimator
from ..io import Record
from ..model import SMDModel, blf
from ..progress import tqdm
from .plausibility import implausible_reasons
from ..signals import RECORD_RATE, Preprocessed, check_rate, decimate_record, decimation_note, preprocess

DEFAULT_ESTIMATOR = "ekf"
"""Estimator used when none is named: fast, deterministic and, with repeated passes, honest about its
widths (docs/benchmarks.md measures every estimator; the article's particle filter is over-confident)."""

CONVERGENCE_FLOOR = {"f_h": 0.0, "xi_h": 0.05, "blf": 0.02}
"""Magnitudes below which the ±tolerance rule is applied to the floor instead (xi_h in -, BLF in g),
so that a BLF of 0.001 g need not settle to 0.00005 g."""


@dataclass
class CycleOutcome:
    """What identifying one cycle produced: its table row, per-pass history and final filter result."""

    row: dict
    history: list = field(default_factory=list)
    result: FilterResult | None = None


def summarise(model: SMDModel, result: FilterResult, mass: float) -> dict:
    """Reported quantities of a pass: parameters with sds, BLFs (Eq. 5), K_h (Eq. 17), C_h (Eq. 18)."""
    mean, sd = result.final_mean, result.final_std
    ratio = result.width_ratio()
    out = {}
    for name in model.parameter_names:
        i = model.index(name)
        out[name] = float(mean[i])
        out[f"{name}_sd"] = float(sd[i])
    for name in ("f_h", "xi_h"):
        out[f"{name}_width_ratio"] = float(ratio[model.index(name)])
        out[f"{name}_determined"] = bool(ratio[model.index(name)] < DETERMINED_FRACTION)
    for i in range(1, model.n_harmonics + 1):
        ia, ib = model.index(f"a{i}"), model.index(f"b{i}")
        a, b = mean[ia], mean[ib]
        value = float(blf(a, b))
        out[f"blf_{i}"] = value
        # Delta method: sd of sqrt(a^2 + b^2) from the coefficients' sds.
        out[f"blf_{i}_sd"] = float(np.hypot(a * sd[ia], b * sd[ib]) / value) if value > 0 else float(np.hypot(sd[ia], sd[ib]))
        out[f"blf_{i}_determined"] = bool(max(ratio[ia], ratio[ib]) < DETERMINED_FRACTION)
    derived = model.derived(mean, mass)
    out["k_h"], out["c_h"] = float(derived["k_h"]), float(derived["c_h"])
    out["log_likelihood"] = float(result.log_likelihood)
    for counter in ("covariance_repairs", "resamples"):
        if counter in result.diagnostics:
            out[counter] = int(result.diagnostics[counter])
    return out


def converged(previous: dict, current: dict, model: SMDModel, tolerance: float) -> bool:
    """The article's rule: every parameter changed by no more than ``tolerance`` (relative) between passes.

    Checked on ``f_h``, ``xi_h`` and ``BLF_1..n``; magnitudes below
    :data:`CONVERGENCE_FLOOR` are compared against the floor.
    """
    names = ["f_h", "xi_h"] + [f"blf_{i}" for i in range(1, model.n_harmonics + 1)]
    for name in names:
        floor = CONVERGENCE_FLOOR["blf" if name.startswith("blf") else name]
        if abs(current[name] - previous[name]) > tolerance * max(abs(previous[name]), floor):
            return False
    return True


def check_sampling(model: SMDModel, preprocessed: Preprocessed) -> None:
    """Refuse a record sampled too slowly for the force harmonics of the model (Eq. 4).

    Harmonic ``k`` of a cycle at ``f_b`` oscillates at ``k f_b``; it must stay
    below the Nyquist frequency ``fs / 2`` of the record.
    """
    top = int(model.harmonic_orders().max())
    valid = [cycle.f_b for cycle in preprocessed.valid_cycles]
    if not valid:
        return
    f_b = max(valid)
    if top * f_b >= 0.5 * preprocessed.fs:
        raise OptionError(
            f"{preprocessed.source}: sampled at {preprocessed.fs:g} Hz, too slowly for force harmonic {top} at "
            f"f_b up to {f_b:.2f} Hz ({top * f_b:.1f} Hz needs more than {2 * top * f_b:.0f} Hz); "
            "lower --harmonics or record faster"
        )


def identify_cycle(model: SMDModel, estimator, data, seed, record_key: int, mass: float, max_passes: int,
                   tolerance: float, cycle_info: dict, keep_result: bool = True) -> CycleOutcome:
    """Identify one cycle with repeated passes (runs in a worker process when an executor is used).

    With ``keep_result=False`` the final :class:`FilterResult` (for a particle
    filter it holds the whole cloud, 0.5 MB at 5000 particles) is dropped in
    the worker, so it is neither sent back nor held.
    """
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(record_key, data.index)))
    row = dict(cycle_info)
    history = []
    started = time.perf_counter()
    result = None
    try:
        passes = max_passes if estimator.supports_passes else 1
        done = not estimator.supports_passes
        for number in range(1, passes + 1):
            result = estimator.run(model, data, start=result.restart if result is not None else None, rng=rng)
            summary = summarise(model, result, mass)
            history.append(dict(summary, pass_number=number))
            if number > 1 and converged(history[-2], summary, model, tolerance):
                done = True
                break
        bad = [name for name, value in history[-1].items()
               if isinstance(value, float) and not np.isfinite(value) and not name.endswith("width_ratio")]
        if bad:
            raise EstimatorFailure(f"cycle {data.index}: non-finite {', '.join(bad[:3])} after pass {len(history)}")
        row.update(history[-1])
        row.update(passes=len(history), converged=done, status="ok", reason="")
    except (EstimatorFailure, ArithmeticError, np.linalg.LinAlgError) as failure:
        # A diverging cycle is that cycle's failure, never the batch's, and never a silent NaN in the table.
        reason = str(failure) if isinstance(failure, EstimatorFailure) else f"{type(failure).__name__}: {failure}"
        row.update(passes=len(history) + 1, converged=False, status="failed", reason=reason)
        result = None  # an earlier pass's result must not stand in for the failed cycle
    row["seconds"] = time.perf_counter() - started
    return CycleOutcome(row=row, history=history, result=result if keep_result else None)


class CycleRunner:
    """Identify every cycle of a record with one estimator and the article's repeated passes.

    Parameters
    ----------
    model : SMDModel, optional
        The augmented-state model (default ``SMDModel()``: 4 harmonics, RK4).
    estimator : str or Estimator
        ``"pf"`` (the article's particle filter), ``"rbpf"``, ``"ukf"``,
        ``"ekf"`` or ``"grid"`` (exact reference, one pass). Default
        :data:`DEFAULT_ESTIMATOR`, as on the command line.
    max_passes : int
        Largest number of passes per cycle.
    tolerance : float
        Relative change between passes below which a cycle has converged (the article: 0.05).
    seed : int
        Seed of the run; each cycle's stream is derived from it and the cycle's identity.
    progress : bool
        Show a progress bar (tqdm) on the terminal.
    executor : concurrent.futures.Executor, optional
        Runs cycles in parallel (processes, threads or a Dask cluster's executor).
    keep_results : bool
        Keep every cycle's final :class:`FilterResult` in ``results_`` (for diagnostics).
    rate : float or None
        A :class:`~smd_statespace.io.Record` sampled at twice this rate (Hz) or faster is
        low-pass filtered and decimated to between ``rate`` and ``2 rate`` before it is
        preprocessed (:func:`~smd_statespace.signals.decimate_record`; default
        :data:`~smd_statespace.signals.RECORD_RATE`). The article's noise levels and random
        walk (Eq. 6) are per sample at its 100 Hz; at 1000 Hz the same settings walk ten
        times as often, and every cycle costs ten times more (``benchmarks/fast_records.py``,
        docs/performance.md "Fast records": median ``f_h`` error 0.87 -> 0.69 Hz with the
        EKF, 1.36 -> 0.68 Hz with the grid, 9-13 times faster). None keeps every sample.
        A :class:`~smd_statespace.signals.Preprocessed` input is used as it is.
    **options
        Estimator options, e.g. ``n_particles=5000``.

    Attributes (after :meth:`run`)
    ------------------------------
    table_ : pandas.DataFrame
        The returned table.
    history_ : dict of int to list of dict
        Per-pass estimates of every cycle (for convergence plots, the article's Fig. 4).
    results_ : dict of int to FilterResult
        Final-pass filter results (with ``keep_results=True``).
    preprocessed_ : Preprocessed
        The pipeline output the cycles came from.
    notes_ : list of str
        What was done to the record before the cycles, in words (the decimation).
    """

    def __init__(self, model: SMDModel | None = None, estimator=None, max_passes: int = 8, tolerance: float = 0.05,
                 seed: int = 0, progress: bool = True, executor=None, keep_results: bool = True,
                 rate=RECORD_RATE, **options):
        self.model = SMDModel() if model is None else model
        if isinstance(estimator, str) and estimator not in ESTIMATORS:
            raise OptionError(f"unknown estimator {estimator!r}; choose one of {', '.join(sorted(ESTIMATORS))}")
        self.estimator = get_estimator(DEFAULT_ESTIMATOR if estimator is None else estimator, **options)
        if isinstance(max_passes, bool) or int(max_passes) != max_passes or max_passes < 1:
            raise OptionError(f"max_passes must be a whole number >= 1, got {max_passes!r}")
        if not 0 < float(tolerance) < 1:
            raise OptionError(f"tolerance must be a fraction in (0, 1), got {tolerance!r}")
        if isinstance(seed, bool) or int(seed) != seed or seed < 0:
            raise OptionError(f"seed must be a whole number >= 0, got {seed!r}")
        self.max_passes = int(max_passes)
        self.tolerance = float(tolerance)
        self.seed = int(seed)
        self.progress = progress
        self.executor = executor
        self.keep_results = keep_results
        self.rate = check_rate(rate)

    def cycles(self, preprocessed: Preprocessed):
        """The valid cycles of a record, as :class:`~smd_statespace.estimators.CycleData`."""
        return [(cycle, cycle_data(self.model, preprocessed, cycle)) for cycle in preprocessed.valid_cycles]

    def run(self, record, mass: float | None = None, record_key: int = 0) -> pd.DataFrame:
        """Identify every cycle of ``record``; return one row per cycle.

        Parameters
        ----------
        record : Record or Preprocessed
            A checked record (it is preprocessed first) or a pipeline output.
        mass : float, optional
            Body mass (kg); taken from the record when omitted.
        record_key : int
            Identity of the record within a batch, part of every cycle's seed.
        """
        if isinstance(record, Record):
            decimated, factor, _ = decimate_record(record, self.rate)
            self.notes_ = decimation_note(record.fs, decimated, factor, self.rate)
            preprocessed = preprocess(decimated)
        else:
            self.notes_, preprocessed = [], record
        check_sampling(self.model, preprocessed)
        mass = float(preprocessed.mass if mass is None else mass)
        self.preprocessed_ = preprocessed
        jobs = []
        skipped = []
        for cycle in preprocessed.cycles:
            info = {"cycle": cycle.index, "t_start": cycle.t_start, "t_end": cycle.t_end, "f_b": cycle.f_b,
                    "estimator": self.estimator.name}
            if not cycle.valid:
                skipped.append(dict(info, status="skipped", reason=cycle.reason, passes=0, converged=False))
                continue
            jobs.append((cycle_data(self.model, preprocessed, cycle), info))
        outcomes = self._execute(jobs, mass, record_key)
        rows = [outcome.row for outcome in outcomes] + skipped
        self.history_ = {outcome.row["cycle"]: outcome.history for outcome in outcomes}
        self.results_ = {o.row["cycle"]: o.result for o in outcomes if o.result is not None} if self.keep_results else {}
        table = mark_implausible(pd.DataFrame(rows).sort_values("cycle").reset_index(drop=True), self.model)
        self.table_ = order_columns(table, self.model)
        return self.table_

    def run_many(self, records, path, masses=None) -> int:
        """Identify many records one after another, appending each record's rows to the CSV ``path``.

        Nothing is held between records (``results_`` and ``history_`` describe
        the last record only, and with ``keep_results=False`` not even its filter
        results), so memory stays flat however many records and cycles there are:
        this is how a study of thousands of cycles runs (docs/performance.md).

        Parameters
        ----------
        records : iterable of Record or Preprocessed
            Loaded lazily if it is a generator. Record ``i`` gets ``record_key=i``
            (part of every cycle's seed), so the rows do not depend on how the
            study is split into calls, as long as the keys are kept.
        path : str or Path
            CSV written afresh; one header (the first record's columns), a
            ``record`` column with the key.
        masses : sequence of float, optional
            Body masses (default: each record's own).

        Returns
        -------
        int
            Rows written.
        """
        rows, columns = 0, None
        with open(path, "w", newline="") as handle:
            for key, record in enumerate(records):
                table = self.run(record, mass=None if masses is None else masses[key], record_key=key)
                table.insert(0, "record", key)
                if columns is None:
                    columns = list(table.columns)
                table.reindex(columns=columns).to_csv(handle, header=rows == 0, index=False)
                rows += len(table)
        return rows

    def _execute(self, jobs, mass, record_key):
        arguments = [(self.model, self.estimator, data, self.seed, record_key, mass, self.max_passes, self.tolerance,
                      info, self.keep_results) for data, info in jobs]
        bar = tqdm(total=len(jobs), desc=f"identify ({self.estimator.name})", unit="cycle",
                   disable=not self.progress, leave=False)
        outcomes = []
        try:
            if self.executor is None:
                for args in arguments:
                    outcomes.append(identify_cycle(*args))
                    bar.update()
            else:
                futures = [self.executor.submit(identify_cycle, *args) for args in arguments]
                for future in futures:
                    outcomes.append(future.result())
                    bar.update()
        finally:
            bar.close()
        return outcomes


def mark_implausible(table: pd.DataFrame, model: SMDModel) -> pd.DataFrame:
    """Add ``implausible`` and ``implausible_reason`` to a runner table; such cycles determine nothing.

    Only ``ok`` rows are checked (failed and skipped rows have no estimates: False, ``""``). The
    limits are those of :func:`smd_statespace.identify.plausibility.implausible_reasons` with the model's
    prior; the check of the floor force uses the base SMD and is left out for models with effects.
    The filter's own claim stays readable in the ``*_width_ratio`` columns.
    """
    ok = (table["status"] == "ok").to_numpy() if "status" in table else np.zeros(len(table), dtype=bool)
    reasons = pd.Series("", index=table.index, dtype=object)
    if ok.any():
        reasons[ok] = implausible_reasons(table[ok], model=model, grf=not model.effects)
    table["implausible"] = (reasons != "").to_numpy()
    table["implausible_reason"] = reasons
    for column in [c for c in table.columns if c.endswith("_determined")]:
        table[column] = table[column].where(~table["implausible"], False)
    return table


def order_columns(table: pd.DataFrame, model: SMDModel) -> pd.DataFrame:
    """Put the documented columns first, in a stable order."""
    n = model.n_harmonics
    first = ["cycle", "t_start", "t_end", "f_b", "f_h", "f_h_sd", "xi_h", "xi_h_sd"]
    first += [f"blf_{i}" for i in range(1, n + 1)] + [f"blf_{i}_sd" for i in range(1, n + 1)]
    first += ["a0", "k_h", "c_h", "passes", "converged", "log_likelihood", "estimator", "status", "reason",
              "implausible", "implausible_reason", "f_h_determined", "xi_h_determined"]
    first += [f"blf_{i}_determined" for i in range(1, n + 1)]
    first = [c for c in first if c in table.columns]
    return table[first + [c for c in table.columns if c not in first]]
