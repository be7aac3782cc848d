"""``smd-statespace structure``: a crowd of SMD people on a structure's modes, coupled vs force-only."""

from __future__ import annotations

import json
from pathlib import Path

from ..errors import OptionError
from .common import _count, _nonnegative, _positive, _seed, out_dir


def _people(text: str):
    """argparse type of ``--people``: a whole number >= 0 (people drawn) or a CSV path."""
    return int(text) if text.isdigit() else text


def add_structure(subparsers):
    """Declare ``smd-statespace structure``."""
    parser = subparsers.add_parser(
        "structure",
        help="a crowd on a structure: SMD people coupled to its modes, response vs the force-only model",
        description=(
            "Put people on a structure given by its modes (modes.csv: f_hz, zeta, mass_kg; shapes.csv: point, x_m, "
            "y_m, phi_1..phi_m) or a built-in example, each person the article's SMD (Eq. 2): active people bounce "
            "with the force of Eq. 4 (Table 2's people), passive people stand (5.0 Hz, 0.40). Solve the coupled "
            "model and the force-only one (the active people's rigid-floor GRFs on the empty structure) and write "
            "DIR/summary.json (empty and occupied modes; per response point peak, maximum 1 s running RMS and VDV "
            "of the acceleration, the last two also W_b-weighted (BS 6841), both models, and the maximum 1 s RMS "
            "against the IStructE/DCLG/DCMS (2008) Route 2 criteria by scenario, 3 / 7.5 / 20 %g, as an "
            "open-source implementation of Route 2 codes them), DIR/response.csv, DIR/people.csv and figures; with "
            "--draws K > 1 also K random crowds (DIR/draws.csv, their 95th percentiles and a histogram)."
        ),
    )
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--modes", metavar="MODES.csv", help="one row per mode: f_hz, zeta, mass_kg (needs --shapes)")
    source.add_argument("--example", choices=("sdof", "beam", "plate"),
                        help="a built-in structure: sdof (4 Hz, 20 t), beam (15 m simply supported, 4/16/36 Hz, "
                             "15 t modal mass) or plate (the article's Table 3 plate at mid-span)")
    parser.add_argument("--shapes", metavar="SHAPES.csv", help="one row per point: point, x_m, y_m, phi_1 ... phi_m")
    parser.add_argument("--people", required=True, type=_people, metavar="PEOPLE.csv|N",
                        help="a people table (point, and optional mass_kg, f_h, xi_h, active, f_b, blf_1..3; empty "
                             "cells drawn) or a number of people drawn at random points")
    parser.add_argument("--active", type=_nonnegative, default=0.5, metavar="SHARE",
                        help="with --people N: the share who bounce (0-1, default 0.5); the others stand")
    parser.add_argument("--fb", type=_positive, default=2.0, metavar="HZ",
                        help="bouncing frequency f_b (Hz, 1.35-3.75, default 2)")
    parser.add_argument("--duration", type=_positive, default=30.0, metavar="S", help="length (s, default 30)")
    parser.add_argument("--rate", type=_positive, default=200.0, metavar="HZ",
                        help="sampling rate (Hz, default 200); every mode must be below half of it")
    parser.add_argument("--phase-spread", type=_nonnegative, default=1.0, metavar="FRAC",
                        help="active people's phase offsets uniform over this fraction of a cycle: 1 unsynchronised "
                             "(default), 0 all in step")
    parser.add_argument("--points", metavar="P1,P2,...",
                        help="response points (default where each mode's shape is largest)")
    parser.add_argument("--draws", type=_count, default=1, metavar="K", help="random crowds (with --people N)")
    parser.add_argument("--jobs", type=_count, default=1, metavar="N", help="processes for the draws (default 1)")
    parser.add_argument("--seed", type=_seed, default=0, metavar="S", help="random seed (default 0)")
    parser.add_argument("--out", required=True, metavar="DIR", help="output directory")
    return parser


