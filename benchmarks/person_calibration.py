"""Which calibration of the record-level intervals holds on generators and noise levels it was not made on (issue 22).

The default intervals of ``f_h`` and ``xi_h`` (``identify_person(intervals="calibrated")``)
are the record's standard errors times a factor per variation model
(:data:`~smd_statespace.person.calibration.CALIBRATION`), widened by a model-error floor in
quadrature (:data:`~smd_statespace.person.calibration.MODEL_ERROR_FLOOR`), and replaced by the
yardstick's width where the record does not determine the parameter. This study refits
nothing: it reads the rows of ``person_accuracy.py`` runs (``--csv``; e.g. one run at
``--noise 0.01`` and one at ``--noise 0.003``) and, for each *scheme* of calibration and
each generator of force variation held out in turn,

1. measures the scheme's factors on the *other* generators' records (the 90th percentile
   of ``|error| / sd`` over 1.645, on the records the factor applies to and that the
   record determines);
2. chooses the scheme's floor on the other generators (the smallest floor at which every
   other generator, at every noise level, covers at least 90 %, if the scheme has one);
3. rebuilds the held-out generator's intervals, with the "determined" rule
   (:meth:`PersonResult.determined <smd_statespace.person.results.PersonResult.determined>`:
   sd below a quarter of the yardstick) applied to the *new* sds, and reports their
   coverage per noise level and the median half-width of the determined ones.

Factors are measured on the raw sds (the observed information's, before any factor): the
rows' ``f_h_raw_se``, ``xi_h_raw_se``, or for rows of runs before they were written, the
calibrated ``f_h_se``, ``xi_h_se`` divided by the factors of the time
(:data:`ROWS_CALIBRATION`).

Schemes:

- ``as fitted``: the rows' own intervals (the library's calibration at the time of the run);
- ``by variation``: factors per variation model chosen, as the library's were made, and a
  floor chosen held out;
- ``by variation, no floor``: the same without a floor;
- ``by variation and whiteness``: factors per variation model and per whether the
  record's innovations pass the Ljung-Box test (p >= 0.01, the library's warning "the
  model misses something"): a record that shows its misfit gets the factor of records
  that show theirs; no floor;
- ``by variation, floors held out``: factors per variation model and a floor per variation
  model, the largest any generator needs when it is left out (:func:`held_out_floors`):
  the rule the library ships (``person.calibration.MODEL_ERROR_FLOOR``).
- ``by variation and noise level, floors held out``: the same with factors per variation model
  and per the simulated noise level (the true one: an upper bound on what the record's
  estimated noise could give).

::

    python benchmarks/person_calibration.py benchmarks/results/person_accuracy_seed2027.csv \\
        benchmarks/results/person_accuracy_seed2028_quiet.csv

``--rules`` compares instead the "determined" rules of :data:`RULES` on the rows' own intervals.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from smd_statespace.person.results import DETERMINED_FRACTION, MISFIT_SHARE, PRIOR_SD

ROWS_CALIBRATION = {"independent": {"f_h": 1.89, "xi_h": 2.63}, "smooth": {"f_h": 3.21, "xi_h": 1.96},
                    "random_walk": {"f_h": 2.73, "xi_h": 2.25}, "both": {"f_h": 2.73, "xi_h": 2.25}}
"""The library's factors when rows without ``f_h_raw_se`` were made (up to commit 597ec25): their sds are divided
by them to get the raw ones."""

ROWS_FLOOR = {"f_h": 0.06, "xi_h": 0.05}
"""The library's model-error floor at the time of :data:`ROWS_CALIBRATION` (every variation model)."""

LEVEL = 0.9
Z = stats.norm.ppf(0.5 + LEVEL / 2.0)
TARGET = (85.0, 95.0)
WHITE_P = 0.01
"""Ljung-Box p at or above which a record's innovations count as white (no warning)."""
FLOORS = {"f_h": np.round(np.arange(0.0, 0.101, 0.005), 3), "xi_h": np.round(np.arange(0.0, 0.101, 0.005), 3)}
"""Floors tried (relative to ``f_h`` for ``f_h``, absolute for ``xi_h``)."""

