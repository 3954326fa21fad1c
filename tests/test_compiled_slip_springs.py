"""Slipping wheels beside joint springs and dampers on the compiled engine (robotdyn/_compiled.cpp: slip_rhs_into adds
the springs' generalised force Q(q, v), kernels/joint_springs.hpp, to the right-hand side of kernels/sliding.hpp's and
kernels/sliding_rigid_limit.hpp's systems, and a run carries the friction work and the damper work), against the
Python reference (robotdyn.contact.sliding.forward and sliding_rigid_limit.coupled add app.Q; the scipy engine) and
closed forms derived here.

Fixtures (this test's own):

- ``rover``: examples/skid_steer.toml (linear tyre law; loads determinate, its front axle oscillates) with a spring
  on the axle's roll joint (k = 40 N m/rad, c = 1.5 N m s/rad, rest 0.02 rad) and a damper on every wheel spin
  (d = 0.02 N m s/rad; its lateral-slip variant: d = 2 N m s/rad and no axle spring).
- ``husky``: examples/husky_like.toml (regularised Coulomb law; four loads left open, split by the rigid limit)
  whose xacro gives each wheel joint a URDF ``<dynamics damping="D"/>`` (D = 0.5 N m s/rad), applied by default as a
  joint damper: the user's case, since ROS descriptions carry wheel damping. The ``sprung`` variant adds a
  ``[[springs]]`` stiffness of 3 N m/rad (rest 0.2 rad) on one wheel, merged with its URDF damping.

Closed forms:

- A motor acting on joint j alone (B = e_j) and a damper on that joint both enter as a generalised force on q_j, so
  the right-hand side with dampers d at wheel rates phi equals the one without them at the torques tau - d phi, on
  either system (determinate and open loads), and the dampers' power is -d sum phi_i^2.
- tests/test_lateral_slip.py's rover turning in place (wheels rolling along t1, sliding sideways under the linear
  law: f_n = m g / 4, spin rates phi_i = -omega y_i / r) with its wheels damped: the dampers' power
  -d sum phi_i^2 = -4 d (b / r)^2 omega^2 joins the power balance, J omega' = 4 tau b / r - 4 c omega with
  c = f_n k a^2 + d b^2 / r^2, so omega(t) = omega* (1 - exp(-t / T)), omega* = tau b / (r c), T = J / (4 c).
"""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from robotdyn.contact.sliding import forward
from robotdyn.fast.compiled import available
from robotdyn.fast.compiled_derivatives import compiled_derivatives
from robotdyn.fast.dispatch import compiled_model, use_compiled
from robotdyn.interfaces.constraint_file import read
from robotdyn.reduction.joint_springs import JointSpring
from robotdyn.robot import Robot
from robotdyn.simulation import simulate
from robotdyn.simulation.compiled_engine import choose_engine
from robotdyn.simulation.torque_profile import Constant

sys.path.insert(0, str(Path(__file__).parent))
from test_lateral_slip import A, B, G, R, _yaw_inertia  # noqa: E402

pytestmark = pytest.mark.skipif(not available(), reason="compiled extension not built")
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
D_WHEEL, D_LATERAL, D_HUSKY = 0.02, 2.0, 0.5  # wheel dampers [N m s/rad]: the rovers', the Husky-like's (URDF)
WHEELS = ("front_left", "front_right", "rear_left", "rear_right")


def _rover(lateral: bool = False, springs: bool = True) -> Robot:
    spec = read(EXAMPLES / "skid_steer.toml").SPEC
    if lateral:
        spec = replace(spec, wheels=[replace(w, slip="lateral") for w in spec.wheels], independent=["x", "y", "yaw"])
    extra = [JointSpring(f"{w}_spin", damping=D_LATERAL if lateral else D_WHEEL) for w in WHEELS]
    if not lateral:
        extra.append(JointSpring("axle_roll", 40.0, 1.5, 0.02))
    return Robot(replace(spec, springs=extra if springs else []))


@pytest.fixture(scope="module")
def husky_files(tmp_path_factory):
    """The damped Husky-like's description and constraint files (the example's, with wheel damping)."""
    root = tmp_path_factory.mktemp("damped_husky")
    xacro = (EXAMPLES / "husky_like.urdf.xacro").read_text()
    joint = '<axis xyz="0 1 0"/>\n    </joint>'
    assert xacro.count(joint) == 1
    xacro = xacro.replace(joint, f'<axis xyz="0 1 0"/>\n      <dynamics damping="{D_HUSKY}"/>\n    </joint>')
    (root / "husky_like.urdf.xacro").write_text(xacro)
    toml = (EXAMPLES / "husky_like.toml").read_text()
    (root / "damped.toml").write_text(toml)
    (root / "sprung.toml").write_text(toml + '\n[[springs]]\njoint = "front_left_wheel"\nstiffness = 3.0\n'
                                             'rest = 0.2\n')
    return root


def _husky(files, name="damped", **args):
    return read(files / f"{name}.toml", xacro_args=args or None).robot()


