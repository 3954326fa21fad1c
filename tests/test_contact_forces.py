"""Constraint forces (robotdyn.contact.contact_forces) against independent references: Pinocchio's own KKT solve of the
constrained dynamics, the static force and moment balance of the whole robot, and the closed form of a disc
rolling down an incline."""

from __future__ import annotations


import numpy as np
import pinocchio as pin
import pytest
from scipy.linalg import qr

import robotdyn
from robotdyn.errors import InputError
from robotdyn.robot import Robot

ROBOTS = ["quasimoro", "omni_caster", "linkage_suspension", "adaptable_wheel", "mmr12_eod"]


@pytest.fixture(scope="module")
def robots():
    return {name: robotdyn.load(name) for name in ROBOTS}


def _pinocchio_kkt(robot, q, v, tau_full):
    """Pinocchio's forwardDynamics with the independent constraint rows: accelerations and A^T lambda."""
    rows = robot.constraint_rows(robotdyn.constraints.constraint.KinematicState(robot.model, robot.data, q, v))
    A, gamma = rows.A, rows.Adot @ v
    r = np.linalg.matrix_rank(A)
    sel = np.sort(qr(A.T, pivoting=True)[2][:r])  # a maximal independent subset of the rows
    data = robot.model.createData()
    a = pin.forwardDynamics(robot.model, data, q, v, tau_full, A[sel], gamma[sel], 0.0).copy()
    lam_sel = data.lambda_c.copy()
    if not np.all(np.isfinite(a)):
        # massless links make M singular (Pinocchio's solve factors M): the same KKT system, solved densely
        M = pin.crba(robot.model, data, q)
        h = pin.rnea(robot.model, data, q, v, np.zeros_like(v))
        J = A[sel]
        K = np.block([[M, -J.T], [J, np.zeros((len(sel), len(sel)))]])
        sol = np.linalg.solve(K, np.concatenate([tau_full - h, -gamma[sel]]))
        a, lam_sel = sol[: len(v)], sol[len(v):]
    return a, A, sel, lam_sel


@pytest.mark.parametrize("name", ROBOTS)
def test_forces_match_pinocchio_kkt(robots, name):
    """A^T lambda and every determined multiplier equal Pinocchio's KKT solution to 1e-9 (random velocities and
    motor torques at the robot's neutral configuration)."""
    robot = robots[name]
    rng = np.random.default_rng(7)
    q = robot.neutral()
    for _ in range(3):
        nu = rng.normal(scale=0.5, size=robot.mobility)
        tau = rng.normal(size=len(robot.motors))
        f = robot.contact_forces(q, nu, tau=tau, twin=False)  # the model's own multipliers
        red = robot.reduced(q, nu)
        kin = robotdyn.constraints.constraint.KinematicState(robot.model, robot.data, q, red.v)
        B = robotdyn.reduction.actuation.input_matrix(robot.motors, kin)
        a_pin, A, sel, lam_pin = _pinocchio_kkt(robot, q, red.v, B @ tau)
        scale = 1.0 + np.abs(A.T @ f.lam).max()
        np.testing.assert_allclose(red.S @ f.nudot + red.w, a_pin, atol=1e-9 * (1 + np.abs(a_pin).max()))
        # Pinocchio's convention: M a + h = tau + J^T lambda_c, the same sign as robotdyn's
        np.testing.assert_allclose(A.T @ f.lam, A[sel].T @ lam_pin, atol=1e-9 * scale)
        full = np.zeros(len(f.lam))
        full[sel] = lam_pin
        np.testing.assert_allclose(f.lam[f.determined], full[f.determined], atol=1e-9 * scale)
        assert f.residual < 1e-10


def _holding(robot, q):
    """Motor torques that hold the robot at rest at q (inverse dynamics with zero accelerations)."""
    return robot.inverse_dynamics(q, np.zeros(robot.mobility), np.zeros(robot.mobility))[1]


@pytest.mark.parametrize("name", ["adaptable_wheel", "linkage_suspension"])
def test_static_balance_at_rest(robots, name):
    """At rest with holding torques, the ground's forces balance the weight: their sum is (0, 0, m g) and their
    moment about the centre of mass is zero (Newton-Euler of the whole robot, independent of the projection)."""
    robot = robots[name]
    q = robot.neutral()
    zero = np.zeros(robot.mobility)
    f = robot.contact_forces(q, zero, nudot=zero, tau=_holding(robot, q))
    assert all(w.determined[2] for w in f.wheels)  # every normal load (the linkage's two middle lateral forces
    # are statically indeterminate; any member of lambda + N z has the same resultant, so the balance still holds)
    mass = sum(robot.model.inertias[i].mass for i in range(robot.model.njoints))
    g = -robot.model.gravity.linear[2]
    com = pin.centerOfMass(robot.model, robot.data, q)
    total = sum(w.world for w in f.wheels)
    moment = sum(np.cross(w.point - com, w.world) for w in f.wheels)
    np.testing.assert_allclose(total, [0.0, 0.0, mass * g], atol=1e-8 * mass * g)
    np.testing.assert_allclose(moment, 0.0, atol=1e-8 * mass * g)
    assert all(w.normal > 0 for w in f.wheels)


