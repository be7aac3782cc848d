"""The fast paths compute what the reference paths compute; parallel and distributed runs equal serial ones.

No timings here (they are in benchmarks/perf.py and docs/performance.md): only equality.
"""

import numpy as np
import pytest

from smd_statespace.effects import make_effect
from smd_statespace.estimators import GaussianStart, get_estimator
from smd_statespace.estimators.particle import noise_generator
from smd_statespace.model import SMDModel

from helpers import FIXED, linear_case, well_excited_cycle



def run_both(model, data, **options):
    results = {}
    for engine in ("numba", "numpy"):
        rng = np.random.default_rng(3)
        pf = get_estimator("pf", engine=engine, **options)
        result = pf.run(model, data, rng=rng)
        results[engine] = (result, rng.bit_generator.state, pf)
    return results


def assert_same_pass(a, b):
    np.testing.assert_allclose(a.mean, b.mean, rtol=1e-9, atol=1e-13)
    np.testing.assert_allclose(a.std, b.std, rtol=1e-7, atol=1e-11)  # a fixed slot: sd of rounding
    np.testing.assert_allclose(a.innovations, b.innovations, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(a.innovation_cov, b.innovation_cov, rtol=1e-9, atol=1e-15)
    assert a.log_likelihood == pytest.approx(b.log_likelihood, rel=1e-11)
    np.testing.assert_allclose(a.restart.particles, b.restart.particles, rtol=1e-9, atol=1e-13)
    np.testing.assert_array_equal(a.diagnostics["ess"] > 0, b.diagnostics["ess"] > 0)
    assert a.diagnostics["resamples"] == b.diagnostics["resamples"]


@pytest.mark.parametrize("discretisation,substeps,observation", [("rk4", 1, "full"), ("euler", 2, "full"),
                                                                  ("rk4", 1, "acc")])
def test_compiled_particle_filter_equals_numpy_path(discretisation, substeps, observation):
    model = SMDModel(discretisation=discretisation, substeps=substeps, observation=observation)
    _, data, _ = well_excited_cycle(samples=40)
    if observation == "acc":
        data = type(data)(t=data.t, y=data.y[:, 2:], inputs=data.inputs)
    runs = run_both(model, data, n_particles=400)
    (fast, fast_state, fast_pf), (slow, slow_state, _) = runs["numba"], runs["numpy"]
    assert fast.diagnostics["engine"] == "numba" and slow.diagnostics["engine"] == "numpy"
    assert fast.diagnostics["resamples"] > 3
    assert_same_pass(fast, slow)
    # The generator is left exactly where numpy leaves it, so the next pass draws the same numbers too.
    assert fast_state == slow_state
    again = get_estimator("pf", engine="numba", n_particles=400).run(model, data, start=fast.restart,
                                                                    rng=np.random.default_rng(4))
    other = get_estimator("pf", engine="numpy", n_particles=400).run(model, data, start=slow.restart,
                                                                    rng=np.random.default_rng(4))
    assert_same_pass(again, other)


def test_compiled_particle_filter_with_fixed_slots_and_reflection():
    model, data = linear_case("rk4")
    runs = run_both(model, data, n_particles=300)
    assert_same_pass(runs["numba"][0], runs["numpy"][0])
    fixed = {}
    for engine in ("numba", "numpy"):
        pf = get_estimator("pf", engine=engine, n_particles=300)
        fixed[engine] = pf.run(model, data, fixed=FIXED, rng=np.random.default_rng(9))
        np.testing.assert_allclose(fixed[engine].mean[:, model.index("f_h")], FIXED["f_h"], rtol=1e-12)
    assert_same_pass(fixed["numba"], fixed["numpy"])
    # A Gaussian start far outside the coefficient box exercises the reflection at the bounds.
    setup_mean = np.zeros(model.n_state)
    setup_mean[model.index("f_h")], setup_mean[model.index("xi_h")] = 2.5, 0.3
    setup_mean[model.index("a1")] = 0.39
    start = GaussianStart(setup_mean, np.diag(np.r_[1e-4, 1e-2, 0.1, 0.01, np.full(model.n_state - 4, 0.04)]))
    edge = {engine: get_estimator("pf", engine=engine, n_particles=300).run(model, data, start=start,
                                                                            rng=np.random.default_rng(2))
            for engine in ("numba", "numpy")}
    assert_same_pass(edge["numba"], edge["numpy"])


def test_engine_choice():
    model = SMDModel(n_harmonics=2)
    assert get_estimator("pf").engine_for(model) == "numba"
    assert get_estimator("pf", engine="numpy").engine_for(model) == "numpy"
    with_effect = model.with_effects(make_effect("cubic_stiffness"))
    assert get_estimator("pf").engine_for(with_effect) == "numpy"
    from smd_statespace.errors import OptionError

    with pytest.raises(OptionError, match="engine='numba' needs"):
        get_estimator("pf", engine="numba").engine_for(with_effect)
    with pytest.raises(OptionError, match="engine must be one of"):
        get_estimator("pf", engine="cuda")


def test_noise_generator_is_a_function_of_the_given_generator():
    a = noise_generator(np.random.default_rng(5)).standard_normal(4)
    b = noise_generator(np.random.default_rng(5)).standard_normal(4)
    c = noise_generator(np.random.default_rng(6)).standard_normal(4)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)



