"""TIAGo from example-robot-data through a constraint file: a description no one here wrote.

examples/tiago.toml: planar root, two rolling driven wheels, torso/arm/head/hand locked. The minimal model in
(theta_R_dot, theta_L_dot) is compared with the classical differential drive with an offset mass centre,
derived with sympy in tests/oracles/diff_drive_sympy.py, whose constants (m, I_A, I_w, d, e, b) are
Pinocchio's composite mass properties of the locked TIAGo, themselves cross-checked against a plain sum over
the URDF's link inertials (yourdfpy forward kinematics).

examples/tiago_arm.toml: the same base with torso, arm and head moving (12 velocities): A S = 0 and the energy
balance of a torque-free motion.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from oracles import diff_drive_sympy as oracle

from robotdyn.interfaces.constraint_file import read
from robotdyn.errors import RobotDynError
from robotdyn.simulation.engine import simulate

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
R_WHEEL = 0.0985  # examples/tiago.toml


@pytest.fixture(scope="module")
def tiago_file():
    return read(EXAMPLES / "tiago.toml")


@pytest.fixture(scope="module")
def tiago(tiago_file):
    return tiago_file.robot()


@pytest.fixture(scope="module")
def tiago_arm():
    return read(EXAMPLES / "tiago_arm.toml").robot()


def test_oracle_routes_agree():
    """Lagrange-d'Alembert projection and the textbook Newton-Euler form give the same M_r and h_r (symbolic)."""
    oracle.self_test()
    M, h = oracle.textbook_reduced()
    s = oracle.SYMBOLS
    # the classical special case e = 0: M_r = [[I_w + r^2 (m/4 + I_A/(4 b^2)), r^2 (m/4 - I_A/(4 b^2))], ...]
    import sympy as sp

    M0 = M.subs(s.e, 0)
    assert sp.simplify(M0[0, 0] - (s.I_w + s.r**2 * (s.m / 4 + s.I_A / (4 * s.b**2)))) == 0
    assert sp.simplify(M0[0, 1] - s.r**2 * (s.m / 4 - s.I_A / (4 * s.b**2))) == 0
    # h_r vanishes with the mass centre on the axle (d = 0)
    assert sp.simplify(h.subs(s.d, 0)) == sp.zeros(2, 1)


def constants(robot) -> dict:
    """The oracle's constants from Pinocchio's composite mass properties at the robot's neutral configuration."""
    model, data = robot.model, robot.data
    q = robot.neutral()
    pin.crba(model, data, q)
    pin.framesForwardKinematics(model, data, q)
    c_r = data.oMf[model.getFrameId("wheel_right_link")].translation.copy()
    c_l = data.oMf[model.getFrameId("wheel_left_link")].translation.copy()
    mid = (c_r + c_l) / 2
    b = np.linalg.norm(c_l - c_r) / 2
    m = pin.computeTotalMass(model)
    com = pin.centerOfMass(model, data, q)
    Y = data.Ycrb[model.getJointId("psi")]  # whole robot, in the yaw joint's frame (= world at psi = 0)
    I_A = Y.inertia[2, 2] + m * np.sum((Y.lever[:2] - mid[:2]) ** 2)
    I_w = []
    for joint in ("wheel_right_joint", "wheel_left_joint"):
        Yw = model.inertias[model.getJointId(joint)]
        a = np.array([0.0, 0.0, 1.0])  # the URDF's wheel joint axis
        I_w.append(a @ Yw.inertia @ a + Yw.mass * np.linalg.norm(np.cross(Yw.lever, a)) ** 2)
    assert abs(I_w[0] - I_w[1]) < 1e-15
    return dict(m=m, I_A=I_A, I_w=I_w[0], d=com[0] - mid[0], e=com[1] - mid[1], r=R_WHEEL, b=b, mid=mid,
                axle=(c_l - c_r) / (2 * b), com=com)


def test_tiago_builds_as_a_differential_drive(tiago):
    assert tiago.coordinates == ["x", "y", "psi", "theta_L", "theta_R"]
    assert tiago.velocity_names == ["theta_R_dot", "theta_L_dot"]
    c = constants(tiago)
    np.testing.assert_allclose(c["mid"], [0.0, 0.0, R_WHEEL], atol=1e-12)  # axle midpoint above base_footprint
    np.testing.assert_allclose(c["axle"], [0.0, 1.0, 0.0], atol=1e-12)  # left wheel at +y
    # the wheel radius of the file is the height of the wheel centres: the wheels touch the ground
    np.testing.assert_allclose(tiago.constraint_residual(tiago.neutral()), 0.0, atol=1e-12)


