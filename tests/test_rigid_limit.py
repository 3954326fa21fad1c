"""Loads that rigid-body dynamics leave open, fixed by the rigid limit of the wheels' normal compliance
(robotdyn/contact/rigid_limit.py, issue 23), against independent references.

The chassis: examples/jackal_like.urdf.xacro (and husky_like), a rigid box on four wheels at (+-a, +-b) from
base_link (a = wheelbase / 2, b = track / 2), on flat ground, at rest. W = m g is the whole robot's weight and
(x_c, y_c) its centre of mass (Pinocchio's centerOfMass, not robotdyn's forces).

Closed form of a rigid body on four linear springs (derived here). The chassis' small displacement u = (w, th_x,
th_y) compresses spring i by d_i = w + y_i th_x - x_i th_y; N_i = k_i d_i; equilibrium: sum N_i = W,
sum y_i N_i = W y_c, sum x_i N_i = W x_c.

- Equal k: sum N = 4 k w, sum y N = 4 k b^2 th_x, sum x N = -4 k a^2 th_y (the cross sums vanish), so
  N_i = W/4 (1 + x_i x_c / a^2 + y_i y_c / b^2).
- Front pair k_f, rear pair k_r: heave and pitch involve the axle totals only, which statics fix:
  N_f = W (a + x_c) / (2a), N_r = W (a - x_c) / (2a). Roll: sum y N = 2 b^2 (k_f + k_r) th_x = W y_c, and each
  axle's left-right difference is 2 k b th_x, so the roll moment is shared by the axles in proportion to their
  stiffness (the vehicle engineer's roll-stiffness distribution):
  N_{FL,FR} = N_f / 2 +- k_f W y_c / (2 b (k_f + k_r)), N_{RL,RR} = N_r / 2 +- k_r W y_c / (2 b (k_f + k_r)).
- Warp (equal k): a wheel raised by h (FL on a block) adds d = h to that spring only; the compatible correction
  must carry no net force or moment, i.e. along the warp mode (+1, -1, -1, +1) for (FL, FR, RL, RR): with
  N = k (J u + h e_FL) and J^T N = 0 for the correction, u cancels the part of h e_FL in range(J), leaving
  k h (e_FL . v) v / |v|^2 with v = (1, -1, -1, 1): +-k h / 4 diagonally. Past h* = 4 min(N_FR, N_RL) / k the
  lighter of FR, RL is unloaded and the chassis rests on three wheels: their loads are statics' alone.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from robotdyn.contact.contact_forces import constraint_forces
from robotdyn.contact.rigid_limit import MODEL, normal_map, split
from robotdyn.interfaces.constraint_file import read
from robotdyn.robot import Robot

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
G = 9.81
NAMES = ("front_left", "front_right", "rear_left", "rear_right")


def rolling(name: str, xacro_args: dict | None = None, stiffness: dict | None = None) -> Robot:
    """The example with wheels that roll without slipping (its friction law dropped), optional xacro arguments
    (centre of mass) and per-wheel normal stiffnesses."""
    spec = read(EXAMPLES / f"{name}.toml").SPEC
    wheels = [replace(w, friction="rolling", slip_velocity=None, normal_stiffness=(stiffness or {}).get(w.name))
              for w in spec.wheels]
    return Robot(replace(spec, wheels=wheels, independent=None, xacro_args={**spec.xacro_args, **(xacro_args or {})}))


def geometry(robot: Robot) -> tuple[float, float, float, float, float]:
    """(W, x_c, y_c, a, b) by Pinocchio at the neutral configuration."""
    q = robot.neutral()
    data = robot.model.createData()
    c = pin.centerOfMass(robot.model, data, q)
    W = float(data.mass[0]) * G
    pin.framesForwardKinematics(robot.model, data, q)
    fl = data.oMf[robot.model.getFrameId("front_left_wheel_link")].translation
    return W, float(c[0]), float(c[1]), float(fl[0]), float(fl[1])


def normals(robot: Robot, **kw) -> np.ndarray:
    f = constraint_forces(robot, robot.neutral(), np.zeros(robot.mobility), tau=np.zeros(len(robot.motors)), **kw)
    return np.array([f.wheel(n).normal for n in NAMES]), f


COM = {"com_x": "0.05", "com_y": "0.03"}


def test_equal_stiffness_equals_the_closed_form():
    robot = rolling("jackal_like", COM)
    W, xc, yc, a, b = geometry(robot)
    assert abs(xc) > 0.02 and abs(yc) > 0.01  # an offset centre of mass
    x = np.array([a, a, -a, -a])
    y = np.array([b, -b, b, -b])
    expected = W / 4 * (1 + x * xc / a**2 + y * yc / b**2)
    got, f = normals(robot)
    np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-9)
    assert all(w.source == MODEL and w.compliance[2] and not w.determined[2] for w in f.wheels)
    assert "rigid limit of compliance" in f.table()


def test_unequal_stiffness_shares_the_roll_moment_by_axle_stiffness():
    kf, kr = 3.0e5, 1.0e5
    robot = rolling("jackal_like", COM, {"front_left": kf, "front_right": kf, "rear_left": kr, "rear_right": kr})
    W, xc, yc, a, b = geometry(robot)
    Nf, Nr = W * (a + xc) / (2 * a), W * (a - xc) / (2 * a)
    roll_f, roll_r = kf * W * yc / (2 * b * (kf + kr)), kr * W * yc / (2 * b * (kf + kr))
    expected = np.array([Nf / 2 + roll_f, Nf / 2 - roll_f, Nr / 2 + roll_r, Nr / 2 - roll_r])
    got, _ = normals(robot)
    np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-9)
    equal, _ = normals(rolling("jackal_like", COM))
    assert np.max(np.abs(got - equal)) > 0.1  # unequal stiffnesses give another split (not the minimum norm)


def test_warp_shifts_load_diagonally_until_a_wheel_unloads():
    """One wheel (FL) raised by h: +-k h / 4 diagonally, then three-wheel statics (module docstring)."""
    robot = rolling("jackal_like", COM)
    W, xc, yc, a, b = geometry(robot)
    base, f = normals(robot)
    rows = [np.array(idx) for idx, _, _ in f._tangential]
    C = normal_map(rows, [D for _, D, _ in f._tangential], len(f.lam))
    k = 1.0e5
    raw = constraint_forces(robot, robot.neutral(), np.zeros(robot.mobility), compliance=False)
    h_star = 4 * min(base[1], base[2]) / k
    for h in (0.25 * h_star, 0.9 * h_star):
        res = split(raw.lam, raw.null_space, C, np.full(4, k), raw.determined, offset=[h, 0, 0, 0])
        np.testing.assert_allclose(C @ res.lam - base, k * h / 4 * np.array([1, -1, -1, 1]), atol=1e-8)
    res = split(raw.lam, raw.null_space, C, np.full(4, k), raw.determined, offset=[2 * h_star, 0, 0, 0])
    loads = C @ res.lam
    light = 1 if base[1] < base[2] else 2
    assert res.unloaded == [light] and abs(loads[light]) < 1e-9
    x = np.array([a, a, -a, -a])
    y = np.array([b, -b, b, -b])
    three = [i for i in range(4) if i != light]
    statics = np.linalg.solve(np.vstack([np.ones(3), x[three], y[three]]), W * np.array([1.0, xc, yc]))
    np.testing.assert_allclose(loads[three], statics, rtol=1e-9)


def _stiff_statics(robot: Robot, k: float) -> np.ndarray:
    """The loads of the chassis resting on four linear springs of stiffness k under its wheels' lowest points
    (a direct static solve, independent of robotdyn's forces): unknowns z, pitch, roll; spring i pressed by its
    wheel's penetration p_i = r sqrt(1 - a_z^2) - c_z (c: wheel centre, a: axle in world axes); equilibrium of
    the whole robot: vertical force and the moments about its centre of mass of the vertical spring forces."""
    from scipy.optimize import fsolve

    model, data = robot.model, robot.model.createData()
    radius = 0.098
    iz, ip, ir = (robot.coordinate_index(c) for c in ("z", "pitch", "roll"))
    frames = [model.getFrameId(f"{n}_wheel_link") for n in NAMES]
    W = float(pin.computeTotalMass(model)) * G

    def loads(u):
        q = robot.neutral()
        q[iz], q[ip], q[ir] = u
        pin.framesForwardKinematics(model, data, q)
        c = pin.centerOfMass(model, data, q)
        out, points = [], []
        for fid in frames:
            M = data.oMf[fid]
            axle = M.rotation @ np.array([0.0, 1.0, 0.0])
            low = M.translation[2] - radius * math.sqrt(1 - axle[2] ** 2)
            out.append(k * max(-low, 0.0))
            points.append(M.translation[:2])  # the lowest point lies below the centre to first order
        return np.array(out), np.array(points), c

    def residual(u):
        n, p, c = loads(u)
        return [(n.sum() - W) / W, n @ (p[:, 0] - c[0]) / W, n @ (p[:, 1] - c[1]) / W]

    u = fsolve(residual, [radius - W / (4 * k), 0.0, 0.0], xtol=1e-14)
    return loads(u)[0]


def test_compliant_loads_converge_to_the_rigid_limit():
    """A direct stiff-spring static solve: its loads differ from the rigid limit's by O(1/k) (the chassis tilts
    by O(W / (k a)), moving the contact points), and the difference times k stays bounded."""
    robot = rolling("jackal_like", COM)
    rigid, _ = normals(robot)
    errors = [np.max(np.abs(_stiff_statics(robot, k) - rigid)) for k in (1e4, 1e5, 1e6)]
    assert errors[2] < 1e-3 * rigid.max()
    assert errors[0] > errors[1] > errors[2]
    assert 50 < errors[0] / errors[2] < 200  # first order: 100 (k times the error ~ 2030 N^2/m here)


def test_rigid_determined_combinations_unchanged_to_1e9():
    """At a moving, driven state: every combination c^T lambda with c in range(A) (those rigid-body dynamics
    determine: c orthogonal to the null space of A^T), the rows flagged determined, the total and axle loads,
    equal the minimum-norm values of today to 1e-9."""
    robot = rolling("husky_like", {"com_x": "0.04", "com_y": "-0.02"}, {"front_left": 4.0e5, "rear_left": 1.0e5})
    q = robot.neutral()
    nu = np.array([0.8, 1.3, -0.7, 0.9, 1.1])[: robot.mobility]
    tau = np.array([3.0, -1.0, 2.0, 0.5])
    new = constraint_forces(robot, q, nu, tau=tau)
    old = constraint_forces(robot, q, nu, tau=tau, compliance=False)
    N = old.null_space
    assert N.shape[1] >= 1 and new.compliance.any()
    U = np.linalg.svd(N, full_matrices=True)[0][:, N.shape[1]:]  # orthonormal complement: range(A)
    scale = max(1.0, np.max(np.abs(old.lam)))
    np.testing.assert_allclose(U.T @ new.lam, U.T @ old.lam, atol=1e-9 * scale)
    assert np.array_equal(new.lam[old.determined], old.lam[old.determined])
    total = lambda f: sum(w.normal for w in f.wheels)  # noqa: E731
    assert total(new) == pytest.approx(total(old), abs=1e-9 * scale)
    assert not np.allclose(new.lam, old.lam)  # the split itself did change (equal stiffnesses: the minimum norm)


def test_pulling_wheel_carries_zero():
    """A centre of mass far beyond the FL-RR diagonal: the compatible loads would pull on RR; the rigid limit
    unloads it and the other three carry statics' own loads."""
    robot = rolling("jackal_like", {"com_x": "0.10", "com_y": "0.16"})
    W, xc, yc, a, b = geometry(robot)
    x = np.array([a, a, -a, -a])
    y = np.array([b, -b, b, -b])
    assert np.min(W / 4 * (1 + x * xc / a**2 + y * yc / b**2)) < 0  # the unconstrained split pulls
    got, f = normals(robot)
    assert f.unloaded == ["rear_right"] and abs(got[3]) < 1e-9
    statics = np.linalg.solve(np.vstack([np.ones(3), x[:3], y[:3]]), W * np.array([1.0, xc, yc]))
    np.testing.assert_allclose(got[:3], statics, rtol=1e-9)
    assert "unloaded (would pull): rear_right" in f.table()