SCHEMES = {"as fitted": (None, None), "by variation": (("variation",), "one"),
           "by variation, no floor": (("variation",), "none"),
           "by variation and whiteness": (("variation", "white"), "none"),
           "by variation, floors held out": (("variation",), "held out"),
           "by variation and noise level, floors held out": (("variation", "noise"), "held out")}
"""Scheme name -> (the record features its factors are measured per, its floor: :func:`scheme_floor`); ``(None,
None)``: the rows' own intervals."""
MIN_RECORDS = 8
"""A generator's records of one variation model count for the held-out floors from this many on."""


def load(paths) -> pd.DataFrame:
    """The default-timing rows of ``person_accuracy.py`` runs that fitted (:func:`prepare`)."""
    return prepare(pd.concat([pd.read_csv(path) for path in paths], ignore_index=True))


def prepare(frame: pd.DataFrame) -> pd.DataFrame:
    """``person_accuracy.py`` rows (a run without ``noise``: 1 % BW): those of the default timing that fitted, with
    the raw sds, whiteness, what else than the sd left a record undetermined and whether its interval was widened."""
    frame = frame.copy()
    if "noise" not in frame:
        frame["noise"] = 0.01
    frame["noise"] = frame["noise"].fillna(0.01)
    frame["error"] = frame["error"].fillna("").astype(str)
    frame = frame[(frame["timing"] == "model") & (frame["error"] == "")].reset_index(drop=True)
    frame["white"] = frame["ljung_box_p"] >= WHITE_P
    for name in ("f_h", "xi_h"):
        if f"{name}_raw_se" not in frame or frame[f"{name}_raw_se"].isna().any():
            old = frame[f"{name}_se"] / frame["variation"].map({v: f[name] for v, f in ROWS_CALIBRATION.items()})
            frame[f"{name}_raw_se"] = frame.get(f"{name}_raw_se", old).fillna(old)
        threshold = DETERMINED_FRACTION * PRIOR_SD[name]
        determined = frame[f"{name}_determined"].astype(bool)
        # what else than the sd made a record undetermined: known where its sd was small enough
        other_fail = (~determined & (frame[f"{name}_se"] < threshold))
        if name == "f_h":
            other_fail |= frame["f_h_artefact"].astype(bool)
        other_fail |= (frame["misfit_share"] > MISFIT_SHARE) | (frame["xi_h_est"] > 1.0)
        frame[f"{name}_other_fail"] = other_fail
        frame[f"{name}_widened"] = ((frame[f"{name}_low"] < frame[f"{name}_low_narrow"] - 1e-12)
                                    | (frame[f"{name}_high"] > frame[f"{name}_high_narrow"] + 1e-12))
    return frame


def measure_factors(train: pd.DataFrame, name: str, by) -> tuple:
    """``(factors by group, pooled)`` on the raw sd: 90th percentile of ``|error| / raw sd`` over 1.645."""
    rows = train[~train[f"{name}_other_fail"]]
    ratio = (rows[f"{name}_est"] - rows[name]).abs() / rows[f"{name}_raw_se"]
    pooled = float(np.nanpercentile(ratio, 90) / Z)
    groups = {key: float(np.nanpercentile(r, 90) / Z) for key, r in ratio.groupby([rows[b] for b in by])}
    return {(k if isinstance(k, tuple) else (k,)): v for k, v in groups.items()}, pooled


