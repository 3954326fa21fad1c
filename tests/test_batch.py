"""Batch evaluation equals one-by-one evaluation, in one process and in worker processes."""

from __future__ import annotations

import numpy as np
import pytest

import robotdyn.simulation.batch as batch
from robotdyn.simulation.batch import evaluate
from robotdyn.errors import RobotDynError


def _started(monkeypatch) -> list:
    """Record each pool of workers evaluate() starts."""
    started, context = [], batch.mp.get_context
    monkeypatch.setattr(batch.mp, "get_context", lambda method: started.append(method) or context(method))
    return started


def test_batch_equals_single_evaluations(quasimoro, monkeypatch):
    rng = np.random.default_rng(0)
    Q = rng.uniform(-2, 2, (400, quasimoro.nq))  # (the probe's 257 states here, the rest in two workers)
    NU = rng.normal(size=(400, quasimoro.mobility))
    serial = evaluate(quasimoro, Q, NU, processes=1)
    monkeypatch.setattr(batch, "MIN_WORK_PER_PROCESS", 0.0)  # (workers whatever the work)
    started = _started(monkeypatch)
    parallel = evaluate(quasimoro, Q, NU, processes=2)
    assert started == ["fork"]
    for i in (0, 17, 399):
        red = quasimoro.reduced(Q[i], NU[i])
        assert np.allclose(serial.M[i], red.M, atol=1e-15) and np.allclose(serial.h[i], red.h, atol=1e-15)
    for name in ("M", "h", "g", "B", "S"):
        assert np.array_equal(getattr(serial, name), getattr(parallel, name))


def test_batch_shape_errors(quasimoro):
    with pytest.raises(RobotDynError, match=r"Q has shape \(3, 5\); expected \(N, 6\)"):
        evaluate(quasimoro, np.zeros((3, 5)), np.zeros((3, 3)))
    with pytest.raises(RobotDynError, match="NaN"):
        evaluate(quasimoro, np.full((2, 6), np.nan), np.zeros((2, 3)))


def test_small_batches_start_no_workers(quasimoro, monkeypatch):
    """2000 compiled states take some 10 ms, less than forking two workers and shutting them down (20-60 ms
    measured): evaluated in this process, the same numbers."""
    rng = np.random.default_rng(1)
    Q = rng.uniform(-2, 2, (2000, quasimoro.nq))
    NU = rng.normal(size=(2000, quasimoro.mobility))
    serial = evaluate(quasimoro, Q, NU, processes=1)
    started = _started(monkeypatch)
    two = evaluate(quasimoro, Q, NU, processes=2)
    assert started == []
    for name in ("M", "h", "g", "B", "S"):
        assert np.array_equal(getattr(serial, name), getattr(two, name))


def test_workers_end_on_sigterm_whatever_handler_the_parent_has(quasimoro, monkeypatch, capfd):
    """The pool ends its workers with SIGTERM; a handler inherited from the parent (the CLI's raises
    KeyboardInterrupt, and stays installed when the CLI runs in-process) must not run in them: it left a worker dead
    while holding the pool's queue lock and its sibling blocked on it, and the pool's exit waiting forever."""
    import signal

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    old = signal.signal(signal.SIGTERM, interrupt)
    try:
        monkeypatch.setattr(batch, "MIN_WORK_PER_PROCESS", 0.0)
        rng = np.random.default_rng(1)
        Q, NU = rng.uniform(-2, 2, (300, quasimoro.nq)), rng.normal(size=(300, quasimoro.mobility))
        for _ in range(20):
            evaluate(quasimoro, Q, NU, processes=2)
    finally:
        signal.signal(signal.SIGTERM, old)
    assert "KeyboardInterrupt" not in capfd.readouterr().err  # no worker ran the parent's handler
