"""Coverage of the record-level intervals on quiet and fast records (:func:`smd_statespace.person.identify_person`).

``person.calibration.CALIBRATION`` was measured on 30 s records at 100 Hz with 1 % BW
noise (``person_accuracy.py``). Real force plates are quieter and faster. This
study simulates the same people (``person_accuracy.draw_people``) in four
conditions, 100 Hz or 1000 Hz (decimated to 100 Hz by ``identify_person``)
and 1 % or 0.3 % BW noise, with both generators of force variation, fits each
record as a user would (``identify_person`` with its defaults) and counts how
often the 90 % intervals hold the truth::

    python benchmarks/person_noise.py --jobs 2 --records 16 --seed 77    # about 10 min on 2 cores
    python benchmarks/person_noise.py --floor 0.08,0.05                   # another floor
    python benchmarks/person_noise.py --generators smooth,matern --records 8 --jobs 2   # the variation's shape

Columns: coverage of ``f_h`` and ``xi_h``, without the model-error floor (the same fits'
calibrated sds alone, as ``--floor 0,0`` would give) and with it; the median signed error of ``f_h``
(%), which the noise level does not remove; the median calibrated sd of
``f_h`` (Hz); the share of records whose innovations pass the Ljung-Box test
(p >= 0.01: no "the model misses something" warning); the share of records whose ``f_h`` is called
determined, and of those determined yet more than 10 % off (a confident wrong answer). ``--floor F,X`` sets
``person.calibration.MODEL_ERROR_FLOOR`` for the
run, for every variation model (relative for ``f_h``, absolute for ``xi_h``).

Everything random comes from ``SeedSequence(--seed)`` through ``draw_people``;
the rows do not depend on ``--jobs``.
"""

from __future__ import annotations

import argparse
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pandas as pd
from scipy import stats
from tqdm.auto import tqdm

sys.path.insert(0, str(Path(__file__).resolve().parent))
import person_accuracy  # noqa: E402  (draw_people: the same people as the accuracy study)

from smd_statespace.person import calibration as person_calibration  # noqa: E402
from smd_statespace.person import identify_person  # noqa: E402
from smd_statespace.person.noise_floor import NOISE_FLOOR  # noqa: E402
from smd_statespace.simulation import simulate_bouncing  # noqa: E402

CONDITIONS = (("100 Hz, 1 % BW", 100.0, 0.01), ("100 Hz, 0.3 % BW", 100.0, 0.003),
              ("1000 Hz, 1 % BW", 1000.0, 0.01), ("1000 Hz, 0.3 % BW", 1000.0, 0.003))
"""(label, sampling rate in Hz, GRF noise as a fraction of body weight)."""

DURATION = 30.0


def one(task) -> dict:
    """Simulate and identify one record; never raises."""
    person, (label, fs, noise), generator, floor, noise_floor = task
    if floor is not None:
        for floors in person_calibration.MODEL_ERROR_FLOOR.values():  # the same floor for every variation model
            floors.update(f_h=floor[0], xi_h=floor[1])
    row = {"condition": label, "generator": generator, "record": int(person["record"]), "error": ""}
    blf = [person[f"blf{i}"] for i in range(1, 5)]
    try:
        record = simulate_bouncing(mass=person["mass"], f_b=person["f_b"], f_h=person["f_h"], xi_h=person["xi_h"],
                                   duration=DURATION, fs=fs, blf=blf, noise=noise, seed=int(person["sim_seed"]),
                                   variation=generator).record
        result = identify_person(record, noise_floor=noise_floor)
    except Exception as exc:  # noqa: BLE001 - one record must never kill the study
        row["error"] = f"{type(exc).__name__}: {str(exc).splitlines()[0][:120]}"
        return row
    for which, name in enumerate(("f_h", "xi_h")):
        low, high = result.intervals[name]
        row[f"{name}_covered"] = bool(low <= person[name] <= high)
        row[f"{name}_error"] = float(result.params[which] - person[name])
        row[f"{name}_sd"] = float(result.se[which])
    row["f_h_error_pct"] = 100.0 * row["f_h_error"] / person["f_h"]
    d = result.to_dict()
    row["white"] = bool(d["ljung_box_p"] >= 0.01)  # no "the model misses something" warning
    row.update(misfit_share=float(d["misfit_share"]), misfit=bool(d["misfit"]),
               f_h_determined=bool(d["f_h_determined"]))
    return row