def rebuild(rows: pd.DataFrame, name: str, factors, by, floor: float) -> tuple:
    """``(low, high, determined, sd)``: the intervals a scheme gives, the determined rule on its sds."""
    by_group, pooled = factors
    keys = list(zip(*[rows[b] for b in by]))
    factor = np.array([by_group.get(k, pooled) for k in keys])
    sd = factor * rows[f"{name}_raw_se"].to_numpy()
    est = rows[f"{name}_est"].to_numpy()
    if isinstance(floor, dict):  # a floor per variation model
        floor = rows["variation"].map(floor).fillna(max(floor.values(), default=0.0)).to_numpy()
    extra = floor * (est if name == "f_h" else 1.0)
    half = Z * np.hypot(sd, extra)
    low, high = est - half, est + half
    determined = ~rows[f"{name}_other_fail"].to_numpy() & (sd < DETERMINED_FRACTION * PRIOR_SD[name])
    return (*widen(rows, name, low, high, determined), determined, sd)


def widen(rows: pd.DataFrame, name: str, low, high, determined) -> tuple:
    """``(low, high)`` as the library widens them: an undetermined answer's to at least the yardstick's width
    around the estimate; artefacts (whole search range) and disagreeing variation models as recorded."""
    est = rows[f"{name}_est"].to_numpy()
    low = np.where(determined, low, np.minimum(low, est - Z * PRIOR_SD[name]))
    high = np.where(determined, high, np.maximum(high, est + Z * PRIOR_SD[name]))
    kept = rows[f"{name}_widened"].to_numpy() & (rows[f"{name}_other_fail"].to_numpy()
                                                 | rows["variations_disagree"].astype(bool).to_numpy())
    return (np.where(kept, np.minimum(low, rows[f"{name}_low"]), low),
            np.where(kept, np.maximum(high, rows[f"{name}_high"]), high))


def cell(rows, name, low, high, determined) -> dict:
    truth = rows[name].to_numpy()
    scale = truth if name == "f_h" else 1.0
    half = (high - low) / 2.0 / scale
    return {"coverage": 100.0 * float(np.mean((low <= truth) & (truth <= high))), "records": len(rows),
            "half-width": float(np.median(half[determined])) if determined.any() else np.nan,
            "determined": int(determined.sum())}


def choose_floor(train, name, factors, by) -> float:
    """The smallest floor at which every (generator, noise) group of ``train`` covers >= 90 %."""
    for floor in FLOORS[name]:
        worst = min(cell(rows, name, *rebuild(rows, name, factors, by, floor)[:3])["coverage"]
                    for _, rows in train.groupby(["generator", "noise"]))
        if worst >= 100.0 * LEVEL:
            return float(floor)
    return float(FLOORS[name][-1])


def needed_floor(train, test, name, by) -> dict:
    """Per variation model, the smallest floor at which ``test``'s records of it (at every noise level with at least
    :data:`MIN_RECORDS`) cover >= 90 % with factors measured on ``train``."""
    factors = measure_factors(train, name, by)

    def covers(rows, floor):
        return cell(rows, name, *rebuild(rows, name, factors, by, float(floor))[:3])["coverage"]

    out = {}
    for variation, rows in test.groupby("variation"):
        groups = [r for _, r in rows.groupby("noise") if len(r) >= MIN_RECORDS]
        # a group whose misses no floor in FLOORS reaches (estimates far off, called determined) asks for the
        # coverage the largest floor gives, not for the largest floor
        targets = [min(100.0 * LEVEL, covers(r, FLOORS[name][-1])) for r in groups]
        out[variation] = next((float(f) for f in FLOORS[name]
                               if all(covers(r, f) >= t for r, t in zip(groups, targets))), float(FLOORS[name][-1]))
    return out


def held_out_floors(frame: pd.DataFrame, name: str, by) -> dict:
    """Per variation model, the largest floor any generator of ``frame`` needs when it is left out of the factors'
    measurement (:func:`needed_floor`): the model error of a generator not yet seen, sized by the worst one seen."""
    floors = {}
    for generator in frame["generator"].unique():
        need = needed_floor(frame[frame["generator"] != generator], frame[frame["generator"] == generator], name, by)
        for variation, floor in need.items():
            floors[variation] = max(floors.get(variation, 0.0), floor)
    return floors


