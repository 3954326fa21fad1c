"""MMR12-EOD (Zuniga-Aviles et al. 2014): model, reduced dynamics (eq 22), kinematics (eqs 1-14, 27-31).

References are independent of the model path: finite differences, energy balance, Pinocchio's KKT constrained
forward dynamics, the closed forms of eqs 12-14, a separate numeric product of Table 2's HTG chain and the
paper's printed numbers.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import robotdyn
from robotdyn.errors import InputError, RobotDynError
from robotdyn.robots.mmr12_eod import model as mm
from robotdyn.robots.mmr12_eod import paper as mm_paper
from robotdyn.robots.mmr12_eod import comparison as mm_cmp
from robotdyn.simulation import power, simulate


@pytest.fixture(scope="module")
def robot():
    return robotdyn.load("mmr12_eod")


def random_q(robot, rng, lift=False):
    """A configuration in the joint ranges; lambda_C = 0 (drive wheels on the ground) unless ``lift``."""
    q = robot.neutral()
    lo, hi = robot.description.lower, robot.description.upper
    for i, name in enumerate(robot.coordinates):
        a = lo[i] if np.isfinite(lo[i]) else -3.0
        c = hi[i] if np.isfinite(hi[i]) else 3.0
        q[i] = rng.uniform(a + 1e-3 * (c - a), c - 1e-3 * (c - a))
    if not lift:
        q[robot.coordinate_index("lambda_C")] = 0.0
    return q


# ----------------------------------------------------------------------------------- model and constraints
def test_model_loads_with_expected_coordinates(robot):
    assert robot.nq == 16
    assert robot.mobility == 12
    assert set(robot.coordinates) == {"x", "y", "psi", "lambda_C", *mm.ACTUATED}
    assert robot.velocity_names == [f"{c}_dot" for c in mm.ACTUATED]
    total = pin.computeTotalMass(robot.model)
    masses = ["m_platform", "m_turret", "m_boom", "m_link3", "m_link4", "m_load"]
    expected = sum(robot.params[k] for k in masses) + 2 * robot.params["m_wheel"] + 4 * robot.params["m_arm"] + 0.2
    assert total == pytest.approx(expected, rel=1e-12)


def test_AS_zero_and_S_matches_eqs_12_to_14(robot):
    rng = np.random.default_rng(0)
    iR, iL = robot.velocity_names.index("theta_R_dot"), robot.velocity_names.index("theta_L_dot")
    ix, iy, ipsi = (robot.coordinate_index(c) for c in ("x", "y", "psi"))
    for _ in range(20):
        q = random_q(robot, rng)
        nu = rng.normal(size=robot.mobility)
        red = robot.reduced(q, nu)
        assert np.max(np.abs(red.rows.A @ red.S)) < 1e-13
        ref = mm_paper.paper_platform_rates(robot.params, q[ipsi], nu[iR], nu[iL])
        assert red.v[[ix, iy, ipsi]] == pytest.approx(ref, abs=1e-12)
        assert red.v[robot.coordinate_index("lambda_C")] == pytest.approx(0.0, abs=1e-13)
        # eq 12: no lateral velocity; eq 13 with the right wheel at -b
        assert -red.v[ix] * np.sin(q[ipsi]) + red.v[iy] * np.cos(q[ipsi]) == pytest.approx(0.0, abs=1e-12)


def test_Mr_symmetric_positive_definite(robot):
    rng = np.random.default_rng(1)
    for _ in range(20):
        red = robot.reduced(random_q(robot, rng), np.zeros(robot.mobility))
        assert np.max(np.abs(red.M - red.M.T)) < 1e-12 * np.max(np.abs(red.M))
        assert np.linalg.eigvalsh(red.M).min() > 0


def test_Mr_and_gr_from_energies(robot):
    """M_r by polarisation of Pinocchio's kinetic energy (body velocities, not CRBA) at v = S nu; g_r as the
    directional derivative of the potential energy (mass centres' heights, not RNEA) along the columns of S."""
    rng = np.random.default_rng(4)
    model, data = robot.model, robot.data
    for _ in range(5):
        q = random_q(robot, rng)
        red = robot.reduced(q, np.zeros(robot.mobility))
        S, k = red.S, robot.mobility

        def T(nu):
            return pin.computeKineticEnergy(model, data, q, S @ nu)

        E = np.eye(k)
        M = np.array([[T(E[i] + E[j]) - T(E[i]) - T(E[j]) if i != j else 2 * T(E[i]) for j in range(k)]
                      for i in range(k)])
        assert M == pytest.approx(red.M, abs=1e-10 * np.max(np.abs(red.M)))
        eps = 1e-6
        g = np.array([(pin.computePotentialEnergy(model, data, q + eps * S[:, i])
                       - pin.computePotentialEnergy(model, data, q - eps * S[:, i])) / (2 * eps) for i in range(k)])
        assert g == pytest.approx(red.g, abs=1e-6 * max(1.0, np.max(np.abs(red.g))))


def test_reduced_dynamics_matches_kkt_forward_dynamics(robot):
    """Eq 22 (projection path) vs Pinocchio's constrained forward dynamics (KKT with J = A, gamma = Adot v)."""
    rng = np.random.default_rng(2)
    model, data = robot.model, robot.data
    for _ in range(10):
        q = random_q(robot, rng)
        nu = rng.normal(size=robot.mobility)
        tau = rng.normal(size=len(robot.motors)) * 5
        red = robot.reduced(q, nu)
        nudot = np.linalg.solve(red.M, red.B @ tau - red.h)
        a_red = red.S @ nudot + red.w
        rows = red.rows.A[red.projection.rows]
        gamma = (red.rows.Adot @ red.v)[red.projection.rows]
        tau_full = np.zeros(robot.nq)
        for j, m in enumerate(robot.motors):
            tau_full[m.index] += tau[j]
        a_kkt = pin.forwardDynamics(model, data, q, red.v, tau_full, rows, gamma)
        assert a_red == pytest.approx(a_kkt, abs=1e-8 * (1 + np.max(np.abs(a_kkt))))


def test_Mr_dot_minus_2Cr_is_skew_by_finite_differences(robot):
    rng = np.random.default_rng(3)
    for _ in range(5):
        q = random_q(robot, rng)
        q[robot.coordinate_index("theta1")] = np.clip(q[robot.coordinate_index("theta1")], 0.2, 2.9)
        nu = rng.normal(size=robot.mobility)
        red = robot.reduced(q, nu, coriolis=True)
        eps = 1e-6
        Mp = robot.reduced(q + eps * red.v, nu).M
        Mm = robot.reduced(q - eps * red.v, nu).M
        Mdot = (Mp - Mm) / (2 * eps)
        N = Mdot - 2 * red.C
        assert np.max(np.abs(N + N.T)) < 1e-6 * max(1.0, np.max(np.abs(Mdot)))
        # and C_r nu + g_r is the bias of eq 22
        assert red.C @ nu + red.g == pytest.approx(red.h, abs=1e-9 * (1 + np.max(np.abs(red.h))))


def test_energy_balance_torque_free_and_with_torque(robot):
    q0 = robot.neutral()
    nu0 = np.zeros(robot.mobility)
    nu0[robot.velocity_names.index("theta_R_dot")] = 2.0
    nu0[robot.velocity_names.index("theta_L_dot")] = -1.0
    nu0[robot.velocity_names.index("theta1_dot")] = 0.3
    traj = simulate(robot, 0.5, q0, nu0, None, n_out=11, rtol=1e-10, atol=1e-12, progress=False)
    assert np.max(np.abs(traj.energy - traj.energy[0])) < 1e-6 * abs(traj.energy[0])
    assert np.ptp(traj.column("theta1")) > 0.05  # it did move
    # with torque: E(T) - E(0) = integral of motor power
    torque = lambda t, q, nu: np.full(len(robot.motors), 0.5) * np.cos(3 * t)  # noqa: E731
    traj = simulate(robot, 0.5, q0, nu0, torque, n_out=201, rtol=1e-10, atol=1e-12, progress=False)
    P = power(robot, traj, torque)
    work = np.trapezoid(P, traj.t) if hasattr(np, "trapezoid") else np.trapz(P, traj.t)
    assert traj.energy[-1] - traj.energy[0] == pytest.approx(work, abs=1e-4 * max(1.0, abs(work)))


# -------------------------------------------------------------------------------------------- joint ranges
@pytest.mark.parametrize("label, value", [("lambda2", -0.1), ("theta_C1", 1.7), ("theta_C4", -2.0),
                                          ("lambda6", 0.5), ("lambda_C", -0.01), ("theta1", -0.2)])
def test_out_of_range_joint_is_a_clear_error(robot, label, value):
    q = robot.neutral()
    q[robot.coordinate_index(label)] = value
    with pytest.raises(InputError, match=rf"q\[{label}\] = .* outside its joint range"):
        robot.check_q(q)


# ------------------------------------------------------------------------------------- forward kinematics
from robotdyn.description.kinematics import check_pose, frame_names, frame_pose, is_rotation, position_ik, relative_pose  # noqa: E402

_FK_NAMES = ["x", "y", "psi", "lambda_C", "theta1", "lambda2", "theta3", "theta4", "lambda6"]


def _fk_values(rng):
    return dict(x=rng.uniform(-3, 3), y=rng.uniform(-3, 3), psi=rng.uniform(-np.pi, np.pi),
                lambda_C=rng.uniform(0, 0.37), theta1=rng.uniform(0, np.pi), lambda2=rng.uniform(0, 1.5),
                theta3=rng.uniform(-np.pi, np.pi), theta4=rng.uniform(-np.pi, np.pi), lambda6=rng.uniform(0, 0.3))


def test_fk_matches_htg_chain_and_eq2_except_the_R22_typo(robot):
    rng = np.random.default_rng(10)
    for _ in range(30):
        vals = _fk_values(rng)
        args = [vals[k] for k in _FK_NAMES]
        T = frame_pose(robot, mm.state(robot, theta_mu=0.0, **vals), "X")
        assert T == pytest.approx(mm_paper.paper_htg_chain(robot.params, *args), abs=1e-12)
        P = mm_paper.paper_X_M(robot.params, *args)
        mask = np.ones((4, 4), bool)
        mask[1, 1] = False
        assert T[mask] == pytest.approx(P[mask], abs=1e-12)
        # the printed R22 = S_C C13; the chain gives S_C S13 (column 2 = z_4 = (C_C S13, S_C S13, -C13))
        S13 = np.sin(vals["theta1"] + vals["theta3"])
        assert T[1, 1] == pytest.approx(np.sin(vals["psi"]) * S13, abs=1e-12)


def test_printed_eq2_is_not_a_rotation_in_general(robot):
    P = mm_paper.paper_X_M(robot.params, 0, 0, 0.7, 0.0, 1.0, 0.5, -0.4, 0.3, 0.1)
    assert not is_rotation(P[:3, :3], 1e-3)


def test_every_library_pose_is_a_proper_rotation(robot):
    rng = np.random.default_rng(11)
    frames = frame_names(robot)
    assert {"C", "X", "E", "frame0", "CS1", "W_R"} <= set(frames)
    for _ in range(5):
        q = random_q(robot, rng, lift=True)
        for f in frames:
            T = frame_pose(robot, q, f)
            R = T[:3, :3]
            assert np.max(np.abs(R.T @ R - np.eye(3))) < 1e-12
            assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-12)
            assert T[3] == pytest.approx([0, 0, 0, 1])
        Trel = relative_pose(robot, q, "X", "C")
        assert is_rotation(Trel[:3, :3], 1e-12)


