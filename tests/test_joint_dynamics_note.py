"""A URDF's joint ``<dynamics damping friction>`` is left out of the dynamics, and ``info`` says so (found on the
ROSbot 2's description: each wheel joint carries 0.001 N m s/rad of damping and 0.001 N m of friction for Gazebo;
at 100 rad/s that damping is 0.1 N m, as much as the torque of a gentle run, and robotdyn ran without it and
without a word).

Fixture (this test's own): a fixed base with two independent joints, a hinge about the vertical axis (a rod of
Izz = 0.05 kg m^2; gravity exerts no torque on it) with damping 0.02 N m s/rad and friction 0.1 N m, and a
horizontal slider carrying m = 2 kg with damping 3 N s/m. Closed forms with no motor torque at velocities
(w, s): without damping both accelerations are 0; with the slider's damping applied by ``[[springs]]``
(c = 3 N s/m), the slider's is -c s / m.
"""

from __future__ import annotations

import numpy as np
import pytest

from robotdyn.interfaces.constraint_file import load_robot

URDF = """<?xml version="1.0"?>
<robot name="damped_fixture">
  <link name="base"/>
  <link name="rod"><inertial><mass value="1.0"/>
    <inertia ixx="0.03" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.05"/></inertial></link>
  <link name="carriage"><inertial><mass value="2.0"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="hinge" type="continuous"><parent link="base"/><child link="rod"/><axis xyz="0 0 1"/>
    {hinge}</joint>
  <joint name="slider" type="prismatic"><parent link="base"/><child link="carriage"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/>{slider}</joint>
</robot>
"""
HINGE = '<dynamics damping="0.02" friction="0.1"/>'
SLIDER = '<dynamics damping="3.0"/>'
SPRING = '\n[[springs]]\njoint = "slider"\ndamping = 3.0\n'


def _robot(folder, dynamics: bool, spring: bool):
    name = f"damped_{int(dynamics)}{int(spring)}"
    (folder / f"{name}.urdf").write_text(URDF.format(hinge=HINGE if dynamics else "", slider=SLIDER if dynamics else ""))
    (folder / f"{name}.toml").write_text(f'urdf = "{name}.urdf"\nroot = "fixed"\n' + (SPRING if spring else ""))
    return load_robot(folder / f"{name}.toml")


def test_info_names_the_unapplied_joint_dynamics(tmp_path):
    robot = _robot(tmp_path, dynamics=True, spring=False)
    notes = [n for n in robot.info()["mobility_notes"] if "<dynamics>" in n]
    assert notes == ["the description's joint <dynamics> are not applied (damping 0.02 N m s/rad on hinge; friction "
                     "0.1 N m on hinge; damping 3 N s/m on slider): apply a joint's damping with a [[springs]] entry "
                     "(joint, damping; stiffness 0) in the constraint file; joint dry friction is not modelled"]
    assert not any("<dynamics>" in n for n in _robot(tmp_path, False, False).info()["mobility_notes"])

    # what the note says, checked: the <dynamics> change nothing; the [[springs]] damping is applied (closed form)
    q, v = np.zeros(2), np.array([1.5, 0.4])  # (hinge, slider) [rad/s, m/s]
    assert robot.coordinates == ["hinge", "slider"]
    assert robot.forward_dynamics(q, v, []) == pytest.approx([0.0, 0.0], abs=1e-12)
    sprung = _robot(tmp_path, dynamics=True, spring=True)
    assert sprung.forward_dynamics(q, v, []) == pytest.approx([0.0, -3.0 * 0.4 / 2.0], abs=1e-12)
    notes = [n for n in sprung.info()["mobility_notes"] if "<dynamics>" in n]  # the slider's damping is applied now
    assert len(notes) == 1 and "on slider" not in notes[0] and "damping 0.02 N m s/rad on hinge" in notes[0]
