"""Fixtures shared by the test modules: simulated records and the expensive fits made from them.

Session-scoped, so a record is simulated and a person identified once per test run, whichever
modules use them. Plain helpers (no fixtures) are in ``helpers.py``.
"""

from pathlib import Path

import pytest

from smd_statespace.simulation import simulate_bouncing

SMOKE = {
    # whole modules: records, checks, the model and its Jacobians, the pipeline, the layers
    "test_io.py": None, "test_layers.py": None, "test_model.py": None, "test_jacobians.py": None,
    "test_applicability.py": None, "test_signals.py": None, "test_suggestions.py": None,
    # one test of each kind elsewhere: an estimator against the exact Kalman filter, the person's exact gradient
    # and search, the command line's errors and start
    "test_estimators.py": ("test_grid_equals_textbook_kalman_filter_on_linear_subcase",
                           "test_kalman_type_filters_match_exact_filter_on_linear_subcase",
                           "test_vectorised_ukf_equals_filterpy_loop", "test_bad_estimator_options"),
    "test_person_score.py": ("test_gradient_is_the_derivative_of_the_profile_loglike[independent]",
                             "test_a_broken_pass_gives_nan"),
    "test_cli.py": ("test_version_and_help", "test_starting_the_cli_loads_no_heavy_module",
                    "test_simulate_bad_inputs_are_one_line_errors", "test_simulate_writes_a_readable_record"),
    "test_simulate.py": ("test_steady_state_harmonics_equal_eq2_frequency_response", "test_free_decay_matches",
                         "test_grf_is_eq3"),
}
"""The smoke tier (``python -m pytest -m smoke``, under a minute): modules, or test-name prefixes in a module; never a
test marked slow."""


MODULE_SECONDS = {
    "test_person.py": 114, "test_docs.py": 77, "test_missing.py": 76, "test_notebooks.py": 76,
    "test_person_effects.py": 63, "test_batch.py": 44, "test_cli.py": 40, "test_person_screen.py": 39,
    "test_user_effect.py": 34, "test_suggestions.py": 32, "test_accelerometer_person.py": 32,
    "test_simulate.py": 29, "test_person_validation.py": 24, "test_phone_session.py": 22, "test_estimators.py": 19,
    "test_time_change.py": 20, "test_stats.py": 17, "test_crowd.py": 16, "test_reliability.py": 15, "test_fade.py": 15,
    "test_lab_person.py": 14, "test_diagnostics.py": 12, "test_hsi.py": 11, "test_applicability.py": 10,
    "test_threads.py": 10, "test_simulation_generators.py": 10, "test_person_breaks.py": 9,
    "test_performance.py": 8, "test_runner.py": 8, "test_person_in_time.py": 7, "test_floor_measured_physics.py": 7,
    "test_floor_effect.py": 7, "test_reference.py": 7, "test_lab_records.py": 6, "test_person_score.py": 6,
    "test_structure_cli.py": 6,
}
"""Seconds each test module took on one worker (``pytest -n auto --durations=0``, 2 cores, 2026-11-30; the modules of
5 s or more). The modules run heaviest first, each on one worker (``--dist loadscope --no-loadscope-reorder`` in
setup.cfg): xdist's own order, most tests first, left the heavy modules of few tests to the end, one worker
finishing them alone (measured: 511 s of wall time for 968 s of tests on two workers). A module not listed runs
after those listed, in the order collected."""


def pytest_collection_modifyitems(config, items):
    order = {id(item): position for position, item in enumerate(items)}
    items.sort(key=lambda item: (-MODULE_SECONDS.get(Path(str(item.fspath)).name, 0), order[id(item)]))
    for item in items:
        chosen = SMOKE.get(Path(str(item.fspath)).name, ())
        if item.get_closest_marker("slow") is None and (
                chosen is None or any(item.name.startswith(prefix) for prefix in chosen)):
            item.add_marker(pytest.mark.smoke)


@pytest.fixture(scope="session")
def short_sim():
    """An 8 s record (f_b 2 Hz, f_h 2.5 Hz, xi_h 0.3, 1 % BW noise)."""
    return simulate_bouncing(mass=70, f_b=2.0, f_h=2.5, xi_h=0.3, duration=8, seed=1)


@pytest.fixture(scope="session")
def long_sim():
    """A 40 s record with little noise; its true force-cycle boundaries are known."""
    return simulate_bouncing(mass=70, f_b=2.2, f_h=2.8, xi_h=0.25, duration=40, noise=0.002, seed=11)


@pytest.fixture(scope="session")
def long_fit(long_sim):
    """The record-level person of :func:`long_sim` (the default ``identify_person``)."""
    from smd_statespace.person import identify_person

    return identify_person(long_sim.record)
