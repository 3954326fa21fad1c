"""``roller_angle`` means what the file-format reference says (found on the ROSbot 2's mecanum variant, whose Gazebo
friction directions give each wheel's ground-roller axis in the base's axes: the reference said only "angle of the
rollers' axes", so a newcomer had to guess its origin and sign, and a wrong guess runs without a word, mirrored).

The reference: the angle of the ground roller's axis (the one direction in which the wheel cannot slip) from the
wheel's rolling direction, counter-clockwise seen from above; a ground roller pointing forward-right is -45 deg.

Closed form: a wheel with spin axis a (horizontal), radius r, spin rate w, on a base moving at (vx, vy) without
turning, touches the ground at a point moving at (vx, vy) - r w (a x n) (n = up). The roller cannot slip along its
axis e: ((vx, vy) - r w (a x n)) . e = 0. For a pure sideways motion (0, vy) with a = +y (a x n = +x):
-r w e_x + vy e_y = 0; with a = -y (a x n = -x): r w e_x + vy e_y = 0. Fixture (this test's own, no description
copied): four wheels of radius r = 0.05 m, left ones with a = +y, right ones with a = -y (as some descriptions
write them), ground rollers fl, rr forward-right e = (1, -1)/sqrt 2 and fr, rl forward-left e = (1, 1)/sqrt 2.
Sideways to the left at vy = r w0: w_fl = -w0, w_fr = -w0, w_rl = +w0, w_rr = +w0.
"""

from __future__ import annotations

import numpy as np
import pytest

from robotdyn.interfaces.constraint_file import load_robot

R = 0.05  # wheel radius [m]
WHEELS = (("fl", 0.1, 0.12, 1, "-45 deg"), ("fr", 0.1, -0.12, -1, "45 deg"), ("rl", -0.1, 0.12, 1, "45 deg"),
          ("rr", -0.1, -0.12, -1, "-45 deg"))  # name, x, y, sign of the spin axis along y, roller_angle
URDF = ('<?xml version="1.0"?>\n<robot name="mecanum_fixture">\n  <link name="base_link"><inertial><mass value="3.0"/>'
        '<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.03"/></inertial></link>\n'
        + "".join(f'  <link name="{n}_wheel"><inertial><mass value="0.1"/><inertia ixx="1e-4" ixy="0" ixz="0" '
                  f'iyy="2e-4" iyz="0" izz="1e-4"/></inertial></link>\n  <joint name="{n}_joint" type="continuous">'
                  f'<parent link="base_link"/><child link="{n}_wheel"/><origin xyz="{x} {y} 0"/>'
                  f'<axis xyz="0 {s} 0"/></joint>\n' for n, x, y, s, _ in WHEELS)
        + "</robot>\n")
TOML = ('name = "mecanum_fixture"\nurdf = "mecanum.urdf"\nroot = "planar"\nindependent = ["fl_joint", "fr_joint", '
        '"rl_joint"]\n' + "".join(f'\n[[wheels]]\nname = "{n}"\njoint = "{n}_joint"\nradius = {R}\nkind = "omni"\n'
                                  f'roller_angle = "{angle}"\n' for n, _, _, _, angle in WHEELS))


@pytest.mark.filterwarnings("ignore::robotdyn.errors.RobotDynWarning")  # the fixture has no meshes
def test_sideways_motion_of_a_mecanum_base(tmp_path):
    (tmp_path / "mecanum.urdf").write_text(URDF)
    (tmp_path / "mecanum.toml").write_text(TOML)
    robot = load_robot(tmp_path / "mecanum.toml")
    assert robot.mobility == 3
    w0 = 2.0
    S = robot.reduced(robot.neutral(), [-w0, -w0, w0]).S  # full velocities from (w_fl, w_fr, w_rl)
    v = S @ np.array([-w0, -w0, w0])
    assert robot.coordinates == ["x", "y", "psi", "fl_joint", "fr_joint", "rl_joint", "rr_joint"]
    assert v[:3] == pytest.approx([0.0, R * w0, 0.0], abs=1e-12)  # x_dot, y_dot, psi_dot (at psi = 0, any axes)
    assert v[3:] == pytest.approx([-w0, -w0, w0, w0], abs=1e-12)  # fl, fr, rl, rr in the URDF's joint order
