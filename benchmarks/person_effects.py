"""Hidden-effect study of the record-level ``diagnose`` (:func:`smd_statespace.person.diagnose.diagnose_person`).

Simulated people bounce for 30 s at 100 Hz (1 % BW noise) with one hidden
physical effect, at a small and a large size, or with none; each record is
identified as a user would (``identify_person`` with its defaults) and
diagnosed with the default candidates. Counted: how often the true effect is
ranked first (and significant), false alarms on clean records, the residual
(innovation sd) and the person's errors before and after the top candidate
is added::

    python benchmarks/person_effects.py --jobs 2          # 8 records per kind and size, 16 clean
    python benchmarks/person_effects.py --records 2       # a smoke run

Effects (:data:`KINDS`): extra harmonics 5-6 (``harmonics``), a cubic spring
(``cubic_stiffness``), a floor mode with the floor acceleration measured
(kind ``floor_measured``: the record's ``floor_acc`` kept, so the candidate
``floor_mode`` takes the measured floor) and without it (the same records, ``floor_acc`` dropped:
only ``harmonics`` and ``cubic_stiffness`` can be proposed, so a correct
answer is "no candidate fits", which is what is counted). The effect's size
is measured on every record as the RMS of the GRF difference it makes
(same seed, noise-free, with and without the effect) over the noise sd.

Everything random comes from ``numpy.random.SeedSequence(--seed)`` (one
child per record, fresh seeds: not those of the tests or of
``person_accuracy.py``); the rows do not depend on ``--jobs``.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd
from tqdm.auto import tqdm

from smd_statespace.io import G
from smd_statespace.person import identify_person
from smd_statespace.person.diagnose import diagnose_person
from smd_statespace.simulation import DEFAULT_BLF, simulate_bouncing

REPO = Path(__file__).resolve().parents[1]
DURATION, FS, NOISE = 30.0, 100.0, 0.01

KINDS = {
    "clean": [None],
    "harmonics": [{"harmonics": {"blf": (0.022, 0.016)}}, {"harmonics": {"blf": (0.065, 0.048)}}],
    "cubic_stiffness": [{"cubic_stiffness": {"beta_3": 450.0}}, {"cubic_stiffness": {"beta_3": 1500.0}}],
    "floor_measured": [{"floor_mode": {"modal_mass": 2000.0}}, {"floor_mode": {"modal_mass": 700.0}}],
    "floor_unmeasured": [{"floor_mode": {"modal_mass": 2000.0}}, {"floor_mode": {"modal_mass": 700.0}}],
}
"""Hidden effects at a small and a large size (about 2x and 5x the noise on a typical record)."""

EXPECTED = {"clean": None, "harmonics": "harmonics", "cubic_stiffness": "cubic_stiffness",
            "floor_measured": "floor_mode", "floor_unmeasured": None}
"""The right answer of ``diagnose`` per kind (None: nothing proposed)."""


def tasks(records: int, seed: int) -> list:
    """``(kind, size, index, person, sim_seed)`` for every record; clean records twice as many."""
    out = []
    children = iter(np.random.SeedSequence(seed).spawn(10_000))
    for kind, sizes in KINDS.items():
        for size, effects in enumerate(sizes):
            for i in range(records * (2 if kind == "clean" else 1)):
                rng = np.random.default_rng(next(children))
                person = {"f_b": rng.uniform(1.5, 3.5), "f_h": rng.uniform(1.8, 4.2), "xi_h": rng.uniform(0.1, 0.5),
                          "mass": rng.uniform(50.0, 90.0),
                          "blf": tuple(np.array(DEFAULT_BLF) * rng.uniform(0.7, 1.3, 4))}
                out.append((kind, size, i, person, int(rng.integers(2**31)), effects))
    return out


def one(task) -> dict:
    """Simulate, identify and diagnose one record; never raises."""
    kind, size, index, person, sim_seed, effects = task
    row = {"kind": kind, "size": ("small", "large")[size] if effects else "-", "index": index, **{
        k: v for k, v in person.items() if k != "blf"}}
    common = dict(mass=person["mass"], f_b=person["f_b"], f_h=person["f_h"], xi_h=person["xi_h"], duration=DURATION,
                  fs=FS, blf=person["blf"], seed=sim_seed)
    started = time.perf_counter()
    try:
        sim = simulate_bouncing(noise=NOISE, effects=effects, **common)
        record = sim.record
        if kind == "floor_unmeasured":
            record = dataclasses.replace(record, floor_acc=None)
        if effects:
            plain = simulate_bouncing(noise=0.0, **common).record.force
            forced = simulate_bouncing(noise=0.0, effects=effects, **common).record.force
            row["effect_size"] = float(np.sqrt(np.mean((forced - plain) ** 2)) / (NOISE * person["mass"] * G))
        base = identify_person(record)
        diagnosis = diagnose_person(base)
        table = diagnosis.table()
    except Exception as exc:  # noqa: BLE001 - one record must never kill the study
        row.update(error=f"{type(exc).__name__}: {str(exc).splitlines()[0][:160]}",
                   seconds=time.perf_counter() - started)
        return row
    top = diagnosis.missing[0] if diagnosis.missing else None
    row.update(error="", seconds=time.perf_counter() - started, proposed=top or "", variation=base.model.variation,
               base_warned=any("serially correlated" in w for w in base.warnings),
               f_h_before=base.f_h, xi_h_before=base.xi_h, sigma_before=base.sigma)
    if top is not None:
        chosen = table.loc[top]
        row.update(f_h_after=float(chosen["f_h"]), xi_h_after=float(chosen["xi_h"]),
                   noise_change_pct=float(chosen["noise_change_%"]), lr=float(chosen["lr"]),
                   estimate=float(chosen["estimate"]))
    else:
        row.update(f_h_after=base.f_h, xi_h_after=base.xi_h, noise_change_pct=0.0)
    row["correct"] = (top == EXPECTED[kind])
    return row


def summary(frame: pd.DataFrame) -> list:
    """Markdown table: one row per kind and size."""
    lines = ["| hidden effect | size | records (failed) | effect size / noise, median | right answer | "
             "ranked first | Ljung-Box warning before | |f_h error| before -> after, median | "
             "|xi_h error| before -> after, median | innovation sd change, median |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for (kind, size), rows in frame.groupby(["kind", "size"], sort=False):
        ok = rows[rows["error"] == ""]
        n = len(ok)
        if n == 0:
            lines.append(f"| {kind} | {size} | {len(rows)} ({len(rows)}) | | | | | | | |")
            continue
        expected = EXPECTED[kind] or "nothing"
        firsts = ", ".join(f"{k or 'nothing'} {v}" for k, v in ok["proposed"].replace("", None).fillna(
            "nothing").value_counts().items())
        f_before = (100 * (ok["f_h_before"] / ok["f_h"] - 1)).abs().median()
        f_after = (100 * (ok["f_h_after"] / ok["f_h"] - 1)).abs().median()
        x_before = (ok["xi_h_before"] - ok["xi_h"]).abs().median()
        x_after = (ok["xi_h_after"] - ok["xi_h"]).abs().median()
        size_text = f"{ok['effect_size'].median():.1f}" if "effect_size" in ok and ok["effect_size"].notna().any() \
            else "-"
        lines.append(f"| {kind} | {size} | {len(rows)} ({len(rows) - n}) | {size_text} | "
                     f"{int(ok['correct'].sum())}/{n} ({expected}) | {firsts} | {int(ok['base_warned'].sum())}/{n} | "
                     f"{f_before:.1f} % -> {f_after:.1f} % | {x_before:.3f} -> {x_after:.3f} | "
                     f"{ok['noise_change_pct'].median():+.1f} % |")
    return lines


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--records", type=int, default=8, help="records per kind and size (default 8; clean: 2x)")
    parser.add_argument("--seed", type=int, default=77, help="root of the SeedSequence (default 77)")
    parser.add_argument("--jobs", type=int, default=1, help="processes (default 1)")
    parser.add_argument("--csv", type=Path, default=None, help="also write every record's row here")
    args = parser.parse_args(argv)
    work = tasks(args.records, args.seed)
    started = time.perf_counter()
    rows = []
    with tqdm(total=len(work), desc="records", unit="record", file=sys.stderr) as bar:
        if args.jobs > 1:
            with ProcessPoolExecutor(args.jobs) as pool:
                for row in pool.map(one, work):
                    rows.append(row)
                    bar.update()
        else:
            for task in work:
                rows.append(one(task))
                bar.update()
    frame = pd.DataFrame(rows)
    if args.csv:
        frame.to_csv(args.csv, index=False)
    print("\n".join(summary(frame)))
    failed = frame[frame["error"] != ""]
    for _, row in failed.iterrows():
        print(f"failed: {row['kind']} {row['size']} #{row['index']}: {row['error']}")
    print(f"\n{len(frame)} records, {(time.perf_counter() - started) / 60:.1f} min, {args.jobs} process(es)")


if __name__ == "__main__":
    main()
