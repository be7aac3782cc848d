"""Cost of the exact gradient (:func:`smd_statespace.person.score.score`) against finite differences.

On a simulated 30 s record at 100 Hz, the record-level model with variation
"independent", a phase template and the offset regressor (9 parameters),
fastest of ``--repeats`` runs (one thread) of:

* ``model.system(params)`` alone, the compiled augmented pass alone, ``model.loglike`` (both and the GLS);
* the derivatives of the system arrays in ``f_h`` and ``xi_h`` (analytic through the discretisation, the
  default for linear dynamics, or central differences of ``system``), the sensitivity pass alone, and the whole
  :func:`score`;
* ``k + 1`` likelihood evaluations (L-BFGS-B's 2-point gradient) and ``2 k`` (a central gradient);
* once each: the numerical Hessian of :func:`~smd_statespace.person.search.information` (``2 k^2`` evaluations)
  and the per-cycle scores of the robust covariance (``_cluster_scores``: ``2 k`` evaluations), which
  :func:`score` gives (its expected information and its per-sample scores) from one pass.

Then (``--no-information`` skips it) the shipped sample record (``data/sample.csv``, 30 s) is identified with
variation "independent" (``identify_person``: about 10 s) and the standard errors of ``f_h`` and ``xi_h`` from
:func:`score`'s expected information, conditional on ``delta`` and with ``delta`` and ``sigma^2`` profiled out,
are compared with those of the observed information (``information(model, params, "oim")``).

Usage::

    OPENBLAS_NUM_THREADS=1 python benchmarks/person_score.py [--repeats 7] [--duration 30]

Runs in well under two minutes.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from smd_statespace.io import G  # noqa: E402
from smd_statespace.person import RecordModel, Regressor, estimate_timing  # noqa: E402
from smd_statespace.person import kalman  # noqa: E402
from smd_statespace.person.search import _cluster_scores, information  # noqa: E402
from smd_statespace.person.score import score, sensitivity_pass, system_derivatives  # noqa: E402
from smd_statespace.simulation import simulate_bouncing  # noqa: E402

TEMPLATE = np.array([0.0, -0.2, 0.1, 0.1, 0.05, 0.03, 0.0, 0.01, 0.0])
"""A force template (g) for the phase and rate errors (about the simulated person's)."""


def fastest(func, repeats):
    """Fastest wall-clock time (ms) of ``repeats`` calls."""
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        func()
        best = min(best, time.perf_counter() - start)
    return 1e3 * best


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--duration", type=float, default=30.0)
    parser.add_argument("--no-information", dest="information", action="store_false",
                        help="skip the comparison of the information matrices on the fitted sample record")
    args = parser.parse_args(argv)
    sim = simulate_bouncing(mass=70, f_b=2.2, f_h=2.8, xi_h=0.3, duration=args.duration, seed=3)
    record = sim.record
    y = record.force / record.mass - G
    timing = estimate_timing(record.time, record.force, 4, "template")
    offset = Regressor("offset", np.ones_like(y), "m/s^2", dynamic=False)
    model = RecordModel(record.time, y, timing, 4, "independent", regressors=(offset,), phase_template=TEMPLATE)
    params = model.start_params(2.75, 0.28, -2.5)
    k = params.size
    sys = model.system(params)
    fitted = model.filter(params)
    pass_args = sys.pass_arguments(model.y, model.n_coefficients)
    der = system_derivatives(model, params, sys)
    sens_args = pass_args + (fitted["delta"], der["dyn"], der["d_hx"], der["d_Phi"], der["d_Gam"],
                             der["d_offset"], der["d_X_tr"], der["d_y"], der["d_Qx"], der["d_D"], der["d_E"],
                             der["d_drift"], der["d_sphi"], der["d_sq"], der["d_sp0"])
    score(model, params)  # compile
    sensitivity_pass(*sens_args)
    print(f"load average {os.getloadavg()[0]:.2f}; {record.time.size} samples, {k} parameters "
          f"({', '.join(model.param_names)}), OPENBLAS_NUM_THREADS={os.environ['OPENBLAS_NUM_THREADS']}")
    rows = {
        "model.system": fastest(lambda: model.system(params), args.repeats),
        "augmented_pass": fastest(lambda: kalman.augmented_pass(*pass_args), args.repeats),
        "model.loglike": fastest(lambda: model.loglike(params), args.repeats),
        "system_derivatives (analytic)": fastest(lambda: system_derivatives(model, params, sys), args.repeats),
        "system_derivatives (difference)": fastest(
            lambda: system_derivatives(model, params, sys, method="difference"), args.repeats),
        "sensitivity_pass": fastest(lambda: sensitivity_pass(*sens_args), args.repeats),
        "score": fastest(lambda: score(model, params), args.repeats),
        "score (given filter)": fastest(lambda: score(model, params, fitted), args.repeats),
    }
    loglike = rows["model.loglike"]
    rows[f"{k + 1} x loglike (2-point gradient)"] = fastest(
        lambda: [model.loglike(params) for _ in range(k + 1)], max(2, args.repeats // 3))
    rows[f"{2 * k} x loglike (central gradient)"] = fastest(
        lambda: [model.loglike(params) for _ in range(2 * k)], max(2, args.repeats // 3))
    index = np.arange(k)
    steps = np.where(index < 2, 1e-4 * np.maximum(np.abs(params), 0.05), 1e-3 * model.scales)
    rows["_cluster_scores (robust)"] = fastest(lambda: _cluster_scores(model, params, index), 1)
    rows["information 'oim' (Hessian)"] = fastest(lambda: information(model, params, "oim"), 1)
    width = max(len(name) for name in rows)
    for name, ms in rows.items():
        print(f"{name:<{width}}  {ms:9.2f} ms  {ms / loglike:6.2f} loglikes")
    print(f"score / (k+1) loglike: {rows['score'] / rows[f'{k + 1} x loglike (2-point gradient)']:.2f}; "
          f"score / 2k loglike: {rows['score'] / rows[f'{2 * k} x loglike (central gradient)']:.2f}")
    print(f"load average after {os.getloadavg()[0]:.2f}")
    if args.information:
        compare_information()


def compare_information():
    """Standard errors of ``f_h``, ``xi_h``: :func:`score`'s expected information against the observed one."""
    from smd_statespace.io import read_record
    from smd_statespace.person import identify_person
    from smd_statespace.simulation import sample_path

    start = time.perf_counter()
    result = identify_person(read_record(sample_path(), 70.0), variation="independent", intervals="wald")
    model, params = result.model, result.params
    fitted = time.perf_counter()
    cov, free = information(model, params, "oim")
    hessian = time.perf_counter()
    out = score(model, params)
    done = time.perf_counter()
    index = np.flatnonzero(free)
    observed = np.sqrt(np.diag(cov)[index])
    print(f"\nsample.csv, variation independent, {params.size} parameters: fit {fitted - start:.1f} s, "
          f"observed information {1e3 * (hessian - fitted):.0f} ms, score {1e3 * (done - hessian):.0f} ms; "
          f"gradient at the fit: {np.array2string(out['gradient'], precision=3)}")
    print(f"se from the observed information: f_h {observed[0]:.4f} Hz, xi_h {observed[1]:.4f}")
    for key in ("expected_information", "profile_information"):
        se = np.sqrt(np.diag(np.linalg.inv(out[key][np.ix_(index, index)])))
        print(f"{key:<21} se / observed se: f_h {se[0] / observed[0]:.2f}, xi_h {se[1] / observed[1]:.2f}")


if __name__ == "__main__":
    main()
