"""Adaptable-wheel tricycle (Mardani & Ebrahimi 2016): model, constraints, inverse kinematics, statics, dynamics.

References are independent of the code under test: finite differences in time and in q, the core rolling
contact against the paper's transcribed contact equations, the paper's printed numbers, equilibrium residuals.
"""

from __future__ import annotations

import numpy as np
import pytest

from robotdyn.constraints.constraint import KinematicState
from robotdyn.errors import RobotDynError
from robotdyn.constraints.joint_coupling import JointCoupling
from robotdyn.reduction.projection import project
from robotdyn.robot import Robot
from robotdyn.robots.adaptable_wheel import model as aw
from robotdyn.robots.adaptable_wheel import paper as aw_paper
from robotdyn.robots.adaptable_wheel import missions as aw_missions
from robotdyn.robots.adaptable_wheel import dynamics as aw_dyn
from robotdyn.robots.adaptable_wheel import comparison as aw_cmp


@pytest.fixture(scope="module")
def robot():
    return Robot(aw.SPEC)


@pytest.fixture(scope="module")
def slip_robot():
    return Robot(aw.SPEC, {"lateral": "slip"})


@pytest.fixture(scope="module")
def mission1():
    return aw_missions.run_mission("mission1")


@pytest.fixture(scope="module")
def mission2():
    return aw_missions.run_mission("mission2")


def _state(robot, t=0.7, qx=0.04, qy=-0.03, seed=0):
    """A configuration on the constraint manifold (from the IK) and an admissible velocity."""
    cmd = aw_paper.Commands(np.sin(t), np.cos(t), 0.15, qx, qy, -t)
    x, err, _ = aw_paper.solve_ik(cmd, robot.params, robot.terrain)
    q = aw_cmp.model_configuration(robot, cmd, x, spins=np.array([0.3, -1.1, 2.0]))
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
    off = aw_paper.offsets(robot.params)
    z = q[robot.coordinate_index("z")]
    for tag in aw.WHEELS:
        c = robot.data.oMf[robot.model.getFrameId(f"wheel_{tag}")].translation
        np.testing.assert_allclose(c, off[tag] + [0, 0, z], atol=1e-14)
    full = Robot(aw.SPEC, {"L_reading": "full"})
    np.testing.assert_allclose(aw_paper.offsets(full.params)["fr"], [0.3, -0.3, 0.0])


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


def test_coupling_law_is_eq1_and_eq33(robot):
    """The coupling's law (a CosineLaw, so the compiled path can evaluate it) is eq 1 and its derivatives eq 33
    (and the second derivative) as transcribed in radius_law*, and f' and f'' agree with finite differences."""
    w = robot.params["w"]
    c = next(c for c in robot.constraints if c.name == "eq1_fr")
    for q in np.linspace(0.0, np.pi, 7):
        assert c.law(q) == pytest.approx(aw_paper.radius_law(q, w), abs=1e-15)
        assert c.dlaw(q) == pytest.approx(aw_paper.radius_law_d(q, w), abs=1e-15)
        assert c.ddlaw(q) == pytest.approx(aw_paper.radius_law_dd(q, w), abs=1e-15)
        h = 1e-5
        assert c.dlaw(q) == pytest.approx((c.law(q + h) - c.law(q - h)) / (2 * h), abs=1e-9)
        assert c.ddlaw(q) == pytest.approx((c.dlaw(q + h) - c.dlaw(q - h)) / (2 * h), abs=1e-9)


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


# --------------------------------------------------------------------------------------- inverse kinematics
@pytest.mark.parametrize("name", ["mission1", "mission2"])
def test_ik_converges_every_step(name, request, robot):
    run = request.getfixturevalue(name)
    assert len(run.t) == 501 and run.t[-1] == pytest.approx(5.0)
    assert run.error.max() <= 1e-10
    assert np.all((run.q >= 0) & (run.q <= np.pi))
    # independent check: the core rolling contact (u = projected normal, p = c - R u) at the model configuration
    r = Robot(aw.SPEC, {"terrain": run.mission.terrain})
    worst = 0.0
    for i in range(0, len(run.t), 5):
        q = aw_cmp.model_configuration(r, run.commands[i], np.concatenate([run.beta[i], run.q[i]]))
        worst = max(worst, np.max(np.abs(r.constraint_residual(q))))
    assert worst < 1e-10


