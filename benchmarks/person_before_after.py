"""Seconds of ``identify_person`` under two source trees, on the same records, in alternating fresh processes.

The machine's speed drifts by tens of per cent between runs minutes apart (docs/performance.md,
"The host's two speeds"), so a change's saving is measured here by running the tree before it
and the tree after it record by record, alternately (which goes first alternates too), one
process at a time. Each process imports the tree given, loads numba's compiled passes (one
likelihood and one derivative pass of each variation model on a short record, untimed),
simulates the record (``person_accuracy.py``'s people and generators) and times
``identify_person(record)`` with its defaults. A process runs at one of the host's two speeds,
about 1.5x apart (docs/performance.md): with ``--repeats R`` each tree runs each record R times
(alternating) and the fastest counts. Prints per record both times and the answers.

With ``--diagnose`` the time is that of ``diagnose_person(result, library=True, threads=1)`` after the
identification (untimed), the whole library screened as ``diagnose`` does, and the answer its verdict;
``--hidden harmonics`` hides the extra harmonics 5-6 of the hidden-effect tests (BLF 0.04 and 0.03) in every
record, so that the library's quick fits and the candidates' fits run.

::

    git archive OLD smd_statespace | tar -x -C /tmp/before     # the tree before the change
    OPENBLAS_NUM_THREADS=1 python benchmarks/person_before_after.py /tmp/before . --records 1 --repeats 3

(``.``: this checkout.) About 2 x R x 10 s per record.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

GENERATORS = ("jumps", "smooth", "coefficients", "pulses", "tempo")

CHILD = r"""
import json, sys, time
import numpy as np
sys.path.insert(0, {benchmarks!r})
import person_accuracy
from smd_statespace.person import identify_person
from smd_statespace.person.model import RecordModel
from smd_statespace.person.score import score
from smd_statespace.person.timing import estimate_timing
from smd_statespace.simulation import simulate_bouncing
from smd_statespace.io import G

warm = simulate_bouncing(mass=70, f_b=2.2, f_h=2.8, xi_h=0.3, duration=6, seed=1).record
y = warm.force / warm.mass - G
for variation in ("independent", "smooth"):  # numba's compiled passes loaded from its cache, untimed
    model = RecordModel(warm.time, y, estimate_timing(warm.time, warm.force), 4, variation)
    score(model, model.start_params(2.5, 0.3, -2.0))
person = person_accuracy.draw_people({records}, {seed}).iloc[{index}]
record = person_accuracy.simulate(person, {generator!r}, effects={effects!r}).record
began = time.perf_counter()
result = identify_person(record)
verdict = ""
if {diagnose!r}:
    from smd_statespace.person.diagnose import diagnose_person
    began = time.perf_counter()
    verdict = ",".join(diagnose_person(result, library=True, threads=1).missing) or "nothing"
import smd_statespace, os
print(json.dumps({{"seconds": time.perf_counter() - began, "f_h": result.f_h, "xi_h": result.xi_h,
                  "variation": result.model.variation, "verdict": verdict,
                  "package": os.path.dirname(smd_statespace.__file__)}}))
"""


HIDDEN = {"none": None, "harmonics": {"harmonics": {"blf": (0.04, 0.03)}}}
"""Effects ``--hidden`` puts in every record (``simulate_bouncing``'s ``effects``)."""


def run(tree: Path, generator: str, index: int, records: int, seed: int, diagnose=False, hidden="none") -> dict:
    """One fresh process with ``tree`` first on the path: its ``identify_person`` (or, with ``diagnose``, its
    ``diagnose_person``) on one record."""
    env = {**os.environ, "PYTHONPATH": str(tree.resolve()), "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    code = CHILD.format(benchmarks=str(Path(__file__).resolve().parent), records=records, seed=seed, index=index,
                        generator=generator, diagnose=diagnose, effects=HIDDEN[hidden])
    # -P: the working directory is not put first on the path (with "-c" it would be, and a run from a checkout
    # would import the checkout's package whatever PYTHONPATH says); the child says which package it ran
    out = subprocess.run([sys.executable, "-P", "-c", code], env=env, capture_output=True, text=True, check=True)
    row = json.loads(out.stdout.strip().splitlines()[-1])
    if Path(row["package"]).resolve() != (tree / "smd_statespace").resolve():
        raise RuntimeError(f"the run for {tree} imported {row['package']}, not {tree / 'smd_statespace'}")
    return row


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before", type=Path, help="folder holding the 'before' tree's smd_statespace package")
    parser.add_argument("after", type=Path, help="folder holding the 'after' tree's smd_statespace package")
    parser.add_argument("--records", type=int, default=2, help="people per generator (default 2)")
    parser.add_argument("--seed", type=int, default=77)
    parser.add_argument("--generators", default=",".join(GENERATORS))
    parser.add_argument("--repeats", type=int, default=1, help="runs per tree and record; the fastest counts")
    parser.add_argument("--diagnose", action="store_true", help="time diagnose (the whole library) after identify")
    parser.add_argument("--hidden", choices=sorted(HIDDEN), default="none",
                        help="an effect hidden in every record (default none)")
    args = parser.parse_args(argv)
    for tree in (args.before, args.after):
        if not (tree / "smd_statespace" / "__init__.py").is_file():
            parser.error(f"{tree}: no smd_statespace package there (git archive REV smd_statespace | tar -x -C DIR)")
    print("| record | before s | after s | after / before | f_h before -> after (Hz) | xi_h before -> after "
          "| variation before -> after | verdict before -> after |\n|---|---|---|---|---|---|---|---|")
    ratios, totals = [], [0.0, 0.0]
    order = 0
    for generator in [g.strip() for g in args.generators.split(",") if g.strip()]:
        for index in range(args.records):
            runs = {args.before: [], args.after: []}
            for _ in range(args.repeats):
                trees = (args.before, args.after) if order % 2 == 0 else (args.after, args.before)
                order += 1
                for tree in trees:
                    runs[tree].append(run(tree, generator, index, args.records, args.seed, args.diagnose,
                                          args.hidden))
            old, new = (min(runs[t], key=lambda r: r["seconds"]) for t in (args.before, args.after))
            ratios.append(new["seconds"] / old["seconds"])
            totals[0] += old["seconds"]
            totals[1] += new["seconds"]
            print(f"| {generator} {index} | {old['seconds']:.2f} | {new['seconds']:.2f} | {ratios[-1]:.2f} "
                  f"| {old['f_h']:.4f} -> {new['f_h']:.4f} | {old['xi_h']:.4f} -> {new['xi_h']:.4f} "
                  f"| {old['variation']} -> {new['variation']} | {old['verdict']} -> {new['verdict']} |", flush=True)
    print(f"\n{len(ratios)} records, fastest of {args.repeats} each: after / before median {np.median(ratios):.2f} "
          f"[{min(ratios):.2f}, {max(ratios):.2f}]; total {totals[0]:.1f} -> {totals[1]:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
