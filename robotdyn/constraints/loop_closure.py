"""Loop closure between two frames on different branches of the kinematic tree.

Frames F1 and F2 must coincide in a chosen subset of the six relative-motion components, measured in F1's axes:
translations ``x``, ``y``, ``z`` of F2's origin relative to F1's, and rotations ``rx``, ``ry``, ``rz`` of F2
relative to F1. A spherical joint closes ``x y z``; a revolute joint about F1's z closes ``x y z rx ry``; a prismatic
joint along F1's x closes ``y z rx ry rz``; a planar loop closes its in-plane components.

With :math:`d = p_2 - p_1` (world), rotation :math:`R_1` of F1 and LOCAL_WORLD_ALIGNED Jacobians :math:`J_i`:

- translation rows: :math:`e = R_1^T d`, :math:`\\dot e = R_1^T (J_{2,v} - J_{1,v} + [d]_\\times J_{1,\\omega}) v`;
- rotation rows: :math:`R_1^T (J_{2,\\omega} - J_{1,\\omega}) v`, residual :math:`\\log(R_1^T R_2)`;
- both time derivatives use :math:`\\frac{d}{dt} R_1^T x = R_1^T(\\dot x - \\omega_1 \\times x)`.

All rows are holonomic.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from .constraint import Constraint, ConstraintRows, KinematicState, cross, skew
from ..errors import DescriptionError

COMPONENTS = ("x", "y", "z", "rx", "ry", "rz")


class LoopClosure(Constraint):
    """Two frames that must coincide in some relative-motion components (holonomic).

    Args:
        description: The robot's :class:`~robotdyn.description.urdf.Description`.
        frame1, frame2: The two frames (on different bodies).
        components: Subset of ``x y z rx ry rz`` to close, in frame1's axes.
        name: Name used in row labels (default ``"frame1~frame2"``).
    """

    def __init__(self, description, frame1: str, frame2: str, components=("x", "y", "z"), name: str | None = None):
        self.frame1, self.frame2 = frame1, frame2
        self.f1, self.f2 = description.frame_id(frame1), description.frame_id(frame2)
        model = description.model
        if model.frames[self.f1].parentJoint == model.frames[self.f2].parentJoint:
            raise DescriptionError(
                f"loop closure {frame1!r}-{frame2!r}: both frames are on the same body; expected frames on two "
                "different branches of the tree"
            )
        comps = list(components.split() if isinstance(components, str) else components)
        bad = [c for c in comps if c not in COMPONENTS]
        if bad or not comps or len(set(comps)) != len(comps):
            raise DescriptionError(
                f"loop closure {frame1!r}-{frame2!r}: components {comps} invalid; expected a non-empty subset of "
                f"{' '.join(COMPONENTS)}"
            )
        self.components = comps
        self._sel = np.array([COMPONENTS.index(c) for c in comps])
        self.name = name or f"{frame1}~{frame2}"

    def __repr__(self) -> str:
        return f"LoopClosure({self.frame1!r}, {self.frame2!r}, components={' '.join(self.components)!r})"

    def rows(self, kin: KinematicState) -> ConstraintRows:
        """The closure rows (relative velocity of the two frames in the closed components, in frame1's axes) with
        their time derivative and position residuals.

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v) (placements, Jacobians and
                their time variation of the robot's model).

        Returns:
            The :class:`~robotdyn.constraints.constraint.ConstraintRows` (one holonomic row per closed component).
        """
        M1, J1, dJ1 = kin.frame(self.f1)
        M2, J2, dJ2 = kin.frame(self.f2)
        v = kin.v
        R1 = M1.rotation
        d = M2.translation - M1.translation
        ddot = (J2[:3] - J1[:3]) @ v
        w1 = J1[3:] @ v
        Kt = J2[:3] - J1[:3] + skew(d) @ J1[3:]
        dKt = dJ2[:3] - dJ1[:3] + skew(ddot) @ J1[3:] + skew(d) @ dJ1[3:]
        Kr = J2[3:] - J1[3:]
        dKr = dJ2[3:] - dJ1[3:]
        W = skew(w1)
        A = np.vstack([R1.T @ Kt, R1.T @ Kr])
        Adot = np.vstack([R1.T @ (dKt - W @ Kt), R1.T @ (dKr - W @ Kr)])
        residual = np.concatenate([R1.T @ d, pin.log3(R1.T @ M2.rotation)])
        sel = self._sel
        labels = [f"{self.name}.{c}" for c in self.components]
        return ConstraintRows(A[sel], Adot[sel], residual[sel], np.ones(len(sel), bool), labels)

    def jacobian(self, kin: KinematicState) -> ConstraintRows:
        """The rows and residuals without :math:`\\dot A` (configuration only).

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v) (placements, Jacobians and
                their time variation of the robot's model).

        Returns:
            The :class:`~robotdyn.constraints.constraint.ConstraintRows`.
        """
        M1, J1 = kin.pose(self.f1)
        M2, J2 = kin.pose(self.f2)
        R1T = M1.rotation.T
        d = M2.translation - M1.translation
        K = J2 - J1
        K[:3] += skew(d) @ J1[3:]
        A = (R1T @ K.reshape(2, 3, -1)).reshape(6, -1)
        residual = np.concatenate([R1T @ d, pin.log3(R1T @ M2.rotation)])
        sel = self._sel
        labels = [f"{self.name}.{c}" for c in self.components]
        return ConstraintRows(A[sel], None, residual[sel], np.ones(len(sel), bool), labels)

    def drift(self, kin: KinematicState) -> np.ndarray:
        """:math:`\\dot A v` from the frames' velocities and :math:`\\dot J v` (3-vectors, no matrix :math:`\\dot A`).

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v) (placements, Jacobians and
                their time variation of the robot's model).

        Returns:
            One value per closed component [m/s^2 or rad/s^2].
        """
        M1, J1, dJ1 = kin.frame(self.f1)
        M2, J2, dJ2 = kin.frame(self.f2)
        v = kin.v
        V1, V2 = J1 @ v, J2 @ v
        a1, a2 = dJ1 @ v, dJ2 @ v
        d = M2.translation - M1.translation
        w1 = V1[3:]
        ddot = V2[:3] - V1[:3]
        kt = ddot + cross(d, w1)
        dkt = a2[:3] - a1[:3] + cross(ddot, w1) + cross(d, a1[3:])
        kr = V2[3:] - V1[3:]
        dkr = a2[3:] - a1[3:]
        R1T = M1.rotation.T
        out = np.concatenate([R1T @ (dkt - cross(w1, kt)), R1T @ (dkr - cross(w1, kr))])
        return out[self._sel]

