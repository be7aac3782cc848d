"""How often ``identify`` says "the person changes during the record" of a person who does not change.

``identify_person`` (its defaults) fits the person, then asks whether one person explains the whole record: the
halves' test (:func:`~smd_statespace.person.change.change_test`) and eight score tests of ``f_h`` or ``xi_h``
drifting or stepping (:func:`~smd_statespace.person.screen.time_change`, Holm at
:data:`~smd_statespace.person.screen.CHANGE_ALPHA` = 0.01 over the eight). Here every person is stationary
(``simulate_bouncing``: 30 s at 100 Hz, 1 % BW noise, one ``f_b``, ``f_h``, ``xi_h`` per row, a fresh simulator
seed per record), so every "changes" is a false alarm. For each score test the record's cycle-clustered statistic
is also recomputed with a Newey-West (Bartlett, 2 lags) variance of the cycles' scores, and the lag-1
autocorrelation of those scores is reported: were neighbouring cycles' scores correlated, the clustered variance
would understate the sum's and the tests would fire too often.

Usage::

    python benchmarks/change_false_alarms.py --records 40 --jobs 2 --out /tmp/change_false_alarms.md

Rows (``--rows``): ``generator:f_b`` pairs, default ``jumps:2.2,jumps:2.7,smooth:2.2``; ``f_h`` 2.9 Hz, ``xi_h``
0.3, mass 70 kg, the force's default load factors. Seeds: ``SeedSequence(--seed)`` spawned per (row, record).
"""

from __future__ import annotations

import os

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")
os.environ.setdefault("SMD_STATESPACE_THREADS", "1")  # the processes keep the cores busy

import argparse  # noqa: E402
import time  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from scipy import stats  # noqa: E402

from accuracy import markdown_report, markdown_table  # noqa: E402  (beside this script)
from smd_statespace.effects.generic import label  # noqa: E402
from smd_statespace.person import identify_person  # noqa: E402
from smd_statespace.person.screen import CHANGE_ALPHA, TIME_KINDS, generic_library, holm, score_tests  # noqa: E402
from smd_statespace.simulation import simulate_bouncing  # noqa: E402

F_H, XI_H, MASS = 2.9, 0.3, 70.0
NEWEY_WEST_LAGS = 2


def newey_west(cycle_scores, lags: int = NEWEY_WEST_LAGS) -> float:
    """The variance of the sum of ``cycle_scores`` (centred) with Bartlett-weighted autocovariances up to ``lags``,
    scaled ``J / (J - 1)`` as the library's clustered variance is."""
    x = np.asarray(cycle_scores, dtype=float)
    x = x - x.mean()
    variance = float(x @ x)
    for lag in range(1, lags + 1):
        variance += 2.0 * (1.0 - lag / (lags + 1.0)) * float(x[lag:] @ x[:-lag])
    return variance * x.size / max(x.size - 1, 1)


def one(task) -> dict:
    """One stationary person identified; what the change tests said. Never raises."""
    generator, f_b, index, seed = task
    row = {"generator": generator, "f_b": f_b, "record": index}
    try:
        sim = simulate_bouncing(mass=MASS, f_b=f_b, f_h=F_H, xi_h=XI_H, duration=30.0, fs=100.0, noise=0.01,
                                seed=seed, variation=generator)
        result = identify_person(sim.record)
        library = generic_library(result, TIME_KINDS)
        tests = score_tests(result, library)
    except Exception as exc:  # noqa: BLE001 - one record must never kill the study
        return {**row, "error": f"{type(exc).__name__}: {str(exc).splitlines()[0][:120]}"}
    change = result.change or {}
    p_robust = np.array([test["p_robust"] for test in tests])
    p_nw = np.array([stats.chi2.sf(test["cycle_scores"].sum() ** 2 / newey_west(test["cycle_scores"]), 1)
                     for test in tests])
    lag_one = [float(np.corrcoef(test["cycle_scores"][1:], test["cycle_scores"][:-1])[0, 1]) for test in tests]
    smallest = int(np.argmin(p_robust))
    return {**row, "error": "", "f_h_estimate": result.f_h, "changed": ",".join(change.get("changed", [])),
            "by_halves": ",".join(change.get("by_halves", [])),
            "by_time": ",".join((change.get("time") or {}).get("changed", [])),
            "smallest_term": label(library[smallest]), "p_smallest": float(p_robust[smallest]),
            "p_holm": float(holm(p_robust).min()), "p_holm_newey_west": float(holm(p_nw).min()),
            "lag_one_autocorrelation": float(np.mean(lag_one))}


