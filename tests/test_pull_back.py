"""The holonomic pull-back (robotdyn.reduction.pull_back) on rows a planar root cannot move (issue 14, item 1).

Fixture: tests/data/tilted_axles.urdf, a differential drive whose wheel joints use ROS's rounded rpy="-1.57 0 0",
so each axle is tilted by eps = pi/2 - 1.57 = 7.96e-4 rad and the lowest rim point lies
r (1 - cos eps) = 3.17e-8 m above the ground (closed form) -- within the 1e-6 constraint check, on a wheel's normal
row, which a planar root (x, y, psi) cannot change: its Jacobian is round-off (~1e-24). A plain least-squares
pull-back turned that into corrections ~1e16 and "integration failed at t = 0". The same with an exact axle and a
radius off by 1e-7 m."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from robotdyn.fast.dispatch import use_compiled
from robotdyn.errors import ConstraintError
from robotdyn.reduction.pull_back import RANK_TOL, correction, offsets
from robotdyn.robot import MotorSpec, Robot, RobotSpec, Wheel
from robotdyn.simulation.engine import simulate
from robotdyn.constraints.terrain import RampTerrain

TILTED = Path(__file__).parent / "data" / "tilted_axles.urdf"
R = 0.1
EPS = np.pi / 2 - 1.57


def drive(tmp_path=None, radius: float = R, exact: bool = False, terrain=None) -> Robot:
    """The fixture's differential drive (``exact``: axles at rpy = -pi/2 exactly, written to tmp_path)."""
    path = TILTED
    if exact:
        path = tmp_path / "exact_axles.urdf"
        path.write_text(TILTED.read_text().replace('rpy="-1.57 0 0"', f'rpy="{-np.pi / 2!r} 0 0"'))
    spec = RobotSpec(name="tilted", title="differential drive, tilted axles", xacro=path, root="planar",
                     wheels=[Wheel("wheel_l", radius, axis=(0, 0, 1)), Wheel("wheel_r", radius, axis=(0, 0, 1))],
                     motors=[MotorSpec("ml", "wheel_l_joint"), MotorSpec("mr", "wheel_r_joint")])
    return Robot(spec, terrain=terrain)


def torque(t, q, nu):
    return np.array([0.1, 0.2 * np.cos(t)])


@pytest.mark.parametrize("compiled", [True, False])
def test_tilted_axles_simulate_with_the_offset_reported(compiled, capsys):
    robot = drive()
    offset = R * (1 - np.cos(EPS))  # the lowest rim point's height, closed form
    q0 = robot.neutral()
    assert np.allclose(robot.constraint_residual(q0), offset, rtol=1e-6, atol=0)
    with use_compiled(compiled):
        traj = simulate(robot, 2.0, q0, np.zeros(2), torque, n_out=201, progress=False)
        free = simulate(robot, 2.0, q0, np.zeros(2), torque, n_out=201, stabilisation=0.0, progress=False)
    assert traj.t[-1] == 2.0 and np.all(np.isfinite(traj.q))
    assert set(traj.stats["offsets"]) == {"wheel_l.normal", "wheel_r.normal"}
    assert np.allclose(list(traj.stats["offsets"].values()), offset, rtol=1e-6, atol=0)
    assert "wheel_l.normal 3.17e-08" in capsys.readouterr().err  # reported once, by name
    # nothing correctable: the pull-back leaves the motion exactly as without it, and the offset stays constant
    assert np.array_equal(traj.q, free.q) and np.array_equal(traj.nu, free.nu)
    assert np.allclose(traj.residual, offset, rtol=1e-6, atol=0)


def test_tilted_axles_move_as_exact_ones_to_first_order(tmp_path):
    """The tilt changes the motion by O(eps) (the effective radius r cos eps): the trajectories of the tilted and
    the exact drive differ by less than 1e-2 relative, and energy balance holds on the tilted one."""
    tilted, exact = drive(), drive(tmp_path, exact=True)
    runs = [simulate(r, 2.0, r.neutral(), np.zeros(2), torque, n_out=201, progress=False) for r in (tilted, exact)]
    scale = np.max(np.abs(runs[1].q))
    assert np.max(np.abs(runs[0].q - runs[1].q)) < 10 * EPS * scale


def test_radius_offset_reported(tmp_path, capsys):
    robot = drive(tmp_path, radius=R + 1e-7, exact=True)
    traj = simulate(robot, 1.0, robot.neutral(), np.zeros(2), torque, n_out=11, progress=False)
    assert np.allclose(list(traj.stats["offsets"].values()), -1e-7, rtol=1e-6, atol=0)
    assert traj.t[-1] == 1.0


