"""Scale benchmark: how the particle filter's cost grows with cycles, particles and harmonics; processes; memory.

Everything runs the library as a user would (``preprocess`` then
``CycleRunner``, or one estimator pass) on simulated records::

    python benchmarks/scale.py                      # the sweeps, the 1-vs-2-process run, the figure
    python benchmarks/scale.py --study 6800         # also a study of 6800 cycles streamed to CSV: time, peak RSS

Sweeps (one process): cycles (records of about 5-40 valid cycles, the
runner's repeated passes), particles (one pass over one cycle, N = 500 to
50000) and harmonics (one pass, N = 5000, n = 1 to 8: 7 to 21 states).
Processes: the same record identified with ``--jobs 1`` and 2
(``ProcessPoolExecutor``); the tables are checked equal. The study runs
records one after another through :meth:`CycleRunner.run_many` with two
processes and ``keep_results=False``, and reports the peak resident memory
of the main process and of the largest worker.

Writes ``docs/figures/scale.png`` and prints markdown tables, with the load
average before and after (the machine may be shared).
"""

from __future__ import annotations

import argparse
import os
import resource
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from smd_statespace.estimators import cycle_data, get_estimator
from smd_statespace.model import SMDModel
from smd_statespace.identify.runner import CycleRunner
from smd_statespace.signals import preprocess
from smd_statespace.simulation import simulate_bouncing

F_B = 2.2
MARGIN = 2.0  # preprocess's edge margin (s) at each end


def record_with(cycles: int, seed: int = 0):
    """A simulated, preprocessed record with about ``cycles`` valid cycles."""
    duration = 2 * MARGIN + (cycles + 1) / F_B
    return preprocess(simulate_bouncing(mass=64.0, f_b=F_B, f_h=2.6, xi_h=0.35, duration=duration, seed=seed).record)


def particle_steps(runner, table, n):
    """Particle-steps the runner did: passes x samples x particles, summed over cycles."""
    lengths = {c.index: len(cycle_data(runner.model, runner.preprocessed_, c)) for c in runner.preprocessed_.valid_cycles}
    ok = table[table.status == "ok"]
    return int(sum(lengths[c] * p for c, p in zip(ok.cycle, ok.passes))) * n


def sweep_cycles(n, max_passes):
    rows = []
    for cycles in (5, 10, 20, 40):
        record = record_with(cycles)
        runner = CycleRunner(estimator="pf", n_particles=n, max_passes=max_passes, progress=False, seed=1,
                             keep_results=False)
        started = time.perf_counter()
        table = runner.run(record)
        seconds = time.perf_counter() - started
        steps = particle_steps(runner, table, n)
        rows.append(dict(cycles=int((table.status == "ok").sum()), seconds=seconds,
                         passes=float(table[table.status == "ok"].passes.mean()), ns=seconds / steps * 1e9))
    return rows


def one_pass_seconds(model, data, n, repeats=3):
    pf = get_estimator("pf", n_particles=n)
    pf.run(model, data, rng=np.random.default_rng(0))
    times = []
    for seed in range(repeats):
        started = time.perf_counter()
        pf.run(model, data, rng=np.random.default_rng(seed))
        times.append(time.perf_counter() - started)
    return min(times)


def sweep_particles():
    record = record_with(5)
    model = SMDModel()
    data = cycle_data(model, record, record.valid_cycles[2])
    rows = []
    for n in (500, 1000, 2000, 5000, 10000, 20000, 50000):
        seconds = one_pass_seconds(model, data, n)
        rows.append(dict(n=n, seconds=seconds, ns=seconds / (n * len(data)) * 1e9))
    return rows


def sweep_harmonics(n):
    record = record_with(5)
    rows = []
    for harmonics in (1, 2, 4, 6, 8):
        model = SMDModel(n_harmonics=harmonics)
        data = cycle_data(model, record, record.valid_cycles[2])
        seconds = one_pass_seconds(model, data, n)
        rows.append(dict(harmonics=harmonics, states=model.n_state, seconds=seconds,
                         ns=seconds / (n * len(data)) * 1e9))
    return rows


