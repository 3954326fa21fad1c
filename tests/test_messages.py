"""Messages that say what to do (issue 25, item 8): each stumble of "bring your own robot" is answered by the
error or warning itself, naming the fix."""

from __future__ import annotations

import dataclasses
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

import robotdyn
from robotdyn.errors import InputError, RobotDynWarning
from robotdyn.interfaces.constraint_file import ConstraintFileError, _Tree, load_robot, read

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "examples/ros_ws/src"


def _diff_drive(tmp_path: Path, caster: str, extra: str = "") -> Path:
    """The demo differential drive (its ball caster on a fixed joint) with the caster entry ``caster``."""
    path = tmp_path / "dd.toml"
    path.write_text(f'''name = "dd"
urdf = "package://demo_description/urdf/diff_drive.urdf.xacro"
root = "planar"
package_dirs = ["{SRC.as_posix()}"]
labels = {{ right_wheel_joint = "theta_R", left_wheel_joint = "theta_L" }}
{extra}
[[wheels]]
name = "right"
joint = "right_wheel_joint"
radius = 0.08
[[wheels]]
name = "left"
joint = "left_wheel_joint"
radius = 0.08
[[wheels]]
name = "caster"
radius = 0.03
kind = "support"
{caster}
[[motors]]
name = "tau_R"
joint = "right_wheel_joint"
[[motors]]
name = "tau_L"
joint = "left_wheel_joint"
''')
    return path


def test_ball_caster_on_a_fixed_joint_names_the_frame_to_give(tmp_path):
    with pytest.raises(ConstraintFileError) as info:
        read(_diff_drive(tmp_path, 'joint = "caster_mount"'))
    assert "frame = 'caster_link'" in str(info.value) and "kind = 'support'" in str(info.value)


def test_ball_caster_by_frame_needs_no_axis(tmp_path):
    """A support without a spin joint gets an axle horizontal at rest: the same rows and contact forces as the
    file that writes axis = [0, 1, 0] (caster_link is not rotated from base_link)."""
    robot = load_robot(_diff_drive(tmp_path, 'frame = "caster_link"'))
    explicit = load_robot(_diff_drive(tmp_path, 'frame = "caster_link"\naxis = [0, 1, 0]'))
    caster = [c for c in robot.constraints if c.name == "caster"][0]
    np.testing.assert_allclose(caster.axis, [0.0, 1.0, 0.0], atol=1e-15)
    q, nu = robot.neutral(), np.array([1.0, 0.5])
    np.testing.assert_allclose(robot.reduced(q, nu).M, explicit.reduced(q, nu).M, rtol=1e-12)
    f1 = robot.contact_forces(q, nu, tau=[0.3, 0.1])
    f2 = explicit.contact_forces(q, nu, tau=[0.3, 0.1])
    np.testing.assert_allclose(f1.wheels[2].normal, f2.wheels[2].normal, rtol=1e-10)


def test_default_axis_of_a_support_is_horizontal_in_a_rotated_frame():
    """The frame's rotation from the URDF origins (rpy = fixed-axis roll, pitch, yaw: R = Rz Ry Rx) chained over
    two joints; the default axle R^T e_y is then the world y axis."""
    urdf = """<robot name="r"><link name="a"/><link name="b"/><link name="c"/>
      <joint name="j1" type="fixed"><parent link="a"/><child link="b"/><origin rpy="0.3 0 1.2"/></joint>
      <joint name="j2" type="continuous"><parent link="b"/><child link="c"/><origin rpy="0 -0.7 0.4"/>
      <axis xyz="0 0 1"/></joint></robot>"""
    tree = _Tree.parse(urdf, [])

    def rpy(r, p, y):
        Rx = np.array([[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]])
        Ry = np.array([[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]])
        Rz = np.array([[math.cos(y), -math.sin(y), 0], [math.sin(y), math.cos(y), 0], [0, 0, 1]])
        return Rz @ Ry @ Rx

    expected = rpy(0.3, 0, 1.2) @ rpy(0, -0.7, 0.4)
    np.testing.assert_allclose(tree.rotation("c"), expected, atol=1e-14)
    np.testing.assert_allclose(tree.rotation("c") @ (tree.rotation("c").T @ [0, 1, 0]), [0, 1, 0], atol=1e-14)


SWIVEL = """<?xml version="1.0"?>
<!-- a differential drive (wheels r = 0.1 m, track 0.5 m) with a swivel caster (trail 0.05 m, r = 0.05 m) -->
<robot name="swivel">
  <link name="base_link"><inertial><mass value="10"/><inertia ixx="0.1" iyy="0.1" izz="0.2" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="wl"><inertial><mass value="1"/><inertia ixx="0.005" iyy="0.01" izz="0.005" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="wr"><inertial><mass value="1"/><inertia ixx="0.005" iyy="0.01" izz="0.005" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="fork"><inertial><mass value="0.1"/><inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="cw"><inertial><mass value="0.1"/><inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="left_joint" type="continuous"><parent link="base_link"/><child link="wl"/><origin xyz="0 0.25 0"/><axis xyz="0 1 0"/></joint>
  <joint name="right_joint" type="continuous"><parent link="base_link"/><child link="wr"/><origin xyz="0 -0.25 0"/><axis xyz="0 1 0"/></joint>
  <joint name="swivel" type="continuous"><parent link="base_link"/><child link="fork"/><origin xyz="-0.4 0 0"/><axis xyz="0 0 1"/></joint>
  <joint name="caster_spin" type="continuous"><parent link="fork"/><child link="cw"/><origin xyz="-0.05 0 -0.05"/><axis xyz="0 1 0"/></joint>
</robot>
"""


