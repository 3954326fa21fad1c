"""A four-wheel car in a steady turn (examples/cornering_car.toml: the car of examples/sprung_car.urdf.xacro with its
suspensions held, front wheels steered by the Ackermann pair, every wheel rolling without slipping) against closed
forms derived here. Symbols (the xacro's defaults): chassis mass m_c = 1200 kg with its centre of mass G_c at
h_c = 0.55 m, four uprights (25 kg) and wheels (15 kg, radius r = 0.3 m, spin inertia I_w = 0.6 kg m^2) with their
centres at height r, axles at x_f = lf = 1.1 m and x_r = -lr = -1.5 m (wheelbase L = lf + lr), half track b = 0.75 m
(track t = 2b), chassis axes x forward, y left, origin at G_c.

Ackermann geometry. With tan(delta_l) = L / (R - b), tan(delta_r) = L / (R + b) every wheel's axle points at the
point C = (x_r, R) (chassis axes): the only motion without slip is the rotation about the vertical through C at a
yaw rate w, the rear axle's midpoint moving at v = w R along x (the independent velocity of the example), so
w = v / R; each wheel centre i moves at w rho_i perpendicular to C - p_i (rho_i its distance from C) and spins at
w rho_i / r; the material point of each wheel at its contact has zero velocity.

Total load transfer (rigid-body dynamics determine it). Every body i moves on a circle about C at constant w: its
acceleration is a_i = w^2 (C - p_i) (horizontal); the chassis and uprights turn about their principal z axes
(constant angular momentum); a wheel's angular momentum I_w (s_i / r) y_i + I_d w z (spin s_i / r about its axle
y_i) turns with the car, dH_i/dt = w z x I_w (s_i / r) y_i = -I_w w (s_i / r) x_i. The moment balance of the whole
car about the longitudinal axis through the ground below G_c (contact forces act at z = 0, so only the normal
loads N at y = +-b have a moment about it):

    b (N_L - N_R) = sum_i m_i (y_i (a_z,i + g) - z_i a_y,i) + sum_wheels (dH_i/dt)_x,

with a_y,i = w^2 (R - y_i), a_z,i = 0, sum_i m_i y_i = sum_i m_i z_i y_i = 0 (a symmetric car) and
(s_i / r) cos(delta_i) = w (R - y_i) / r (the wheel centre's forward velocity over r), summing to 4 w R / r:

    N_R - N_L = w^2 R (m h_G + 4 I_w / r) / b,  i.e.  Delta F = (N_R - N_L) / 2 = (m h_G + 4 I_w / r) v^2 / (R t),

m h_G = sum_i m_i z_i: the textbook m v^2 h / (R t) plus the wheels' gyroscopic term. The same balance about the
lateral axis through the ground, with a_x,i = -w^2 (lr + x_i), the gravity moment g sum_i m_i x_i and
(dH_i/dt)_y = -I_w w (s_i / r) sin(delta_i) (s_i sin(delta_i) = w L for a front wheel, 0 for a rear one), gives the
front axle's load N_f (the rear's N_r = m g - N_f):

    x_f N_f + x_r (m g - N_f) = g sum_i m_i x_i + w^2 sum_i m_i z_i (lr + x_i) + 2 I_w w^2 L / r.

Split between the axles (rigid-body statics leave it open: the warp (+1, -1, -1, +1) of the four loads is a self-
equilibrated set). The rigid limit of the tyres' normal compliance (robotdyn.contact.rigid_limit) minimises the
complementary energy sum N_i^2 / (2 k_i) over that family: d/ds sum (N_i + s w_i)^2 / (2 k_i) = 0 with the warp w
gives (N_FL - N_FR) / k_f = (N_RL - N_RR) / k_r, so the front axle carries the share

    (N_FR - N_FL) / (N_R - N_L) = k_f / (k_f + k_r)

of the transfer: each axle's roll stiffness is 2 k b^2 (equal tracks), so this is the roll stiffness distribution
(1/2 for equal tyres). These must hold to 1e-9 (they are exact); the total also equals the one rigid-body dynamics
give without any split (the minimum-norm multipliers' combination, robotdyn's value before the rigid limit).

On springs (examples/sprung_cornering_car.toml: the same car on its vertical suspensions, spring k_f at each front
corner and k_r at each rear one, tyres sliding sideways under a stiff linear law), the car enters the turn upright,
rolls by phi and settles (dampers). Each wheel's load is its spring's force plus its corner's unsprung weight; the
suspensions are vertical sliders, so each wheel's instant centre relative to the chassis is at infinity sideways
and the roll centre is at the ground: the lateral forces pass into the chassis with no moment about the ground
axis, and the whole roll moment is carried by the springs. A roll phi compresses the outer spring of an axle by
b phi and extends the inner one by as much, so to first order in phi

    (N_FR - N_FL) / (N_R - N_L) = 2 k_f b phi / (2 k_f b phi + 2 k_r b phi) = K_f / (K_f + K_r),  K = 2 k b^2,

the roll stiffness distribution (2/3 for the example's k_f = 2 k_r, 1/2 for equal springs; the static weight
distribution lr / L = 0.58 would be the answer of a model that split the transfer like the weight). The terms left
out are of order phi times the left-right difference of an axle's lateral forces (the tilted sliders pass a share
sin(phi) of them to the wheels' loads) and the pitch: below 1e-3 of the share at phi = 3 degrees (measured 3e-4).
The roll angle itself follows the linear roll gradient phi = (m h_G + 4 I_w / r) a_y / (K_f + K_r - m_c g h_c)
(the roll moment of the module's balance, plus the chassis' weight leaning by phi, carried by the springs), with
a_y = w v from the simulated yaw rate w and forward speed v; within 4 % (the tyres' slip, sin phi against phi).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from robotdyn.interfaces.constraint_file import read
from robotdyn.reduction.joint_springs import JointSpring
from robotdyn.robot import Robot
from robotdyn.simulation.engine import simulate

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
LF, LR, B, R_W, H_C, I_W, G = 1.1, 1.5, 0.75, 0.3, 0.55, 0.6, 9.81
M_C, M_U, M_W = 1200.0, 25.0, 15.0
CORNERS = ("front_left", "front_right", "rear_left", "rear_right")


def _car(k_front: float | None = None, k_rear: float | None = None, radius: float | None = None):
    cf = read(EXAMPLES / "cornering_car.toml")
    spec = cf.SPEC
    if k_front is not None:
        stiff = {n: (k_front if n.startswith("front") else k_rear) for n in CORNERS}
        spec = replace(spec, wheels=[replace(w, normal_stiffness=stiff[w.name]) for w in spec.wheels])
    robot = Robot(spec, params={"turn_radius": radius} if radius is not None else None)
    return robot, cf.SCENARIOS["corner"]


def _closed_form(w: float, R: float) -> tuple[float, float]:
    """(N_R - N_L, N_f) of the module's closed forms at yaw rate w [rad/s] on radius R [m]."""
    m = M_C + 4 * (M_U + M_W)
    mh = M_C * H_C + 4 * (M_U + M_W) * R_W
    transfer = w**2 * R * (mh + 4 * I_W / R_W) / B
    L = LF + LR
    # sum_i m_i x_i (chassis at 0, two corners at each axle) and sum_i m_i z_i (lr + x_i)
    mx = 2 * (M_U + M_W) * (LF - LR)
    mzx = M_C * H_C * LR + 2 * (M_U + M_W) * R_W * L  # the rear corners' lr + x_i is 0
    front = (G * mx + w**2 * mzx + 2 * I_W * w**2 * L / R_W + LR * m * G) / L
    return transfer, front


