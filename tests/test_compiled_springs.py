"""Joint springs and dampers through the compiled model's every door (robotdyn.fast.compiled: the evaluator adds
S^T Q to the forward dynamics, the springs' terms to the derivative set and -Q to the constraint forces' right-hand
side; robotdyn/kernels/joint_springs_derivatives.hpp), not only in its simulation.

References, independent of the code under test:
- the Python reference path (``use_compiled(False)``: robotdyn.reduction.dynamics_derivatives with spring_terms,
  robotdyn.contact.contact_forces with applied_forces): the derivative set to 1e-10 relative to the largest entry,
  the forward dynamics and the constraint forces to 1e-12;
- Richardson-extrapolated central differences (tests/test_dynamics_derivatives.py's ``richardson``) of the Python
  reference's forward dynamics, along the holonomic manifold in q, to 1e-7;
- the damped coaster's closed forms (tests/test_urdf_joint_damping.py: wheels damped by d = 0.01 N m s/rad,
  J = 0.058 kg m^2 rolling straight, J_turn = 0.039 kg m^2 turning on the spot): at rest,
  d nu'/d nu = -d M_r^-1 has the eigenvalues -2 d / J on (1, 1) and -2 d / J_turn on (1, -1).

Fixtures (own): the damped coaster (URDF damping only); the linkage rover on its ramp with a spring and damper on
a loop-closure joint (gamma1, inside the right slider loop: k = 40 N m/rad, c = 1.5 N m s/rad, rest 0.05 rad) and a
damper on the rocker psi (c = 2 N m s/rad, coupled to both sides by the ball joints' loops); the adaptable-wheel
tricycle with a spring and damper on a coupled joint (q_fl, coupled to Rch_fl by a cosine law).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from test_dynamics_derivatives import START, admissible_state, richardson
from test_urdf_joint_damping import D, J, J_TURN, _coaster_file

from robotdyn.constraints.posture import set_terrain, solve_posture
from robotdyn.fast.compiled import LazyProjection, available, why_not
from robotdyn.fast.compiled_derivatives import compiled_derivatives
from robotdyn.fast.dispatch import compiled_model, use_compiled
from robotdyn.interfaces.constraint_file import load_robot
from robotdyn.reduction.dynamics_derivatives import dynamics_derivatives
from robotdyn.reduction.joint_springs import JointSpring
from robotdyn.robot import Robot
from robotdyn.robots import module

pytestmark = pytest.mark.skipif(not available(), reason="compiled extension not built")
FIELDS = ("nudot", "dq", "dnu", "dtau", "qdot", "dqdot_dq", "S", "tangent", "dq_manifold")


def sprung(name: str, springs: list) -> Robot:
    """A built-in robot with joint springs and dampers added."""
    return Robot(replace(module(name).SPEC, springs=springs))


@pytest.fixture(scope="module")
def coaster(tmp_path_factory):
    return load_robot(_coaster_file(tmp_path_factory.mktemp("coaster")))


@pytest.fixture(scope="module")
def linkage():
    robot = sprung("linkage_suspension", [JointSpring("gamma1", 40.0, 1.5, 0.05), JointSpring("psi", damping=2.0)])
    set_terrain(robot, module("linkage_suspension").TERRAINS["ramp"]())
    return robot


@pytest.fixture(scope="module")
def tricycle():
    return sprung("adaptable_wheel", [JointSpring("q_fl", 5.0, 0.3, 0.01)])


def states(robot, rng, count=2):
    """Random admissible states (q on the holonomic manifold, nu and tau random)."""
    if robot.spec.name == "linkage_suspension":
        for _ in range(count):
            fixed = {"x": rng.uniform(-0.2, 0.2), "y": rng.uniform(-0.2, 0.2), "yaw": rng.uniform(-0.5, 0.5)}
            yield (solve_posture(robot, fixed, tol=1e-13).q, rng.normal(size=robot.mobility) * 0.5,
                   rng.normal(size=len(robot.motors)))
    else:
        start = START.get(robot.spec.name)
        for _ in range(count):
            yield admissible_state(robot, start, rng)


def python_nudot(robot, q, nu, tau):
    with use_compiled(False):
        return robot.forward_dynamics(q, nu, tau, check=False)


def test_the_compiled_model_serves_joint_springs(coaster, linkage, tricycle):
    for robot in (coaster, linkage, tricycle):
        assert why_not(robot) is None and compiled_model(robot) is not None
        robot.reduced(robot.neutral(), np.zeros(robot.mobility))  # (the first call: the Python path chooses the rows)
        red = robot.reduced(robot.neutral(), np.zeros(robot.mobility))
        assert isinstance(red.projection, LazyProjection)  # the compiled reduced model, not the Python path's


@pytest.mark.parametrize("which", ["coaster", "linkage", "tricycle"])
def test_derivative_set_equals_python_and_richardson_differences(which, request):
    robot = request.getfixturevalue(which)
    rng = np.random.default_rng(11)
    for i, (q, nu, tau) in enumerate(states(robot, rng)):
        C = compiled_derivatives(robot, q, nu, tau)
        assert C is not None
        with use_compiled(False):
            P = dynamics_derivatives(robot, q, nu, tau)
        for name in FIELDS:
            got, ref = getattr(C, name), getattr(P, name)
            assert np.abs(got - ref).max(initial=0.0) <= 1e-10 * max(1.0, np.abs(ref).max(initial=0.0)), name
        # the springs matter here: the same state without them differs (not a vacuous comparison); on its plane the
        # linkage's suspension is held by the wheels (its loop joints' rows of S are zero), so its springs change
        # the loads only (test_forward_dynamics_and_forces_equal_the_python_path)
        if which != "linkage":
            bare = Robot(replace(robot.spec, springs=[], urdf_damping=False))
            B = compiled_derivatives(bare, q, nu, tau)
            for name in ("dnu", "nudot") + (("dq",) if any(sp.stiffness for sp in robot.springs) else ()):
                ref = getattr(C, name)
                assert np.abs(ref - getattr(B, name)).max() > 1e-3 * max(1.0, np.abs(ref).max()), name
        if i:  # differences at one state per robot (the other: the Python comparison only)
            continue
        names = [robot.coordinates[j] for j in C.positions]
        if len(C.positions) == robot.nq:
            on_manifold = lambda qp: qp  # noqa: E731 (no holonomic row restricts q)
        else:
            on_manifold = lambda qp: solve_posture(robot, dict(zip(names, qp)), q0=q, tol=1e-13,  # noqa: E731
                                                    check_limits=False).q
        refs = {"dq_manifold": richardson(lambda x: python_nudot(robot, on_manifold(x), nu, tau), q[C.positions]),
                "dnu": richardson(lambda x: python_nudot(robot, q, x, tau), nu),
                "dtau": richardson(lambda x: python_nudot(robot, q, nu, x), tau)}
        for name, ref in refs.items():
            got = getattr(C, name)
            assert np.abs(got - ref).max() <= 1e-7 * max(1.0, np.abs(ref).max()), (name, np.abs(got - ref).max())


def test_forward_dynamics_and_forces_equal_the_python_path(coaster, linkage, tricycle):
    rng = np.random.default_rng(4)
    for robot in (coaster, linkage, tricycle):
        for q, nu, tau in states(robot, rng, 1):
            fast = robot.forward_dynamics(q, nu, tau)
            slow = python_nudot(robot, q, nu, tau)
            assert np.abs(fast - slow).max() <= 1e-12 * max(1.0, np.abs(slow).max())
            # the compiled forces call (nudot and the multipliers in one) and the constraint forces' door
            nudot = np.array(compiled_model(robot).forces(q, nu, tau)[0])
            assert np.abs(nudot - slow).max() <= 1e-12 * max(1.0, np.abs(slow).max())
            got = robot.contact_forces(q, nu, tau)
            with use_compiled(False):
                ref = robot.contact_forces(q, nu, tau)
            F, R = (np.array([w.force for w in f.wheels]) for f in (got, ref))
            assert np.abs(F - R).max() <= 1e-10 * max(1.0, np.abs(R).max())
            bare = Robot(replace(robot.spec, springs=[], urdf_damping=False))
            set_terrain(bare, robot.terrain)
            F0 = np.array([w.force for w in bare.contact_forces(q, nu, tau).wheels])
            assert np.abs(F - F0).max() > 1e-3 * np.abs(R).max()  # the springs carry load here


def test_the_coaster_closed_forms_through_the_compiled_doors(coaster):
    """At rest the damped coaster's d nu'/d nu is -d M_r^-1: eigenvalues -2 d / J and -2 d / J_turn; rolling at w
    each wheel's nu' is -2 d w / J (straight), and the wheel loads carry the dampers' torque: the ground's tangential
    force on each wheel is the damper torque over r less the wheel's own inertia, summing to m_total a."""
    C = compiled_derivatives(coaster, coaster.neutral(), np.zeros(2), np.zeros(2))
    assert C is not None
    assert C.dnu @ [1.0, 1.0] == pytest.approx([-2 * D / J] * 2, rel=1e-12)
    assert C.dnu @ [1.0, -1.0] == pytest.approx([-2 * D / J_TURN, 2 * D / J_TURN], rel=1e-12)
    w = 10.0
    assert coaster.forward_dynamics(coaster.neutral(), [w, w], [0.0, 0.0]) == pytest.approx([-2 * D * w / J] * 2,
                                                                                             rel=1e-12)
    f = coaster.contact_forces(coaster.neutral(), [w, w], [0.0, 0.0])
    along = sum(wh.world[0] for wh in f.wheels)  # the ground's forces along x
    assert along == pytest.approx(5.0 * 0.1 * (-2 * D * w / J), rel=1e-10)  # m_total r w'


