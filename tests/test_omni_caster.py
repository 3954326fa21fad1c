"""Omni caster robot (Chung, Yi, Kim, Han): model from the URDF vs independent references.

References: the paper's closed forms transcribed in robotdyn.robots.omni_caster.paper (eqs 12-17, 43, 48-51, 60), a
derivation of the offset link's missing velocity terms, A S = 0, finite differences and energy balance.
"""

from __future__ import annotations

import numpy as np
import pytest

from robotdyn.errors import InputError, RobotDynError, SingularConstraintError
from robotdyn.robot import Robot
from robotdyn.robots.omni_caster import model as oc
from robotdyn.robots.omni_caster import paper as oc_paper
from robotdyn.robots.omni_caster import comparison as oc_cmp

TOL = 1e-10


@pytest.fixture(scope="module")
def robot():
    return Robot(oc.SPEC)


@pytest.fixture(scope="module")
def bare():
    return Robot(oc.SPEC, dict(oc.NO_WHEELS))


def _states(n, seed):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        phi = rng.uniform(-np.pi, np.pi, 3)
        pose = rng.uniform(-5, 5, 3)
        yield phi, pose, rng.normal(size=3)


def _q(robot, phi, pose):
    return oc.steering_configuration(robot, phi, psi=pose[2], x=pose[0], y=pose[1])


# ------------------------------------------------------------------------------------------ priority 1
def test_loads_with_mobility_three(robot):
    assert robot.mobility == 3
    assert robot.velocity_names == ["v_cx", "v_cy", "omega"]
    assert sorted(robot.coordinates) == sorted(["x", "y", "psi", "phi1", "phi2", "phi3", "theta1", "theta2", "theta3"])
    q = robot.neutral()
    robot.check_constraints(q, tol=1e-12)
    red = robot.reduced(q, np.zeros(3))
    assert red.projection.rows.size == 6  # 9 rows of rank 6: the three normal rows vanish on the plane
    assert np.linalg.matrix_rank(red.rows.A, tol=1e-9) == 6


def test_AS_zero_and_outputs_identity(robot):
    import pinocchio as pin

    fid = robot.description.frame_id("platform")
    for phi, pose, nu in _states(50, 1):
        q = _q(robot, phi, pose)
        red = robot.reduced(q, nu)
        assert np.abs(red.rows.A @ red.S).max() < 1e-13
        pin.computeJointJacobians(robot.model, robot.data, q)
        pin.updateFramePlacements(robot.model, robot.data)
        J = pin.getFrameJacobian(robot.model, robot.data, fid, pin.ReferenceFrame.LOCAL)[[0, 1, 5]]
        np.testing.assert_allclose(J @ red.S, np.eye(3), atol=1e-13)
        # body axes: the world velocity of C is R(psi) (v_cx, v_cy)
        v = red.v
        ix, iy = robot.coordinate_index("x"), robot.coordinate_index("y")
        c, s = np.cos(pose[2]), np.sin(pose[2])
        np.testing.assert_allclose([v[ix], v[iy]], [c * nu[0] - s * nu[1], s * nu[0] + c * nu[1]], atol=1e-13)


def test_inertia_matches_eq48_at_200_configurations(robot):
    worst = 0.0
    for phi, pose, _ in _states(200, 2):
        M = robot.reduced(_q(robot, phi, pose), np.zeros(3)).M
        worst = max(worst, np.abs(M - oc_paper.paper_inertia(robot.params, phi)).max())
    assert worst < TOL


def test_no_wheel_inertia_is_platform_diag(bare):
    p = bare.params
    expected = np.diag([p["m_pl"], p["m_pl"], p["m_pl"] * p["b"] ** 2 / 2])
    np.testing.assert_allclose(expected, np.diag([5.0, 5.0, 0.025]))  # the paper's printed no-wheel matrix
    for phi, pose, _ in _states(200, 3):
        M = bare.reduced(_q(bare, phi, pose), np.zeros(3)).M
        assert np.abs(M - expected).max() < TOL


def test_printed_with_wheel_matrix_not_reachable_with_table_parameters(robot):
    # trace of the translational block is independent of the steering angles (a sum of cos^2 + sin^2 per chain)
    traces = [np.trace(robot.reduced(_q(robot, phi, pose), np.zeros(3)).M[:2, :2]) for phi, pose, _ in _states(20, 4)]
    assert np.ptp(traces) < 1e-10
    printed = 5.4329 + 7.5379
    assert abs(traces[0] - printed) > 0.2  # 12.731 vs 12.971: no steering configuration reproduces it


