"""Compliant wheels that roll while in contact (robotdyn.contact.compliant_rolling,
robotdyn.simulation.compliant_rolling) against closed forms, on the disc of tests/data/disc.urdf (planar root x, y,
psi; height z, lean about x, spin about the axle y; m = 2 kg, spin inertia I = 0.04 kg m^2, radius r = 0.3 m).

Sign convention: the spin w is about +y, x points forward, so the disc's material point at the contact moves at
v - r w along x (rolling forward: v = r w).

- Touch-down (a plastic tangential impact, no normal impulse from the compliant law): the contact impulse passes
  through the contact point, so the angular momentum about the contact point, L = m r v + I w, is conserved, and
  after it v1 = r w1:  v1 = (m r^2 v0 + I r w0) / (m r^2 + I). The energy lost is the kinetic energy of the stopped
  relative motion, (1/2) m_t (v0 - r w0)^2 with the tangential effective mass m_t = m I / (m r^2 + I) (direct
  check: 1/2 m v0^2 + 1/2 I w0^2 - 1/2 (m + I / r^2) v1^2 is the same number).
- The normal side is the damped oscillator of tests/test_compliant_contact.py (gravity off, linear law, zeta < 1/sqrt 2):
  the wheel's rows are dropped when its force k x + c x' returns to zero, at w_d t* = pi - atan2(2 zeta sqrt(1 -
  zeta^2), 1 - 2 zeta^2) after touch-down (the lift-off event of a rolling wheel is the force's zero), leaving at
  v_out = -x'(t*).
- A constant torque tau on the spin of a disc rolling on flat ground (gravity g, resting at its static deflection
  m g / k): m a = F, I alpha = tau - F r, a = r alpha, so a = r tau / (I + m r^2) and the traction force is
  F = m r tau / (I + m r^2): required mu = F / (m g), at every sample.
- Energy at every sample: E(t) - E(0) = motor work + damper work - the touch-down losses so far.
- The rigid limit: the rolling compliant disc over a bump converges to the rigid rolling disc as k grows: the
  velocity error falls at least like 1/k (measured x4 in k: error / 7.4, / 6.4), the height error is the static
  deflection m g / k.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from robotdyn.robot import MotorSpec, Parameter, Robot, RobotSpec, Wheel
from robotdyn.simulation.engine import simulate
from robotdyn.simulation.torque_profile import Constant

DISC = Path(__file__).parent / "data" / "disc.urdf"
M, I, R = 2.0, 0.04, 0.3  # tests/data/disc.urdf's mass and spin inertia (iyy); the wheel radius


def disc(g: float = 0.0, motors=(), terrain=None, **contact) -> Robot:
    wheel = Wheel("disc", R, contact="compliant", **contact)  # friction = "rolling" (the default): rolls in contact
    spec = RobotSpec(name="disc", title="rolling compliant disc", xacro=DISC, root="planar", wheels=[wheel],
                     parameters=[Parameter("g", g, "m/s^2", xacro=False)], motors=list(motors))
    return Robot(spec, terrain=terrain)


def state(robot, z: float, vz: float = 0.0, vx: float = 0.0, w: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    q = np.zeros(robot.nq)
    q[robot.coordinate_index("z")] = z
    nu = np.zeros(robot.mobility)
    for name, value in (("z_dot", vz), ("x_dot", vx), ("spin_dot", w)):
        nu[robot.velocity_names.index(name)] = value
    return q, nu


def events(traj, kind: str) -> list[dict]:
    return [e for e in traj.stats["flight"] if e["event"] == kind]


@pytest.mark.parametrize("v0, w0", [(2.0, 1.0), (1.0, -4.0)])  # top spin short of rolling; back spin
def test_touch_down_conserves_angular_momentum_about_the_contact(v0, w0):
    k, zeta, v_in, gap = 2.0e4, 0.3, 1.0, 0.01
    c = 2 * zeta * np.sqrt(k * M)
    robot = disc(normal_stiffness=k, normal_damping=c)
    q0, nu0 = state(robot, R + gap, -v_in, v0, w0)
    traj = simulate(robot, 0.06, q0, nu0, n_out=7, rtol=1e-10, atol=1e-13, progress=False)
    v1 = (M * R**2 * v0 + I * R * w0) / (M * R**2 + I)
    lost = 0.5 * M * I / (M * R**2 + I) * (v0 - R * w0) ** 2
    assert lost == pytest.approx(0.5 * M * v0**2 + 0.5 * I * w0**2 - 0.5 * (M + I / R**2) * v1**2, rel=1e-12)
    down, up = events(traj, "touch-down"), events(traj, "lift-off")
    assert [e["t"] for e in down] == pytest.approx([gap / v_in], abs=1e-9)
    assert down[0]["loss"] == pytest.approx(lost, rel=1e-10)
    assert down[0]["slip"] == pytest.approx(abs(v0 - R * w0), rel=1e-10)
    # rolling from the touch-down on, in contact and in flight (no tangential force on a free disc)
    assert traj.column("x_dot")[-1] == pytest.approx(v1, rel=1e-9)
    assert R * traj.column("spin_dot")[-1] == pytest.approx(v1, rel=1e-9)
    # the normal side: the damped oscillator, its rows dropped where the force returns to zero
    wn = np.sqrt(k / M)
    s, wd = zeta * wn, wn * np.sqrt(1 - zeta**2)
    theta = np.pi - np.arctan2(2 * zeta * np.sqrt(1 - zeta**2), 1 - 2 * zeta**2)
    v_out = -v_in * np.exp(-s * theta / wd) * (np.cos(theta) - s / wd * np.sin(theta))
    assert len(up) == 1 and up[0]["t"] - down[0]["t"] == pytest.approx(theta / wd, rel=1e-7)
    assert traj.column("z_dot")[-1] == pytest.approx(v_out, rel=1e-7)
    assert -traj.damper_work[-1] == pytest.approx(0.5 * M * (v_in**2 - v_out**2), rel=1e-7)
    assert traj.impact_loss[-1] == pytest.approx(lost, rel=1e-10) == traj.stats["touchdown_loss"]
    assert np.all(traj.impact_loss[traj.t < gap / v_in] == 0.0)
    balance = traj.energy - traj.energy[0] - traj.damper_work + traj.impact_loss
    assert np.max(np.abs(balance)) < 1e-8 * traj.energy[0]
    assert traj.stats["rolling_residual"] < 1e-8


def test_energy_balance_with_a_motor_and_bounces():
    """A driven disc dropped slipping (v0 = 1 m/s, no spin) bounces, lands again and rolls: E(t) - E(0) = motor
    work - |damper work| - sum of touch-down losses at every sample; the motor's work is tau (spin(t) - spin(0))."""
    robot = disc(g=9.81, motors=[MotorSpec("m", "spin")], normal_stiffness=5.0e4, normal_damping=60.0)
    q0, nu0 = state(robot, R + 0.02, vx=1.0)
    tau = 0.8
    traj = simulate(robot, 0.3, q0, nu0, Constant([tau]), n_out=151, rtol=1e-10, atol=1e-13, progress=False)
    spin = traj.q[:, robot.coordinate_index("spin")]
    motor = tau * (spin - spin[0])
    balance = traj.energy - traj.energy[0] - motor - traj.damper_work + traj.impact_loss
    assert np.max(np.abs(balance)) < 1e-7 * abs(traj.energy[0])
    assert traj.damper_work[-1] < -1e-3 and traj.impact_loss[-1] > 0.1
    assert np.all(np.diff(traj.impact_loss) >= 0) and np.all(np.diff(traj.damper_work) <= 1e-12)
    assert len(events(traj, "touch-down")) >= 2 and len(events(traj, "lift-off")) >= 1
    assert np.max(np.abs(traj.friction_work)) == 0.0  # rolling: no friction law, the rows' forces do no work


