"""``smd-statespace hsi``: the article's Section 6 simulated with a person whose parameters do not change."""

from __future__ import annotations

import json

import pandas as pd

from ..estimators import ESTIMATORS
from .common import _count, _positive, _seed, out_dir


def add_hsi(subparsers):
    """Declare ``smd-statespace hsi``."""
    parser = subparsers.add_parser(
        "hsi",
        help="human-structure interaction: is the article's Table 4 shift an artefact of the floor motion?",
        description=(
            "Simulate one person bouncing at 1.75 Hz on a rigid floor and at mid-span of the article's plate "
            "(Table 3, six modes; same force, person's own parameters unchanged), identify the person with the "
            "rigid-floor model and with the floor_mode effect, fit the same by estimator-free least squares on "
            "exact states, and compare the changes rigid -> plate with Table 4. Writes DIR/hsi_table.csv and "
            "other tables, the records, DIR/hsi_floor.png (like Fig. 10) and DIR/hsi_parameters.png (like Fig. 11)."
        ),
    )
    parser.add_argument("--out", default="hsi_output", metavar="DIR", help="output directory (default ./hsi_output)")
    parser.add_argument("--seed", type=_seed, default=0, metavar="S", help="random seed (default 0)")
    parser.add_argument("--duration", type=_positive, default=30.0, metavar="S",
                        help="length of each identified record (s, default 30, >= 8)")
    parser.add_argument("--repeats", type=_count, default=10, metavar="N",
                        help="records of the estimator-free fit (default 10)")
    parser.add_argument("--estimator", choices=sorted(ESTIMATORS), default="ekf",
                        help="estimator of the per-cycle identification (default ekf, the fastest)")
    parser.add_argument("--max-passes", type=_count, default=8, metavar="N",
                        help="largest number of repeated passes per cycle (default 8)")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    return parser


def run_hsi(args) -> int:
    """Run ``smd-statespace hsi``."""
    from ..plotting.hsi import plot_floor, plot_parameters
    from ..studies.hsi import hsi_study

    directory = out_dir(args.out)
    if not args.quiet:
        print(f"simulating and identifying (about 25 s per 10 s of record with {args.estimator}) ...", flush=True)
    study = hsi_study(duration=args.duration, seed=args.seed, repeats=args.repeats, estimator=args.estimator,
                      max_passes=args.max_passes, progress=not args.quiet)
    written = study.write(directory)
    written += [directory / "hsi_floor.png", directory / "hsi_parameters.png"]
    plot_floor(study, written[-2])
    plot_parameters(study, written[-1])
    (directory / "hsi_run.json").write_text(json.dumps(study.settings, indent=1, default=str) + "\n",
                                            encoding="utf-8")
    columns = ["truth", "ekf_rigid", "ekf_plate", "ekf_change_%", "ekf_floor_mode_change_%", "ls_change_%",
               "ls_change_sd_%", "article_rigid", "article_plate", "article_change_%"]
    shown = study.table[columns].rename(columns=lambda c: c.replace("ekf", study.settings["estimator"]))
    with pd.option_context("display.width", 200, "display.max_columns", 20):
        print(shown.T.round(3).to_string())
        print()
        print(study.floors.round(3).to_string())
        print()
        print(study.sensitivity[["floor_acc_rms", "f_h_change_%", "xi_h_change_%", "blf_1_change_%",
                                 "blf_2_change_%", "blf_3_change_%"]].round(2).to_string())
    print()
    print(study.finding())
    print(f"\n{study.seconds:.0f} s; wrote {', '.join(str(p) for p in written)}, {directory / 'hsi_run.json'}")
    return 0
