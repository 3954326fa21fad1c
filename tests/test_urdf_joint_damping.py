"""A URDF's joint ``<dynamics damping>`` is applied (as Gazebo, Drake and MuJoCo's URDF import apply it) as a viscous
joint torque -d q', through every door; ``urdf_damping = false`` leaves it out; a joint damped both by the URDF and by
a ``[[springs]]`` entry is refused in one line; a joint's dry friction is named by ``info`` and not applied (found
on the ROSbot 2's description: its wheel joints carry 0.001 N m s/rad, as much as a gentle run's motor torque at
100 rad/s, and robotdyn ran without it).

Fixtures (this test's own):

- ``damped``: a fixed base with two independent joints: a hinge about the vertical axis carrying a rod (Izz = 0.05
  kg m^2 about the axis; gravity exerts no torque on it) with damping d_h = 0.02 N m s/rad and friction 0.1 N m, and
  a horizontal slider carrying m = 2 kg with damping d_s = 3 N s/m. With no torque at velocities (w, s) the
  accelerations are -d_h w / Izz and -d_s s / m (0 without the damping).
- ``coaster``: a differential drive (planar root; base 4 kg with its mass centre on the axle, two wheels of 0.5 kg,
  radius r = 0.1 m, axial inertia Iw = 0.004 kg m^2, 0.2 m either side; izz of base 0.08, of each wheel 0.002),
  each wheel joint damped by d = 0.01 N m s/rad. Rolling straight at wheel rate w, the kinetic energy is
  (1/2) J w^2 with J = (m_total r^2 + 2 Iw) = 5 * 0.01 + 0.008 = 0.058 kg m^2, and the dampers take 2 d w^2, so
  J w' = -2 d w: w(t) = w0 exp(-2 d t / J). In the reduced coordinates (w_L, w_R) the mass matrix is
  [[a, b], [b, a]] with a + b = J / 2 (straight) and a - b = J_turn / 2 (turning on the spot, w_R = -w_L = w:
  yaw rate r w / 0.2, so J_turn = (0.08 + 2 * 0.002 + 2 * 0.5 * 0.2^2) (r / 0.2)^2 + 2 Iw = 0.039 kg m^2); the
  linearised dnu'/dnu = -d M_r^-1 has the eigenvalues -2 d / J and -2 d / J_turn on (1, 1) and (1, -1).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from robotdyn.cli.commands import main
from robotdyn.interfaces.constraint_file import ConstraintFileError, load_robot
from robotdyn.simulation.engine import simulate

DAMPED = """<?xml version="1.0"?>
<robot name="damped_fixture">
  <link name="base"/>
  <link name="rod"><inertial><mass value="1.0"/>
    <inertia ixx="0.03" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.05"/></inertial></link>
  <link name="carriage"><inertial><mass value="2.0"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="hinge" type="continuous"><parent link="base"/><child link="rod"/><axis xyz="0 0 1"/>
    <dynamics damping="0.02" friction="0.1"/></joint>
  <joint name="slider" type="prismatic"><parent link="base"/><child link="carriage"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/><dynamics damping="3.0"/></joint>
</robot>
"""
D_H, IZZ, D_S, MASS = 0.02, 0.05, 3.0, 2.0

COASTER = """<?xml version="1.0"?>
<robot name="coaster">
  <link name="base"><inertial><mass value="4.0"/>
    <inertia ixx="0.05" iyy="0.05" izz="0.08" ixy="0" ixz="0" iyz="0"/></inertial></link>
  {wheels}
</robot>
"""
WHEEL = """<link name="{side}_wheel"><inertial><mass value="0.5"/>
    <inertia ixx="0.002" iyy="0.004" izz="0.002" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="{side}_spin" type="continuous"><parent link="base"/><child link="{side}_wheel"/>
    <origin xyz="0 {y} 0"/><axis xyz="0 1 0"/><dynamics damping="0.01"/></joint>