def test_ik_yaw_follows_path_tangent(mission1):
    """Eqs 18-23 with the body level: q_zd = direction of the path tangent of x = sin t, y = cos t, i.e. -t."""
    np.testing.assert_allclose(mission1.yaw, -mission1.t, atol=1e-12)
    # the CG is h_CG above the path point along the normal (eq 6)
    from robotdyn.constraints.terrain import SineTerrain
    terrain = SineTerrain(1 / 15, 0.5, 0.5)
    for i in (0, 123, 400):
        x, y = np.sin(mission1.t[i]), np.cos(mission1.t[i])
        ground = np.array([x, y, np.sin(0.5 * (x + y)) / 15])
        np.testing.assert_allclose(np.linalg.norm(mission1.cg[i] - ground), 0.15, atol=1e-14)


def test_ik_mission2_constant_on_ramp(mission2):
    """On a plane, moving along the level direction with the body level, the solution is the same at every step
    and the radii follow the ramp: R_T = centre height - ground height under the (vertical) wheel."""
    np.testing.assert_allclose(mission2.q, np.broadcast_to(mission2.q[0], mission2.q.shape), atol=1e-9)
    n = np.array([0.0, 0.2, 1.0]) / np.sqrt(1.04)
    cg = 0.15 * n  # path point at the origin, ramp z = -0.2 y
    for k, yk in enumerate((-0.6, 0.6, 0.0)):
        expected = cg[2] - (-0.2 * (cg[1] + yk))
        assert mission2.RT[0, k] == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize(
    "cmd, wheel, limit",
    [
        (aw_paper.Commands(0, 0, 0.2, 0, 0.15, 0), "wheel r", "q = 0 deg"),
        (aw_paper.Commands(0, 0, 0.2, 0.3, 0, 0), "wheel fl", "q = 0 deg"),
        (aw_paper.Commands(0, 0, 0.01), "wheel fr", "q = 180 deg"),
    ],
)
def test_ik_out_of_range_names_wheel_and_limit(cmd, wheel, limit, robot):
    from robotdyn.constraints.terrain import FlatTerrain
    with pytest.raises(aw_paper.MechanismRangeError) as exc:
        aw_paper.solve_ik(cmd, robot.params, FlatTerrain())
    msg = str(exc.value)
    assert wheel in msg and limit in msg and "0-180 deg" in msg and "\n" not in msg
    assert isinstance(exc.value, RobotDynError)


def test_ik_mission_out_of_range_reports_time():
    with pytest.raises(aw_paper.MechanismRangeError, match=r"mission1, t = 0.00 s: wheel \w+: .*0-180 deg"):
        aw_missions.run_mission("mission1", {"w": 0.1})


# ------------------------------------------------------------------------------------------------ statics
def test_statics_flat_lever_rule(robot):
    """Flat ground, level body: the CG is midway between the front axle and the rear wheel, so the rear wheel
    carries m g / 2 and each front wheel m g / 4 (not the m g / 3 of eq 35); no friction is needed."""
    from robotdyn.constraints.terrain import FlatTerrain
    p = robot.params
    cmd = aw_paper.Commands(0.0, 0.0, 0.15)
    x, _, _ = aw_paper.solve_ik(cmd, p, FlatTerrain())
    res = aw_paper.static_torques(cmd, x, p, FlatTerrain())
    mg = 10 * 9.81
    np.testing.assert_allclose(res.normal, [mg / 4, mg / 4, mg / 2], atol=1e-10)
    np.testing.assert_allclose(res.friction, 0.0, atol=1e-10)
    # eq 34 with the equal-share load of eq 35 gives eq 35 exactly
    share = -0.5 * (mg / 3) * 0.3 * np.sin(x[3:] / 2) * np.cos(np.pi / 6)
    np.testing.assert_allclose(aw_paper.paper_torque_eq35(x[3:], p), share, rtol=1e-14)


