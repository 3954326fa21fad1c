"""Many evaluations or simulations in one call (design sweeps, learning data sets).

:func:`simulate_many` (from :mod:`robotdyn.simulation.many_runs`) runs N simulations of one robot's variants -- per-run
parameters (masses, inertias, lengths: :mod:`robotdyn.simulation.model_variants`) or built robots, initial states and torque
profiles -- in C++ on the machine's cores (threads, the GIL released, one model copy per thread), returning arrays
per run (:class:`ManyRuns`).

:func:`evaluate` returns stacked arrays, ``M`` (N, k, k), ``h`` (N, k), ``g`` (N, k), ``B`` (N, k, m) and ``S``
(N, n, k), for N states, optionally spread over worker processes (one robot copy per process, inherited by
fork): by the robot's compiled model (:mod:`robotdyn.fast.compiled`) in one call per chunk where it serves the robot,
else one state at a time. A state where the constraints are singular raises
:class:`~robotdyn.errors.SingularConstraintError` naming its index.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import time
from dataclasses import dataclass

import numpy as np

from ..fast.dispatch import compiled_model
from ..errors import RobotDynError, SingularConstraintError

_WORKER_ROBOT = None
PROBE = 256
"""States :func:`evaluate` times in its own process before it decides whether worker processes pay off."""
MIN_WORK_PER_PROCESS = 0.1
"""Least estimated work [s] per worker process for :func:`evaluate` to start them: forking a pool of two and shutting
it down cost 20-60 ms here (measured on 2 cores, beside the 8 ms that 1000 compiled states take), so below this the
states are evaluated in the calling process."""


@dataclass
class Batch:
    """Reduced models at N states (arrays stacked along the first axis).

    Attributes:
        M: Reduced mass matrices (N, k, k) [kg, kg m^2].
        h: Biases C_r nu + g_r (N, k) [N, N m].
        g: Gravity terms g_r (N, k) [N, N m].
        B: Reduced input matrices (N, k, motors).
        S: Velocity maps (N, n, k) with v = S nu.
    """

    M: np.ndarray
    h: np.ndarray
    g: np.ndarray
    B: np.ndarray
    S: np.ndarray

    def __len__(self) -> int:
        return self.M.shape[0]

    def __repr__(self) -> str:
        return f"Batch(N={len(self)}, k={self.M.shape[1]})"


def _reduced_named(robot, q: np.ndarray, nu: np.ndarray, index: int):
    """``robot.reduced(q, nu)``, with a singular state's index in the error message."""
    try:
        return robot.reduced(q, nu)
    except SingularConstraintError as exc:
        raise SingularConstraintError(f"state {index}: {exc}", exc.condition) from None


def _evaluate_compiled(robot, fast, Q: np.ndarray, NU: np.ndarray, offset: int) -> tuple[np.ndarray, ...]:
    """All states in one call of the robot's compiled model (:mod:`robotdyn.fast.compiled`); states where its row
    choice does not apply are evaluated one by one by :meth:`Robot.reduced`."""
    if not fast.ready:  # the Python path chooses the projection's rows at the first state
        _reduced_named(robot, Q[0], NU[0], offset)
    M, h, g, S, _, B, failed = fast.evaluate_many(Q, NU)
    for i in failed:
        red = _reduced_named(robot, Q[i], NU[i], offset + i)
        M[i], h[i], g[i], B[i], S[i] = red.M, red.h, red.g, red.B, red.S
    return M, h, g, B, S


def _evaluate_chunk(robot, Q: np.ndarray, NU: np.ndarray, offset: int) -> tuple[np.ndarray, ...]:
    fast = compiled_model(robot)
    if len(Q) and fast is not None:
        return _evaluate_compiled(robot, fast, Q, NU, offset)
    return _evaluate_loop(robot, Q, NU, offset)


def _evaluate_loop(robot, Q: np.ndarray, NU: np.ndarray, offset: int) -> tuple[np.ndarray, ...]:
    N, k = len(Q), robot.mobility
    M = np.empty((N, k, k))
    h = np.empty((N, k))
    g = np.empty((N, k))
    B = np.empty((N, k, len(robot.motors)))
    S = np.empty((N, robot.nq, k))
    for i in range(N):
        red = _reduced_named(robot, Q[i], NU[i], offset + i)
        M[i], h[i], g[i], B[i], S[i] = red.M, red.h, red.g, red.B, red.S
    return M, h, g, B, S


