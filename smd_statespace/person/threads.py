"""Both cores for one record: a record's independent searches run side by side in threads.

The compiled passes of the likelihood and its derivatives
(:func:`~smd_statespace.person.kalman.augmented_pass`,
:func:`~smd_statespace.person.sensitivity.sensitivity_pass`) release Python's global interpreter
lock (numba's ``nogil``) and take about 70 % of a search's time. The searches of one record that do
not depend on each other — each variation model re-placing its own cycle starts
(:func:`~smd_statespace.person.search.choose_with_own_timing`), the person fitted on each half of
the record (:func:`~smd_statespace.person.change.change_test`) — therefore run in threads, one per
core, and give the same numbers as run one after the other: nothing is shared between them and
nothing is drawn at random.

A batch of records already keeps every core busy with one record per process
(``identify FOLDER --jobs N``); its worker processes run their searches in one thread
(:data:`THREADS_VARIABLE`).

Where a record's searches cannot run side by side (one variation model still re-placing its cycle starts after
the other has finished, the final fit, the information), one derivative pass at a time ran on one core while the
other waited: measured on six 30 s records with two threads, a derivative pass ran alone during 0.7-1.4 s of
1.6-2.8 s. The person's entry points count the threads their searches keep busy (:func:`record_cores`,
:func:`thread_map`), and a derivative pass that finds one of the ``threads`` idle (:func:`spare_thread`) splits
its parameters' derivatives between itself and it
(:func:`~smd_statespace.person.score.sensitivities`): each column of the derivatives is computed as in one pass
(the same numbers to the last bit, tested), so the answer does not depend on when a thread was free. A search's
list of trial starts is evaluated the same way, half in an idle thread (:func:`spare_map`, :func:`spare_best`).

The linear algebra a search does in numpy and scipy is on small matrices (a state of 6-30, a few thousand
samples), where a BLAS library's own threads only compete with these searches and with other processes for the
cores: :func:`one_blas_thread` runs the person's entry points with BLAS limited to one thread (threadpoolctl,
as scikit-learn limits it inside estimators that run threads of their own). Measured on a 30 s record
(``identify`` then ``diagnose`` in one process): 15.1 -> 12.4 s of CPU for the same answers and about the same
wall time; the person's tests on two test processes, 118 -> 101 s.
"""

from __future__ import annotations

import contextlib
import functools
import inspect
import os
import threading
from concurrent.futures import ThreadPoolExecutor

from ..errors import OptionError

__all__ = ["THREADS_VARIABLE", "one_blas_thread", "record_cores", "search_threads", "spare_best", "spare_halves",
           "spare_map", "spare_thread", "thread_map"]

THREADS_VARIABLE = "SMD_STATESPACE_THREADS"
"""Environment variable: the number of threads one record's searches use when ``threads`` is not given
(default: two, or one on a single-core machine)."""


def available_cores() -> int:
    """Cores this process may run on (its CPU affinity where the system says, else the machine's count)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def search_threads(threads=None) -> int:
    """The number of threads for one record's independent searches.

    Parameters
    ----------
    threads : int or None
        As given (at least 1); None: :data:`THREADS_VARIABLE` if set, else ``min(2, cores)``
        (there are at most two independent searches at a time).

    Raises
    ------
    OptionError
        ``threads``, or the environment variable, is not a whole number of at least 1.
    """
    source = "threads"
    if threads is None:
        setting = os.environ.get(THREADS_VARIABLE, "").strip()
        if not setting:
            return min(2, available_cores())
        source, threads = f"environment variable {THREADS_VARIABLE}", setting
    try:
        count = int(threads)
    except (TypeError, ValueError):
        count = 0
    if count < 1 or str(count) != str(threads).strip():
        raise OptionError(f"{source} {threads!r} is not valid: give a whole number of threads, at least 1")
    return count


def thread_map(function, items, threads: int) -> list:
    """``[function(item) for item in items]``, in up to ``threads`` threads; results in the order of ``items``.

    An exception in any call is raised here, as the loop would raise it.
    """
    items = list(items)
    if threads <= 1 or len(items) <= 1:
        return [function(item) for item in items]
    workers = min(threads, len(items))
    counted = _CORES.inside()  # a search of a person's entry point: each item running is a busy thread of the record

    def run(item):
        _count(counted, 1)
        _CORES.local.inside = counted
        try:
            return function(item)
        finally:
            _CORES.local.inside = False
            _count(counted, -1)

    _count(counted, -1)  # the caller waits for its workers
    try:
        with ThreadPoolExecutor(max_workers=workers) as pool:
            return list(pool.map(run, items))
    finally:
        _count(counted, 1)


def _count(counted: bool, change: int) -> None:
    if counted:
        with _CORES.lock:
            _CORES.busy += change


class _Cores:
    """The threads a record's searches may use (``capacity``, set by the outermost entry point) and those busy now.

    ``local.inside``: whether the current thread runs inside an entry point's searches (counted in ``busy``).
    """

    def __init__(self):
        self.lock = threading.Lock()
        self.capacity = 0
        self.busy = 0
        self.local = threading.local()

    def inside(self) -> bool:
        return getattr(self.local, "inside", False)


_CORES = _Cores()


def record_cores(function):
    """A decorator of the person's entry points: the call's searches may keep ``threads`` threads busy.

    ``threads`` is the function's own argument (None: :func:`search_threads`). The outermost call sets how many
    threads the record may use; a call made inside it (``fit_effects`` under ``identify_person``, ``diagnose``'s
    candidates in threads) counts as part of it. :func:`thread_map`'s workers count as busy threads while they
    run, and :func:`spare_thread` lends an idle one to a derivative pass.
    """
    signature = inspect.signature(function)

    @functools.wraps(function)
    def counted(*args, **kwargs):
        if _CORES.inside():
            return function(*args, **kwargs)
        threads = search_threads(signature.bind_partial(*args, **kwargs).arguments.get("threads"))
        with _CORES.lock:
            if _CORES.busy == 0:
                _CORES.capacity = threads
            _CORES.busy += 1
        _CORES.local.inside = True
        try:
            return function(*args, **kwargs)
        finally:
            _CORES.local.inside = False
            with _CORES.lock:
                _CORES.busy -= 1

    return counted


@contextlib.contextmanager
def spare_thread():
    """``with spare_thread() as spare:`` ``spare`` is True when one of the record's threads is idle, and it is then
    counted as busy until the block ends; False outside a person's entry point (:func:`record_cores`)."""
    with _CORES.lock:
        spare = _CORES.inside() and _CORES.busy < _CORES.capacity
        if spare:
            _CORES.busy += 1
    try:
        yield spare
    finally:
        if spare:
            with _CORES.lock:
                _CORES.busy -= 1