@pytest.mark.parametrize("name", ["mission1", "mission2"])
def test_statics_equilibrium_cone_and_virtual_work(name, request):
    run = request.getfixturevalue(name)
    r = Robot(aw.SPEC, {"terrain": run.mission.terrain})
    for i in (0, 77, 250, 500):
        x = np.concatenate([run.beta[i], run.q[i]])
        res = aw_paper.static_torques(run.commands[i], x, r.params, r.terrain)
        assert res.equilibrium < 1e-9
        assert np.all(res.normal > 0) and np.all(res.ratio <= 1 + 1e-9)
        # total force and moment about the CG, recomputed here
        np.testing.assert_allclose(res.forces.sum(0), [0, 0, 98.1], atol=1e-9)
        np.testing.assert_allclose(np.cross(res.contacts - run.cg[i], res.forces).sum(0), 0, atol=1e-9)
        chk = aw_cmp.model_static_check(r, run.commands[i], x, res)
        assert chk["residual"] < 1e-9  # the whole model is in equilibrium with these forces and torques
        np.testing.assert_allclose(chk["tau_adjust"], res.torque, atol=1e-9)  # eq 34 = model
        np.testing.assert_allclose(chk["tau_fd"], res.torque, atol=1e-6)  # eq 34 = finite-difference work


def test_statics_friction_cone_enforced():
    """A steep ramp with little friction: the KKT minimum leaves the cone, the optimiser must respect it or fail
    with a one-line error."""
    from robotdyn.contact.statics import solve_contact_forces
    pts = np.array([[0.5, -0.5, 0.0], [0.5, 0.5, 0.0], [-0.5, 0.0, 0.0]])
    n = np.array([0.0, -0.3, 1.0]) / np.sqrt(1.09)
    nrm = np.tile(n, (3, 1))
    ok = solve_contact_forces(pts, nrm, [0, 0, 98.1], [0, 0, 0], [0, 0, 0.2], mu=0.5)
    assert np.all(ok.ratio <= 1 + 1e-9) and ok.equilibrium < 1e-9
    with pytest.raises(RobotDynError, match="friction cones"):
        solve_contact_forces(pts, nrm, [0, 0, 98.1], [0, 0, 0], [0, 0, 0.2], mu=0.2)


# ------------------------------------------------------------------------------------------------ dynamics
def test_dynamics_rates_match_ik_finite_differences(mission1):
    """The constraint layer's adjustment rates (S nu, rolling + eq-1 coupling rows) equal the time derivative of
    the paper's IK (independent route), and the model's force balance closes."""
    d = aw_dyn.mission_dynamics(mission1, every=50)
    np.testing.assert_allclose(d.qdot_model, d.qdot_fd, atol=1e-8)
    assert d.residual.max() < 1e-9
    assert np.all(d.ratio_dynamic <= 1 + 1e-9) and np.all(d.normal_dynamic > 0)


@pytest.mark.parametrize("params", [{}, {"m_wheel": 0.5, "I_adjust": 0.01}])
def test_dynamics_energy_balance(mission1, params):
    """dE/dt (finite differences of Pinocchio's energy along the motion) = motor power + contact-force power."""
    mm = aw_dyn.MissionModel(mission1, params)
    h = 1e-4
    for t in (0.7, 2.3, 4.1):
        r = mm.at(t)
        dE = (mm.at(t + h)["energy"] - mm.at(t - h)["energy"]) / (2 * h)
        assert dE == pytest.approx(r["motor_power"] + r["contact_power"], abs=1e-6)


def test_dynamics_at_rest_equals_statics():
    """With the body at rest (zero path velocity) the kinetostatic route reproduces eqs 25-34."""
    m = aw_missions.Mission("rest", "", "rough", lambda t: (0.3, -0.2, 0.0, 0.0), t_end=0.05)
    run = aw_missions.run_mission(m)
    d = aw_dyn.mission_dynamics(run)
    np.testing.assert_allclose(d.tau_dynamic[:, 3:], d.tau_static, atol=1e-9)
    assert d.lateral_slip.max() < 1e-12


def test_mission1_needs_lateral_slip(mission1):
    """Rolling without slipping forbids mission 1: each wheel slides sideways at about |yaw rate| * Lx."""
    d = aw_dyn.mission_dynamics(mission1, every=100)
    assert d.lateral_slip.min() > 0.5


# ------------------------------------------------------------------------------------ scenario, compare, CLI
def test_hold_scenario_stays_at_rest(robot):
    sc = aw.SCENARIOS["hold"]
    traj = sc.run(robot, t_end=0.5, n_out=11, progress=False)
    assert np.abs(traj.nu).max() < 1e-8
    np.testing.assert_allclose(traj.q[-1], traj.q[0], atol=1e-9)
    assert traj.residual.max() < 1e-9
    red = robot.reduced(traj.q[0], np.zeros(robot.mobility))
    np.testing.assert_allclose(red.B @ sc.holding, red.g, atol=1e-10)


