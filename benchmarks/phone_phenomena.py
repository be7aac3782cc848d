"""Which phone phenomenon breaks the phone's answer (issue 44): the plate and the phone on the same people, one
phenomenon at a time.

Each row records its people (``--people``, default 40) as :mod:`phone_vs_plate` does: 30 s of bouncing (the
``jumps`` variation unless the row says otherwise), people across the article's range (``f_b`` 1.5-3.5 Hz, ``f_h``
1.8-4.2 Hz, ``xi_h`` 0.1-0.5, 50-90 kg, each BLF the default times 0.7-1.3, the phone tilted 0-30 degrees), one and
the same bounce seen by

- the **plate**: GRF at 100 Hz with 1 % BW noise (:meth:`PhoneRecord.plate_record`), ``identify_person(record)``;
- the **phone**: :func:`~smd_statespace.simulation.phone.simulate_phone` with the baseline's settings (those of
  ``phone_vs_plate.py``: bias up to 0.2 m/s^2, noise 0.05 m/s^2, clock jitter 0.3 ms with exact stamps, 0.5 % of
  samples dropped, sway 3 degrees at 0.1 Hz, horizontal COM acceleration 0.3 m/s^2, the sensor's anti-alias
  filter, 200 Hz) and the row's phenomenon on top (:data:`ROWS`), written in phyphox's format, read back with
  ``accelerometer_record(path)`` and identified with ``identify_person(record)``'s defaults.

Per row: median and worst ``|f_h error|`` of plate and phone, median ``|xi_h error|``, coverage of the 90 %
intervals of ``f_h``, determined share, confident misses (determined and the interval misses), the phone fit's
median seconds, and the median kurtosis and Ljung-Box p of the innovations (``result.test_pvalues()``)::

    python benchmarks/phone_phenomena.py --people 12 --jobs 2            # explore
    python benchmarks/phone_phenomena.py --people 40 --jobs 2 --resume   # the run (goes on after a kill)

Seeds: person ``k`` of row ``r`` (its index in :data:`ROWS`, whatever ``--rows`` selects) draws everything from
``numpy.random.SeedSequence(seed, spawn_key=(r, k))``: the rows do not depend on ``--jobs``, ``--people`` or
``--rows``. Every person's row is appended to the CSV (default
``benchmarks/results/phone_phenomena_seed<S>.csv``) in one write as it finishes; ``--resume`` fits only the missing
ones (and those that failed). A failure (simulation, reading or fit) is a row with ``error`` set; the run goes on.
Rows marked held out (:data:`HELD_OUT`) are combinations not used to decide what breaks the answer.
"""

from __future__ import annotations

import os

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import shlex  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from concurrent.futures import ProcessPoolExecutor, as_completed  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
import phone_vs_plate  # noqa: E402  (beside this script: the people's ranges, the answer's fields)
from result_csv import append_row, open_csv  # noqa: E402  (beside this script: the resumable CSV)

BASELINE = dict(bias=0.2, noise=0.05, fs=200.0)
"""The phone of ``phone_vs_plate.py`` (its other settings are simulate_phone's defaults: jitter 0.3 ms, drop 0.5 %,
sway 3 degrees at 0.1 Hz, horizontal 0.3 m/s^2, anti-alias filter on)."""

PLATE = dict(fs=100.0, noise=0.01)
"""The plate: 100 Hz, noise 1 % of body weight (``phone_vs_plate.py``'s defaults)."""

ALL = dict(anti_alias=False, rocking=5.0, wander=5.0, stamp_jitter=1e-3, jitter=0.0, gaps=(4, 0.25), scale=0.03,
           bias=0.5, body_sway=0.5)
"""Every phenomenon together at its row's level (the body sway's frequency drawn per person)."""

