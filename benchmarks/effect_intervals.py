"""Do the effects' parameter intervals hold the truth? ``identify --effect`` with the true effect, on simulated people.

``identify --effect SPEC`` (:func:`~smd_statespace.person.extend.fit_effects`, the cycle starts re-placed with the
effect) reports each effect parameter with a Wald interval from the observed information of the (for a nonlinear
effect, path-linearised) likelihood; unlike ``f_h`` and ``xi_h`` it is not calibrated. This script simulates
``benchmarks/person_effects.py``'s people with a hidden effect (its kinds and sizes; the ``jumps`` and ``smooth``
generators), adds the true effect as ``identify --effect`` does and reports, per kind and size:

- how often the 90 % interval ``identify`` reports holds the truth (``covered``: calibrated by
  :data:`~smd_statespace.person.calibration.EFFECT_CALIBRATION` since 2026-11-30; the two runs in
  ``benchmarks/results/effect_intervals_seed9*.md`` were made before, with the information's intervals), how often
  the information's own (estimate +- 1.645 sd: ``covered_information``), and the z of the estimate
  (``(estimate - truth) / sd``);
- the same with the sd raised to the cycle-clustered sandwich's where that is wider (the rule ``identify`` applies to
  ``f_h`` and ``xi_h``: :data:`~smd_statespace.person.search.WIDER_SANDWICH`);
- records where the comparison is not the estimator's to answer: the front end fitted part of the record (a step
  that made the simulated force touch zero splits it into two bouts: the step is then not where the truth says),
  or the truth lies outside the parameter's search range (a cubic spring's range is scaled to the record).

::

    OPENBLAS_NUM_THREADS=1 python benchmarks/effect_intervals.py --records 8 --seed 92 --jobs 2 \\
        --out benchmarks/results/effect_intervals_seed92.md
"""

from __future__ import annotations

import os

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")
os.environ.setdefault("SMD_STATESPACE_THREADS", "1")


import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from scipy import stats  # noqa: E402

from accuracy import markdown_report, markdown_table  # noqa: E402  (benchmarks/, the script's own folder)
import person_effects  # noqa: E402

KINDS = ("term_abs_u", "term_v_abs_v", "term_f_drift", "term_f_step", "cubic_stiffness")
"""The hidden effects with one parameter whose truth is known (``person_effects.TRUE_PARAMETER``)."""


def _sandwich_sd(fitted, position: int) -> float:
    """The cycle-clustered sandwich sd of the parameter at ``position``, with ``f_h`` and ``xi_h`` beside it and the
    other parameters profiled out (``search.information``'s rule for the person, applied to one more parameter)."""
    from smd_statespace.person.search import _differencing, _hessian, _robust_core

    model, params = fitted.model, fitted.params
    steps, free = _differencing(model, params)
    index = np.flatnonzero(free)
    if position not in index:
        return float("nan")
    keep = [int(np.flatnonzero(index == p)[0]) for p in (0, 1, position)]
    return float(np.sqrt(_robust_core(model, params, index, -_hessian(model, params, index, steps[index]), keep)[2, 2]))


def one(task) -> dict:
    """The true effect added to the identified person of one simulated record; never raises."""
    from smd_statespace.person import identify_person
    from smd_statespace.person.extend import fit_effects
    from smd_statespace.simulation import simulate_bouncing

    kind, size, generator, index, person, sim_seed, effects = task
    row = {"kind": kind, "size": size, "generator": generator, "index": index}
    try:
        sim = simulate_bouncing(noise=person_effects.NOISE, effects=effects,
                                **person_effects.simulation_settings(person, sim_seed, generator))
        base = identify_person(sim.record, measured_floor=False)
        fitted = fit_effects(base, [person_effects._true_spec(kind, base)])
    except Exception as exc:  # a record refused (contact lost) is reported, not fatal
        return {**row, "error": " ".join(str(exc).split())[:120]}
    name, key = person_effects.TRUE_PARAMETER[kind]
    truth = float(sim.truth["effects"][next(iter(effects))][key])
    estimate = fitted.effect_estimates().loc[name]
    whole_record, truth_in_range = person_effects.fair_comparison(fitted, name, truth)
    return {**row, "parameter": name, "truth": truth, "estimate": float(estimate["value"]),
            "sd": float(estimate["sd"]), "low": float(estimate["low"]), "high": float(estimate["high"]),
            "sd_sandwich": _sandwich_sd(fitted, fitted.model.position(name)),
            "whole_record": whole_record, "truth_in_range": truth_in_range,
            "f_h_true": person["f_h"], "f_h": fitted.f_h, "f_h_sd": float(fitted.sd("f_h"))}


def fair_rows(rows: pd.DataFrame) -> pd.DataFrame:
    """The records the comparison is fair on (fitted whole, truth in range), with each one's z and whether the
    reported interval, the information's and the wider of it and the sandwich's hold the truth."""
    z90 = stats.norm.ppf(0.95)
    fair = rows[rows["whole_record"].astype(bool) & rows["truth_in_range"].astype(bool)].copy()
    fair["z"] = (fair["estimate"] - fair["truth"]) / fair["sd"]
    fair["covered"] = (fair["low"] <= fair["truth"]) & (fair["truth"] <= fair["high"])  # as identify reports it
    fair["covered_information"] = fair["z"].abs() <= z90  # estimate +- 1.645 sd
    fair["covered_wider"] = ((fair["estimate"] - fair["truth"]).abs()
                             <= z90 * np.maximum(fair["sd"], fair["sd_sandwich"].fillna(0.0)))
    fair["sandwich_ratio"] = fair["sd_sandwich"] / fair["sd"]
    return fair


def summary(fair: pd.DataFrame) -> pd.DataFrame:
    """Coverage and z per kind and size of :func:`fair_rows`."""
    return fair.groupby(["kind", "size"]).agg(records=("z", "size"), covered=("covered", "mean"),
                                              covered_information=("covered_information", "mean"),
                                              covered_wider=("covered_wider", "mean"), z_mean=("z", "mean"),
                                              z_sd=("z", "std"), sandwich_ratio=("sandwich_ratio", "median"))


def main(argv=None) -> None:
    args, rows, started = person_effects.study_of_tasks(__doc__.split("\n\n")[0], KINDS, one, argv)
    done = rows[rows["estimate"].notna()] if "estimate" in rows else rows.iloc[:0]
    fair = fair_rows(done)
    markdown_report(f"Effects' parameter intervals against the truth (seed {args.seed}, {args.records} records a row)",
                    "effect_intervals.py", argv, started,
                    [f"90 % intervals hold the truth on {int(fair['covered'].sum())} of {len(fair)} records fitted "
                     f"whole with the truth in the search range; left out: "
                     f"{int((~done['whole_record'].astype(bool)).sum())} fitted in part, "
                     f"{int((~done['truth_in_range'].astype(bool)).sum())} with the truth outside the range; "
                     f"{len(rows) - len(done)} records refused.", "",
                     markdown_table(summary(fair).reset_index().round(3)), "", markdown_table(rows.round(4))],
                    args.out)


if __name__ == "__main__":
    main()
