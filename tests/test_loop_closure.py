"""Loop closures on their own: a planar four-bar linkage cut at the coupler-rocker joint.

Checks the closure Jacobian and drift against finite differences, the rank-revealing removal of redundant rows
(closing all five components of the cut revolute joint in a planar loop), energy conservation under gravity with
the position residual held at the tolerance level, and the singular-projection error at a dead centre."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from robotdyn.constraints.constraint import KinematicState
from robotdyn.errors import DescriptionError, SingularConstraintError
from robotdyn.constraints.loop_closure import LoopClosure
from robotdyn.reduction.projection import project
from robotdyn.robot import Closure, Robot, RobotSpec
from robotdyn.simulation.engine import simulate

FOURBAR = Path(__file__).parent / "data" / "fourbar.urdf"


def fourbar(components=("x", "z"), independent=("crank_joint",)) -> Robot:
    spec = RobotSpec(name="fourbar", title="four-bar", xacro=FOURBAR, root="fixed",
                     closures=[Closure("coupler_tip", "rocker_tip", components)],
                     independent=list(independent) if independent else None)
    return Robot(spec)


def close(robot: Robot, q: np.ndarray, keep: str = "crank_joint") -> np.ndarray:
    """Newton on the closure residual for the coordinates other than ``keep`` (qdot = v, so A is the Jacobian)."""
    q = q.copy()
    free = [i for i in range(robot.nq) if robot.coordinates[i] != keep]
    for _ in range(50):
        kin = KinematicState(robot.model, robot.data, q, np.zeros(robot.nq))
        rows = robot.constraint_rows(kin)
        if np.max(np.abs(rows.residual)) < 1e-14:
            break
        q[free] -= np.linalg.lstsq(rows.A[:, free], rows.residual, rcond=None)[0]
    return q


def closed_state(robot, crank: float) -> np.ndarray:
    q = np.zeros(robot.nq)
    q[robot.coordinate_index("crank_joint")] = crank
    q[robot.coordinate_index("coupler_joint")] = -crank + 0.6
    q[robot.coordinate_index("rocker_joint")] = 1.7
    return close(robot, q)


def test_closure_jacobian_and_drift_match_finite_differences():
    robot = fourbar(("x", "y", "z", "rx", "rz"))
    closure = robot.constraints[0]
    rng = np.random.default_rng(0)
    h = 1e-6
    for _ in range(20):
        q, v = rng.uniform(-2, 2, robot.nq), rng.normal(size=robot.nq)
        rows = closure.rows(KinematicState(robot.model, robot.data, q, v))
        A = lambda x: closure.rows(KinematicState(robot.model, robot.data, x, v)).A  # noqa: E731
        assert np.max(np.abs(rows.Adot - (A(q + h * v) - A(q - h * v)) / (2 * h))) < 1e-7
        # translation rows are the exact gradient of the translation residual
        res = lambda x: closure.rows(KinematicState(robot.model, robot.data, x, v)).residual  # noqa: E731
        fd = (res(q + h * v) - res(q - h * v)) / (2 * h)
        assert np.allclose(rows.A[:3] @ v, fd[:3], atol=1e-8)


def test_redundant_rows_of_a_planar_loop_are_removed():
    """Closing x y z rx rz of the cut revolute joint: y, rx, rz are identically satisfied in the plane; the
    rank is 2 and the mobility 1, and S is the same as with only x z closed."""
    full, planar = fourbar(("x", "y", "z", "rx", "rz")), fourbar(("x", "z"))
    q = closed_state(planar, 0.8)
    a = full.reduced(q, [1.0])
    b = planar.reduced(q, [1.0])
    assert a.projection.rows.size == 2 and a.projection.mobility == 1
    assert np.max(np.abs(a.jacobian_rows.A @ a.S)) < 1e-13
    assert np.allclose(a.S, b.S, atol=1e-12) and np.allclose(a.M, b.M, atol=1e-12)


def test_fourbar_swings_under_gravity_conserving_energy():
    robot = fourbar()
    q = closed_state(robot, 0.8)
    traj = simulate(robot, 3.0, q, [2.0], None, n_out=301, rtol=1e-11, atol=1e-12, progress=False)
    assert np.max(traj.residual) < 1e-9
    assert np.max(np.abs(traj.energy - traj.energy[0])) < 1e-8 * max(1.0, abs(traj.energy[0]))


def test_dead_centre_is_reported_as_singular():
    """Crank and coupler collinear: with the rocker as the independent velocity the dependent block is singular;
    with the crank it is not."""
    robot = fourbar(independent=("crank_joint",))
    x = (0.45**2 - 0.3**2 + 0.4**2) / 0.8
    z = np.sqrt(0.45**2 - x**2)
    q = np.zeros(robot.nq)
    q[robot.coordinate_index("crank_joint")] = np.arctan2(z, x)
    q[robot.coordinate_index("rocker_joint")] = np.arctan2(z, x - 0.4)
    assert np.max(np.abs(robot.constraint_residual(q))) < 1e-12
    A = robot.constraint_rows(KinematicState(robot.model, robot.data, q, np.zeros(robot.nq))).A
    ok = project(A, [robot.coordinate_index("crank_joint")], robot.velocity_labels)
    assert np.isfinite(ok.condition)
    with pytest.raises(SingularConstraintError, match="singular"):
        project(A, [robot.coordinate_index("rocker_joint")], robot.velocity_labels)
    with pytest.raises(SingularConstraintError, match="mobility"):
        project(A, [0, 1], robot.velocity_labels)


def test_bad_closures_give_clear_errors():
    robot = fourbar()
    with pytest.raises(DescriptionError, match="same body"):
        LoopClosure(robot.description, "coupler", "coupler_tip")
    with pytest.raises(DescriptionError, match="components"):
        LoopClosure(robot.description, "coupler_tip", "rocker_tip", ("x", "w"))
    with pytest.raises(DescriptionError, match="no frame named"):
        LoopClosure(robot.description, "coupler_tip", "rocker_tpi")