ROWS = (
    ("baseline", {}),
    ("no_anti_alias_100", dict(anti_alias=False, fs=100.0)),
    ("no_anti_alias_200", dict(anti_alias=False)),
    ("no_anti_alias_400", dict(anti_alias=False, fs=400.0)),
    ("rocking_5deg", dict(rocking=5.0)),
    ("wander_5deg", dict(wander=5.0)),
    ("stamp_jitter_1ms_200", dict(stamp_jitter=1e-3, jitter=0.0)),
    ("stamp_jitter_1ms_400", dict(stamp_jitter=1e-3, jitter=0.0, fs=400.0)),
    ("stamp_jitter_2ms_100", dict(stamp_jitter=2e-3, jitter=0.0, fs=100.0)),
    ("clock_1ms_drop3", dict(jitter=1e-3, drop=0.03)),
    ("gaps_4x0.25s", dict(gaps=(4, 0.25))),
    ("gain3_bias0.5", dict(scale=0.03, bias=0.5)),
    ("body_sway_0.5", dict(body_sway=0.5)),
    ("all_200", dict(ALL)),
    ("all_100_smooth", dict(ALL, fs=100.0, variation="smooth", rocking=3.0, wander=3.0, stamp_jitter=2e-3,
                            gaps=(3, 0.2), scale=0.02, bias=0.3, body_sway=0.3)),
    ("all_400", dict(ALL, fs=400.0, rocking=4.0, stamp_jitter=0.5e-3, gaps=(6, 0.15), drop=0.02)),
    ("all_but_gaps_200", {k: v for k, v in ALL.items() if k != "gaps"}),
    ("gaps_4x0.1s", dict(gaps=(4, 0.1))),
    ("session_handling", dict(session=True)),
)
"""``(name, options of simulate_phone over BASELINE)``; ``body_sway`` rows draw its frequency per person, 0.2-1 Hz;
``variation`` is the person's force generator (default ``jumps``). The last two were added after a first look at 12
people per row (every ``all`` row broken, and so was ``gaps_4x0.25s``): everything but the gaps, and shorter gaps.
``session_handling`` (held out) is a phone record as people make one
(:func:`~smd_statespace.simulation.phone_session.simulate_phone_session` with the baseline's rate, bias and noise:
on the table, picked up, worn standing 5 s, ramps, 30 s of bouncing, standing, taken off) against the plate's record
of the same person (standing before and after, ramps): both through the front end. New rows go at the end: a row's
index seeds its people."""

HELD_OUT = {"all_100_smooth", "all_400", "session_handling"}
"""Combinations not used to decide which phenomenon breaks the answer."""

COLUMNS = ("seed", "row", "row_index", "person", "held_out", "fs", "options", "f_b", "f_h", "xi_h", "mass", "tilt",
           "body_sway_frequency", "plate_f_h", "plate_f_h_error", "plate_xi_h", "plate_xi_h_error",
           "plate_f_h_covered", "plate_xi_h_covered", "plate_f_h_determined", "plate_blf_1", "plate_misfit",
           "plate_kurtosis", "plate_ljung_box_p", "plate_variation", "phone_f_h", "phone_f_h_error", "phone_xi_h",
           "phone_xi_h_error", "phone_f_h_covered", "phone_xi_h_covered", "phone_f_h_determined", "phone_blf_1",
           "phone_misfit", "phone_kurtosis", "phone_ljung_box_p", "phone_variation", "phone_f_h_low",
           "phone_f_h_high", "phone_seconds", "phone_samples", "phone_n_backwards", "tilt_estimated",
           "direction_change_deg", "reading_rms", "reading_max", "reading_kurtosis", "blf_1_truth", "seconds",
           "error")
"""One CSV row per person and row."""

CSV_KEYS = (("seed", int), ("row", str), ("person", int))
"""The columns that name a fitted person in the CSV (``--resume`` skips those fitted without error)."""


def row_options(name: str) -> dict:
    return dict(dict(ROWS)[name])


def draw(seed: int, row_index: int, k: int) -> dict:
    """Person ``k`` of row ``row_index``: ``phone_vs_plate.person``'s ranges from ``SeedSequence(seed,
    spawn_key=(row_index, k))``, then the body sway's frequency (0.2-1 Hz; used only where the row sways)."""
    from smd_statespace.simulation import DEFAULT_BLF

    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(row_index, k)))
    p = {"f_b": rng.uniform(1.5, 3.5), "f_h": rng.uniform(1.8, 4.2), "xi_h": rng.uniform(0.1, 0.5),
         "mass": rng.uniform(50.0, 90.0), "blf": tuple(np.array(DEFAULT_BLF) * rng.uniform(0.7, 1.3, 4)),
         "tilt": rng.uniform(0.0, 30.0), "seed": int(rng.integers(2**31))}
    p["body_sway_frequency"] = rng.uniform(0.2, 1.0)
    return p


def _tests(result, prefix: str) -> dict:
    tests = result.test_pvalues()
    return {f"{prefix}_kurtosis": tests["kurtosis"], f"{prefix}_ljung_box_p": tests["ljung_box_p"],
            f"{prefix}_variation": result.model.variation}


