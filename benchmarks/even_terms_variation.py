"""Which way of varying the force makes a term even in the motion look significant on a clean record (issue 45)?

``diagnose``'s false alarms on clean records are mostly the even generic terms (``u2``, ``v2``, ``u_v``): on a
record with none of them, the term's coefficient comes out systematically off zero, and draws of the noise do not
move it (docs/effects.md). This script fits the person with one such term (``identify_person(effects=[term])``,
the term's coefficient estimated with ``f_h`` and ``xi_h``) on clean ``jumps`` records whose force varies from
cycle to cycle in one way at a time (``simulate_bouncing``):

``alike``      the default: frequency 2 %, each harmonic's amplitude 10 % and phase 0.1 rad;
``amplitude``  the harmonics' amplitudes alone (10 %);
``phase``      the harmonics' phases alone (0.1 rad, ``phase_variation``): the force keeps its size, shifts its shape;
``frequency``  the cycle frequency alone (2 %).

and prints, per variation and term, each record's coefficient, its z (estimate / sd) and its likelihood ratio
(1 degree of freedom; 10.8 is p 0.001). With ``--diagnose``, ``diagnose`` as a user runs it instead (every
registered effect and the library of generic terms, ``diagnose_person``) on the same clean records: what it
proposes is a false alarm. With ``--true-timing`` the fits use the simulator's own cycle starts (its cycles
table), not the starts the model places: where the force jumps at its true starts, the even terms' share
comes from starts placed elsewhere (2026-11-30: on phase-jittered records the likelihood ratio of ``u2`` and
``v2`` fell from 9-36 to 3-13 at the true starts, while the person without a term fitted only 2-6 better
there). ``--start-jitter MS`` adds random errors (sd in ms, drawn from each record's seed) to those true starts:
errors of 2.5 ms alone, not tied to the force, gave ``u2`` and ``v2`` likelihood ratios of 10-32 on
phase-jittered records (2026-11-30)::

    OPENBLAS_NUM_THREADS=1 python benchmarks/even_terms_variation.py --records 6 --jobs 2 \\
        --out benchmarks/results/even_terms_variation.md
    OPENBLAS_NUM_THREADS=1 python benchmarks/even_terms_variation.py --records 8 --jobs 2 --diagnose
    OPENBLAS_NUM_THREADS=1 python benchmarks/even_terms_variation.py --records 6 --jobs 2 --true-timing
    OPENBLAS_NUM_THREADS=1 python benchmarks/even_terms_variation.py --records 6 --jobs 2 --true-timing \
        --start-jitter 2.5
"""

from __future__ import annotations

import os

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

import argparse  # noqa: E402
import time  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from accuracy import markdown_table  # noqa: E402  (benchmarks/, the script's own folder)

VARIATIONS = {
    "alike": {},
    "amplitude": {"fb_variation": 0.0, "phase_variation": 0.0},
    "phase": {"fb_variation": 0.0, "coef_variation": 0.0, "phase_variation": 0.1},
    "frequency": {"coef_variation": 0.0},
}
"""The ways the force varies from cycle to cycle: ``simulate_bouncing``'s settings on top of its defaults."""

PERSON = {"mass": 70.0, "f_b": 2.2, "f_h": 2.8, "xi_h": 0.3, "duration": 30.0}
"""The person of every record (30 s at 100 Hz, 1 % BW noise)."""

SCALE = 0.012
"""The terms' scale (m or m/s: the record's RMS motion to within a factor of two; it sets the coefficient's unit)."""


def fit_one(job) -> dict:
    """The person with ``term`` on one record: the term's coefficient, sd and likelihood ratio (at the simulator's
    own cycle starts when ``true_timing``)."""
    from smd_statespace.person import identify_person
    from smd_statespace.simulation import simulate_bouncing

    variation, term, record, seed, true_timing, jitter_ms = job
    sim = simulate_bouncing(**PERSON, seed=seed, variation="jumps", **VARIATIONS[variation])
    if true_timing:
        _use_true_starts(sim, jitter_ms, seed)
    started = time.perf_counter()
    result = identify_person(sim.record, effects=[f"term:kind={term},scale={SCALE}"], check_change=False,
                             threads=1, timing="template" if true_timing else "model")
    estimate = result.effect_estimates().iloc[0]
    return {"variation": variation, "term": term, "record": record, "coefficient": float(estimate["value"]),
            "sd": float(estimate["sd"]), "z": float(estimate["value"] / estimate["sd"]),
            "lr": float(result.effect_test()["lr"]), "f_h": result.f_h, "seconds": time.perf_counter() - started}


