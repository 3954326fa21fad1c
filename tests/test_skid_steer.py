"""The skid-steer rover example (examples/skid_steer.toml): four non-steering wheels that turn the rover only by
slipping, against a closed form of steady skid-steer turning.

Closed form (derived here for the linear tyre law F = -f_n k s, equal loads f_n = m g / 4, wheels at (+-a, +-b)
in the chassis frame, turning in place with wheel rates -phi (left) and +phi (right) and yaw rate omega): each
contact point slips by s = (-omega y_i - r phi_i, omega x_i); the yaw moment sum_i (x_i F_y - y_i F_x) vanishes
when omega (a^2 + b^2) = b r phi, and each wheel's torque balance tau = r f_n k s_x gives
phi = tau (a^2 + b^2) / (r^2 f_n k a^2). The instantaneous centres of rotation of the two sides (Mandow et al.
2007, "Experimental kinematics for wheeled skid-steer mobile robots"; Kozlowski & Pazderski 2004) lie at
y = +-r phi / omega = +-(a^2 + b^2) / b: symmetric, with the expansion factor chi = 1 + (a/b)^2 > 1 (chi = 1 would
be a differential drive without slip)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from robotdyn.interfaces.constraint_file import read

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "skid_steer.toml"
A, B, R, K, TAU, G = 0.25, 0.22, 0.1, 5.0, 0.3, 9.81


@pytest.fixture(scope="module")
def rover():
    mod = read(EXAMPLE)
    return mod, mod.robot()


@pytest.fixture(scope="module")
def turn(rover):
    mod, robot = rover
    return robot, mod.SCENARIOS["turn_in_place"].run(robot, t_end=6.0, n_out=61, progress=False)


def test_turns_in_place_at_the_closed_form_rates(turn):
    robot, traj = turn
    mass = sum(robot.model.inertias[i].mass for i in range(robot.model.njoints))
    fn = mass * G / 4
    phi = TAU * (A**2 + B**2) / (R**2 * fn * K * A**2)
    omega = B * R * phi / (A**2 + B**2)
    assert traj.column("yaw_dot")[-1] == pytest.approx(omega, rel=1e-6)
    for wheel, sign in [("front_left", -1), ("rear_left", -1), ("front_right", 1), ("rear_right", 1)]:
        assert traj.column(f"{wheel}_spin_dot")[-1] == pytest.approx(sign * phi, rel=1e-6)
    # the side ICRs: symmetric, expansion factor 1 + (a/b)^2
    y_left = R * traj.column("rear_left_spin_dot")[-1] / traj.column("yaw_dot")[-1]
    y_right = R * traj.column("rear_right_spin_dot")[-1] / traj.column("yaw_dot")[-1]
    assert y_left == pytest.approx(-y_right, rel=1e-6)
    assert (y_right - y_left) / (2 * B) == pytest.approx(1 + (A / B) ** 2, rel=1e-6)
    assert np.hypot(traj.column("x")[-1], traj.column("y")[-1]) < 1e-6  # it turns about its centre


def test_loads_and_friction_while_turning(turn):
    """Steady turning in place: every wheel carries a quarter of the weight; friction only dissipates."""
    robot, traj = turn
    mass = sum(robot.model.inertias[i].mass for i in range(robot.model.njoints))
    f = robot.contact_forces(traj.q[-1], traj.nu[-1], tau=[-TAU, TAU, -TAU, TAU])
    for w in f.wheels:
        assert w.kind == "slipping" and w.load_determined
        assert w.normal == pytest.approx(mass * G / 4, rel=1e-6)
    assert np.all(np.diff(traj.friction_work) <= 1e-12)


def test_without_slip_the_rover_cannot_turn(rover):
    """The same rover with wheels that roll without slipping has mobility 1 on flat ground; its four normal rows
    on a rigid chassis and oscillating axle are still determinate, but the no-slip rows lock the yaw."""
    from dataclasses import replace

    from robotdyn.robot import Robot

    mod, robot = rover
    spec = replace(mod.SPEC, wheels=[replace(w, friction="rolling", stiffness=None) for w in mod.SPEC.wheels],
                   independent=None)
    rolling = Robot(spec)
    A_rows = rolling.rows_at(rolling.neutral()).A
    assert rolling.nq - np.linalg.matrix_rank(A_rows) == 1
    assert rolling.mobility == 1


def test_info_explains_a_locked_base(tmp_path, capsys):
    """robotdyn info on the rover with wheels that roll without slipping: mobility 1 (n - rank A), and the note
    that turning requires slip; with its slipping wheels, mobility 7 and no such note."""
    from robotdyn.cli.commands import main

    text = EXAMPLE.read_text().replace('friction = "linear"', 'friction = "rolling"').replace("stiffness = 5.0", "")
    text = text.replace("mu = 0.8", "").replace('urdf = "skid_steer.urdf.xacro"',
                                                 f'urdf = "{EXAMPLE.parent / "skid_steer.urdf.xacro"}"')
    text = "\n".join(line for line in text.splitlines() if not line.startswith("independent ="))
    rolling = tmp_path / "rolling.toml"
    rolling.write_text(text)
    assert main(["info", "--constraints", str(rolling)]) == 0
    out = capsys.readouterr().out
    assert "mobility at the neutral configuration: 1 (n - rank A)" in out and "turning requires slip" in out
    assert main(["info", "--constraints", str(EXAMPLE)]) == 0
    out = capsys.readouterr().out
    assert "mobility at the neutral configuration: 7" in out and "turning requires slip" not in out


def test_support_wheels_from_toml(tmp_path):
    """kind = "support" in a constraint file: the normal row only (mobility of the rover grows by the two
    tangential rows of each wheel made a support)."""
    text = EXAMPLE.read_text().replace('urdf = "skid_steer.urdf.xacro"',
                                       f'urdf = "{EXAMPLE.parent / "skid_steer.urdf.xacro"}"')
    text = "\n".join(line for line in text.splitlines() if not line.startswith("independent ="))
    text = "\n".join('kind = "support"' if line.startswith("friction =") else line for line in text.splitlines()
                     if not line.startswith(("stiffness =", "mu =")))
    path = tmp_path / "support.toml"
    path.write_text(text)
    robot = read(path).robot()
    assert [type(c).__name__ for c in robot.constraints] == ["SupportWheel"] * 4
    assert [lab.split(".")[1] for lab in robot.rows_at(robot.neutral()).labels] == ["normal"] * 4