def reading_error(phone, record, anti_alias: bool) -> dict:
    """The read vertical ``a_v`` (the record's ``GRF / M - g``) against the truth the sensor saw at the grid's
    times (the COM acceleration through the sensor's filter when it has one), away from the first and last
    second: its RMS, largest value (m/s^2) and kurtosis. Large here: the reading is wrong; small while the fit is
    wrong: the model."""
    from smd_statespace.io import G
    from smd_statespace.simulation.phone import sensor_filter

    states = phone.person.states
    fine_time, sensed = states["time"].to_numpy(), states["u_ddot"].to_numpy()
    if anti_alias:
        sensed = sensor_filter(sensed, phone.truth["phone"]["fs"], float(phone.person.truth["fs"]))
    start = record.extra["clock"]["start"]  # the grid's first time (the record's time starts at 0 there)
    error = record.force / record.mass - G - np.interp(record.time + start, fine_time, sensed)
    error = error[(record.time > 1.0) & (record.time < record.time[-1] - 1.0)]
    centred = error - error.mean()
    return {"reading_rms": float(np.sqrt(np.mean(error**2))), "reading_max": float(np.abs(error).max()),
            "reading_kurtosis": float(np.mean(centred**4) / np.mean(centred**2) ** 2)}


def _simulate(p: dict, options: dict):
    """The phone's record of person ``p``: :func:`simulate_phone` (30 s of bouncing), or with ``session`` in the
    options :func:`simulate_phone_session` (handling, standing, ramps, 30 s of bouncing)."""
    from smd_statespace.simulation.phone import simulate_phone
    from smd_statespace.simulation.phone_session import simulate_phone_session

    person = dict(mass=p["mass"], f_b=p["f_b"], f_h=p["f_h"], xi_h=p["xi_h"], blf=p["blf"], tilt=p["tilt"],
                  seed=p["seed"])
    if options.get("session"):
        return simulate_phone_session(**person, bout=30.0, fs=options["fs"], bias=options["bias"],
                                      noise=options["noise"])
    return simulate_phone(**person, duration=30.0, **options)


def run_person(task) -> dict:
    """Simulate person ``k`` of a row, identify plate and phone; never raises (the failure is ``error``)."""
    from smd_statespace.accelerometer import accelerometer_record
    from smd_statespace.person import identify_person

    seed, name, k = task
    index = [r for r, _ in ROWS].index(name)
    options = dict(BASELINE, **row_options(name))
    p = draw(seed, index, k)
    out = {c: "" for c in COLUMNS}
    out.update(seed=seed, row=name, row_index=index, person=k, held_out=name in HELD_OUT, fs=options["fs"],
               options=json.dumps(row_options(name), sort_keys=True), blf_1_truth=p["blf"][0],
               **{c: p[c] for c in ("f_b", "f_h", "xi_h", "mass", "tilt")})
    if options.get("body_sway"):
        options["body_sway_frequency"] = out["body_sway_frequency"] = p["body_sway_frequency"]
    started = time.perf_counter()
    stage = "simulate"
    try:
        truth = {"f_h": p["f_h"], "xi_h": p["xi_h"]}
        phone = _simulate(p, options)
        stage = "plate"
        plate = identify_person(phone.plate_record(fs=PLATE["fs"], noise=PLATE["noise"], seed=p["seed"] + 1))
        out.update({f"plate_{key}": v for key, v in phone_vs_plate._answer(plate, truth).items()})
        out.update(_tests(plate, "plate"))
        stage = "phone"
        with tempfile.TemporaryDirectory() as folder:
            path, _ = phone.write(Path(folder) / "phone.csv")
            moment = time.perf_counter()
            record = accelerometer_record(path)
            result = identify_person(record)
            out["phone_seconds"] = round(time.perf_counter() - moment, 3)
        if not options.get("session"):  # the session's phone clock starts before the person's (pick-up)
            out.update(reading_error(phone, record, options.get("anti_alias", True)))
        out.update({f"phone_{key}": v for key, v in phone_vs_plate._answer(result, truth).items()})
        out.update(_tests(result, "phone"))
        low, high = (float(v) for v in result.intervals["f_h"])
        out.update(phone_f_h_low=low, phone_f_h_high=high, phone_samples=len(phone.time),
                   phone_n_backwards=record.extra["clock"].get("n_backwards", ""),
                   tilt_estimated=record.extra["geometry"]["tilt_deg"],
                   direction_change_deg=record.extra["geometry"]["direction_change_deg"])
    except Exception as exc:  # noqa: BLE001 - one record must never stop the run
        text = str(exc).strip().splitlines()
        out["error"] = f"{stage}: {type(exc).__name__}: {text[0][:200] if text else ''}"
    out["seconds"] = round(time.perf_counter() - started, 3)
    return out


