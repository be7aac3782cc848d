"""Are the printed detection limits of a change in time honest? A change placed at the limit, found how often?

``identify`` prints, for a record that shows no change of the person, the change of ``f_h`` (a drift over the
record, a step in its middle) that its score tests would find 80 % of the time
(:mod:`smd_statespace.person.detection`). For each simulated person this script identifies the clean record,
reads its limits, then simulates the *same* record (person, seed: the same noise and force variation) with
``f_h`` drifting, and stepping, by exactly the limit, identifies it and asks whether the person was found to change
(``result.change["changed"]`` names ``f_h``). Where the limit is honest, about 80 % of the records are found
where it is printed (``f_h`` determined); the records where it is not printed show what the words withhold.

::

    SMD_STATESPACE_THREADS=1 python benchmarks/change_limits.py --records 12 --jobs 2 --seed 5 \\
        --csv benchmarks/results/change_limits_seed5.csv
"""

from __future__ import annotations

import os

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

import argparse  # noqa: E402
import functools  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from smd_statespace.accelerometer import accelerometer_record  # noqa: E402
from smd_statespace.person import identify_person  # noqa: E402
from smd_statespace.simulation import DEFAULT_BLF, simulate_bouncing, simulate_lab_record  # noqa: E402
from smd_statespace.simulation.phone import simulate_phone  # noqa: E402

GENERATORS = ("jumps", "smooth", "lab", "phone")
"""The two generators of force variation of ``simulate_bouncing``, a lab's export of a whole trial
(``simulate_lab_record``: standing before and after, 1000 Hz, hum, a drifting zero; its change of ``f_h`` is the
simulator's own, linear over the bout or a step in its middle) and a phone at the waist (``simulate_phone``, its
defaults: 200 Hz, tilted 20 degrees, swaying, biased, jittered, 0.5 % of samples dropped; written as a phone app
writes it and read back without the mass, as a user's file)."""
DURATION, FS, NOISE = 30.0, 100.0, 0.01
SHAPES = {"f_drift": "drift", "f_step": "step"}


def people(records: int, seed: int, generators=GENERATORS) -> list:
    """``(generator, index, person, sim_seed)``: each record's person and seed from its place."""
    out = []
    for g, generator in enumerate(GENERATORS):
        if generator not in generators:
            continue
        for i in range(records):
            rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(g, i)))
            person = {"f_b": rng.uniform(1.5, 3.5), "f_h": rng.uniform(1.8, 4.2), "xi_h": rng.uniform(0.1, 0.5),
                      "mass": rng.uniform(50.0, 90.0), "blf": tuple(np.array(DEFAULT_BLF) * rng.uniform(0.7, 1.3, 4))}
            out.append((generator, i, person, int(rng.integers(2**31))))
    return out


def _identify(person, sim_seed, generator, kind=None, size=0.0):
    """The person of the record with ``f_h`` changed by ``size``: a coefficient ``c`` of generic term ``kind``
    (``f_drift``, ``f_step``), or for a lab export the simulator's relative change of ``f_h``."""
    common = dict(mass=person["mass"], f_b=person["f_b"], f_h=person["f_h"], xi_h=person["xi_h"], blf=person["blf"],
                  seed=sim_seed)
    effects = {"term": {"kind": kind, "scale": DURATION, f"c_{kind}": size}} if kind else {}
    if generator == "lab":
        sim = simulate_lab_record(**common, f_h_change=size, change=SHAPES[kind] if kind else "drift")
    elif generator == "phone":
        phone = simulate_phone(duration=DURATION, variation="jumps", effects=effects, **common)
        with tempfile.TemporaryDirectory() as folder:
            path, _ = phone.write(Path(folder) / "phone.csv")
            return identify_person(accelerometer_record(path), threads=1)
    else:
        sim = simulate_bouncing(duration=DURATION, fs=FS, variation=generator, noise=NOISE, effects=effects, **common)
    return identify_person(sim.record, measured_floor=False, threads=1)


