"""Adaptable-wheel tricycle (Mardani & Ebrahimi 2016): model, constraints, inverse kinematics, statics, dynamics.

References are independent of the code under test: finite differences in time and in q, the core rolling
contact against the paper's transcribed contact equations, the paper's printed numbers, equilibrium residuals.
"""

from __future__ import annotations

import numpy as np
import pytest

from robotdyn.constraint import KinematicState
from robotdyn.errors import RobotDynError
from robotdyn.joint_coupling import JointCoupling
from robotdyn.projection import project
from robotdyn.robot import Robot
from robotdyn.robots import adaptable_wheel as aw


@pytest.fixture(scope="module")
def robot():
    return Robot(aw.SPEC)


@pytest.fixture(scope="module")
def slip_robot():
    return Robot(aw.SPEC, {"lateral": "slip"})


@pytest.fixture(scope="module")
def mission1():
    return aw.run_mission("mission1")


@pytest.fixture(scope="module")
def mission2():
    return aw.run_mission("mission2")


def _state(robot, t=0.7, qx=0.04, qy=-0.03, seed=0):
    """A configuration on the constraint manifold (from the IK) and an admissible velocity."""
    cmd = aw.Commands(np.sin(t), np.cos(t), 0.15, qx, qy, -t)
    x, err, _ = aw.solve_ik(cmd, robot.params, robot.terrain)
    q = aw.model_configuration(robot, cmd, x, spins=np.array([0.3, -1.1, 2.0]))
    nu = np.random.default_rng(seed).normal(size=robot.mobility)
    return q, robot.reduced(q, nu).v


# ------------------------------------------------------------------------------------------------- model
def test_description_loads_and_names(robot):
    assert robot.nq == 15
    for tag in aw.WHEELS:
        for label in (f"theta_{tag}", f"q_{tag}", f"Rch_{tag}"):
            robot.coordinate_index(label)
    assert robot.description.upper[robot.coordinate_index("q_fr")] == pytest.approx(np.pi)
    assert robot.description.upper[robot.coordinate_index("Rch_fr")] == pytest.approx(0.3 * np.cos(np.pi / 6))
    # total mass as in Table 1, whatever the split between body and hubs
    for mw in (0.0, 0.5):
        r = Robot(aw.SPEC, {"m_wheel": mw})
        assert sum(i.mass for i in r.model.inertias) == pytest.approx(10.0)


def test_wheel_positions_eq8(robot):
    q = robot.neutral()
    import pinocchio as pin
    pin.forwardKinematics(robot.model, robot.data, q)
    pin.updateFramePlacements(robot.model, robot.data)
    off = aw.offsets(robot.params)
    z = q[robot.coordinate_index("z")]
    for tag in aw.WHEELS:
        c = robot.data.oMf[robot.model.getFrameId(f"wheel_{tag}")].translation
        np.testing.assert_allclose(c, off[tag] + [0, 0, z], atol=1e-14)
    full = Robot(aw.SPEC, {"L_reading": "full"})
    np.testing.assert_allclose(aw.offsets(full.params)["fr"], [0.3, -0.3, 0.0])


def test_residuals_solvable_and_AS_zero(robot, slip_robot):
    for r in (robot, slip_robot):
        q, v = _state(r)
        assert np.max(np.abs(r.constraint_residual(q))) < 1e-12
        kin = KinematicState(r.model, r.data, q, np.zeros(r.nq))
        rows = r.constraint_rows(kin)
        proj = project(rows.A, r.independent_indices)
        assert np.max(np.abs(rows.A @ proj.S)) < 1e-12
    assert robot.mobility == 3  # 15 coordinates, 9 rolling rows + 3 couplings, all independent here
    assert slip_robot.mobility == 6  # lateral rows dropped: the six commands of section 2


def test_coupling_enforces_eq1(robot):
    """The radius is set by the constraint layer: the residual is R_ch - w cos(q/2) cos(pi/6)."""
    q = robot.neutral()
    i, j = robot.coordinate_index("Rch_fl"), robot.coordinate_index("q_fl")
    q[j] = 1.0
    q[i] = 0.3 * np.cos(0.5) * np.cos(np.pi / 6) + 0.01
    labels = [c.name for c in robot.constraints]
    c = robot.constraints[labels.index("eq1_fl")]
    assert isinstance(c, JointCoupling)
    assert c.residual(q) == pytest.approx(0.01, abs=1e-15)
    np.testing.assert_allclose(c.solve_driven(q)[i], 0.3 * np.cos(0.5) * np.cos(np.pi / 6), atol=1e-15)


def _fd_drift(robot, q, v, h=1e-5):
    """d/dt [A(q + t v) v] at t = 0 by central differences (a = 0, q' = v)."""
    def Av(s):
        kin = KinematicState(robot.model, robot.data, q + s * v, v)
        return robot.constraint_rows(kin).A @ v
    return (Av(h) - Av(-h)) / (2 * h)


@pytest.mark.parametrize("admissible", [True, False])
def test_drift_matches_finite_differences(robot, admissible):
    """Adot v of every row (rolling with variable radius on the curved terrain, and the eq-1 coupling)."""
    q, v = _state(robot)
    if not admissible:
        v = np.random.default_rng(3).normal(size=robot.nq)
    rows = robot.constraint_rows(KinematicState(robot.model, robot.data, q, v))
    fd = _fd_drift(robot, q, v)
    np.testing.assert_allclose(rows.Adot @ v, fd, atol=1e-7 * max(1.0, np.abs(fd).max()))


def test_coupling_drift_and_jacobian_fd(robot):
    """The coupling row alone: A = d(phi)/dq and Adot = dA/dt by finite differences."""
    c = [c for c in robot.constraints if isinstance(c, JointCoupling)][0]
    rng = np.random.default_rng(7)
    for _ in range(5):
        q, v = rng.uniform(0.2, 2.9, robot.nq), rng.normal(size=robot.nq)
        rows = c.rows(KinematicState(robot.model, robot.data, q, v))
        h = 1e-6
        grad = np.array([(c.residual(q + h * e) - c.residual(q - h * e)) / (2 * h) for e in np.eye(robot.nq)])
        np.testing.assert_allclose(rows.A[0], grad, atol=1e-9)
        A = lambda s: c.rows(KinematicState(robot.model, robot.data, q + s * v, v)).A[0]
        np.testing.assert_allclose(rows.Adot[0], (A(h) - A(-h)) / (2 * h), atol=1e-8)


def test_mass_matrix_spd(robot):
    q, v = _state(robot)
    red = robot.reduced(q, np.ones(robot.mobility))
    np.testing.assert_allclose(red.M, red.M.T, atol=1e-12)
    assert np.linalg.eigvalsh(red.M).min() > 0