def test_composite_mass_properties_match_a_sum_over_urdf_links(tiago, tiago_file):
    """Pinocchio's locked composite (m, com, I_A) equals a plain sum over the URDF inertials (yourdfpy FK)."""
    import yourdfpy

    spec = tiago_file.SPEC
    urdf = yourdfpy.URDF.load(str(spec.xacro), load_meshes=False, build_collision_scene_graph=False)
    cfg = {j: spec.locked.get(j, 0.0) for j in urdf.actuated_joint_names}
    urdf.update_cfg(cfg)
    m, mc, links = 0.0, np.zeros(3), []
    for link in urdf.robot.links:
        if link.inertial is None or link.inertial.mass is None or link.name in spec.massless:
            continue
        origin = np.eye(4) if link.inertial.origin is None else link.inertial.origin
        T = urdf.get_transform(link.name, "base_footprint") @ origin
        links.append((link.inertial.mass, T[:3, 3], T[:3, :3] @ link.inertial.inertia @ T[:3, :3].T))
        m += link.inertial.mass
        mc += link.inertial.mass * T[:3, 3]
    c = constants(tiago)
    I_A = sum(I[2, 2] + mi * np.sum((p[:2] - c["mid"][:2]) ** 2) for mi, p, I in links)
    assert abs(m - c["m"]) < 1e-12 * m
    np.testing.assert_allclose(mc / m, c["com"], atol=1e-12)
    assert abs(I_A - c["I_A"]) < 1e-12 * I_A
    # the values (reported in the notebook): 65.894 kg, COM 16.7 mm ahead and 7.2 mm right of the axle midpoint
    assert 60 < m < 70 and 0.01 < c["d"] < 0.03 and -0.01 < c["e"] < 0


def _symmetrised_wheels(urdf_text: str) -> str:
    """Make both wheels' central inertias axisymmetric about their axle (link z): ixx = iyy = mean, no products."""

    def fix(match: re.Match) -> str:
        block = match.group(0)
        vals = {k: float(v) for k, v in re.findall(r'(i[xyz]{2})="([^"]+)"', block)}
        mean = (vals["ixx"] + vals["iyy"]) / 2
        new = f'ixx="{mean!r}" ixy="0" ixz="0" iyy="{mean!r}" iyz="0" izz="{vals["izz"]!r}"'
        return re.sub(r'ixx="[^"]+".*?izz="[^"]+"', new, block, flags=re.S)

    out, n = re.subn(r'<link name="wheel_(left|right)_link">.*?</link>', fix, urdf_text, flags=re.S)
    assert n == 2
    return out


def _compare(robot, states: int, seed: int) -> tuple[float, float, float]:
    """Largest |M_r - oracle|, |h_r - oracle| and |nu|^2 over random states (random x, y, psi and wheel angles)."""
    p = constants(robot)
    rng = np.random.default_rng(seed)
    dM = dh = nu2 = 0.0
    for _ in range(states):
        q = robot.neutral()
        q[:5] = rng.uniform(-np.pi, np.pi, 5)
        q[:2] *= 3.0
        nu = rng.normal(size=2) * 4.0
        red = robot.reduced(q, nu)
        M_o, h_o = oracle.numeric(p, nu)
        dM, dh, nu2 = max(dM, np.abs(red.M - M_o).max()), max(dh, np.abs(red.h - h_o).max()), max(nu2, nu @ nu)
        np.testing.assert_allclose(red.B, np.eye(2), atol=1e-12)  # the motors drive theta_R, theta_L
    return dM, dh, nu2


def test_reduced_dynamics_equal_closed_form_with_axisymmetric_wheels(tiago_file, tmp_path):
    """With the wheels made axisymmetric (the closed form's assumption) the agreement is to round-off."""
    urdf = tmp_path / "tiago_axisymmetric_wheels.urdf"
    urdf.write_text(_symmetrised_wheels(Path(tiago_file.SPEC.xacro).read_text()))
    robot = read(EXAMPLES / "tiago.toml", urdf=urdf).robot()
    dM, dh, _ = _compare(robot, 20, 1)
    assert dM < 1e-11 and dh < 1e-11, (dM, dh)  # round-off (M_r ~ 0.25 kg m^2 built from 65.9 kg terms)


