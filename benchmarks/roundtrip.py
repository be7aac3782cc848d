"""Round trip of the article's Section 5: Table 2 -> people -> GRF records -> identification -> Table 2 again.

How much does identification error widen or bias the population
distributions? People are drawn from the published Table 2
(:func:`~smd_statespace.simulation.sample_population`: independent
skew-normal marginals of Eq. 19, truncated at the simulator's physical
bounds), each bounces for ``--duration`` seconds at a bouncing frequency
drawn uniformly inside one of the article's six bands, the record is
simulated (:func:`~smd_statespace.simulation.simulate_bouncing`, default
cycle-to-cycle variation, 1 % BW noise) and identified exactly as
``smd-statespace identify`` does (``preprocess``, then
:class:`~smd_statespace.identify.runner.CycleRunner` with the article's prior and
repeated passes). The statistics of ``smd-statespace stats``
(:func:`~smd_statespace.population.population_stats`) are then fitted three times
per band and parameter:

``drawn``
    the people's true values (one per person): what a perfect identification
    of these people would give;
``identified``
    every identified cycle the runner flags as determining the parameter
    (the default of ``stats``);
``identified, all``
    every identified cycle, determined or not.

and each is compared with the published Table 2 (mean, sd and the
Kolmogorov-Smirnov distance between the fitted and published distribution
functions)::

    python benchmarks/roundtrip.py                        # the documented run: 20 people per band, 20 s each
    python benchmarks/roundtrip.py --people 2 --duration 8 --jobs 2     # a quick look

Every person's random numbers come from their own child of one
:class:`numpy.random.SeedSequence`, so the same ``--seed`` gives the same
records and results whatever ``--jobs``. Finished people are kept in
``OUT/results/`` and not recomputed when the script is run again.
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd
from tqdm import tqdm

from smd_statespace import article
from smd_statespace.identify.batch import atomic_write_csv
from smd_statespace.errors import SMDInputError
from smd_statespace.model import SMDModel
from smd_statespace.identify.runner import CycleRunner
from smd_statespace.signals import preprocess
from smd_statespace.simulation import DEFAULT_BLF, sample_population, simulate_bouncing
from smd_statespace.population import compare_table2, population_stats

EDGE_MARGIN = 0.05
"""Bouncing frequencies are drawn this far (Hz) inside the band edges, so that a person's cycles
(2 % cycle-to-cycle variation of f_b) stay in their band."""

PARAMETERS = ("f_h", "xi_h", "BLF1", "BLF2", "BLF3")
"""Table 2 parameters compared (K_h and C_h follow from these and the mass, Eq. 17-18)."""

COLUMNS = {"f_h": "f_h", "xi_h": "xi_h", "BLF1": "blf1", "BLF2": "blf2", "BLF3": "blf3"}
"""Column of each parameter in :func:`sample_population`'s table."""


def draw_person(index: int, band: int, seed: np.random.SeedSequence) -> dict:
    """Person ``index`` of ``band``: a bouncing frequency inside the band and Table 2 values."""
    rng = np.random.default_rng(seed)
    low, high = article.BANDS[band]
    f_b = float(rng.uniform(low + EDGE_MARGIN, high - EDGE_MARGIN))
    person = sample_population(1, f_b, seed=rng).iloc[0].to_dict()
    return dict(person, person=index, band=band)


