"""What the per-cycle method's cycles say about the person together (identify.pooled), against the truth.

Simulated people from the article's Table 2 (``sample_population``, ``f_h`` inside the prior 1-4 Hz, BLFs
below the prior box's largest coefficient) bounce for ``--duration`` s at ``f_b`` cycling through 1.5-3.0 Hz,
with the simulator's cycle-to-cycle variation (``--variation``) and 1 % BW noise. Each record is identified
cycle by cycle exactly as ``identify REC --estimator NAME`` does (``preprocess``, ``CycleRunner`` with its
defaults)::

    python benchmarks/pooled_cycles.py --records 64 --jobs 2 --seed 7 \
        --csv benchmarks/results/pooled_cycles_jumps_seed7.csv

Per parameter, two answers for the record:

- the library's (:func:`~smd_statespace.identify.pooled.pool_cycles`): the cycles' median, and how often
  the range of the central 90 % of the cycles holds the truth;
- the experiment the library declined: where at least half of the plausible cycles (and 3) determine the
  parameter (and, for ``xi_h`` and the BLFs, ``f_h`` too), a random-effects pool of those cycles
  (``statsmodels``' ``combine_effects``, Paule-Mandel; the Hartung-Knapp-Sidik-Jonkman sd where wider,
  Jackson et al. 2017) with its 90 % t interval: how often it is made and how often it holds the truth.

``BLF_i`` is per force cycle in the simulator: its truth here is the mean amplitude over the force cycles
that the identified cycles span (:func:`realised_blf`). Same ``--seed``, same tables, whatever ``--jobs``.
"""

from __future__ import annotations

import argparse
import time
import warnings
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pandas as pd

from accuracy import markdown_table  # benchmarks/, the script's own folder
from smd_statespace.errors import SMDInputError
from smd_statespace.identify import CycleRunner
from smd_statespace.identify.pooled import POOLED, pool_cycles
from smd_statespace.model import SMDModel
from smd_statespace.signals import preprocess
from smd_statespace.simulation import sample_population, simulate_bouncing

FB_LEVELS = (1.5, 2.0, 2.5, 3.0)


def realised_blf(force_cycles: pd.DataFrame, table: pd.DataFrame) -> dict:
    """The mean amplitude of each of the first three harmonics over the force cycles the identified cycles span:
    what a pool of the cycles estimates (the person's nominal ``blf_i`` differs from it by the simulator's
    cycle-to-cycle variation)."""
    ok = table[table["status"] == "ok"]
    inside = force_cycles[(force_cycles["t_start"] >= ok["t_start"].min() - 0.05)
                          & (force_cycles["t_end"] <= ok["t_end"].max() + 0.05)]
    return {f"blf_{i}": float(inside[f"blf{i}"].mean()) for i in (1, 2, 3)}


def one_record(task):
    """Simulate, identify per cycle, pool: one row per parameter (truth, pool, verdict); a record the library
    refuses (a bouncing frequency outside its range, ...) gives one row saying why."""
    try:
        return _one_record(task)
    except SMDInputError as exc:
        return [{"record": task[0], "parameter": "refused", "reason": " ".join(str(exc).split())}]


def _one_record(task):
    index, seed, options = task
    people_seed, record_seed, runner_seed = seed.spawn(3)
    person = sample_population(1, FB_LEVELS[index % len(FB_LEVELS)], seed=people_seed,
                               bounds={"f_h": (1.0, 4.0), "blf": (0.0, 0.4)}).iloc[0]
    blf = (person["blf1"], person["blf2"], person["blf3"], 0.02)
    sim = simulate_bouncing(mass=person["mass"], f_b=person["f_b"], f_h=person["f_h"], xi_h=person["xi_h"],
                            blf=blf, duration=options["duration"], variation=options["variation"],
                            seed=int(record_seed.generate_state(1)[0]))
    started = time.perf_counter()
    table = CycleRunner(SMDModel(), estimator=options["estimator"], progress=False,
                        seed=int(runner_seed.generate_state(1)[0])).run(preprocess(sim.record))
    seconds = time.perf_counter() - started
    truth = {"f_h": person["f_h"], "xi_h": person["xi_h"], **realised_blf(sim.cycles, table)}
    pools = random_effects_pools(table)
    rows = []
    for name, row in pool_cycles(table).iterrows():
        pool = pools.get(name, {})
        rows.append({"record": index, "f_b": person["f_b"], "parameter": name, "truth": truth[name], **row.to_dict(),
                     "held": bool(row["low"] <= truth[name] <= row["high"]),
                     "error": float(row["value"] - truth[name]), "pool_made": bool(pool),
                     "pool_value": pool.get("value", np.nan), "pool_sd": pool.get("sd", np.nan),
                     "pool_held": bool(pool) and bool(pool["low"] <= truth[name] <= pool["high"]),
                     "seconds": seconds})
    return rows


