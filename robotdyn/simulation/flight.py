"""Flight phases of compliant wheels (:mod:`robotdyn.contact.compliant_contact`) during a simulation.

A compliant wheel lifts off where its penetration :math:`\\delta` crosses zero downwards and touches down where it
crosses zero upwards; both are events of the integrator (located to its tolerance, non-terminal: the run goes on,
the wheel flies and lands). :func:`flight_phases` turns them into ``stats["flight"]``: per event the time, the wheel
and ``lift-off`` or ``touch-down``, in time order, which ``simulate`` prints.

Stiff contact (a stiffness giving about 1 mm of static deflection oscillates at tens of Hz and is damped in
milliseconds) makes an explicit integrator crawl: robots with compliant wheels are integrated by default with
:data:`STIFF_METHOD`, scipy's LSODA (ODEPACK: Adams steps in flight, BDF steps, implicit, while the stiff contact
acts, switched automatically). Radau's trial steps across a touch-down's kink in the force can reach states far
inside the ground; there it failed where LSODA and BDF did not (a disc landing while sliding: LSODA 4301
evaluations, BDF 2652 but twice LSODA's time, DOP853 24161).
"""

from __future__ import annotations

import numpy as np

from ..constraints.constraint import KinematicState

STIFF_METHOD = "LSODA"
"""scipy ``solve_ivp`` method for robots with compliant wheels unless another is asked for."""


def flight_events(robot, wheels, n: int) -> list[tuple]:
    """Event functions of ``wheels``' penetrations for scipy's ``solve_ivp``: ``(function, wheel name, kind)``
    with kind ``lift-off`` (penetration decreasing through zero) or ``touch-down`` (increasing through zero).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        wheels: Its :class:`~robotdyn.contact.compliant_contact.CompliantWheel` list.
        n: Number of coordinates (the state's first n entries are q).

    Returns:
        One ``(function, wheel name, kind)`` tuple per wheel and kind.
    """
    out = []
    last: dict = {}  # the penetrations of every wheel at the last configuration asked for (one kinematics pass)

    def depths(q: np.ndarray) -> np.ndarray:
        key = q.tobytes()
        if last.get("key") != key:
            kin = KinematicState(robot.model, robot.data, q, np.zeros(robot.model.nv))
            last["key"], last["depths"] = key, np.array([w.penetration(kin) for w in wheels])
        return last["depths"]

    for i, w in enumerate(wheels):
        for kind, direction in (("lift-off", -1.0), ("touch-down", 1.0)):
            def event(t, y, i=i):
                return float(depths(np.asarray(y[:n], float))[i])

            event.terminal, event.direction = False, direction
            out.append((event, w.name, kind))
    return out


def flight_phases(events: list[tuple], times: list, t_end: float) -> list[dict]:
    """``[{"t": s, "wheel": name, "event": "lift-off" | "touch-down"}, ...]`` in time order from the event
    functions of :func:`flight_events` and the times solve_ivp found for each (``sol.t_events``).

    Args:
        events: The ``(function, wheel name, kind)`` list of :func:`flight_events`.
        times: For each event, in the same order, the times [s] it was found at (``sol.t_events``).
        t_end: End time [s]: later events are dropped.

    Returns:
        The event dicts, sorted by time.
    """
    out = [{"t": float(t), "wheel": name, "event": kind}
           for (_, name, kind), ts in zip(events, times) for t in ts if t <= t_end]
    return sorted(out, key=lambda e: e["t"])


def airborne(robot, wheels, q: np.ndarray) -> list[str]:
    """The names of ``wheels`` not touching the ground at q (penetration <= 0).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        wheels: Its :class:`~robotdyn.contact.compliant_contact.CompliantWheel` list to check.
        q: Natural coordinates (n,) [m, rad], in the robot's coordinate order.

    Returns:
        The wheel names, in the order of ``wheels``.
    """
    kin = KinematicState(robot.model, robot.data, np.asarray(q, float), np.zeros(robot.model.nv))
    return [w.name for w in wheels if w.penetration(kin) <= 0.0]


def flight_summary(phases: list[dict], start: list[str] = ()) -> list[str]:
    """One line per wheel with its lift-off and touch-down times [s] (empty without events or wheels in the air
    at the start).

    Args:
        phases: The time-ordered events of :func:`flight_phases`.
        start: Names of the wheels in the air at the start (:func:`airborne` at q0; default none).

    Returns:
        The lines, one per wheel with an event or in the air at the start.
    """
    wheels: dict[str, list[str]] = {name: ["in the air at the start"] for name in start}
    for e in phases:
        lost = f" (impact -{e['loss']:.4g} J)" if e.get("loss") else ""  # a rolling wheel's touch-down
        wheels.setdefault(e["wheel"], []).append(f"{e['event']} {e['t']:.6g} s{lost}")
    return [f"wheel {name}: {', '.join(items)}" for name, items in wheels.items()]


__all__ = ["STIFF_METHOD", "flight_events", "flight_phases", "flight_summary", "airborne"]
