"""SUNDIALS CVODE (``method="cvode"``, robotdyn.simulation.cvode: variable-order BDF on the compiled model, flight
phases by CVODE's rootfinding) against independent references:

- a disc dropped on a linear spring-damper: touch-down at gap / v_in, contact time and rebound speed of the damped
  oscillator whose force never pulls (the closed form of tests/compliant_disc.py, derived there), energy lost =
  -damper work, E(t) - E(0) = damper work + friction work at every sample;
- examples/bump_base.toml over its bump (front wheels leaving the crest): the same trajectory, works and flight
  phases as the compiled engine's Dormand-Prince run to the tolerance;
- the rolling compliant base (examples/bump_base_rolling.toml, contact switches as CVODE's terminal root): the same
  switches and touch-down loss as the dopri5 run;
- bad input: cvode where it does not apply, in one line.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from robotdyn.errors import RobotDynError
from robotdyn.fast.compiled import available
from robotdyn.simulation.engine import simulate

from compliant_disc import M, R, check_landing, disc, phases, state  # tests/compliant_disc.py

pytestmark = pytest.mark.skipif(not available(), reason="the compiled extension was not built")

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.mark.parametrize("zeta", [0.0, 0.5])
def test_dropped_disc_damped_oscillator(zeta):
    k, v_in, gap = 2.0e4, 1.0, 0.01
    c = 2 * zeta * np.sqrt(k * M)
    robot = disc(normal_stiffness=k, normal_damping=c)
    q0, nu0 = state(robot, R + gap, -v_in)
    # rtol 1e-11 where the dopri5 test runs at 1e-10: at 1e-10 BDF's numerical damping of the undamped bounce loses
    # 4e-8 J of 1 J (rebound speed off by 2e-8), twice the energy bound below (dopri5: 5e-9 J; CVODE at 1e-11: 5e-9 J
    # in 406 evaluations, dopri5 at 1e-10: 956)
    traj = simulate(robot, 0.1, q0, nu0, n_out=101, rtol=1e-11, atol=1e-13, progress=False, method="cvode")
    assert traj.stats["engine"] == "compiled (cvode)"
    check_landing(traj, k, zeta, v_in, gap)  # tests/compliant_disc.py
    assert traj.stats["nfev"] > 0 and traj.stats["jacobians"] > 0


def test_bump_base_equals_dopri5():
    from robotdyn.interfaces.constraint_file import read

    cf = read(EXAMPLES / "bump_base.toml")
    robot = cf.robot()
    sc = cf.SCENARIOS["bump"]
    q0, nu0 = sc.initial_state(robot)
    options = dict(n_out=31, rtol=1e-9, atol=1e-11, progress=False)
    a = simulate(robot, 0.1, q0, nu0, sc.torque, method="cvode", **options)
    b = simulate(robot, 0.1, q0, nu0, sc.torque, method="dopri5", **options)
    assert (a.stats["engine"], b.stats["engine"]) == ("compiled (cvode)", "compiled (dopri5)")
    assert [(e["wheel"], e["event"]) for e in a.stats["flight"]] == [(e["wheel"], e["event"]) for e in b.stats["flight"]]
    assert [e["event"] for e in a.stats["flight"]] == ["lift-off", "lift-off"]
    # measured: lift-offs 7e-11 s apart, q 7e-9, nu 5e-9 relative, works 3e-10 and the balance 3e-10 of E(0)
    assert np.allclose([e["t"] for e in a.stats["flight"]], [e["t"] for e in b.stats["flight"]], rtol=0, atol=1e-8)
    assert np.array_equal(a.t, b.t)
    assert np.max(np.abs(a.q - b.q)) < 1e-7
    assert np.max(np.abs(a.nu - b.nu)) < 1e-7 * np.max(np.abs(b.nu))
    for x, y in ((a.friction_work, b.friction_work), (a.damper_work, b.damper_work), (a.energy, b.energy)):
        assert np.max(np.abs(x - y)) < 1e-8 * abs(b.energy[0])
    balance = a.energy - a.energy[0] - a.friction_work - a.damper_work  # coasting: no motor work
    assert np.max(np.abs(balance)) < 1e-8 * abs(a.energy[0])
    assert a.stats["nfev"] < b.stats["nfev"]  # 847 against 2,390


def test_rolling_compliant_wheels_equal_dopri5():
    from robotdyn.interfaces.constraint_file import read

    cf = read(EXAMPLES / "bump_base_rolling.toml")
    robot, sc = cf.robot(), cf.SCENARIOS["bump"]
    options = dict(t_end=0.3, n_out=16, rtol=1e-9, atol=1e-11, progress=False)
    a = sc.run(robot, method="cvode", **options)
    b = sc.run(robot, method="dopri5", **options)
    assert (a.stats["engine"], b.stats["engine"]) == ("compiled (cvode)", "compiled (dopri5)")
    assert a.stats["contact_switches"] == b.stats["contact_switches"] > 0
    assert [(e["wheel"], e["event"]) for e in a.stats["flight"]] == [(e["wheel"], e["event"]) for e in b.stats["flight"]]
    # measured: switch times 1.6e-10 s apart, q 4e-8
    assert np.allclose([e["t"] for e in a.stats["flight"]], [e["t"] for e in b.stats["flight"]], rtol=0, atol=1e-8)
    assert a.stats["touchdown_loss"] == pytest.approx(b.stats["touchdown_loss"], rel=1e-9)
    assert np.max(np.abs(a.q - b.q)) < 1e-6
    assert a.stats["steps"] is None  # (CVODE's step count is not returned by scikit-sundae)


def test_sprung_car_braking_equals_adams():
    """examples/sprung_car.toml (joint springs; rigid rolling wheels whose rows are redundant on the chassis): the
    Jacobian's differences leave the constraints by ~1e-8, which the compiled projection's span check lets pass only
    while it is told (CVODE's own difference quotients stopped this run at t = 0.13 s with a rank error). Same
    trajectory and damper work as Adams; E(t) - E(0) = motor work + damper work with the constant brake torques
    doing tau (phi(t) - phi(0))."""
    from robotdyn.interfaces.constraint_file import read

    cf = read(EXAMPLES / "sprung_car.toml")
    robot, sc = cf.robot(), cf.SCENARIOS["brake"]
    q0, nu0 = sc.initial_state(robot)
    a, b = (simulate(robot, 1.0, q0, nu0, sc.torque, n_out=21, rtol=1e-10, atol=1e-12, progress=False, method=m)
            for m in ("cvode", "adams"))
    assert (a.stats["engine"], b.stats["engine"]) == ("compiled (cvode)", "compiled (adams)")
    # measured: q 5e-11, nu 3e-10, damper work 1.6e-8 relative, the balance 5e-12 of the motor work
    assert np.max(np.abs(a.q - b.q)) < 1e-9
    assert np.max(np.abs(a.nu - b.nu)) < 1e-8
    assert np.max(np.abs(a.damper_work - b.damper_work)) < 1e-7 * abs(b.damper_work[-1])
    tau = np.asarray(sc.torque(0.0, q0, nu0), float)
    spins = [robot.coordinate_index(f"{n}_spin") for n in ("front_left", "front_right", "rear_left", "rear_right")]
    motor = (a.q[:, spins] - a.q[0, spins]) @ tau
    assert np.max(np.abs(a.energy - a.energy[0] - motor - a.damper_work)) < 1e-9 * abs(motor[-1])


def test_cvode_refused_where_it_does_not_apply():
    import robotdyn

    robot = robotdyn.load("quasimoro")  # rigid contacts: no compliance to make the run stiff
    q0, nu0 = robot.neutral(), np.zeros(robot.mobility)
    with pytest.raises(RobotDynError, match=r"^engine = 'compiled' cannot run this simulation: method 'cvode' "
                                            r"\(SUNDIALS' stiff BDF\) runs robots with compliant wheels or joint "
                                            r"springs; expected one of adams, "):
        simulate(robot, 0.1, q0, nu0, method="cvode", progress=False)
    soft = disc(normal_stiffness=2.0e4)
    q0, nu0 = state(soft, R + 0.01, -1.0)
    with pytest.raises(RobotDynError, match="^method 'cvode' is a compiled integrator; the scipy engine has"):
        simulate(soft, 0.05, q0, nu0, method="cvode", engine="scipy", progress=False)
    with pytest.raises(RobotDynError, match=r"^method = 'cvod'; expected one of adams, .*cvode \(compiled\) or "
                                            r"DOP853, .*LSODA \(scipy\)$") as info:
        simulate(soft, 0.05, q0, nu0, method="cvod", progress=False)  # was scipy's ValueError listing its classes
    assert "\n" not in str(info.value)
