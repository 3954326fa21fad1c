"""A wheel whose ``axis`` lies (almost) along the ground normal is named by ``info`` (found on the TurtleBot3 Burger's
description: its skid caster's link is turned by a rounded ``rpy="-1.57 0 0"``, so the axis [0, 1, 0] a newcomer
writes in the world's axes points 0.0008 rad from vertical in the link's; the contact geometry refuses only an axle
exactly along the normal, so the skid's contact point silently sat a radius to the side of its centre and ``info``
only said that the wheels did not all touch the ground, advising to check the radii).

Fixture: a small differential drive of this test's own (no description is copied), its skid link turned by
-1.4 rad about x: its y axis is pi/2 - 1.4 = 0.1708 rad from the vertical, so the contact point of a skid of radius
r = 0.006 m with axis [0, 1, 0] is r cos(0.1708) = 0.0059 m to the side of its centre.
"""

from __future__ import annotations

import math

import pytest

from robotdyn.interfaces.constraint_file import load_robot

URDF = """<?xml version="1.0"?>
<robot name="tilt_fixture">
  <link name="base_link">
    <inertial><mass value="1.0"/><inertia ixx="0.005" ixy="0" ixz="0" iyy="0.005" iyz="0" izz="0.005"/></inertial>
  </link>
  <link name="wheel_left"><inertial><mass value="0.03"/>
    <inertia ixx="1e-5" ixy="0" ixz="0" iyy="2e-5" iyz="0" izz="1e-5"/></inertial></link>
  <link name="wheel_right"><inertial><mass value="0.03"/>
    <inertia ixx="1e-5" ixy="0" ixz="0" iyy="2e-5" iyz="0" izz="1e-5"/></inertial></link>
  <link name="skid"><inertial><mass value="0.01"/>
    <inertia ixx="1e-6" ixy="0" ixz="0" iyy="1e-6" iyz="0" izz="1e-6"/></inertial></link>
  <joint name="left_joint" type="continuous"><parent link="base_link"/><child link="wheel_left"/>
    <origin xyz="0 0.08 0.033"/><axis xyz="0 1 0"/></joint>
  <joint name="right_joint" type="continuous"><parent link="base_link"/><child link="wheel_right"/>
    <origin xyz="0 -0.08 0.033"/><axis xyz="0 1 0"/></joint>
  <joint name="skid_joint" type="fixed"><parent link="base_link"/><child link="skid"/>
    <origin xyz="-0.08 0 0.006" rpy="-1.4 0 0"/></joint>
</robot>
"""

TOML = """
name = "tilt_fixture"
urdf = "tilt_fixture.urdf"
root = "planar"
independent = ["right_joint", "left_joint"]

[[wheels]]
name = "left"
joint = "left_joint"
radius = 0.033

[[wheels]]
name = "right"
joint = "right_joint"
radius = 0.033

[[wheels]]
name = "skid"
frame = "skid"
radius = 0.006
axis = {axis}
kind = "support"

[[motors]]
name = "tau_R"
joint = "right_joint"
"""


def _robot(tmp_path, axis: str):
    (tmp_path / "tilt_fixture.urdf").write_text(URDF)
    (tmp_path / "tilt_fixture.toml").write_text(TOML.replace("{axis}", axis))
    return load_robot(tmp_path / "tilt_fixture.toml")


def test_an_axle_near_the_ground_normal_is_named(tmp_path):
    notes = _robot(tmp_path, "[0, 1, 0]").info()["mobility_notes"]
    flat = [n for n in notes if "lying flat" in n]
    assert len(flat) == 1 and "wheel 'skid'" in flat[0] and "frame 'skid'" in flat[0]
    tilt = math.pi / 2 - 1.4
    assert f"is {tilt:.2g} rad from the ground normal" in flat[0]
    assert f"{0.006 * math.cos(tilt):.3g} m to the side" in flat[0]


@pytest.mark.parametrize("axis", ["[1, 0, 0]", "[0, 0, 1]"])
def test_a_horizontal_axle_is_not_named(tmp_path, axis):
    """[1, 0, 0] is the link's x (horizontal); its z, turned by -1.4 about x, is 0.17 rad from the horizontal."""
    notes = _robot(tmp_path, axis).info()["mobility_notes"]
    assert not [n for n in notes if "lying flat" in n], notes