def test_required_mu_of_a_driven_rolling_disc():
    k, g, tau = 2.0e4, 9.81, 0.5
    robot = disc(g=g, motors=[MotorSpec("m", "spin")], normal_stiffness=k, normal_damping=2 * 0.3 * np.sqrt(k * M),
                 mu=0.5)
    q0, nu0 = state(robot, R - M * g / k, vx=1.0, w=1.0 / R)
    a = R * tau / (I + M * R**2)
    nudot = robot.forward_dynamics(q0, nu0, [tau])
    assert nudot[robot.velocity_names.index("x_dot")] == pytest.approx(a, rel=1e-12)
    assert R * nudot[robot.velocity_names.index("spin_dot")] == pytest.approx(a, rel=1e-12)
    from robotdyn.contact.traction import traction

    traj = simulate(robot, 0.1, q0, nu0, Constant([tau]), n_out=6, rtol=1e-10, atol=1e-13, progress=False)
    assert traj.stats["flight"] == []  # it starts rolling at rest on its static deflection: nothing to stop
    tr = traction(robot, traj, Constant([tau]))
    assert tr.wheels == ["disc"] and tr.sliding == []
    assert np.allclose(tr.normal[:, 0], M * g, rtol=1e-9)
    assert np.allclose(tr.required_mu[:, 0], M * R * tau / ((I + M * R**2) * M * g), rtol=1e-8)
    assert "required mu up to 0.0695" in tr.summary()