def processes(n, max_passes, cycles=40):
    record = record_with(cycles, seed=3)
    options = dict(estimator="pf", n_particles=n, max_passes=max_passes, progress=False, seed=2, keep_results=False)
    rows, tables = [], []
    for jobs in (1, 2):
        started = time.perf_counter()
        if jobs == 1:
            table = CycleRunner(**options).run(record)
        else:
            with ProcessPoolExecutor(max_workers=jobs) as pool:
                pool.submit(int, 0).result()  # workers up before the clock matters little; counted anyway
                table = CycleRunner(executor=pool, **options).run(record)
        seconds = time.perf_counter() - started
        tables.append(table.drop(columns="seconds"))
        rows.append(dict(jobs=jobs, cycles=int((table.status == "ok").sum()), seconds=seconds))
    same = tables[0].equals(tables[1])
    for row in rows:
        row["speedup"] = rows[0]["seconds"] / row["seconds"]
    return rows, same


def study(cycles, n, max_passes, jobs):
    """A study of ``cycles`` cycles streamed to a CSV; wall time and peak RSS (main process, largest worker)."""
    template = record_with(40, seed=5)
    per_record = len(template.valid_cycles)  # 39 of the 40 requested lie inside the edge margins
    records = max(1, -(-cycles // per_record))  # at least ``cycles`` cycles in all
    options = dict(estimator="pf", n_particles=n, max_passes=max_passes, progress=False, seed=4, keep_results=False)
    with tempfile.TemporaryDirectory() as folder, ProcessPoolExecutor(max_workers=jobs) as pool:
        path = os.path.join(folder, "study.csv")
        started = time.perf_counter()
        CycleRunner(executor=pool, **options).run_many((template for _ in range(records)), path)
        seconds = time.perf_counter() - started
        size = os.path.getsize(path)
        import pandas as pd

        status = pd.read_csv(path, usecols=["status"]).status
        rows = int((status == "ok").sum())
        failed = int((status == "failed").sum())
        worker_peaks = list(pool.map(_peak_rss_mb, range(jobs)))
    return dict(records=records, per_record=per_record, rows=rows, failed=failed, seconds=seconds, csv_mb=size / 1e6,
                main_mb=_peak_rss_mb(), worker_mb=max(worker_peaks), n=n, max_passes=max_passes, jobs=jobs)


def _peak_rss_mb(_=None):
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def figure(cycles, particles, harmonics, procs, path, note=""):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(10, 7.5))
    ax = axes[0, 0]
    ax.plot([r["cycles"] for r in cycles], [r["seconds"] for r in cycles], "o-")
    ax.set(xlabel="cycles identified", ylabel="wall time (s)", title="(a) cost vs cycles (N = 5000, up to 5 passes)")
    ax.grid(alpha=0.3)
    ax = axes[0, 1]
    ax.loglog([r["n"] for r in particles], [r["seconds"] for r in particles], "o-", label="one pass (s)")
    ax.set(xlabel="particles N", ylabel="seconds per pass", title="(b) cost vs particles (one pass, 13 states)")
    twin = ax.twinx()
    twin.semilogx([r["n"] for r in particles], [r["ns"] for r in particles], "s--", color="C1",
                  label="ns per particle-step")
    twin.set_ylabel("ns per particle-step", color="C1")
    twin.set_ylim(0, max(r["ns"] for r in particles) * 1.3)
    ax.grid(alpha=0.3, which="both")
    ax = axes[1, 0]
    ax.plot([r["states"] for r in harmonics], [r["ns"] for r in harmonics], "o-")
    for r in harmonics:
        ax.annotate(f"n={r['harmonics']}", (r["states"], r["ns"]), textcoords="offset points", xytext=(4, -12))
    ax.set(xlabel="states (5 + 2 n harmonics)", ylabel="ns per particle-step", ylim=(0, None),
           title="(c) cost vs harmonics (one pass, N = 5000)")
    ax.grid(alpha=0.3)
    ax = axes[1, 1]
    bars = ax.bar([str(r["jobs"]) for r in procs], [r["speedup"] for r in procs], color=["C0", "C2"])
    for bar, r in zip(bars, procs):
        ax.text(bar.get_x() + bar.get_width() / 2, bar.get_height(), f"{r['speedup']:.2f}x\n{r['seconds']:.1f} s",
                ha="center", va="bottom")
    ax.axhline(2.0, color="grey", ls=":", lw=1)
    ax.set(xlabel="processes", ylabel="speed-up over 1 process", ylim=(0, 2.5),
           title=f"(d) parallel speed-up ({procs[0]['cycles']} cycles)")
    if note:
        fig.suptitle(note, fontsize=9, color="dimgrey")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--particles", type=int, default=5000)
    parser.add_argument("--max-passes", type=int, default=5)
    parser.add_argument("--study", type=int, default=0, metavar="CYCLES", help="also run a study of CYCLES cycles")
    parser.add_argument("--study-particles", type=int, default=5000)
    parser.add_argument("--figure", default=os.path.join(os.path.dirname(__file__), "..", "docs", "figures",
                                                         "scale.png"))
    parser.add_argument("--skip-sweeps", action="store_true", help="only the study")
    args = parser.parse_args(argv)
    load_before = os.getloadavg()
    started = time.perf_counter()
    get_estimator("pf", n_particles=10).run(SMDModel(), cycle_data(SMDModel(), record_with(5), record_with(5).valid_cycles[0]))
    lines = []
    if not args.skip_sweeps:
        cycles = sweep_cycles(args.particles, args.max_passes)
        particles = sweep_particles()
        harmonics = sweep_harmonics(args.particles)
        procs, same = processes(args.particles, args.max_passes)
        load = os.getloadavg()
        figure(cycles, particles, harmonics, procs, args.figure,
               note=f"one core per process, 2-core machine; load average (1, 5, 15 min) before "
                    f"{', '.join(f'{v:.2f}' for v in load_before)}, after {', '.join(f'{v:.2f}' for v in load)}")
        lines += ["| cycles | mean passes | wall (s) | ns / particle-step |", "|---|---|---|---|"]
        lines += [f"| {r['cycles']} | {r['passes']:.1f} | {r['seconds']:.2f} | {r['ns']:.0f} |" for r in cycles]
        lines += ["", "| particles | s / pass | ns / particle-step |", "|---|---|---|"]
        lines += [f"| {r['n']} | {r['seconds']:.4f} | {r['ns']:.0f} |" for r in particles]
        lines += ["", "| harmonics | states | s / pass | ns / particle-step |", "|---|---|---|---|"]
        lines += [f"| {r['harmonics']} | {r['states']} | {r['seconds']:.4f} | {r['ns']:.0f} |" for r in harmonics]
        lines += ["", "| processes | cycles | wall (s) | speed-up |", "|---|---|---|---|"]
        lines += [f"| {r['jobs']} | {r['cycles']} | {r['seconds']:.2f} | {r['speedup']:.2f}x |" for r in procs]
        lines.append(f"\nTables at 1 and 2 processes identical: {same}.")
    if args.study:
        s = study(args.study, args.study_particles, args.max_passes, 2)
        lines += ["", f"Study: {s['rows']} cycles identified, {s['failed']} failed ({s['records']} records of one "
                  f"simulated person, {s['per_record']} valid cycles each), "
                  f"N = {s['n']}, up to {s['max_passes']} passes, {s['jobs']} processes, streamed to CSV "
                  f"({s['csv_mb']:.1f} MB): {s['seconds']:.0f} s wall; peak RSS main process {s['main_mb']:.0f} MB, "
                  f"largest worker {s['worker_mb']:.0f} MB."]
    load_after = os.getloadavg()
    lines.insert(0, f"Load average (1, 5, 15 min) before: {', '.join(f'{v:.2f}' for v in load_before)}; after: "
                    f"{', '.join(f'{v:.2f}' for v in load_after)}; {os.cpu_count()} CPUs; "
                    f"run took {time.perf_counter() - started:.0f} s.\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
