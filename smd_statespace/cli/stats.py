"""``smd-statespace stats``: population statistics of identified cycles (Section 5, Table 2, Eq. 19)."""

from __future__ import annotations

import time

from .common import _positive, _seed, _whole, out_dir


def _min_cycles(text: str) -> int:
    """argparse type: a whole number >= 3 (a skew-normal fit has three parameters)."""
    return _whole(text, 3, "a whole number >= 3")


def _bootstrap(text: str) -> int:
    """argparse type: a whole number >= 0 (0: no bootstrap intervals)."""
    return _whole(text, 0, "a whole number >= 0")


def add_stats(subparsers):
    """Declare ``smd-statespace stats``."""
    from ..population import MIN_CYCLES, N_BOOTSTRAP

    parser = subparsers.add_parser(
        "stats",
        help="bands, skew-normal fits (Table 2) and trends of many identified cycles",
        description=("Read the results.csv of one or many 'identify' runs, or any table of identified cycles with "
                     "a column f_b and parameter columns (f_h, xi_h, k_h, c_h, blf_1..3), assign the ok cycles to "
                     "bouncing-frequency bands (the article's six by default), give per band the count, mean and sd "
                     "of f_h, xi_h, K_h, C_h and BLF1-3 and a skew-normal fit (Eq. 19) by maximum likelihood with "
                     "bootstrap intervals, in the layout of the article's Table 2; fit the trends in f_b with OLS "
                     "(f_h linear, xi_h and BLF1 quadratic with the 'preferred frequency' at the vertex). Cycles "
                     "whose estimates cannot be true (column implausible, or xi_h < 0, C_h < 0, a BLF or floor-force "
                     "harmonic > 2 g) or from an inadequate model (column model_adequate False) are left out and "
                     "counted. A table without status or *_determined columns has every row taken as an identified, "
                     "determined cycle (said in the report). Writes CSV tables and PNG figures into DIR "
                     "(Wang et al. 2019, Section 5)."),
    )
    parser.add_argument("results", nargs="+", metavar="RESULTS.csv",
                        help="results.csv written by 'identify', or any CSV of cycles with f_b and parameter columns")
    parser.add_argument("--out", default="smd_stats", metavar="DIR", help="output directory (default ./smd_stats)")
    parser.add_argument("--min-cycles", type=_min_cycles, default=MIN_CYCLES, metavar="N",
                        help=f"fewest cycles in a band for a skew-normal fit (default {MIN_CYCLES})")
    parser.add_argument("--bootstrap", type=_bootstrap, default=N_BOOTSTRAP, metavar="N",
                        help=f"bootstrap resamples for the intervals, 0 for none (default {N_BOOTSTRAP})")
    parser.add_argument("--seed", type=_seed, default=0, metavar="S", help="seed of the bootstrap (default 0)")
    parser.add_argument("--include-undetermined", action="store_true",
                        help="keep cycles that did not determine a parameter (default: leave them out of it)")
    parser.add_argument("--include-implausible", action="store_true",
                        help="keep cycles whose estimates cannot be true or whose model was found inadequate "
                             "(default: leave them out; they are counted either way)")
    parser.add_argument("--parameters", metavar="LIST",
                        help="comma-separated parameters to analyse, every table must have them: f_h, xi_h, K_h, "
                             "C_h, BLF1, BLF2, BLF3 or their columns (default: those of the seven the tables have)")
    parser.add_argument("--mass", type=_positive, metavar="KG",
                        help="body mass for K_h and C_h (Eq. 17-18) of tables without k_h, c_h and mass columns")
    parser.add_argument("--bands", default="article", metavar="EDGES",
                        help="'article' (default: 1.35-3.75 Hz in six 0.4 Hz bands) or increasing edges in Hz, "
                             "e.g. 1.5,2,2.5,3")
    return parser


def run_stats(args) -> int:
    """Run ``smd-statespace stats``."""
    from ..population import PARAMETERS, Bands, parse_parameters, population_stats

    bands = Bands.parse(args.bands, option="--bands")
    parameters = None if args.parameters is None else parse_parameters(args.parameters, option="--parameters")
    directory = out_dir(args.out)
    started = time.perf_counter()
    stats = population_stats(args.results, bands=bands, parameters=parameters, mass=args.mass,
                             min_cycles=args.min_cycles, n_bootstrap=args.bootstrap, seed=args.seed,
                             include_undetermined=args.include_undetermined,
                             include_implausible=args.include_implausible)
    fitted = time.perf_counter() - started
    print(stats.summary())

    written = []
    frame = stats.to_frame()
    frame[["low", "high", "n", "excluded", "undetermined", "mean", "sd"]].to_csv(directory / "bands.csv")
    frame.to_csv(directory / "table2.csv")
    written += [directory / "bands.csv", directory / "table2.csv"]
    if stats.bands.is_article:
        stats.compare_table2().to_csv(directory / "table2_vs_article.csv")
        written.append(directory / "table2_vs_article.csv")
    stats.trend_frame().to_csv(directory / "trends.csv", index=False)
    written.append(directory / "trends.csv")
    stats.plot_trends(directory / "trends.png")
    written.append(directory / "trends.png")
    for parameter in stats.parameters:
        path = directory / f"hist_{PARAMETERS[parameter].column}.png"
        stats.plot_histograms(parameter, path)
        written.append(path)
    print(f"\n{stats.counts['in_bands']} {stats.noun}, {args.bootstrap} bootstrap resamples: statistics in {fitted:.1f} s, "
          f"with tables and figures {time.perf_counter() - started:.1f} s")
    print("wrote " + ", ".join(str(path) for path in written))
    return 0
