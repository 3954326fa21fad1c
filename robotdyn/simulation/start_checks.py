"""The holonomic start checks of :func:`robotdyn.simulation.engine.simulate`, from the compiled rows where they decide.

A run starts with two checks on the constraint rows at q0: :meth:`robotdyn.robot.Robot.check_constraints` (every
residual within 1e-6, else a one-line :class:`~robotdyn.errors.ConstraintError`) and
:func:`robotdyn.reduction.pull_back.start_offsets` (the residuals no coordinate can change, kept as offsets, and the
refusal of a pull-back that would move the coordinates by more than
:data:`~robotdyn.reduction.pull_back.MAX_CORRECTION`). Their rows come from the Python kinematics
(:meth:`~robotdyn.robot.Robot.rows_at`, ~0.15 ms on Quasimoro: a sixth of a compiled run's set-up), while the robot's
compiled model gives the same rows in one evaluation (~7 us).

:func:`start_offsets` takes the compiled residuals where they settle both checks: where every residual is at most
:data:`CLEAR` (1e-15), the Python rows' residuals are of the same rounding size (the compiled rows are the
twins of the Python ones, equal to them to rounding: ``tests/test_compiled.py``), so that

* every residual is far below the 1e-6 of ``check_constraints``: it passes;
* every residual is far below :data:`~robotdyn.reduction.pull_back.OFFSET_TOL` (1e-12), which bounds the
  offsets (the part of phi outside the rows' range is at most abs(phi)): there are none;
* the pull-back's start correction is at most abs(phi) sqrt(h) / (RANK_TOL max(sigma_max, 1)), about 1e-6 sqrt(h)
  for h holonomic rows, far below MAX_CORRECTION (1e-3): no refusal.

So the result is the one of the Python rows: no offsets and no error. Any other start (a residual above
:data:`CLEAR`, no compiled model, no row choice yet, a compiled evaluation that falls back) runs both checks on the
Python rows exactly as before, so every refusal keeps its one-line message and every offset its value.

:func:`start_dynamics` checks the dynamics where a run starts, for every engine: regular (the Python path's
forward dynamics, its errors), and with slipping wheels none pulling the ground
(:func:`robotdyn.contact.sliding.check_start_loads`, from the same forward solve).
"""

from __future__ import annotations

import numpy as np

from ..contact.sliding import check_start_loads, sliding_now
from ..contact.stick_slip_wheel import stick_slip_wheels
from ..fast.dispatch import compiled_model
from ..reduction.pull_back import start_offsets as python_start_offsets

CLEAR = 1e-15
"""Largest compiled residual [m or rad] of any constraint row at q0 with which the start checks pass without the
Python rows (see the module text)."""


def compiled_residuals(robot, q0: np.ndarray) -> np.ndarray | None:
    """Every constraint row's residual at q0 from the robot's compiled model (``None`` where it does not serve:
    no compiled model, no row choice made yet, stick-slip wheels, or an evaluation that fails at q0).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        q0: Natural coordinates (n,) [m, rad], checked (finite, of the robot's length).

    Returns:
        The residuals (m,) [m or rad] in the order of the robot's rows, or ``None``.
    """
    if stick_slip_wheels(robot):  # (their runs switch models segment by segment: the Python rows, as before)
        return None
    try:  # (the model the run's own evaluations use through robot.reduced: built here at the latest)
        fast = compiled_model(robot)
        if fast is None or not fast.ready:
            return None
        residual = fast.evaluate(q0, np.zeros(robot.mobility))[8]
    except Exception:  # noqa: BLE001 (a fallback or any refusal: the Python rows decide, with their messages)
        return None
    residual = np.asarray(residual, float)
    return residual if residual.shape == (len(fast.labels),) else None


def start_offsets(robot, q0: np.ndarray, stabilisation: float, check: bool = True) -> dict[str, float]:
    """:meth:`~robotdyn.robot.Robot.check_constraints` (with ``check``) and then
    :func:`robotdyn.reduction.pull_back.start_offsets` at q0, on the compiled residuals where they settle both (see
    the module text), else on the Python rows.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        q0: The initial configuration (n,) [m, rad], checked (finite, of the robot's length).
        stabilisation: Gain alpha [1/s] of the pull-back of the holonomic residuals (0: none).
        check: Refuse a q0 that violates a constraint by more than 1e-6 (default True; a continuation of an
            earlier run does not).

    Returns:
        The offsets by row label [m or rad] (empty if none).

    Raises:
        ConstraintError: As ``check_constraints`` and ``start_offsets`` raise it (the same one-line messages).
    """
    residual = compiled_residuals(robot, q0)
    if residual is not None and np.all(np.abs(residual) <= CLEAR):
        return {}
    rows = robot.rows_at(q0)  # (once: both checks read them)
    if check:
        robot.check_constraints(q0, rows=rows)
    return python_start_offsets(robot, q0, stabilisation, rows)


def start_dynamics(robot, t0: float, q0: np.ndarray, nu0: np.ndarray, tau0: np.ndarray) -> None:
    """Refuse a start where the dynamics are not regular (:meth:`~robotdyn.robot.Robot.forward_dynamics`'s errors)
    or, with slipping wheels, where one already pulls the ground
    (:func:`~robotdyn.contact.sliding.check_start_loads`, whose forward solve is the one ``forward_dynamics`` makes
    with slipping wheels: the state is solved once).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        t0: Start time [s] (for the messages).
        q0: Natural coordinates (n,) [m, rad] where the run starts.
        nu0: Independent velocities (k,) [m/s, rad/s] there.
        tau0: Motor torques (one per motor) [N m or N] there.

    Raises:
        RobotDynError: As ``forward_dynamics`` and ``check_start_loads`` raise it (one line each).
    """
    if sliding_now(robot):
        check_start_loads(robot, t0, q0, nu0, tau0)
    else:
        robot.forward_dynamics(q0, nu0, tau0)


__all__ = ["start_offsets", "start_dynamics", "compiled_residuals", "CLEAR"]