def scheme_floor(rule: str, train: pd.DataFrame, name: str, factors, by):
    """A scheme's floor measured on ``train``: ``"none"`` 0; ``"one"`` one floor for all (:func:`choose_floor`);
    ``"held out"`` one per variation model (:func:`held_out_floors`)."""
    if rule == "one":
        return choose_floor(train, name, factors, by)
    return held_out_floors(train, name, by) if rule == "held out" else 0.0


def held_out(frame: pd.DataFrame, name: str, schemes=None) -> pd.DataFrame:
    """One row per scheme (all of :data:`SCHEMES`, or those named), held-out generator and noise level."""
    out = []
    for held in frame["generator"].unique():
        train, test = frame[frame["generator"] != held], frame[frame["generator"] == held]
        for scheme in schemes or SCHEMES:
            by, rule = SCHEMES[scheme]
            if by is None:
                factors, floor = ({}, np.nan), np.nan
            else:
                factors = measure_factors(train, name, by)
                floor = scheme_floor(rule, train, name, factors, by)
            for noise, rows in test.groupby("noise"):
                if by is None:
                    low, high = rows[f"{name}_low"].to_numpy(), rows[f"{name}_high"].to_numpy()
                    determined = rows[f"{name}_determined"].astype(bool).to_numpy()
                else:
                    low, high, determined, _ = rebuild(rows, name, factors, by, floor)
                out.append({"scheme": scheme, "held out": held, "noise": noise, "floor": floor,
                            **cell(rows, name, low, high, determined)})
    return pd.DataFrame(out)


def _floor_text(floor) -> str:
    if isinstance(floor, dict):
        return ", ".join(f"{v} {f:g}" for v, f in sorted(floor.items()))
    return "-" if not np.isfinite(floor) else f"{floor:g}"


def _factor_text(factors: dict) -> str:
    return ", ".join(f"{' '.join(str(k) for k in key).replace('True', 'white').replace('False', 'not white')} "
                     f"{v:.2f}" for key, v in sorted(factors.items(), key=lambda kv: str(kv[0])))


def table(results: pd.DataFrame, name: str) -> list:
    """Markdown: schemes as rows, (held-out generator, noise) as columns: coverage (determined records' median
    half-width)."""
    results = results.assign(column=results["held out"] + ", " + (100 * results["noise"]).map("{:g} %".format))
    columns = list(dict.fromkeys(results["column"]))
    unit = " (of f_h)" if name == "f_h" else ""
    lines = [f"| {name}: scheme | floor{unit} chosen on the others | " + " | ".join(columns)
             + " | cells within 85-95 % | cells below 85 % |", "|---|---|" + "---|" * len(columns) + "---|---|"]
    for scheme, rows in results.groupby("scheme", sort=False):
        by = rows.set_index("column")
        within = ((by["coverage"] >= TARGET[0]) & (by["coverage"] <= TARGET[1])).sum()
        below = (by["coverage"] < TARGET[0]).sum()
        texts = list(dict.fromkeys(_floor_text(f) for f in by["floor"]))
        floor = texts[0] if len(texts) == 1 else "; ".join(texts)
        cells = [f"{by.loc[c, 'coverage']:.0f} % ("
                 + ("-" if np.isnan(by.loc[c, "half-width"]) else f"{by.loc[c, 'half-width']:.3f}") + ")"
                 for c in columns]
        lines.append(f"| {scheme} | {floor} | " + " | ".join(cells) + f" | {within}/{len(columns)} | {below} |")
    return lines


def on_all(frame: pd.DataFrame, name: str) -> tuple:
    """Each scheme calibrated on every generator (what the library would ship): Markdown bullets of its factors and
    floor, and the rows of its coverage per generator and noise level (in-sample)."""
    lines, out = [], []
    for scheme, (by, rule) in SCHEMES.items():
        if by is None:
            continue
        factors, pooled = measure_factors(frame, name, by)
        floor = scheme_floor(rule, frame, name, (factors, pooled), by)
        lines.append(f"- {name}, {scheme}: {_factor_text(factors)} (pooled {pooled:.2f}); floor "
                     f"{_floor_text(floor)}")
        for (generator, noise), rows in frame.groupby(["generator", "noise"]):
            low, high, determined, _ = rebuild(rows, name, (factors, pooled), by, floor)
            out.append({"scheme": scheme, "held out": generator, "noise": noise, "floor": floor,
                        **cell(rows, name, low, high, determined)})
    return lines, pd.DataFrame(out)


