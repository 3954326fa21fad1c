"""Joint springs and compliant wheels on the compiled engine (robotdyn/kernels/joint_springs.hpp,
robotdyn/kernels/compliant_contact.hpp; Dormand-Prince by default, the stiff Boost.Odeint rosenbrock4 of
robotdyn/_stiff_integrator.hpp on request, flight phases on their dense output), against the closed forms of
tests/test_compliant_contact.py and against the scipy path (LSODA for compliant wheels, DOP853 for springs), the
reference:

- the applied forces (generalised force Q, friction and damper powers, penetrations, contact forces) and the stored
  energy at one state equal robotdyn.contact.applied_forces' to rounding;
- a disc thrown at the ground lands on a linear spring-damper: touch-down at gap / v_in, contact time and rebound
  speed of the damped oscillator whose force never pulls (derived in tests/test_compliant_contact.py), energy lost =
  -damper work, E(t) - E(0) = damper work + friction work at every sample;
- the sprung car braking (examples/sprung_car.toml), the bump_base example (a rigid four-wheel base whose wheels fly
  over a bump) and the compliant linkage rover over its bump at speed: the same trajectory, works and flight phases
  as the scipy path to the integration tolerance;
- what stays on the Python path is refused in one line.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from robotdyn.fast.compiled import available
from robotdyn.fast.dispatch import use_compiled
from robotdyn.robot import Robot
from robotdyn.simulation.engine import simulate

from compliant_disc import DISC, M, R, check_landing, disc, phases, state  # noqa: F401 (tests/compliant_disc.py)

pytestmark = pytest.mark.skipif(not available(), reason="the compiled extension was not built")

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
T_BUMP, T_ROVER = 0.1, 0.45  # durations [s] of the bump_base and rover runs compared
BALANCE = 1e-7  # relative energy balance of the bump_base run at rtol 1e-9 (it missed by 4e-4 with the old rate)


def same_flights(a, b, tol: float) -> None:
    """The same flight events (wheel, kind) at the same times to tol [s] (events at one time in any order)."""
    def events(traj):
        return sorted(traj.stats["flight"], key=lambda e: (round(e["t"] / (10 * tol)), e["wheel"], e["event"]))

    ea, eb = events(a), events(b)
    assert [(e["wheel"], e["event"]) for e in ea] == [(e["wheel"], e["event"]) for e in eb]
    assert np.allclose([e["t"] for e in ea], [e["t"] for e in eb], rtol=0, atol=tol)


def bump_base():
    from robotdyn.interfaces.constraint_file import read

    cf = read(EXAMPLES / "bump_base.toml")
    robot = cf.robot()
    return robot, cf.SCENARIOS["bump"]


def sprung_car():
    from robotdyn.interfaces.constraint_file import read

    cf = read(EXAMPLES / "sprung_car.toml")
    return cf.robot(), cf.SCENARIOS["brake"]


@pytest.mark.parametrize("which", ["bump_base", "sprung_car"])
def test_applied_forces_and_energy_equal_the_python_path(which):
    from robotdyn.contact.applied_forces import applied
    from robotdyn.fast.applied_model import applied_model, applied_state

    robot, sc = bump_base() if which == "bump_base" else sprung_car()
    q0, nu0 = sc.initial_state(robot)
    rng = np.random.default_rng(1)
    q = q0.copy()  # (the car's wheels roll: its q must keep their contact rows)
    if which == "bump_base":
        q += rng.uniform(-2e-3, 2e-3, robot.nq)
        q[robot.coordinate_index("roll")] += 0.03  # one side's wheels pressed in, the other's lifted
    nu = nu0 + rng.uniform(-0.5, 0.5, robot.mobility)
    fast = applied_model(robot)
    Q, friction, damper, contacts = applied_state(fast, q, nu)
    v = robot.velocity(q, nu)
    ref = applied(robot, q, v)
    scale = max(1.0, float(np.max(np.abs(ref.Q))))
    assert np.max(np.abs(Q - ref.Q)) < 1e-12 * scale
    assert friction == pytest.approx(ref.friction_power, rel=1e-12, abs=1e-12 * scale)
    assert damper == pytest.approx(ref.damper_power, rel=1e-12, abs=1e-12 * scale)
    for row, (name, st) in zip(contacts, ref.wheels.items()):
        assert row[0] == pytest.approx(st["delta"], abs=1e-15)
        assert row[2:] == pytest.approx(st["force"], rel=1e-12, abs=1e-12 * scale)
    if which == "bump_base":  # some wheels pressed in (a force), some lifted (none): both branches compared
        normals = [st["normal"] for st in ref.wheels.values()]
        assert any(n > 0 for n in normals) and any(n == 0 for n in normals)
    energy, _ = fast.ev.observe(np.concatenate([q, nu]))
    assert energy == pytest.approx(robot.energy(q, v), rel=1e-12, abs=1e-9)


@pytest.mark.parametrize("method", [None, "rosenbrock4"])
@pytest.mark.parametrize("zeta", [0.0, 0.5])
def test_dropped_disc_damped_oscillator(zeta, method):
    k, v_in, gap = 2.0e4, 1.0, 0.01
    c = 2 * zeta * np.sqrt(k * M)
    robot = disc(normal_stiffness=k, normal_damping=c)
    q0, nu0 = state(robot, R + gap, -v_in)
    traj = simulate(robot, 0.1, q0, nu0, n_out=101, rtol=1e-10, atol=1e-13, progress=False, method=method)
    assert traj.stats["engine"] == f"compiled ({method or 'dopri5'})"
    check_landing(traj, k, zeta, v_in, gap)  # tests/compliant_disc.py


def test_sprung_car_braking_equals_the_scipy_path():
    robot, sc = sprung_car()
    q0, nu0 = sc.initial_state(robot)
    runs = [simulate(robot, 1.0, q0, nu0, sc.torque, n_out=21, rtol=1e-10, atol=1e-12, progress=False, engine=engine,
                     method=method) for engine, method in (("scipy", None), ("compiled", None), ("compiled", "rosenbrock4"))]
    ref = runs[0]
    assert ref.stats["engine"].startswith("scipy")
    assert [r.stats["engine"] for r in runs[1:]] == ["compiled (adams)", "compiled (rosenbrock4)"]
    for traj in runs[1:]:
        assert traj.stats["engine"].startswith("compiled")
        assert np.max(np.abs(traj.q - ref.q)) < 1e-7
        assert np.max(np.abs(traj.nu - ref.nu)) < 1e-6
        assert np.max(np.abs(traj.damper_work - ref.damper_work)) < 1e-6 * abs(ref.damper_work[-1])
        assert np.max(np.abs(traj.energy - ref.energy)) < 1e-7 * abs(ref.energy[0])
        assert traj.friction_work is None
    # energy: E(t) - E(0) = motor work + damper work, constant brake torques doing tau (phi(t) - phi(0))
    tau = np.asarray(sc.torque(0.0, q0, nu0), float)
    spins = [robot.coordinate_index(f"{n}_spin") for n in ("front_left", "front_right", "rear_left", "rear_right")]
    traj = runs[1]
    motor = (traj.q[:, spins] - traj.q[0, spins]) @ tau
    assert np.max(np.abs(traj.energy - traj.energy[0] - motor - traj.damper_work)) < 1e-7 * abs(motor[-1])


def test_bump_base_example_equals_lsoda():
    """examples/bump_base.toml's scenario: the front wheels leave the bump's crest; the compiled run
    (dopri5) and the scipy path (LSODA) at rtol 1e-9 agree on the trajectory, the works, the energies and the flight
    phases; on both, coasting, E(t) - E(0) = friction work + damper work at every sample, on this curved terrain too
    (the penetration rate is d phi(q)/dt, tests/test_compliant_curved_terrain.py; it missed by 0.1 J of 246 J while
    it was the contact point's normal velocity)."""
    robot, sc = bump_base()
    q0, nu0 = sc.initial_state(robot)
    options = dict(n_out=31, rtol=1e-9, atol=1e-11, progress=False)
    a = simulate(robot, T_BUMP, q0, nu0, sc.torque, **options)
    with use_compiled(False):
        b = simulate(robot, T_BUMP, q0, nu0, sc.torque, **options)
    assert (a.stats["engine"], b.stats["engine"]) == ("compiled (dopri5)", "scipy (LSODA)")
    assert [e["event"] for e in a.stats["flight"]] == ["lift-off", "lift-off"]  # the front wheels, off the crest
    same_flights(a, b, 1e-6)
    assert np.max(np.abs(a.q - b.q)) < 1e-6
    assert np.max(np.abs(a.nu - b.nu)) < 1e-4 * np.max(np.abs(b.nu))
    for x, y in ((a.friction_work, b.friction_work), (a.damper_work, b.damper_work), (a.energy, b.energy)):
        assert np.max(np.abs(x - y)) < 1e-6 * abs(b.energy[0])
    for traj in (a, b):  # no motor work: E(t) - E(0) = friction work + damper work
        balance = traj.energy - traj.energy[0] - traj.friction_work - traj.damper_work
        assert np.max(np.abs(balance)) < BALANCE * abs(traj.energy[0]), traj.stats["engine"]


def test_compliant_linkage_rover_over_the_bump_equals_lsoda():
    """The compliant linkage rover (robotdyn.robots.linkage_suspension.compliant) driven at 25 rad/s over its 5 cm
    bump, wheels flying, on the compiled engine: at every sample its accelerations equal the Python path's forward
    dynamics (springs of the tyres included), and from the sample before the first lift-off the scipy path (LSODA,
    the speed law called from Python) reaches the same lift-off and state (a window: the whole run costs a minute
    on the Python path)."""
    from robotdyn.robots.linkage_suspension.compliant import bump_run, compliant_spec, hold_speed_law
    from robotdyn.robots.linkage_suspension.model import SPEC

    rigid, soft = Robot(SPEC), Robot(compliant_spec())
    a = bump_run(soft, T_ROVER, rigid, speed=25.0, feedback=True, rtol=1e-8, atol=1e-10, n_out=46)
    assert a.stats["engine"] == "compiled (dopri5)"
    assert len(a.stats["flight"]) >= 4  # wheels leave the ground and land
    law = hold_speed_law(soft, 25.0).bound(soft)
    from robotdyn.fast.applied_model import applied_model

    fast = applied_model(soft)
    for t, q, nu in zip(a.t, a.q, a.nu):
        tau = law(t, q, nu)
        compiled = fast.ev.rhs(q, nu, tau, 0.0)[soft.nq:]
        python = soft.forward_dynamics(q, nu, tau)
        assert np.max(np.abs(compiled - python)) < 1e-9 * max(1.0, np.max(np.abs(python)))
    first = a.stats["flight"][0]
    i = int(np.searchsorted(a.t, first["t"])) - 1
    t0, t1 = float(a.t[i]), float(a.t[i]) + 0.02
    options = dict(t0=t0, n_out=3, rtol=1e-9, atol=1e-11, progress=False)
    with use_compiled(False):
        p = simulate(soft, t1, a.q[i], a.nu[i], law, **options)
    assert p.stats["engine"] == "scipy (LSODA)"
    for method in ("dopri5", "rosenbrock4"):
        c = simulate(soft, t1, a.q[i], a.nu[i], law, method=method, **options)
        assert c.stats["engine"] == f"compiled ({method})"
        assert (first["wheel"], first["event"]) in [(e["wheel"], e["event"]) for e in c.stats["flight"]]
        same_flights(c, p, 1e-7)
        assert np.max(np.abs(c.q - p.q)) < 1e-7
        assert np.max(np.abs(c.nu - p.nu)) < 1e-5 * np.max(np.abs(p.nu))
        assert np.max(np.abs(c.damper_work - p.damper_work)) < 1e-7 * abs(p.energy[0])


def test_what_stays_on_the_python_path_is_refused_in_one_line():
    from robotdyn.errors import RobotDynError
    from robotdyn.simulation.many_runs import simulate_many

    robot = disc(normal_stiffness=2.0e4)
    q0, nu0 = state(robot, R + 0.01, -1.0)
    with pytest.raises(RobotDynError, match="^engine = 'compiled' cannot run this simulation: compliant wheels' "
                                            "flight phases are located on a dense output"):
        simulate(robot, 0.05, q0, nu0, method="adams", progress=False)
    with pytest.raises(RobotDynError, match="compliant wheels \\(normal force laws\\) are evaluated on the Python "
                                            "path"):
        simulate_many(robot, 0.05, q0=q0[None, :], nu0=nu0[None, :])
