"""A description whose macro reads ``$(arg NAME)`` that the top-level file does not declare: the one-line error says
what to declare and where (found on the ROSbot 2's description: its robot macro reads ``$(arg use_sim)`` and relies
on the package's own top-level file, which also includes sensor packages a user may not have, to declare it; a
user's own top-level file that includes only the macro got xacro's bare "Undefined substitution argument use_sim",
and robotdyn refuses ``--xacro-arg use_sim=...`` for an argument no ``<xacro:arg>`` declares).

Also: the macro file itself given as the description (it expands to no joints).

Fixture: a package of this test's own, one macro (a box with one wheel) whose wheel mass is ``$(arg wheel_mass)``.
"""

from __future__ import annotations

import pytest

from robotdyn.cli import main
from robotdyn.interfaces.constraint_file import load_robot

MACRO = """<?xml version="1.0"?>
<robot xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:macro name="cart">
    <link name="base_link"><inertial><mass value="1.0"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
    <link name="wheel"><inertial><mass value="$(arg wheel_mass)"/>
      <inertia ixx="1e-4" ixy="0" ixz="0" iyy="2e-4" iyz="0" izz="1e-4"/></inertial></link>
    <joint name="wheel_joint" type="continuous"><parent link="base_link"/><child link="wheel"/>
      <origin xyz="0 0 0.05"/><axis xyz="0 1 0"/></joint>
  </xacro:macro>
</robot>
"""
TOP = """<?xml version="1.0"?>
<robot name="cart" xmlns:xacro="http://www.ros.org/wiki/xacro">
  {declare}
  <xacro:include filename="$(find cart_description)/urdf/cart_macro.urdf.xacro"/>
  <xacro:cart/>
</robot>
"""
TOML = 'urdf = "{top}"\npackage_dirs = ["ws"]\nroot = "planar"\n\n[[wheels]]\nname = "w"\njoint = "wheel_joint"\nradius = 0.05\n'


@pytest.fixture()
def folder(tmp_path):
    pkg = tmp_path / "ws" / "cart_description"
    (pkg / "urdf").mkdir(parents=True)
    (pkg / "package.xml").write_text("<package format='3'><name>cart_description</name></package>")
    (pkg / "urdf" / "cart_macro.urdf.xacro").write_text(MACRO)
    for top, declare in (("bare", ""), ("declared", '<xacro:arg name="wheel_mass" default="0.1"/>')):
        (tmp_path / f"{top}.urdf.xacro").write_text(TOP.format(declare=declare))
        (tmp_path / f"{top}.toml").write_text(TOML.format(top=f"{top}.urdf.xacro"))
    return tmp_path


def test_undeclared_argument_names_the_declaration(folder, capsys):
    assert main(["info", "--constraints", str(folder / "bare.toml")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err
    assert err.endswith("cannot expand xacro bare.urdf.xacro: Undefined substitution argument wheel_mass; expected "
                        '<xacro:arg name="wheel_mass" default="..."/> in bare.urdf.xacro (the description reads $(arg wheel_mass): '
                        "the top-level file declares it, also to set it with --xacro-arg or xacro_args)")


def test_declared_argument_is_read(folder):
    """The advice followed: the description loads, and the argument reaches the macro (total mass 1 + m)."""
    import pinocchio as pin

    robot = load_robot(folder / "declared.toml", xacro_args={"wheel_mass": "0.25"})  # not the default 0.1
    assert pin.computeTotalMass(robot.model) == pytest.approx(1.25, abs=1e-12)


def test_a_macro_file_given_as_the_description(folder, capsys):
    """The package's macro file itself (it defines the robot but never calls it, so it expands to no joints): the
    error says so instead of only "no joint named 'wheel_joint'"."""
    macro = folder / "ws" / "cart_description" / "urdf" / "cart_macro.urdf.xacro"
    assert main(["info", "--constraints", str(folder / "declared.toml"), "--urdf", str(macro)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.endswith(
        "wheels[0] (w): joint: no joint named 'wheel_joint' in cart_macro.urdf.xacro, which has no joints at all; "
        "expected the description's top-level file (a file of Xacro macros defines a robot only where it is called)")