def _loads(forces) -> dict[str, float]:
    return {wf.name: wf.normal for wf in forces.wheels}


@pytest.mark.parametrize("k_front, k_rear, radius", [(2.0e5, 2.0e5, None), (3.0e5, 2.0e5, None),
                                                     (1.0e5, 4.0e5, 60.0)])
def test_steady_turn_load_transfer(k_front, k_rear, radius):
    robot, sc = _car(k_front, k_rear, radius)
    R = radius if radius is not None else 30.0
    q0, nu0 = sc.initial_state(robot)
    v = float(nu0[0])
    w = v / R
    forces = robot.contact_forces(q0, nu0, tau=np.zeros(4))
    n = _loads(forces)
    assert all(wf.source == "rigid limit of compliance" for wf in forces.wheels)
    transfer, front = _closed_form(w, R)
    right_minus_left = n["front_right"] + n["rear_right"] - n["front_left"] - n["rear_left"]
    assert right_minus_left == pytest.approx(transfer, rel=1e-9)
    assert n["front_left"] + n["front_right"] == pytest.approx(front, rel=1e-9)
    m = M_C + 4 * (M_U + M_W)
    assert sum(n.values()) == pytest.approx(m * G, rel=1e-12)
    # the textbook term alone is not enough: the wheels' gyroscopic share is 4 I_w / (r m h_G) = 1.1 % of it
    assert abs(right_minus_left - w**2 * R * (M_C * H_C + 4 * (M_U + M_W) * R_W) / B) > 1e-3 * transfer
    # the rigid limit moves only what rigid-body dynamics leave open: the minimum-norm multipliers (no split
    # chosen) give the same total transfer
    Nsp = forces.null_space
    lam_mn = forces.lam - Nsp @ (Nsp.T @ forces.lam)
    rows = {lab: i for i, lab in enumerate(forces.labels)}
    mn = {c: lam_mn[rows[f"{c}.normal"]] for c in CORNERS}
    assert mn["front_right"] + mn["rear_right"] - mn["front_left"] - mn["rear_left"] == pytest.approx(
        right_minus_left, rel=1e-9)
    # the split: the front axle's share of the transfer is its share of the roll stiffness
    front_share = (n["front_right"] - n["front_left"]) / right_minus_left
    assert front_share == pytest.approx(k_front / (k_front + k_rear), rel=1e-9)
    # no wheel lifts: every load within the closed forms' range
    assert min(n.values()) > 0