def _use_true_starts(sim, jitter_ms: float = 0.0, seed: int = 0) -> None:
    """Make ``identify_person`` in this process start every cycle where the simulator started it (with
    ``timing="template"`` they are kept as they are), each moved by a normal error of sd ``jitter_ms``: the
    benchmark's probe, not an option of the package."""
    from smd_statespace.person import CycleTiming
    from smd_statespace.person import fit

    cycles = sim.cycles
    starts = np.r_[cycles["t_start"].to_numpy(), cycles["t_end"].to_numpy()[-1]]
    starts = starts + np.random.default_rng(seed).normal(0.0, jitter_ms / 1000.0, starts.size)
    fit.estimate_timing = lambda *args, **kwargs: CycleTiming(starts, "template")


def diagnose_one(job) -> dict:
    """``diagnose`` on one clean record: what it proposes (nothing is right)."""
    from smd_statespace.person import identify_person
    from smd_statespace.person.diagnose import diagnose_person
    from smd_statespace.simulation import simulate_bouncing

    variation, _, record, seed, _, _ = job
    sim = simulate_bouncing(**PERSON, seed=seed, variation="jumps", **VARIATIONS[variation])
    started = time.perf_counter()
    diagnosis = diagnose_person(identify_person(sim.record, threads=1), threads=1)
    return {"variation": variation, "record": record, "proposed": ", ".join(diagnosis.missing) or "nothing",
            "seconds": time.perf_counter() - started}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--records", type=int, default=6, help="records per variation (default 6)")
    parser.add_argument("--terms", default="u2", help="generic terms, comma-separated (default u2; also v2, u_v)")
    parser.add_argument("--seed", type=int, default=0, help="SeedSequence root of the records (default 0)")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--diagnose", action="store_true", help="diagnose each clean record with every candidate")
    parser.add_argument("--true-timing", action="store_true",
                        help="fit at the simulator's own cycle starts (not with --diagnose)")
    parser.add_argument("--start-jitter", type=float, default=0.0, metavar="MS",
                        help="with --true-timing: random errors of the true starts, sd in ms (default 0)")
    parser.add_argument("--out", type=Path, default=None, help="also write the tables as Markdown")
    args = parser.parse_args(argv)
    if args.start_jitter and not args.true_timing:
        parser.error("--start-jitter: errors of the true starts, with --true-timing only")
    if args.diagnose and args.true_timing:
        parser.error("--true-timing: the fits with one term only, not with --diagnose")
    if args.diagnose:
        args.terms = "diagnose"
    seeds = [int(child.generate_state(1)[0]) for child in np.random.SeedSequence(args.seed).spawn(args.records)]
    jobs = [(variation, term, i, seed, args.true_timing, args.start_jitter) for term in args.terms.split(",")
            for variation in VARIATIONS for i, seed in enumerate(seeds)]  # the same records' seeds for every variation
    started = time.perf_counter()
    with ProcessPoolExecutor(args.jobs) as pool:
        rows = pd.DataFrame(list(pool.map(diagnose_one if args.diagnose else fit_one, jobs)))
    if args.diagnose:
        summary = rows.groupby("variation", sort=False).agg(
            records=("proposed", "size"), false_alarms=("proposed", lambda p: int((p != "nothing").sum())))
    else:
        summary = rows.groupby(["term", "variation"], sort=False).agg(
            records=("z", "size"), coefficient_mean=("coefficient", "mean"), z_mean=("z", "mean"),
            z_min=("z", "min"), z_max=("z", "max"), lr_over_10_8=("lr", lambda lr: int((lr > 10.83).sum())))
    how = "--diagnose" if args.diagnose else f"--terms {args.terms}" + (" --true-timing" if args.true_timing else "")
    how += f" --start-jitter {args.start_jitter:g}" if args.start_jitter else ""
    lines = [f"`python benchmarks/even_terms_variation.py --records {args.records} {how} --seed {args.seed}` "
             f"({(time.perf_counter() - started) / 60:.1f} min, {args.jobs} processes)", "",
             markdown_table(summary.reset_index().round(3)), "", markdown_table(rows.round(4))]
    print("\n".join(lines))
    if args.out:
        args.out.write_text("# Even terms on clean records, by the way the force varies\n\n" + "\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