CAR = """name = "rigid_car"
urdf = "{urdf}"
root = "floating"
neutral = {{ z = 0.165 }}
{wheels}
[[motors]]
name = "tau_rl"
joint = "rear_left_wheel"
[[motors]]
name = "tau_rr"
joint = "rear_right_wheel"
[[scenarios]]
name = "drive"
t_end = 0.05
torque = [{tau}, {tau}]
"""


def _car_mu(robot: Robot, tau: float) -> float:
    """The rear (driven) wheels' required mu of a rigid four-wheel car driven straight from rest by tau on each
    rear wheel, in closed form (derived here). Whole robot: mass m, weight W, centre of mass x_c ahead of the
    axles' middle at height z_c, wheelbase L = 2a, wheel radius r and spin inertia I_w. Rolling straight:
    m acc = 2 F_r + 2 F_f with the wheels' spin balances F_r = tau / r - I_w acc / r^2, F_f = -I_w acc / r^2, so
    acc = 2 tau / r / (m + 4 I_w / r^2). Moments about the rear contact line (the friction forces act on it): the
    weight W (a + x_c) against the front loads 2 N_f L equals the rate of angular momentum m acc z_c + 4 I_w acc / r
    (the chassis' and the wheels' spin), so N_f = (W (a + x_c) - m acc z_c - 4 I_w acc / r) / (2 L) and
    N_r = W / 2 - N_f. The lateral forces are open but nothing asks for them (a straight run): the best split
    needs none, so the smallest mu is F_r / N_r (the front wheels need far less)."""
    model = robot.model
    data = model.createData()
    q = robot.neutral()
    c = pin.centerOfMass(model, data, q)
    m = float(data.mass[0])
    W, xc, zc = m * G, float(c[0]), float(c[2])
    _, _, _, a, _ = geometry(robot)
    r = 0.165
    Iw = float(model.inertias[model.getJointId("rear_left_wheel")].inertia[1, 1])
    acc = 2 * tau / r / (m + 4 * Iw / r**2)
    Nf = (W * (a + xc) - m * acc * zc - 4 * Iw * acc / r) / (4 * a)
    return (tau / r - Iw * acc / r**2) / (W / 2 - Nf)


