"""One robot used from several threads at once: the compiled fast path (whose compute() returns views of its
buffers) and the Python path (Pinocchio's data) give every thread its own buffers, so concurrent results equal the
single-threaded ones (issue 15: before, concurrent calls returned wrong numbers, off by up to 1e285). A thread's
compiled model may choose other independent rows than the main thread's, so results agree to round-off (1e-12)
rather than bit for bit. The interpreter switches threads every microsecond here, to provoke the races.)"""

from __future__ import annotations

import threading

import numpy as np
import pytest

import robotdyn
from robotdyn.fast.dispatch import compiled_model

from concurrency import switching_often


def _race(threads) -> None:
    """Start and join ``threads`` with the interpreter switching between them as often as it can (a switch interval
    of 1 us), so that unsynchronised shared state shows."""
    with switching_often():
        for t in threads:
            t.start()
        for t in threads:
            t.join()


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
    _race(threads)
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


def test_use_compiled_is_local_to_its_thread():
    """Issue 24: use_compiled(False) was a process-wide global that each block saved and restored. Two threads whose
    blocks interleave (A enters, B enters, A leaves, B leaves) left it off for the whole process: B restored the
    False it had saved while A was inside. Now the switch is a ContextVar: inside a block only the calling thread
    sees the fast path off, the main thread meanwhile does not, and afterwards every thread has it on again."""
    from robotdyn.fast.dispatch import enabled, use_compiled

    if not enabled():
        pytest.skip("the compiled fast path is off here")
    steps = [threading.Event() for _ in range(4)]  # A in, B in, A out, B out (each waits for the one before)
    seen = {}

    def a():
        with use_compiled(False):
            seen["A inside"] = enabled()
            steps[0].set()
            steps[1].wait(5)
        steps[2].set()

    def b():
        steps[0].wait(5)
        with use_compiled(False):
            seen["B inside"] = enabled()
            steps[1].set()
            seen["main while both inside"] = None
            steps[2].wait(5)
        steps[3].set()

    threads = [threading.Thread(target=a), threading.Thread(target=b)]
    for t in threads:
        t.start()
    steps[1].wait(5)
    main_inside = enabled()  # both threads are inside their blocks now
    for t in threads:
        t.join()
    assert steps[3].is_set()
    assert seen["A inside"] is False and seen["B inside"] is False
    assert main_inside is True
    assert enabled() is True
    after = {}
    t = threading.Thread(target=lambda: after.setdefault("enabled", enabled()))
    t.start()
    t.join()
    assert after["enabled"] is True


def test_many_threads_switching_leave_the_fast_path_on():
    """The issue's report: four threads running with use_compiled(False) while others use the fast path. Afterwards
    simulate_many (which needs the compiled model) still runs, and no thread ever saw another's switch."""
    from robotdyn.fast.dispatch import enabled, use_compiled
    from robotdyn.simulation.many_runs import simulate_many

    if not enabled():
        pytest.skip("the compiled fast path is off here")
    robot = robotdyn.load("quasimoro")
    q = robot.neutral()
    wrong = []

    def off():
        for _ in range(200):
            with use_compiled(False):
                if compiled_model(robot) is not None:
                    wrong.append("off block saw a compiled model")

    def on():
        for _ in range(200):
            if compiled_model(robot) is None:
                wrong.append("the fast path was off outside any block")

    threads = [threading.Thread(target=off) for _ in range(4)] + [threading.Thread(target=on) for _ in range(2)]
    _race(threads)
    assert wrong == []
    assert enabled()
    runs = simulate_many(robot, 0.2, q0=np.tile(q, (2, 1)), nu0=[[0.1, 0.0, 0.0], [0.0, 0.1, 0.0]], n_out=3,
                         threads=1, progress=False)
    assert runs.ok.all()


