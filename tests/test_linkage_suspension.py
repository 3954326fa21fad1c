"""Six-wheel robot with linkage suspension (Chen et al.): model, posture on terrain, paper comparison, dynamics.

Independent references used here: closed-form geometry of the nominal posture, the rim of each wheel sampled and
minimised against the terrain (not the contact code), frame placements read straight from Pinocchio for the loop
closures (not the LoopClosure code), A S = 0, finite differences along a path, and energy balance.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from scipy.optimize import minimize_scalar

from robotdyn.constraints.constraint import KinematicState
from robotdyn.errors import ConstraintError, RobotDynError
from robotdyn.constraints.posture import set_terrain, solve_posture
from robotdyn.reduction.projection import project
from robotdyn.robot import Robot
from robotdyn.robots.linkage_suspension import model as ls
from robotdyn.robots.linkage_suspension import comparison as ls_cmp
from robotdyn.constraints.terrain import BumpTerrain, FlatTerrain, FunctionTerrain, RampTerrain, SineTerrain


@pytest.fixture(scope="module")
def robot():
    return Robot(ls.SPEC)


def _random_terrain(rng, kind):
    if kind == 0:
        return SineTerrain(rng.uniform(0, 0.03), rng.uniform(-4, 4), rng.uniform(-4, 4), rng.uniform(0, 6))
    if kind == 1:
        return RampTerrain(rng.uniform(-0.3, 0.3), rng.uniform(-np.pi, np.pi))
    return BumpTerrain(rng.uniform(-0.06, 0.06), rng.uniform(-0.4, 0.4), rng.uniform(0.1, 0.3))


def _rim_gap(robot, q, terrain, frame, radius):
    """Smallest height of the wheel's rim above the terrain, measured along z (sampled + refined rim angle)."""
    pin.forwardKinematics(robot.model, robot.data, q)
    pin.updateFramePlacements(robot.model, robot.data)
    M = robot.data.oMf[robot.model.getFrameId(frame)]
    c, e1, e3 = M.translation, M.rotation[:, 0], M.rotation[:, 2]  # wheel plane spanned by the link's x and z

    def gap(a):
        p = c + radius * (np.cos(a) * e1 + np.sin(a) * e3)
        return p[2] - terrain.height(p[0], p[1])

    grid = np.linspace(0, 2 * np.pi, 721)
    a0 = grid[np.argmin([gap(a) for a in grid])]
    res = minimize_scalar(gap, bounds=(a0 - 0.01, a0 + 0.01), method="bounded", options={"xatol": 1e-12})
    return res.fun


def _closure_errors(robot, q):
    """Loop-closure errors straight from the frame placements (independent of robotdyn.constraints.loop_closure)."""
    pin.forwardKinematics(robot.model, robot.data, q)
    pin.updateFramePlacements(robot.model, robot.data)
    oMf = robot.data.oMf
    fid = robot.model.getFrameId
    out = []
    for side in "RL":
        g, b = oMf[fid(f"guide_{side}")], oMf[fid(f"block_{side}")]
        d = b.translation - g.translation
        axis = g.rotation[:, 0]
        out.append(np.linalg.norm(d - (d @ axis) * axis))  # block off the guide line
        out.append(np.linalg.norm(g.rotation - b.rotation))  # block turned relative to the guide
        out.append(np.linalg.norm(oMf[fid(f"ball_{side}")].translation - oMf[fid(f"rod_{side}_end")].translation))
    return np.array(out)


# ------------------------------------------------------------------------------------------ priority 1
def test_model_loads_with_documented_dimensions(robot):
    assert robot.nq == 25
    assert robot.mobility == 2
    assert robot.velocity_names == ["phi2_dot", "phi5_dot"]
    for name in ("theta1", "theta2", "beta1", "beta2", "z", "pitch", "roll", "psi"):
        robot.coordinate_index(name)
    kinds = [type(c).__name__ for c in robot.constraints]
    assert kinds.count("OmniWheel") == 4 and kinds.count("RollingWheel") == 2 and kinds.count("LoopClosure") == 4


