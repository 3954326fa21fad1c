"""Joint-origin angles that look like a rounded multiple of pi/2 (``rpy="0 0 3.14"``, ``1.57``, ``1.5708``).

A rounded pi tilts a wheel's axle by 1.6e-3 rad: rows that are dependent with the exact angle (two wheels on one
axle, parallel steering axes) become independent, and the mobility drops (e.g. from 5 to 3) with nothing in the
description pointing at the cause. :func:`rounded_angles` lists such values; the hint says which exact value to
write.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

NEAR = 0.01
"""Largest distance [rad] from a multiple of pi/2 that counts as a rounding of it."""
EXACT = 1e-10
"""Distance [rad] below which the angle is that multiple (e.g. ``${pi/2}`` in Xacro, or 17 digits)."""


@dataclass
class RoundedAngle:
    """A joint-origin angle within :data:`NEAR` of a multiple of pi/2 but not equal to it.

    Attributes:
        joint: The joint's name.
        axis: ``"roll"``, ``"pitch"`` or ``"yaw"`` (the ``rpy`` entry).
        value: The angle as written [rad].
        exact: The multiple of pi/2 it is close to [rad].
        text: That multiple in words (``"pi"``, ``"-pi/2"``).
    """

    joint: str
    axis: str
    value: float
    exact: float
    text: str

    @property
    def off(self) -> float:
        """How far the written angle is from the exact one [rad]."""
        return self.value - self.exact


def _words(k: int) -> str:
    sign = "-" if k < 0 else ""
    k = abs(k)
    return sign + ("pi/2" if k == 1 else "pi" if k == 2 else f"3*pi/2" if k == 3 else f"{k}*pi/2")


def rounded_angles(urdf: str) -> list[RoundedAngle]:
    """Joint-origin rpy angles of a URDF text within :data:`NEAR` of a nonzero multiple of pi/2, not exact.

    Args:
        urdf: The URDF's XML text (Xacro already expanded).

    Returns:
        One :class:`RoundedAngle` per such angle, in the file's joint order (empty where there is none).
    """
    out = []
    for joint in ET.fromstring(urdf).iter("joint"):
        origin = joint.find("origin")
        if origin is None:
            continue
        try:
            rpy = [float(x) for x in origin.get("rpy", "").split()]
        except ValueError:
            continue
        for axis, value in zip(("roll", "pitch", "yaw"), rpy):
            k = int(round(value / (np.pi / 2)))
            off = abs(value - k * np.pi / 2)
            if k != 0 and EXACT < off <= NEAR:
                out.append(RoundedAngle(joint.get("name"), axis, value, k * np.pi / 2, _words(k)))
    return out


def hint(found: list[RoundedAngle]) -> str:
    """One line naming each rounded angle and the exact value to write.

    Args:
        found: The angles :func:`rounded_angles` found.

    Returns:
        The hint's text, one line.
    """
    items = ", ".join(f"{f.joint} {f.axis} = {f.value:.10g} ({f.off:+.2g} rad from {f.text})" for f in found)
    return (f"joint origin angles that look like a rounded multiple of pi/2: {items}; a rounded angle tilts axles "
            "and axes by that much, which can make dependent constraint rows independent and change the mobility: "
            "write the exact value (${pi} in Xacro, or 17 significant digits, 3.141592653589793)")