"""
COASTER_TOML = """urdf = "coaster.urdf"
root = "planar"
independent = ["left_spin", "right_spin"]
{extra}
[[wheels]]
name = "left"
joint = "left_spin"
radius = 0.1
[[wheels]]
name = "right"
joint = "right_spin"
radius = 0.1
[[motors]]
name = "tau_L"
joint = "left_spin"
[[motors]]
name = "tau_R"
joint = "right_spin"
"""
D, J, J_TURN = 0.01, 5 * 0.1**2 + 2 * 0.004, (0.08 + 2 * 0.002 + 2 * 0.5 * 0.2**2) * (0.1 / 0.2) ** 2 + 2 * 0.004


def _damped(folder, extra: str = ""):
    (folder / "damped.urdf").write_text(DAMPED)
    (folder / "damped.toml").write_text('urdf = "damped.urdf"\nroot = "fixed"\nindependent = ["hinge", "slider"]\n'
                                        + extra)
    return load_robot(folder / "damped.toml")


def _coaster_file(folder, extra: str = ""):
    (folder / "coaster.urdf").write_text(COASTER.format(wheels=WHEEL.format(side="left", y=0.2)
                                                        + WHEEL.format(side="right", y=-0.2)))
    (folder / "coaster.toml").write_text(COASTER_TOML.format(extra=extra))
    return folder / "coaster.toml"


@pytest.fixture(scope="module")
def coaster(tmp_path_factory):
    return load_robot(_coaster_file(tmp_path_factory.mktemp("coaster")))


def test_damping_is_applied_and_info_says_so(tmp_path):
    robot = _damped(tmp_path)
    q, v = np.zeros(2), np.array([1.5, 0.4])  # (hinge, slider) [rad/s, m/s]
    assert robot.forward_dynamics(q, v, []) == pytest.approx([-D_H * 1.5 / IZZ, -D_S * 0.4 / MASS], abs=1e-12)
    # the torque that holds the speeds is the dampers' (a motor's terminal speed under tau is tau / d)
    assert robot.inverse_dynamics(q, v, np.zeros(2))[0] == pytest.approx([D_H * 1.5, D_S * 0.4], abs=1e-12)
    notes = [n for n in robot.info()["mobility_notes"] if "the description's joint" in n]
    assert notes == ["the description's joint damping is applied as a viscous joint torque -d q' (0.02 N m s/rad on "
                     "hinge; 3 N s/m on slider); urdf_damping = false in the constraint file leaves it out",
                     "the description's joint dry friction is not applied (0.1 N m on hinge): robotdyn does not model "
                     "joint dry friction"]
    assert [repr(s) for s in robot.springs] == [
        "SpringForce('hinge', k=0, c=0.02, rest=0 rad, c from the URDF's <dynamics>)",
        "SpringForce('slider', k=0, c=3, rest=0 m, c from the URDF's <dynamics>)"]

    off = _damped(tmp_path, "urdf_damping = false\n")  # the papers' ideal joints
    assert off.springs == [] and off.forward_dynamics(q, v, []) == pytest.approx([0.0, 0.0], abs=1e-12)
    assert [n for n in off.info()["mobility_notes"] if "the description's joint" in n][0] == (
        "the description's joint damping is not applied (urdf_damping = false): 0.02 N m s/rad on hinge; 3 N s/m on "
        "slider")
    # a stiffness-only [[springs]] entry on a damped joint takes the URDF's damping: a = (-k s_pos - d_s s) / m
    sprung = _damped(tmp_path, '[[springs]]\njoint = "slider"\nstiffness = 50.0\n')
    assert sprung.forward_dynamics(np.array([0.0, 0.1]), v, []) == pytest.approx(
        [-D_H * 1.5 / IZZ, (-50.0 * 0.1 - D_S * 0.4) / MASS], abs=1e-12)


def test_damping_given_twice_is_one_line_naming_both_ways_out(tmp_path):
    with pytest.raises(ConstraintFileError) as info:
        _damped(tmp_path, '[[springs]]\njoint = "slider"\ndamping = 3.0\n')  # session 33's advice, followed
    msg = str(info.value)
    assert "\n" not in msg and msg.startswith(str(tmp_path / "damped.toml"))
    assert ("joint 'slider' is damped twice: 3 N s/m by the description's <dynamics damping> (applied by default) and "
            "3 N s/m by spring 'slider'; expected one: remove the spring's damping, or set urdf_damping = false to keep "
            "the spring's only") in msg
    robot = _damped(tmp_path, 'urdf_damping = false\n[[springs]]\njoint = "slider"\ndamping = 5.0\n')  # way out 2
    assert robot.forward_dynamics(np.zeros(2), np.array([1.5, 0.4]), []) == pytest.approx([0.0, -5.0 * 0.4 / MASS])
    assert main(["info", "--constraints", str(tmp_path / "damped.toml")]) == 0
    with pytest.raises(ConstraintFileError, match="urdf_damping = 'no'; expected true"):
        _damped(tmp_path, 'urdf_damping = "no"\n')


@pytest.mark.parametrize("engine", ["compiled", "scipy"])
def test_a_damped_wheel_coasts_down_exponentially(coaster, engine):
    """w(t) = w0 exp(-2 d t / J) on both engines; the energy lost is the dampers' work."""
    w0 = 10.0
    traj = simulate(coaster, 1.0, coaster.neutral(), [w0, w0], None, n_out=5, engine=engine, rtol=1e-10,
                    atol=1e-10, progress=False)
    assert traj.stats["engine"].startswith(engine)
    expected = w0 * np.exp(-2 * D * traj.t / J)
    assert np.abs(traj.nu - expected[:, None]).max() < 1e-7 * w0
    assert traj.column("x")[-1] == pytest.approx(0.1 * w0 * J / (2 * D) * (1 - math.exp(-2 * D / J)), rel=1e-7)
    assert traj.energy - traj.energy[0] == pytest.approx(traj.damper_work, abs=1e-8)
    assert traj.damper_work[-1] == pytest.approx(-0.5 * J * (w0**2 - expected[-1] ** 2), rel=1e-7)