def test_wrong_nu_length_is_an_error(robot):
    with pytest.raises(InputError):
        robot.reduced(robot.neutral(), np.zeros(2))
    with pytest.raises(RobotDynError):
        robot.check_nu([1, 2])


# ------------------------------------------------------------------------------------------ priority 2
def test_kinematic_matrices_eq12_to_17(robot):
    p = robot.params
    worst_inv, worst_fwd, printed16 = 0.0, 0.0, []
    for phi, pose, _ in _states(50, 5):
        G = oc_cmp.model_chain_jacobians(robot, _q(robot, phi, pose))
        for i in oc.CHAINS:
            worst_inv = max(worst_inv, np.abs(G[i] - oc_paper.paper_inverse(p, i, phi[i - 1])).max())
            worst_fwd = max(worst_fwd, np.abs(np.linalg.inv(G[i]) - oc_paper.paper_forward(p, i, phi[i - 1])).max())
        diff = np.abs(G[2] - oc_paper.paper_inverse(p, 2, phi[1], corrected=False))
        printed16.append(diff)
    assert worst_inv < 1e-9  # entries are O(1/r) = 40: relative 1e-11
    assert worst_fwd < TOL
    # eq (16) as printed differs in entry (1, 3) only, by l r cos(phi2) / (d r) = l cos(phi2) / d
    d = np.array(printed16)
    mask = np.zeros((3, 3), bool)
    mask[0, 2] = True
    assert d[:, ~mask].max() < 1e-9
    assert d[:, 0, 2].max() > 1.0


def test_bias_matches_eq49_plus_offset_link_terms(robot):
    worst = 0.0
    for phi, pose, nu in _states(100, 6):
        h = robot.reduced(_q(robot, phi, pose), nu).h
        ref = oc_paper.paper_bias(robot.params, phi, nu) + oc_cmp.offset_link_correction(robot.params, phi, nu)
        worst = max(worst, np.abs(h - ref).max())
    assert worst < TOL


def test_bias_matches_eq49_exactly_when_link_mass_centre_on_wheel_axis():
    robot = Robot(oc.SPEC, {"p": 0.0})
    for phi, pose, nu in _states(50, 7):
        h = robot.reduced(_q(robot, phi, pose), nu).h
        assert np.abs(h - oc_paper.paper_bias(robot.params, phi, nu)).max() < TOL
    # and with the default p the omitted terms are not negligible
    robot = Robot(oc.SPEC)
    phi, pose, nu = next(_states(1, 8))
    h = robot.reduced(_q(robot, phi, pose), nu).h
    assert np.abs(h - oc_paper.paper_bias(robot.params, phi, nu)).max() > 1e-4


def test_reduced_coriolis_consistent(robot):
    eps = 1e-6
    for phi, pose, nu in _states(20, 9):
        q = _q(robot, phi, pose)
        red = robot.reduced(q, nu, coriolis=True)
        np.testing.assert_allclose(red.C @ nu, red.h - red.g, atol=1e-12)
        qdot = red.v
        Mdot = (robot.reduced(q + eps * qdot, nu).M - robot.reduced(q - eps * qdot, nu).M) / (2 * eps)
        N = Mdot - 2 * red.C
        # central differences of M_r = S^T M S with |S| ~ 1e3 (wheel rates per unit omega): noise ~1e-7
        np.testing.assert_allclose(N + N.T, 0.0, atol=5e-6)
        assert np.abs(N).max() > 1e-3  # not trivially zero


# ------------------------------------------------------------------------------------------ priority 3
@pytest.fixture(scope="module")
def noc():
    return Robot(oc.noc_spec())


def test_noc_singular_at_fig16_configuration(robot, noc):
    phi = [0.0, 0.0, 0.0]  # Fig. 16: theta1' and theta2' rows coincide (both links along i, A1 and A2 at y = -a)
    assert abs(np.linalg.det(oc_paper.paper_noc_jacobians(robot.params, phi)[0])) < 1e-15
    with pytest.raises(SingularConstraintError) as err:
        noc.reduced(oc.steering_configuration(noc, phi), np.zeros(3))
    assert "singular" in str(err.value) and "\n" not in str(err.value)
    rep = oc.noc_report(robot, noc, phi)
    assert rep["noc_M"] is None and rep["noc_error"]
    assert np.all(np.isfinite(rep["op_M"])) and rep["op_condition"] < 1e3
    np.testing.assert_allclose(rep["op_M"], oc_paper.paper_inertia(robot.params, phi), atol=TOL)


