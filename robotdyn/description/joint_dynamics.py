"""A URDF's joint damping and friction (its ``<dynamics>`` tags), which robotdyn does not apply, named for ``info``.

Pinocchio reads a joint's ``<dynamics>`` into ``model.damping`` and ``model.friction``; robotdyn's equations of
motion leave both out (its dynamics are those of the papers' ideal joints), so a description written for Gazebo,
whose wheels carry, e.g., 0.001 N m s/rad of damping, runs undamped without a word. Damping can be applied as a
``[[springs]]`` entry with its ``damping`` (stiffness 0, :mod:`robotdyn.reduction.joint_springs`); a joint's dry
friction is not modelled. :func:`unapplied_joint_dynamics` says which joints are concerned and how.
"""

from __future__ import annotations

from collections.abc import Iterable

import pinocchio as pin


def unapplied_joint_dynamics(model: pin.Model, damped: Iterable[int] = ()) -> list[str]:
    """One note naming the joints whose URDF ``<dynamics>`` damping or friction the dynamics leave out.

    Args:
        model: The Pinocchio model (its ``damping`` and ``friction`` hold the URDF's ``<dynamics>``, one per
            velocity).
        damped: Velocity indices of joints whose damping a ``[[springs]]`` entry already applies (not named).

    Returns:
        ``[]`` where no joint has ``<dynamics>``; otherwise one line: per value, the joints and the unit
        (N m s/rad and N m for a revolute joint, N s/m and N for a prismatic one), and the fix.
    """
    damped = set(damped)
    found: dict[tuple[str, float, str], list[str]] = {}
    for j in range(1, model.njoints):
        joint = model.joints[j]
        if joint.nv != 1:  # the root joints robotdyn adds carry none
            continue
        name = joint.shortname()  # JointModelPX/PY/PZ, JointModelPrismaticUnaligned; revolute: JointModelR...
        prismatic = name.startswith("JointModelP") and not name.startswith("JointModelPlanar")
        for what, values, unit in (("damping", model.damping, "N s/m" if prismatic else "N m s/rad"),
                                   ("friction", model.friction, "N" if prismatic else "N m")):
            value = float(values[joint.idx_v])
            if value != 0.0 and not (what == "damping" and joint.idx_v in damped):
                found.setdefault((what, value, unit), []).append(model.names[j])
    if not found:
        return []
    listed = "; ".join(f"{what} {value:g} {unit} on {', '.join(names)}" for (what, value, unit), names in found.items())
    return [f"the description's joint <dynamics> are not applied ({listed}): apply a joint's damping with a "
            "[[springs]] entry (joint, damping; stiffness 0) in the constraint file; joint dry friction is not modelled"]
