"""A person on a measured floor, as ``identify REC --mass M`` answers by default: ``f_h`` against the truth.

The records are the ``floor_measured`` rows of ``benchmarks/person_effects.py`` (30 s, 100 Hz, 1 % BW
noise, the article's plate mode 1 at 3.48 Hz under the person, modal mass 2000 kg "small" and 700 kg
"large", the ``jumps`` and ``smooth`` generators; the same people and seeds for the same ``--seed``), and,
with ``--resonance``, a person bouncing at the floor's resonance (``f_b`` 3.5 Hz, ``f_h`` 3.65 Hz,
``xi_h`` 0.47, 88 kg; 20 and 30 s, seeds 1-3; the force's rate jittering alone, and with its harmonics
jumping too), the person of ``tests/test_floor_effect.py``. Each record is identified with
:func:`~smd_statespace.person.identify_person`'s defaults (the measured floor in the model); per record:
``f_h`` and ``xi_h`` against the truth, whether the calibrated interval holds it, the floor's likelihood
ratio against the person without it, whether ``identify`` warned that the floor fits worse, where the
cycle starts of the answer came from (the note of ``fit._starts_without_floor``: ``new`` placed again on
the force less the floor's share, ``grf`` the first, empty where the code has no such step) and the
seconds. Run it in two trees to compare code (``PYTHONPATH=/tmp/base python -P benchmarks/floor_starts.py``)::

    python benchmarks/floor_starts.py --jobs 2 --records 8 --csv /tmp/floor_starts.csv
    python benchmarks/floor_starts.py --jobs 2 --records 8 --seed 93 --generators jumps,smooth --resonance
    python benchmarks/floor_starts.py --summary after.csv --before before.csv    # the table, side by side

Everything random comes from ``numpy.random.SeedSequence(--seed)`` through ``person_effects.tasks``; the rows do
not depend on ``--jobs``.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from person_effects import NOISE, simulation_settings, tasks  # noqa: E402

from smd_statespace.person import identify_person  # noqa: E402
from smd_statespace.progress import tqdm  # noqa: E402
from smd_statespace.simulation import simulate_bouncing  # noqa: E402

RESONANCE = dict(mass=88.0, f_b=3.5, f_h=3.65, xi_h=0.47, blf=(0.29, 0.11, 0.04, 0.02),
                 effects={"floor_mode": {"modal_mass": 2000.0}})
"""The person at the floor's resonance (``tests/test_floor_effect.py``'s ``FLOOR_RESONANCE`` without its seed and
length)."""


def work(records: int, seed: int, generators, resonance: bool) -> list:
    """``(row label, simulate_bouncing's arguments)`` for every record."""
    out = []
    for kind, size, generator, index, person, sim_seed, effects in tasks(records, seed, generators=generators,
                                                                       kinds=("floor_measured",)):
        arguments = dict(noise=NOISE, effects=effects, **simulation_settings(person, sim_seed, generator))
        out.append(({"row": f"{generator} {size}", "index": index}, arguments))
    if resonance:
        for duration in (20, 30):
            for sim_seed in (1, 2, 3):
                for variation, extra in (("rate only", {"coef_variation": 0.0}), ("jumps", {})):
                    out.append(({"row": f"resonance, {variation}", "index": f"{duration} s, seed {sim_seed}"},
                                dict(duration=duration, seed=sim_seed, **RESONANCE, **extra)))
    return out


def one(task) -> dict:
    """Identify one record as a user would; never raises."""
    label, arguments = task
    row = {**label, "f_h_true": arguments["f_h"], "xi_h_true": arguments["xi_h"], "f_b": arguments["f_b"]}
    record = simulate_bouncing(**arguments).record
    started = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = identify_person(record)
    except Exception as exc:  # noqa: BLE001 - one record must never kill the study
        return {**row, "error": f"{type(exc).__name__}: {str(exc).splitlines()[0][:160]}"}
    low, high = result.intervals["f_h"]
    note = next((n for n in result.notes if n.startswith("the cycle starts were placed again")), "")
    return {**row, "error": "", "f_h": result.f_h, "xi_h": result.xi_h, "f_h_error": result.f_h / row["f_h_true"] - 1,
            "covered": bool(low <= row["f_h_true"] <= high), "lr": result.effect_test()["lr"],
            "warned": any("floor_acc makes the fit worse" in w for w in result.record_warnings),
            "starts": "" if not note else ("new" if note.endswith("the new starts is kept") else "grf"),
            "seconds": time.perf_counter() - started}


def summary(frame: pd.DataFrame, before: pd.DataFrame | None = None) -> list:
    """Markdown rows per row label: ``|f_h error|`` median and worst, within 3 %, covered, warned, negative ratios,
    where the starts came from, seconds; ``before -> after`` where ``before`` is given (matched by row and index)."""
    def cells(rows):
        ok = rows[rows["error"] == ""]
        error = 100 * ok["f_h_error"].abs()
        return [f"{len(ok)} ({len(rows) - len(ok)})", f"{error.median():.1f} %", f"{error.max():.1f} %",
                f"{int((error <= 3).sum())}/{len(ok)}", f"{int(ok['covered'].sum())}/{len(ok)}",
                f"{int(ok['warned'].sum())}/{len(ok)}", f"{int((ok['lr'] < 0).sum())}/{len(ok)}",
                f"{ok['seconds'].median():.1f}"]

    names = ["records (failed)", "\\|f_h error\\| median", "worst", "within 3 %", "interval holds the truth",
             "warned", "ratio < 0", "s per record"]
    lines = ["| row | " + " | ".join(names) + " | starts from the force less the floor's share |",
             "|---" * (len(names) + 2) + "|"]
    for name, rows in frame.groupby("row", sort=False):
        after = cells(rows)
        if before is not None:
            earlier = cells(before[before["row"] == name])
            after = [f"{a} -> {b}" if a != b else a for a, b in zip(earlier, after)]
        kept = rows["starts"].fillna("") if "starts" in rows else pd.Series([], dtype=str)
        lines.append(f"| {name} | " + " | ".join(after) + f" | {int((kept == 'new').sum())} of "
                     f"{int(kept.isin(['new', 'grf']).sum())} placed again |")
    return lines


def read(path) -> pd.DataFrame:
    """A CSV of this script's rows, its text columns empty where they were written empty."""
    frame = pd.read_csv(path)
    for column in ("error", "starts"):
        frame[column] = frame[column].astype(object).fillna("")
    return frame


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=8, help="records per generator and size (default 8)")
    parser.add_argument("--seed", type=int, default=92, help="root of the SeedSequence (default 92)")
    parser.add_argument("--generators", default="jumps,smooth", help="of person_effects (default jumps,smooth)")
    parser.add_argument("--resonance", action="store_true", help="also the person at the floor's resonance")
    parser.add_argument("--jobs", type=int, default=1, help="processes (default 1)")
    parser.add_argument("--csv", type=Path, help="write the rows here")
    parser.add_argument("--summary", type=Path, help="only print the table of this CSV")
    parser.add_argument("--before", type=Path, help="with --summary: the same records by other code, side by side")
    args = parser.parse_args(argv)
    if args.summary:
        before = read(args.before) if args.before else None
        print("\n".join(summary(read(args.summary), before)))
        return
    todo = work(args.records, args.seed, tuple(args.generators.split(",")), args.resonance)
    with ProcessPoolExecutor(args.jobs) as pool:
        rows = list(tqdm(pool.map(one, todo), total=len(todo), desc="records", unit="record", file=sys.stderr))
    frame = pd.DataFrame(rows)
    if args.csv:
        frame.to_csv(args.csv, index=False)
    print("\n".join(summary(frame)))


if __name__ == "__main__":
    main()
