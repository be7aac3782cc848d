"""The steady span find_bouts gives (issue 43): its start and end against the truth, before and after a change.

    python benchmarks/frontend_spans.py                      # 40 typical + 16 held-out lab records, 15 end to end
    python benchmarks/frontend_spans.py --before REV         # the front end of git revision REV as "before"
    python benchmarks/frontend_spans.py --n 80 --cache DIR   # more records; simulated records kept in DIR

Only the front end runs (hum found and removed, :func:`find_bouts`; under 0.1 s a record), no identification.
The records (seed ``--seed``, record ``k``: ``SeedSequence(seed, spawn_key=(group, k))``):

``typical``
    :func:`simulate_typical_lab_record` with ``LabRanges(tire=(0, 0.35))``: the person tires by 0-35 % over
    the bout, ``f_h`` and ``xi_h`` drift or step (or not) as the default ranges draw, ramps of 1-3 cycles.
``held_out``
    ``benchmarks/lab_records.py``'s held-out ranges (smooth variation, tiring 20-35 %, 0-1 s of standing, strong
    sway, hum and drift; every other record ends without standing).
``end_to_end``
    :func:`simulate_bouncing` of each variation (30 s at 100 Hz and 1000 Hz, no standing): the steady span should
    cover nearly the whole record.

The fitted span is the longest bout's (as ``prepare_record``); its error at each end, in cycles of the bouncing
there (``f_b_start`` at the start, ``f_b_end`` at the end), is positive when bouncing is lost (the span starts after
``full_start_s`` or ends before ``full_end_s``). The table gives, per version and group: the median and worst
(largest magnitude, signed) error at each end, the share of records within 1 cycle at both ends, and the share
losing more than 2 cycles at either end (or finding no bout).
"""

import argparse
import dataclasses
import importlib
import json
import subprocess
import sys
import time
import types
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BEFORE = "b6c0bce297f4caf4417396785ce93dbe1f85687c"
"""The last commit with the ramp rule against the bout's median swing (STEADY_SWING of the whole bout)."""

GROUPS = {"typical": 0, "held_out": 1, "end_to_end": 2}


def frontend_of(revision):
    """The module ``smd_statespace/signals/frontend.py`` at git ``revision`` (None: the working tree)."""
    if revision is None:
        return importlib.import_module("smd_statespace.signals.frontend")
    source = subprocess.run(["git", "-C", str(ROOT), "show", f"{revision}:smd_statespace/signals/frontend.py"],
                            check=True, capture_output=True, text=True).stdout
    importlib.import_module("smd_statespace.signals")
    name = f"smd_statespace.signals._frontend_{revision[:10]}"
    module = types.ModuleType(name)
    module.__package__ = "smd_statespace.signals"
    module.__file__ = f"{revision}:smd_statespace/signals/frontend.py"
    sys.modules[name] = module
    exec(compile(source, module.__file__, "exec"), module.__dict__)  # noqa: S102 - our own file, another revision
    return module


def _ranges(group):
    from smd_statespace.simulation.lab import LAB_RANGES

    if group == "typical":
        return LAB_RANGES.__class__(tire=(0.0, 0.35))
    return dataclasses.replace(LAB_RANGES, fs=(500.0,), hum_frequency=(60,), hum=((15.0, 20.0), (4.0, 5.0),
                                                                                  (8.0, 10.0)),
                               variation=("smooth",), tire=(0.2, 0.35), stand=(0.0, 1.0), sway=(6.0, 10.0),
                               drift=(30.0, 60.0))


