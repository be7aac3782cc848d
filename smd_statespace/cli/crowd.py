"""``smd-statespace crowd``: GRFs of N people bouncing together, drawn from Table 2, and the total crowd force."""

from __future__ import annotations

from pathlib import Path

from ..simulation.crowd import DEFAULT_DURATION
from ..errors import OptionError
from .common import _count, _nonnegative, _positive, _seed


def add_crowd(subparsers):
    """Declare ``smd-statespace crowd``."""
    parser = subparsers.add_parser(
        "crowd",
        help="crowd load: N people bouncing, drawn from Table 2, and their total force",
        description=(
            "Draw N people bouncing at f_b from the article's Table 2 skew-normal fits (Eq. 19) or your own "
            "table, synthesise each person's GRF with the SMD model on a rigid floor (Eq. 2-4; own mass, phase "
            "offset and cycle-to-cycle variation) and write the forces (time, one column per person, total; N), "
            "the people table (<out stem>_people.csv) and a figure. The model has no flight phase: a person whose "
            "GRF would go below zero (pulling on the floor) is redrawn, and the summary and the people table "
            "(draw, rejected_steady, rejected_cycles) say how many and why."
        ),
    )
    parser.add_argument("--people", required=True, type=_count, metavar="N", help="number of people")
    parser.add_argument("--fb", required=True, type=_positive, metavar="HZ",
                        help="bouncing frequency f_b (Hz), within 1.35-3.75 (the article's bands)")
    parser.add_argument("--duration", type=_positive, default=DEFAULT_DURATION, metavar="S",
                        help=f"length (s, default {DEFAULT_DURATION:g})")
    parser.add_argument("--out", required=True, metavar="CSV", help="forces file to write")
    parser.add_argument("--fs", type=_positive, default=200.0, metavar="HZ", help="sampling frequency (default 200)")
    parser.add_argument("--seed", type=_seed, metavar="S",
                        help="random seed (default: fresh entropy, printed and kept in the people table)")
    parser.add_argument("--table", metavar="TABLE.csv",
                        help="your own skew-normal fits: columns parameter, band, m, s, a[, low, high] "
                             "(the layout of 'smd-statespace stats' table2.csv); default Table 2")
    parser.add_argument("--figure", metavar="PNG", help="figure to write (default <out stem>.png beside --out)")
    parser.add_argument("--people-table", metavar="CSV", help="people table (default <out stem>_people.csv)")
    parser.add_argument("--fb-variation", type=_nonnegative, default=0.02, metavar="FRAC",
                        help="cycle-to-cycle relative SD of f_b (default 0.02)")
    parser.add_argument("--coef-variation", type=_nonnegative, default=0.10, metavar="FRAC",
                        help="cycle-to-cycle relative SD of the force harmonics (default 0.10)")
    parser.add_argument("--phase-spread", type=_nonnegative, default=1.0, metavar="FRAC",
                        help="phase offsets uniform over this fraction of a cycle: 1 unsynchronised (default), "
                             "0 all in step")
    parser.add_argument("--effect", action="append", default=[], metavar="NAME[:key=value,...]",
                        help="physical effect every person has, repeatable: any registered effect, as for "
                             "'simulate --effect' (each person is then integrated numerically, about 1-2 s each)")
    return parser


def run_crowd(args) -> int:
    """Run ``smd-statespace crowd``."""
    from ..simulation.crowd import simulate_crowd

    out = Path(args.out)
    figure = out.with_suffix(".png") if args.figure is None else Path(args.figure)
    people = None if args.people_table is None else Path(args.people_table)
    for label, path in (("--out", out), ("--figure", figure), ("--people-table", people)):
        if path is not None and not path.parent.is_dir():
            raise OptionError(f"{label} {path}: directory {path.parent} does not exist")
    if args.table is not None and not Path(args.table).is_file():
        raise OptionError(f"--table {args.table}: no such file")
    try:
        crowd = simulate_crowd(args.people, args.fb, args.duration, fs=args.fs, seed=args.seed, table=args.table,
                               fb_variation=args.fb_variation, coef_variation=args.coef_variation,
                               phase_spread=args.phase_spread, effects=args.effect or None)
    except OptionError as exc:
        # The library names itself ("crowd: ..."); on the command line that is noise.
        raise OptionError(str(exc).replace("crowd: ", "", 1)) from None
    csv_path, people_path = crowd.write(out, people)
    crowd.plot(figure)
    print(crowd.summary())
    print(f"wrote {csv_path} (time, {args.people} GRF columns, total; N), {people_path}, {figure}")
    return 0
