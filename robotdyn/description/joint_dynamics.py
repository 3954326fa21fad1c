"""A URDF's joint damping and friction (its ``<dynamics damping friction>`` tags): which joints carry them, and
what ``info`` says of them.

Pinocchio reads a joint's ``<dynamics>`` into ``model.damping`` and ``model.friction``, one value per velocity.
robotdyn applies the damping d as Gazebo, Drake and MuJoCo's URDF import do: a viscous generalised force
:math:`Q_j = -d\\,\\dot q_j` on the joint's coordinate (N m s/rad on a revolute joint, N s/m on a prismatic one),
built as a joint damper of stiffness 0 (:mod:`robotdyn.reduction.joint_springs`, so that every door, the compiled
engine included, applies it). A robot's ``urdf_damping = false`` (constraint file) or ``RobotSpec.urdf_damping``
leaves it out, for the papers' ideal joints. A joint's dry friction is not modelled: ``info`` names it and says so.

:func:`urdf_dampers` lists the damped joints; :func:`joint_dynamics_notes` gives ``info``'s lines.
"""

from __future__ import annotations

from dataclasses import dataclass

import pinocchio as pin


@dataclass(frozen=True)
class JointDamper:
    """A joint's URDF damping.

    Attributes:
        joint: The joint's URDF name.
        index: Its velocity index in the model (natural coordinates: also its index in q).
        damping: d [N m s/rad on a revolute joint, N s/m on a prismatic one] (> 0).
        unit: ``"N m s/rad"`` or ``"N s/m"``.
    """

    joint: str
    index: int
    damping: float
    unit: str


def _one_dof_joints(model: pin.Model):
    """``(name, velocity index, prismatic)`` of each one-coordinate joint (the root joints robotdyn adds carry no
    ``<dynamics>``)."""
    for j in range(1, model.njoints):
        joint = model.joints[j]
        if joint.nv != 1:
            continue
        name = joint.shortname()  # JointModelPX/PY/PZ, JointModelPrismaticUnaligned; revolute: JointModelR...
        yield model.names[j], int(joint.idx_v), name.startswith("JointModelP") and not name.startswith(
            "JointModelPlanar")


def urdf_dampers(model: pin.Model) -> list[JointDamper]:
    """The joints whose URDF ``<dynamics damping>`` is not zero, in the model's joint order.

    Args:
        model: The Pinocchio model (its ``damping`` holds the URDF's ``<dynamics damping>``, one per velocity).

    Returns:
        One :class:`JointDamper` per damped one-coordinate joint (empty where none is).
    """
    return [JointDamper(name, i, float(model.damping[i]), "N s/m" if prismatic else "N m s/rad")
            for name, i, prismatic in _one_dof_joints(model) if float(model.damping[i]) != 0.0]


def _listed(values: list[tuple[float, str, str]]) -> str:
    """``"0.02 N m s/rad on hinge, wheel; 3 N s/m on slider"``: joints grouped by value and unit."""
    found: dict[tuple[float, str], list[str]] = {}
    for value, unit, joint in values:
        found.setdefault((value, unit), []).append(joint)
    return "; ".join(f"{value:g} {unit} on {', '.join(names)}" for (value, unit), names in found.items())


def joint_dynamics_notes(model: pin.Model, applied: bool) -> list[str]:
    """``info``'s lines on the URDF's joint ``<dynamics>``: the damping applied (or left out) and the dry friction
    not modelled.

    Args:
        model: The Pinocchio model (its ``damping`` and ``friction`` hold the URDF's ``<dynamics>``).
        applied: Whether the robot applies the URDF's damping (``urdf_damping``, default true).

    Returns:
        ``[]`` where no joint has ``<dynamics>``; otherwise one line on the damping (where any joint has some) and
        one on the friction (where any joint has some), each naming the joints, the values and the units.
    """
    notes = []
    dampers = urdf_dampers(model)
    if dampers:
        listed = _listed([(d.damping, d.unit, d.joint) for d in dampers])
        notes.append(f"the description's joint damping is applied as a viscous joint torque -d q' ({listed}); "
                     "urdf_damping = false in the constraint file leaves it out" if applied else
                     f"the description's joint damping is not applied (urdf_damping = false): {listed}")
    friction = [(float(model.friction[i]), "N" if prismatic else "N m", name)
                for name, i, prismatic in _one_dof_joints(model) if float(model.friction[i]) != 0.0]
    if friction:
        notes.append(f"the description's joint dry friction is not applied ({_listed(friction)}): robotdyn does not "
                     "model joint dry friction")
    return notes


__all__ = ["JointDamper", "joint_dynamics_notes", "urdf_dampers"]