def simulate(group, seed, k):
    """``(time, force, mass, truth)`` of record ``k`` of ``group``."""
    from smd_statespace.simulation import VARIATIONS, simulate_bouncing
    from smd_statespace.simulation.lab import simulate_typical_lab_record

    sequence = np.random.SeedSequence(seed, spawn_key=(GROUPS[group], k))
    if group == "end_to_end":
        variation = VARIATIONS[k % len(VARIATIONS)]
        fs = (100.0, 1000.0)[(k // len(VARIATIONS)) % 2]
        synthetic = simulate_bouncing(duration=30.0, fs=fs, seed=sequence, variation=variation)
        r = synthetic.record
        f_b = float(synthetic.truth["f_b"])
        truth = {"variation": variation, "tire": 0.0, "f_b_start": f_b, "f_b_end": f_b,
                 "span": {"full_start_s": float(r.time[0]), "full_end_s": float(r.time[-1])}}
        return r.time, r.force, r.mass, truth
    fixed = {"stand_after": 0.0} if group == "held_out" and k % 2 else {}
    synthetic = simulate_typical_lab_record(sequence, _ranges(group), **fixed)
    t = synthetic.truth
    truth = {key: t[key] for key in ("tire", "f_b_start", "f_b_end", "span", "change")}
    truth["variation"] = synthetic.truth.get("variation", "")
    return synthetic.record.time, synthetic.record.force, synthetic.record.mass, truth


def record(group, seed, k, cache):
    """The record (cached in ``cache`` when given) and its truth."""
    from smd_statespace.io import make_record

    path = None if cache is None else Path(cache) / f"{group}_{seed}_{k}.npz"
    if path is not None and path.exists():
        data = np.load(path)
        return make_record(data["time"], data["force"], float(data["mass"])), json.loads(str(data["truth"]))
    t, force, mass, truth = simulate(group, seed, k)
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savez(path, time=t, force=force, mass=mass, truth=json.dumps(truth))
    return make_record(t, force, mass), truth


def errors(frontend, rec, truth):
    """``(start, end)`` error (cycles; positive: bouncing lost) of the longest bout, nan without one; and seconds."""
    begin = time.perf_counter()
    bouts = frontend.find_bouts(frontend.remove_hum(rec))
    seconds = time.perf_counter() - begin
    if not bouts.bouts:
        return np.nan, np.nan, seconds
    bout = max(bouts.bouts, key=lambda b: b.cycles)
    span = truth["span"]
    return ((bout.start - span["full_start_s"]) * truth["f_b_start"],
            (span["full_end_s"] - bout.end) * truth["f_b_end"], seconds)


def _worst(values):
    values = np.asarray(values, float)
    return f"{values[np.nanargmax(np.abs(values))]:+.2f}" if np.isfinite(values).any() else "-"


def summary(name, group, rows):
    """One markdown row: median and worst at each end, within 1 cycle, losing more than 2 at either end."""
    start, end = np.array([r[0] for r in rows]), np.array([r[1] for r in rows])
    found = np.isfinite(start)
    within = np.mean(found & (np.abs(start) <= 1.0) & (np.abs(end) <= 1.0))
    losing = np.mean(~found | (start > 2.0) | (end > 2.0))
    return (f"| {name} | {group} | {len(rows)} | {np.nanmedian(start):+.2f} | {_worst(start)} | "
            f"{np.nanmedian(end):+.2f} | {_worst(end)} | {100 * within:.0f} % | {100 * losing:.0f} % | "
            f"{int((~found).sum())} |")


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--n", type=int, default=40, help="typical lab records (default 40)")
    p.add_argument("--held-out", type=int, default=16, help="held-out lab records (default 16)")
    p.add_argument("--end-to-end", type=int, default=15, help="records bouncing end to end (default 15)")
    p.add_argument("--seed", type=int, default=4343)
    p.add_argument("--before", default=BEFORE, help="git revision of the 'before' front end")
    p.add_argument("--cache", default=None, help="directory keeping the simulated records")
    p.add_argument("--list", action="store_true", help="print every record's errors")
    return p.parse_args(argv)


def main(argv=None):
    args = parse_args(argv)
    versions = {"before": frontend_of(args.before), "after": frontend_of(None)}
    tasks = ([("typical", k) for k in range(args.n)] + [("held_out", k) for k in range(args.held_out)]
             + [("end_to_end", k) for k in range(args.end_to_end)])
    results = {(v, g): [] for v in versions for g in (*GROUPS, "tiring", "untired")}
    seconds = []
    for group, k in tasks:
        rec, truth = record(group, args.seed, k, args.cache)
        line = [f"{group:>10} {k:3d} tire {truth['tire']:.2f} f_b {truth['f_b_start']:.2f}"]
        for name, module in versions.items():
            start, end, took = errors(module, rec, truth)
            seconds.append(took)
            results[(name, group)].append((start, end))
            if group != "end_to_end" and (truth["tire"] >= 0.2 or truth["tire"] < 0.1):
                results[(name, "tiring" if truth["tire"] >= 0.2 else "untired")].append((start, end))
            line.append(f"{name} {start:+6.2f} {end:+6.2f}")
        if args.list:
            print("  ".join(line), flush=True)
    print(f"\nseed {args.seed}; before: {args.before[:10]}, after: the working tree; find_bouts with remove_hum: "
          f"median {np.median(seconds):.3f} s, max {np.max(seconds):.3f} s a record\n")
    print("Errors in cycles of the bouncing at that end; positive: bouncing lost (the span starts late or ends "
          "early). `tiring`, `untired`: the lab records (typical and held-out) with tire >= 0.2, < 0.1.\n")
    print("| version | records | n | start median | start worst | end median | end worst | within 1 cycle "
          "| losing > 2 cycles | no bout |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for group in (*GROUPS, "tiring", "untired"):
        for name in versions:
            if results[(name, group)]:
                print(summary(name, group, results[(name, group)]))


if __name__ == "__main__":
    main()
