"""Speed of a crowd on a structure (issue 48): 1000 people on a 5-mode beam, 60 s at 200 Hz; Monte Carlo draws.

Times, on one core unless said, each the best of ``--repeats`` runs:

- the crowd's forces: every active person's force cycles and exact rigid-floor GRF
  (:func:`smd_statespace.structure.draw_occupants`, the crowd generator's engine);
- the coupled solution: the occupied modes (Newton on ``det D(s) = 0``) and the
  coupled and force-only time histories (frequency domain,
  :func:`smd_statespace.structure.analyse_structure`);
- Monte Carlo: ``--draws`` crowds of ``--mc-people`` people (30 s) on ``--jobs``
  processes, and the same table serially (identical: checked).

::

    python benchmarks/structure_speed.py                       # about 1-2 min
    python benchmarks/structure_speed.py --draws 200 --jobs 2   # the issue's 200 draws
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor

from smd_statespace.structure import CrowdDraws, analyse_structure, beam, draw_occupants, monte_carlo


def best(function, repeats):
    """``(best wall-clock seconds, last result)`` of ``function()`` over ``repeats`` runs."""
    times, result = [], None
    for _ in range(repeats):
        started = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - started)
    return min(times), result


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--people", type=int, default=1000)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--draws", type=int, default=20)
    parser.add_argument("--mc-people", type=int, default=200)
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args(argv)
    model = beam(f1_hz=3.0, n_modes=5)  # 3, 12, 27, 48, 75 Hz: all below 100 Hz
    print(f"{model.name}, {model.n_modes} modes; {args.people} people, 60 s at 200 Hz")
    for share in (0.5, 1.0):
        seconds, occupants = best(lambda: draw_occupants(model, args.people, share, duration=60.0, seed=1),
                                  args.repeats)
        solved, result = best(lambda: analyse_structure(model, occupants), args.repeats)
        print(f"active share {share:g} ({int(occupants.active.sum())} bouncing): forces {seconds:.2f} s, "
              f"coupled + force-only solution {solved:.2f} s ({result.solution.padded} padded samples), "
              f"total {seconds + solved:.2f} s")
    spec = CrowdDraws(model, args.mc_people, active_share=0.5, duration=30.0)
    serial_seconds, serial = best(lambda: monte_carlo(spec, args.draws, seed=7), 1)
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        parallel_seconds, parallel = best(lambda: monte_carlo(spec, args.draws, seed=7, executor=pool), 1)
    same = serial.equals(parallel)
    print(f"Monte Carlo, {args.draws} draws of {args.mc_people} people (30 s): {serial_seconds:.1f} s serially, "
          f"{parallel_seconds:.1f} s on {args.jobs} processes ({parallel_seconds / args.draws:.2f} s per draw; "
          f"200 draws ~ {200 * parallel_seconds / args.draws / 60:.1f} min); tables identical: {same}")


if __name__ == "__main__":
    main()
