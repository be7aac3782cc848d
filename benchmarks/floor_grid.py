"""Does the floor mode's trial grid, computed coarse to fine, start the search where the whole grid does (issue 46)?

An estimated floor mode (``floor_mode:source=modal``, the candidate ``diagnose`` tries on a record without
``floor_acc``) starts its search from the best of about 232 trial frequencies, 1 % apart over 2-20 Hz, each one
likelihood of the person's model with the floor: about 1.7 s of a clean 30 s record's 3 s floor fit, the longest
of ``diagnose``'s candidates. :func:`~smd_statespace.person.extend.grid_best` computes the likelihood at every
other frequency first and then around the best of those. This script computes every trial's likelihood on
simulated records (``benchmarks/person_effects.py``'s people: clean ones and people on a floor mode, not
measured; the ``jumps`` and ``smooth`` generators) and reports, per record, whether the coarse-to-fine choice is
the whole grid's, how many likelihoods it took, and what a miss costs in log-likelihood::

    OPENBLAS_NUM_THREADS=1 python benchmarks/floor_grid.py --records 8 --seed 92 --jobs 2 \\
        --out benchmarks/results/floor_grid_seed92.md
"""

from __future__ import annotations

import os

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")
os.environ.setdefault("SMD_STATESPACE_THREADS", "1")

import dataclasses  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from accuracy import markdown_report, markdown_table  # noqa: E402  (benchmarks/, the script's own folder)
import person_effects  # noqa: E402

FLOOR = "floor_mode:source=modal"


def one(task) -> dict:
    """Every trial start's log-likelihood on one record and the coarse-to-fine choice; never raises."""
    from smd_statespace.person import identify_person
    from smd_statespace.person.effect_adapter import record_grid_start, record_starts
    from smd_statespace.person.extend import configured_for_record, effect_model
    from smd_statespace.person.starts import grid_best
    from smd_statespace.simulation import simulate_bouncing

    kind, size, generator, index, person, sim_seed, effects = task
    row = {"kind": kind, "size": size, "generator": generator, "index": index}
    try:
        sim = simulate_bouncing(noise=person_effects.NOISE, effects=effects,
                                **person_effects.simulation_settings(person, sim_seed, generator))
        base = identify_person(dataclasses.replace(sim.record, floor_acc=None), measured_floor=False)
    except Exception as exc:  # a record refused (contact lost) is reported, not fatal
        return {**row, "error": " ".join(str(exc).split())[:120]}
    effect = configured_for_record(FLOOR, base)
    model = effect_model(base, [effect])
    default = model.start_params(base.f_h, base.xi_h)
    low, high = np.asarray(model.bounds).T
    named = base.model.unpack(base.params)
    starts = [np.clip([{**named, **trial}.get(name, value) for name, value in zip(model.param_names, default)],
                      low, high) for trial in record_starts(effect, base)]
    moment = time.perf_counter()
    every = np.array([model.loglike(p) for p in starts])
    whole_seconds = time.perf_counter() - moment
    computed = []

    def counted(i):
        computed.append(i)
        return every[i]

    moment = time.perf_counter()
    grid_best(lambda i: model.loglike(starts[i]), range(len(starts)), record_grid_start(effect))
    coarse_seconds = time.perf_counter() - moment
    chosen = grid_best(counted, range(len(starts)), record_grid_start(effect))
    best = int(np.argmax(every))
    return {**row, "trials": len(starts), "computed": len(computed), "same": chosen == best,
            "f_f_whole": float(starts[best][model.position("f_f")]),
            "f_f_chosen": float(starts[chosen][model.position("f_f")]),
            "loss": float(every[best] - every[chosen]), "gain_over_median": float(every[best] - np.median(every)),
            "whole_s": whole_seconds, "coarse_to_fine_s": coarse_seconds}


def main(argv=None) -> None:
    args, rows, started = person_effects.study_of_tasks(__doc__.split("\n\n")[0], ("clean", "floor_unmeasured"),
                                                        one, argv)
    done = rows[rows["trials"].notna()] if "trials" in rows else rows.iloc[:0]
    summary = (done.groupby(["generator", "kind", "size"])
               .agg(records=("same", "size"), same=("same", "sum"), computed=("computed", "mean"),
                    trials=("trials", "mean"), worst_loss=("loss", "max"), whole_s=("whole_s", "median"),
                    coarse_to_fine_s=("coarse_to_fine_s", "median")))
    markdown_report(f"The floor mode's trial grid, coarse to fine (seed {args.seed}, {args.records} records a row)",
                    "floor_grid.py", argv, started,
                    [f"The whole grid's choice on {int(done['same'].sum())} of {len(done)} records, with "
                     f"{done['computed'].mean():.0f} likelihoods instead of {done['trials'].mean():.0f} "
                     f"({done['coarse_to_fine_s'].sum():.1f} s against {done['whole_s'].sum():.1f} s, one thread a "
                     f"record); {len(rows) - len(done)} records refused.", "",
                     markdown_table(summary.reset_index().round(3)), "", markdown_table(rows.round(4))], args.out)


if __name__ == "__main__":
    main()
