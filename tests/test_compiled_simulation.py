"""The compiled simulation engine (robotdyn.simulation.compiled_engine) against the scipy reference (DOP853, rtol 1e-10,
atol 1e-12), and the drift it leaves: holonomic residuals and, where no torque acts, the energy."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import robotdyn
from robotdyn.fast.dispatch import available
from robotdyn.simulation.compiled_engine import native_profile, rechooser
from robotdyn.errors import RobotDynError
from robotdyn.robots import module
from robotdyn.simulation.engine import simulate
from robotdyn.simulation.torque_profile import Constant, Sine

pytestmark = pytest.mark.skipif(not available(), reason="compiled extension not built")


def test_quasimoro_rectilinear_90s_equals_scipy(quasimoro):
    """Staicu's manoeuvre (eq 19 pulse, then free), 90 s: the compiled trajectory is the scipy path's to 1e-8,
    the energy is constant to 1e-9 J once the pulse is over, and the compiled engine was used."""
    sc = module("quasimoro").SCENARIOS["rectilinear"]
    fast = sc.run(quasimoro, progress=False)
    ref = sc.run(quasimoro, progress=False, engine="scipy")
    assert fast.stats["engine"] == "compiled (adams)" and ref.stats["engine"] == "scipy (DOP853)"
    assert np.array_equal(fast.t, ref.t)
    assert np.max(np.abs(fast.q - ref.q)) <= 1e-8 and np.max(np.abs(fast.nu - ref.nu)) <= 1e-8
    free = fast.t > 1.0  # the pulse acts for t <= 1 s
    assert np.ptp(fast.energy[free]) <= 1e-9
    assert np.allclose(fast.energy, ref.energy, rtol=0, atol=1e-9)
    # the pulse did work: the energy rose by what the motors put in (the paper's manoeuvre is not trivial)
    assert fast.energy[-1] - fast.energy[0] > 1e-3


def _cases():
    """(label, robot, q0, nu0, torque, t_end, conservative): every compiled robot, with profile torques or none."""
    r = robotdyn.load("linkage_suspension")
    q0, nu0 = module("linkage_suspension").SCENARIOS["ramp_free"].initial_state(r)
    yield "linkage_suspension ramp", r, q0, nu0, None, 1.0, True
    r = robotdyn.load("adaptable_wheel")
    hold = module("adaptable_wheel").SCENARIOS["hold"]
    q0, nu0 = hold.initial_state(r)
    yield "adaptable_wheel hold", r, q0, nu0, hold.torque + Sine(np.full(6, 0.02), 3.0), 1.0, False
    r = robotdyn.load("omni_caster")
    yield "omni_caster", r, r.neutral(), np.array([0.3, -0.2, 0.4]), Sine(np.full(6, 0.5), 2.0), 1.0, False
    r = robotdyn.load("mmr12_eod")
    nu0 = 0.1 * np.random.default_rng(0).normal(size=r.mobility)
    yield "mmr12_eod", r, r.neutral(), nu0, None, 1.0, True
    r = robotdyn.load("quasimoro")
    yield "quasimoro rotation", r, r.neutral(), np.zeros(3), module("quasimoro").SCENARIOS["pure_rotation"].torque, \
        10.0, False


@pytest.mark.parametrize("case", list(_cases()), ids=lambda c: c[0])
def test_every_compiled_robot_equals_scipy(case):
    """The scipy path's trajectory to 1e-8 relative to the motion's scale (max(1, |q|), max(1, |nu|)), residuals
    below 1e-9, and a torque-free run's energy constant to 1e-9 (relative)."""
    label, robot, q0, nu0, torque, t_end, conservative = case
    fast = simulate(robot, t_end, q0, nu0, torque, n_out=101, progress=False)
    ref = simulate(robot, t_end, q0, nu0, torque, n_out=101, progress=False, engine="scipy")
    assert fast.stats["engine"].startswith("compiled")
    scale_q = max(1.0, float(np.max(np.abs(ref.q))))
    scale_nu = max(1.0, float(np.max(np.abs(ref.nu))))
    assert np.max(np.abs(fast.q - ref.q)) <= 1e-8 * scale_q, label
    assert np.max(np.abs(fast.nu - ref.nu)) <= 1e-8 * scale_nu, label
    assert np.max(fast.residual) <= 1e-9
    if conservative:
        assert np.ptp(fast.energy) <= 1e-9 * max(1.0, abs(fast.energy[0]))