def random_effects_pools(table: pd.DataFrame, level: float = 0.9) -> dict:
    """The pool the library declined, per parameter where it would be made: ``{name: {value, sd, low, high}}``."""
    from scipy import stats
    from statsmodels.stats.meta_analysis import combine_effects

    from smd_statespace.identify.plausibility import flagged

    ok = table[table["status"] == "ok"]
    ok = ok[~np.asarray(flagged(ok), dtype=bool)]
    pools = {}
    for name in POOLED:
        usable = ok[np.isfinite(ok[name]) & np.isfinite(ok[f"{name}_sd"])]
        chosen = usable[usable[f"{name}_determined"].astype(bool).to_numpy()]
        if len(chosen) < max(3, 0.5 * len(usable)) or (name != "f_h" and "f_h" not in pools):
            continue
        with warnings.catch_warnings(), np.errstate(divide="ignore", invalid="ignore"):
            warnings.simplefilter("ignore")  # identical estimates: an undefined I^2
            fit = combine_effects(chosen[name].to_numpy(float), np.maximum(chosen[f"{name}_sd"].to_numpy(float),
                                                                           1e-12) ** 2)
        sd = float(max(fit.sd_eff_w_re, np.nan_to_num(fit.sd_eff_w_re_hksj)))
        half = stats.t.ppf(0.5 + level / 2.0, len(chosen) - 1) * sd
        value = float(fit.mean_effect_re)
        pools[name] = {"value": value, "sd": sd, "low": value - half, "high": value + half}
    return pools


def summary(rows: pd.DataFrame) -> pd.DataFrame:
    """Per parameter: the library's answer (median, the cycles' range) and the declined random-effects pool."""
    out = []
    for name in POOLED:
        part = rows[rows["parameter"] == name]
        made = part[part["pool_made"].astype(bool)]
        out.append({"parameter": name, "records": len(part),
                    "median \\|error\\|": part["error"].abs().median(),
                    "cycles' central 90 % holds truth": f"{int(part['held'].sum())}/{len(part)}",
                    "pool made": len(made),
                    "pool's 90 % interval holds truth": f"{int(made['pool_held'].sum())}/{len(made)}" if len(made)
                    else "-",
                    "pool: median \\|error\\|": (made["pool_value"] - made["truth"]).abs().median() if len(made)
                    else np.nan,
                    "pool: median sd": made["pool_sd"].median() if len(made) else np.nan})
    return pd.DataFrame(out).set_index("parameter")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=24)
    parser.add_argument("--duration", type=float, default=30.0)
    parser.add_argument("--estimator", default="ekf")
    parser.add_argument("--variation", default="jumps")
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--csv", help="write every record's rows here")
    args = parser.parse_args(argv)
    options = {"duration": args.duration, "estimator": args.estimator, "variation": args.variation}
    seeds = np.random.SeedSequence(args.seed).spawn(args.records)
    tasks = [(i, seeds[i], options) for i in range(args.records)]
    started = time.perf_counter()
    if args.jobs > 1:
        with ProcessPoolExecutor(max_workers=args.jobs) as pool:
            results = list(pool.map(one_record, tasks))
    else:
        results = [one_record(task) for task in tasks]
    rows = pd.DataFrame([row for record in results for row in record])
    refused = rows[rows["parameter"] == "refused"]
    rows = rows[rows["parameter"] != "refused"]
    if args.csv:
        rows.to_csv(args.csv, index=False)
    print(f"{args.records} records of {args.duration:g} s ({args.variation}), {args.estimator}, seed {args.seed}: "
          f"{time.perf_counter() - started:.0f} s")
    for _, row in refused.iterrows():
        print(f"record {row['record']} refused: {row['reason']}")
    table = summary(rows).reset_index()
    print(markdown_table(table, {c: ".3g" for c in table.columns if "median" in c}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
