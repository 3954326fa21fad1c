"""A wheel with exact Coulomb friction that sticks (rolls without slipping) or slides, phase by phase.

A :class:`StickSlipWheel` is in one of two phases:

- **stick**: the three rolling rows (longitudinal, lateral, normal) are constraints;
- **slide**: only the normal row is a constraint; the tangential force is Coulomb's :math:`-\\mu f_n \\hat s` with
  :math:`\\hat s = s/\\|s\\|` the slip direction (:math:`\\hat s_0`, the direction the slide started with, while the
  slip speed :math:`\\|s\\|` is below :data:`SLIP_ZERO`).

The events that switch the phases, and the integration segment by segment, are the stick-slip engine's
(:mod:`robotdyn.simulation.stick_slip`).
"""

from __future__ import annotations

import functools
import threading
import weakref

import numpy as np

from ..constraints.rolling_contact import RollingWheel
from ..reduction.projection import auto_independent

_STICK = (np.eye(3), ("longitudinal", "lateral", "normal"))
_SLIDE = (np.array([[0.0, 0.0, 1.0]]), ("normal",))
SLIP_ZERO = 1e-12
"""Slip speed [m/s] below which a sliding wheel's friction keeps the direction it started with."""


class StickSlipWheel(RollingWheel):
    """A standard wheel with Coulomb friction coefficient ``mu`` that sticks (rolls) or slides (see the module).

    Takes the arguments of :class:`~robotdyn.constraints.rolling_contact.RollingWheel` and:

    Args:
        mu: Friction coefficient (>= 0), the same for sticking and sliding.
        description: The robot's :class:`~robotdyn.description.urdf.Description`.
        frame: Frame (link) whose origin is the wheel centre.
        radius: Wheel radius R [m] (> 0).
        **kwargs: ``axis``, ``terrain``, ``radius_joint``, ``name`` as for
            :class:`~robotdyn.constraints.rolling_contact.RollingWheel`.
    """

    def __init__(self, description, frame: str, radius: float, mu: float, **kwargs) -> None:
        super().__init__(description, frame, radius, **kwargs)
        self.mu = float(mu)
        self.set_phase("stick")

    def __repr__(self) -> str:
        return f"StickSlipWheel(frame={self.frame!r}, radius={self.radius}, mu={self.mu}, phase={self.phase!r})"

    def set_phase(self, phase: str, direction: np.ndarray | None = None) -> None:
        """Switch to ``stick`` or to ``slide`` (with the initial slip direction (2,) in (t1, t2)).

        Args:
            phase: ``stick`` (rolls: three rows) or ``slide`` (normal row; Coulomb friction opposes the slip).
            direction: Sliding: the initial slip direction (2,) in (t1, t2), normalised here (default ``None``).
        """
        self.phase = phase
        self._directions, self._row_names = _STICK if phase == "stick" else _SLIDE
        self.direction = None if direction is None else np.asarray(direction, float) / np.linalg.norm(direction)

    @property
    def sliding(self) -> bool:
        """Whether its tangential force currently comes from Coulomb friction."""
        return self.phase == "slide"

    def friction_coefficient(self, s: np.ndarray) -> np.ndarray:
        """Coulomb's :math:`\\mu\\hat s` (the friction force is :math:`-f_n\\mu\\hat s`).

        Args:
            s: The slip velocity (2,) [m/s] of the wheel's material point at the contact, in (t1, t2) of its contact
                frame.

        Returns:
            mu times the unit slip direction (2,) (the initial direction below the zero-slip threshold).
        """
        speed = float(np.hypot(s[0], s[1]))
        return self.mu * (s / speed if speed > SLIP_ZERO else self.direction)

    def jacobian(self, kin):  # an override keeps the wheel off the compiled path (its rows change)
        return super().jacobian(kin)