def _states(robot, count=3, seed=11):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        q = robot.neutral()
        for name in ("x", "y", "yaw"):
            q[robot.coordinate_index(name)] = rng.uniform(-np.pi, np.pi)
        nu = np.r_[rng.uniform(-1.5, 1.5, 3), rng.uniform(-12.0, 12.0, 4)]  # (x', y', yaw', four wheel rates)
        yield q, nu, rng.uniform(-6.0, 6.0, 4)


def _compiled(robot, q, nu, tau):
    """The compiled right-hand side at one state: d/dt (q, nu, friction work, damper work), the normal loads."""
    fast = compiled_model(robot)
    fast.select(robot.reduced(q, nu).projection)
    out, normal, _, _ = fast.ev.slip_rhs(q, nu, tau, 0.0)
    return out, normal


@pytest.mark.parametrize("which", ["rover", "husky", "husky corner", "husky sprung"])
def test_right_hand_side_equals_the_python_path(which, husky_files):
    """Accelerations, loads, friction power and damper power of the compiled slipping solve with springs equal
    sliding.forward's (which adds app.Q) at random states; the springs matter there (the same state without them
    differs by far more than the tolerance), and their derivatives stay on the Python path."""
    if which == "rover":
        robot, bare = _rover(), _rover(springs=False)
    else:
        args = {"com_x": "0.19", "com_y": "0.21"} if which == "husky corner" else {}
        robot = _husky(husky_files, "sprung" if which == "husky sprung" else "damped", **args)
        bare = read(EXAMPLES / "husky_like.toml", xacro_args=args or None).robot()
    fast = compiled_model(robot)
    assert fast.ev.slipping == 4 and fast.slip_simulated and fast.loads_open == (which != "rover")
    assert "derivatives and batched runs are on the Python path" in fast.slip_refusal
    n, k = robot.nq, robot.mobility
    for q, nu, tau in _states(robot):
        with use_compiled(False):
            st = forward(robot, q, nu, tau)
            plain = forward(bare, q, nu, tau)
        out, normal = _compiled(robot, q, nu, tau)
        scale = max(1.0, np.max(np.abs(st.nudot)))
        assert np.max(np.abs(plain.nudot - st.nudot)) > 1e-3 * scale  # (not a vacuous comparison)
        np.testing.assert_allclose(out[n:n + k], st.nudot, rtol=0, atol=1e-10 * scale)
        np.testing.assert_allclose(normal, st.normal, rtol=0, atol=1e-10 * np.max(np.abs(st.normal)))
        assert out[n + k] == pytest.approx(st.power, rel=1e-10, abs=1e-12)
        assert out[n + k + 1] == pytest.approx(st.damper_power, rel=1e-10, abs=1e-12) and st.damper_power < 0
        assert compiled_derivatives(robot, q, nu, tau) is None  # (the Python path's derivatives answer)


@pytest.mark.parametrize("which", ["rover", "husky"])
def test_a_damper_is_a_torque_on_its_joint(which, husky_files):
    """The module's first closed form: with dampers d at wheel rates phi, the right-hand side equals the undamped
    robot's at tau - d phi, and the damper power is -d sum phi^2 (the rover's roll spring is left out here)."""
    if which == "rover":
        robot = Robot(replace(_rover().spec, springs=[JointSpring(f"{w}_spin", damping=D_WHEEL) for w in WHEELS]))
        bare, d = _rover(springs=False), D_WHEEL
    else:
        robot, bare, d = _husky(husky_files), read(EXAMPLES / "husky_like.toml").robot(), D_HUSKY
    n, k = robot.nq, robot.mobility
    for q, nu, tau in _states(robot, seed=5):
        phi = nu[3:]  # the wheel rates are the last four independent velocities (each motor's joint)
        out, normal = _compiled(robot, q, nu, tau)
        ref, ref_normal = _compiled(bare, q, nu, tau - d * phi)
        np.testing.assert_allclose(out[:n + k + 1], ref, rtol=0, atol=1e-10 * max(1.0, np.max(np.abs(ref))))
        np.testing.assert_allclose(normal, ref_normal, rtol=0, atol=1e-10 * np.max(np.abs(ref_normal)))
        assert out[n + k + 1] == pytest.approx(-d * phi @ phi, rel=1e-12)


def _run(robot, engine, t_end, nu0, tau, n_out=5, **kw):
    return simulate(robot, t_end, robot.neutral(), np.asarray(nu0, float), tau, n_out=n_out, rtol=1e-10,
                    atol=1e-12, engine=engine, progress=False, **kw)


