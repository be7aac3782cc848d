"""One record's independent searches in threads: the same answer as one after the other."""

import threading

import numpy as np
import pandas as pd
import pytest

from smd_statespace.errors import OptionError
from smd_statespace.person import identify_person, kalman, sensitivity
from smd_statespace.person.screen import generic_library, screen
from smd_statespace.person.threads import THREADS_VARIABLE, available_cores, search_threads, thread_map
from smd_statespace.simulation import simulate_bouncing


def test_thread_map_runs_side_by_side_in_order_and_raises():
    meeting = threading.Barrier(2, timeout=10)  # two calls must be running at once to pass it

    def meet(item):
        meeting.wait()
        return item * 10

    assert thread_map(meet, [1, 2], 2) == [10, 20]
    assert thread_map(lambda item: item + 1, range(5), 2) == [1, 2, 3, 4, 5]
    assert thread_map(lambda item: item + 1, [7], 4) == [8]

    def fail(item):
        if item == 3:
            raise ValueError("three")
        return item

    with pytest.raises(ValueError, match="three"):
        thread_map(fail, [1, 2, 3, 4], 2)


def test_the_compiled_passes_release_the_interpreter_lock():
    assert kalman.augmented_pass.targetoptions.get("nogil")
    assert sensitivity.sensitivity_pass.targetoptions.get("nogil")


def test_search_threads_default_environment_and_bad_values(monkeypatch):
    monkeypatch.delenv(THREADS_VARIABLE, raising=False)
    assert search_threads() == min(2, available_cores())
    assert search_threads(3) == 3
    monkeypatch.setenv(THREADS_VARIABLE, "1")
    assert search_threads() == 1
    assert search_threads(2) == 2  # given beats the environment
    for bad in ("0", "two", "1.5"):
        monkeypatch.setenv(THREADS_VARIABLE, bad)
        with pytest.raises(OptionError, match=THREADS_VARIABLE):
            search_threads()
    with pytest.raises(OptionError, match="threads 0 is not valid"):
        search_threads(0)


@pytest.fixture(scope="module")
def record():
    return simulate_bouncing(mass=70, f_b=2.2, f_h=2.9, xi_h=0.3, duration=16, seed=31).record


def test_identify_in_two_threads_equals_one(record):
    one = identify_person(record, threads=1)
    two = identify_person(record, threads=2)
    np.testing.assert_array_equal(one.params, two.params)
    np.testing.assert_array_equal(one.cov, two.cov)  # the information's passes in threads too
    assert one.model.variation == two.model.variation
    assert [row.loglike for row in one.comparison] == [row.loglike for row in two.comparison]
    assert one.change is not None and one.change["z"] == two.change["z"]
    # and the answer is the person's, not merely the same twice
    assert abs(one.f_h - 2.9) < 3 * one.sd("f_h")


def test_screen_in_two_threads_equals_one(record):
    result = identify_person(record, check_change=False, threads=2)
    terms = generic_library(result)[:6]
    pd.testing.assert_frame_equal(screen(result, terms, threads=1), screen(result, terms, threads=2))
