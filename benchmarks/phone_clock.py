"""Were a phone's samples taken at their stamps or on its regular clock? How often ``resample_uniform`` tells right.

A phone's time stamps scatter about its clock for one of two reasons: the sensor sampled at scattered instants
and stamped them truly (``simulate_phone(jitter=...)``), or it sampled on its clock and each stamp came late or
early (``simulate_phone(stamp_jitter=..., jitter=0)``). :func:`~smd_statespace.accelerometer.resample_uniform`
chooses between the two by which predicts each sample from its neighbours better
(:data:`~smd_statespace.accelerometer.resampling.CLOCK_MARGIN`). For each record this script reports the choice,
whether it was right, the rate's error and the reading's error: the values on the grid against the three axes at
the true sampling instants (m/s^2 rms, the first and last second left out), with the choice and, for comparison,
read at the stamps.

Usage::

    python benchmarks/phone_clock.py --records 3 --out /tmp/phone_clock.md

Rows (``--rows``, default all of :data:`ROWS`): ``simulate_phone``'s options over a 30 s bounce of 70 kg at
``f_b`` 2.2 Hz (``f_h`` 2.9 Hz, ``xi_h`` 0.3), the phone's defaults otherwise (200 Hz, 0.3 ms of sampling jitter,
0.5 % dropped). Seeds: ``SeedSequence(--seed)`` spawned per (row, record), the simulator's seed the first word of
each record's state.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import pandas as pd

from accuracy import markdown_report, markdown_table  # beside this script
from smd_statespace.accelerometer import resample_uniform
from smd_statespace.simulation.phone import simulate_phone

ROWS = {
    "sampled_jitter_0.3ms": ({}, "stamps"),
    "sampled_jitter_1ms": ({"jitter": 1e-3}, "stamps"),
    "sampled_jitter_1ms_drop3": ({"jitter": 1e-3, "drop": 0.03}, "stamps"),
    "sampled_0.3ms_400_no_filter": ({"anti_alias": False, "fs": 400.0}, "stamps"),
    "stamps_0.3ms": ({"stamp_jitter": 3e-4, "jitter": 0.0}, "regular clock"),
    "stamps_1ms": ({"stamp_jitter": 1e-3, "jitter": 0.0}, "regular clock"),
    "stamps_1ms_sampled_0.3ms": ({"stamp_jitter": 1e-3}, "regular clock"),
    "stamps_1ms_drop3": ({"stamp_jitter": 1e-3, "jitter": 0.0, "drop": 0.03}, "regular clock"),
    "stamps_1ms_gaps": ({"stamp_jitter": 1e-3, "jitter": 0.0, "gaps": (4, 0.25)}, "regular clock"),
    "stamps_0.5ms_400": ({"stamp_jitter": 5e-4, "jitter": 0.0, "fs": 400.0}, "regular clock"),
    "stamps_2ms_100": ({"stamp_jitter": 2e-3, "jitter": 0.0, "fs": 100.0}, "regular clock"),
    "stamps_2ms_100_drop3": ({"stamp_jitter": 2e-3, "jitter": 0.0, "fs": 100.0, "drop": 0.03}, "regular clock"),
    "stamps_1ms_400": ({"stamp_jitter": 1e-3, "jitter": 0.0, "fs": 400.0}, "stamps"),
}
"""Row name: (``simulate_phone`` options, the reading expected, ``info["samples_at"]``). Stamps scattered by 1 ms at
400 Hz (0.4 of an interval) cannot be numbered on a regular clock
(:data:`~smd_statespace.accelerometer.resampling.REGULAR_SCATTER`): they are read at the stamps."""


def on_grid(grid, times, acc) -> np.ndarray:
    """The axes ``acc`` (T, k), taken at ``times`` (s, in any order), linearly interpolated onto ``grid``."""
    order = np.argsort(times, kind="stable")
    return np.column_stack([np.interp(grid, times[order], acc[order, k]) for k in range(acc.shape[1])])


def reading_error(grid, values, instants, acc) -> float:
    """RMS (m/s^2) of ``values`` on ``grid`` against the three axes ``acc`` interpolated at their true ``instants``,
    the first and last second left out."""
    exact = on_grid(grid, instants, acc)
    inside = (grid > grid[0] + 1.0) & (grid < grid[-1] - 1.0)
    return float(np.sqrt(np.mean((values - exact)[inside] ** 2)))


def run_record(row: str, seed: np.random.SeedSequence) -> dict:
    """One phone record of ``row``: the clock's choice and the reading's errors."""
    options, right = ROWS[row]
    phone = simulate_phone(mass=70.0, f_b=2.2, f_h=2.9, xi_h=0.3, duration=30.0,
                           seed=int(seed.generate_state(1)[0]), **options)
    instants = phone.instants if phone.instants is not None else phone.time
    grid, values, info = resample_uniform(phone.time, phone.acc)
    at_stamps = on_grid(grid, phone.time, phone.acc)  # read at the stamps, for comparison
    return {"row": row, "right": right, "chosen": info["samples_at"],
            "rate_error": info["fs_nominal"] / phone.truth["phone"]["fs"] - 1.0,
            "error": reading_error(grid, values, instants, phone.acc),
            "error_at_stamps": reading_error(grid, at_stamps, instants, phone.acc)}


def summary(frame: pd.DataFrame) -> pd.DataFrame:
    """One line per row: the choices right, the largest rate error, the reading's errors (median, worst)."""
    def spread(values) -> str:
        return f"{values.median():.4f} / {values.max():.4f}"

    lines = []
    for row, group in frame.groupby("row", sort=False):
        lines.append({"row": row, "read at (expected)": group.right.iloc[0],
                      "chosen right": f"{int((group.chosen == group.right).sum())}/{len(group)}",
                      "largest \\|rate error\\|": float(group.rate_error.abs().max()),
                      "reading error m/s^2, median / worst": spread(group.error),
                      "read at the stamps": spread(group.error_at_stamps)})
    return pd.DataFrame(lines)


def parse_args(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=3, help="records per row (default 3)")
    parser.add_argument("--seed", type=int, default=4490, help="root seed (default 4490)")
    parser.add_argument("--rows", default=",".join(ROWS), help="comma-separated rows (default all)")
    parser.add_argument("--out", help="also write the report here (Markdown)")
    args = parser.parse_args(argv)
    rows = [row.strip() for row in args.rows.split(",") if row.strip()]
    unknown = [row for row in rows if row not in ROWS]
    if unknown:
        parser.error(f"--rows: unknown row {unknown[0]!r}; valid: {', '.join(ROWS)}")
    if args.records < 1:
        parser.error(f"--records {args.records}: give at least 1")
    return args, rows


def main(argv=None):
    args, rows = parse_args(argv)
    started = time.perf_counter()
    seeds = np.random.SeedSequence(args.seed).spawn(len(ROWS))
    records = [run_record(row, seed) for row in rows
               for seed in seeds[list(ROWS).index(row)].spawn(args.records)]
    frame = pd.DataFrame(records)
    body = [markdown_table(summary(frame), {"largest \\|rate error\\|": ".1e"}), "",
            f"Chosen right on {int((frame.chosen == frame.right).sum())} of {len(frame)} records."]
    markdown_report("How a phone's samples are put on its clock", "phone_clock.py", argv, started, body, args.out)


if __name__ == "__main__":
    main()