def test_noc_inertia_blows_up_near_singularity_operational_stays_finite(robot, noc):
    p = robot.params
    prev = None
    for eps in (1e-1, 1e-2, 1e-3, 1e-4):
        rep = oc.noc_report(robot, noc, [eps, 0.0, 0.0])
        K = oc_paper.paper_noc_map(p, [eps, 0.0, 0.0])
        Kinv = np.linalg.inv(K)
        ref = Kinv.T @ rep["op_M"] @ Kinv  # same kinetic energy in the NOC velocities
        assert np.abs(rep["noc_M"] - ref).max() < 1e-9 * np.abs(ref).max()
        big = np.abs(rep["noc_M"]).max()
        if prev is not None:
            assert 50 < big / prev < 200  # ~1/eps^2
        prev = big
        assert rep["op_condition"] < 1e3


def test_noc_singular_set_matches_paper_det_Jp(robot, noc):
    from scipy.optimize import brentq

    rng = np.random.default_rng(11)
    p = robot.params
    found = 0
    while found < 5:
        phi12 = rng.uniform(-np.pi, np.pi, 2)
        f = lambda t: np.linalg.det(oc_paper.paper_noc_map(p, [*phi12, t]))
        grid = np.linspace(-np.pi, np.pi, 73)
        vals = [f(t) for t in grid]
        for t0, t1, f0, f1 in zip(grid[:-1], grid[1:], vals[:-1], vals[1:]):
            if f0 * f1 < 0:
                t = brentq(f, t0, t1, xtol=1e-15)
                phi = [*phi12, t]
                assert abs(np.linalg.det(oc_paper.paper_noc_jacobians(p, phi)[0])) < 1e-12
                with pytest.raises(SingularConstraintError):
                    noc.reduced(oc.steering_configuration(noc, phi), np.zeros(3))
                rep = oc.noc_report(robot, noc, [*phi12, t + 0.2])  # away from it: both fine
                assert rep["noc_M"] is not None
                found += 1
                break


def test_noc_dependent_rates_satisfy_eq_A7(robot):
    p = robot.params
    for phi, pose, nu in _states(20, 12):
        Jp, Ja = oc_paper.paper_noc_jacobians(p, phi)
        G = oc_cmp.model_chain_jacobians(robot, _q(robot, phi, pose))
        rates = {i: G[i] @ nu for i in oc.CHAINS}
        dep = np.array([rates[1][0], rates[1][2], rates[2][0], rates[2][2], rates[3][0], rates[3][1]])
        ind = np.array([rates[1][1], rates[2][1], rates[3][2]])
        assert np.abs(Jp @ dep - Ja @ ind).max() < 1e-9


# ------------------------------------------------------------------------------------------ priority 4
def test_beta_profile_is_eq61():
    T = 60.0
    a3, a4, a5 = 20 * np.pi / 60**3, -30 * np.pi / 60**4, 12 * np.pi / 60**5  # the paper's coefficients
    t = np.linspace(0, T, 37)
    b, bd, bdd = oc.beta_profile(t, T)
    np.testing.assert_allclose(b, a3 * t**3 + a4 * t**4 + a5 * t**5, atol=1e-13)
    np.testing.assert_allclose(bd, 3 * a3 * t**2 + 4 * a4 * t**3 + 5 * a5 * t**4, atol=1e-13)
    np.testing.assert_allclose(bdd, 6 * a3 * t + 12 * a4 * t**2 + 20 * a5 * t**3, atol=1e-13)
    assert abs(b[-1] - 2 * np.pi) < 1e-12 and abs(bd[-1]) < 1e-12 and abs(bd[0]) < 1e-15


@pytest.mark.parametrize("kind, heading", [("circle", None), ("ellipse", "tangent"), ("ellipse", "fixed")])
def test_path_twist_is_body_frame_derivative_of_pose(kind, heading):
    t = np.linspace(0.5, oc.CIRCLE["T"] - 0.5 if kind == "circle" else oc.ELLIPSE["T"] - 0.5, 23)
    dt = 1e-5
    par = {"heading": heading} if heading else None
    st, sp, sm = (oc.path_state(kind, x, par) for x in (t, t + dt, t - dt))
    dpose = (sp["pose"] - sm["pose"]) / (2 * dt)
    psi = st["pose"][:, 2]
    vb = np.stack([np.cos(psi) * dpose[:, 0] + np.sin(psi) * dpose[:, 1],
                   -np.sin(psi) * dpose[:, 0] + np.cos(psi) * dpose[:, 1], dpose[:, 2]], axis=1)
    np.testing.assert_allclose(st["nu"], vb, atol=1e-8)
    np.testing.assert_allclose(st["nudot"], (sp["nu"] - sm["nu"]) / (2 * dt), atol=1e-8)
    if heading != "fixed":
        assert np.abs(st["nu"][:, 0]).max() < 1e-15  # moving along +j
    np.testing.assert_allclose(st["pose"][0], 0.0, atol=1e-3)  # starts near the origin (t = 0.5 s)