# -- the pieces of the compiled pass that replace a library call --------------------------------


def test_compiled_normals_are_numpys():
    from smd_statespace.estimators._pf_numba import fill_normal_transposed

    generator = np.random.Generator(np.random.SFC64(11))
    state = generator.bit_generator.state["state"]["state"].copy()
    expected = generator.standard_normal(200_000)  # enough draws to pass through every slow-path branch
    drawn = np.empty(200_000)
    fill_normal_transposed(state, drawn.reshape(1, -1))
    np.testing.assert_array_equal(drawn, expected)
    assert np.array_equal(state, generator.bit_generator.state["state"]["state"])
    blocks = np.empty((13, 50))
    fill_normal_transposed(state, blocks)
    np.testing.assert_array_equal(blocks, generator.standard_normal((50, 13)).T)


def test_ziggurat_tables_follow_their_construction():
    """The copied tables are Marsaglia and Tsang's 256 layers of equal area under exp(-x**2/2), edge R."""
    from math import erfc, exp, log, pi, sqrt

    from smd_statespace.estimators._ziggurat import FI, INVERSE_R, KI, R, WI

    area = R * exp(-R * R / 2) + sqrt(pi / 2) * erfc(R / sqrt(2))  # base layer: rectangle and tail
    edges = np.empty(256)
    edges[255] = R
    for i in range(255, 1, -1):  # each layer above has the same area
        edges[i - 1] = sqrt(-2 * log(exp(-edges[i] ** 2 / 2) + area / edges[i]))
    edges[0] = area / exp(-R * R / 2)
    np.testing.assert_allclose(WI * 2.0**52, edges, rtol=1e-12)
    np.testing.assert_allclose(FI[1:], np.exp(-edges[1:] ** 2 / 2), rtol=1e-12)
    assert FI[0] == 1.0 and KI[1] == 0 and INVERSE_R == pytest.approx(1 / R, rel=1e-15)
    ratios = np.r_[R / edges[0], 0.0, edges[1:255] / edges[2:]]
    np.testing.assert_allclose(KI.astype(float) / 2.0**52, ratios, rtol=1e-12, atol=0)


def test_vectorised_exponential_is_within_one_ulp_of_libm():
    from smd_statespace.estimators._pf_numba import exponentiate

    rng = np.random.default_rng(0)
    x = np.concatenate([-rng.exponential(50.0, 100_000), -rng.random(10_000) * 1e-6, [0.0, -1e-300, -707.9]])
    out = np.empty_like(x)
    exponentiate(x, 0.0, out)
    expected = np.exp(x)
    assert np.max(np.abs(out - expected) / np.spacing(expected)) <= 1.0
    shifted = np.empty(3)
    exponentiate(np.array([3.0, 2.0, -np.inf]), 3.0, shifted)  # exp(log_weights - top)
    np.testing.assert_allclose(shifted, [1.0, np.exp(-1.0), 0.0], rtol=1e-15)
    below = np.empty(3)
    exponentiate(np.array([-708.5, -800.0, -np.inf]), 0.0, below)  # numpy: subnormals, at most 3e-308
    np.testing.assert_array_equal(below, 0.0)


@pytest.mark.parametrize("seed", range(5))
def test_branch_free_systematic_index_equals_searchsorted(seed):
    from smd_statespace.estimators._pf_numba import systematic_index
    from smd_statespace.estimators.particle import systematic_resample

    rng = np.random.default_rng(seed)
    n = 1000
    weights = rng.random(n) ** 8  # a few heavy particles, as after a sharp likelihood
    weights[rng.random(n) < 0.3] = 0.0  # and particles whose weight underflowed
    total = weights.sum()
    offset = rng.random()
    chosen = np.empty(n, np.intp)
    systematic_index(weights, 1.0 / total, offset, np.empty(n + 1, np.intp), chosen)

    class Fixed:  # the same uniform for the reference
        def random(self):
            return offset

    np.testing.assert_array_equal(chosen, systematic_resample(weights / total, Fixed()))
    assert np.all(weights[chosen] > 0)