def identify_person(person: dict, seed: np.random.SeedSequence, duration: float, estimator: str,
                    max_passes: int, path: Path) -> pd.DataFrame:
    """Simulate one person's record, identify every cycle, write ``path`` (one row per cycle)."""
    simulate_seed, identify_seed = seed.spawn(2)
    blf = (person["blf1"], person["blf2"], person["blf3"], DEFAULT_BLF[3])
    synthetic = simulate_bouncing(mass=person["mass"], f_b=person["f_b"], f_h=person["f_h"], xi_h=person["xi_h"],
                                  duration=duration, blf=blf, seed=np.random.default_rng(simulate_seed))
    runner = CycleRunner(SMDModel(), estimator=estimator, max_passes=max_passes,
                         seed=int(identify_seed.generate_state(1)[0]), progress=False)
    try:
        table = runner.run(preprocess(synthetic.record))
    except SMDInputError as exc:  # e.g. a GRF with two peaks per bouncing cycle: the record cannot be segmented
        table = pd.DataFrame([{"f_b": person["f_b"], "status": "failed", "reason": str(exc)}])
    table.insert(0, "person", person["person"])
    atomic_write_csv(table, path)  # a killed run leaves no half-written results
    return table


def _identify(arguments):
    return identify_person(*arguments)


def run(people_per_band: int, duration: float, estimator: str, max_passes: int, jobs: int, seed: int, out: Path):
    """Draw, simulate and identify every person (reusing finished ones); return (people, cycle table)."""
    root = np.random.SeedSequence(seed)
    n_bands = len(article.BANDS)
    person_seeds = root.spawn(n_bands * people_per_band)
    people = pd.DataFrame([draw_person(i, i % n_bands, s.spawn(1)[0]) for i, s in enumerate(person_seeds)])
    results = out / "results"
    results.mkdir(parents=True, exist_ok=True)
    people.to_csv(out / "people.csv", index=False)
    todo = [(person, person_seeds[int(person["person"])], duration, estimator, max_passes,
             results / f"person_{int(person['person']):04d}.csv")
            for person in people.to_dict("records")]
    todo = [item for item in todo if not item[-1].exists()]
    with tqdm(total=len(todo), desc=f"identify ({estimator})", unit="person") as bar:
        if jobs > 1:
            with ProcessPoolExecutor(max_workers=jobs) as pool:
                for _ in pool.map(_identify, todo):
                    bar.update()
        else:
            for item in todo:
                _identify(item)
                bar.update()
    files = sorted(results.glob("person_*.csv"))
    cycles = pd.concat([pd.read_csv(f) for f in files], ignore_index=True)
    return people, cycles


def drawn_as_cycles(people: pd.DataFrame) -> pd.DataFrame:
    """The people's true values in the layout of ``results.csv`` (one row per person, all determined)."""
    table = pd.DataFrame({
        "f_b": people["f_b"], "f_h": people["f_h"], "xi_h": people["xi_h"],
        "blf_1": people["blf1"], "blf_2": people["blf2"], "blf_3": people["blf3"],
        "k_h": people["K_h"], "c_h": people["C_h"], "status": "ok",
    })
    for name in ("f_h", "xi_h", "blf_1", "blf_2", "blf_3"):
        table[f"{name}_determined"] = True
    return table


def compare(people: pd.DataFrame, cycles: pd.DataFrame, min_cycles: int, seed: int) -> pd.DataFrame:
    """Mean, sd and KS distance to Table 2 per (parameter, band) for the drawn and the identified values."""
    frames = {}
    sets = (("drawn", drawn_as_cycles(people), False), ("identified", cycles, False),
            ("identified, all", cycles, True))
    for label, table, include in sets:
        stats = population_stats(table, parameters=PARAMETERS, min_cycles=min_cycles, n_bootstrap=0, seed=seed,
                                 include_undetermined=include)
        frames[label] = compare_table2(stats)[["n", "mean", "mean_article", "sd", "sd_article", "ks"]]
    out = pd.concat(frames, axis=1)
    return out


def summary(table: pd.DataFrame) -> pd.DataFrame:
    """Per parameter: median over bands of the mean's bias, the sd ratio and the KS distance."""
    rows = {}
    for parameter in PARAMETERS:
        part = table.loc[parameter]
        row = {}
        for label in ("drawn", "identified", "identified, all"):
            block = part[label]
            row[(label, "n")] = int(block["n"].sum())
            # pandas' median skips the bands without a fit (NaN)
            row[(label, "mean bias %")] = (100 * (block["mean"] / block["mean_article"] - 1)).median()
            row[(label, "sd ratio")] = (block["sd"] / block["sd_article"]).median()
            row[(label, "KS")] = block["ks"].median()
        rows[parameter] = row
    return pd.DataFrame(rows).T