def _swivel(tmp_path: Path, extra: str = "") -> Path:
    (tmp_path / "swivel.urdf").write_text(SWIVEL)
    path = tmp_path / "swivel.toml"
    path.write_text(f'''urdf = "swivel.urdf"
root = "planar"
{extra}
[[wheels]]
joint = "left_joint"
radius = 0.1
[[wheels]]
joint = "right_joint"
radius = 0.1
[[wheels]]
joint = "caster_spin"
radius = 0.05
[[motors]]
name = "tau_L"
joint = "left_joint"
[[motors]]
name = "tau_R"
joint = "right_joint"
''')
    return path


def test_automatic_independent_velocities_are_named_with_the_line_that_chooses(tmp_path):
    with pytest.warns(RobotDynWarning) as record:
        robot = load_robot(_swivel(tmp_path))
    (message,) = [str(w.message) for w in record if "independent" in str(w.message)]
    chosen = [v.removesuffix("_dot") for v in robot.velocity_names]
    assert set(chosen) != {"left_joint", "right_joint"}  # the automatic choice takes a caster velocity here
    assert f"those of {', '.join(chosen)}" in message
    assert "independent = ['left_joint', 'right_joint'] (the motor joints)" in message
    with warnings.catch_warnings():  # the suggested line silences it and gives the drive wheels' velocities
        warnings.simplefilter("error", RobotDynWarning)
        chosen = load_robot(_swivel(tmp_path, 'independent = ["left_joint", "right_joint"]'))
    assert chosen.velocity_names == ["left_joint_dot", "right_joint_dot"]


def test_no_warning_where_the_automatic_choice_is_the_motor_joints(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("error", RobotDynWarning)
        robot = load_robot(_diff_drive(tmp_path, 'frame = "caster_link"'))
    assert set(robot.velocity_names) == {"theta_R_dot", "theta_L_dot"}


def test_unknown_parameter_of_a_robot_without_parameters_says_how_to_declare_them(tmp_path):
    spec = read(_diff_drive(tmp_path, 'frame = "caster_link"')).SPEC
    with pytest.raises(InputError) as info:
        spec.parameter("mu")
    text = str(info.value)
    assert "has no parameters" in text and "[[parameters]]" in text and "xacro = true" in text
    assert "expected one of ;" not in text and not text.rstrip().endswith("one of")


def test_unknown_parameter_lists_the_declared_ones_and_the_xacro_route():
    with pytest.raises(InputError) as info:
        robotdyn.load("quasimoro").spec.parameter("link_mass")
    assert "expected one of m, M, J1" in str(info.value) and "xacro = true" in str(info.value)


def test_sweep_example_runs_without_error_rows(tmp_path):
    """examples/quasimoro_sweep.toml: 24 runs, every one physical (its file explains the bound M d^2 <= 0.3)."""
    from robotdyn.sweep import load, run
    from robotdyn.sweep.spec import from_toml

    spec = dataclasses.replace(from_toml(ROOT / "examples/quasimoro_sweep.toml"), t_end=0.05)
    res = run(spec, tmp_path / "out", workers=0, progress=False, plot=False)
    df = load(tmp_path / "out")
    assert len(df) == 24 and (df["status"] == "ok").all(), df["error"].dropna().tolist()
    assert res is not None


def test_the_suggested_line_where_the_motors_are_no_valid_set_keeps_the_automatic_choice(tmp_path):
    """examples/bump_base.toml without its 'independent' line: its four spin motors cannot be the independent set of
    ten free velocities (compliant wheels constrain none), so the warning suggests the automatic choice itself; the
    example carries that line, loads silently, and chooses as before."""
    example = ROOT / "examples/bump_base.toml"
    text = example.read_text().replace('urdf = "skid_steer.urdf.xacro"',
                                       f'urdf = "{(ROOT / "examples/skid_steer.urdf.xacro").as_posix()}"')
    start = text.index("independent = [")
    bare = tmp_path / "bump_base.toml"
    bare.write_text(text[:start] + text[text.index("]", start) + 1:])
    with pytest.warns(RobotDynWarning) as record:
        robot = read(bare).robot()
    (message,) = [str(w.message) for w in record if "independent" in str(w.message)]
    chosen = [robot.coordinates[i] for i in robot.independent_indices]
    assert chosen == robot.coordinates  # (all ten: nothing constrains them)
    assert message.endswith(f"add independent = [{', '.join(repr(c) for c in chosen)}] to the file"), message
    with warnings.catch_warnings():
        warnings.simplefilter("error", RobotDynWarning)
        given = read(example).robot()
    np.testing.assert_array_equal(given.independent_indices, robot.independent_indices)