def _disc_on_ramp(slope: float) -> tuple[Robot, np.ndarray]:
    """The test disc rolling (no slip) on a ramp, its height solved onto the terrain."""
    from test_sliding import disc

    return disc(slope, independent=("psi", "lean", "spin"))


@pytest.mark.parametrize("slope", [0.1, 0.5, 1.2])
def test_disc_rolling_down_incline_closed_form(slope):
    """A disc of inertia ratio k = I/(m R^2) rolling down an incline of angle alpha: normal load m g cos(alpha),
    friction m g sin(alpha) k/(1+k) up the slope, required mu = tan(alpha) k/(1+k) (tan(alpha)/3 for a solid disc)."""
    robot, q = _disc_on_ramp(slope)
    m, inertia, radius, g = 2.0, 0.04, 0.3, 9.81
    k = inertia / (m * radius**2)
    alpha = np.arctan(slope)
    f = robot.contact_forces(q, np.zeros(robot.mobility))
    w = f.wheels[0]
    assert f.all_determined
    assert w.normal == pytest.approx(m * g * np.cos(alpha), rel=1e-12)
    assert w.tangential == pytest.approx(m * g * np.sin(alpha) * k / (1 + k), rel=1e-12)
    assert w.force[1] == pytest.approx(0.0, abs=1e-12)
    assert w.required_mu == pytest.approx(np.tan(alpha) * k / (1 + k), rel=1e-12)
    # the friction points up the slope (the ground holds the disc back): negative x in world axes
    assert w.world[0] < 0


def test_planar_loads_from_the_floating_twin_match_pinocchio(robots):
    """A planar model's normal loads come from its floating twin: Pinocchio's KKT solve of the floating model at
    the lifted state gives zero out-of-plane accelerations (the planar motion is a motion of the floating model)
    and the same multipliers, to 1e-9 (omni caster: three casters, loads determinate)."""
    robot = robots["omni_caster"]
    q = robot.neutral()
    rng = np.random.default_rng(3)
    nu, tau = rng.normal(scale=0.5, size=3), rng.normal(size=len(robot.motors))
    f = robot.contact_forces(q, nu, tau=tau)
    assert all(w.load_determined for w in f.wheels) and f.notes
    twin = robot._floating_twin
    red = robot.reduced(q, nu)
    idx = [twin.description.joint_names.index("yaw" if j == "psi" else j) for j in robot.description.joint_names]
    qt, vt = np.zeros(twin.nq), np.zeros(twin.nq)
    qt[idx], vt[idx] = q, red.v
    kin = robotdyn.constraints.constraint.KinematicState(twin.model, twin.data, qt, vt)
    B = robotdyn.reduction.actuation.input_matrix(twin.motors, kin)
    a_pin, A, sel, lam_pin = _pinocchio_kkt(twin, qt, vt, B @ tau)
    out_of_plane = [twin.coordinate_index(c) for c in ("z", "pitch", "roll")]
    np.testing.assert_allclose(a_pin[out_of_plane], 0.0, atol=1e-9)
    np.testing.assert_allclose(a_pin[idx], red.S @ f.nudot + red.w, atol=1e-9)
    full = np.zeros(len(f.lam))
    full[sel] = lam_pin
    np.testing.assert_allclose(f.lam[f.determined], full[f.determined], atol=1e-9 * (1 + np.abs(full).max()))
    weight = -sum(twin.model.inertias[i].mass for i in range(twin.model.njoints)) * twin.model.gravity.linear[2]
    assert sum(w.normal for w in f.wheels) == pytest.approx(weight, rel=1e-12)  # no vertical acceleration


def test_two_wheels_alone_cannot_hold_a_planar_model(robots):
    """MMR12-EOD's description stands on two wheels: its floating twin cannot be held by them, so the loads stay
    undetermined and the reason says so."""
    robot = robots["mmr12_eod"]
    f = robot.contact_forces(robot.neutral(), np.zeros(robot.mobility))
    assert any("cannot hold" in r for r in f.undetermined_reason)
    assert not f.wheels[0].determined[2]