@pytest.mark.parametrize("which", ["rover", "husky"])
def test_compiled_run_equals_the_scipy_run(which, husky_files):
    """Sliding forward while turning, both engines: q, nu, the friction work and the damper work agree to the
    integration tolerance (the Python path's scipy run is the reference). The rover runs on the compiled dopri5: on
    its fast tyre mode the default Adams stepper's own error at rtol 1e-10 is 1e-8 to 6e-8 in q (against a dopri5
    run at rtol 1e-12; the same with or without the springs), scipy's DOP853's and dopri5's about 1e-11."""
    robot = _rover() if which == "rover" else _husky(husky_files)
    assert choose_engine(robot, Constant(np.zeros(4)), None, "auto")
    tau = Constant([-0.3, 0.5, -0.3, 0.5] if which == "rover" else [-6.0, 9.0, -6.0, 9.0])
    nu0 = [1.0, 0.0, 0.8, 5.0, 12.0, 5.0, 12.0] if which == "rover" else [1.0, 0.0, 0.8, 2.0, 8.0, 2.0, 8.0]
    method = {"method": "dopri5"} if which == "rover" else {}
    runs = [_run(robot, "compiled", 0.02, nu0, tau, **method), _run(robot, "scipy", 0.02, nu0, tau)]
    assert runs[0].stats["engine"].startswith("compiled") and runs[1].stats["engine"].startswith("scipy")
    np.testing.assert_allclose(runs[0].q, runs[1].q, rtol=0, atol=1e-8)
    np.testing.assert_allclose(runs[0].nu, runs[1].nu, rtol=0, atol=1e-7)
    np.testing.assert_allclose(runs[0].friction_work, runs[1].friction_work, rtol=0, atol=1e-7)
    np.testing.assert_allclose(runs[0].damper_work, runs[1].damper_work, rtol=0, atol=1e-9)
    assert runs[0].damper_work[-1] < -1e-3


def test_energy_balance_of_a_damped_compiled_turn(husky_files):
    """Motor work (constant torques: sum tau_i times each wheel's turn) plus the friction work plus the dampers' work
    (states of the run, each <= 0) equals the change of mechanical energy, sample by sample."""
    robot = _husky(husky_files)
    tau = np.array([-12.0, 12.0, -12.0, 12.0])
    traj = _run(robot, "compiled", 0.5, [0.3, 0, 0.5, 0, 0, 0, 0], Constant(tau), n_out=11)
    assert traj.stats["engine"].startswith("compiled")
    wheels = [robot.coordinate_index(f"{c}_wheel") for c in WHEELS]
    motor = (traj.q[:, wheels] - traj.q[0, wheels]) @ tau
    assert traj.friction_work[-1] < -1.0 and traj.damper_work[-1] < -1.0
    assert np.all(np.diff(traj.damper_work) <= 1e-12)
    np.testing.assert_allclose(traj.energy - traj.energy[0], motor + traj.friction_work + traj.damper_work,
                               rtol=0, atol=1e-7)


def test_damped_lateral_slip_turn_at_the_closed_form():
    """The module's second closed form on the compiled engine: the yaw rate omega* (1 - exp(-t / T)) with the wheel
    dampers' c = f_n k a^2 + d b^2 / r^2 (they lower omega* by a third here), and the dampers' work, the integral
    of -4 d (b / r)^2 omega^2."""
    robot = _rover(lateral=True)
    mass = sum(robot.model.inertias[i].mass for i in range(robot.model.njoints))
    fn, k, tau = mass * G / 4, 5.0, 0.3
    c = fn * k * A**2 + D_LATERAL * B**2 / R**2
    omega_star, T = tau * B / (R * c), _yaw_inertia(robot) / (4 * c)
    assert omega_star < 0.75 * tau * B / (R * fn * k * A**2)  # (the dampers matter)
    traj = simulate(robot, 0.3, robot.neutral(), np.zeros(3), Constant([-tau, tau, -tau, tau]), n_out=31,
                    rtol=1e-10, atol=1e-12, progress=False)
    assert traj.stats["engine"].startswith("compiled")
    assert 0.3 > 2 * T  # (the approach, not only the start)
    closed = omega_star * (1 - np.exp(-traj.t / T))
    assert np.max(np.abs(traj.column("yaw_dot") - closed)) < 1e-6 * omega_star
    closed_work = -4 * D_LATERAL * (B / R) ** 2 * omega_star**2 * (
        traj.t - 2 * T * (1 - np.exp(-traj.t / T)) + T / 2 * (1 - np.exp(-2 * traj.t / T)))
    np.testing.assert_allclose(traj.damper_work, closed_work, rtol=0, atol=1e-6 * abs(closed_work[-1]))


def test_stiff_and_cvode_methods_refuse_slipping_wheels_in_one_line():
    """rosenbrock4 (and CVODE) locate no lift-off of slipping wheels: refused in one line naming the methods that
    do (rosenbrock4 used to end in the extension's bare ValueError)."""
    from robotdyn.errors import RobotDynError

    for robot in (_rover(), read(EXAMPLES / "skid_steer.toml").robot()):
        for method in ("rosenbrock4", "cvode"):
            with pytest.raises(RobotDynError, match=f"method '{method}' does not run slipping wheels.*expected one "
                                                    "of adams, bulirsch_stoer, dopri5$") as info:
                _run(robot, "auto", 0.01, np.zeros(7), Constant(np.zeros(4)), method=method)
            assert "\n" not in str(info.value)


def test_the_cli_simulates_a_damped_skid_steer_compiled(capsys, husky_files):
    import json

    from robotdyn.cli import main

    argv = ["simulate", "--constraints", str(husky_files / "damped.toml"), "--scenario", "turn_in_place",
            "--t-end", "0.05", "--quiet", "--json"]
    assert main(argv) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["engine"].startswith("compiled") and not data.get("engine_reason")