def test_compare_verdicts(robot, mission1, mission2):
    cmp = aw_cmp.compare(robot, {"mission1": mission1, "mission2": mission2})
    rows = {r.quantity: r for r in cmp.rows}
    assert rows["eq 24: max ||C|| over missions 1-2 (criterion 1e-5)"].verdict == "reproduced"
    # eq 35 evaluated at Table 2's own angles does not give Table 2's torques (paper's internal inconsistency)
    r = rows["Table 2: torque r, eq 35 at Table 2's angle [N m]"]
    assert r.model == pytest.approx(0.5 * 98.1 * 0.3 * np.sin(np.radians(57.5)) * np.cos(np.pi / 6) / 3, abs=1e-12)
    assert r.verdict == "differs"
    assert rows["sec 7: max torque, mission 1, eq 35 [N m]"].verdict == "reproduced"


def test_cli_ik(capsys, tmp_path):
    import json

    from robotdyn.cli import main
    assert main(["ik", "adaptable_wheel", "--commands", "0.3", "0.2", "0.15", "0", "0", "0.1", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["error"] <= 1e-10
    r = Robot(aw.SPEC)
    q = np.array([data["model_q"][c] for c in r.coordinates])
    assert np.max(np.abs(r.constraint_residual(q))) < 1e-10
    assert main(["ik", "adaptable_wheel", "--commands", "0", "0", "0.35", "0", "0", "0"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "wheel fr" in err and "q = 0 deg" in err
    assert main(["ik", "adaptable_wheel", "--commands", "1", "2"]) == 2
    assert "expected 6 values" in capsys.readouterr().err
    csv = tmp_path / "m2.csv"
    assert main(["ik", "adaptable_wheel", "--mission", "mission2", "--csv", str(csv)]) == 0
    assert np.loadtxt(csv, delimiter=",", skiprows=1).shape == (501, 15)


# ------------------------------------------------------------------------------ forward dynamics and singularity
@pytest.mark.parametrize("params", [{}, {"m_wheel": 0.4, "I_adjust": 0.002}])
def test_energy_balance_forward_simulation(params):
    """Rolling without slipping on a gentle ramp: energy conserved without torques, and E(t) - E(0) = work of the
    motors with torques (Simpson quadrature of the motor power)."""
    from scipy.integrate import cumulative_simpson

    from robotdyn.simulation import power, simulate
    r = Robot(aw.SPEC, {"terrain": "ramp", "ramp_slope": 0.05, **params})
    cmd = aw_paper.Commands(0.3, -0.2, 0.15)
    x, _, _ = aw_paper.solve_ik(cmd, r.params, r.terrain)
    q0 = aw_cmp.model_configuration(r, cmd, x)
    nu0 = np.random.default_rng(0).normal(size=r.mobility) * 0.3
    free = simulate(r, 0.05, q0, nu0, None, n_out=11, progress=False)
    assert np.ptp(free.energy) < 1e-8 and free.residual.max() < 1e-9
    red = r.reduced(q0, np.zeros(r.mobility))
    hold, *_ = np.linalg.lstsq(red.B, red.g, rcond=None)
    tau = lambda t, q, nu: hold * (1 + 0.05 * np.sin(5 * t))  # noqa: E731
    tr = simulate(r, 0.3, q0, nu0, tau, n_out=301, progress=False)
    work = cumulative_simpson(power(r, tr, tau), x=tr.t, initial=0)
    assert abs(work[-1]) > 0.5
    np.testing.assert_allclose(tr.energy - tr.energy[0], work, atol=1e-8)


def test_front_radii_singularity():
    """Three fixed parallel axles: with equal front radii on flat ground the two front lateral rows coincide
    (rank 11, the core reports the mismatch); the smallest singular value grows linearly with the difference."""
    from robotdyn.errors import SingularConstraintError
    from robotdyn.constraints.terrain import FlatTerrain
    r = Robot(aw.SPEC, {"terrain": "flat"})
    ratios = []
    for roll in (0.0, 0.01, 0.1):
        cmd = aw_paper.Commands(0, 0, 0.15, roll, 0, 0)
        x, _, _ = aw_paper.solve_ik(cmd, r.params, FlatTerrain())
        q = aw_cmp.model_configuration(r, cmd, x)
        s = np.linalg.svd(r.constraint_rows(KinematicState(r.model, r.data, q, np.zeros(15))).A, compute_uv=False)
        ratios.append(s[-1] / s[0])
        if roll == 0.0:
            assert np.sum(s > 1e-9 * s[0]) == 11
            with pytest.raises(SingularConstraintError):
                r.reduced(q, np.zeros(r.mobility))
    assert ratios[2] / ratios[1] == pytest.approx(10, rel=0.05)


def test_cli_compare_simulate_and_errors(capsys):
    import json

    from robotdyn.cli import main
    assert main(["compare", "adaptable_wheel", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["rows"]
    assert {r["verdict"] for r in rows} == {"reproduced", "differs"}
    assert main(["simulate", "adaptable_wheel", "--scenario", "hold", "--t-end", "0.2", "--quiet", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert abs(out["energy_end"] - out["energy_start"]) < 1e-9
    assert main(["ik", "adaptable_wheel", "--param", "L_reading=third", "--commands", "0", "0", "0.15", "0", "0",
                 "0"]) == 2
    assert "expected one of half, full" in capsys.readouterr().err
    assert main(["ik", "adaptable_wheel", "--commands", "0", "0", "-0.1", "0", "0", "0"]) == 2
    assert "positive height" in capsys.readouterr().err


def test_generic_modules_reject_bad_input(robot):
    from robotdyn.contact.statics import solve_contact_forces
    with pytest.raises(RobotDynError, match="driven and driver"):
        JointCoupling(robot.description, "adjust_fr_joint", "adjust_fr_joint", np.cos, np.sin, np.cos)
    with pytest.raises(RobotDynError, match="no joint"):
        JointCoupling(robot.description, "nope", "adjust_fr_joint", np.cos, np.sin, np.cos)
    with pytest.raises(RobotDynError, match="mu"):
        solve_contact_forces(np.zeros((3, 3)), np.tile([0, 0, 1.0], (3, 1)), [0, 0, 1], [0, 0, 0], [0, 0, 0], 0.0)
    with pytest.raises(RobotDynError, match="expected two"):
        solve_contact_forces(np.zeros((3, 2)), np.zeros((3, 3)), [0, 0, 1], [0, 0, 0], [0, 0, 0], 1.0)


# -------------------------------------------------------------------- mission 1 with a lateral friction law
@pytest.fixture(scope="module")
def friction_run():
    from dataclasses import replace

    return aw_dyn.mission_friction(aw_missions.run_mission(replace(aw_missions.MISSIONS["mission1"], t_end=1.0)))


def test_mission1_lateral_friction_energy_balance(friction_run):
    """Wheels rolling along t1 and sliding sideways under Coulomb friction (mu = 1, Table 1): the torques and loads
    of robotdyn.contact.sliding.inverse close the energy balance dE/dt = motor power + friction power (finite differences of
    Pinocchio's energy, O(dt^2) = 1e-4 of the ~100 W powers), and the friction only dissipates."""
    fr = friction_run
    assert np.all(fr.rank == 15) and fr.residual.max() < 1e-9
    dE = np.gradient(fr.energy, fr.t)
    np.testing.assert_allclose(dE[2:-2], fr.power.sum(axis=1)[2:-2], atol=1e-3)
    assert np.all(fr.normal > 0) and np.all(fr.power[:, 1] < 0)
    np.testing.assert_allclose(np.abs(fr.lateral), fr.normal, rtol=1e-5)  # Coulomb: |f_lat| = mu f_n at 0.6 m/s
    assert np.all(np.abs(fr.slip) > 0.5)


def test_mission1_impossible_with_lateral_friction(friction_run):
    """The finding of the errata: with a real lateral law the commanded motion needs |f_t| / f_n far beyond mu = 1
    (not a threshold on mu: no mu makes it consistent, tests/test_errata.py) (the rigid model balances the lateral forces only through the terrain's tilt, with traction of ~1 kN), and on
    flat ground no torques and contact forces realise it at all (rank 14 of 15: lateral sliding friction sums to
    mu (f_fr + f_fl - f_r), which the pitch balance forces to zero, while the path needs m v^2 / rho = 10 N)."""
    from dataclasses import replace

    assert friction_run.required_mu.min() > 10
    mission = replace(aw_missions.MISSIONS["mission1"], terrain="flat", t_end=0.2)
    flat = aw_dyn.mission_friction(aw_missions.run_mission(mission))
    assert np.all(flat.rank == 14) and flat.residual.min() > 1.0
