"""Compiled passes of another tree against this checkout's, side by side in one process (issue 25).

This host runs processes at two speeds about 1.5x apart (docs/performance.md, "The host's two
speeds"): two processes a minute apart can differ by half, more than most changes to compiled
code. Here the other tree's package is loaded beside this checkout's (under another name), and
each compiled pass of the two is called in turn on the same inputs, so both see the same speed:

* the particle filter's pass (``estimators/_pf_numba.run_pass``; N particles, the cycle of
  ``perf.py``), in ns per particle-step;
* the record level's likelihood pass (``person/kalman.augmented_pass``) and derivative pass
  (``sensitivity_pass``, in ``person/sensitivity.py`` or, in older trees, ``person/score.py``) on a
  30 s record with nine parameters, variations "independent" and "smooth", in ms.

Each row says whether the two give the same numbers (the largest difference of their outputs).

::

    mkdir -p /tmp/before && git archive 6214a14 smd_statespace | tar -x -C /tmp/before
    OPENBLAS_NUM_THREADS=1 python benchmarks/side_by_side.py /tmp/before --repeats 15
"""

from __future__ import annotations

import os

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

import argparse  # noqa: E402
import importlib  # noqa: E402
import importlib.util  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from perf import the_cycle  # noqa: E402

from smd_statespace import SMDModel  # noqa: E402
from smd_statespace.estimators import _pf_kernel, get_estimator  # noqa: E402
from smd_statespace.io import G  # noqa: E402
from smd_statespace.person import RecordModel, Regressor, estimate_timing, kalman  # noqa: E402
from smd_statespace.person.score import sensitivity_pass, system_derivatives  # noqa: E402
from smd_statespace.simulation import simulate_bouncing  # noqa: E402

OTHER = "other_smd_statespace"
"""The name the other tree's package is loaded under."""

TEMPLATE = np.array([0.0, -0.2, 0.1, 0.1, 0.05, 0.03, 0.0, 0.01, 0.0])
"""A force template (g) for the phase and rate errors (nine parameters with variation "independent")."""


def load_other(tree: Path):
    """The other tree's ``smd_statespace`` as the package :data:`OTHER` (its relative imports stay inside it)."""
    init = tree / "smd_statespace" / "__init__.py"
    if not init.is_file():
        raise SystemExit(f"{tree}: no smd_statespace/__init__.py (give a tree made by git archive REV smd_statespace)")
    spec = importlib.util.spec_from_file_location(OTHER, init, submodule_search_locations=[str(init.parent)])
    package = importlib.util.module_from_spec(spec)
    sys.modules[OTHER] = package
    spec.loader.exec_module(package)
    return package


def other_function(module_names, name):
    """``name`` from the first of the other tree's modules ``module_names`` that has it."""
    for module_name in module_names:
        try:
            module = importlib.import_module(f"{OTHER}.{module_name}")
        except ModuleNotFoundError:
            continue
        if hasattr(module, name):
            return getattr(module, name)
    raise SystemExit(f"the other tree has no {name} in {', '.join(module_names)}")


def interleaved(other, ours, arguments, repeats):
    """Fastest and median seconds of each, called in turn (the order swapped every repeat), and the largest
    difference of their outputs."""
    def fresh():
        return tuple(a.copy() if isinstance(a, np.ndarray) else a for a in arguments)

    first, second = other(*fresh()), ours(*fresh())
    arrays = [(a, b) for a, b in zip(first, second) if isinstance(a, np.ndarray) or np.isscalar(a)]
    difference = max(float(np.max(np.abs(np.asarray(a, float) - np.asarray(b, float)))) for a, b in arrays)
    times = {"other": [], "ours": []}
    for repeat in range(repeats):
        order = (("other", other), ("ours", ours)) if repeat % 2 else (("ours", ours), ("other", other))
        for label, function in order:
            given = fresh()
            started = time.perf_counter()
            function(*given)
            times[label].append(time.perf_counter() - started)
    return {label: (min(values), float(np.median(values))) for label, values in times.items()}, difference