def _model(args):
    from ..structure.modes import EXAMPLES, read_modal_model

    if args.example is not None:
        if args.shapes is not None:
            raise OptionError("--shapes goes with --modes, not with --example")
        return EXAMPLES[args.example]()
    if args.shapes is None:
        raise OptionError("--modes needs --shapes SHAPES.csv (point, x_m, y_m, phi_1 ... phi_m)")
    return read_modal_model(args.modes, args.shapes)


def run_structure(args) -> int:
    """Run ``smd-statespace structure``."""
    import numpy as np

    from ..plotting.structure import plot_draws, plot_frequency_response, plot_running_rms
    from ..structure.analysis import analyse_structure
    from ..structure.people import draw_occupants, read_occupants

    model = _model(args)
    model.check_rate(args.rate, source=args.modes or f"--example {args.example}")
    for option, value in (("--active", args.active), ("--phase-spread", args.phase_spread)):
        if value > 1:
            raise OptionError(f"{option} must be a fraction from 0 to 1, got {value:g}")
    points = None if args.points is None else [p.strip() for p in args.points.split(",") if p.strip()]
    if points is not None:
        model.index(points, source="--points")
    drawn = isinstance(args.people, int)
    if args.draws > 1 and not drawn:
        raise OptionError("--draws K > 1 needs --people N (random crowds), not a people table")
    directory = out_dir(args.out)
    seed = np.random.SeedSequence(args.seed)
    options = {"f_b": args.fb, "duration": args.duration, "fs": args.rate, "phase_spread": args.phase_spread}
    occupants = (draw_occupants(model, args.people, args.active, seed=seed, **options) if drawn
                 else read_occupants(args.people, model, seed=seed, **options))
    result = analyse_structure(model, occupants, points)
    written = result.write(directory)
    figures = [directory / "structure_frf.png", directory / "structure_rms.png"]
    plot_frequency_response(result, figures[0])
    plot_running_rms(result, figures[1])
    print(result.text())
    if args.draws > 1:
        written += _draws(args, model, points, options, result, directory, plot_draws)
    print(f"wrote {', '.join(str(p) for p in written + figures)}")
    return 0


def _draws(args, model, points, options, result, directory, plot_draws):
    """The Monte Carlo part of ``structure``: draws.csv, the percentiles in summary.json, the histogram."""
    from concurrent.futures import ProcessPoolExecutor

    import numpy as np

    from ..structure.limits import MODELS, ROUTE2
    from ..structure.montecarlo import CrowdDraws, monte_carlo, percentiles

    spec = CrowdDraws(model, args.people, args.active, points=None if points is None else tuple(points), **options)
    seed = np.random.SeedSequence(args.seed).spawn(4)[3]  # children 0-2 are the shown crowd's (people._split)
    if args.jobs > 1:
        with ProcessPoolExecutor(max_workers=args.jobs) as pool:
            frame = monte_carlo(spec, args.draws, seed, executor=pool)
    else:
        frame = monte_carlo(spec, args.draws, seed)
    paths = [directory / "draws.csv", directory / "structure_draws.png"]
    frame.to_csv(paths[0], index=False, float_format="%.6g")
    worst = result.model.points[result.points[result.worst()]]
    plot_draws(frame, worst, paths[1])
    table = percentiles(frame)
    summary_path = directory / "summary.json"
    summary = json.loads(summary_path.read_text(encoding="utf-8"))
    limits = ROUTE2
    summary["draws"] = {"count": args.draws, "percentile": 95,
                        "points": {point: {k: float(v) for k, v in row.items()} for point, row in table.iterrows()},
                        "limits": {point: limits.classify_models(row) for point, row in table.iterrows()}}
    summary_path.write_text(json.dumps(summary, indent=1) + "\n", encoding="utf-8")
    print(f"{args.draws} random crowds, 95th percentile at {worst}: rms_1s_max coupled "
          f"{table.loc[worst, 'coupled_rms_1s_max']:.3f} vs force-only {table.loc[worst, 'force_only_rms_1s_max']:.3f} "
          "m/s^2")
    for model, label in MODELS.items():
        print(f"  {label} 95th percentile: {limits.sentence(table.loc[worst, f'{model}_{limits.measure}'])}")
    return [Path(p) for p in paths]