def test_ackermann_turn_rolls_without_slip():
    robot, sc = _car()
    R = 30.0
    q0, nu0 = sc.initial_state(robot)
    v = float(nu0[0])
    w = v / R
    traj = simulate(robot, sc.t_end, q0, nu0, sc.torque, n_out=21, progress=False, rtol=1e-10, atol=1e-12)
    assert np.max(np.abs(traj.column("yaw") - w * traj.t)) < 1e-9  # steady yaw rate v / R
    assert np.max(np.abs(traj.nu[:, 0] - v)) < 1e-9  # coasting without loss: constant speed
    L = LF + LR
    centre = {"front_left": (L, B - R), "front_right": (L, -B - R), "rear_left": (0.0, B - R),
              "rear_right": (0.0, -B - R)}  # wheel centre minus the centre of the turn, chassis axes
    model, data = robot.model, robot.data
    for q, nu in zip(traj.q[::5], traj.nu[::5]):
        vel = robot.velocity(q, nu)
        pin.forwardKinematics(model, data, q, vel)
        pin.updateFramePlacements(model, data)
        for name in CORNERS:
            fid = model.getFrameId(f"{name}_wheel")
            centre_w = data.oMf[fid].translation
            twist = pin.getFrameVelocity(model, data, fid, pin.LOCAL_WORLD_ALIGNED)
            contact = twist.linear + np.cross(twist.angular, np.array([0.0, 0.0, -R_W]))
            assert np.max(np.abs(contact)) < 1e-9, name  # the material point at the contact does not slide
            assert centre_w[2] == pytest.approx(R_W, abs=1e-12)
            spin = vel[robot.coordinate_index(f"{name}_spin")]
            assert spin == pytest.approx(w * np.hypot(*centre[name]) / R_W, rel=1e-9)
        assert vel[robot.coordinate_index("yaw")] == pytest.approx(w, rel=1e-12)
    # steady loads along the run
    first, last = (_loads(robot.contact_forces(traj.q[i], traj.nu[i], tau=np.zeros(4))) for i in (0, -1))
    for name in CORNERS:
        assert last[name] == pytest.approx(first[name], rel=1e-9)