def test_planar_root_reports_normal_loads_as_undetermined(robots):
    """Under a planar root the normal rows act on no coordinate: the model's own loads are undetermined, with why."""
    f = robots["omni_caster"].contact_forces(robots["omni_caster"].neutral(), np.zeros(3), twin=False)
    assert not any(w.determined[2] for w in f.wheels)
    assert any("act on no coordinate" in r for r in f.undetermined_reason)
    assert "undetermined" in f.table()
    assert f.as_dict()["wheels"]["wheel_1"]["required_mu"] is None


def test_redundant_rows_give_the_null_space(robots):
    """Quasimoro's two lateral rows on one axle: only their sum is determined; the null space says which
    combination is free, and A^T N = 0."""
    robot = robots["quasimoro"]
    q = robot.neutral()
    f = robot.contact_forces(q, [0.3, -0.2, 0.1], tau=[0.2, -0.1])
    A = robot.rows_at(q).A
    np.testing.assert_allclose(A.T @ f.null_space, 0.0, atol=1e-12)
    i, j = f.labels.index("wheel_A.lateral"), f.labels.index("wheel_B.lateral")
    assert not f.determined[i] and not f.determined[j]
    # the sum of the two lateral forces is determined: it is orthogonal to every null direction
    np.testing.assert_allclose(f.null_space[i] + f.null_space[j], 0.0, atol=1e-12)


def test_bad_input_is_one_line(robots):
    robot = robots["quasimoro"]
    with pytest.raises(InputError, match="tau"):
        robot.contact_forces(robot.neutral(), np.zeros(3), tau=[1.0])
    with pytest.raises(InputError, match="unknown wheel"):
        robot.contact_forces(robot.neutral(), np.zeros(3)).wheel("nope")


def test_minimum_mu_over_undetermined_splits(robots):
    """Quasimoro's two lateral forces on one axle: only their sum L is determined. The smallest mu that admits a
    split inside both cones, min over y of max_i sqrt(l_i^2 + y_i^2)/n_i with y_A + y_B = L, against a brute-force
    search over the split (independent of the SLSQP solve)."""
    robot = robots["quasimoro"]
    q = robot.neutral()
    q[robot.coordinate_index("theta3")] = 0.3
    f = robot.contact_forces(q, [1.0, 0.5, 0.2], tau=[0.1, 0.1])
    wa, wb = f.wheel("wheel_A"), f.wheel("wheel_B")
    total = wa.force[1] + wb.force[1]  # determined: the min-norm split has the right sum
    def ratio(y):
        return np.maximum(np.hypot(wa.force[0], y) / wa.normal, np.hypot(wb.force[0], total - y) / wb.normal)

    y = np.linspace(-5 * abs(total) - 1, 5 * abs(total) + 1, 400001)
    for _ in range(3):  # zoom in around the best grid point
        best, step = y[np.argmin(ratio(y))], y[1] - y[0]
        y = np.linspace(best - 2 * step, best + 2 * step, 100001)
    assert f.minimum_mu() == pytest.approx(ratio(y).min(), rel=1e-9)
    # determined everywhere (the disc): the minimum is the wheel's own required mu
    robot_d, qd = _disc_on_ramp(0.5)
    fd = robot_d.contact_forces(qd, np.zeros(robot_d.mobility))
    assert fd.minimum_mu() == pytest.approx(fd.wheels[0].required_mu, rel=1e-12)


def test_a_planar_model_lacking_a_support_reports_no_split_loads():
    """MMR12-EOD's built-in planar model stands on its two drive wheels only: its floating twin cannot hold the
    out-of-plane equilibrium (it would pitch over), so no normal load has a value. The rigid limit used to split
    them anyway (377.6 N per wheel against a weight of 968 N, labelled 'rigid limit of compliance', with a minimum
    mu of 0.0014) beside the line saying the loads stay undetermined."""
    import robotdyn

    robot = robotdyn.load("mmr12_eod")
    q, nu = robot.neutral(), np.zeros(robot.mobility)
    for forces in (robot.contact_forces(q, nu, tau=np.zeros(len(robot.motors))),
                   robot.contact_forces(q, nu, nudot=np.zeros(robot.mobility))):
        assert any("lacks a support" in r for r in forces.undetermined_reason)
        assert not any(w.known[2] for w in forces.wheels)
        assert forces.minimum_mu() is None
        assert "rigid limit" not in forces.table()