def test_check_pose_rejects_the_printed_eq29():
    with pytest.raises(RobotDynError, match="not a proper rotation"):
        check_pose(mm_paper.PRINTED["eq 29"])
    check_pose(mm_paper.PRINTED["eq 28"], tol=2e-4)  # 4-decimal rounding of a rotation


@pytest.mark.parametrize("key", sorted(mm_paper.PRINTED))
def test_printed_transforms_entry_by_entry(robot, key):
    """Eqs 27-31 with the parameters printed beside them: which entries the model reproduces."""
    paper = mm_paper.PRINTED[key]
    model = mm_cmp.model_printed(robot, key)
    assert is_rotation(model[:3, :3], 1e-12)
    differs = {(i, j) for i in range(3) for j in range(4)
               if abs(paper[i, j] - model[i, j]) > (5e-20 if 0 < abs(paper[i, j]) < 1e-10 else 5e-5)}
    expected = {"eq 27": set(), "eq 28": set(), "eq 30": set(), "eq 29": {(2, 2)},  # R33 sign typo
                "eq 31": {(0, 3), (1, 3), (2, 3)}}[key]  # position of the arm frame not reproduced
    assert differs == expected
    if key == "eq 29":
        assert paper[2, 2] == pytest.approx(-model[2, 2], abs=5e-5)  # a sign flip
        assert abs(np.linalg.det(paper[:3, :3])) < 1e-12  # printed matrix singular: columns 2 and 3 equal
    else:
        assert is_rotation(paper[:3, :3], 2e-4)