def run_one(task, factors=(1.0,)) -> list:
    """The clean record's limits, then the record with each change at each multiple of its limit: one row each."""
    generator, index, person, sim_seed = task
    started = time.perf_counter()
    base = dict(generator=generator, index=index, f_h=person["f_h"], f_b=person["f_b"], xi_h=person["xi_h"])
    try:
        clean = _identify(person, sim_seed, generator)
        tests = clean.change["time"]
        base.update(variation=clean.model.variation, f_h_determined=clean.determined("f_h"),
                    clean_changed="f_h" in clean.change["changed"])
        rows = []
        for kind, shape in SHAPES.items():
            limit = tests["limits"].get(kind)
            for factor in factors:
                row = {**base, "shape": shape, "factor": factor, "limit_c": limit["c"] if limit else np.nan,
                       "limit_percent": limit["percent"] if limit else np.nan}
                if limit and factor * limit["c"] < 1.5:
                    size = factor * (limit["percent"] / 100.0 if generator == "lab" else limit["c"])
                    changed = _identify(person, sim_seed, generator, kind, size)
                    row.update(found="f_h" in changed.change["changed"],
                               p_holm=min(t["p_holm"] for t in changed.change["time"]["terms"]
                                          if t["parameter"] == "f_h"))
                rows.append({**row, "error": "", "seconds": time.perf_counter() - started})
        return rows
    except Exception as exc:  # noqa: BLE001 - one record must never kill the study
        return [{**base, "error": f"{type(exc).__name__}: {str(exc).splitlines()[0][:160]}",
                 "seconds": time.perf_counter() - started}]


def summary(frame: pd.DataFrame) -> list:
    """Markdown: per generator and shape, found at the limit where it is printed and where it is not."""
    lines = ["| generator | change | change / limit | records (failed) | clean record said to change | limit printed (f_h determined) "
             "| found at the printed limit | limit not printed: found at the limit | limit (% of f_h), median "
             "[range] where printed |",
             "|---|---|---|---|---|---|---|---|---|"]
    for (generator, shape, factor), rows in frame.groupby(["generator", "shape", "factor"], sort=False):
        ok = rows[rows["found"].notna()]
        printed = ok[ok["f_h_determined"].astype(bool) & ~ok["clean_changed"].astype(bool)]
        withheld = ok[~ok["f_h_determined"].astype(bool) & ~ok["clean_changed"].astype(bool)]
        spread = (f"{printed['limit_percent'].median():.1f} [{printed['limit_percent'].min():.1f}-"
                  f"{printed['limit_percent'].max():.1f}]" if len(printed) else "-")
        lines.append(f"| {generator} | {shape} | {factor:g} | {len(rows)} ({int((rows['error'] != '').sum())}) | "
                     f"{int(ok['clean_changed'].astype(bool).sum())}/{len(ok)} | {len(printed)}/{len(ok)} | "
                     f"{int(printed['found'].astype(bool).sum())}/{len(printed)} | "
                     f"{int(withheld['found'].astype(bool).sum())}/{len(withheld)} | {spread} |")
    failed = frame[frame["error"].fillna("") != ""]
    lines += [f"\n{len(failed)} record(s) failed: " + "; ".join(f"{r.generator} {r.index}: {r.error}"
                                                          for r in failed.itertuples())] if len(failed) else []
    return lines


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=12, help="people per generator")
    parser.add_argument("--seed", type=int, default=5)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--generators", default=",".join(GENERATORS), help="comma-separated, of " + ", ".join(GENERATORS))
    parser.add_argument("--factors", default="1", help="the changes simulated, as multiples of the clean record's limit")
    parser.add_argument("--csv", type=Path, default=None, help="write the rows here (and the table beside it, .md)")
    args = parser.parse_args(argv)
    tasks = people(args.records, args.seed, args.generators.split(","))
    factors = tuple(float(f) for f in args.factors.split(","))
    started = time.perf_counter()
    with ProcessPoolExecutor(args.jobs) as pool:
        rows = [row for result in pool.map(functools.partial(run_one, factors=factors), tasks) for row in result]
    frame = pd.DataFrame(rows)
    text = "\n".join(summary(frame))
    print(text)
    print(f"\n{len(tasks)} records in {(time.perf_counter() - started) / 60:.1f} min")
    if args.csv:
        frame.to_csv(args.csv, index=False)
        args.csv.with_suffix(".md").write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
