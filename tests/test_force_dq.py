"""The constraint forces' configuration derivative at fixed multipliers, d(A(q)^T mu)/dq, and the motors'
d(B(q) tau)/dq at fixed torques (robotdyn.constraints.row_derivatives.force_dq, robotdyn.reduction.dynamics_derivatives
.motor_force_dq, the operational twist rows' twist_force_dq; twins of the compiled ReducedDerivatives::force_dq and
twist_force_dq, which the compiled derivative sets use for their multiplier term S^T d(A^T mu)/dq instead of one frame
pass per column of S).

Reference: the same matrix assembled row by row from the rows' velocity derivatives at the unit velocities,
T[j, :] = mu^T d(A e_j)/dq (row_derivatives.velocity_dq on a FramePass at e_j: Pinocchio's own
getFrameVelocityDerivatives), and motor_rows at the unit velocities, which is d(B tau)/dq. Both independent of the
formula under test (a wheel's contact force differentiated through its contact point and frame, a closure's wrench
through frame 1's rotation and frame 2's point, Pinocchio's Jacobian-derivative rule J_c x J_j): equal to 1e-12 of the
largest entry. The compiled set against the Python reference with motors reacting on a body other than their parent
(TIAGo's arm: the only case with a motor term): 1e-10, as tests/test_compiled_derivatives.py."""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from test_dynamics_derivatives import START, admissible_state

from robotdyn.constraints import row_derivatives as rd
from robotdyn.constraints.constraint import KinematicState
from robotdyn.constraints.posture import set_terrain, solve_posture
from robotdyn.constraints.terrain import SineTerrain
from robotdyn.interfaces.constraint_file import read
from robotdyn.reduction.dynamics_derivatives import motor_force_dq, motor_rows, twist_force_dq
from robotdyn.robot import MotorSpec, Robot
from robotdyn.robots import module

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def _kin(robot, q):
    return KinematicState(robot.model, robot.model.createData(), q, np.zeros(robot.model.nv))


def _unit_passes(kin0):
    return [rd.FramePass(kin0, e) for e in np.eye(kin0.model.nv)]


@pytest.mark.parametrize("name, terrain", [(n, None) for n in START] + [("adaptable_wheel", "sine"),
                                                                          ("linkage_suspension", "ramp")])
def test_force_dq_equals_the_rows_derivatives_at_the_unit_velocities(name, terrain):
    mod = module(name)
    robot = Robot(mod.SPEC)
    rng = np.random.default_rng(11)
    if terrain == "ramp":
        set_terrain(robot, mod.TERRAINS["ramp"]())
        q = solve_posture(robot, {"x": 0.1, "y": 0.05, "yaw": 0.3}, tol=1e-13).q
    else:
        q = admissible_state(robot, START[name], rng)[0]
        if terrain == "sine":
            set_terrain(robot, SineTerrain(0.03, 2.0, 1.5, 0.3))
    kin0 = _kin(robot, q)
    constraints = list(robot.constraints)
    mu = rng.normal(size=robot.rows_at(q).A.shape[0])
    T = rd.force_dq(constraints, kin0, mu)
    ref = np.vstack([mu @ rd.velocity_dq(constraints, fp) for fp in _unit_passes(kin0)])
    scale = np.abs(ref).max()
    assert scale > 0.1  # not a vacuous comparison
    assert np.abs(T - ref).max() <= 1e-12 * scale


@pytest.fixture(scope="module")
def reacting_tiago():
    """The TIAGo example with two arm motors reacting on a link other than their joint's parent (the torso, the
    second arm link): with joints of different axes in between, B(q) tau depends on q (on the built-in robots every
    motor's reaction is its joint's parent, or the joints in between are parallel, and the term vanishes)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the example's placeholder hand inertias (tests/test_tiago.py)
        spec = read(EXAMPLES / "tiago_arm.toml").robot().spec
        motors = list(spec.motors) + [MotorSpec("tau_a3", "arm_3_joint", "torso_lift_link"),
                                      MotorSpec("tau_a5", "arm_5_joint", "arm_2_link")]
        robot = Robot(dataclasses.replace(spec, motors=motors))
    rng = np.random.default_rng(3)
    q = np.clip(robot.neutral() + 0.3 * rng.uniform(-1, 1, robot.nq), robot.description.lower,
                robot.description.upper)
    return robot, q, rng.normal(size=robot.mobility), rng.normal(size=len(robot.motors))


def test_motor_force_dq_equals_motor_rows_at_the_unit_velocities(reacting_tiago):
    robot, q, _, tau = reacting_tiago
    kin0 = _kin(robot, q)
    T = motor_force_dq(robot, kin0, tau)
    ref = motor_rows(robot, kin0, _unit_passes(kin0), tau)
    assert np.abs(ref).max() > 0.1
    assert np.abs(T - ref).max() <= 1e-12 * np.abs(ref).max()


def test_compiled_derivatives_with_reacting_motors_equal_python(reacting_tiago):
    from robotdyn.fast.compiled import available
    from robotdyn.fast.compiled_derivatives import compiled_derivatives
    from robotdyn.reduction.dynamics_derivatives import dynamics_derivatives

    if not available():
        pytest.skip("compiled extension not built")
    from test_compiled_derivatives import assert_same

    robot, q, nu, tau = reacting_tiago
    C = compiled_derivatives(robot, q, nu, tau)
    assert C is not None
    assert_same(C, dynamics_derivatives(robot, q, nu, tau))


@pytest.mark.parametrize("frame, axes", [("platform", "local"), ("wheel_link_1", "local"), ("link_2", "world")])
def test_twist_force_dq_equals_the_frame_velocity_derivatives_at_the_unit_velocities(frame, axes):
    """An operational twist's rows J_o (the omni platform's own, and frames away from the root, in both axes):
    d(J_o^T mu)/dq against mu^T d(J_o e_j)/dq from Pinocchio's frame velocity derivatives (FramePass)."""
    robot = Robot(module("omni_caster").SPEC)
    rng = np.random.default_rng(8)
    q = admissible_state(robot, START["omni_caster"], rng)[0]
    kin0 = _kin(robot, q)
    twist = SimpleNamespace(fid=robot.model.getFrameId(frame), axes=axes, select=np.array([0, 1, 2, 3, 5]))
    mu = rng.normal(size=5)
    T = twist_force_dq(twist, kin0, mu)
    rows = [(fp.local_velocity if axes == "local" else fp.velocity)(twist.fid)[1][twist.select]
            for fp in _unit_passes(kin0)]
    ref = np.vstack([mu @ r for r in rows])
    assert np.abs(ref).max() > 0.01
    assert np.abs(T - ref).max() <= 1e-12 * np.abs(ref).max()