def test_eq26_lift_matches_the_model_over_the_range(robot):
    for th in np.linspace(-0.5, np.pi / 2, 25):
        assert mm_cmp.model_lift(robot, th) == pytest.approx(mm_paper.paper_delta_lambda(robot.params, th), abs=1e-12)
    assert mm_cmp.model_lift(robot, np.pi / 2) + robot.params["lambda_C0"] == pytest.approx(0.52, abs=1e-12)  # eq 30


def test_cli_fk_prints_a_proper_pose(capsys):
    from robotdyn.cli import main

    q = ["2", "2", str(np.pi / 4), "0.37", str(3 * np.pi / 4), "1.4", str(-np.pi / 2), str(np.pi / 2), "0.25", "0",
         *(["1.5707963"] * 4), "0", "0"]
    assert main(["fk", "mmr12_eod", "--q", *q, "--frame", "X", "--json"]) == 0
    import json

    data = json.loads(capsys.readouterr().out)
    T = np.array(data["T"])
    assert is_rotation(T[:3, :3], 1e-12)
    assert T[:3, 3] == pytest.approx([2.8567, 2.8567, 1.3305], abs=5e-5)  # eq 29's printed position
    assert main(["fk", "mmr12_eod", "--q", *q, "--frame", "C"]) == 0
    assert "pose of 'C'" in capsys.readouterr().out
    bad = list(q)
    bad[5] = "-0.2"  # lambda2 < 0
    assert main(["fk", "mmr12_eod", "--q", *bad, "--frame", "X"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "lambda2" in err and "outside its joint range" in err
    assert main(["fk", "mmr12_eod", "--q", *q, "--frame", "nowhere"]) == 2
    assert "no frame named 'nowhere'" in capsys.readouterr().err


# ------------------------------------------------------------------------------------- inverse kinematics
@pytest.fixture(scope="module")
def ik_cases(robot):
    return mm_cmp.ik_cases(robot, n=4, seed=3)


def test_numerical_ik_reaches_targets_in_the_manipulation_range(robot, ik_cases):
    for case in ik_cases:
        for sol in (case["platform"], case["free"]):
            assert sol.success and sol.error < 1e-9
            robot.check_q(sol.q)  # within the joint ranges
            assert frame_pose(robot, sol.q, "E")[:3, 3] == pytest.approx(case["target"], abs=1e-9)
        t = case["target"]
        assert t[0] <= 2.5 and t[1] <= 2.5 and t[2] <= 1.5


def test_eqs_3_10_11_reproduce_the_numerical_ik(robot, ik_cases):
    p = robot.params
    for case in ik_cases:
        q = case["platform"].q
        ik = mm_paper.paper_ik(p, case["target"], case["arm"]["lambda2"], case["arm"]["theta1"], case["arm"]["theta3"])
        assert ik["phi"] == pytest.approx(q[robot.coordinate_index("psi")], abs=1e-12)  # eq 3 (imposed)
        assert ik["x_C"] == pytest.approx(q[robot.coordinate_index("x")], abs=1e-9)
        assert ik["y_C"] == pytest.approx(q[robot.coordinate_index("y")], abs=1e-9)
        # free IK: the heading always points from C at the target (eq 3 measured from C)
        qf = case["free"].q
        C = frame_pose(robot, qf, "C")[:3, 3]
        phi = np.arctan2(case["target"][1] - C[1], case["target"][0] - C[0])
        assert phi == pytest.approx(qf[robot.coordinate_index("psi")], abs=1e-8)


def test_eqs_10_11_omit_the_load_offset_lambda6(robot, ik_cases):
    case = ik_cases[0]
    q = case["platform"].q.copy()
    q[robot.coordinate_index("lambda6")] = 0.25
    target_X = frame_pose(robot, q, "X")[:3, 3]
    arm = case["arm"]
    ik = mm_paper.paper_ik(robot.params, target_X, arm["lambda2"], arm["theta1"], arm["theta3"])
    miss = np.hypot(ik["x_C"] - q[robot.coordinate_index("x")], ik["y_C"] - q[robot.coordinate_index("y")])
    assert miss == pytest.approx(0.25 * abs(np.sin(arm["theta1"] + arm["theta3"])), abs=1e-9)


def test_eq4_is_the_interior_angle_only_without_l3(ik_cases):
    r0 = robotdyn.load("mmr12_eod", {"l3": 0.0})
    for case in mm_cmp.ik_cases(r0, n=3, seed=4):
        q = case["free"].q
        rel = case["target"] - frame_pose(r0, q, "frame0")[:3, 3]
        th1, lam2, th3 = (q[r0.coordinate_index(c)] for c in ("theta1", "lambda2", "theta3"))
        assert mm_paper.paper_ik(r0.params, rel, lam2, th1, th3)["theta3"] == pytest.approx(np.pi - abs(th3), abs=1e-8)
    # with the paper's l3 = 0.15 it misses (documented in the errata)
    r = robotdyn.load("mmr12_eod")
    case = ik_cases[0]
    q = case["free"].q
    rel = case["target"] - frame_pose(r, q, "frame0")[:3, 3]
    th1, lam2, th3 = (q[r.coordinate_index(c)] for c in ("theta1", "lambda2", "theta3"))
    assert abs(mm_paper.paper_ik(r.params, rel, lam2, th1, th3)["theta3"] - (np.pi - abs(th3))) > 0.05


def test_eq5_does_not_invert_the_model(robot, ik_cases):
    """Eq 5 evaluated at exact model solutions does not return their lambda2, whatever d_z is measured from."""
    worst = np.zeros(3)
    for case in ik_cases:
        q = case["free"].q
        th1, lam2, th3 = (q[robot.coordinate_index(c)] for c in ("theta1", "lambda2", "theta3"))
        z0 = frame_pose(robot, q, "frame0")[2, 3]
        zC = frame_pose(robot, q, "C")[2, 3]
        for k, dz in enumerate((case["target"][2] - z0, case["target"][2] - zC, case["target"][2])):
            worst[k] = max(worst[k], abs(mm_paper.paper_ik(robot.params, [0, 0, dz], lam2, th1, th3)["lambda2"] - lam2))
    assert np.all(worst > 0.1)


def test_ik_bad_target_is_a_clear_error(robot):
    with pytest.raises(InputError, match="IK target"):
        position_ik(robot, "E", [1.0, np.nan, 1.0], robot.neutral(), ["x", "y"])


# ---------------------------------------------------------------------------------- lifting and climbing
@pytest.fixture(scope="module")
def lifting_run(robot):
    return mm.SCENARIOS["lifting"].run(robot, progress=False)


def test_lifting_follows_eq26_and_reaches_052(lifting_run):
    traj = lifting_run
    rob = traj.stats["robot"]
    lam = traj.column("lambda_C")
    th = traj.q[:, [rob.coordinate_index(f"theta_C{i}") for i in mm._ARMS]]
    ref = np.array([mm_paper.paper_delta_lambda(rob.params, a) for a in th[:, 0]])
    assert np.max(np.abs(lam - ref)) < 1e-7  # eq 1 / 26 along the whole lift (model's contact constraints)
    assert np.max(np.abs(th - th[:, :1])) < 1e-7  # the four arms move together
    assert lam[0] + rob.params["lambda_C0"] == pytest.approx(0.15, abs=1e-12)
    assert lam[-1] + rob.params["lambda_C0"] == pytest.approx(0.52, abs=5e-4)  # eq 30 (dead point at pi/2)
    assert np.max(np.abs(traj.q[:, [rob.coordinate_index(c) for c in ("x", "y", "psi")]])) < 1e-9
    assert np.max(traj.residual) < 1e-7


def test_lifting_energy_balance(lifting_run):
    traj = lifting_run
    rob, ctrl = traj.stats["robot"], traj.stats["controller"]
    P = power(rob, traj, ctrl)
    work = np.trapezoid(P, traj.t) if hasattr(np, "trapezoid") else np.trapz(P, traj.t)
    gain = traj.energy[-1] - traj.energy[0]
    assert gain > 0.9 * 98.7 * 9.81 * 0.36  # about m g times the lift of most of the mass
    assert gain == pytest.approx(work, rel=1e-5)  # trapezoid rule on 121 samples (measured 1e-8)


def test_lift_configuration_dead_point_is_singular(robot):
    lr = mm.lift_robot(robot)
    q = mm.state(lr, lambda_C=0.37, **{f"theta_C{i}": np.pi / 2 for i in mm._ARMS})
    with pytest.raises(RobotDynError, match=r"rank A = 1\); expected exactly the mobility"):
        lr.reduced(q, np.zeros(lr.mobility))  # all four tip rows reduce to lambda_C' = 0: a change of mobility
    q = mm.state(lr, lambda_C=0.3699, **{f"theta_C{i}": np.arcsin(0.3699 / 0.44 - 1e-12 + 0.07 / 0.44) for i in mm._ARMS})
    assert lr.reduced(q, np.zeros(lr.mobility)).projection.condition > 30  # ill-conditioned near it


def test_climbing_balance_gravity_part_from_the_model(robot):
    for deg in (5.0, 20.0, 35.0):
        out = mm.climbing_balance(robot, np.radians(deg))
        m, g = pin.computeTotalMass(robot.model), robot.params["g"]
        assert out["mass"] == pytest.approx(98.7, rel=1e-12)
        assert out["F_gravity_model"] == pytest.approx(m * g * np.sin(np.radians(deg)), rel=1e-10)
        assert out["F_paper"] == pytest.approx(m * g * (np.sin(np.radians(deg)) + 0.1 * np.cos(np.radians(deg))))
    assert robot.model.gravity.linear == pytest.approx([0, 0, -9.81])  # restored
    with pytest.raises(InputError, match="slope"):
        mm.climbing_balance(robot, 2.0)


# ------------------------------------------------------------------------------------------------ control
def test_feedback_linearisation_gives_nudot_equal_u(robot):
    """Eqs 23-24: with tau = S^T M S (u - f2) the reduced model's accelerations are exactly u."""
    rng = np.random.default_rng(20)
    ctrl = mm.platform_controller(robot, "sinusoid")
    for _ in range(5):
        q = random_q(robot, rng)
        nu = rng.normal(size=robot.mobility)
        u, tau = ctrl.command(1.0, q, nu)
        assert robot.forward_dynamics(q, nu, tau) == pytest.approx(u, abs=1e-9 * (1 + np.max(np.abs(u))))


@pytest.mark.parametrize("name, t_end, bound", [("straight", 2.0, 1e-6), ("sinusoid", 2.0, 1e-6),
                                                ("orientation", 3.0, 0.06)])
def test_table4_tracking_is_bounded(robot, name, t_end, bound):
    from robotdyn.simulation.control import tracking_errors

    traj = mm.SCENARIOS[name].run(robot, t_end=t_end, n_out=31, rtol=1e-7, atol=1e-9, progress=False)
    err = tracking_errors(traj.stats["controller"], traj)
    assert err["max"] < bound
    assert err["rms"] >= err["mean"]
    if name == "orientation":  # started from rest: an initial error that decays (eq 25, critically damped)
        assert err["final"] < 0.5 * err["max"]
        assert np.max(np.hypot(traj.column("x"), traj.column("y"))) < 0.1  # C stays near the centre
    others = [c for c in mm.ACTUATED if c not in ("theta_R", "theta_L")]
    idx = [robot.coordinate_index(c) for c in others]
    assert np.max(np.abs(traj.q[:, idx] - traj.q[0, idx])) < 1e-6  # held joints held


def test_manipulation_reaches_the_target_in_range(robot):
    from robotdyn.simulation.control import tracking_errors

    traj = mm.SCENARIOS["manipulation"].run(robot, t_end=3.0, n_out=31, rtol=1e-7, atol=1e-9, progress=False)
    err = tracking_errors(traj.stats["controller"], traj)
    assert err["max"] < 1e-6
    for q in traj.q:
        robot.check_q(q)
    goal = mm.manipulation_goal(robot)
    assert goal.success and frame_pose(robot, goal.q, "E")[:3, 3] == pytest.approx(mm.MANIPULATION_TARGET, abs=1e-9)


def test_cli_simulate_and_compare(capsys):
    from robotdyn.cli import main

    assert main(["simulate", "mmr12_eod", "--scenario", "straight", "--t-end", "0.5", "--quiet", "--json"]) == 0
    import json

    data = json.loads(capsys.readouterr().out)
    assert data["final"]["y"] == pytest.approx(0.5 - mm.LOOK_AHEAD, abs=1e-6)  # P on y = t, C behind it by L
    assert data["final"]["x"] == pytest.approx(30.0, abs=1e-6)
    assert main(["compare", "mmr12_eod", "--json"]) == 0
    rows = {r["quantity"]: r for r in json.loads(capsys.readouterr().out)["rows"]}
    assert rows["eq 29 [3,3]"]["verdict"] == "differs"
    assert rows["eq 2 X_M[2,2] (as printed)"]["verdict"] == "differs"
    assert rows["eq 30 [3,4]"]["verdict"] == "reproduced"
    assert main(["simulate", "mmr12_eod", "--scenario", "nope", "--quiet"]) == 2


def test_point_task_jacobian_and_drift_by_finite_differences(robot):
    """y'' = J a + Jdot v for the look-ahead point, against the second difference of its position along the
    curve q(t) = q + v t + a t^2 / 2 (natural coordinates: q'' = a)."""
    from robotdyn.constraints.constraint import KinematicState
    from robotdyn.simulation.control import PointTask, hold

    task = PointTask("link3", hold([0.0, 0.0, 0.0]), offset=(0.1, -0.05, 0.2))
    rng = np.random.default_rng(30)
    for _ in range(5):
        q = random_q(robot, rng)
        q[robot.coordinate_index("theta1")] = np.clip(q[robot.coordinate_index("theta1")], 0.3, 2.8)
        q[robot.coordinate_index("lambda2")] = np.clip(q[robot.coordinate_index("lambda2")], 0.3, 1.2)
        v = rng.normal(size=robot.nq)
        a = rng.normal(size=robot.nq)
        kin = KinematicState(robot.model, robot.data, q, v)
        y, J, drift = task.evaluate(robot, kin)
        h = 1e-4

        def pos(t):
            qt = q + v * t + 0.5 * a * t * t
            k = KinematicState(robot.model, robot.data, qt, np.zeros(robot.nq))
            return task.evaluate(robot, k)[0]

        assert (pos(h) - pos(-h)) / (2 * h) == pytest.approx(J @ v, abs=1e-6)
        assert (pos(h) - 2 * y + pos(-h)) / h**2 == pytest.approx(J @ a + drift, abs=1e-4)