def test_contact_force_derivatives_carry_the_springs(tricycle):
    """The contact-force and required-mu derivatives (compiled and Python, now that both take -Q and its
    derivatives) equal each other and Richardson differences of the reported forces, on the tricycle whose sprung
    coupled joint moves with nu (its spring terms enter the derivatives, not only the forces); they were refused."""
    from test_force_derivatives import check_against_differences

    from robotdyn.contact.compiled_force_derivatives import compiled_force_derivatives

    q, nu, tau = next(states(tricycle, np.random.default_rng(8), 1))
    assert compiled_force_derivatives(tricycle, q, nu, tau) is not None  # (the compiled twin serves it)
    D_fast = check_against_differences(tricycle, q, nu, tau)
    with use_compiled(False):
        D_slow = tricycle.contact_force_derivatives(q, nu, tau)
    bare = Robot(module("adaptable_wheel").SPEC).contact_force_derivatives(q, nu, tau)
    assert np.abs(bare.dforce_dnu - D_fast.dforce_dnu).max() > 1e-3 * np.abs(D_fast.dforce_dnu).max()
    for name in ("force", "dforce_dq", "dforce_dnu", "dforce_dtau", "dmu_dq"):
        got, ref = getattr(D_fast, name), getattr(D_slow, name)
        assert np.abs(got - ref).max() <= 1e-10 * max(1.0, np.abs(ref).max()), name