def test_flat_posture_matches_nominal_geometry(robot):
    p = robot.params
    th0 = p["theta0"]
    guess = robot.neutral()
    rng = np.random.default_rng(3)
    free = [i for i, c in enumerate(robot.coordinates) if c not in ("x", "y", "yaw") and not c.startswith("phi")]
    guess[free] += rng.uniform(-0.02, 0.02, len(free))
    post = solve_posture(robot, {"x": 0.4, "y": -0.2, "yaw": 0.7}, guess)
    q = dict(zip(robot.coordinates, post.q))
    assert post.residual <= 1e-10
    # closed form: all wheel centres at -(d1 + a5 cos theta0) in R, so z = r + d1 + a5 cos theta0
    assert q["z"] == pytest.approx(p["r"] + p["d1"] + p["a5"] * np.cos(th0), abs=1e-10)
    for name, value in (("pitch", 0), ("roll", 0), ("theta1", th0), ("theta2", th0), ("beta1", th0 + np.pi / 2),
                        ("beta2", th0 + np.pi / 2), ("gamma1", 0), ("gamma2", 0), ("psi", 0)):
        assert q[name] == pytest.approx(value, abs=1e-9), name
    assert (q["x"], q["y"], q["yaw"]) == (0.4, -0.2, 0.7)


def test_posture_on_random_terrains_closes_every_loop_and_touches(robot):
    rng = np.random.default_rng(0)
    worst_res, worst_rim, worst_loop, worst_AS, solved = 0.0, 0.0, 0.0, 0.0, 0
    mobilities = set()
    try:
        for k in range(210):
            terrain = _random_terrain(rng, k % 3)
            set_terrain(robot, terrain)
            x, y, yaw = rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-np.pi, np.pi)
            guess = robot.neutral()
            guess[robot.coordinate_index("z")] += terrain.height(x, y)
            post = solve_posture(robot, {"x": x, "y": y, "yaw": yaw}, guess)
            solved += 1
            worst_res = max(worst_res, float(np.max(np.abs(robot.constraint_residual(post.q)))))
            if k % 7 == 0:  # the independent checks are slower: every 7th sample
                for i in range(1, 7):
                    worst_rim = max(worst_rim, abs(_rim_gap(robot, post.q, terrain, f"wheel{i}", robot.params["r"])))
                worst_loop = max(worst_loop, float(np.max(_closure_errors(robot, post.q))))
                # mobility is 2 on laterally symmetric ground and 1 where the middle wheels are not coaxial
                # (beta1 != beta2): A S = 0 with the automatic, rank-revealing choice of independent velocities
                rows = robot.constraint_rows(KinematicState(robot.model, robot.data, post.q, np.zeros(robot.nq)))
                proj = project(rows.A)
                mobilities.add(proj.mobility)
                worst_AS = max(worst_AS, float(np.max(np.abs(rows.A @ proj.S))))
    finally:
        set_terrain(robot, FlatTerrain())
    assert solved == 210
    assert worst_res <= 1e-10  # typically ~1e-13: the solver aims at 1e-3 tol
    assert worst_rim <= 1e-9  # every wheel's lowest rim point is on the surface (z-gap, independent sampling)
    assert worst_loop <= 1e-9
    assert worst_AS <= 1e-12
    assert mobilities <= {1, 2}


# ------------------------------------------------------------------------------------------ priority 2
def _plateau(h, x0, x1, y0, y1, w):
    """A smooth rectangular plateau of height h (product of tanh steps), with gradient and Hessian."""

    def s(t, a, b):
        ta, tb = np.tanh((t - a) / w), np.tanh((t - b) / w)
        return (0.5 * (ta - tb), 0.5 * (tb**2 - ta**2) / w, (-ta * (1 - ta**2) + tb * (1 - tb**2)) / w**2)

    def f(x, y):
        return h * s(x, x0, x1)[0] * s(y, y0, y1)[0]

    def grad(x, y):
        sx, sy = s(x, x0, x1), s(y, y0, y1)
        return h * np.array([sx[1] * sy[0], sx[0] * sy[1]])

    def hess(x, y):
        sx, sy = s(x, x0, x1), s(y, y0, y1)
        return h * np.array([[sx[2] * sy[0], sx[1] * sy[1]], [sx[1] * sy[1], sx[0] * sy[2]]])

    return FunctionTerrain(f, grad, hess)


def test_plateau_under_one_wheel_within_travel_is_solved(robot):
    terrain = _plateau(0.2, 0.22, 0.8, -0.8, -0.14, 0.02)  # 0.2 m block under the front-right wheel only
    set_terrain(robot, terrain)
    try:
        post = solve_posture(robot, {"x": 0.0, "y": 0.0, "yaw": 0.0})
        for i in range(1, 7):
            assert abs(_rim_gap(robot, post.q, terrain, f"wheel{i}", robot.params["r"])) <= 1e-9
    finally:
        set_terrain(robot, FlatTerrain())
    q = dict(zip(robot.coordinates, post.q))
    assert q["theta1"] < q["theta2"]  # the differential: the right rocker lifts its front, the left one drops it