def tasks(rows, records: int, seed: int) -> list:
    out = []
    for r, (generator, f_b) in enumerate(rows):
        for index in range(records):
            child = np.random.SeedSequence(seed, spawn_key=(r, index))
            out.append((generator, f_b, index, int(child.generate_state(1)[0])))
    return out


def summary(frame: pd.DataFrame) -> list:
    table = []
    for (generator, f_b), rows in frame.groupby(["generator", "f_b"], sort=False):
        ok = rows[rows["error"] == ""]
        n = len(ok)
        table.append({"generator": generator, "f_b (Hz)": f_b, "records (failed)": f"{n} ({len(rows) - n})",
                      "said to change": f"{int((ok['changed'] != '').sum())}/{n}",
                      "by the halves": f"{int((ok['by_halves'] != '').sum())}/{n}",
                      "by the score tests": f"{int((ok['by_time'] != '').sum())}/{n}",
                      "the same with a Newey-West variance":
                          f"{int((ok['p_holm_newey_west'] < CHANGE_ALPHA).sum())}/{n}",
                      "cycles' scores, lag-1 correlation (mean)": f"{ok['lag_one_autocorrelation'].mean():+.3f}",
                      "smallest p (Holm) of the record": ", ".join(f"{p:.2g}" for p in sorted(ok["p_holm"])[:3])})
    lines = [markdown_table(pd.DataFrame(table)), ""]
    alarms = frame[(frame["error"] == "") & (frame["changed"] != "")]
    for _, r in alarms.iterrows():
        lines.append(f"- {r['generator']} f_b {r['f_b']} record {r['record']}: `{r['changed']}` said to change "
                     f"({r['smallest_term']}, p {r['p_smallest']:.2g}, Holm {r['p_holm']:.2g}); "
                     f"f_h {r['f_h_estimate']:.3f} (truth {F_H})")
    for _, r in frame[frame["error"] != ""].iterrows():
        lines.append(f"- failed: {r['generator']} f_b {r['f_b']} record {r['record']}: {r['error']}")
    return lines


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=40, help="stationary people per row (default 40)")
    parser.add_argument("--rows", default="jumps:2.2,jumps:2.7,smooth:2.2",
                        help="generator:f_b pairs (default jumps:2.2,jumps:2.7,smooth:2.2)")
    parser.add_argument("--seed", type=int, default=5150, help="root of the SeedSequence (default 5150)")
    parser.add_argument("--jobs", type=int, default=1, help="processes (default 1)")
    parser.add_argument("--out", help="also write the report here (markdown)")
    args = parser.parse_args(argv)
    rows = [(item.split(":")[0], float(item.split(":")[1])) for item in args.rows.split(",")]
    started = time.perf_counter()
    with ProcessPoolExecutor(args.jobs) as pool:
        frame = pd.DataFrame(list(pool.map(one, tasks(rows, args.records, args.seed))))
    body = [f"Stationary people ({F_H} Hz, xi_h {XI_H}, {MASS:g} kg), 30 s at 100 Hz, 1 % BW noise: every "
            "\"the person changes\" is a false alarm (the level of the score tests: 1 %, Holm over 8).", "",
            *summary(frame)]
    markdown_report("False alarms of \"the person changes\"", "change_false_alarms.py", argv, started, body, args.out)


if __name__ == "__main__":
    main()