def test_engine_choice_and_errors(quasimoro):
    q0, nu0 = quasimoro.neutral(), np.zeros(3)
    lam = lambda t, q, nu: np.array([0.1, 0.1])  # noqa: E731
    assert simulate(quasimoro, 0.5, q0, nu0, lam, progress=False).stats["engine"] == "scipy (DOP853)"
    assert simulate(quasimoro, 0.5, q0, nu0, None, progress=False).stats["engine"] == "compiled (adams)"
    assert simulate(quasimoro, 0.5, q0, nu0, None, method="RK45", progress=False).stats["engine"] == "scipy (RK45)"
    out = simulate(quasimoro, 0.5, q0, nu0, Constant([0.1, 0.1]), method="bulirsch_stoer", progress=False)
    assert out.stats["engine"] == "compiled (bulirsch_stoer)"
    with pytest.raises(RobotDynError, match="Python function"):
        simulate(quasimoro, 0.5, q0, nu0, lam, engine="compiled", progress=False)
    with pytest.raises(RobotDynError, match="engine = 'turbo'"):
        simulate(quasimoro, 0.5, q0, nu0, engine="turbo", progress=False)
    with pytest.raises(RobotDynError, match="compiled integrator"):
        simulate(quasimoro, 0.5, q0, nu0, method="adams", engine="scipy", progress=False)


def test_adams_steps_do_not_depend_on_the_sampling():
    """Adams takes the samples between its steps from the Hermite interpolant of its accepted points: on the
    linkage's straight_line (a feedback law, 400 samples/s by default) 11 samples and 451 give the same steps (same
    evaluations, the same final state bit for bit), and the interpolated samples are the scipy run's (DOP853 at the
    same rtol 1e-10) to 1e-8 in q and 1e-7 in nu."""
    robot = robotdyn.load("linkage_suspension")
    sc = module("linkage_suspension").SCENARIOS["straight_line"]
    few = sc.run(robot, t_end=1.5, n_out=11, progress=False)
    many = sc.run(robot, t_end=1.5, n_out=601, progress=False)
    ref = sc.run(robot, t_end=1.5, n_out=601, progress=False, engine="scipy")
    assert few.stats["engine"] == many.stats["engine"] == "compiled (adams)"
    assert few.stats["nfev"] == many.stats["nfev"]
    assert np.array_equal(few.q[-1], many.q[-1]) and np.array_equal(few.nu[-1], many.nu[-1])
    # two integrators at rtol 1e-10 over 1.5 s: global differences 2.3e-9 (q) and 3.4e-8 (nu, wheel speeds ~5 rad/s);
    # Adams stepping onto every sample (before the interpolant) differed from DOP853 by 6.2e-9 and 6.4e-8
    assert np.max(np.abs(many.q - ref.q)) <= 1e-8 and np.max(np.abs(many.nu - ref.nu)) <= 1e-7
    assert np.max(np.abs(many.nu[:, 0] - many.nu[0, 0])) > 1.0  # the wheels sped up


def test_the_three_compiled_integrators_agree(quasimoro):
    sc = module("quasimoro").SCENARIOS["rectilinear"]
    runs = [sc.run(quasimoro, t_end=5.0, progress=False, method=m) for m in ("adams", "bulirsch_stoer", "dopri5")]
    for other in runs[1:]:
        assert np.max(np.abs(other.q - runs[0].q)) <= 1e-9


def test_a_failing_row_choice_is_rechosen_by_the_python_path():
    """Where the compiled row choice stops working mid-run, the C++ integrator asks the Python path for a new one
    (as the scipy path evaluates that state in Python): here the run starts with a wrong choice."""
    robot = robotdyn.load("omni_caster")
    q0, nu0 = robot.neutral(), np.array([0.3, -0.2, 0.4])
    torque = Sine(np.full(len(robot.motors), 0.5), 2.0)
    good = simulate(robot, 1.0, q0, nu0, torque, n_out=11, progress=False)
    fast = robotdyn.fast.dispatch.compiled_model(robot)
    hint = fast._hint
    calls = []
    choose = rechooser(robot, fast)
    bad = [int(hint.rows[0])] * len(hint.rows)  # one row repeated: a singular block
    fast.ev.set_operational(bad, *fast._op)  # (this robot's velocities are a platform twist)
    fast._hint = None  # the Python side must not rely on the old choice either
    with pytest.raises(robotdyn.fast.compiled.Fallback):
        fast.ev.evaluate(q0, nu0)  # the wrong choice fails here

    def counting(q, nu):
        calls.append(1)
        return choose(q, nu)

    out = fast.ev.simulate(q0, nu0, 0.0, 1.0, np.linspace(0, 1, 11), 1e-10, 1e-12, 10.0,
                           native_profile(torque), [], "adams", None, counting)
    assert calls and np.max(np.abs(out["y"][:, :robot.nq] - good.q)) <= 1e-9


def test_compiled_engine_keeps_the_pull_back_offsets():
    from test_pull_back import drive

    robot = drive()
    traj = simulate(robot, 1.0, robot.neutral(), np.zeros(2), Constant([0.1, 0.2]), n_out=11, progress=False,
                    engine="compiled")
    assert set(traj.stats["offsets"]) == {"wheel_l.normal", "wheel_r.normal"} and traj.t[-1] == 1.0


