"""The phases of an exact stick-slip run sample by sample, and the robot set to them: how
:func:`robotdyn.contact.traction.traction` reports such a run's loads and friction forces.

The stick-slip engine (:mod:`robotdyn.simulation.stick_slip`) records each output sample's phases
(:func:`recorded_phases`, gathered by :func:`phase_table` into ``stats["phases"]``). A wheel's contact force at a
sample depends on its phase there: sticking, its tangential force is a constraint force (the required friction
:math:`\\|f_t\\|/f_n` is what it needs, at most its mu); sliding, it is Coulomb's :math:`\\mu f_n` opposite to the slip.
:func:`phase_states` sets the robot to each sample's phases (:meth:`StickSlipWheel.set_phase` and
:func:`~robotdyn.contact.stick_slip_wheel.configure`, as the run did) so that the traction pass evaluates
:func:`~robotdyn.contact.contact_forces.constraint_forces` there, and restores the robot afterwards.

A stick-slip wheel's friction coefficient is its law's: the run already switched it by that mu, so another one for
the traction check (``simulate --mu``) is refused (:func:`check_mu`), and the same one is accepted.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .stick_slip_wheel import StickSlipWheel, configure, phase_lock, stick_slip_wheels


@dataclass(eq=False)
class PhaseTable:
    """The phases of a stick-slip run's stick-slip wheels at every output sample.

    Attributes:
        wheels: The stick-slip wheels' names (W), in the robot's constraint order.
        sliding: (N, W) ``True`` where that wheel slides at that sample.
        direction: (N, W, 2) a sliding wheel's initial slip direction in (t1, t2) of its contact frame (zeros
            where it sticks): its friction direction while its slip speed is below
            :data:`~robotdyn.contact.stick_slip_wheel.SLIP_ZERO`.
    """

    wheels: list[str]
    sliding: np.ndarray
    direction: np.ndarray


def recorded_phases(wheels: list[StickSlipWheel]) -> list[tuple[bool, np.ndarray]]:
    """One sample's phases: ``(sliding, direction (2,))`` per wheel (direction zeros where it sticks).

    Args:
        wheels: The robot's :class:`~robotdyn.contact.stick_slip_wheel.StickSlipWheel` constraints.

    Returns:
        A list of ``(sliding, direction)`` in the order of ``wheels``.
    """
    return [(w.phase == "slide", np.zeros(2) if w.direction is None else np.array(w.direction, float))
            for w in wheels]


def phase_table(names: list[str], samples: list, n: int) -> PhaseTable:
    """The :class:`PhaseTable` of a run from its samples' :func:`recorded_phases`.

    Args:
        names: The stick-slip wheels' names (W).
        samples: One :func:`recorded_phases` list per output sample (n of them).
        n: Number of output samples.

    Returns:
        The table (N = n).
    """
    sliding = np.array([[s for s, _ in row] for row in samples], bool).reshape(n, len(names))
    direction = np.array([[d for _, d in row] for row in samples], float).reshape(n, len(names), 2)
    return PhaseTable(list(names), sliding, direction)


def phases_of(traj) -> PhaseTable | None:
    """The phase table of a stick-slip trajectory (``None`` for any other run).

    Args:
        traj: A :class:`~robotdyn.simulation.trajectory.Trajectory`.

    Returns:
        ``traj.stats["phases"]`` where it is a :class:`PhaseTable` whose rows match the samples, else ``None``.
    """
    table = getattr(traj, "stats", {}).get("phases")
    return table if isinstance(table, PhaseTable) and len(table.sliding) == len(traj.t) else None


def check_mu(robot, mu) -> None:
    """Refuse a friction coefficient for the traction check that differs from a stick-slip wheel's own.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        mu: ``None``, one coefficient for every wheel, or a dict by wheel name (as
            :func:`robotdyn.contact.traction.traction` takes it).

    Raises:
        InputError: A stick-slip wheel given another mu than its law's (one line naming both values).
    """
    if mu is None:
        return
    for w in stick_slip_wheels(robot):
        value = mu.get(w.name) if isinstance(mu, dict) else mu
        if value is not None and abs(float(value) - w.mu) > 1e-12 * max(1.0, w.mu):
            raise InputError(f"mu = {float(value):g} for wheel {w.name!r}, whose friction law (friction = "
                             f"'stick_slip') has mu = {w.mu:g}: the run switched it between sticking and sliding by "
                             "that mu; omit --mu (the law's mu is the one checked) or change mu in the wheel's "
                             "[[wheels]] entry")


@contextmanager
def phase_states(robot, traj, table: PhaseTable) -> Iterator[Callable[[int], np.ndarray]]:
    """Set the robot to each sample's phases in turn, restoring its phases and projection on exit.

    Args:
        robot: The :class:`~robotdyn.robot.Robot` the trajectory was simulated with.
        traj: The stick-slip :class:`~robotdyn.simulation.trajectory.Trajectory` (its velocities are the full v).
        table: Its :class:`PhaseTable`.

    Yields:
        ``state(i)``: sets the phases of sample i and returns its independent velocities (k,) for the phase's
        projection (the entries of v at the independent coordinates).
    """
    wheels = {w.name: w for w in stick_slip_wheels(robot)}
    if sorted(wheels) != sorted(table.wheels):
        raise InputError(f"the trajectory's stick-slip wheels {', '.join(table.wheels)} are not the robot's "
                         f"({', '.join(wheels) or 'none'}); expected the robot it was simulated with")
    with phase_lock(robot):  # (another thread's run or pass switches the same wheels: they take turns)
        yield from _phase_states(robot, traj, table, wheels)


def _phase_states(robot, traj, table: PhaseTable, wheels: dict) -> Iterator[Callable[[int], np.ndarray]]:
    """:func:`phase_states`' body, under the robot's phase lock."""
    saved = ({n: (w.phase, w.direction) for n, w in wheels.items()}, robot.independent_indices,
             list(robot.velocity_names), robot._projection_hint)

    last = {}

    def state(i: int) -> np.ndarray:
        key = (table.sliding[i].tobytes(), table.direction[i].tobytes())
        if last.get("key") != key:  # the projection is rebuilt where the phases change, as in the run
            for j, name in enumerate(table.wheels):
                if table.sliding[i, j]:
                    wheels[name].set_phase("slide", table.direction[i, j])
                else:
                    wheels[name].set_phase("stick")
            configure(robot, traj.q[i])
            last["key"] = key
        return np.asarray(traj.nu[i], float)[robot.independent_indices]

    try:
        yield state
    finally:
        phases, robot.independent_indices, robot.velocity_names, robot._projection_hint = saved
        for name, (phase, direction) in phases.items():
            wheels[name].set_phase(phase, direction)