@pytest.mark.parametrize("k_front, k_rear", [(40000.0, 20000.0), (30000.0, 30000.0)])
def test_sprung_car_splits_the_transfer_by_roll_stiffness(k_front, k_rear):
    cf = read(EXAMPLES / "sprung_cornering_car.toml")
    spec = cf.SPEC
    if (k_front, k_rear) != (40000.0, 20000.0):  # the example's own; others: each spring preloaded by its share
        L = LF + LR
        preload = {"front": M_C * G * LR / L / 2, "rear": M_C * G * LF / L / 2}
        stiff = {"front": k_front, "rear": k_rear}
        spec = replace(spec, springs=[JointSpring(s.joint, stiff[s.joint.split("_")[0]], s.damping,
                                                  -preload[s.joint.split("_")[0]] / stiff[s.joint.split("_")[0]])
                                      for s in spec.springs])
    robot, sc = Robot(spec), cf.SCENARIOS["corner"]
    q0, nu0 = sc.initial_state(robot)
    traj = simulate(robot, 1.5, q0, nu0, sc.torque, n_out=4, progress=False)
    q, nu = traj.q[-1], traj.nu[-1]
    assert abs(traj.column("roll_dot")[-1]) < 2e-3  # settled (dampers): steady roll
    n = _loads(robot.contact_forces(q, nu, tau=np.zeros(4)))
    transfer = n["front_right"] + n["rear_right"] - n["front_left"] - n["rear_left"]
    share = (n["front_right"] - n["front_left"]) / transfer
    assert share == pytest.approx(k_front / (k_front + k_rear), rel=1e-3)
    # the roll gradient of linear theory
    c = robot.coordinates
    v = robot.velocity(q, nu)
    yaw, w = q[c.index("yaw")], v[c.index("yaw")]
    forward = np.cos(yaw) * v[c.index("x")] + np.sin(yaw) * v[c.index("y")]
    moment = (M_C * H_C + 4 * (M_U + M_W) * R_W + 4 * I_W / R_W) * w * forward
    phi = moment / (2 * (k_front + k_rear) * B**2 - M_C * G * H_C)
    assert q[c.index("roll")] == pytest.approx(phi, rel=0.04)
    assert q[c.index("roll")] > 0.04  # a real roll (to the outside of the left turn: positive about x)


def test_dump_prints_the_same_loads(capsys):
    """`robotdyn dump --forces` on the example, in the steady turn (12 m/s): the four loads of the closed forms (to
    the 6 digits printed), each reported as the rigid limit of compliance."""
    from robotdyn.cli.commands import main

    rc = main(["dump", "--constraints", str(EXAMPLES / "cornering_car.toml"), "--q", "0", "0", "0.55",
               *["0"] * 7, "--v", "12", "--tau", "0", "0", "0", "0", "--forces"])
    out = capsys.readouterr().out
    assert rc == 0
    rows = {line.split()[0]: line.split() for line in out.splitlines() if line.split()[:1] and
            line.split()[0] in CORNERS}
    transfer, front = _closed_form(12.0 / 30.0, 30.0)
    share = 3.0e5 / (3.0e5 + 2.0e5)  # the example's tyre stiffnesses
    m = M_C + 4 * (M_U + M_W)
    expected = {"front_left": front / 2 - share * transfer / 2, "front_right": front / 2 + share * transfer / 2,
                "rear_left": (m * G - front) / 2 - (1 - share) * transfer / 2,
                "rear_right": (m * G - front) / 2 + (1 - share) * transfer / 2}
    for name in CORNERS:
        assert float(rows[name][3]) == pytest.approx(expected[name], rel=1e-6), rows[name]
        assert "rigid limit of compliance" in " ".join(rows[name])
