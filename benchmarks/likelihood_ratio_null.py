"""Is the record-level likelihood ratio of an absent effect chi-square distributed? Three null studies.

``diagnose`` and ``identify --effect`` judge an effect by its likelihood ratio against chi-square with the
effect's degrees of freedom. That is right only if, on records without the effect, the ratio is so
distributed. Three studies, each over many records without the effect (these were Monte-Carlo tests in
``tests/`` until issue 46 moved them here; each test keeps one record with and one without):

- ``regressor``: records drawn from the record-level state-space model itself (its statsmodels simulator,
  :class:`~smd_statespace.person.statespace.RecordStateSpace`), a regressor that is not there
  (``sin(2 pi 0.7 t)``) added: the exact Gaussian likelihood, chi-square(1) expected;
- ``disturbance``: simulated people (8 s, 100 Hz) with a known disturbance ``c_d sin(2 pi 7.3 t)`` of unknown
  gain added through an effect (linear: the likelihood stays exact): chi-square(1) expected;
- ``cubic``: the same people with a cubic spring added (nonlinear: the likelihood is the extended Kalman
  filter's, linearised about the predicted path until it settles): near chi-square(1) expected, every path
  settled.

Per study: the records, the mean ratio (1 for chi-square(1); the sd of a mean of 30 is about 0.26), the median
(0.45), the share over the 95 % point (3.84), the Kolmogorov-Smirnov p against chi-square(1)::

    python benchmarks/likelihood_ratio_null.py --records 30 --jobs 2 --out benchmarks/results/likelihood_ratio_null.md

Seeds: ``numpy.random.SeedSequence(--seed)``, one child per study and record; the rows do not depend on
``--jobs``.
"""

from __future__ import annotations

import argparse
import inspect
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from scipy import stats
from tqdm.auto import tqdm

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the tests' known_disturbance effect

STUDIES = ("regressor", "disturbance", "cubic")


def regressor_ratio(seed) -> dict:
    """One record drawn from the record-level model; the ratio of adding a regressor that is not there."""
    from smd_statespace.person import CycleTiming, RecordModel, Regressor
    from smd_statespace.person.search import fit_model
    from smd_statespace.person.statespace import RecordStateSpace

    t = np.arange(0.0, 8.0, 0.01)
    timing = CycleTiming(np.arange(-0.5, 8.6, 0.5))
    offset = Regressor("offset", np.ones_like(t), dynamic=False)
    absent = Regressor("absent", np.sin(2 * np.pi * 0.7 * t + 0.3))
    truth = RecordModel(t, np.zeros_like(t), timing, n_harmonics=2, regressors=(offset,))
    params = np.array([2.6, 0.3, -6.0, -1.0, -3.0])
    delta = np.zeros(2 + truth.n_coefficients + 1)
    delta[2:2 + truth.n_coefficients] = [0.0, -0.25, 0.05, 0.1, 0.12]
    simulator = RecordStateSpace(truth, delta)
    keyword = "rng" if "rng" in inspect.signature(simulator.simulate).parameters else "random_state"
    y = simulator.simulate(params, t.size, **{keyword: np.random.default_rng(seed)})
    without = fit_model(RecordModel(t, y, timing, n_harmonics=2, regressors=(offset,)), params)
    with_ = fit_model(RecordModel(t, y, timing, n_harmonics=2, regressors=(offset, absent)), without["params"])
    return {"lr": max(2.0 * (with_["loglike"] - without["loglike"]), 0.0), "settled": True}


def effect_ratio(study: str, seed) -> dict:
    """One simulated person without the effect; the ratio of adding it (``fit_effects``, Wald intervals)."""
    from helpers import known_disturbance

    from smd_statespace.effects import make_effect
    from smd_statespace.person import identify_person
    from smd_statespace.person.extend import fit_effects
    from smd_statespace.simulation import simulate_bouncing

    effect = known_disturbance() if study == "disturbance" else make_effect("cubic_stiffness")
    sim = simulate_bouncing(mass=70, f_b=2.2, f_h=2.7, xi_h=0.3, duration=8, seed=seed)
    base = identify_person(sim.record, variation="independent", timing="template", intervals="wald")
    fitted = fit_effects(base, [effect], intervals="wald")
    test = fitted.effect_test()
    return {"lr": float(test["lr"]), "settled": bool(fitted.settled), "df": int(test["lr_df"])}


def one(task) -> dict:
    study, index, seed = task
    started = time.perf_counter()
    row = regressor_ratio(seed) if study == "regressor" else effect_ratio(study, seed)
    return {"study": study, "index": index, **row, "seconds": time.perf_counter() - started}


def tasks(records: int, seed: int) -> list:
    root = np.random.SeedSequence(seed)
    return [(study, i, child) for study, study_seed in zip(STUDIES, root.spawn(len(STUDIES)))
            for i, child in enumerate(study_seed.spawn(records))]


def summary(rows: list) -> list:
    lines = ["| study | records | mean LR (chi2(1): 1) | median (0.45) | over 3.84 (5 %) | KS p vs chi2(1) | "
             "paths settled | s per record |", "|---|---|---|---|---|---|---|---|"]
    for study in STUDIES:
        mine = [r for r in rows if r["study"] == study]
        if not mine:
            continue
        lr = np.array([r["lr"] for r in mine])
        lines.append(f"| {study} | {lr.size} | {lr.mean():.2f} | {np.median(lr):.2f} | "
                     f"{int((lr > stats.chi2(1).ppf(0.95)).sum())}/{lr.size} | "
                     f"{stats.kstest(lr, stats.chi2(1).cdf).pvalue:.2g} | "
                     f"{sum(r['settled'] for r in mine)}/{lr.size} | {np.median([r['seconds'] for r in mine]):.1f} |")
    return lines


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--records", type=int, default=30, help="records per study (default 30)")
    parser.add_argument("--seed", type=int, default=2026, help="root of the SeedSequence (default 2026)")
    parser.add_argument("--jobs", type=int, default=1, help="processes (default 1)")
    parser.add_argument("--studies", default=",".join(STUDIES), help=f"which (default all: {', '.join(STUDIES)})")
    parser.add_argument("--out", type=Path, default=None, help="also write the table here (markdown)")
    args = parser.parse_args(argv)
    work = [task for task in tasks(args.records, args.seed) if task[0] in args.studies.split(",")]
    started = time.perf_counter()
    with ProcessPoolExecutor(args.jobs) as pool:
        rows = list(tqdm(pool.map(one, work), total=len(work), desc="records", unit="record", file=sys.stderr))
    lines = summary(rows) + ["", f"{len(rows)} records, {(time.perf_counter() - started) / 60:.1f} min, "
                                 f"{args.jobs} process(es), seed {args.seed}"]
    print("\n".join(lines))
    if args.out:
        args.out.write_text("\n".join(lines) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