def test_wall_taller_than_the_suspension_reach_is_an_error(robot):
    # A 1 m wall under the front-right wheel: its centre would have to be 1 m above the middle wheel's, but the
    # chain front wheel -> F -> D -> B2 -> middle wheel is at most 0.266 + 0.071 + 0.2 + 0.123 = 0.66 m long.
    set_terrain(robot, _plateau(1.0, 0.22, 0.8, -0.8, -0.14, 0.02))
    try:
        with pytest.raises(ConstraintError, match="no posture found") as err:
            solve_posture(robot, {"x": 0.0, "y": 0.0, "yaw": 0.0})
    finally:
        set_terrain(robot, FlatTerrain())
    assert "\n" not in str(err.value)


def test_posture_bad_input_is_one_line_error(robot):
    with pytest.raises(RobotDynError, match="unknown coordinate"):
        solve_posture(robot, {"heading": 0.0})
    with pytest.raises(RobotDynError, match="finite"):
        solve_posture(robot, {"x": float("nan")})


# ------------------------------------------------------------------------------------------ priority 3, 4
@pytest.fixture(scope="module")
def comparison(robot):
    return {r.quantity: r for r in ls_cmp.compare(robot).rows}


def _verdicts(comparison, prefix):
    return {k: r.verdict for k, r in comparison.items() if k.startswith(prefix)}


def test_urdf_realises_table1(comparison):
    (row,) = [r for k, r in comparison.items() if k.startswith("eq 3")]
    assert row.verdict == "reproduced" and row.model <= 1e-12


def test_eq4_entries_classified(comparison):
    printed = {k.split()[2]: r.verdict for k, r in comparison.items() if k.startswith("eq 4") and "as printed" in k}
    assert printed == {"T11": "reproduced", "T12": "reproduced", "T13": "differs", "T14": "reproduced",
                       "T21": "differs", "T22": "reproduced", "T23": "reproduced", "T24": "reproduced",
                       "T31": "reproduced", "T32": "reproduced", "T33": "differs", "T34": "differs"}
    readings = _verdicts(comparison, "eq 4: T")
    readings = {k: v for k, v in readings.items() if "read with" in k}
    assert len(readings) == 4 and set(readings.values()) == {"reproduced"}


def test_eq10_wheel_centre_velocity(comparison):
    rows = _verdicts(comparison, "eq 10")
    for k, v in rows.items():
        if "body terms" in k or "Table 1 axes" in k or "row 2" in k:
            assert v == "reproduced", k
        else:  # rows 1 and 3: printed theta1', beta1' coefficients and hence the whole left-hand side
            assert v == "differs", k


def test_eq9_rolling(comparison):
    rows = _verdicts(comparison, "eq 9")
    assert len(rows) == 10
    for k, v in rows.items():
        assert v == ("reproduced" if "absolute rate" in k else "differs"), k


def test_section3_profile_and_travel(comparison, robot):
    from scipy.integrate import quad

    # independent: r times the integral of the wheel speed (quadrature of the profile, piecewise)
    t = ls.PROFILE
    angle = sum(quad(lambda s: ls.wheel_speed(s)[0], a, b)[0] for a, b in zip((0.0,) + t[:-1], t))
    assert angle == pytest.approx(np.radians(300) * 3.0, rel=1e-10)
    row = comparison["sec 3.1: travel distance [m] (0.52 -> -1.48 m, Fig. 7)"]
    assert row.model == pytest.approx(robot.params["r"] * angle, rel=1e-6)
    assert row.verdict == "differs"  # 2.199 m, not 2 m
    assert ls.profile_distance(0.73) == pytest.approx(2.19)
    assert comparison["sec 3.1: peak centroid speed [m/s] (Fig. 8)"].model == pytest.approx(
        robot.params["r"] * np.radians(300), rel=1e-6)
    assert comparison["sec 3.2: pivot-steering turns (two circles, Fig. 12)"].model == pytest.approx(
        robot.params["r"] * angle / robot.params["d5"] / (2 * np.pi), rel=1e-6)


# ------------------------------------------------------------------------------------------ priority 5
@pytest.fixture(scope="module")
def bump_robot():
    rob = Robot(ls.SPEC)
    set_terrain(rob, BumpTerrain(0.05, 0.2, 0.15))
    return rob


