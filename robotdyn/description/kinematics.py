"""Forward and inverse kinematics of named frames, and checks of homogeneous transforms.

Poses are 4x4 homogeneous transforms of a frame (link or joint frame of the description) in the world frame
(m, dimensionless rotation), computed by Pinocchio from the robot's natural coordinates. Every pose returned here
is checked to carry a proper rotation (orthonormal, determinant +1).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import InputError, RobotDynError

ROTATION_TOL = 1e-9
"""Largest accepted ``max|R^T R - I|`` and ``|det R - 1|`` for a computed rotation."""


def rotation_defects(R) -> tuple[float, float]:
    """How far a 3x3 matrix is from a rotation.

    Args:
        R: A 3x3 matrix.

    Returns:
        ``(orthonormality, determinant)``: ``max|R^T R - I|`` and ``det R - 1``.
    """
    R = np.asarray(R, dtype=float)
    if R.shape != (3, 3):
        raise InputError(f"rotation has shape {R.shape}; expected (3, 3)")
    return float(np.max(np.abs(R.T @ R - np.eye(3)))), float(np.linalg.det(R) - 1.0)


def is_rotation(R, tol: float = ROTATION_TOL) -> bool:
    """True if R is orthonormal with determinant +1 within ``tol``.

    Args:
        R: A 3x3 matrix.
        tol: Tolerance on both defects (:func:`rotation_defects`).

    Returns:
        Whether R is a proper rotation within ``tol``.
    """
    ortho, det = rotation_defects(R)
    return ortho <= tol and abs(det) <= tol


def check_pose(T, tol: float = ROTATION_TOL, what: str = "pose") -> np.ndarray:
    """Validate a 4x4 homogeneous transform (finite, last row 0 0 0 1, proper rotation); return it as an array.

    Args:
        T: A 4x4 homogeneous transform (rotation, translation [m]).
        tol: Tolerance on the rotation's defects.
        what: What the pose is, for messages.

    Returns:
        T as a float array (4, 4).

    Raises:
        RobotDynError: naming the defect.
    """
    T = np.asarray(T, dtype=float)
    if T.shape != (4, 4) or not np.all(np.isfinite(T)):
        raise RobotDynError(f"{what} is not a finite 4x4 matrix")
    if np.max(np.abs(T[3] - [0.0, 0.0, 0.0, 1.0])) > tol:
        raise RobotDynError(f"{what}: last row {T[3].tolist()}; expected [0, 0, 0, 1]")
    ortho, det = rotation_defects(T[:3, :3])
    if ortho > tol or abs(det) > tol:
        raise RobotDynError(f"{what}: rotation block is not a proper rotation (|R^T R - I| = {ortho:.3g}, "
                            f"det - 1 = {det:.3g})")
    return T


def frame_names(robot) -> list[str]:
    """Names of the robot's link frames (the frames ``frame_pose`` accepts), in model order.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.

    Returns:
        The body frame names, in the Pinocchio model's frame order.
    """
    return [f.name for f in robot.model.frames if f.type == pin.FrameType.BODY]


def frame_pose(robot, q, frame: str) -> np.ndarray:
    """Pose of a frame in the world frame as a 4x4 homogeneous transform.

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (checked against the joint ranges).
        frame: A link (or joint) frame name of the description.

    Returns:
        T (4, 4): rotation of the frame's axes in world axes and position of its origin [m].

    Raises:
        InputError: wrong q or joint values outside their range. DescriptionError: unknown frame.
    """
    q = robot.check_q(q)
    fid = robot.description.frame_id(frame)
    pin.framesForwardKinematics(robot.model, robot.data, q)
    return check_pose(robot.data.oMf[fid].homogeneous.copy(), what=f"pose of frame {frame!r}")


def relative_pose(robot, q, frame: str, base: str) -> np.ndarray:
    """Pose of ``frame`` in the axes and origin of ``base`` (4x4): ``T_base^-1 T_frame``.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
        frame: The frame (link) whose pose is wanted.
        base: The frame (link) it is expressed in.

    Returns:
        The 4x4 pose T_base^-1 T_frame.
    """
    Tb = frame_pose(robot, q, base)
    Tf = frame_pose(robot, q, frame)
    out = np.linalg.solve(Tb, Tf)
    return check_pose(out, what=f"pose of {frame!r} in {base!r}")


@dataclass
class IKResult:
    """A numerical inverse-kinematics solution.

    Attributes:
        q: Natural coordinates found (within the joint ranges).
        error: Final position error norm [m].
        success: ``error <= tol``.
        nfev: Function evaluations.
    """

    q: np.ndarray
    error: float
    success: bool
    nfev: int


def position_ik(
    robot,
    frame: str,
    target,
    q0,
    variables: Sequence[str],
    tol: float = 1e-9,
    regularisation: float = 0.0,
    extra: Callable[[np.ndarray], np.ndarray] | None = None,
) -> IKResult:
    """Solve ``position(frame, q) = target`` over the coordinates ``variables`` (others fixed at q0).

    A bounded nonlinear least-squares problem (scipy ``least_squares``, trust-region reflective) within the
    joint ranges; redundancy is resolved by ``regularisation`` * (q - q0) residuals (minimum change) and any
    ``extra`` residuals.

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.
        frame: The frame whose origin must reach the target.
        target: World position (3,) [m].
        q0: Starting configuration (also fixes the coordinates not in ``variables``).
        variables: Coordinate labels to solve for.
        tol: Position tolerance [m] for ``success``.
        regularisation: Weight of the minimum-change residuals.
        extra: Extra residuals as a function of the full q.

    Returns:
        An :class:`IKResult`: the configuration q (nq,), the residual norm [m], whether it is below ``tol``, and the
        number of function evaluations.
    """
    target = np.asarray(target, dtype=float)
    if target.shape != (3,) or not np.all(np.isfinite(target)):
        raise InputError(f"IK target {target.tolist()}; expected 3 finite numbers [m]")
    q0 = robot.check_q(q0)
    idx = np.array([robot.coordinate_index(v) for v in variables], dtype=int)
    lo = robot.description.lower[idx]
    hi = robot.description.upper[idx]
    x0 = np.clip(q0[idx], np.where(np.isfinite(lo), lo + 1e-9, -np.inf), np.where(np.isfinite(hi), hi - 1e-9, np.inf))
    fid = robot.description.frame_id(frame)
    model, data = robot.model, robot.data

    def full(x):
        q = q0.copy()
        q[idx] = x
        return q

    def residual(x):
        q = full(x)
        pin.framesForwardKinematics(model, data, q)
        parts = [data.oMf[fid].translation - target]
        if regularisation:
            parts.append(regularisation * (x - q0[idx]))
        if extra is not None:
            parts.append(np.atleast_1d(extra(q)))
        return np.concatenate(parts)

    from scipy.optimize import least_squares

    sol = least_squares(residual, x0, bounds=(lo, hi), xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=2000)
    nfev = int(sol.nfev)
    if regularisation:  # polish: the exact solution nearest the regularised one
        regularisation = 0.0
        x1 = np.clip(sol.x, lo, hi)
        sol = least_squares(residual, x1, bounds=(lo, hi), xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=2000)
        nfev += int(sol.nfev)
    q = full(sol.x)
    pin.framesForwardKinematics(model, data, q)
    err = float(np.linalg.norm(data.oMf[fid].translation - target))
    return IKResult(q, err, err <= tol, nfev)


def pose_text(T: np.ndarray, title: str) -> str:
    """A 4x4 pose as text (10 significant digits).

    Args:
        T: A 4x4 pose.
        title: The first line.

    Returns:
        ``title`` followed by the four rows of the matrix, one per line.
    """
    return title + "\n" + "\n".join("  " + " ".join(f"{x: .10g}".rjust(18) for x in row) for row in T)


__all__ = ["pose_text", "frame_pose", "relative_pose", "frame_names", "check_pose", "is_rotation", "rotation_defects",
           "position_ik", "IKResult", "ROTATION_TOL"]