def _worker(args):
    Q, NU, offset = args
    return _evaluate_chunk(_WORKER_ROBOT, Q, NU, offset)


def _default_sigterm() -> None:
    """A forked worker's SIGTERM back to the default (end the process): the pool ends its workers with SIGTERM, and
    a handler inherited from the parent (the CLI's, which raises KeyboardInterrupt) left a worker blocked on the
    pool's queue lock alive, so that the pool's exit waited for it forever (seen once in the test suite). The
    workers are forked with SIGTERM blocked (:func:`evaluate`) and unblock it only here, after the default is back: a
    SIGTERM that came between the fork and this line used to trip the inherited Python handler, which the default
    installed here then discarded (CPython skips a tripped signal whose handler is now SIG_DFL), so the worker lived
    on, waiting for tasks, and the pool's exit joined it forever (seen in tests/test_batch.py under load)."""
    import signal

    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGTERM})  # a SIGTERM already sent now ends the worker


def evaluate(robot, Q, NU, processes: int | None = 1) -> Batch:
    """The reduced model of ``robot`` at the states (Q[i], NU[i]).

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.
        Q: Natural coordinates, shape (N, n).
        NU: Independent velocities, shape (N, k).
        processes: Worker processes (``None``: one per CPU; 1: in this process). Workers are started only where
            the first :data:`PROBE` states, timed here, let the rest take at least :data:`MIN_WORK_PER_PROCESS`
            per worker (with the compiled model, some 3e5 states/s per process: batches of about 6e4 states and
            more); smaller batches are evaluated here, the same numbers without the workers' start-up.

    Returns:
        A :class:`Batch` of the reduced model at the N states (arrays stacked along a first axis of length N).

    Raises:
        RobotDynError: Wrong shapes or non-finite entries.
        SingularConstraintError: At a singular state (its index is named).
    """
    Q, NU = np.asarray(Q, dtype=float), np.asarray(NU, dtype=float)
    if Q.ndim != 2 or Q.shape[1] != robot.nq:
        raise RobotDynError(f"Q has shape {Q.shape}; expected (N, {robot.nq}) ({', '.join(robot.coordinates)})")
    if NU.shape != (len(Q), robot.mobility):
        raise RobotDynError(f"NU has shape {NU.shape}; expected ({len(Q)}, {robot.mobility})")
    if not (np.all(np.isfinite(Q)) and np.all(np.isfinite(NU))):
        raise RobotDynError("Q and NU must be finite (found NaN or inf)")
    processes = (os.cpu_count() or 1) if processes is None else int(processes)
    if processes <= 1 or len(Q) < 2 * processes or "fork" not in mp.get_all_start_methods():
        return Batch(*_evaluate_chunk(robot, Q, NU, 0))
    head = min(len(Q), PROBE + 1)  # (the first state alone: it may choose the projection's rows)
    parts = [_evaluate_chunk(robot, Q[:1], NU[:1], 0)]
    start = time.perf_counter()
    parts.append(_evaluate_chunk(robot, Q[1:head], NU[1:head], 1))
    per_state = (time.perf_counter() - start) / max(head - 1, 1)
    if (len(Q) - head) * per_state / processes < MIN_WORK_PER_PROCESS:
        parts.append(_evaluate_chunk(robot, Q[head:], NU[head:], head))
    else:
        global _WORKER_ROBOT
        _WORKER_ROBOT = robot
        bounds = np.linspace(head, len(Q), processes + 1).astype(int)
        chunks = [(Q[a:b], NU[a:b], a) for a, b in zip(bounds[:-1], bounds[1:])]
        try:
            import signal

            mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGTERM})  # until _default_sigterm: see there
            try:
                pool = mp.get_context("fork").Pool(processes, initializer=_default_sigterm)
            finally:
                signal.pthread_sigmask(signal.SIG_SETMASK, mask)
            with pool:
                parts += pool.map(_worker, chunks)
        finally:
            _WORKER_ROBOT = None
    return Batch(*(np.concatenate([p[j] for p in parts]) for j in range(5)))


from .many_runs import ManyRuns, simulate_many  # noqa: E402  (many simulations: robotdyn.many_runs)

__all__ = ["Batch", "evaluate", "ManyRuns", "simulate_many"]
