"""A vehicle that exact stick-slip friction brings to rest (issue 24): a tricycle whose two rear wheels are locked
(fixed to the chassis, ``friction = "stick_slip"``, mu = 0.5) and whose front wheel rolls freely, launched at
2 m/s (tests/data/locked_tricycle.urdf). Once the rear wheels stick no velocity is left (S has no columns): the
run crashed there (``ValueError: zero-size array to reduction operation maximum`` in reduction/projection.py), and
such a vehicle could not be started from the CLI (``nu0`` and ``independent`` refused: none is free when every wheel
sticks). Now it stays at rest to the end of the run, and a scenario's ``nu0`` gives its full initial velocities.

Closed form of the sliding phase (straight ahead, symmetric): with m = 11 kg, the front wheel's axle inertia
I = 0.005 kg m^2 and radius r = 0.1 m, deceleration a, rear normal load N_r (both wheels) and front load N_f:

- vertical: N_r + N_f = m g;
- horizontal: m a = mu N_r - f, the front contact's force f = I a / r^2 forward (it slows the wheel's spin);
- pitch about the centre of mass (x_c = 0.4/11 m ahead of the chassis origin, 0.1 m above the ground): the ground
  forces' moment equals the rate of the spin's angular momentum, -I a / r:
  (0.2 + x_c + 0.1 mu) N_r - 0.1 f - (0.4 - x_c) N_f = -I a / r.

The vehicle stops at t* = v0 / a after v0^2 / (2a), having lost m v0^2/2 + I (v0/r)^2/2 = 23 J to friction."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from robotdyn.robot import Robot, RobotSpec, Wheel
from robotdyn.simulation.engine import simulate
from robotdyn.simulation.stick_slip import simulate as hybrid

URDF = Path(__file__).parent / "data" / "locked_tricycle.urdf"
M, I, R, MU, G, V0 = 11.0, 0.005, 0.1, 0.5, 9.81, 2.0


def tricycle() -> Robot:
    spec = RobotSpec(name="locked_tricycle", title="tricycle with locked stick-slip rear wheels", xacro=str(URDF),
                     root="floating",
                     wheels=[Wheel("rear_left", R, name="rear_left", friction="stick_slip", mu=MU),
                             Wheel("rear_right", R, name="rear_right", friction="stick_slip", mu=MU),
                             Wheel("front_wheel", R, name="front")])
    return Robot(spec)


def closed_form() -> float:
    """The deceleration a [m/s^2] of the sliding phase (unknowns a, N_r, N_f)."""
    xc = 0.4 / M
    f = I / R**2  # front contact force per unit deceleration
    A = np.array([[0.0, 1.0, 1.0],
                  [M + f, -MU, 0.0],
                  [-0.1 * f + I / R, 0.2 + xc + 0.1 * MU, -(0.4 - xc)]])
    a, _, _ = np.linalg.solve(A, [M * G, 0.0, 0.0])
    return float(a)


def start(robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    q0 = robot.neutral()
    q0[robot.coordinate_index("z")] = R
    v0 = np.zeros(robot.nq)
    v0[robot.coordinate_index("x")] = V0
    v0[robot.coordinate_index("front_spin")] = V0 / R
    return q0, v0


def test_launched_tricycle_slides_to_rest_and_stays_there():
    robot = tricycle()
    assert robot.mobility == 0  # every wheel sticking holds it
    q0, v0 = start(robot)
    traj = hybrid(robot, 1.0, q0, v0, n_out=11, progress=False)  # before: ValueError: zero-size array ... maximum
    a = closed_form()
    t_star, x_star = V0 / a, V0**2 / (2 * a)
    switches = traj.stats["switches"]
    assert {s["wheel"] for s in switches} == {"rear_left", "rear_right"} and all(s["phase"] == "stick" for s in switches)
    assert all(s["t"] == pytest.approx(t_star, rel=1e-7) for s in switches)
    x, xdot = traj.column("x"), traj.column("x_dot")
    sliding = traj.t < t_star
    np.testing.assert_allclose(x[sliding], V0 * traj.t[sliding] - 0.5 * a * traj.t[sliding] ** 2, rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(x[~sliding], x_star, rtol=1e-8)  # at rest to the end of the run
    assert np.all(xdot[~sliding] == 0.0) and traj.t[-1] == 1.0
    loss = M * V0**2 / 2 + I * (V0 / R) ** 2 / 2
    assert loss == pytest.approx(23.0)
    assert traj.energy[0] - traj.energy[-1] == pytest.approx(loss, rel=1e-8)
    assert traj.friction_work[-1] == pytest.approx(-loss, rel=1e-8)


def test_tricycle_at_rest_stays_at_rest():
    """Started at rest, the statically indeterminate sticking forces (two locked wheels and a rolling one) have a
    split inside the cones (zero friction): before, the one-line "statically indeterminate" error at t = 0."""
    robot = tricycle()
    q0, _ = start(robot)
    traj = simulate(robot, 0.5, q0, np.zeros(robot.nq), n_out=6, progress=False)
    assert traj.stats["switches"] == [] and len(traj.t) == 6
    np.testing.assert_array_equal(traj.q, np.tile(q0, (6, 1)))


def test_cli_starts_a_vehicle_that_sticking_wheels_hold(tmp_path, capsys):
    """A constraint file's scenario gives the full initial velocities by coordinate (before: "nu0 'x' is not an
    independent velocity"; with `independent`, "the constraints leave 0 velocities free")."""
    from robotdyn.cli import main

    wheels = "".join(f"""
[[wheels]]
name = "{w}"
frame = "{w}"
axis = [0, 1, 0]
radius = {R}
friction = "stick_slip"
mu = {MU}
""" for w in ("rear_left", "rear_right"))
    text = f"""name = "locked_tricycle"
urdf = "{URDF}"
root = "floating"
neutral = {{ z = {R} }}
INDEPENDENT
{wheels}
[[wheels]]
name = "front"
joint = "front_spin"
radius = {R}

[[scenarios]]
name = "launch"
t_end = 1.0
nu0 = {{ x = {V0}, front_spin = {V0 / R} }}
"""
    a = closed_form()
    import json

    for independent, t_end in (("", 1.0), ('independent = ["x", "yaw"]', 0.2)):  # the second stops sliding
        path = tmp_path / "tricycle.toml"
        path.write_text(text.replace("INDEPENDENT", independent))
        assert main(["simulate", "--constraints", str(path), "--scenario", "launch", "--quiet", "--json",
                     "--t-end", str(t_end)]) == 0, capsys.readouterr().err
        out = json.loads(capsys.readouterr().out)
        if t_end == 1.0:
            assert out["final"]["x"] == pytest.approx(V0**2 / (2 * a), rel=1e-8)
            assert [s["t"] for s in out["switches"]] == pytest.approx([V0 / a] * 2, rel=1e-7)
        else:
            assert out["final"]["x"] == pytest.approx(V0 * t_end - a * t_end**2 / 2, rel=1e-8)
            assert out["switches"] == []
