"""Derivatives of the wheel contact forces and of the required mu (robotdyn.contact.force_derivatives).

References, independent of the code under test:
- finite differences of the reported forces (Robot.contact_forces: forward dynamics, then the force solve with the
  rigid limit of compliance where rigid-body dynamics leave loads open, a planar model's loads from its floating
  twin) with Richardson extrapolation (central differences at h and h/2, combined as (4 D(h/2) - D(h))/3), along
  the holonomic manifold (each perturbed point re-solved onto it by solve_posture), at random admissible states;
  required agreement 1e-7 relative to the largest entry (or absolute below 1);
- a closed form for Quasimoro derived here by hand from Newton's law for the whole robot (wheel centres at
  constant height r, G = C2 + d (sin th3 x1 - cos th3 z1), both rolling directions t1 = x1), with the
  accelerations from the independent sympy model of tests/oracles/quasimoro_sympy.py, differentiated by sympy:
      N_A + N_B = (2 m + M) g + M d (cos th3 th3d^2 + sin th3 th3dd),
      F_A + F_B = (2 m + M) vdot + M d (cos th3 th3dd - sin th3 th3d^2 - sin th3 psid^2),
  vdot = r (th1dd + th2dd) / 2, psid = rho (th2d - th1d); in a symmetric state (equal wheel speeds and torques)
  each wheel carries half and mu = |F_A + F_B| / (N_A + N_B).
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from oracles import quasimoro_sympy as qo
from test_dynamics_derivatives import EXAMPLES, START, admissible_state, richardson, skid_steer

from robotdyn.constraints.posture import solve_posture
from robotdyn.errors import InputError
from robotdyn.interfaces.constraint_file import read
from robotdyn.robot import Robot
from robotdyn.robots import module


def reported(robot, q, nu, tau):
    """Forces (W*3,) and required mu (W,) as Robot.contact_forces reports them."""
    f = robot.contact_forces(q, nu, tau)
    return np.concatenate([np.array([w.force for w in f.wheels]).ravel(), [w.required_mu for w in f.wheels]])


def check_against_differences(robot, q, nu, tau):
    D = robot.contact_force_derivatives(q, nu, tau)
    ref = robot.contact_forces(q, nu, tau)
    W = len(D.wheels)
    assert D.wheels == [w.name for w in ref.wheels]
    scale = max(1.0, np.abs(D.force).max())
    assert np.abs(D.force - np.array([w.force for w in ref.wheels])).max() < 1e-10 * scale  # one story
    assert np.array_equal(D.known, np.array([w.known for w in ref.wheels]))
    names = [robot.coordinates[i] for i in D.positions]
    if len(D.positions) == robot.nq:
        on_manifold = lambda qp: qp  # noqa: E731
    else:
        on_manifold = lambda qp: solve_posture(robot, dict(zip(names, qp)), q0=q, tol=1e-13,  # noqa: E731
                                                check_limits=False).q
    smooth = np.array([w not in D.not_smooth for w in D.wheels])
    keep = np.concatenate([np.ones(3 * W, bool), smooth])  # mu rows only where mu has a derivative
    refs = {"q": richardson(lambda x: reported(robot, on_manifold(x), nu, tau)[keep], q[D.positions]),
            "nu": richardson(lambda x: reported(robot, q, x, tau)[keep], nu),
            "tau": richardson(lambda x: reported(robot, q, nu, x)[keep], tau)}
    got = {"q": np.vstack([D.dforce_dq_manifold.reshape(3 * W, -1), D.dmu_dq_manifold[smooth]]),
           "nu": np.vstack([D.dforce_dnu.reshape(3 * W, -1), D.dmu_dnu[smooth]]),
           "tau": np.vstack([D.dforce_dtau.reshape(3 * W, -1), D.dmu_dtau[smooth]])}
    for name, r in refs.items():
        err = np.abs(got[name] - r).max()
        assert err <= 1e-7 * max(1.0, np.abs(r).max()), (name, err, np.abs(r).max())
    return D


@pytest.mark.parametrize("name", list(START))
def test_force_derivatives_equal_richardson_differences_on_built_in_robots(name):
    robot = Robot(module(name).SPEC)
    D = check_against_differences(robot, *admissible_state(robot, START[name], np.random.default_rng(7)))
    assert np.abs(D.dforce_dtau).max() > 1e-2  # the torques move the forces
    if name in ("quasimoro", "omni_caster"):
        assert D.source == "floating twin"  # a planar model's loads: its floating twin's


def test_force_derivatives_on_the_linkage_rover_on_a_ramp():
    """Six wheels on a linkage (four loop closures) on a slope: the loads depend on the configuration."""
    from robotdyn.constraints.posture import set_terrain

    mod = module("linkage_suspension")
    robot = Robot(mod.SPEC)
    set_terrain(robot, mod.TERRAINS["ramp"]())
    q = solve_posture(robot, {"x": 0.1, "y": 0.05, "yaw": 0.3}, tol=1e-13).q
    rng = np.random.default_rng(3)
    D = check_against_differences(robot, q, rng.normal(size=2) * 0.5, rng.normal(size=6))
    assert np.abs(D.dforce_dq_manifold).max() > 1.0


@pytest.mark.parametrize("variant", ["linear", "coulomb", "lateral"])
def test_force_derivatives_with_slipping_wheels_on_the_skid_steer(variant, tmp_path):
    """The skid-steer example (friction depends on the slip, loads split by the rigid limit inside the coupled
    solve), with regularised Coulomb friction, and with its rear wheels rolling and slipping sideways only."""
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
    assert np.abs(D.dforce_dnu).max() > 1.0  # friction depends on the slip velocities


def test_force_derivatives_on_tiago():
    robot = read(EXAMPLES / "tiago.toml").robot()
    rng = np.random.default_rng(11)
    q = robot.neutral()
    q[:5] = rng.uniform(-2, 2, 5)
    check_against_differences(robot, q, rng.normal(size=2) * 3, rng.normal(size=2))


def test_force_derivatives_of_the_mmr12_climbing_posture():
    """MMR12-EOD on a 20 deg ramp (floating root, two drive wheels, two frictionless arm tips; the arm motors
    determine the tip loads, the drive wheels' lateral squeeze stays open: its derivative is that of the
    minimum-norm choice, flagged by ``known``)."""
    from robotdyn.robots.mmr12_eod.climbing_posture import locked_climbing_robot, locked_climbing_state

    slope = np.radians(20.0)
    robot = locked_climbing_robot(slope)
    q = locked_climbing_state(robot, slope)
    rng = np.random.default_rng(1)
    for c in ("theta1", "lambda2", "theta3", "theta4"):
        q[robot.coordinate_index(c)] += rng.uniform(-0.1, 0.1)
    q = solve_posture(robot, {c: q[robot.coordinate_index(c)] for c in ("x", "y", "yaw", "theta_C4")}, q0=q,
                      tol=1e-13).q
    tau = robot.inverse_dynamics(q, np.zeros(robot.mobility), np.zeros(robot.mobility))[1]
    D = check_against_differences(robot, q, rng.normal(size=robot.mobility) * 0.1, tau + rng.normal(size=12) * 0.5)
    assert not D.known[D.wheel("W_R"), 1] and D.known[:, 2].all()


def rigid_husky(tmp_path):
    """examples/husky_like.toml with its wheels rolling without slipping (four wheels on a rigid chassis: the
    loads are split by the rigid limit of compliance)."""
    import tomllib

    import tomli_w

    data = tomllib.loads((EXAMPLES / "husky_like.toml").read_text())
    data["urdf"] = str(EXAMPLES / "husky_like.urdf.xacro")
    for wheel in data["wheels"]:
        for key in ("friction", "stiffness", "mu", "slip_velocity"):
            wheel.pop(key, None)
    data["independent"] = ["front_left_wheel"]
    path = tmp_path / "husky_rigid.toml"
    path.write_text(tomli_w.dumps(data))
    return read(path).robot()


@pytest.mark.parametrize("deg", [30.0, 44.0])
def test_force_derivatives_follow_the_rigid_limit_and_its_active_set(deg, tmp_path):
    """A rigid four-wheel chassis on a ramp, turned 45 deg across it: its loads are the rigid limit of the wheels'
    normal compliance; at 44 deg the front right wheel would pull, the rigid limit holds it at zero (its active set)
    and the derivatives are those of that branch."""
    from robotdyn.constraints.posture import set_terrain
    from robotdyn.constraints.terrain import RampTerrain

    robot = rigid_husky(tmp_path)
    set_terrain(robot, RampTerrain(np.tan(np.radians(deg))))
    q = solve_posture(robot, {"x": 0.0, "y": 0.0, "yaw": np.pi / 4}, tol=1e-13).q
    nu = np.array([0.3])
    tau = robot.inverse_dynamics(q, nu, np.zeros(1))[1] + np.array([0.5, -0.2, 0.1, 0.3])
    D = check_against_differences(robot, q, nu, tau)
    forces = robot.contact_forces(q, nu, tau)
    assert all(w.source == "rigid limit of compliance" for w in forces.wheels)
    assert D.unloaded == (["front_right"] if deg > 40 else [])
    assert D.not_smooth == D.unloaded and np.abs(D.dforce_dq_manifold[:, 2]).max() > 1.0


# ------------------------------------------------------------------------------------------- closed form
def closed_form(params):
    """Numerical functions of (th3, nu, tau): the sums (N, F) of Quasimoro's normal loads and traction (module
    docstring) and their derivatives in th3, nu and tau: the partials of N and F in (th3, nu, nudot) by sympy, the
    accelerations nudot = M_r^{-1} (B_r tau - h - g_r) and their derivatives from the sympy model (as in
    test_dynamics_derivatives), combined by the chain rule."""
    s = qo.symbolic_reduced()
    sub = {sym: params[k] for sym, k in zip(qo.PARAM_SYMS, qo.PARAM_KEYS)}
    th3 = qo.Q[5]
    nu = sp.Matrix(qo.NU)
    acc = sp.Matrix(sp.symbols("a1 a2 a3", real=True))
    m, M, r, d, rho, g = (sub[qo.PARAM_SYMS[i]] for i in (0, 1, 4, 5, 6, 7))
    psid = rho * (nu[1] - nu[0])
    N = (2 * m + M) * g + M * d * (sp.cos(th3) * nu[2] ** 2 + sp.sin(th3) * acc[2])
    F = (2 * m + M) * r * (acc[0] + acc[1]) / 2 + M * d * (sp.cos(th3) * acc[2] - sp.sin(th3) * nu[2] ** 2
                                                            - sp.sin(th3) * psid ** 2)
    NF = sp.Matrix([N, F])
    parts = sp.lambdify((th3, qo.NU, acc), [NF, NF.diff(th3), NF.jacobian(nu), NF.jacobian(acc)], "numpy")
    Mr, hg, Br = (s[k].subs(sub) for k in ("M_r", "h", "B_r"))
    hg = hg + s["g_r"].subs(sub)
    model = sp.lambdify((th3, qo.NU), [Mr, hg, Mr.diff(th3), hg.diff(th3), hg.jacobian(nu), Br], "numpy")

    def f(t3, v, tau):
        Mn, hn, dM, dh, dh_nu, B = (np.array(x, float) for x in model(t3, v))
        a = np.linalg.solve(Mn, B @ tau - hn.ravel())
        da_th3 = np.linalg.solve(Mn, -dh.ravel() - dM @ a)
        da_nu, da_tau = np.linalg.solve(Mn, -dh_nu), np.linalg.solve(Mn, B)
        val, p_th3, p_nu, p_acc = (np.array(x, float) for x in parts(t3, v, a))
        return (val.ravel(), p_th3.ravel() + p_acc @ da_th3, p_nu + p_acc @ da_nu, p_acc @ da_tau)

    return f


def test_quasimoro_load_derivatives_equal_a_closed_form():
    robot = Robot(module("quasimoro").SPEC)
    f = closed_form({k: robot.params[k] for k in qo.PARAM_KEYS})
    rng = np.random.default_rng(5)
    for i in range(4):
        q = rng.uniform(-np.pi, np.pi, 6)
        nu, tau = rng.normal(size=3), rng.normal(size=2)
        if i % 2:  # symmetric: equal wheel speeds and torques, each wheel carries half
            nu[1], tau[1] = nu[0], tau[0]
        val, d_th3, d_nu, d_tau = f(q[5], nu, tau)
        D = robot.contact_force_derivatives(q, nu, tau)
        sums = D.force[:, [2, 0]].sum(axis=0)  # (normal, t1) summed over the wheels
        assert np.abs(sums - val).max() < 1e-10 * np.abs(val).max()
        ref_q = np.zeros((2, 6))
        ref_q[:, 5] = d_th3
        for got, ref in ((D.dforce_dq[:, [2, 0]].sum(axis=0), ref_q), (D.dforce_dnu[:, [2, 0]].sum(axis=0), d_nu),
                         (D.dforce_dtau[:, [2, 0]].sum(axis=0), d_tau)):
            assert np.abs(got - ref).max() < 1e-10 * max(1.0, np.abs(ref).max()), np.abs(got - ref).max()
        if i % 2:  # mu = |F| / N on each wheel; its derivative along symmetric directions
            N, F = val
            assert D.required_mu == pytest.approx([abs(F) / N] * 2, rel=1e-10)
            dmu = lambda dN, dF: np.sign(F) * dF / N - abs(F) * dN / N ** 2  # noqa: E731
            sym_nu = np.array([[1.0, 0.0], [1.0, 0.0], [0.0, 1.0]])  # (th1d = th2d, th3d)
            for got, ref in ((D.dmu_dq[:, 5], dmu(*d_th3)), (D.dmu_dnu @ sym_nu, dmu(*(d_nu @ sym_nu))),
                             (D.dmu_dtau.sum(axis=1), dmu(*d_tau.sum(axis=1)))):
                assert np.abs(got - ref).max() < 1e-10 * max(1.0, np.abs(ref).max())


def test_compliant_wheels_are_refused_in_one_line():
    from compliant_disc import disc  # tests/compliant_disc.py (joint springs: tests/test_compiled_springs.py)

    robot = disc(g=9.81)
    with pytest.raises(InputError, match="compliant wheels") as info:
        robot.contact_force_derivatives(robot.neutral(), np.zeros(robot.mobility), np.zeros(len(robot.motors)))
    assert "\n" not in str(info.value)


def test_repr_names_the_shapes_and_mu():
    robot = Robot(module("quasimoro").SPEC)
    D = robot.contact_force_derivatives(robot.neutral(), np.zeros(3), np.array([0.5, 0.5]))
    text = repr(D)
    assert "2 wheels" in text and "required mu" in text and "floating twin" in text
    assert D.dforce_dq.shape == (2, 3, 6) and D.dforce_dnu.shape == (2, 3, 3) and D.dforce_dtau.shape == (2, 3, 2)
    assert D.dmu_dq_manifold.shape == (2, len(D.positions))


@pytest.mark.parametrize("args, expected", [
    ((np.zeros(5), np.zeros(3), np.zeros(2)), "q has 5 values; expected 6 values"),
    ((np.zeros(6), np.zeros(3), np.zeros(3)), "tau has 3 values; expected 2 values"),
    ((np.zeros(6), np.array([0.0, np.nan, 0.0]), np.zeros(2)), "nu"),
])
def test_bad_input_is_one_line(args, expected):
    robot = Robot(module("quasimoro").SPEC)
    with pytest.raises(InputError) as err:
        robot.contact_force_derivatives(*args)
    assert expected in str(err.value) and "\n" not in str(err.value)