def test_compiled_model_refuses_a_thread_that_does_not_own_it():
    """Issue 24: a CompiledModel handed to other threads gave wrong numbers in about one call in ten (its buffers
    are overwritten by the other threads' calls). Now every evaluation from a thread that did not build it raises
    a one-line ThreadError; the owning thread and compiled_model(robot) in the other thread still work, and the
    other thread's own model gives the owner's numbers to round-off."""
    from robotdyn.fast.compiled import ThreadError

    robot = robotdyn.load("quasimoro")
    fast = compiled_model(robot)
    if fast is None:
        pytest.skip("quasimoro is not compiled here")
    q, nu = robot.neutral(), np.array([0.3, -0.2, 0.1])
    h = np.array(fast.compute(q, nu)[1])
    caught, own = [], {}

    def other():
        for call in (lambda: fast.compute(q, nu), lambda: fast.reduced(q, nu), lambda: fast.evaluate(q, nu),
                     lambda: fast.rhs(q, nu, np.zeros(len(robot.motors)), 10.0),
                     lambda: fast.forces(q, nu, np.zeros(len(robot.motors)))):
            try:
                call()
            except ThreadError as exc:
                caught.append(str(exc))
        mine = compiled_model(robot)
        own["same object"] = mine is fast
        own["h"] = np.array(mine.compute(q, nu)[1])

    t = threading.Thread(target=other)
    t.start()
    t.join()
    assert len(caught) == 5 and all("\n" not in m and "thread" in m for m in caught)
    assert own["same object"] is False
    np.testing.assert_allclose(own["h"], h, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(np.array(fast.compute(q, nu)[1]), h)  # the owner is unaffected


def test_newest_compiled_paths_from_two_threads_equal_serial_bit_for_bit():
    """The compiled paths added by issues 23 and 26, called from two threads at once on one Robot: unchecked
    dynamics derivatives, compiled contact-force and required-mu derivatives, a compiled controller run (MMR12-EOD
    ``orientation``: operational-space feedback as data) and a compiled rolling compliant run (``bump_base_rolling``,
    switching at touch-down in Python between compiled segments). Each thread's results equal the serial ones bit
    for bit (every thread builds its own compiled model, with the same rows as the serial call's)."""
    from pathlib import Path

    from robotdyn.interfaces.constraint_file import read
    from robotdyn.robots import module

    linkage = robotdyn.load("linkage_suspension")
    rng = np.random.default_rng(3)
    states = [(linkage.neutral(), rng.normal(size=linkage.mobility), rng.normal(size=len(linkage.motors)))
              for _ in range(8)]
    mmr = robotdyn.load("mmr12_eod")
    orientation = module("mmr12_eod").SCENARIOS["orientation"]
    bump = read(Path(__file__).resolve().parents[1] / "examples" / "bump_base_rolling.toml")
    base = bump.robot()

    def derivatives():
        return [x for d in (linkage.dynamics_derivatives(*s, check=False) for s in states)
                for x in (d.nudot, d.dq, d.dnu, d.dtau)]

    def forces():
        return [x for f in (linkage.contact_force_derivatives(*s) for s in states)
                for x in (f.force, f.dforce_dq, f.dforce_dnu, f.dforce_dtau, f.required_mu, f.dmu_dq)]

    def controller():
        tr = orientation.run(mmr, t_end=0.1, n_out=11, progress=False)
        assert tr.stats["engine"].startswith("compiled")
        return [tr.q, tr.nu]

    def compliant():
        tr = bump.SCENARIOS["bump"].run(base, t_end=0.1, n_out=11, progress=False)
        assert tr.stats["engine"].startswith("compiled")
        return [tr.q, tr.nu]

    for work in (derivatives, forces, controller, compliant):
        serial = work()
        results: list = [None, None]

        def run(i, work=work):
            results[i] = work()

        _race([threading.Thread(target=run, args=(i,)) for i in range(2)])
        for got in results:
            assert got is not None and all(np.array_equal(a, b) for a, b in zip(got, serial)), work.__name__