def test_steady_steering_zeroes_the_model_steering_rates(robot):
    rng = np.random.default_rng(13)
    idx = [robot.coordinate_index(f"phi{i}") for i in oc.CHAINS]
    for _ in range(10):
        u = rng.normal(size=3) * [1, 1, 0.5]
        for trailing in (True, False):
            phi = oc.steady_steering(robot.params, u, trailing)
            v = robot.reduced(oc.steering_configuration(robot, phi), u).v
            assert np.abs(v[idx]).max() < 1e-10


@pytest.mark.parametrize("kind, t_end, par", [("circle", 12.0, None), ("ellipse", 8.0, None),
                                              ("ellipse", 8.0, {"heading": "fixed"})])
def test_inverse_dynamics_power_balance(robot, kind, t_end, par):
    pl = oc.plan(robot, kind, n=25, t_end=t_end, rtol=1e-10, params=par)
    ix = [robot.coordinate_index(c) for c in ("x", "y", "psi")]
    assert np.abs(pl["q"][:, ix] - pl["pose"]).max() < 1e-6  # integrated twist reproduces the prescribed path
    F = oc.operational_forces(robot, pl)
    power = np.einsum("ij,ij->i", F, pl["nu"])
    dt = 1e-3
    for k, t in enumerate(pl["t"][1:-1], start=1):
        ep = oc.kinetic_energy(robot, pl["sol"].sol(t + dt), oc.path_state(kind, t + dt, par)["nu"])
        em = oc.kinetic_energy(robot, pl["sol"].sol(t - dt), oc.path_state(kind, t - dt, par)["nu"])
        assert abs((ep - em) / (2 * dt) - power[k]) < 1e-6 * np.abs(power).max() + 1e-9
    assert np.abs(power).max() > 1e-3


def test_circle_scenario_feedforward_follows_plan(robot):
    from robotdyn.simulation.engine import power

    sc = oc.SCENARIOS["circle"]
    tr = sc.run(robot, t_end=4.0, n_out=9, progress=False)
    st = oc.path_state("circle", tr.t)
    assert np.abs(tr.nu - st["nu"]).max() < 1e-7
    P = power(robot, tr, sc.torque_law(robot))
    assert np.all(np.diff(tr.energy) > 0) and P.max() > 0


# ------------------------------------------------------------------------------------------ priority 5-6
def test_impact_matches_eq60_and_restitution(robot):
    from robotdyn.contact.impulse import impact

    rng = np.random.default_rng(21)
    for phi, pose, nu in _states(20, 22):
        M = robot.reduced(_q(robot, phi, pose), np.zeros(3)).M
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        if n @ nu >= 0:
            nu = -nu
        e = rng.uniform(0, 1)
        res = impact(M, n, nu, e)
        assert abs(res.magnitude - oc_paper.paper_impulse(M, n, nu, e)) < 1e-12 * abs(res.magnitude)
        assert abs(res.normal_after + e * res.normal_before) < 1e-12  # Newton's law on the normal velocity
        # momentum: M (nu+ - nu-) = F n; tangential (M-orthogonal) part unchanged: kinetic energy loss >= 0
        np.testing.assert_allclose(M @ res.delta_nu, res.magnitude * n, atol=1e-12)
        assert 0.5 * res.nu_after @ M @ res.nu_after <= 0.5 * nu @ M @ nu + 1e-12


def test_impact_bad_input():
    from robotdyn.contact.impulse import impact

    M = np.eye(3)
    for args in [(M, [0, 0, 0], [-1, 0, 0], 0.8), (M, [1, 0, 0], [-1, 0, 0], 1.5), (M, [1, 0], [-1, 0, 0], 0.5),
                 (M, [1, 0, 0], [1, 0, 0], 0.5), (M, [1, 0, 0], [np.nan, 0, 0], 0.5),
                 (np.zeros((3, 3)), [1, 0, 0], [-1, 0, 0], 0.5)]:
        with pytest.raises(InputError):
            impact(*args)


