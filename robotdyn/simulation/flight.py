"""Flight phases of compliant wheels (:mod:`robotdyn.contact.compliant_contact`) during a simulation.

A compliant wheel lifts off where its penetration :math:`\\delta` crosses zero downwards and touches down where it
crosses zero upwards; both are events of the integrator (located to its tolerance, non-terminal: the run goes on,
the wheel flies and lands). :func:`flight_phases` turns them into ``stats["flight"]``: per event the time, the wheel
and ``lift-off`` or ``touch-down``, in time order, which ``simulate`` prints.

Stiff contact (a stiffness giving about 1 mm of static deflection oscillates at tens of Hz and is damped in
milliseconds) makes an explicit integrator crawl: robots with compliant wheels are integrated by default with
:data:`STIFF_METHOD`, scipy's implementation of the implicit Radau IIA method of order 5.
"""

from __future__ import annotations

import numpy as np

from ..constraints.constraint import KinematicState

STIFF_METHOD = "Radau"
"""scipy ``solve_ivp`` method for robots with compliant wheels unless another is asked for (implicit, stiffly
accurate; LSODA and BDF are the other stiff ones)."""


def flight_events(robot, wheels, n: int) -> list[tuple]:
    """Event functions of ``wheels``' penetrations for scipy's ``solve_ivp``: ``(function, wheel name, kind)``
    with kind ``lift-off`` (penetration decreasing through zero) or ``touch-down`` (increasing through zero).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        wheels: Its :class:`~robotdyn.contact.compliant_contact.CompliantWheel` list.
        n: Number of coordinates (the state's first n entries are q).
    """
    out = []
    for w in wheels:
        def depth(t, y, w=w):
            kin = KinematicState(robot.model, robot.data, y[:n], np.zeros(robot.model.nv))
            return w.penetration(kin)

        for kind, direction in (("lift-off", -1.0), ("touch-down", 1.0)):
            def event(t, y, depth=depth):
                return depth(t, y)

            event.terminal, event.direction = False, direction
            out.append((event, w.name, kind))
    return out


def flight_phases(events: list[tuple], times: list, t_end: float) -> list[dict]:
    """``[{"t": s, "wheel": name, "event": "lift-off" | "touch-down"}, ...]`` in time order from the event
    functions of :func:`flight_events` and the times solve_ivp found for each (``sol.t_events``)."""
    out = [{"t": float(t), "wheel": name, "event": kind}
           for (_, name, kind), ts in zip(events, times) for t in ts if t <= t_end]
    return sorted(out, key=lambda e: e["t"])


def flight_summary(phases: list[dict]) -> list[str]:
    """One line per wheel with its lift-off and touch-down times [s] (empty without events)."""
    wheels: dict[str, list[str]] = {}
    for e in phases:
        wheels.setdefault(e["wheel"], []).append(f"{e['event']} {e['t']:.6g} s")
    return [f"wheel {name}: {', '.join(items)}" for name, items in wheels.items()]


__all__ = ["STIFF_METHOD", "flight_events", "flight_phases", "flight_summary"]
