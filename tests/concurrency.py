"""Driving one call from several threads at once and comparing every result with the same call made serially, bit
for bit: the helpers of the tests/test_threads_*.py files.

The interpreter switches threads every microsecond while they run (instead of every 5 ms), and the threads start
together at a barrier, so that state shared without synchronisation shows as wrong numbers or exceptions.
"""

from __future__ import annotations

import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import numpy as np


@contextmanager
def switching_often() -> Iterator[None]:
    """While inside, the interpreter switches threads every microsecond (instead of every 5 ms), so that state
    shared without synchronisation shows; the previous interval is restored on the way out."""
    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    try:
        yield
    finally:
        sys.setswitchinterval(interval)


def race(workers: list[Callable[[], None]], timeout: float = 60.0) -> list[str]:
    """Run ``workers`` in one thread each, released together at a barrier, with the interpreter switching threads
    every microsecond; returns the exceptions they raised (as ``repr``), empty if none.

    Args:
        workers: Functions of no argument, one per thread.
        timeout: Seconds to wait for each thread [s] (a hang fails the caller's assertion, not the session).

    Returns:
        The exceptions raised in the workers, as strings.
    """
    barrier = threading.Barrier(len(workers))
    raised: list[str] = []

    def run(work):
        barrier.wait(timeout)
        try:
            work()
        except Exception as exc:  # noqa: BLE001 - reported to the test, which fails on any
            raised.append(repr(exc))

    threads = [threading.Thread(target=run, args=(w,), daemon=True) for w in workers]
    with switching_often():
        for t in threads:
            t.start()
        for t in threads:
            t.join(timeout)
    return raised + [f"thread {i} still running after {timeout} s" for i, t in enumerate(threads) if t.is_alive()]


def identical(got, expected) -> bool:
    """Whether two lists of results are equal bit for bit (arrays by ``np.array_equal``, NaN equal to NaN; anything
    else by ``==``)."""
    if len(got) != len(expected):
        return False
    return all(_same(a, b) for a, b in zip(got, expected))


def _same(a, b) -> bool:
    if not (isinstance(a, np.ndarray) or isinstance(b, np.ndarray)):
        return a == b
    try:
        return np.array_equal(a, b, equal_nan=True)  # (a NaN where the serial call has one is the same result)
    except TypeError:  # (not numbers)
        return np.array_equal(a, b)


def hammer(calls: dict[str, Callable[[], list]], lanes: list[list[str]], reps: int) -> tuple[list[str], int]:
    """Each call made serially once, then the lanes run at once (one thread per lane, each making its calls in its
    order ``reps`` times); every concurrent result is compared with the serial one bit for bit.

    Args:
        calls: Name -> function of no argument returning a list of results (arrays, strings, numbers).
        lanes: For each thread, the names of the calls it makes, in order.
        reps: How many times each thread goes through its lane.

    Returns:
        ``(problems, made)``: the names of the calls whose results differed and the exceptions raised (empty if
        none), and how many concurrent calls were made.
    """
    serial = {name: f() for name, f in calls.items()}
    wrong: list[str] = []
    made = [0] * len(lanes)  # (one counter per thread: ``+=`` on a shared one is not atomic)

    def lane(i, names):
        def work():
            for _ in range(reps):
                for name in names:
                    if not identical(calls[name](), serial[name]):
                        wrong.append(name)
                    made[i] += 1
        return work

    raised = race([lane(i, names) for i, names in enumerate(lanes)])
    return wrong + raised, sum(made)