def test_reduced_dynamics_equal_closed_form_up_to_wheel_asymmetry(tiago):
    """With TIAGo's own wheels, the difference is bounded by their tiny non-axisymmetric inertia.

    Wheel central inertia (link z = axle): the in-plane deviatoric part delta1 = |((ixx-iyy)/2, ixy)| and the
    axle coupling delta2 = |(ixz, iyz)| enter the kinetic energy as (1/2) w^2 delta1 cos(..) + w th' delta2 cos(..)
    with w = k (th_R' - th_L'), k = r/(2b): |dM_r| <= 2 (2 k^2 delta1 + 2 k delta2) per entry (both wheels) and the
    velocity terms (theta-derivatives of those, twice the angular frequency) <= 3 * 2 * that * |nu|^2.
    """
    Yw = tiago.model.inertias[tiago.model.getJointId("wheel_right_joint")].inertia
    delta1 = np.hypot((Yw[0, 0] - Yw[1, 1]) / 2, Yw[0, 1])
    delta2 = np.hypot(Yw[0, 2], Yw[1, 2])
    k = R_WHEEL / (2 * 0.2022)
    bound_M = 2 * (2 * k**2 * delta1 + 2 * k * delta2)
    dM, dh, nu2 = _compare(tiago, 20, 2)
    assert 1e-11 < dM <= bound_M, (dM, bound_M)  # it is there, and it is as small as the wheels predict
    assert dh <= 6 * bound_M * nu2, (dh, bound_M * nu2)
    assert bound_M < 1e-7  # relative to M_r ~ 0.25 kg m^2: below 4e-7


def test_torque_driven_turn_energy_balance(tiago_file, tiago):
    """dE/dt = tau . nu: E(t) - E(0) equals the integral of the motor power (trapezoid on a fine grid)."""
    sc = tiago_file.SCENARIOS["turn"]
    traj = sc.run(tiago, t_end=1.0, n_out=401, rtol=1e-10, atol=1e-12, progress=False)
    tau = sc.torque(0.0, None, None)
    power = traj.nu @ tau
    work = np.concatenate([[0.0], np.cumsum((power[1:] + power[:-1]) / 2 * np.diff(traj.t))])
    err = np.abs(traj.energy - traj.energy[0] - work).max()
    assert traj.energy[-1] - traj.energy[0] > 1.0  # the motors did real work
    assert err < 1e-5 * (traj.energy[-1] - traj.energy[0]), err
    # turning left: the right wheel faster, the heading increases
    assert traj.column("theta_R_dot")[-1] > traj.column("theta_L_dot")[-1] > 0
    assert traj.column("psi")[-1] > 0


def test_arm_moving_constraints_and_mass_matrix(tiago_arm):
    assert tiago_arm.mobility == 12
    rng = np.random.default_rng(3)
    lo, hi = tiago_arm.description.lower, tiago_arm.description.upper
    for _ in range(10):
        q = np.where(np.isfinite(lo), rng.uniform(np.maximum(lo, -3), np.minimum(hi, 3)), rng.uniform(-3, 3, lo.size))
        nu = rng.normal(size=12)
        red = tiago_arm.reduced(q, nu)
        A = red.rows.A
        assert np.abs(A @ red.S).max() < 1e-13
        assert np.abs(A @ red.v).max() < 1e-13
        np.testing.assert_allclose(red.M, red.M.T, atol=1e-13)
        assert np.linalg.eigvalsh(red.M).min() > 0


def test_arm_moving_energy_is_conserved_without_torques(tiago_arm):
    """Torque-free: the robot rolls while the arm swings under gravity; E stays constant."""
    q0 = tiago_arm.neutral()
    nu0 = np.zeros(12)
    for name, value in {"theta_R_dot": 2.0, "theta_L_dot": 1.0, "arm_1_joint_dot": 0.8, "arm_4_joint_dot": -0.6,
                        "torso_lift_joint_dot": 0.05}.items():
        nu0[tiago_arm.velocity_names.index(name)] = value
    traj = simulate(tiago_arm, 1.0, q0, nu0, n_out=101, rtol=1e-10, atol=1e-12, progress=False)
    E = traj.energy
    kinetic0 = E[0] - tiago_arm.energy(q0, np.zeros(tiago_arm.nq))
    assert np.abs(E - E[0]).max() < 1e-7 * kinetic0, (np.abs(E - E[0]).max(), kinetic0)
    # it did move: the arm joints and the heading changed
    assert abs(traj.column("arm_1_joint")[-1] - q0[tiago_arm.coordinate_index("arm_1_joint")]) > 0.1
    assert abs(traj.column("psi")[-1]) > 0.01


def test_locked_value_outside_the_joint_range_is_one_line(tmp_path):
    path = tmp_path / "tiago_bad.toml"
    path.write_text((EXAMPLES / "tiago.toml").read_text().replace("torso_lift_joint = 0.15", "torso_lift_joint = 0.5"))
    with pytest.raises(RobotDynError) as info:
        read(path).robot()
    msg = str(info.value)
    assert "\n" not in msg and msg.startswith(str(path))
    assert "locked joint 'torso_lift_joint' = 0.5 is outside its range [0, 0.35]" in msg