def spare_halves(first, second):
    """``(first(), second())`` with ``second()`` run in an idle thread of the record while ``first()`` runs here, or
    None (and nothing run) when no thread is idle (:func:`spare_thread`). An error in either is raised here."""
    with spare_thread() as spare:
        if not spare:
            return None
        other = {}

        def run_second():
            try:
                other["out"] = second()
            except BaseException as exc:  # raised in the caller's thread below, not printed by the helper's
                other["error"] = exc

        helper = threading.Thread(target=run_second, name="smd-spare")
        helper.start()
        try:
            here = first()
        finally:
            helper.join()
    if "error" in other:
        raise other["error"]
    return here, other["out"]


def spare_map(function, items) -> list:
    """``[function(item) for item in items]``, the second half in an idle thread of the record when there is one
    (:func:`spare_halves`): the same list either way (the likelihoods of a search's many trial starts)."""
    items = list(items)
    half = len(items) // 2
    halves = spare_halves(lambda: [function(item) for item in items[:half]],
                          lambda: [function(item) for item in items[half:]]) if len(items) > 1 else None
    return [function(item) for item in items] if halves is None else halves[0] + halves[1]


def spare_best(function, items):
    """The first of ``items`` with the largest ``function`` value, as ``max(items, key=function)`` takes it, the
    values computed by :func:`spare_map` (a search's trial starts by their likelihood)."""
    items = list(items)
    if len(items) == 1:
        return items[0]
    values = spare_map(function, items)
    return items[max(range(len(items)), key=values.__getitem__)]


def one_blas_thread(function):
    """``function`` run with the BLAS libraries that numpy and scipy call limited to one thread.

    A decorator of the person's entry points (:func:`~smd_statespace.person.fit.identify_person`,
    :func:`~smd_statespace.person.extend.fit_effects`, :func:`~smd_statespace.person.diagnose.diagnose_person`).
    The limit is the process's (BLAS has one setting), so it is counted: the first call to enter sets it
    (threadpoolctl's ``threadpool_limits``), calls nested in it or running at the same time in other threads
    (``diagnose`` fits its candidates in threads) keep it, and the last to leave gives the caller's setting back,
    also after an error. (Each call setting and restoring on its own gave, for two calls in threads where the first
    to enter left first, the second call the caller's threads back while it ran, and the caller one thread after.)
    """

    @functools.wraps(function)
    def limited(*args, **kwargs):
        with _BLAS_LIMIT["lock"]:
            if _BLAS_LIMIT["calls"] == 0:
                from threadpoolctl import threadpool_limits  # imported when a fit runs: the CLI starts without it

                _BLAS_LIMIT["limiter"] = threadpool_limits(limits=1, user_api="blas")
            _BLAS_LIMIT["calls"] += 1
        try:
            return function(*args, **kwargs)
        finally:
            with _BLAS_LIMIT["lock"]:
                _BLAS_LIMIT["calls"] -= 1
                if _BLAS_LIMIT["calls"] == 0:
                    _BLAS_LIMIT.pop("limiter").restore_original_limits()

    return limited


_BLAS_LIMIT = {"lock": threading.Lock(), "calls": 0}
"""The limit of :func:`one_blas_thread`: the calls inside it now, and the limiter that set it."""