def test_rigid_limit_rolling_over_a_bump():
    from robotdyn.constraints.terrain import BumpTerrain

    bump = BumpTerrain(0.03, 0.4, 0.15)

    def run(r, dz=0.0):
        q0 = np.zeros(r.nq)
        q0[r.coordinate_index("x")] = -0.6
        q0[r.coordinate_index("z")] = R + bump.height(-0.6, 0.0) - dz
        v0 = np.zeros(r.nq)
        v0[r.coordinate_index("x")], v0[r.coordinate_index("spin")] = 1.5, 1.5 / R  # rolling
        traj = simulate(r, 1.0, q0, v0[r.independent_indices], n_out=2, rtol=1e-9, atol=1e-12, progress=False)
        return traj, traj.q[-1], r.velocity(traj.q[-1], traj.nu[-1])

    spec = RobotSpec(name="disc", title="disc", xacro=DISC, root="planar", wheels=[Wheel("disc", R)],
                     parameters=[Parameter("g", 9.81, "m/s^2", xacro=False)])
    rigid = Robot(spec, terrain=bump)
    _, q_r, v_r = run(rigid)
    assert q_r[rigid.coordinate_index("x")] > 0.8  # past the bump
    errors = []
    for k in (1e4, 4e4):
        r = disc(g=9.81, terrain=bump, normal_stiffness=k, normal_damping=2 * 0.5 * np.sqrt(k * M))
        traj, q, v = run(r, M * 9.81 / k)
        assert traj.stats["flight"] == [] and traj.stats["touchdown_loss"] < 1e-20  # it keeps its contact
        errors.append(np.max(np.abs(v - v_r)))
        dz = q[r.coordinate_index("z")] - q_r[rigid.coordinate_index("z")]
        assert dz == pytest.approx(-M * 9.81 / k, rel=0.02)  # the static deflection (flat ground past the bump)
    assert errors[0] < 1e-3 * 1.5
    assert errors[0] / errors[1] > 4.0  # at least 1/k


def test_plastic_impact_is_the_one_row_impact_with_e_0_and_splits_redundant_rows():
    from robotdyn.contact.impulse import impact, plastic_impact

    rng = np.random.default_rng(3)
    X = rng.normal(size=(4, 4))
    Mr = X @ X.T + 4 * np.eye(4)
    n = rng.normal(size=4)
    nu = -n + 0.1 * rng.normal(size=4)
    one = impact(Mr, n, nu, 0.0)
    many = plastic_impact(Mr, n[None, :] / np.linalg.norm(n), nu)
    assert np.allclose(many.nu_after, one.nu_after, atol=1e-13)
    assert many.impulse[0] == pytest.approx(one.magnitude, rel=1e-12)
    ke = 0.5 * nu @ Mr @ nu - 0.5 * one.nu_after @ Mr @ one.nu_after
    assert many.energy_lost == pytest.approx(ke, rel=1e-12)
    # a repeated row changes nothing but splits the impulse evenly (minimum norm)
    twice = plastic_impact(Mr, np.vstack([n, n]) / np.linalg.norm(n), nu)
    assert twice.rank == 1 and np.allclose(twice.nu_after, one.nu_after, atol=1e-12)
    assert twice.impulse == pytest.approx([one.magnitude / 2] * 2, rel=1e-10)