INTERRUPTED_RUN = """
import signal, sys, numpy as np, robotdyn
from robotdyn.robots import module
signal.signal(signal.SIGTERM, lambda *a: (_ for _ in ()).throw(KeyboardInterrupt()))
robot = robotdyn.load("quasimoro")
traj = module("quasimoro").SCENARIOS["rectilinear"].run(robot, t_end=1e5)
print(traj.stats["engine"], len(traj.t), traj.t[-1], np.all(np.diff(traj.t) > 0), traj.stats.get("partial"))
"""


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_interrupted_compiled_simulation_keeps_its_samples(sig):
    """Ctrl-C (or SIGTERM turned into KeyboardInterrupt, as the CLI does) during a compiled run: the C++ loop sees
    the signal within ~50 ms and returns the samples so far, marked partial (the CLI then writes them, as
    tests/test_interrupt.py checks on the scipy path)."""
    proc = subprocess.Popen([sys.executable, "-c", INTERRUPTED_RUN], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env={**os.environ, "ROBOTDYN_COMPILED": "1"},
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.time() + 60
    for line in proc.stderr:  # wait until the integration is under way (progress after 1 s)
        if line.startswith("simulate: t =") or time.time() > deadline:
            break
    proc.send_signal(sig)
    start = time.time()
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    engine, _, samples, last, increasing, *partial = out.split()
    assert engine == "compiled" and int(samples) >= 2 and float(last) < 1e5 and increasing == "True"
    assert "interrupted at t =" in " ".join(partial)
    assert time.time() - start < 30


@pytest.mark.parametrize("engine", ["compiled", "scipy"])
def test_time_limit_stops_a_crawling_run_on_both_engines(quasimoro, engine):
    """Torques x 1e6 make the error control crawl (tiny steps): past its wall-clock limit the run raises a named
    error saying where it was, within a poll interval of the limit; a run inside its limit is untouched."""
    from robotdyn.errors import TimeLimitError

    q0, nu0 = quasimoro.neutral(), np.zeros(quasimoro.mobility)
    start = time.perf_counter()
    with pytest.raises(TimeLimitError, match=r"exceeded its time limit of 0.3 s at t = "):
        simulate(quasimoro, 0.5, q0, nu0, Sine([1e5, 1e5], np.pi), progress=False, engine=engine, time_limit=0.3)
    assert 0.3 < time.perf_counter() - start < 1.5
    free = simulate(quasimoro, 0.5, q0, nu0, Sine([0.1, 0.1], np.pi), progress=False, engine=engine)
    limited = simulate(quasimoro, 0.5, q0, nu0, Sine([0.1, 0.1], np.pi), progress=False, engine=engine,
                       time_limit=60.0)
    assert np.array_equal(free.q, limited.q)
    with pytest.raises(RobotDynError, match="time_limit = -1 s; expected a positive"):
        simulate(quasimoro, 0.5, q0, nu0, progress=False, engine=engine, time_limit=-1)


@pytest.mark.parametrize("method", ["dopri5", "bulirsch_stoer"])
def test_dense_steppers_cross_windows_meeting_one_double_apart(quasimoro, method):
    """Two torque windows meeting one double apart (the second starts at nextafter(0.3)) give two breakpoints one
    ulp apart. The dense-output driver restarted at each in turn and took the 1-ulp gap as its next step, which
    then failed as vanishing ("Required step size is less than spacing between numbers": MMR12-EOD's manipulation
    scenario with dopri5 at t = 10 s); it now restarts once there. The run ends where Adams (which skipped both
    already) and the scipy path end, to the tolerances, and the torque did work: 0.5 N m on the wheels for 0.3 s,
    then 0.2 N m."""
    after = float(np.nextafter(0.3, np.inf))
    torque = Sine([0.5, 0.5], 0.0, np.pi / 2, 0.0, 0.3) + Sine([0.2, 0.2], 0.0, np.pi / 2, after, 1.0)
    assert len(torque.breakpoints()) == 4 and torque.breakpoints()[2] - torque.breakpoints()[1] < 1e-15
    q0, nu0 = quasimoro.neutral(), np.zeros(3)
    runs = {m: simulate(quasimoro, 0.5, q0, nu0, torque, n_out=6, progress=False, method=m, rtol=1e-10, atol=1e-12)
            for m in (method, "adams")}
    ref = simulate(quasimoro, 0.5, q0, nu0, torque, n_out=6, progress=False, engine="scipy")
    assert runs[method].stats["engine"] == f"compiled ({method})" and runs[method].t[-1] == 0.5
    for traj in runs.values():
        assert np.max(np.abs(traj.q - ref.q)) <= 1e-8 and np.max(np.abs(traj.nu - ref.nu)) <= 1e-8
    assert np.max(np.abs(ref.nu[-1])) > 0.1  # it moved
