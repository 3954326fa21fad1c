"""Motors: how actuator torques enter the equations of motion.

A motor drives a one-degree-of-freedom joint: a torque (revolute) or force (prismatic) :math:`\\tau` along the
joint axis acts on the joint's child body, and its reaction on a ``reaction`` body (by default the joint's parent,
the usual joint motor). By virtual power its generalised-force column is

.. math:: B_j = (J_{\\omega,\\text{child}} - J_{\\omega,\\text{reaction}})^T \\hat a

for a revolute joint (:math:`\\hat a` the axis in world, LOCAL_WORLD_ALIGNED Jacobians), so a wheel motor mounted
on a pendulum body, reacting on it, loads both the wheel and the body coordinates.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..constraints.constraint import KinematicState
from ..errors import DescriptionError


class Motor:
    """A motor on a joint, optionally reacting on a body other than the joint's parent.

    Args:
        description: The robot's :class:`~robotdyn.description.urdf.Description`.
        name: The actuator's name (e.g. ``"m1"``).
        joint: The driven one-degree-of-freedom joint.
        reaction: A frame (link) of the body that takes the reaction; ``None`` for the joint's parent.
    """

    def __init__(self, description, name: str, joint: str, reaction: str | None = None) -> None:
        model = description.model
        self.name, self.joint, self.reaction = name, joint, reaction
        if not model.existJointName(joint):
            raise DescriptionError(f"motor {name!r}: no joint named {joint!r}; joints are {', '.join(description.joint_names)}")
        self.jid = int(model.getJointId(joint))
        self.index = int(model.joints[self.jid].idx_v)
        self.prismatic = "P" in model.joints[self.jid].shortname().replace("Composite", "")
        self.rid = None if reaction is None else description.frame_id(reaction)
        if self.rid is not None and self.prismatic:
            raise DescriptionError(f"motor {name!r}: a reaction body is only supported on revolute joints")

    def __repr__(self) -> str:
        return f"Motor(name={self.name!r}, joint={self.joint!r}, reaction={self.reaction!r})"

    def column(self, kin: KinematicState) -> np.ndarray:
        """The motor's column of the input matrix B (nv,) at the state of ``kin``.

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v).

        Returns:
            The column (nv,), in the model's velocity order.
        """
        col = np.zeros(kin.model.nv)
        if self.rid is None:
            col[self.index] = 1.0
            return col
        jac = pin.getJointJacobian(kin.model, kin.data, self.jid, pin.LOCAL_WORLD_ALIGNED)
        ang = jac[3:, self.index]
        axis = ang if ang @ ang > 0.25 else jac[:3, self.index]  # as KinematicState.joint_axis (|ang| > 0.5)
        j_child = jac[3:]
        _, j_reaction = kin.pose(self.rid)
        return (j_child - j_reaction[3:]).T @ axis


def input_matrix(motors: list[Motor], kin: KinematicState) -> np.ndarray:
    """Stack the motors' columns into B (nv, n_motors).

    Args:
        motors: The :class:`Motor` objects, in the robot's motor order.
        kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v).

    Returns:
        B (nv, n_motors): one column per motor, in motor order.
    """
    B = np.zeros((kin.model.nv, len(motors)))
    for j, m in enumerate(motors):
        if m.rid is None:  # the usual joint motor: a unit column, no kinematics needed
            B[m.index, j] = 1.0
        else:
            B[:, j] = m.column(kin)
    return B
