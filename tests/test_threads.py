"""One record's independent searches in threads: the same answer as one after the other."""

import threading

import numpy as np
import pandas as pd
import pytest

from smd_statespace.errors import OptionError
from smd_statespace.person import identify_person, kalman, sensitivity
from smd_statespace.person.screen import generic_library, screen
from smd_statespace.person import score as score_module
from smd_statespace.person.threads import (THREADS_VARIABLE, available_cores, record_cores, search_threads, spare_best,
                                          spare_map, spare_thread, thread_map)
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


def test_a_derivative_pass_split_with_an_idle_thread_is_the_whole_pass_to_the_last_bit(record, monkeypatch):
    """Inside a person's entry point with a thread idle, a derivative pass computes half of its parameters'
    derivatives in that thread; the numbers are the unsplit pass's exactly. Outside an entry point, or with one
    thread, it does not split; one idle thread is lent once."""
    result = identify_person(record, check_change=False, threads=1)
    model, params = result.model, result.params
    passes = []
    original = score_module.sensitivity_pass

    def counted(*args):
        out = original(*args)
        passes.append(out[2].shape[1])  # the parameters this pass differentiated
        return out

    monkeypatch.setattr(score_module, "sensitivity_pass", counted)
    whole = score_module.score(model, params)
    assert passes == [params.size]

    @record_cores
    def entry(threads):
        with spare_thread() as spare:
            with spare_thread() as second:
                lent = (spare, second)
        return lent, score_module.score(model, params)

    passes.clear()
    lent, split = entry(threads=2)
    assert lent == (True, False) and sorted(passes) == [params.size // 2, params.size - params.size // 2]
    for key in ("loglike", "gradient", "profile_information", "efficient_per_sample", "d_innovations",
                "d_log_variances", "innovations"):
        np.testing.assert_array_equal(whole[key], split[key])
    passes.clear()
    lent, _ = entry(threads=1)
    assert lent == (False, False) and passes == [params.size]


def test_a_list_of_trial_starts_is_evaluated_half_in_an_idle_thread_and_in_order():
    """spare_map gives the list a loop gives; inside an entry point with a thread idle, its second half runs in that
    thread (the likelihoods of a search's trial starts), outside one or with one thread, here."""
    where = {}

    def square(item):
        where[item] = threading.current_thread().name
        return item * item

    @record_cores
    def entry(threads):
        return spare_map(square, range(6))

    assert entry(threads=2) == [0, 1, 4, 9, 16, 25]
    here = threading.current_thread().name
    assert [where[i] == here for i in range(6)] == [True] * 3 + [False] * 3
    where.clear()
    assert entry(threads=1) == spare_map(square, range(6)) == [0, 1, 4, 9, 16, 25]
    assert set(where.values()) == {here}
    # the best of them as max() takes it: the first of equals
    starts = [("a", 1), ("b", 3), ("c", 2), ("d", 3)]
    best = record_cores(lambda threads: spare_best(lambda start: start[1], starts))
    assert best(threads=2) == best(threads=1) == max(starts, key=lambda start: start[1]) == ("b", 3)


def test_screen_in_two_threads_equals_one(record):
    result = identify_person(record, check_change=False, threads=2)
    terms = generic_library(result)[:6]
    pd.testing.assert_frame_equal(screen(result, terms, threads=1), screen(result, terms, threads=2))
    # the steps' scans, one per kind, side by side
    one, two = (generic_library(result, ["f_step", "xi_step"], scan=True, threads=n) for n in (1, 2))
    assert [term.spec for term in one] == [term.spec for term in two] and all(term.scan for term in one)
    for first, second in zip(one, two):
        pd.testing.assert_frame_equal(first.scan["table"], second.scan["table"])


def test_the_person_runs_with_one_blas_thread_and_gives_the_callers_setting_back():
    """The person's entry points limit the BLAS libraries to one thread while they run (their matrices are small and
    their searches run threads of their own) and leave the caller's setting as it was, also when they raise."""
    from types import SimpleNamespace

    from threadpoolctl import threadpool_info, threadpool_limits

    from smd_statespace.person import diagnose, extend
    from smd_statespace.person.threads import one_blas_thread

    def blas_threads():
        return {library["num_threads"] for library in threadpool_info() if library["user_api"] == "blas"}

    if not blas_threads():
        pytest.skip("numpy's BLAS is not one threadpoolctl controls")

    @one_blas_thread
    def inside(fail=False):
        if fail:
            raise ValueError("fails inside")
        return blas_threads()

    with threadpool_limits(limits=2, user_api="blas"):
        assert blas_threads() == {2}
        assert inside() == {1}
        assert blas_threads() == {2}
        with pytest.raises(ValueError, match="fails inside"):
            inside(fail=True)
        assert blas_threads() == {2}

    class Seen(Exception):
        pass

    def seen(*args, **kwargs):  # the first call of each entry point: what BLAS runs on inside it
        raise Seen(blas_threads())

    calls = [(extend, "record_effects", lambda: identify_person(None)),
             (extend, "configured_for_record",
              lambda: extend.fit_effects(SimpleNamespace(effects=()), ["cubic_stiffness"])),
             (diagnose, "label", lambda: diagnose.diagnose_person(SimpleNamespace(effects=["cubic_stiffness"])))]
    for module, first, call in calls:
        with threadpool_limits(limits=2, user_api="blas"), pytest.MonkeyPatch.context() as patch:
            patch.setattr(module, first, seen)
            with pytest.raises(Seen) as inside_entry:
                call()
            assert inside_entry.value.args == ({1},) and blas_threads() == {2}, module.__name__


def test_the_blas_limit_of_calls_in_threads_gives_the_callers_setting_back_whichever_leaves_first(monkeypatch):
    """Two calls in threads, the first to enter leaving first (as a user's threads can): both run on one BLAS thread
    to their end, and the caller has its own setting after both. The process's setting is a stand-in here (a limiter
    with threadpoolctl's calls): OpenBLAS 0.3.31 does not reliably take a limit set from a thread other than the main
    one (seen: ignored once the main thread had set and restored one twice), which made the real setting depend on
    the tests run before in the same process."""
    import threadpoolctl

    from smd_statespace.person.threads import one_blas_thread

    setting = {"threads": 2}  # the caller's

    class Limiter:  # threadpool_limits' calls, on the stand-in
        def __init__(self, limits, user_api):
            assert user_api == "blas"
            self.original, setting["threads"] = setting["threads"], limits

        def restore_original_limits(self):
            setting["threads"] = self.original

    monkeypatch.setattr(threadpoolctl, "threadpool_limits", Limiter)
    first_in, second_in, first_out = threading.Event(), threading.Event(), threading.Event()
    seen = {}

    @one_blas_thread
    def first():
        first_in.set()
        second_in.wait(10)
        seen["first"] = setting["threads"]

    @one_blas_thread
    def second():
        second_in.set()
        first_out.wait(10)
        seen["second"] = setting["threads"]  # the first has left: still one thread

    other = threading.Thread(target=second)
    worker = threading.Thread(target=lambda: (first(), first_out.set()))
    worker.start()
    first_in.wait(10)
    other.start()
    worker.join(10)
    other.join(10)
    assert seen == {"first": 1, "second": 1}
    assert setting["threads"] == 2


@pytest.mark.filterwarnings("error::pytest.PytestUnhandledThreadExceptionWarning")
def test_an_error_in_the_idle_threads_half_is_raised_in_the_caller_and_not_left_in_the_thread(capsys):
    @record_cores
    def entry(threads):
        return spare_map(lambda item: 1 // (item - 4), range(6))  # item 4 is in the second half

    with pytest.raises(ZeroDivisionError):
        entry(threads=2)
    assert "Exception in thread" not in capsys.readouterr().err