def test_reduced_dynamics_on_the_bump(bump_robot):
    rob = bump_robot
    q = solve_posture(rob, {"x": 0.1, "y": 0.0, "yaw": 0.0}).q
    # straight motion: a turn would break the left/right symmetry of the posture on this x-only bump, and there
    # (beta1 != beta2) the non-coaxial middle wheels leave mobility 1 (see the errata)
    nu = np.array([2.5, 2.5])
    red = rob.reduced(q, nu, coriolis=True)
    assert np.max(np.abs(red.rows.A @ red.S)) <= 1e-12
    assert np.allclose(red.M, red.M.T, atol=1e-12) and np.min(np.linalg.eigvalsh(red.M)) > 0
    # C_r nu + g_r is the bias h
    assert np.allclose(red.C @ nu + red.g, red.h, atol=1e-10)
    # g_r = dV/d(eps) along each admissible direction S e_k (central differences of Pinocchio's potential energy)
    eps = 1e-5
    for k in range(2):
        vp = pin.computePotentialEnergy(rob.model, rob.data, q + eps * red.S[:, k])
        vm = pin.computePotentialEnergy(rob.model, rob.data, q - eps * red.S[:, k])
        assert (vp - vm) / (2 * eps) == pytest.approx(red.g[k], abs=1e-6)
    # dM_r/dt - 2 C_r is skew-symmetric (dM_r/dt by central differences along q' = v)
    h = 1e-6
    Mp = rob.reduced(q + h * red.v, nu).M
    Mm = rob.reduced(q - h * red.v, nu).M
    N = (Mp - Mm) / (2 * h) - 2 * red.C
    assert np.max(np.abs(N + N.T)) <= 1e-6 * max(1.0, np.max(np.abs(red.C)))


def test_energy_conserved_torque_free_on_a_ramp():
    from robotdyn.simulation import simulate

    rob = Robot(ls.SPEC)
    set_terrain(rob, RampTerrain(0.15, 0.6))  # slope across the robot's heading: it turns downhill
    q0 = solve_posture(rob, {"x": 0.0, "y": 0.0, "yaw": 0.0}).q
    traj = simulate(rob, 1.0, q0, np.array([2.0, 3.0]), None, n_out=21, rtol=1e-10, atol=1e-12, progress=False)
    assert abs(traj.q[-1, rob.coordinate_index("yaw")]) > 0.1  # a non-trivial motion
    assert np.ptp(traj.energy) <= 1e-7 * abs(traj.energy[0])
    assert np.max(traj.residual) <= 1e-9


def test_drift_term_matches_finite_differences_along_a_bump_run(bump_robot):
    """A a + Adot v = 0 with a from central differences of v = S nu along a simulated torque-free run:
    the error must fall as h^2 (ratio 4 per halving), i.e. vanish in the limit."""
    from robotdyn.simulation import simulate

    rob = bump_robot
    q0 = solve_posture(rob, {"x": -0.1, "y": 0.0, "yaw": 0.0}).q
    traj = simulate(rob, 0.2, q0, np.array([3.0, 3.0]), None, n_out=201, rtol=1e-11, atol=1e-13, progress=False)
    assert np.ptp(traj.energy) <= 1e-9 * abs(traj.energy[0])  # torque-free over the bump
    dt = traj.t[1] - traj.t[0]
    V = np.array([rob.reduced(q, nu).v for q, nu in zip(traj.q, traj.nu)])
    errors = {}
    for step in (1, 2, 4):
        worst, scale = 0.0, 0.0
        for i in range(8, len(traj.t) - 8, 8):
            a = (V[i + step] - V[i - step]) / (2 * step * dt)
            rows = rob.constraint_rows(KinematicState(rob.model, rob.data, traj.q[i], V[i]))
            worst = max(worst, float(np.max(np.abs(rows.A @ a + rows.Adot @ V[i]))))
            scale = max(scale, float(np.max(np.abs(rows.Adot @ V[i]))))
        errors[step] = worst
    assert scale > 0.05  # the drift term is not trivially zero on the bump
    assert errors[1] <= 1e-5 * scale
    assert errors[2] / errors[1] == pytest.approx(4.0, rel=0.05)
    assert errors[4] / errors[2] == pytest.approx(4.0, rel=0.05)