# -- parallel and distributed runs give the serial table ---------------------------------------


@pytest.fixture(scope="module")
def record():
    from smd_statespace.signals import preprocess
    from smd_statespace.simulation import simulate_bouncing

    return preprocess(simulate_bouncing(mass=64.0, f_b=2.4, f_h=2.6, xi_h=0.35, duration=7.0, seed=21).record)


def table_without_timings(table):
    return table[[c for c in table.columns if c != "seconds"]]


def test_identify_jobs_two_equals_jobs_one(tmp_path):
    import pandas as pd

    from smd_statespace.cli import main

    record = tmp_path / "rec.csv"
    assert main(["simulate", "--out", str(record), "--mass", "66", "--fb", "2.4", "--fh", "2.8", "--xi", "0.3",
                 "--duration", "6", "--seed", "3"]) == 0
    tables = []
    for jobs in (1, 2):
        out = tmp_path / f"jobs{jobs}"
        assert main(["identify", str(record), "--mass", "66", "--estimator", "pf", "--particles", "300",
                     "--max-passes", "2", "--seed", "4", "--jobs", str(jobs), "--out", str(out), "--quiet"]) == 0
        tables.append(table_without_timings(pd.read_csv(out / "results.csv")))
    assert (tables[0].status == "ok").sum() >= 4
    pd.testing.assert_frame_equal(tables[0], tables[1])


def test_run_many_streams_records_and_matches_single_runs(record, tmp_path):
    import pandas as pd

    from smd_statespace.identify.runner import CycleRunner

    options = dict(estimator="pf", n_particles=200, max_passes=2, progress=False, seed=5)
    runner = CycleRunner(keep_results=False, **options)
    path = tmp_path / "study.csv"
    rows = runner.run_many([record, record], path)
    study = pd.read_csv(path)
    assert rows == len(study) == 2 * len(record.cycles) and runner.results_ == {}
    for key in (0, 1):
        alone = CycleRunner(**options).run(record, record_key=key)
        part = study[study.record == key].drop(columns="record").reset_index(drop=True)
        np.testing.assert_allclose(part.f_h.to_numpy(float), alone.f_h.to_numpy(float), rtol=1e-12)
        np.testing.assert_allclose(part.log_likelihood.to_numpy(float), alone.log_likelihood.to_numpy(float),
                                   rtol=1e-12)
    # Different record keys draw different numbers.
    assert not np.allclose(study[study.record == 0].f_h.dropna(), study[study.record == 1].f_h.dropna())


def test_dask_cluster_executor_gives_the_serial_table(record):
    distributed = pytest.importorskip("distributed")
    import pandas as pd

    from smd_statespace.identify.runner import CycleRunner

    options = dict(estimator="pf", n_particles=200, max_passes=2, progress=False, seed=5)
    serial = CycleRunner(**options).run(record)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        runner = CycleRunner(executor=client.get_executor(), **options)
        clustered = runner.run(record)
    pd.testing.assert_frame_equal(table_without_timings(serial), table_without_timings(clustered))


@pytest.mark.parametrize("bit_generator", [np.random.SFC64, np.random.PCG64, np.random.MT19937])
def test_prior_columns_are_the_full_draws_columns_and_the_stream_moves_alike(bit_generator):
    model = SMDModel()
    _, data, _ = well_excited_cycle(samples=10)
    prior = model.prior(data.y[0], model.data_scale(data.y, data.inputs))
    full, part = np.random.Generator(bit_generator(3)), np.random.Generator(bit_generator(3))
    dynamic = np.array([slot.kind == "dynamic" for slot in model.slots])
    np.testing.assert_array_equal(prior.sample(part, 300, columns=dynamic), prior.sample(full, 300)[:, dynamic])
    assert part.random() == full.random()  # the skipped uniform slots used the same words
    some = np.array([2, 5])
    np.testing.assert_array_equal(prior.sample(part, 7, columns=some), prior.sample(full, 7)[:, some])
    # What rng.uniform and rng.normal would give, element by element.
    reference = np.random.Generator(bit_generator(8))
    drawn = prior.sample(np.random.Generator(bit_generator(8)), 50)
    uniform = np.array([kind == "uniform" for kind in prior.kinds])
    expected_uniform = reference.uniform(prior.first[uniform], prior.second[uniform], size=(50, uniform.sum()))
    expected_normal = reference.normal(prior.first[~uniform], prior.second[~uniform], size=(50, (~uniform).sum()))
    np.testing.assert_array_equal(drawn[:, uniform], expected_uniform)
    np.testing.assert_array_equal(drawn[:, ~uniform], expected_normal)
