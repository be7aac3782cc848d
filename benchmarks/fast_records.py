"""Per-cycle identification of 1000 Hz records: every sample against decimated to 100 Hz.

The article's noise levels and the random walk of its parameters (Eq. 6) are set per
sample at 100 Hz (its insoles). A force plate records at 1000 Hz; run at every sample,
the same settings walk ten times as often per second and each cycle costs ten times
more. ``CycleRunner(rate=100)`` (the default; ``--rate`` on the command line) decimates
such a record first. This study simulates 1000 Hz records of people drawn as in
``person_accuracy.py`` and identifies each with the chosen per-cycle estimators twice,
``rate=None`` (every sample) and ``rate=100``::

    python benchmarks/fast_records.py --jobs 2 --records 8 --seed 5              # ekf, ukf: about 4 min
    python benchmarks/fast_records.py --jobs 2 --records 2 --estimators grid     # about 6 min

Columns: median over records of the median absolute error of ``f_h`` and ``xi_h`` over a
record's plausible cycles, and the seconds per record. Everything random comes from
``SeedSequence(--seed)``; the rows do not depend on ``--jobs``.
"""

from __future__ import annotations

import argparse
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd
from tqdm.auto import tqdm

sys.path.insert(0, str(Path(__file__).resolve().parent))
import person_accuracy  # noqa: E402  (draw_people: the same people as the accuracy study)

from smd_statespace.identify.plausibility import flagged  # noqa: E402
from smd_statespace.identify.runner import CycleRunner  # noqa: E402
from smd_statespace.simulation import simulate_bouncing  # noqa: E402

FS = 1000.0
DURATION = 15.0
RATES = (("every sample (1000 Hz)", None), ("decimated to 100 Hz", 100.0))


def one(task) -> dict:
    """Simulate one 1000 Hz record and identify it with one estimator at one rate; never raises."""
    person, estimator, (label, rate) = task
    row = {"estimator": estimator, "rate": label, "record": int(person["record"]), "error": ""}
    blf = [person[f"blf{i}"] for i in range(1, 5)]
    record = simulate_bouncing(mass=person["mass"], f_b=person["f_b"], f_h=person["f_h"], xi_h=person["xi_h"],
                               duration=DURATION, fs=FS, blf=blf, seed=int(person["sim_seed"])).record
    started = time.perf_counter()
    try:
        table = CycleRunner(estimator=estimator, progress=False, rate=rate, seed=int(person["sim_seed"])).run(record)
    except Exception as exc:  # noqa: BLE001 - one record must never kill the study
        row["error"] = f"{type(exc).__name__}: {str(exc).splitlines()[0][:120]}"
        return row
    row["seconds"] = time.perf_counter() - started
    ok = table[(table["status"] == "ok").to_numpy() & ~flagged(table)]
    row["cycles"] = len(ok)
    for name in ("f_h", "xi_h"):
        row[f"{name}_abs_error"] = float(np.median(np.abs(ok[name] - person[name]))) if len(ok) else np.nan
    return row


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=8, help="people (default 8)")
    parser.add_argument("--seed", type=int, default=5, help="root of the SeedSequence (default 5)")
    parser.add_argument("--estimators", default="ekf,ukf", help="per-cycle estimators (default ekf,ukf)")
    parser.add_argument("--jobs", type=int, default=1, help="processes (default 1)")
    args = parser.parse_args(argv)
    people = person_accuracy.draw_people(args.records, args.seed)
    tasks = [(person, estimator, rate) for estimator in args.estimators.split(",") for rate in RATES
             for _, person in people.iterrows()]
    started = time.perf_counter()
    with ProcessPoolExecutor(max(1, args.jobs)) as pool:
        frame = pd.DataFrame(list(tqdm(pool.map(one, tasks), total=len(tasks), unit="run", desc="records")))
    print(f"{args.records} people, {DURATION:g} s at {FS:g} Hz, seed {args.seed}")
    print("| estimator | samples used | records (failed) | f_h abs. error, median | xi_h abs. error, median | "
          "s per record |\n|---|---|---|---|---|---|")
    for (estimator, label), rows in frame.groupby(["estimator", "rate"], sort=False):
        ok = rows[rows["error"] == ""]
        print(f"| {estimator} | {label} | {len(rows)} ({len(rows) - len(ok)}) | "
              f"{ok['f_h_abs_error'].median():.3f} Hz | {ok['xi_h_abs_error'].median():.3f} | "
              f"{ok['seconds'].median():.1f} |")
    for _, row in frame[frame["error"] != ""].iterrows():
        print(f"failed: {row['estimator']} {row['rate']} #{row['record']}: {row['error']}")
    print(f"\n{len(frame)} runs, {(time.perf_counter() - started) / 60:.1f} min, {args.jobs} process(es)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