def stick_slip_wheels(robot) -> list[StickSlipWheel]:
    """The robot's stick-slip wheels (a robot with any is simulated by the exact switching engine only).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.

    Returns:
        The :class:`StickSlipWheel` constraints of the robot.
    """
    return [c for c in robot.constraints if isinstance(c, StickSlipWheel)]


def configure(robot, q: np.ndarray) -> None:
    """Choose the independent velocities for the wheels' current phases at configuration q: the spec's choice where
    it still fits the mobility, else :func:`~robotdyn.reduction.projection.auto_independent`'s (the projection is
    rebuilt at every phase switch; sets ``robot.independent_indices`` and ``robot.velocity_names``).

    Args:
        robot: The :class:`~robotdyn.robot.Robot` with stick-slip wheels in the phases wanted.
        q: Natural coordinates (n,) [m, rad].
    """
    robot._projection_hint = None
    A = robot.rows_at(q).A
    mobility = robot.nq - np.linalg.matrix_rank(A) if A.size else robot.nq
    spec = robot.spec.independent
    if spec is not None and len(spec) == mobility:
        robot.independent_indices = np.array([robot.coordinate_index(c) for c in spec], dtype=int)
    else:
        robot.independent_indices = auto_independent(A)
    robot.velocity_names = [robot.velocity_labels[i] for i in robot.independent_indices]


_GUARD = threading.Lock()  # (creating the robots' phase locks)
_PHASE_LOCKS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def phase_lock(robot) -> threading.RLock:
    """The lock held by whatever switches the phases of ``robot``'s stick-slip wheels (and with them its
    independent velocities, :func:`configure`): a stick-slip run (:func:`robotdyn.simulation.stick_slip.simulate`)
    and the traction pass over its trajectory (:func:`robotdyn.contact.stick_slip_traction.phase_states`). Two of
    them on one Robot from two threads take turns; before, each switched the other's wheels mid-run (a KeyError,
    an InputError or a SingularConstraintError in every run of ``tests/test_threads_traction.py``). Other calls
    on that Robot from other threads meanwhile see the run's current phases: give each thread its own Robot.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.

    Returns:
        The robot's re-entrant lock (one per Robot object, dropped with it).
    """
    with _GUARD:
        lock = _PHASE_LOCKS.get(robot)
        if lock is None:
            lock = _PHASE_LOCKS[robot] = threading.RLock()
        return lock


def holding_phases(function):
    """Decorate ``function(robot, ...)`` to run under :func:`phase_lock` of its robot.

    Args:
        function: A function whose first argument is the :class:`~robotdyn.robot.Robot` whose phases it switches.

    Returns:
        The wrapped function (same name, signature and docstring).
    """

    @functools.wraps(function)
    def locked(robot, *args, **kwargs):
        with phase_lock(robot):
            return function(robot, *args, **kwargs)

    return locked


def unloaded_message(wheel: str, t: float, load: float, state: str) -> str:
    """``stats["event"]`` of a run stopped where a rigid wheel's normal load reached zero (a stick-slip wheel, or
    one slipping under a friction law): what happened and how to model it (one line).

    Args:
        wheel: The wheel's name.
        t: Time [s] at which its load reaches zero.
        load: Its normal load there [N] (zero to the event's accuracy).
        state: What its tangential side was doing: ``sticking``, ``sliding`` or ``slipping``.

    Returns:
        The message: the rigid normal row would have to pull to keep the wheel on the ground, so the rigid model
        cannot continue; ``contact = "compliant"`` (with a ``coulomb`` or ``linear`` friction law: a compliant wheel
        takes no stick_slip law) lets it fly and land.
    """
    return (f"wheel {wheel} unloads at t = {t:.6g} s (normal load {load:.3g} N, {state}): the rigid contact "
            "cannot leave the ground, so the run stops there; to let it fly and land give it contact = "
            "\"compliant\" in its [[wheels]] entry (a normal force law of the penetration, with friction = "
            "\"coulomb\" or \"linear\": a compliant wheel takes no stick_slip law)")
