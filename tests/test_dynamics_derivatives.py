"""Derivatives of the reduced forward dynamics (robotdyn.reduction.dynamics_derivatives) and the linearised model.

References, independent of the code under test:
- finite differences of the reduced forward dynamics (the Python reference, robotdyn.reduction.reduced_dynamics)
  with Richardson extrapolation (central differences at h and h/2, combined as (4 D(h/2) - D(h))/3: truncation
  O(h^4) ~ 1e-12), along the holonomic manifold (each perturbed point re-solved onto it by
  robotdyn.constraints.posture.solve_posture) at random admissible states; required agreement 1e-7 relative to
  the largest entry (or absolute below 1);
- symbolic derivatives (sympy) of closed-form models: Quasimoro (tests/oracles/quasimoro_sympy.py) and the
  differential drive (tests/oracles/diff_drive_sympy.py, TIAGo with axisymmetric wheels), to 1e-10;
- the LQR: the linearisation of Quasimoro's inverted body derived here with sympy from the closed-form model gives
  the same A, B and the same closed-loop eigenvalues; the LQR holds the simulated nonlinear robot, which falls
  without it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from oracles import diff_drive_sympy as dd_oracle
from oracles import quasimoro_sympy as qo

from robotdyn.constraints.posture import solve_posture
from robotdyn.contact.sliding import forward, sliding_now
from robotdyn.errors import InputError
from robotdyn.interfaces.constraint_file import read
from robotdyn.reduction.dynamics_derivatives import dynamics_derivatives
from robotdyn.reduction.linearization import linearize, lqr, lqr_torque
from robotdyn.reduction.reduced_dynamics import reference, solve_mass
from robotdyn.robot import Robot
from robotdyn.robots import module
from robotdyn.simulation.engine import simulate

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
START = {"quasimoro": None, "omni_caster": "circle", "mmr12_eod": "straight", "linkage_suspension": None,
         "adaptable_wheel": "hold"}
"""Where each built-in robot starts: its neutral configuration, or a scenario's initial state (off the ground
otherwise)."""


def nudot(robot, q, nu, tau):
    if sliding_now(robot):
        return forward(robot, q, nu, tau).nudot
    red = reference(robot, q, nu)
    return solve_mass(red.M, red.B @ tau - red.h)


def richardson(f, x, h=1e-3):
    """Jacobian of f at x by central differences at h and h/2 with one Richardson step."""
    cols = []
    for j in range(len(x)):
        e = np.zeros(len(x))
        e[j] = h * max(1.0, abs(x[j]))
        d1 = (f(x + e) - f(x - e)) / (2 * e[j])
        d2 = (f(x + e / 2) - f(x - e / 2)) / e[j]
        cols.append((4 * d2 - d1) / 3)
    return np.column_stack(cols)


def admissible_state(robot, start, rng):
    """A random admissible state: the start configuration with the coordinates that no holonomic row involves
    (and the base's planar pose) moved at random, re-solved onto the holonomic manifold; random nu and tau."""
    if start is None:
        q = robot.neutral()
    else:
        q, _ = module(robot.spec.name).SCENARIOS[start].initial_state(robot)
    rows = robot.rows_at(q)
    hol = rows.A[rows.holonomic]
    free = ~np.any(np.abs(hol) > 1e-12, axis=0) if hol.size else np.ones(robot.nq, bool)
    base = ("x", "y", "psi") if robot.spec.root == "planar" else ("x", "y", "yaw")
    for name in base:
        free[robot.coordinate_index(name)] = True
    step = rng.uniform(-0.3, 0.3, robot.nq) * free
    q = np.clip(q + step, robot.description.lower, robot.description.upper)
    if hol.size and np.abs(robot.constraint_residual(q)).max() > 1e-13:  # the base pose kept, the rest solved
        fixed = {c: q[robot.coordinate_index(c)] for c in base}
        q = solve_posture(robot, fixed, q0=q, tol=1e-13).q
    return q, rng.normal(size=robot.mobility) * 0.7, rng.normal(size=len(robot.motors))


def check_against_differences(robot, q, nu, tau):
    D = robot.dynamics_derivatives(q, nu, tau)
    np.testing.assert_allclose(D.nudot, nudot(robot, q, nu, tau), rtol=1e-12, atol=1e-12)
    names = [robot.coordinates[i] for i in D.positions]
    if len(D.positions) == robot.nq:
        on_manifold = lambda qp: qp  # noqa: E731 (no holonomic row restricts q)
    else:
        on_manifold = lambda qp: solve_posture(robot, dict(zip(names, qp)), q0=q, tol=1e-13,  # noqa: E731
                                                check_limits=False).q
    qp = q[D.positions]
    refs = {"dq_manifold": richardson(lambda x: nudot(robot, on_manifold(x), nu, tau), qp),
            "tangent": richardson(on_manifold, qp),
            "dnu": richardson(lambda x: nudot(robot, q, x, tau), nu),
            "dtau": richardson(lambda x: nudot(robot, q, nu, x), tau)}
    for name, ref in refs.items():
        got = getattr(D, name)
        assert np.abs(got - ref).max() <= 1e-7 * max(1.0, np.abs(ref).max()), (name, np.abs(got - ref).max())
    assert D.numerical == (), D.numerical  # every piece analytic (the built-in terrains give third derivatives)
    return D


@pytest.mark.parametrize("name", list(START))
def test_derivatives_equal_richardson_differences_on_built_in_robots(name):
    robot = Robot(module(name).SPEC)
    rng = np.random.default_rng(7)
    D = check_against_differences(robot, *admissible_state(robot, START[name], rng))
    if name != "linkage_suspension":  # (on flat ground its nudot hardly depends on q: see the ramp test)
        assert np.abs(D.dq_manifold).max() > 1e-3  # a configuration-dependent model


def test_derivatives_on_the_linkage_rover_on_a_ramp():
    """Loop closures on a slope: the nudot's q-dependence is large (gravity along the ramp)."""
    from robotdyn.constraints.posture import set_terrain

    mod = module("linkage_suspension")
    robot = Robot(mod.SPEC)
    set_terrain(robot, mod.TERRAINS["ramp"]())
    q = solve_posture(robot, {"x": 0.1, "y": 0.05, "yaw": 0.3}, tol=1e-13).q
    rng = np.random.default_rng(3)
    D = check_against_differences(robot, q, rng.normal(size=2) * 0.5, rng.normal(size=6))
    assert np.abs(D.dq_manifold).max() > 1.0
    assert len(D.positions) == 9 and np.abs(robot.rows_at(q).A[robot.rows_at(q).holonomic] @ D.tangent).max() < 1e-12


def test_terrain_third_derivatives_equal_differences_of_the_hessian():
    """Terrain.third of the built-in curved terrains against Richardson differences of their normal's derivative;
    a terrain without third derivatives (FunctionTerrain) falls back to those differences and says so."""
    from robotdyn.constraints.row_derivatives import terrain_normal_dp
    from robotdyn.constraints.terrain import BumpTerrain, FunctionTerrain, SineTerrain

    for terrain in (SineTerrain(0.1, 0.5, 0.7, 0.3), BumpTerrain(0.05, 0.2, 0.1, 0.3)):
        plain = FunctionTerrain(terrain.height, terrain.gradient, terrain.hessian)
        for p in ([0.23, 0.1, 0.0], [0.41, -0.3, 0.0]):
            said = set()
            ref = terrain_normal_dp(plain, np.array(p), said, "w")
            assert said and "third derivatives" in said.pop()
            got = terrain_normal_dp(terrain, np.array(p))
            assert np.abs(got - ref).max() < 1e-8 * np.abs(ref).max()


def test_derivatives_on_tiago():
    robot = read(EXAMPLES / "tiago.toml").robot()
    rng = np.random.default_rng(11)
    for _ in range(2):
        q = robot.neutral()
        q[:5] = rng.uniform(-2, 2, 5)
        check_against_differences(robot, q, rng.normal(size=2) * 3, rng.normal(size=2))


def test_quasimoro_derivatives_equal_symbolic_ones():
    """Quasimoro against sympy derivatives of the closed-form model (M_r, C_r nu, g_r depend on theta3 only):
    d nudot = M_r^{-1} (-(dh + dg) - dM_r nudot) for q and nu, M_r^{-1} B_r for tau."""
    robot = Robot(module("quasimoro").SPEC)
    s = qo.symbolic_reduced()
    params = {k: robot.params[k] for k in qo.PARAM_KEYS}
    sub = {sym: params[k] for sym, k in zip(qo.PARAM_SYMS, qo.PARAM_KEYS)}
    th3 = qo.Q[5]
    Mr, h, g, Br = (s[k].subs(sub) for k in ("M_r", "h", "g_r", "B_r"))
    nu_s = sp.Matrix(qo.NU)
    f = sp.lambdify((th3, qo.NU), [Mr, h + g, Mr.diff(th3), (h + g).diff(th3), (h + g).jacobian(nu_s), Br], "numpy")
    rng = np.random.default_rng(5)
    for _ in range(5):
        q = rng.uniform(-np.pi, np.pi, 6)
        nu, tau = rng.normal(size=3), rng.normal(size=2)
        M, hg, dM, dhg, dh_nu, B = (np.array(x, float) for x in f(q[5], nu))
        nd = np.linalg.solve(M, B @ tau - hg.ravel())
        ref_q = np.zeros((3, 6))
        ref_q[:, 5] = np.linalg.solve(M, -dhg.ravel() - dM @ nd)
        ref_nu = np.linalg.solve(M, -dh_nu)
        D = dynamics_derivatives(robot, q, nu, tau)
        scale = max(1.0, np.abs(ref_q).max())
        assert np.abs(D.nudot - nd).max() < 1e-10 * max(1.0, np.abs(nd).max())
        assert np.abs(D.dq - ref_q).max() < 1e-10 * scale, np.abs(D.dq - ref_q).max()
        assert np.abs(D.dnu - ref_nu).max() < 1e-10 * max(1.0, np.abs(ref_nu).max())
        assert np.abs(D.dtau - np.linalg.solve(M, B)).max() < 1e-10


def test_differential_drive_derivatives_equal_symbolic_ones(tmp_path):
    """TIAGo with axisymmetric wheels is the closed-form differential drive: nudot = M_r^{-1}(tau - h_r(nu)), M_r
    constant, so d nudot/dq = 0, d nudot/dnu = -M_r^{-1} dh_r/dnu (sympy), d nudot/dtau = M_r^{-1}."""
    from test_tiago import _symmetrised_wheels, constants

    tiago_file = read(EXAMPLES / "tiago.toml")
    urdf = tmp_path / "tiago_axisymmetric_wheels.urdf"
    urdf.write_text(_symmetrised_wheels(Path(tiago_file.SPEC.xacro).read_text()))
    robot = read(EXAMPLES / "tiago.toml", urdf=urdf).robot()
    c = constants(robot)
    M_s, h_s = dd_oracle.textbook_reduced()
    S = dd_oracle.SYMBOLS
    sub = {S.m: c["m"], S.I_A: c["I_A"], S.I_w: c["I_w"], S.d: c["d"], S.e: c["e"], S.r: c["r"], S.b: c["b"]}
    nus = sorted(h_s.free_symbols - set(sub), key=lambda x: x.name)[::-1]  # (nu_R, nu_L)
    assert [x.name for x in nus] == ["nu_R", "nu_L"]
    dh = sp.lambdify(nus, h_s.subs(sub).jacobian(sp.Matrix(nus)), "numpy")
    M = np.array(M_s.subs(sub), float)
    rng = np.random.default_rng(2)
    for _ in range(5):
        q = robot.neutral()
        q[:5] = rng.uniform(-np.pi, np.pi, 5)
        nu, tau = rng.normal(size=2) * 4, rng.normal(size=2)
        D = dynamics_derivatives(robot, q, nu, tau)
        ref_nu = -np.linalg.solve(M, np.array(dh(*nu), float))
        assert np.abs(D.dq).max() < 1e-10
        assert np.abs(D.dnu - ref_nu).max() < 1e-10 * max(1.0, np.abs(ref_nu).max())
        assert np.abs(D.dtau - np.linalg.inv(M)).max() < 1e-10


def skid_steer(tmp_path, law: dict | None = None, lateral: bool = False):
    """examples/skid_steer.toml, its wheels' friction law replaced by ``law`` (keys of a [[wheels]] table), the
    rear pair slipping only sideways with ``lateral``."""
    import tomllib

    import tomli_w

    data = tomllib.loads((EXAMPLES / "skid_steer.toml").read_text())
    data["urdf"] = str(EXAMPLES / "skid_steer.urdf.xacro")
    for wheel in data["wheels"]:
        if law is not None:
            for key in ("friction", "stiffness", "mu", "slip_velocity"):
                wheel.pop(key, None)
            wheel.update(law)
        if lateral and wheel["name"].startswith("rear"):
            wheel["slip"] = "lateral"
    if lateral:
        data["independent"] = data["independent"][:5]  # the rear wheels' rolling rows take two velocities
    if law is not None and law["friction"] == "stick_slip":
        data["independent"] = ["front_left_spin"]  # sticking, the four wheels roll: mobility 1
    path = tmp_path / "skid.toml"
    path.write_text(tomli_w.dumps(data))
    return read(path).robot()


@pytest.mark.parametrize("variant", ["linear", "coulomb", "lateral"])
def test_derivatives_with_slipping_wheels_on_the_skid_steer(variant, tmp_path):
    """The skid-steer example (linear tyre law, as shipped), with regularised Coulomb friction, and with its rear
    wheels slipping sideways only: the coupled accelerations-and-loads solve differentiated."""
    if variant == "linear":
        robot = read(EXAMPLES / "skid_steer.toml").robot()
    elif variant == "coulomb":
        robot = skid_steer(tmp_path, {"friction": "coulomb", "mu": 0.8, "slip_velocity": 0.05})
    else:
        robot = skid_steer(tmp_path, lateral=True)
    rng = np.random.default_rng(9)
    q = robot.neutral()
    for c in ("x", "y", "yaw", "front_left_spin", "rear_right_spin"):
        q[robot.coordinate_index(c)] = rng.uniform(-1, 1)
    D = check_against_differences(robot, q, rng.normal(size=robot.mobility) * 0.5, rng.normal(size=4) * 3)
    assert np.abs(D.dnu).max() > 1.0  # the friction forces depend on the slip velocities


def test_slipping_wheels_need_their_own_rule_and_a_smooth_law(tmp_path):
    robot = read(EXAMPLES / "skid_steer.toml").robot()
    with pytest.raises(InputError, match="friction law"):  # the rolling-only rule refuses them in one line
        dynamics_derivatives(robot, robot.neutral(), np.zeros(robot.mobility), np.zeros(len(robot.motors)))
    exact = skid_steer(tmp_path, {"friction": "stick_slip", "mu": 0.8})  # exact Coulomb: sticking, then sliding
    with pytest.raises(InputError, match="friction law"):
        exact.dynamics_derivatives(exact.neutral(), np.ones(exact.mobility), np.zeros(4))


# ------------------------------------------------------------------------------------------- linearisation
UPRIGHT = ["theta3", "theta1_dot", "theta2_dot", "theta3_dot"]
WEIGHTS = ([10.0, 1.0, 1.0, 1.0], [1.0, 1.0])


def closed_form_upright(params):
    """Quasimoro's body inverted (theta3 = pi, nu = 0, tau = 0), linearised with sympy from the closed-form
    model: states (theta3, nu), A = [[0, e3^T], [-M_r^{-1} d(h + g_r)/dtheta3, -M_r^{-1} d(h)/dnu]],
    B = [0; M_r^{-1} B_r]."""
    s = qo.symbolic_reduced()
    sub = {sym: params[k] for sym, k in zip(qo.PARAM_SYMS, qo.PARAM_KEYS)}
    th3 = qo.Q[5]
    at = {th3: sp.pi, **{n: 0 for n in qo.NU}}
    Mr = s["M_r"].subs(sub)
    rhs = -(s["h"] + s["g_r"]).subs(sub)
    A21 = (Mr.inv() * rhs.diff(th3)).subs(at)
    A22 = (Mr.inv() * rhs.jacobian(sp.Matrix(qo.NU))).subs(at)
    B2 = (Mr.inv() * s["B_r"].subs(sub)).subs(at)
    A = sp.zeros(4, 4)
    A[0, 3] = 1
    A[1:, 0] = A21
    A[1:, 1:] = A22
    return np.array(A.evalf(), float), np.vstack([np.zeros((1, 2)), np.array(B2.evalf(), float)])


def test_lqr_closed_loop_equals_closed_form_and_holds_the_robot():
    robot = Robot(module("quasimoro").SPEC)
    q = robot.neutral()
    q[5] = np.pi
    model = linearize(robot, q, np.zeros(3), np.zeros(2)).restrict(UPRIGHT)
    A_ref, B_ref = closed_form_upright({k: robot.params[k] for k in qo.PARAM_KEYS})
    assert np.abs(model.A - A_ref).max() < 1e-10 * np.abs(A_ref).max()
    assert np.abs(model.B - B_ref).max() < 1e-10 * np.abs(B_ref).max()
    assert model.eigenvalues.real.max() > 1.0  # the inverted body falls
    K, closed = lqr(model, *WEIGHTS)
    import scipy.linalg

    X = scipy.linalg.solve_continuous_are(A_ref, B_ref, np.diag(WEIGHTS[0]), np.diag(WEIGHTS[1]))
    ref = np.linalg.eigvals(A_ref - B_ref @ np.linalg.solve(np.diag(WEIGHTS[1]), B_ref.T @ X))
    ref = ref[np.lexsort((ref.imag, ref.real))]
    assert np.abs(closed - ref).max() < 1e-8 * np.abs(ref).max()
    # the nonlinear robot, from 0.2 rad off upright: held with the LQR, falls without it
    q0 = q.copy()
    q0[5] += 0.2
    held = simulate(robot, 5.0, q0, np.zeros(3), lqr_torque(model, K), n_out=11, rtol=1e-8, atol=1e-10,
                    progress=False)
    assert abs(held.q[-1, 5] - np.pi) < 1e-3 and np.abs(held.nu[-1]).max() < 1e-2
    free = simulate(robot, 1.0, q0, np.zeros(3), None, n_out=11, rtol=1e-8, atol=1e-10, progress=False)
    assert abs(free.q[-1, 5] - np.pi) > 1.0


def test_linear_model_predicts_a_steady_motion():
    """About Quasimoro's steady rolling (body hanging, wheels at 2 rad/s, no torque: not an equilibrium), the
    difference of two nonlinear runs 1e-6 apart follows expm(A t) to second order."""
    import scipy.linalg

    robot = Robot(module("quasimoro").SPEC)
    q, nu, tau = robot.neutral(), np.array([2.0, 2.0, 0.0]), np.zeros(2)
    model = linearize(robot, q, nu, tau)
    assert np.abs(model.xdot0[6:]).max() < 1e-12 and abs(model.xdot0[0]) > 0.5  # rolls forward at constant speed
    rng = np.random.default_rng(4)
    dx = rng.normal(size=9) * 1e-6
    kw = dict(n_out=2, rtol=1e-12, atol=1e-14, progress=False)
    base = simulate(robot, 0.3, q, nu, None, **kw)
    pert = simulate(robot, 0.3, q + dx[:6], nu + dx[6:], None, **kw)
    got = np.concatenate([pert.q[-1] - base.q[-1], pert.nu[-1] - base.nu[-1]])
    pred = scipy.linalg.expm(model.A * 0.3) @ dx
    assert np.abs(got - pred).max() < 1e-3 * np.abs(dx).max(), np.abs(got - pred).max()
    assert np.abs(got - dx).max() > 1e-2 * np.abs(dx).max()  # the motion does change the deviation


def test_linear_model_of_the_omni_platform_on_its_path():
    """The omni-caster platform (operational-space velocities) at the start of its circle, under the path's
    feed-forward torques held constant: the difference of two nonlinear runs 1e-6 apart follows expm(A t) over a
    time short enough that A itself (which turns with the heading) stays put: error O(dx t^2)."""
    import scipy.linalg

    mod = module("omni_caster")
    robot = Robot(mod.SPEC)
    scenario = mod.SCENARIOS["circle"]
    q, _ = scenario.initial_state(robot)
    nu = np.array([0.0, 0.5, 0.1])
    tau = scenario.torque_law(robot)(0.0, q, nu)
    model = linearize(robot, q, nu, tau)
    assert model.states[:3] == ["x", "y", "psi"] and model.B.shape == (12, 6)
    rng = np.random.default_rng(8)
    dx = rng.normal(size=12) * 1e-6
    q1, nu1 = q.copy(), nu + dx[9:]
    q1[model.position_index] += dx[:9]
    const = lambda t, q, nu: tau  # noqa: E731
    kw = dict(n_out=2, rtol=1e-12, atol=1e-14, progress=False)
    base = simulate(robot, 0.02, q, nu, const, **kw)
    pert = simulate(robot, 0.02, q1, nu1, const, **kw)
    got = np.concatenate([(pert.q[-1] - base.q[-1])[model.position_index], pert.nu[-1] - base.nu[-1]])
    pred = scipy.linalg.expm(model.A * 0.02) @ dx
    assert np.abs(got - pred).max() < 1e-4 * np.abs(dx).max(), np.abs(got - pred).max()
    assert np.abs(got - dx).max() > 1e-2 * np.abs(dx).max()


def test_linearize_command_prints_the_api_model(capsys):
    """`robotdyn linearize ... --json` gives the API's A, B, eigenvalues and LQR gain (one story through both
    doors)."""
    import json

    from robotdyn.cli import main

    argv = ["linearize", "quasimoro", "--set", "theta3=3.141592653589793", "--states", *UPRIGHT,
            "--lqr-q", *map(str, WEIGHTS[0]), "--lqr-r", *map(str, WEIGHTS[1]), "--json"]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    robot = Robot(module("quasimoro").SPEC)
    q = robot.neutral()
    q[5] = np.pi
    model = linearize(robot, q, np.zeros(3), np.zeros(2)).restrict(UPRIGHT)
    K, closed = lqr(model, *WEIGHTS)
    assert out["states"] == UPRIGHT and out["inputs"] == ["m1", "m2"]
    np.testing.assert_allclose(out["A"], model.A, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(out["B"], model.B, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(out["K"], K, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(out["eigenvalues_real"], model.eigenvalues.real, atol=1e-10)
    np.testing.assert_allclose(out["closed_loop_real"], closed.real, rtol=1e-10)


def test_quasimoro_lqr_example_balances_the_body():
    """examples/quasimoro_lqr.py runs and holds the inverted body (0.2 rad off at the start)."""
    import runpy

    example = runpy.run_path(str(EXAMPLES / "quasimoro_lqr.py"))
    out = example["main"](["--t-end", "4"])
    assert abs(out["error"][0] - 0.2) < 1e-12 and abs(out["error"][-1]) < 1e-3
    assert np.all(out["closed"].real < 0)