def particle_filter_arguments(n_particles):
    """The arguments of the compiled pass as ``pf.run`` makes them for the cycle of ``perf.py``."""
    kernel, captured = _pf_kernel.kernel(), []

    def capture(*arguments):
        captured.append(arguments)
        return kernel(*arguments)

    _pf_kernel._COMPILED["run_pass"] = capture
    try:
        model = SMDModel()
        get_estimator("pf", n_particles=n_particles).run(model, the_cycle(model), rng=np.random.default_rng(3))
    finally:
        _pf_kernel._COMPILED["run_pass"] = kernel
    arguments = captured[0]
    return kernel, arguments, arguments[0].shape[1] * arguments[2].shape[0]


def record_arguments(variation):
    """The compiled passes' arguments on a 30 s record (f_b 2.2 Hz, f_h 2.8 Hz, xi_h 0.3, seed 3)."""
    sim = simulate_bouncing(mass=70, f_b=2.2, f_h=2.8, xi_h=0.3, duration=30, seed=3)
    record = sim.record
    y = record.force / record.mass - G
    timing = estimate_timing(record.time, record.force, 4, "template")
    offset = Regressor("offset", np.ones_like(y), "m/s^2", dynamic=False)
    model = RecordModel(record.time, y, timing, 4, variation, regressors=(offset,), phase_template=TEMPLATE)
    params = model.start_params(2.75, 0.28, -2.5)
    system = model.system(params)
    passes = system.pass_arguments(model.y, model.n_coefficients)
    der = system_derivatives(model, params, system)
    sensitivity = passes + (model.filter(params)["delta"],) + tuple(
        der[key] for key in ("dyn", "d_hx", "d_Phi", "d_Gam", "d_offset", "d_X_tr", "d_y", "d_Qx", "d_D", "d_E",
                             "d_drift", "d_sphi", "d_sq", "d_sp0"))
    return passes, sensitivity


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("other", type=Path, help="a tree with the other version's smd_statespace/")
    parser.add_argument("--repeats", type=int, default=15, help="calls of each, interleaved (default 15)")
    parser.add_argument("--particles", type=int, default=5000)
    args = parser.parse_args(argv)
    load_other(args.other.resolve())
    rows = []
    kernel, arguments, steps = particle_filter_arguments(args.particles)
    timing, difference = interleaved(other_function(["estimators._pf_numba"], "run_pass"), kernel, arguments,
                                     args.repeats)
    per_step = {label: (fastest / steps * 1e9, median / steps * 1e9) for label, (fastest, median) in timing.items()}
    rows.append(("particle filter pass (ns per particle-step)", per_step, difference))
    other_augmented = other_function(["person.kalman"], "augmented_pass")
    other_sensitivity = other_function(["person.sensitivity", "person.score"], "sensitivity_pass")
    for variation in ("independent", "smooth"):
        passes, sensitivity = record_arguments(variation)
        for name, other, ours, given in (("augmented_pass", other_augmented, kalman.augmented_pass, passes),
                                         ("sensitivity_pass", other_sensitivity, sensitivity_pass, sensitivity)):
            timing, difference = interleaved(other, ours, given, args.repeats)
            rows.append((f"{name}, {variation} (ms)", {k: (a * 1e3, b * 1e3) for k, (a, b) in timing.items()},
                         difference))
    print(f"load average {os.getloadavg()[0]:.2f}; {args.repeats} calls of each, interleaved; other tree {args.other}")
    print("| pass | other: fastest, median | this checkout: fastest, median | largest difference of outputs |")
    print("|---|---|---|---|")
    for name, timing, difference in rows:
        print(f"| {name} | {timing['other'][0]:.2f}, {timing['other'][1]:.2f} | {timing['ours'][0]:.2f}, "
              f"{timing['ours'][1]:.2f} | {difference:.1e} |")


if __name__ == "__main__":
    main()