def _coverage(rows) -> str:
    """``without / with`` the floor, for f_h and xi_h: the first from the same fits' calibrated sds alone."""
    z = stats.norm.ppf(0.95)
    cells = []
    for name in ("f_h", "xi_h"):
        without = (rows[f"{name}_error"].abs() <= z * rows[f"{name}_sd"]).mean()
        cells.append(f"{without:.0%} / {rows[f'{name}_covered'].mean():.0%}")
    return " | ".join(cells)


def _share(flags) -> str:
    """``k/n`` of a boolean column."""
    return f"{int(flags.sum())}/{len(flags)}"


def summary(frame: pd.DataFrame) -> list:
    """Markdown table: one row per condition and generator."""
    lines = ["| record | generator | records (failed) | f_h 90 % coverage, without / with floor | "
             "xi_h: without / with | "
             "f_h signed error, median | \\|f_h error\\|, median | xi_h signed error, median | "
             "f_h sd (calibrated), median | Ljung-Box p >= 0.01 | f_h determined | determined, > 10 % off |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for (condition, generator), rows in frame.groupby(["condition", "generator"], sort=False):
        ok = rows[rows["error"] == ""]
        if ok.empty:
            lines.append(f"| {condition} | {generator} | {len(rows)} ({len(rows)}) |" + " |" * 9)
            continue
        lines.append(f"| {condition} | {generator} | {len(rows)} ({len(rows) - len(ok)}) | {_coverage(ok)} | "
                     f"{ok['f_h_error_pct'].median():+.1f} % | {ok['f_h_error_pct'].abs().median():.1f} % | "
                     f"{ok['xi_h_error'].median():+.3f} | {ok['f_h_sd'].median():.3f} Hz | {ok['white'].mean():.0%} | "
                     f"{_share(ok['f_h_determined'])} | "
                     f"{_share(ok['f_h_determined'] & (ok['f_h_error_pct'].abs() > 10))} |")
    ok = frame[frame["error"] == ""]
    lines.append(f"| all | | {len(frame)} ({len(frame) - len(ok)}) | {_coverage(ok)} | | | | | "
                 f"{ok['white'].mean():.0%} | {_share(ok['f_h_determined'])} | "
                 f"{_share(ok['f_h_determined'] & (ok['f_h_error_pct'].abs() > 10))} |")
    return lines


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=16, help="people per condition and generator (default 16)")
    parser.add_argument("--seed", type=int, default=77, help="root of the SeedSequence (default 77)")
    parser.add_argument("--jobs", type=int, default=1, help="processes (default 1)")
    parser.add_argument("--floor", default=None, metavar="F,X",
                        help="model-error floor of f_h (relative) and xi_h for this run (default: the library's)")
    parser.add_argument("--generators", default=",".join(person_accuracy.GENERATORS),
                        help=f"comma-separated generators (default all: {','.join(person_accuracy.GENERATORS)})")
    parser.add_argument("--noise-floor", type=float, default=NOISE_FLOOR,
                        help=f"identify_person's noise_floor (default {NOISE_FLOOR:g}; 0: the records as measured)")
    parser.add_argument("--csv", type=Path, default=None, help="also write every record's row here")
    args = parser.parse_args(argv)
    floor = None if args.floor is None else tuple(float(v) for v in args.floor.split(","))
    generators = [g.strip() for g in args.generators.split(",") if g.strip()]
    unknown = sorted(set(generators) - set(person_accuracy.GENERATORS))
    if unknown:
        parser.error(f"--generators: {', '.join(unknown)} not among {', '.join(person_accuracy.GENERATORS)}")
    people = person_accuracy.draw_people(args.records, args.seed)
    tasks = [(person, condition, generator, floor, args.noise_floor) for condition in CONDITIONS
             for generator in generators for _, person in people.iterrows()]
    started = time.perf_counter()
    with ProcessPoolExecutor(max(1, args.jobs)) as pool:
        rows = list(tqdm(pool.map(one, tasks), total=len(tasks), unit="record", desc="records"))
    frame = pd.DataFrame(rows)
    if args.csv is not None:
        frame.to_csv(args.csv, index=False)
    used = (f"f_h {floor[0]:g} (relative), xi_h {floor[1]:g}" if floor else
            "; ".join(f"{v}: f_h {f['f_h']:g} (relative), xi_h {f['xi_h']:g}"
                      for v, f in person_calibration.MODEL_ERROR_FLOOR.items()))
    print(f"model-error floor: {used}; noise floor {args.noise_floor:g} of body weight; seed {args.seed}")
    print("\n".join(summary(frame)))
    for _, row in frame[frame["error"] != ""].iterrows():
        print(f"failed: {row['condition']} {row['generator']} #{row['record']}: {row['error']}")
    print(f"\n{len(frame)} records, {(time.perf_counter() - started) / 60:.1f} min, {args.jobs} process(es)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