def test_example_base_on_rolling_tyres_from_simulate(capsys):
    """examples/bump_base_rolling.toml through `robotdyn simulate` (in-process): both front wheels leave the bump's
    crest together (the base is symmetric) with their rows dropped, the rear ones still rolling; the JSON report
    carries the flight events and the touch-down losses; energy change = damper work - touch-down losses (no
    motors, no friction law)."""
    import json

    from robotdyn.cli.commands import main

    example = Path(__file__).resolve().parents[1] / "examples" / "bump_base_rolling.toml"
    rc = main(["simulate", "--constraints", str(example), "--scenario", "bump", "--t-end", "0.08", "--quiet",
               "--json"])
    out = capsys.readouterr()
    assert rc == 0, out.err
    data = json.loads(out.out)
    lifts = {e["wheel"]: e["t"] for e in data["flight"] if e["event"] == "lift-off"}
    assert set(lifts) == {"front_left", "front_right"}
    assert lifts["front_left"] == pytest.approx(lifts["front_right"], abs=1e-9) and 0.06 < lifts["front_left"] < 0.075
    assert data["friction_work"] == 0.0 and data["damper_work"] < 0 and data["touchdown_loss"] >= 0.0
    assert "stopped" not in data
    # the axles' side forces are open (minimum mu over their splits); a wheel in the air needs no friction: the
    # minimum mu stays finite after the lift-off (it was inf: an unloaded wheel counted as one that slips)
    summary = data["traction"]["summary"]
    assert "mu >= " in summary and "inf" not in summary, summary


def test_forces_of_rolling_tyres_one_story(capsys):
    """The rolling rows' forces on the four-wheel base (examples/bump_base_rolling.toml), driven: the same numbers
    from dump --forces as from the API; each wheel's longitudinal force is determined, the lateral split between the
    two wheels of an axle is not (two redundant side-slip rows: reported open, not an arbitrary split), and the
    minimum mu over the admissible splits is at least every wheel's longitudinal |F_x| / F_n."""
    import json

    from robotdyn.cli.commands import main
    from robotdyn.interfaces.constraint_file import load_robot

    example = Path(__file__).resolve().parents[1] / "examples" / "bump_base_rolling.toml"
    robot = load_robot(example)
    q, nu, tau = robot.neutral(), np.array([4, 0, 0, 0, 0, 0, 40, 40, 40, 40.0]), np.array([1.0, 2.0, 3.0, 4.0])
    forces = robot.contact_forces(q, nu, tau=tau)
    assert [w.determined.tolist() for w in forces.wheels] == [[True, False, True]] * 4
    ratios = [abs(w.force[0]) / w.normal for w in forces.wheels]
    assert forces.minimum_mu() >= max(ratios) - 1e-12
    rc = main(["dump", "--constraints", str(example), "--v", *map(str, nu), "--tau", *map(str, tau), "--forces",
               "--json"])
    data = json.loads(capsys.readouterr().out)
    assert rc == 0
    assert np.allclose(data["a"], robot.forward_dynamics(q, nu, tau), rtol=1e-12, atol=1e-12)
    for w in forces.wheels:
        assert data["forces"]["wheels"][w.name]["longitudinal"] == pytest.approx(w.force[0], rel=1e-12)


@pytest.mark.parametrize("example", ["bump_base_rolling", "bump_base"])
def test_what_compliant_wheels_do_not_take_is_refused_in_one_line(example):
    """Inverse dynamics does not take the rolling rows of compliant wheels in contact, and derivatives have no rule
    for compliant wheels: each says so in one line (the derivatives used to end in a numpy broadcast error)."""
    from robotdyn.errors import InputError
    from robotdyn.interfaces.constraint_file import read

    robot = read(Path(__file__).resolve().parents[1] / "examples" / f"{example}.toml").robot()
    q, nu, tau = robot.neutral(), np.zeros(robot.mobility), np.zeros(len(robot.motors))
    calls = [lambda: robot.dynamics_derivatives(q, nu, tau)]
    if example == "bump_base_rolling":  # (at neutral its wheels press on the ground)
        calls.append(lambda: robot.inverse_dynamics(q, nu, np.zeros(robot.mobility)))
    for call in calls:
        with pytest.raises(InputError) as info:
            call()
        assert "\n" not in str(info.value) and "compliant" in str(info.value)


def test_a_compliant_wheels_load_is_reported_as_its_contact_law():
    """The normal load of a compliant wheel comes from its force law, not from rigid-body dynamics: its source says
    so (dump --forces --json printed "rigid")."""
    from robotdyn.contact.contact_forces import COMPLIANT_SOURCE
    from robotdyn.interfaces.constraint_file import read

    robot = read(Path(__file__).resolve().parents[1] / "examples" / "bump_base.toml").robot()
    forces = robot.contact_forces(robot.neutral(), np.zeros(robot.mobility), tau=np.zeros(len(robot.motors)))
    assert {w["source"] for w in forces.as_dict()["wheels"].values()} == {COMPLIANT_SOURCE}