def test_traction_fast_pass_carries_the_springs():
    """The fast traction pass (compiled forward dynamics and forces over blocks of samples) equals the per-sample
    reference on the linkage rover with its loop spring and rocker damper, rolling freely down its ramp, and differs
    from the same run's loads without them."""
    from test_traction_fast import assert_same

    from robotdyn.contact.traction import traction
    from robotdyn.contact.traction_fast import wheel_loads

    sc = module("linkage_suspension").SCENARIOS["ramp_free"]
    robot = sprung("linkage_suspension", [JointSpring("gamma1", 40.0, 1.5, 0.05), JointSpring("psi", damping=2.0)])
    traj = sc.run(robot, t_end=0.3, n_out=13, progress=False)
    loads = wheel_loads(robot, traj.t, traj.q, traj.nu, sc.torque)
    assert loads is not None and loads.fallback == 0
    fast, ref = traction(robot, traj, sc.torque), traction(robot, traj, sc.torque, method="reference")
    assert fast.method == "fast" and ref.method == "reference"
    assert_same(fast, ref)
    bare = Robot(module("linkage_suspension").SPEC)
    set_terrain(bare, robot.terrain)
    other = traction(bare, traj, sc.torque)
    assert np.abs(other.normal - ref.normal).max() > 1e-3 * np.abs(ref.normal).max()


def test_a_damping_changed_in_place_rebuilds_the_compiled_model(tmp_path):
    """The compiled model holds copies of the springs' numbers, so compiled_model keys its cache on them: after a
    damper's c is doubled in place the compiled forward dynamics follow the closed form -2 (2 d) w / J, not the
    stale -2 d w / J."""
    robot = load_robot(_coaster_file(tmp_path))
    w = 10.0
    robot.forward_dynamics(robot.neutral(), [w, w], [0.0, 0.0])  # (the first call: the Python path chooses rows)
    before = compiled_model(robot)
    assert robot.forward_dynamics(robot.neutral(), [w, w], [0.0, 0.0]) == pytest.approx([-2 * D * w / J] * 2,
                                                                                         rel=1e-12)
    for spring in robot.springs:
        spring.damping = 2 * D
    assert compiled_model(robot) is not before
    robot.forward_dynamics(robot.neutral(), [w, w], [0.0, 0.0])
    assert robot.forward_dynamics(robot.neutral(), [w, w], [0.0, 0.0]) == pytest.approx([-4 * D * w / J] * 2,
                                                                                         rel=1e-12)
    assert compiled_model(robot) is compiled_model(robot)  # (unchanged numbers: the cached model)
