"""Does a nonlinear generic term's search stall where it starts, as a hardening spring's did? ``fit_effects`` (the term
started at zero from the fit without it) against a search started at zero from the model's default variances, each
start about its own predicted path (``starts.own_path``), on ``person_effects.py``'s large terms.

A hardening spring's search stalled at zero when started from the fit without it (docs/effects.md); this checks
whether the library's other nonlinear terms need the same second origin. One JSON line per record::

    OPENBLAS_NUM_THREADS=1 python benchmarks/nonlinear_origins.py term_v_abs_v,term_abs_u > origins.jsonl

Measured on 2026-12-01 (seed 92, 8 records a kind and generator, ``benchmarks/results/nonlinear_origins_seed92.jsonl``):
the same optimum from both origins on 31 of 32 (log-likelihoods within 2.7, ``f_h`` within 0.04 Hz); on the 32nd
(``v_abs_v``, ``smooth``) the default origin ran to ``f_h`` 0.51 Hz for 1.6 more. No second origin for them.
"""
import json
import sys
import time
from pathlib import Path

from concurrent.futures import ProcessPoolExecutor

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import person_effects as pe  # noqa: E402  (benchmarks/, the script's own folder)
from smd_statespace.person import identify_person  # noqa: E402
from smd_statespace.person.extend import (_settle_path, configured_for_record, effect_model,  # noqa: E402
                                          fit_effects)
from smd_statespace.person.starts import own_path  # noqa: E402
from smd_statespace.person.search import fit_model  # noqa: E402
from smd_statespace.simulation import simulate_bouncing  # noqa: E402


def one(task) -> dict:
    """Both fits of one record of ``person_effects.tasks``; never raises (an error is a row)."""
    kind, size, gen, i, person, sim_seed, effects = task
    try:
        sim = simulate_bouncing(noise=pe.NOISE, effects=effects, **pe.simulation_settings(person, sim_seed, gen))
        base = identify_person(sim.record, measured_floor=False)
        spec = pe.FITTED[kind]
        t0 = time.time()
        now = fit_effects(base, [spec], timing=False)
        t1 = time.time()
        eff = configured_for_record(spec, base)
        model = effect_model(base, [eff])
        ll, m, s = own_path(model, model.start_params(base.f_h, base.xi_h))
        f = fit_model(m, s, quick=True)
        m2, f2, lin, settled = _settle_path(m, f, base.loglike)
        p = m2.unpack(f2["params"])
        name = pe.TRUE_PARAMETER[kind][0]
        return dict(kind=kind, size=size, gen=gen, i=i, f_h=person["f_h"], base=base.f_h, now=now.f_h,
                    now_ll=now.loglike, now_c=float(now.model.unpack(now.params)[name]), fresh=p["f_h"],
                    fresh_ll=f2["loglike"], fresh_c=p[name], base_ll=base.loglike, t_now=t1 - t0,
                    t_fresh=time.time() - t1,
                    swing=float(np.std(base.predicted_path()[:, 0])))
    except Exception as exc:  # noqa: BLE001 - one record must never kill the study
        return dict(kind=kind, size=size, gen=gen, i=i, error=str(exc)[:100])


if __name__ == "__main__":
    kinds = sys.argv[1].split(",")
    work = pe.tasks(8, 92, sizes=("large",), generators=("jumps", "smooth"), kinds=tuple(kinds))
    with ProcessPoolExecutor(2) as pool:
        for row in pool.map(one, work):
            print(json.dumps({k: (round(v, 3) if isinstance(v, float) else v) for k, v in row.items()}), flush=True)