def test_rigid_car_cannot_hold_below_the_smallest_mu(tmp_path, capsys):
    """A rigid four-wheel car (the Husky-like chassis, rear-wheel drive, wheels rolling): the torque at which its
    driven wheels need mu = 0.39 under every admissible split; the API's minimum mu equals the closed form, and
    simulate --mu 0.3 says it cannot hold (0.45: it holds)."""
    from scipy.optimize import brentq

    from robotdyn.cli.commands import main

    wheels = "".join(f'[[wheels]]\nname = "{n}"\njoint = "{n}_wheel"\nradius = 0.165\n' for n in NAMES)
    urdf = EXAMPLES / "husky_like.urdf.xacro"
    path = tmp_path / "car.toml"
    path.write_text(CAR.format(urdf=urdf, wheels=wheels, tau=1.0))
    robot = read(path).robot()
    tau = brentq(lambda t: _car_mu(robot, t) - 0.39, 0.1, 50.0, xtol=1e-12)
    f = robot.contact_forces(robot.neutral(), np.zeros(robot.mobility), tau=[tau, tau])
    assert f.minimum_mu() == pytest.approx(0.39, rel=1e-6)
    assert not f.wheel("rear_left").determined[1] and f.wheel("rear_left").source == MODEL
    path.write_text(CAR.format(urdf=urdf, wheels=wheels, tau=tau))
    assert main(["simulate", "--constraints", str(path), "--scenario", "drive", "--mu", "0.3", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "no admissible split of the open forces stays within mu" in out and "assumption holds" not in out
    assert main(["simulate", "--constraints", str(path), "--scenario", "drive", "--mu", "0.45", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "no-slip assumption holds" in out and "rigid limit of compliance" in out


def test_compiled_forces_give_the_rigid_limit():
    """CompiledModel.forces (C++) splits the open loads as constraint_forces (Python) does, at a moving, driven
    state with unequal stiffnesses; rigid_limit(False) returns the basic solution (another split, the same
    determined rows)."""
    from robotdyn.fast.dispatch import compiled_model

    robot = rolling("husky_like", {"com_x": "0.04", "com_y": "-0.02"}, {"front_left": 4.0e5, "rear_left": 1.0e5})
    fast = compiled_model(robot)
    if fast is None or not hasattr(fast.ev, "set_rigid_limit"):
        pytest.skip("no compiled model with the rigid limit")
    q = robot.neutral()
    nu = np.array([0.8, 0.9, 1.1, 0.7, 1.2])[: robot.mobility]
    tau = np.array([3.0, -1.0, 2.0, 0.5])
    ref = constraint_forces(robot, q, nu, tau=tau)
    local = np.array(fast.forces(q, nu, tau)[3])
    scale = max(1.0, float(np.max(np.abs(local))))
    np.testing.assert_allclose(local[:, 2], [w.normal for w in ref.wheels], atol=1e-9 * scale)
    fast.rigid_limit(False)
    try:
        basic = np.array(fast.forces(q, nu, tau)[3])
    finally:
        fast.rigid_limit(True)
    assert np.max(np.abs(basic[:, 2] - local[:, 2])) > 1.0
    assert np.sum(basic[:, 2]) == pytest.approx(np.sum(local[:, 2]), abs=1e-9 * scale)


def test_traction_fast_pass_equals_the_reference_with_open_loads():
    """The fast traction pass (robotdyn/contact/traction_fast.py) splits the open loads as constraint_forces does,
    sample by sample: loads, required and minimum mu, and names the model."""
    from robotdyn.contact.traction import traction

    robot = rolling("jackal_like", COM, {"front_left": 2.0e5})
    torque = lambda t, q, nu: np.array([0.4, 0.6, 0.4, 0.6])  # noqa: E731
    traj = simulate_short(robot, torque)
    fast = traction(robot, traj, torque, mu=0.8)
    ref = traction(robot, traj, torque, mu=0.8, method="reference")
    assert fast.method == "fast" and ref.method == "reference" and fast.wheels == list(NAMES)
    np.testing.assert_allclose(fast.normal, ref.normal, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(fast.minimum_mu, ref.minimum_mu, rtol=1e-7, atol=1e-12)
    assert fast.compliance == ref.compliance == list(NAMES)
    assert "rigid limit of compliance" in fast.summary()


def simulate_short(robot, torque):
    from robotdyn.simulation.engine import simulate

    return simulate(robot, 0.2, robot.neutral(), np.zeros(robot.mobility), torque, n_out=21, progress=False)
