"""`simulate --plot` draws the x-y path of any planar/floating root; the traction plot draws every wheel that can
slip, drive wheels first, and the smallest mu of the best split where the wheels' own friction is undetermined
(the Quasimoro figure's friction panel used to be empty)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import robotdyn
from robotdyn.contact.traction import Traction
from robotdyn.interfaces.constraint_file import load_robot
from robotdyn.interfaces.plotting import plot_path, plot_traction, plot_trajectory, pose_columns, wheel_order
from robotdyn.simulation.trajectory import Trajectory

ROOT = Path(__file__).resolve().parents[1]
DIFF_DRIVE = ROOT / "examples/ros_ws/src/demo_description/robotdyn/diff_drive.toml"


def _circle(coordinates, velocity_names):
    """A root driving a quarter circle of radius 2 m, heading tangent: x = 2 sin s, y = 2 (1 - cos s), psi = s."""
    t = np.linspace(0.0, 1.0, 21)
    s = 0.5 * np.pi * t
    q = np.zeros((t.size, len(coordinates)))
    q[:, 0], q[:, 1], q[:, 2] = 2 * np.sin(s), 2 * (1 - np.cos(s)), s
    nu = np.zeros((t.size, len(velocity_names)))
    return Trajectory(t, q, nu, np.zeros_like(t), np.zeros_like(t), list(coordinates), list(velocity_names))


def test_pose_columns_of_planar_and_fixed_roots():
    robot = robotdyn.load("quasimoro")
    traj = _circle(robot.coordinates, robot.velocity_names)
    assert pose_columns(robot, traj) == ("x", "y", "psi")
    fixed = robotdyn.load("linkage_suspension")
    assert fixed.spec.root == "fixed" or pose_columns(fixed, _circle(fixed.coordinates, fixed.velocity_names))


def test_path_panel_draws_the_root_path_and_heading():
    robot = robotdyn.load("quasimoro")
    traj = _circle(robot.coordinates, robot.velocity_names)
    fig = plot_trajectory(traj, robot.velocity_names[:1], None, pose=pose_columns(robot, traj))
    (ax,) = [a for a in fig.axes if a.get_title() == "path in the world x-y plane"]
    x, y = ax.lines[0].get_data()
    np.testing.assert_allclose(x, 2 * np.sin(0.5 * np.pi * traj.t))
    np.testing.assert_allclose(y, 2 * (1 - np.cos(0.5 * np.pi * traj.t)))
    arrows = ax.collections[0]  # heading arrows: unit vectors (cos psi, sin psi); the last one points along +y
    np.testing.assert_allclose(arrows.U[-1], 0.0, atol=1e-12)
    np.testing.assert_allclose(arrows.V[-1], 1.0)
    assert plot_path(traj, "x", "y", "psi") is not None


def _traction(wheels, determined, minimum):
    n = 5
    t = np.linspace(0, 1, n)
    normal = np.full((n, len(wheels)), 20.0)
    return Traction(t, list(wheels), normal, np.zeros_like(normal), np.zeros_like(normal),
                    np.full(len(wheels), np.nan), np.array(determined), minimum_mu=minimum)


def test_friction_panel_shows_the_best_split_when_the_wheels_share_a_force():
    """Quasimoro's two wheels share one lateral force: their own required mu is undetermined, the minimum mu of
    the best split is not; the panel must draw it (it was empty)."""
    minimum = np.array([0.0, 0.005, 0.0103, 0.004, 0.0])
    fig = plot_traction(_traction(["wheel_A", "wheel_B"], [False, False], minimum))
    ax_mu = fig.axes[1]
    drawn = [line for line in ax_mu.lines if len(line.get_xdata())]
    assert len(drawn) == 1
    np.testing.assert_allclose(drawn[0].get_ydata(), minimum)
    assert "0.0103" in drawn[0].get_label()


def test_drive_wheels_first_and_supports_only_in_the_load_panel():
    robot = load_robot(DIFF_DRIVE)
    order, supports = wheel_order(robot, ["caster", "left", "right"])
    assert order == ["left", "right", "caster"] and supports == {"caster"}
    tr = _traction(["caster", "left", "right"], [True, True, True], None)
    tr.required_mu[:, 1:] = 0.2
    fig = plot_traction(tr, robot=robot)
    ax_n, ax_mu = fig.axes[:2]
    assert [line.get_label() for line in ax_n.lines[:3]] == ["left", "right", "caster (support, frictionless)"]
    assert [line.get_label() for line in ax_mu.lines if len(line.get_xdata())] == ["left", "right"]


def test_shading_names_what_it_marks():
    """A wheel in the air (load 0, e.g. a compliant wheel in flight) is shaded and the legend says what the shading
    is (it said "no-slip broken", which is wrong for wheels under a friction law); samples with load shade nothing."""
    tr = _traction(["front", "rear"], [True, True], None)
    tr.normal[2:4, 0] = 0.0
    fig = plot_traction(tr)
    ax_n = fig.axes[0]
    labels = [c.get_label() for c in ax_n.collections]
    assert labels == ["a wheel unloaded or beyond its mu"]
    np.testing.assert_array_equal(tr.broken().any(axis=1), [False, False, True, True, False])


def test_flight_has_its_own_band():
    """A compliant wheel in the air (load 0: flight, which its force law allows) is shaded in a band of its own,
    labelled as flight; a rigid wheel unloaded or beyond its mu keeps the other band. Synthetic loads: the compliant
    wheel "front" flies at samples 1-2, the rigid wheel "rear" needs mu 0.5 > 0.3 at sample 4."""
    tr = _traction(["front", "rear"], [True, True], None)
    tr.compliant = ["front"]
    tr.mu[:] = 0.3
    tr.normal[1:3, 0] = 0.0
    tr.required_mu[1:3, 0] = np.inf
    tr.required_mu[4, 1] = 0.5
    np.testing.assert_array_equal(tr.in_air().any(axis=1), [False, True, True, False, False])
    np.testing.assert_array_equal(tr.broken().any(axis=1), [False, False, False, False, True])
    ax_n = plot_traction(tr).axes[0]
    bands = {c.get_label(): c for c in ax_n.collections}
    assert set(bands) == {"a compliant wheel in the air (flight)", "a wheel unloaded or beyond its mu"}
    flight_x = np.concatenate([p.vertices[:, 0] for p in bands["a compliant wheel in the air (flight)"].get_paths()])
    assert flight_x.min() == 0.25 and flight_x.max() == 0.5  # samples 1-2 of t = 0, 0.25, ..., 1
    slip_x = np.concatenate([p.vertices[:, 0] for p in bands["a wheel unloaded or beyond its mu"].get_paths()])
    assert slip_x.min() == 1.0 and slip_x.max() == 1.0
    # the same wheel with a rigid contact: its zero load is a lift-off, shaded as such
    tr.compliant = []
    assert not tr.in_air().any()
    np.testing.assert_array_equal(tr.broken().any(axis=1), [False, True, True, False, True])


def test_traction_of_a_compliant_robot_names_its_flying_wheels():
    """examples/bump_base.toml over its bump: the front wheels (compliant) leave the crest near t = 0.07 s; the
    traction marks those samples as flight, not as a broken no-slip assumption."""
    from robotdyn.contact.traction import traction
    from robotdyn.interfaces.constraint_file import read
    from robotdyn.simulation.engine import simulate

    cf = read(ROOT / "examples/bump_base.toml")
    robot, sc = cf.robot(), cf.SCENARIOS["bump"]
    q0, nu0 = sc.initial_state(robot)
    traj = simulate(robot, 0.1, q0, nu0, sc.torque, n_out=11, progress=False)
    tr = traction(robot, traj, sc.torque)
    assert set(tr.compliant) == set(tr.wheels)
    air = tr.in_air()
    flying = {w for j, w in enumerate(tr.wheels) if air[:, j].any()}
    assert flying == {"front_left", "front_right"}
    assert not tr.broken()[air].any()
    assert (tr.normal[air] <= 0).all() and (tr.normal[~air] > 0).all()


def test_a_constant_required_mu_is_drawn_inside_the_axes():
    """A steady manoeuvre's required mu is constant (examples/cornering_car.toml: 0.491 all along); its line must lie
    inside the friction panel, not on its upper frame (the axes ended at the line's value)."""
    steady = 0.491 + 1e-12 * np.arange(5)  # (constant to rounding: the axes' autoscale ends at its value)
    fig = plot_traction(_traction(["a", "b"], [False, False], steady))
    bottom, top = fig.axes[1].get_ylim()
    assert bottom == 0.0 and top >= 1.05 * 0.491
