"""Issue 24, "advice that is wrong": the mobility notes of ``info`` checked beyond the neutral configuration, a hint
at rounded multiples of pi/2 in joint origins, and each warning printed once per run."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import robotdyn
from robotdyn.cli import main
from robotdyn.description.rounded_angles import rounded_angles
from robotdyn.interfaces.constraint_file import read

ROOT = Path(__file__).resolve().parent.parent
DEMO = ROOT / "examples" / "ros_ws" / "src" / "demo_description"
PLACEHOLDER = Path(__file__).parent / "data" / "placeholder_inertia"


def _yaw_in_null_space(robot, q) -> float:
    """Largest yaw component of an admissible velocity at q (SVD null space of all constraint rows)."""
    A = robot.rows_at(q).A
    _, s, Vt = np.linalg.svd(A)
    rank = int(np.sum(s > 1e-9 * s[0]))
    return float(np.abs(Vt[rank:, robot.description.joint_names.index("psi")]).max(initial=0.0))


def test_steerable_base_is_not_told_to_slip():
    robot = read(DEMO / "robotdyn" / "swerve3.toml").robot({})
    q0 = robot.neutral()
    assert _yaw_in_null_space(robot, q0) < 1e-12  # all three wheels parallel at neutral: no yaw here
    notes = robot.mobility_check()[1]
    assert not any("friction law" in n for n in notes)
    (note,) = [n for n in notes if "cannot turn" in n]
    assert "but it can without slip at other admissible ones" in note
    from robotdyn.constraints.base_mobility import reachable_motion

    q = reachable_motion(robot, "psi")
    assert np.abs(robot.constraint_residual(q)).max(initial=0.0) < 1e-9  # admissible (holonomic rows hold)
    assert _yaw_in_null_space(robot, q) > 1e-2  # and there the wheels allow turning (independent SVD check)


def test_fixed_parallel_axles_keep_the_slip_advice():
    robot = robotdyn.load("adaptable_wheel")  # three fixed, parallel axles: turning needs slip everywhere
    assert any("the base cannot turn: in every motion" in n and "friction law" in n for n in robot.mobility_check()[1])


def _diff_drive(tmp_path, yaw: str):
    urdf = (PLACEHOLDER / "placeholder.urdf").read_text().replace(
        '<origin xyz="0 -0.12 0"/>', f'<origin xyz="0 -0.12 0" rpy="0 0 {yaw}"/>')
    (tmp_path / "placeholder.urdf").write_text(urdf)
    (tmp_path / "placeholder.toml").write_text((PLACEHOLDER / "placeholder.toml").read_text().replace(
        'independent = ["wheel_left_joint", "wheel_right_joint"]\n', ""))
    return read(tmp_path / "placeholder.toml").robot({})


def test_rounded_pi_in_a_joint_origin_is_named(tmp_path):
    exact = _diff_drive(tmp_path, repr(np.pi))  # the right wheel turned round exactly: its axle still coaxial
    mobility, notes = exact.mobility_check()
    assert mobility == 2 and not any("rounded" in n for n in notes)
    rounded = _diff_drive(tmp_path, "3.14")  # axle tilted by 1.6e-3 rad: the lateral rows become independent
    mobility, notes = rounded.mobility_check()
    assert mobility == 1
    (note,) = [n for n in notes if "rounded multiple of pi/2" in n]
    assert "wheel_right_joint yaw = 3.14 (-0.0016 rad from pi)" in note
    found = rounded_angles(rounded.description.urdf)
    assert [(f.joint, f.text) for f in found] == [("wheel_right_joint", "pi")]
    assert found[0].off == pytest.approx(3.14 - np.pi)
    # 1.5708 and -1.57 are caught too; 0.5 and exact values are not
    text = ('<robot name="r"><joint name="a"><origin rpy="1.5708 -1.57 0.5"/></joint>'
            f'<joint name="b"><origin rpy="{np.pi / 2!r} 0 0"/></joint></robot>')
    assert [(f.joint, f.axis, f.text) for f in rounded_angles(text)] == [("a", "roll", "pi/2"), ("a", "pitch", "-pi/2")]


def test_each_warning_printed_once(capsys, tmp_path):
    """dump --forces builds the planar robot's floating twin: its mesh warnings were printed a second time. They are
    now the viewer's (and info's), not every command's: dump prints none, the viewer each once."""
    robot = ["--constraints", str(DEMO / "robotdyn" / "diff_drive.toml"), "--urdf",
             str(DEMO / "urdf" / "meshes_broken.urdf.xacro")]
    assert main(["dump", *robot, "--v", "0.1", "0", "--tau", "0", "0", "--forces"]) == 0
    assert [line for line in capsys.readouterr().err.splitlines() if "mesh" in line] == []
    assert main(["view", *robot, "--html", str(tmp_path / "page.html")]) == 0
    lines = [line for line in capsys.readouterr().err.splitlines() if line.startswith("robotdyn: warning:")]
    assert len(lines) == 2 and len(set(lines)) == 2 and all("mesh(es)" in line for line in lines)
