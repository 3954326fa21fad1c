"""Coordinates that a trajectory optimisation holds at their start value: those along which the robot's constraints
change rank.

At some configurations the constraint rows are redundant only there: a car whose vertical suspensions and
no-slip wheels leave a roll velocity at zero roll but none at any other roll angle (its rows gain rank as soon as
it rolls), steerable wheels all parallel. The constraints then leave one velocity more at q0 than at every
configuration nearby. No motion of the robot leaves such a configuration along that direction (a motion that
tried would take an impulsive constraint force), and the reduced dynamics refuse every configuration off it
(:class:`~robotdyn.errors.SingularConstraintError`: fewer independent velocities than chosen). An optimiser that
left those coordinates free would try such points, and a central difference across them has no meaning.

Here the independent position coordinates are stepped one at a time from q0 (along the holonomic level set, as the
finite differences step them, :mod:`robotdyn.optimisation.manifold_steps`) by the finite-difference step, and the
rank of the constraint rows is compared with q0's (:func:`robotdyn.reduction.projection.independent_rows`). Rows
independent at q0 cannot gain rank nearby, so robots without redundant rows at q0 are not stepped at all.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..errors import ConstraintError, InputError
from ..reduction.projection import independent_rows

STEP = float(np.cbrt(np.finfo(float).eps))
"""Relative step [m or rad per unit of 1 + abs(q_i)] of the test: the central differences' own
(:data:`robotdyn.optimisation.node_batches.STEP`)."""


def rank_changing(robot, q0: np.ndarray, positions, pair: Callable | None) -> list[int]:
    """The independent position coordinates along which a step from q0 changes the constraint rows' rank.

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.
        q0: Natural coordinates (n,) [m, rad], on the holonomic constraint manifold.
        positions: Indices of the independent position coordinates (those stepped).
        pair: ``(q, i, h) -> (q+, q-)`` steps along the holonomic level set
            (:meth:`~robotdyn.optimisation.manifold_steps.ManifoldSteps.pair`), or ``None`` without holonomic rows
            (plain steps of coordinate i).

    Returns:
        The indices (into q) of the coordinates whose step by :math:`\\pm` :data:`STEP` (1 + abs(q_i)) changes the rank,
        in coordinate order (empty where every row is independent at q0).
    """
    def rank(A: np.ndarray) -> int:
        return len(independent_rows(A)) if A.size else 0

    A0 = robot.rows_at(q0).A
    r0 = rank(A0)
    if r0 == A0.shape[0]:  # every row independent at q0: the rank cannot change nearby (it cannot rise further)
        return []
    out = []
    for i in positions:
        h = STEP * (1.0 + abs(q0[i]))
        if pair is None:
            steps = (q0 + h * np.eye(len(q0))[i], q0 - h * np.eye(len(q0))[i])
        else:
            try:
                steps = pair(q0, int(i), h)
            except ConstraintError:  # no level set along it: not a direction the robot moves in either
                steps = None
        if steps is None or any(rank(robot.rows_at(q).A) != r0 for q in steps):
            out.append(int(i))
    return out


def held_velocities(S: np.ndarray, held: list[int], coordinates: list[str], velocity_names: list[str]) -> list[int]:
    """The independent velocities that move the held coordinates (one each), to hold at zero.

    Args:
        S: The velocity map :math:`\\dot q = S\\nu` at q0 (n, k).
        held: Indices of the held coordinates (:func:`rank_changing`).
        coordinates: The coordinates' names (n).
        velocity_names: The independent velocities' names (k).

    Returns:
        The indices (into nu) of the velocities to hold at zero.

    Raises:
        InputError: A held coordinate that several independent velocities move (one line: the optimiser cannot
            hold it by holding one of them).
    """
    out = []
    for i in held:
        row = np.abs(S[i])
        moving = np.flatnonzero(row > 1e-12 * max(1.0, row.max(initial=0.0)))
        if len(moving) > 1:
            raise InputError(f"the constraints change rank along {coordinates[i]} at q0 (the robot cannot move "
                             f"along it), and {', '.join(velocity_names[j] for j in moving)} all move it; expected a "
                             "start where the constraints keep their rank, or one velocity moving that coordinate")
        out += [int(j) for j in moving if j not in out]
    return out


__all__ = ["rank_changing", "held_velocities", "STEP"]