def test_the_switch_leaves_the_damping_out_on_the_compiled_engine(tmp_path):
    robot = load_robot(_coaster_file(tmp_path, "urdf_damping = false"))
    traj = simulate(robot, 1.0, robot.neutral(), [10.0, 10.0], None, n_out=3, engine="compiled", progress=False)
    assert traj.nu == pytest.approx(np.full((3, 2), 10.0), abs=1e-9)  # undamped: w = w0
    assert traj.column("x")[-1] == pytest.approx(1.0, rel=1e-9)  # r w0 t


def test_dump_and_linearize_carry_the_damping(coaster, tmp_path, capsys):
    w = 10.0
    path = _coaster_file(tmp_path)
    assert main(["dump", "--constraints", str(path), "--v", str(w), str(w), "--tau", "0", "0", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["applied"] == pytest.approx([-D * w, -D * w], abs=1e-12)  # S^T Q: -d w on each wheel
    assert out["a"] == pytest.approx([-2 * D * w / J] * 2, rel=1e-12)
    assert main(["dump", "--constraints", str(path), "--v", str(w), str(w), "--tau", "0", "0"]) == 0
    assert "S^T Q (joint springs and dampers" in capsys.readouterr().out

    from robotdyn.reduction.linearization import linearize

    lin = linearize(coaster, coaster.neutral(), np.zeros(2), np.zeros(2))
    iv = [lin.states.index(s) for s in coaster.velocity_names]
    V = lin.A[np.ix_(iv, iv)]  # d nu' / d nu = -d M_r^-1
    assert V @ [1.0, 1.0] == pytest.approx([-2 * D / J] * 2, rel=1e-9)
    assert V @ [1.0, -1.0] == pytest.approx([-2 * D / J_TURN, 2 * D / J_TURN], rel=1e-9)


def test_refusals_of_springs_name_the_switch(coaster, tmp_path):
    """What joint dampers are refused by says how to leave the URDF's out (the compiled model serves them:
    tests/test_compiled_springs.py)."""
    from robotdyn.errors import RobotDynError
    from robotdyn.fast.compiled import why_not
    from robotdyn.simulation.batch import simulate_many

    hint = ("(the description's <dynamics damping> on left_spin, right_spin is applied as joint dampers: "
            "urdf_damping = false in the constraint file leaves it out)")
    assert why_not(coaster) is None
    with pytest.raises(RobotDynError) as info:
        simulate_many(coaster, 0.1, [coaster.neutral()] * 2, np.zeros((2, 2)), progress=False)
    assert str(info.value).endswith(hint)
    path = _coaster_file(tmp_path)
    path.write_text(path.read_text().replace("radius = 0.1", 'radius = 0.1\nfriction = "stick_slip"\nmu = 0.8'))
    with pytest.raises(RobotDynError) as info:
        stick_slip = load_robot(path)
        simulate(stick_slip, 0.1, stick_slip.neutral(), [1.0, 1.0], None, progress=False)
    assert str(info.value).endswith(hint)


def test_a_sweep_carries_the_damping(tmp_path):
    """The sweep door: a coasting scenario's final wheel rate is the closed form w0 exp(-2 d t / J), and the energy
    balance counts the dampers' work (no drift)."""
    import pyarrow.parquet as pq

    path = _coaster_file(tmp_path, '[[parameters]]\nname = "g"\ndefault = 9.81\nunit = "m/s^2"\n')
    path.write_text(path.read_text() + '[[scenarios]]\nname = "coast"\nt_end = 1.0\ntorque = [0.0, 0.0]\n'
                    'nu0 = { left_spin = 10.0, right_spin = 10.0 }\n')
    assert main(["sweep", "--constraints", str(path), "--scenario", "coast", "--workers", "0", "--quiet", "--no-plot",
                 "--out", str(tmp_path / "sweep"), "--vary", "g=9.81,9.8"]) == 0
    rows = pq.read_table(tmp_path / "sweep" / "results.parquet").to_pylist()
    assert [r["status"] for r in rows] == ["ok", "ok"]
    for r in rows:  # (gravity does no work on a level coast)
        assert r["final.left_spin_dot"] == pytest.approx(10.0 * math.exp(-2 * D / J), rel=1e-6)
        assert abs(r["energy.drift"]) < 1e-6