# ---------------------------------------------------------------------------
# the CSV


def load(path: Path, seed: int, rows, n: int) -> pd.DataFrame:
    frame = pd.read_csv(path, dtype={"error": str, "options": str})
    frame = frame[(frame["seed"] == seed) & frame["row"].isin(rows) & (frame["person"] < n)]
    frame = frame.drop_duplicates(["row", "person"], keep="last")
    frame["error"] = frame["error"].fillna("").astype(str)
    for name in [c for c in COLUMNS if c.endswith(("_covered", "_determined", "_misfit"))] + ["held_out"]:
        frame[name] = frame[name].map({True: True, False: False, "True": True, "False": False})
    return frame


# ---------------------------------------------------------------------------
# tables


def _row_cells(rows: pd.DataFrame) -> list:
    ok = rows[rows["error"] == ""]
    n, failed = len(rows), int((rows["error"] != "").sum())
    if not len(ok):
        return [f"{n} ({failed})"] + ["—"] * 13
    cells = [f"{n} ({failed})"]
    for sensor in ("plate", "phone"):
        err = 100 * ok[f"{sensor}_f_h_error"].astype(float).abs()
        cells.append(f"{err.median():.1f} / {err.max():.1f}")
    for sensor in ("plate", "phone"):
        cells.append(f"{ok[f'{sensor}_xi_h_error'].astype(float).abs().median():.3f}")
    for sensor in ("plate", "phone"):
        det = ok[f"{sensor}_f_h_determined"].astype(bool)
        cov = ok[f"{sensor}_f_h_covered"].astype(bool)
        cells.append(f"{100 * cov.mean():.0f} % / {100 * det.mean():.0f} % / {int((det & ~cov).sum())}")
    cells += [f"{ok['phone_seconds'].astype(float).median():.1f}",
              f"{ok['plate_kurtosis'].astype(float).median():.2f} / {ok['phone_kurtosis'].astype(float).median():.2f}",
              f"{ok['plate_ljung_box_p'].astype(float).median():.2g} / "
              f"{ok['phone_ljung_box_p'].astype(float).median():.2g}",
              f"{(ok['phone_variation'] != ok['plate_variation']).sum()}",
              f"{ok['reading_rms'].astype(float).median():.3f} / {ok['reading_max'].astype(float).median():.2f} / "
              f"{ok['reading_kurtosis'].astype(float).median():.1f}"]
    return cells


HEADER = ("row", "people (failed)", "plate \\|f_h err\\| % median / worst", "phone median / worst",
          "plate \\|xi_h err\\| median", "phone", "plate f_h coverage / determined / confident misses", "phone",
          "phone fit s (median)", "innovation kurtosis plate / phone (median)", "Ljung-Box p plate / phone (median)",
          "variation model differs", "reading error (a_v - truth) rms / max m/s^2 / kurtosis (median)")


SIDE = ("row", "signed median f_h error % plate / phone", "median (\\|phone\\| - \\|plate\\|) error, points",
        "records over 8 %: plate / phone", "phone chose `smooth`", "phone f_h interval width, median Hz")


def _side_cells(rows: pd.DataFrame) -> list:
    """Where the errors go: their sign, the pair's difference, the tail, the variation model, the intervals."""
    ok = rows[rows["error"] == ""]
    if not len(ok):
        return ["—"] * (len(SIDE) - 1)
    plate, phone = ok["plate_f_h_error"].astype(float), ok["phone_f_h_error"].astype(float)
    width = ok["phone_f_h_high"].astype(float) - ok["phone_f_h_low"].astype(float)
    return [f"{100 * plate.median():+.1f} / {100 * phone.median():+.1f}",
            f"{100 * (phone.abs() - plate.abs()).median():+.1f}",
            f"{int((plate.abs() > 0.08).sum())} / {int((phone.abs() > 0.08).sum())}",
            f"{int((ok['phone_variation'] == 'smooth').sum())}/{len(ok)}", f"{width.median():.2f}"]


