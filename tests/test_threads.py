"""One robot used from several threads at once: the compiled fast path (whose compute() returns views of its
buffers) and the Python path (Pinocchio's data) give every thread its own buffers, so concurrent results equal the
single-threaded ones (issue 15: before, concurrent calls returned wrong numbers, off by up to 1e285). A thread's
compiled model may choose other independent rows than the main thread's, so results agree to round-off (1e-12)
rather than bit for bit. The interpreter switches threads every microsecond here, to provoke the races.)"""

from __future__ import annotations

import sys
import threading

import numpy as np
import pytest

import robotdyn
from robotdyn.fast.dispatch import compiled_model


@pytest.mark.parametrize("name", ["quasimoro", "linkage_suspension"])
def test_concurrent_evaluations_equal_sequential(name):
    robot = robotdyn.load(name)
    rng = np.random.default_rng(1)
    q = robot.neutral()
    nus = rng.normal(size=(200, robot.mobility))
    fast = compiled_model(robot)
    expected_fast = [tuple(np.array(x) for x in fast.compute(q, nu)) if fast else None for nu in nus]
    expected_py = [robot.reduced(q, nu).h.copy() for nu in nus]
    errors = []

    def work(offset):
        local = compiled_model(robot)
        for i in np.roll(np.arange(len(nus)), offset):
            if local is not None:
                out = local.compute(q, nus[i])
                got = tuple(np.array(x) for x in out)  # read right away: the views belong to this thread
                if not all(np.allclose(a, b, rtol=1e-12, atol=1e-12) for a, b in zip(got, expected_fast[i])):
                    errors.append(("compiled", i))
            if not np.allclose(robot.reduced(q, nus[i]).h, expected_py[i], rtol=1e-12, atol=1e-12):
                errors.append(("reduced", i))

    threads = [threading.Thread(target=work, args=(k * 37,)) for k in range(4)]
    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    try:
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    finally:
        sys.setswitchinterval(interval)
    assert errors == []


def test_robot_pickles_without_its_thread_caches():
    """A robot (e.g. sent to a worker process) pickles after use; the copy rebuilds its caches and gives the same
    numbers."""
    import pickle

    robot = robotdyn.load("quasimoro")
    q, nu = robot.neutral(), np.array([0.3, -0.2, 0.1])
    h = robot.reduced(q, nu).h.copy()
    compiled_model(robot)
    copy = pickle.loads(pickle.dumps(robot))
    np.testing.assert_array_equal(copy.reduced(q, nu).h, h)