def check(frame: pd.DataFrame, name: str) -> pd.DataFrame:
    """Fresh records fitted with the shipped calibration: their intervals as fitted, and rebuilt with the
    calibration before it (:data:`ROWS_CALIBRATION`, :data:`ROWS_FLOOR`), per generator and noise level."""
    before = ({(v,): f[name] for v, f in ROWS_CALIBRATION.items()}, np.nan)
    out = []
    for (generator, noise), rows in frame.groupby(["generator", "noise"]):
        low, high = rows[f"{name}_low"].to_numpy(), rows[f"{name}_high"].to_numpy()
        determined = rows[f"{name}_determined"].astype(bool).to_numpy()
        out.append({"scheme": "shipped (as fitted)", "held out": generator, "noise": noise, "floor": np.nan,
                    **cell(rows, name, low, high, determined)})
        low, high, determined, _ = rebuild(rows, name, before, ("variation",), ROWS_FLOOR[name])
        out.append({"scheme": "before (rebuilt)", "held out": generator, "noise": noise, "floor": ROWS_FLOOR[name],
                    **cell(rows, name, low, high, determined)})
    return pd.DataFrame(out)


RULES = {"sd < 0.22 Hz (shipped)": None, "sd < 8.66 % of f_h": 0.0866, "sd < 6 % of f_h": 0.06}
""""Determined" rules for ``f_h`` compared by :func:`determined_rules`: ``None`` the library's (a quarter of the
yardstick, 0.22 Hz), a number the sd's largest share of the estimate."""


def determined_rules(frame: pd.DataFrame) -> pd.DataFrame:
    """The rows' own calibrated ``f_h`` intervals with each of :data:`RULES` for "determined" (the other checks
    kept): how many are determined, how many of those miss, the largest error among them, the coverage, and
    against the shipped rule the answers given back (and how many of them miss) and taken away."""
    sd, est, truth = (frame[c].to_numpy() for c in ("f_h_se", "f_h_est", "f_h"))
    error = np.abs(est / truth - 1.0)
    ok = ~frame["f_h_other_fail"].to_numpy()
    narrow_low, narrow_high = frame["f_h_low_narrow"].to_numpy(), frame["f_h_high_narrow"].to_numpy()
    narrow = (narrow_low <= truth) & (truth <= narrow_high)
    shipped = ok & (sd < DETERMINED_FRACTION * PRIOR_SD["f_h"])
    out = []
    for rule, share in RULES.items():
        determined = shipped if share is None else ok & (sd < share * est)
        low, high = widen(frame, "f_h", narrow_low, narrow_high, determined)
        covered = (low <= truth) & (truth <= high)
        given, taken = determined & ~shipped, shipped & ~determined
        out.append({"rule": rule, "determined": int(determined.sum()),
                    "determined and missed": int((determined & ~covered).sum()),
                    "largest error determined (%)": (100.0 * float(error[determined].max())
                                                     if determined.any() else np.nan),
                    "coverage (%)": 100.0 * float(covered.mean()), "given back": int(given.sum()),
                    "given back and missed": int((given & ~narrow).sum()), "taken away": int(taken.sum())})
    return pd.DataFrame(out)


