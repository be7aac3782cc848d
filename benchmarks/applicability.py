"""Is this bouncing? Refusals and warnings of :func:`smd_statespace.applicability.check_bouncing`, measured.

Runs the checks on stand-ins built from physics for records the SMD model
does not describe (a countermovement jump, hopping, running, a squat,
walking with a left/right difference, a clipped record, noise) and on clean
simulated bouncing across the article's range (both generators of force
variation), and counts what each gets::

    python benchmarks/applicability.py                 # 80 clean records, writes docs/figures/applicability.png
    python benchmarks/applicability.py --clean 20
    python benchmarks/applicability.py --fs 1000 --clean 20 --figure /tmp/a.png   # a force plate's rate

Everything random comes from ``numpy.random.SeedSequence(--seed)``.
"""

from __future__ import annotations

import argparse
import sys
import textwrap
from collections import Counter
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from smd_statespace.applicability import check_bouncing  # noqa: E402
from smd_statespace.io import G, make_record  # noqa: E402
from smd_statespace.simulation import DEFAULT_BLF, simulate_bouncing  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
FS, MASS, DURATION = 100.0, 70.0, 30.0
WEIGHT = MASS * G


def stand_ins(rng) -> dict:
    """Forces (N) of records that are not bouncing, at ``FS`` over 30 s."""
    t = np.arange(0.0, DURATION, 1.0 / FS)

    def noisy(force):
        return force + rng.normal(0.0, 0.01 * WEIGHT, t.size)

    jump = np.full(t.size, WEIGHT)
    jump[(t > 3.0) & (t < 3.3)] = 0.6 * WEIGHT
    jump[(t >= 3.3) & (t < 3.6)] = 2.2 * WEIGHT
    jump[(t >= 3.6) & (t < 4.0)] = 0.0
    jump[(t >= 4.0) & (t < 4.15)] = 3.5 * WEIGHT
    phase = (t * 2.0) % 1.0
    hop = np.where(phase < 0.55, np.pi / 1.1 * WEIGHT * np.sin(np.pi * phase / 0.55), 0.0)
    phase = (t * 2.8) % 1.0
    run = np.where(phase < 0.4, np.pi / 0.8 * WEIGHT * np.sin(np.pi * phase / 0.4), 0.0)
    squat = np.full(t.size, WEIGHT)
    squat[(t > 3.0) & (t < 3.4)] = 0.5 * WEIGHT
    squat[(t >= 3.4) & (t < 3.8)] = 1.5 * WEIGHT
    walk = WEIGHT * (1.0 + 0.3 * np.sin(2 * np.pi * 1.6 * t) + 0.12 * np.sin(np.pi * 1.6 * t))
    bounce = simulate_bouncing(mass=MASS, f_b=2.2, f_h=2.8, xi_h=0.3, duration=DURATION, fs=FS, seed=5).record.force
    return {
        "countermovement jump": (t, noisy(jump)),
        "hopping at 2 Hz": (t, noisy(hop)),
        "running at 2.8 Hz": (t, noisy(run)),
        "one squat": (t, noisy(squat)),
        "walking, left/right": (t, noisy(walk)),
        "bouncing clipped at 1.3 BW": (np.arange(bounce.size) / FS, np.minimum(bounce, 1.3 * WEIGHT)),
        "noise only": (t, WEIGHT + rng.normal(0.0, 0.1 * WEIGHT, t.size)),
    }


def clean_records(n: int, seed: int):
    """``n`` simulated bouncing people across the article's range, alternating the two generators."""
    for k, child in enumerate(np.random.SeedSequence(seed).spawn(n)):
        rng = np.random.default_rng(child)
        f_b, f_h, xi_h = rng.uniform(1.5, 3.5), rng.uniform(1.8, 4.2), rng.uniform(0.1, 0.5)
        blf = tuple(np.array(DEFAULT_BLF) * rng.uniform(0.7, 1.3, 4))
        sim = simulate_bouncing(mass=MASS, f_b=f_b, f_h=f_h, xi_h=xi_h, duration=DURATION, blf=blf, fs=FS,
                                seed=int(rng.integers(2**31)), variation=("jumps", "smooth")[k % 2])
        yield (f_b, f_h, xi_h), sim.record


def figure(path: Path, time, force, message: str):
    fig = Figure(figsize=(9, 4.2), constrained_layout=True)
    ax = fig.add_subplot()
    ax.plot(time, force / WEIGHT, lw=0.8, color="C0")
    ax.axhline(0.05, color="C3", lw=0.8, ls="--", label="5 % of body weight: contact lost below")
    ax.set_xlim(1.5, 7.0)
    ax.set_ylim(-0.2, 5.0)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("GRF / body weight")
    ax.set_title("A countermovement jump given to identify: refused, with the reason")
    ax.legend(loc="center right", fontsize=8)
    ax.text(0.01, 0.97, "\n".join(textwrap.wrap("exit 2: " + message, 110)), transform=ax.transAxes, va="top",
            fontsize=7.5, family="monospace", bbox={"facecolor": "white", "edgecolor": "0.7"})
    fig.savefig(path, dpi=120)


def main(argv=None):
    global FS
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--clean", type=int, default=80, help="clean simulated records (default 80)")
    parser.add_argument("--seed", type=int, default=2026, help="root of the SeedSequence (default 2026)")
    parser.add_argument("--figure", type=Path, default=REPO / "docs" / "figures" / "applicability.png")
    parser.add_argument("--fs", type=float, default=FS, help=f"sampling rate of every record (Hz, default {FS:g})")
    args = parser.parse_args(argv)
    FS = args.fs
    rng = np.random.default_rng(np.random.SeedSequence(args.seed).spawn(1)[0])
    print("| record | verdict | kind | what the library says |")
    print("|---|---|---|---|")
    jump = None
    for name, (time, force) in stand_ins(rng).items():
        check = check_bouncing(make_record(time, force, MASS, source=f"{name}.csv"))
        first = (check.refusals or check.findings or [None])[0]
        verdict = "refused" if check.refusals else ("warning" if check.findings else "accepted")
        print(f"| {name} | {verdict} | {first.kind if first else '-'} | {first.message if first else '-'} |")
        if name == "countermovement jump":
            jump = (time, force, f"{name}.csv: not a bouncing record ({first.kind}): {first.message}")
    kinds, refused, n = Counter(), 0, 0
    for (f_b, f_h, xi_h), record in clean_records(args.clean, args.seed):
        check = check_bouncing(record)
        n += 1
        refused += not check.bouncing
        kinds.update(f.kind for f in check.findings)
        if check.findings:
            print(f"clean record f_b {f_b:.2f} Hz, f_h {f_h:.2f} Hz, xi_h {xi_h:.2f}: "
                  + "; ".join(f"{f.kind}: {f.message}" for f in check.findings), file=sys.stderr)
    print(f"\nclean records: {n}; refused {refused}; warnings {sum(kinds.values())} "
          f"({', '.join(f'{k} {v}' for k, v in kinds.most_common()) or 'none'})")
    figure(args.figure, *jump)
    print(f"wrote {args.figure}", file=sys.stderr)


if __name__ == "__main__":
    main()