def test_nearly_rank_deficient_rows_named_in_one_line():
    """On a 1e-8 slope the planar root's x changes the wheels' heights, but only by 1e-8 per metre: removing the
    3e-8 m offset would drag the robot 3 m. That is refused in one line naming the rows."""
    robot = drive(terrain=RampTerrain(1e-8))
    for compiled in (True, False):
        with use_compiled(compiled), pytest.raises(ConstraintError) as err:
            simulate(robot, 1.0, robot.neutral(), np.zeros(2), torque, progress=False)
        msg = str(err.value)
        assert "\n" not in msg and "wheel_l.normal" in msg and "pull-back cannot work" in msg
    traj = simulate(robot, 0.5, robot.neutral(), np.zeros(2), torque, n_out=11, stabilisation=0.0, progress=False)
    assert abs(traj.q[-1, 0]) < 0.1  # without the pull-back the robot is not dragged


def test_correction_is_the_truncated_pseudo_inverse():
    rng = np.random.default_rng(3)
    A = rng.normal(size=(3, 6))
    phi = rng.normal(size=3)
    assert np.allclose(correction(A, phi), np.linalg.lstsq(A, phi, rcond=None)[0], atol=1e-14)
    assert offsets(A, phi, ["a", "b", "c"]) == {}
    # a row of round-off: its residual is an offset, the others are corrected as if it were absent
    B = np.vstack([A[:2], 1e-24 * rng.normal(size=6)])
    dq = correction(B, phi)
    assert np.allclose(dq, np.linalg.lstsq(A[:2], phi[:2], rcond=None)[0], atol=1e-14)
    found = offsets(B, phi, ["a", "b", "c"])
    assert list(found) == ["c"] and found["c"] == pytest.approx(phi[2], abs=1e-12)
    # a row that is a combination of others keeps rank: nothing is dropped below the tolerance
    C = np.vstack([A[:2], A[0] + A[1] + 10 * RANK_TOL * rng.normal(size=6)])
    assert offsets(C, C @ rng.normal(size=6), ["a", "b", "c"]) == {}


def test_compiled_pull_back_on_the_columns_rows_move():
    """The compiled pull-back (robotdyn/kernels/pull_back.hpp) decomposes A_h on its columns that are not exactly zero
    only. The linkage rover's A_h (22 holonomic rows, 25 coordinates) has such columns: coordinates that enter no
    holonomic row. Off its closures (psi + 0.03 rad: residuals above 1e-3) at gain 10, q-dot minus v is -10 dq with
    dq = A_h^+ phi (the Python path's truncated pseudo-inverse, to 1e-10 of its largest entry), and exactly zero on
    those columns (q-dot there is v, bit for bit), where the pseudo-inverse has no component either."""
    import robotdyn
    from robotdyn.fast import dispatch
    from robotdyn.fast.dispatch import compiled_model

    if not dispatch.enabled():
        pytest.skip("the compiled fast path is off")
    robot = robotdyn.load("linkage_suspension")
    q = robot.neutral().copy()
    q[robot.coordinates.index("psi")] += 0.03
    nu, tau = np.array([0.3, -0.2]), np.zeros(len(robot.motors))
    with use_compiled(False):
        red = robot.reduced(q, nu)
    fast = compiled_model(robot)
    fast.select(red.projection)
    out = fast.evaluate(q, nu)
    A, residual, hol = out[7], out[8], np.asarray(fast.holonomic, bool)
    A_h, phi = A[hol], residual[hol]
    assert np.abs(phi).max() > 1e-3
    unmoved = ~np.any(A_h != 0.0, axis=0)
    assert unmoved.sum() >= 1 and (~unmoved).sum() >= A_h.shape[0] // 2
    plain, pulled = fast.rhs(q, nu, tau, 0.0), fast.rhs(q, nu, tau, 10.0)
    n = robot.nq
    assert np.array_equal(pulled[:n][unmoved], plain[:n][unmoved])
    assert np.array_equal(pulled[n:], plain[n:])
    dq = correction(A_h, phi)  # the Python path's truncated pseudo-inverse (an SVD)
    assert np.abs(dq).max() > 1e-4 and np.abs(dq[unmoved]).max() <= 1e-15 * np.abs(dq).max()
    assert np.abs((plain[:n] - pulled[:n]) / 10.0 - dq).max() <= 1e-10 * np.abs(dq).max()