def test_impulse_ellipses(robot, bare):
    curves = oc.impulse_ellipses(robot, samples=721)
    assert set(curves) == {"fig16", "fig17", "fig18", "fig19"}
    for name, (ang, mag) in curves.items():
        assert np.all(np.isfinite(mag)) and mag.min() > 0
    # Fig. 18: uniform; Figs. 16, 17: the largest impulse along the wheels' rolling direction
    _, mag = curves["fig18"]
    assert mag.max() / mag.min() - 1 < 1e-7
    assert curves["fig16"][1].max() / curves["fig16"][1].min() > 1.3
    for name, roll in (("fig16", 0.0), ("fig17", 135.0)):
        ang, mag = curves[name]
        assert abs(np.degrees(ang[np.argmax(mag)]) % 180 - roll) < 0.5
    # without wheel dynamics always a circle of radius (1 + e) m_pl
    for ang, mag in oc.impulse_ellipses(bare).values():
        np.testing.assert_allclose(mag, 1.8 * 5.0, rtol=1e-12)


def test_cli_impulse(capsys):
    import json

    from robotdyn.cli.commands import main

    assert main(["impulse", "omni_caster", "--q", *["0"] * 9, "--direction", "-1", "0", "0", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    robot = Robot(oc.SPEC)
    M = robot.reduced(robot.neutral(), np.zeros(3)).M
    assert abs(out["impulse"] - oc_paper.paper_impulse(M, [-1, 0, 0], [1, 0, 0], 0.8)) < 1e-12
    assert main(["impulse", "omni_caster", "--q", *["0"] * 9, "--direction", "1", "0"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("robotdyn: error:") and err.count("\n") == 1
    assert main(["impulse", "omni_caster", "--q", *["0"] * 9, "--direction", "1", "0", "0", "--e", "-1"]) == 2
    assert main(["impulse", "omni_caster", "--q", *["0"] * 9, "--direction", "1", "0", "0", "--v", "1", "0", "0"]) == 2


def test_cli_dump_and_compare(capsys):
    from robotdyn.cli.commands import main

    assert main(["dump", "omni_caster", "--q", *["0.3"] * 9, "--v", "0.1", "0.2", "0.3"]) == 0
    assert "v_cx" in capsys.readouterr().out
    assert main(["compare", "omni_caster"]) == 0
    table = capsys.readouterr().out
    assert "eq 48" in table and "reproduced" in table


def test_compare_verdicts(robot):
    cmp = oc_cmp.compare(robot, states=20)
    verdict = {r.quantity.split(":")[0]: r.verdict for r in cmp.rows}
    assert verdict["eq 48"] == "reproduced"
    assert verdict["eq 16 as printed"] == "differs"
    assert verdict["eq 49 + derived offset-link terms (worst deviation)"] == "reproduced"
    assert verdict["sec 5 printed with-wheel I_uu*"] == "differs"
    assert verdict["sec 5 with-wheel I_uu* as a steady turn, steering term Table 2's"] == "differs"
    assert verdict["sec 5 with-wheel I_uu* as a steady turn, wheel and steering terms fitted"] == "reproduced"


def test_circle_wheel_mass_sweep_affects_y_and_moment_not_x(robot):
    # sec 5, Figs. 10-12: with the wheels rolling along j, their lateral (x) inertia is taken by the ground
    pl = oc.plan(robot, "circle", n=13, t_end=30.0, rtol=1e-9)
    forces = [oc.operational_forces(Robot(oc.SPEC, oc.wheel_mass_params(total, 5.0)), pl) for total in (0, 1.5, 3)]
    peaks = np.array([np.abs(F).max(axis=0) for F in forces])
    assert abs(peaks[2, 0] / peaks[0, 0] - 1) < 1e-6
    assert peaks[2, 1] / peaks[0, 1] > 1.5 and peaks[2, 2] / peaks[0, 2] > 2.0
    # linear in the wheel mass (the model is linear in the inertial parameters)
    np.testing.assert_allclose(forces[1], 0.5 * (forces[0] + forces[2]), atol=1e-12)


def test_acceleration_offset_matches_finite_differences(robot):
    # w = S' nu along q' = S nu: independent of Pinocchio's Jacobian time variation and of the wheel drift terms
    eps = 1e-6
    for phi, pose, nu in _states(10, 31):
        q = _q(robot, phi, pose)
        red = robot.reduced(q, nu, coriolis=True)
        v = red.v
        fd = (robot.reduced(q + eps * v, nu).v - robot.reduced(q - eps * v, nu).v) / (2 * eps)
        scale = np.abs(fd).max()
        assert np.abs(red.w - fd).max() < 1e-7 * scale
        assert np.abs(red.Sdot @ nu - fd).max() < 1e-7 * scale