def check_figure(fresh: pd.DataFrame, path: Path) -> None:
    """Coverage and half-width per generator and noise level on fresh records: the shipped calibration against the
    one before it, for ``f_h`` and ``xi_h`` (a PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(12, 7), sharex=True)
    for row, name in enumerate(("f_h", "xi_h")):
        results = check(fresh, name)
        results["column"] = results["held out"] + "\n" + (100 * results["noise"]).map("{:g} %".format)
        columns = list(dict.fromkeys(results["column"]))
        x = np.arange(len(columns))
        for offset, (scheme, colour) in zip((-0.2, 0.2), (("before (rebuilt)", "tab:grey"),
                                                          ("shipped (as fitted)", "tab:blue"))):
            by = results[results["scheme"] == scheme].set_index("column").reindex(columns)
            axes[row, 0].bar(x + offset, by["coverage"], width=0.4, color=colour, label=scheme)
            axes[row, 1].bar(x + offset, by["half-width"], width=0.4, color=colour, label=scheme)
        axes[row, 0].axhspan(*TARGET, color="tab:green", alpha=0.15, label="target 85-95 %")
        axes[row, 0].set_ylim(50, 102)
        axes[row, 0].set_ylabel(f"{name}: 90 % coverage (%)")
        axes[row, 1].set_ylabel(f"{name}: median half-width" + (" (of f_h)" if name == "f_h" else ""))
        for ax in axes[row]:
            ax.set_xticks(x)
            ax.set_xticklabels(columns, fontsize=7, rotation=30)
            ax.grid(axis="y", alpha=0.3)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=8, loc="upper right", ncol=3)
    fig.suptitle("Fresh records: the intervals' coverage and width, calibration before and shipped\n"
                 "(half-width over determined answers; pulses has none)", fontsize=10, x=0.3)
    fig.tight_layout(rect=(0, 0, 1, 0.95))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rows", nargs="+", type=Path, help="CSV rows of person_accuracy.py runs (their --csv)")
    parser.add_argument("--check", nargs="+", type=Path, default=(), metavar="CSV",
                        help="rows of fresh runs fitted with the shipped calibration: their coverage and width, "
                             "beside the calibration before it rebuilt on the same fits")
    parser.add_argument("--figure", type=Path, default=None, metavar="PNG",
                        help="with --check: draw the fresh records' coverage and widths here")
    parser.add_argument("--rules", action="store_true",
                        help="only compare the 'determined' rules of RULES on the rows (their own intervals)")
    args = parser.parse_args(argv)
    for path in (*args.rows, *args.check):
        if not path.is_file():
            parser.error(f"{path}: no such file (the --csv of a person_accuracy.py run)")
    frame = load(args.rows)
    if args.rules:
        print(f"{len(frame)} records fitted; f_h 'determined' by each rule:\n")
        rules = determined_rules(frame)
        print("| " + " | ".join(rules.columns) + " |\n" + "|---" * len(rules.columns) + "|")
        for row in rules.itertuples(index=False):
            print("| " + " | ".join(f"{v:.1f}" if isinstance(v, float) else str(v) for v in row) + " |")
        return 0
    counts = frame.groupby(["generator", "noise"]).size()
    print("records fitted: " + ", ".join(f"{g} {100 * n:g} % BW {k}" for (g, n), k in counts.items()) + "\n")
    print("Coverage of the 90 % intervals on each held-out generator (median half-width of its determined "
          "records' intervals, relative for f_h):\n")
    for name in ("f_h", "xi_h"):
        print("\n".join(table(held_out(frame, name), name)) + "\n")
    print("Calibrated on all generators (in-sample): factors on the raw sd, floor, coverage:\n")
    for name in ("f_h", "xi_h"):
        lines, rows = on_all(frame, name)
        print("\n".join(lines) + "\n")
        print("\n".join(table(rows, name)).replace("chosen on the others", "chosen on all") + "\n")
    if args.check:
        fresh = load(args.check)
        counts = fresh.groupby(["generator", "noise"]).size()
        print("Fresh records (" + ", ".join(f"{g} {100 * n:g} % BW {k}" for (g, n), k in counts.items())
              + "): the shipped calibration as fitted, and the one before rebuilt on the same fits:\n")
        for name in ("f_h", "xi_h"):
            print("\n".join(table(check(fresh, name), name)).replace("chosen on the others", "") + "\n")
        if args.figure is not None:
            check_figure(fresh, args.figure)
            print(f"wrote {args.figure}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