def test_wheel_torques_over_the_bump_energy_balance(bump_robot):
    from robotdyn.simulation import power, simulate

    rob = bump_robot
    q0 = solve_posture(rob, {"x": -0.1, "y": 0.0, "yaw": 0.0}).q

    def tau(t, q, nu):
        return np.array([0.5, 0.8, 0.5, 0.5, 0.8, 0.5])

    traj = simulate(rob, 0.3, q0, np.array([3.0, 3.0]), tau, n_out=301, rtol=1e-10, atol=1e-12, progress=False)
    P = power(rob, traj, tau)
    work = np.concatenate([[0.0], np.cumsum(0.5 * (P[1:] + P[:-1]) * np.diff(traj.t))])
    assert work[-1] > 1.0
    assert np.max(np.abs(traj.energy - traj.energy[0] - work)) <= 1e-6 * work[-1]
    assert np.max(traj.residual) <= 1e-9


# ------------------------------------------------------------------------------------------ CLI
def test_cli_posture_dump_and_errors(capsys):
    import json

    from robotdyn.cli import main

    assert main(["linkage-posture", "--terrain", "bump", "--x", "0.1", "--v", "2", "2", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["residual"] <= 1e-10 and out["mobility"] == 2
    M = np.array(out["M"])
    assert np.allclose(M, M.T) and np.all(np.linalg.eigvalsh(M) > 0)
    assert main(["linkage-posture", "--terrain", "nope"]) == 2
    assert "unknown terrain" in capsys.readouterr().err
    assert main(["dump", "linkage_suspension", "--q", *map(str, Robot(ls.SPEC).neutral()), "--v", "1", "1"]) == 0
    assert "minimal coordinates: phi2_dot, phi5_dot" in capsys.readouterr().out
    assert main(["simulate", "linkage_suspension", "--scenario", "ramp_free", "--t-end", "0.1", "--quiet",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert abs(out["energy_end"] - out["energy_start"]) <= 1e-7 * out["energy_start"]


def test_suspension_keeps_six_contacts_where_a_rigid_chassis_lifts_wheels(robot):
    set_terrain(robot, ls.side_bump())
    try:
        post = solve_posture(robot, {"x": 0.5, "y": 0.0, "yaw": 0.0})
        rigid = ls.rigid_chassis_posture(robot, 0.5)
        gaps_susp, gaps_rigid = ls.contact_gaps(robot, post.q), ls.contact_gaps(robot, rigid)
    finally:
        set_terrain(robot, FlatTerrain())
    assert np.max(np.abs(gaps_susp)) <= 1e-10
    assert np.min(gaps_rigid) >= -1e-6  # resting, not sinking
    assert np.sum(gaps_rigid <= 1e-5) >= 3  # on at least three wheels
    assert np.max(gaps_rigid) > 0.03  # and with wheels lifted by centimetres


def test_scenario_keeps_an_equal_terrain_and_its_compiled_model():
    """A terrain scenario's run puts the robot on its terrain; when the robot already stands on an equal one (same
    class, equal attributes, on every wheel) the object is kept, so the compiled model cached on the terrains'
    identity is not rebuilt at every run (it was: ~8 ms per run of the bump scenario). Another terrain, an
    unequal one of the same class, or constraints on different objects are replaced."""
    from robotdyn.fast.dispatch import compiled_model

    rob = Robot(ls.SPEC)
    sc = ls.SCENARIOS["bump"]
    sc.initial_state(rob)
    first, model = rob.terrain, compiled_model(rob)
    assert repr(first) == repr(ls.TERRAINS["bump"]())
    sc.initial_state(rob)
    assert rob.terrain is first and compiled_model(rob) is model
    assert all(getattr(c, "terrain", first) is first for c in rob.constraints)
    for other in (BumpTerrain(0.05, 0.2, 0.16), FlatTerrain()):  # unequal attributes; another class
        set_terrain(rob, other)
        assert not ls._on_terrain(rob, ls.TERRAINS["bump"]())
        sc.initial_state(rob)
        assert rob.terrain is not other and repr(rob.terrain) == repr(first)
    wheel = next(c for c in rob.constraints if hasattr(c, "terrain"))
    wheel.terrain = ls.TERRAINS["bump"]()  # equal, but not the robot's object: one wheel apart
    assert not ls._on_terrain(rob, ls.TERRAINS["bump"]())
    sc.initial_state(rob)
    assert all(getattr(c, "terrain", rob.terrain) is rob.terrain for c in rob.constraints)
