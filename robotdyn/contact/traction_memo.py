"""Work the per-sample traction pass did twice at one state, done once (the same numbers, bit for bit).

Where :func:`robotdyn.contact.traction.traction` computes the loads sample by sample
(:func:`~robotdyn.contact.contact_forces.constraint_forces`), one call evaluates some things twice at the same state:

- a compliant wheel's contact state (:meth:`~robotdyn.contact.compliant_contact.CompliantWheel.state`: its geometry
  on the terrain, Jacobian, penetration gradient and force law), once in the forward dynamics
  (:func:`robotdyn.contact.compliant_rolling.forward`, through :func:`robotdyn.contact.applied_forces.applied`) and
  once in the force solve: most of a sample's cost on ``examples/bump_base_rolling.toml``;
- the reduced model (:meth:`robotdyn.robot.Robot.reduced`, the Python reference for a robot without a compiled
  model, e.g. with stick-slip wheels), once in ``constraint_forces`` and once in the forward dynamics of sliding
  wheels (:func:`robotdyn.contact.sliding.forward`): most of a stick-slip run's traction pass.

:func:`once_per_sample` keeps the last value of each and hands it back (wheel states as copies) when the next call is
at the same arguments bit for bit; the reduced model only within one sample (the pass calls ``next_sample()`` before
each, since a stick-slip run's phases change the projection between samples). On exit the robot is as before;
a copy or pickle made during a pass carries no memory (``Robot.__getstate__`` and
``CompliantWheel.__getstate__`` drop them).

A memory serves only the thread whose pass installed it (another thread's calls go straight to the method), and a
pass leaves alone what another pass (in any thread) has already wrapped: that pass then runs without it.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import numpy as np

from .compliant_contact import compliant_wheels

_LOCK = threading.Lock()  # (installing and removing the memories)


class _StateMemo:
    """One wheel's ``state(kin)`` with a one-entry memory keyed by the state's (q, v) bytes; ``hits`` counts reuses."""

    def __init__(self, method) -> None:
        self.method, self.key, self.value, self.hits = method, None, None, 0
        self.thread = threading.get_ident()

    def __call__(self, kin) -> dict:
        if threading.get_ident() != self.thread:  # (another thread's call: not this pass's)
            return self.method(kin)
        key = (np.asarray(kin.q, float).tobytes(), np.asarray(kin.v, float).tobytes())
        if key != self.key:
            self.key = None  # (a raise leaves no stale entry)
            self.value = self.method(kin)
            self.key = key
        else:
            self.hits += 1
        return {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in self.value.items()}


class _ReducedMemo:
    """The robot's ``reduced(q, nu, coriolis)`` with a one-entry memory keyed by its arguments' bytes, emptied by
    :meth:`clear`; ``hits`` counts reuses."""

    def __init__(self, method) -> None:
        self.method, self.key, self.value, self.hits = method, None, None, 0
        self.thread = threading.get_ident()

    def __call__(self, q, nu, coriolis: bool = False):
        if threading.get_ident() != self.thread:
            return self.method(q, nu, coriolis)
        try:
            key = (np.asarray(q, float).tobytes(), np.asarray(nu, float).tobytes(), bool(coriolis))
        except (TypeError, ValueError):  # (not numbers: the method's own one-line error)
            return self.method(q, nu, coriolis)
        if key != self.key:
            self.key = None
            self.value = self.method(q, nu, coriolis)
            self.key = key
        else:
            self.hits += 1
        return self.value

    def clear(self) -> None:
        self.key = self.value = None


@contextmanager
def once_per_sample(robot) -> Iterator[Callable[[], None]]:
    """Within the block, each compliant wheel of ``robot`` computes its contact state once per (q, v), and the
    robot its reduced model once per (q, nu) between two calls of the yielded ``next_sample``.

    Args:
        robot: The :class:`~robotdyn.robot.Robot` whose traction pass runs in the block.

    Yields:
        ``next_sample()``: forget the reduced model (call it before each sample). Its attribute ``memos`` lists the
        memories installed (the wheels' in constraint order, then the robot's; their ``hits``: evaluations saved).
    """
    owners = [*compliant_wheels(robot), robot]
    names = ["state"] * (len(owners) - 1) + ["reduced"]
    installed = []  # (owner, name, memory)
    with _LOCK:
        for o, n in zip(owners, names):
            if n in o.__dict__:  # (another pass's memory, or the owner's own attribute: left alone)
                continue
            memo = _StateMemo(o.state) if n == "state" else _ReducedMemo(o.reduced)
            setattr(o, n, memo)  # (an instance attribute over the class's method)
            installed.append((o, n, memo))
    reduced = [m for o, n, m in installed if n == "reduced"]

    def next_sample() -> None:
        for memo in reduced:
            memo.clear()

    next_sample.memos = [m for _, _, m in installed]
    try:
        yield next_sample
    finally:
        with _LOCK:
            for o, n, memo in installed:
                if o.__dict__.get(n) is memo:
                    del o.__dict__[n]


__all__ = ["once_per_sample"]