def summary_lines(frame: pd.DataFrame, rows) -> list:
    lines = ["| " + " | ".join(HEADER) + " |", "|" + "---|" * len(HEADER)]
    side = ["", "| " + " | ".join(SIDE) + " |", "|" + "---|" * len(SIDE)]
    for name in rows:
        here = frame[frame["row"] == name]
        if len(here):
            label = name + (" (held out)" if name in HELD_OUT else "")
            lines.append("| " + " | ".join([label] + _row_cells(here)) + " |")
            side.append("| " + " | ".join([label] + _side_cells(here)) + " |")
    lines += side
    lines += ["", "Rows (options of `simulate_phone` over the baseline's "
              f"`{json.dumps(BASELINE)}`; body sway's frequency 0.2-1 Hz per person):", ""]
    lines += [f"- `{name}`{' (held out)' if name in HELD_OUT else ''}: `{json.dumps(opts)}`"
              for name, opts in ROWS if name in rows]
    bad = frame[frame["error"] != ""]
    lines += ["", "Failures:" if len(bad) else "Failures: none."]
    lines += [f"- {r.row} person {r.person}: {r.error}" for r in bad.itertuples()]
    return lines


def worst_lines(frame: pd.DataFrame, rows, count: int = 3) -> list:
    """The phone's worst people per row: truth, plate and phone errors, the phone's interval and innovations."""
    lines = ["", "Worst phone records per row:", ""]
    for name in rows:
        ok = frame[(frame["row"] == name) & (frame["error"] == "")].copy()
        if not len(ok):
            continue
        ok["abs"] = ok["phone_f_h_error"].astype(float).abs()
        for r in ok.sort_values("abs", ascending=False).head(count).itertuples():
            lines.append(f"- {name} {r.person}: f_b {r.f_b:.2f}, f_h {r.f_h:.2f} Hz, xi_h {r.xi_h:.2f}; plate "
                         f"{100 * r.plate_f_h_error:+.1f} %, phone {100 * r.phone_f_h_error:+.1f} % ({r.phone_f_h_low:.2f}-"
                         f"{r.phone_f_h_high:.2f} Hz, {'determined' if r.phone_f_h_determined else 'not determined'}, "
                         f"{r.phone_variation}), kurtosis {r.phone_kurtosis:.1f}, LB p {r.phone_ljung_box_p:.2g}, reading "
                         f"error rms {r.reading_rms:.3f} m/s^2 (max {r.reading_max:.2f})")
    return lines


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--people", type=int, default=40, help="people per row (default 40)")
    parser.add_argument("--seed", type=int, default=4401, help="root seed (default 4401)")
    parser.add_argument("--jobs", type=int, default=1, help="processes (default 1)")
    parser.add_argument("--rows", default=",".join(r for r, _ in ROWS), help="comma-separated rows (default all)")
    parser.add_argument("--csv", type=Path, default=None,
                        help="default benchmarks/results/phone_phenomena_seed<S>.csv")
    parser.add_argument("--md", type=Path, default=None, help="also write the summary here (Markdown)")
    parser.add_argument("--resume", action="store_true", help="go on with an existing --csv")
    args = parser.parse_args(argv)
    rows = tuple(r.strip() for r in args.rows.split(",") if r.strip())
    unknown = [r for r in rows if r not in dict(ROWS)]
    if unknown:
        parser.error(f"unknown rows {unknown}")
    path = args.csv or REPO / "benchmarks" / "results" / f"phone_phenomena_seed{args.seed}.csv"
    done = open_csv(path, args.resume, COLUMNS, CSV_KEYS)
    tasks = [(args.seed, name, k) for name in rows for k in range(args.people) if (args.seed, name, k) not in done]
    print(f"{len(tasks)} people to fit ({len(done)} in {path}), {args.jobs} process(es)", file=sys.stderr)
    started = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        futures = [pool.submit(run_person, task) for task in tasks]
        for i, future in enumerate(as_completed(futures), start=1):
            out = future.result()
            append_row(path, out, COLUMNS)
            phone = f"{100 * out['phone_f_h_error']:+.1f} %" if out["phone_f_h_error"] != "" else "-"
            print(f"[{i}/{len(tasks)} {time.perf_counter() - started:.0f} s] {out['row']} {out['person']}: phone "
                  f"{phone} {out['seconds']} s {out['error']}", file=sys.stderr, flush=True)
    frame = load(path, args.seed, rows, args.people)
    command = "python benchmarks/phone_phenomena.py " + shlex.join(sys.argv[1:] if argv is None else argv)
    text = [f"`{command}`: seed {args.seed}, {args.people} people per row, rows from {path.name}; "
            f"{(time.perf_counter() - started) / 60:.1f} min this call", ""]
    text += summary_lines(frame, rows) + worst_lines(frame, rows)
    print("\n".join(text))
    if args.md:
        args.md.write_text("\n".join(text) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