def plot(people: pd.DataFrame, cycles: pd.DataFrame, path: Path):
    """Per band: true values against the identified ones (cycle medians per person) for f_h and xi_h."""
    from matplotlib.figure import Figure

    ok = cycles[cycles["status"] == "ok"]
    per_person = ok.groupby("person")[["f_h", "xi_h", "blf_1", "blf_2"]].median()
    truth = people.set_index("person").loc[per_person.index]
    fig = Figure(figsize=(11, 3.4), layout="constrained")
    axes = fig.subplots(1, 4)
    for ax, (name, column, label) in zip(axes, (("f_h", "f_h", r"$f_h$ (Hz)"), ("xi_h", "xi_h", r"$\xi_h$"),
                                                ("blf_1", "blf1", r"BLF$_1$ (g)"), ("blf_2", "blf2", r"BLF$_2$ (g)"))):
        x, y = truth[column].to_numpy(), per_person[name].to_numpy()
        scatter = ax.scatter(x, y, c=truth["f_b"], cmap="viridis", s=18, vmin=1.35, vmax=3.75)
        top = max(np.nanmax(x), np.nanmax(y))
        ax.plot([0, top], [0, top], color="0.5", lw=1, ls="--")
        ax.set_xlabel(f"drawn {label}")
        ax.set_ylabel(f"identified {label}\n(median over cycles)")
        ax.grid(alpha=0.3)
    fig.colorbar(scatter, ax=axes, label=r"$f_b$ (Hz)", shrink=0.9)
    fig.suptitle("Round trip: people drawn from Table 2 against their identified values", fontsize=11)
    fig.savefig(path, dpi=90)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--people", type=int, default=20, help="people per band (default 20)")
    parser.add_argument("--duration", type=float, default=20.0, help="record length (s, default 20)")
    parser.add_argument("--estimator", default="ekf", help="estimator (default ekf, the library's default)")
    parser.add_argument("--max-passes", type=int, default=8, help="passes per cycle (default 8)")
    parser.add_argument("--jobs", type=int, default=2, help="parallel processes (default 2)")
    parser.add_argument("--min-cycles", type=int, default=10, help="fewest values for a fit (default 10)")
    parser.add_argument("--seed", type=int, default=2019, help="root seed (default 2019)")
    parser.add_argument("--out", type=Path, default=Path("roundtrip_output"), help="output folder")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    people, cycles = run(args.people, args.duration, args.estimator, args.max_passes, args.jobs, args.seed, args.out)
    table = compare(people, cycles, args.min_cycles, args.seed)
    table.to_csv(args.out / "roundtrip_table.csv")
    brief = summary(table)
    brief.to_csv(args.out / "roundtrip_summary.csv")
    plot(people, cycles, args.out / "roundtrip.png")
    counts = cycles["status"].value_counts().to_dict()
    failed = cycles[(cycles["status"] == "failed") & cycles["cycle"].isna()] if "cycle" in cycles else cycles[:0]
    for row in failed.itertuples():
        print(f"person {row.person} (f_b {row.f_b:.2f} Hz): not identified: {row.reason}")
    with pd.option_context("display.float_format", "{:.3g}".format, "display.width", 200):
        print(f"{len(people)} people, {len(cycles)} cycles {counts}, {time.perf_counter() - started:.0f} s")
        print(brief.to_string())
        print(table.to_string())
    print(f"wrote {args.out}/roundtrip_table.csv, roundtrip_summary.csv, roundtrip.png")


if __name__ == "__main__":
    main()
