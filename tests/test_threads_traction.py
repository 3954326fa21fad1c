"""Traction passes and the runs that change a robot while they go, from several threads at once on one Robot, each
result equal to the serial one bit for bit.

- The traction memo (robotdyn.contact.traction_memo) installs one-sample memories on the robot (``reduced``) and
  on its compliant wheels (``state``) for the duration of a pass: two passes on one Robot from two threads (one
  of them leaves the other's memories alone and runs without), while a third thread evaluates ``robot.reduced``
  through the installed memory (which hands another thread's call straight to the method).
- Exact stick-slip runs switch the phases of the robot's own wheels and its independent velocities as they go,
  and their traction pass sets each sample's phases in turn. Two of them on one Robot from two threads switched
  each other's wheels (a KeyError, an InputError or a SingularConstraintError: the test below failed in 5 of 5
  runs): they now take turns (robotdyn.contact.stick_slip_wheel.phase_lock). Distinct Robots run at once.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from concurrency import hammer, identical, race
from test_sliding import disc

import robotdyn
from robotdyn.contact.traction import traction
from robotdyn.interfaces.constraint_file import read
from robotdyn.robots import module
from robotdyn.simulation.stick_slip import simulate as stick_slip

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def memo_case(which):
    """``(robot, pass)``: a robot and a function running a traction pass over one of its runs."""
    if which == "quasimoro":
        robot = robotdyn.load("quasimoro")
        scenario = module("quasimoro").SCENARIOS["rectilinear"]
        method = "reference"  # (the per-sample pass: the robot's reduced() memory)
    else:
        bump = read(EXAMPLES / "bump_base_rolling.toml")  # compliant wheels: their state() memories
        robot, scenario = bump.robot(), bump.SCENARIOS["bump"]
        method = which.split()[1]
    traj = scenario.run(robot, t_end=0.3, n_out=16, progress=False)

    def run():
        out = traction(robot, traj, scenario.torque, method=method)
        return [out.normal, out.minimum_mu, out.method]

    return robot, run


@pytest.mark.parametrize("which", ["quasimoro", "bump reference", "bump auto"])
def test_traction_passes_and_reduced_from_three_threads(which):
    robot, run = memo_case(which)
    rng = np.random.default_rng(0)
    states = [(robot.neutral(), rng.normal(size=robot.mobility)) for _ in range(4)]
    calls = {"pass": run}
    calls.update({f"reduced {i}": lambda s=s: [robot.reduced(*s).h.copy(), robot.reduced(*s).M.copy()]
                  for i, s in enumerate(states)})
    lanes = [["pass"], ["pass"], [f"reduced {i}" for i in range(4)] * 10]
    problems, made = hammer(calls, lanes, reps=2)
    assert problems == [] and made == 2 * (1 + 1 + 40)
    assert "reduced" not in robot.__dict__  # (every memory removed: the method again)


def launched(robot, q0, v0):
    """A disc launched at v0 [m/s] along x for 0.05 s: sliding throughout (it would stick at t* = v0 / (3 mu g) =
    0.113 s per m/s, tests/test_stick_slip.py), or at rest and sticking (v0 = 0)."""
    v = np.zeros(robot.nq)
    v[robot.coordinate_index("x")] = v0
    traj = stick_slip(robot, 0.05, q0, v, n_out=11, progress=False)
    out = traction(robot, traj)
    return [traj.q, traj.nu, out.normal, out.minimum_mu, list(traj.velocity_names)]


def test_stick_slip_runs_on_one_robot_take_turns():
    """A disc launched sliding at 1 m/s and one at rest (sticking: other independent velocities), run and reported
    by two threads at once on one Robot, eight rounds: each equals its serial run bit for bit."""
    robot, q0 = disc(0.0, friction="stick_slip", mu=0.3)
    expected = {v0: launched(robot, q0, v0) for v0 in (1.0, 0.0)}
    problems = []
    for _ in range(8):
        got = {}
        problems += race([lambda v0=v0: got.__setitem__(v0, launched(robot, q0, v0)) for v0 in expected])
        problems += [f"v0 = {v0}" for v0 in expected if v0 not in got or not identical(got[v0], expected[v0])]
    assert problems == []


def test_stick_slip_runs_on_distinct_robots_at_once():
    robot, q0 = disc(0.0, friction="stick_slip", mu=0.3)
    expected = {v0: launched(robot, q0, v0) for v0 in (1.0, 0.0)}
    robots = {v0: disc(0.0, friction="stick_slip", mu=0.3)[0] for v0 in expected}
    got = {}
    assert race([lambda v0=v0: got.__setitem__(v0, launched(robots[v0], q0, v0)) for v0 in expected]) == []
    assert all(identical(got[v0], expected[v0]) for v0 in expected)


def test_compliant_robot_keeps_one_compiled_model_per_thread_and_pickles():
    """A robot with compliant wheels (``examples/bump_base_rolling.toml``) keeps its compiled applied model per
    thread: a run in another thread leaves the main thread's model in place (before, one slot for all threads:
    every run after another thread's rebuilt it, 11 ms here), each thread's run equals the main thread's bit for
    bit, and the robot pickles after its runs (before: TypeError, the compiled model in the slot), the copy giving
    the same run."""
    import pickle
    import threading

    from robotdyn.fast.applied_model import applied_model

    bump = read(EXAMPLES / "bump_base_rolling.toml")
    robot, scenario = bump.robot(), bump.SCENARIOS["bump"]

    def run(r=robot):
        tr = scenario.run(r, t_end=0.05, n_out=3, progress=False)
        return [tr.q, tr.nu, tr.energy, tr.stats["engine"]]

    expected = run()
    assert expected[3].startswith("compiled")
    mine, seen = applied_model(robot), []
    for _ in range(2):
        thread = threading.Thread(target=lambda: seen.append((applied_model(robot), run())))
        thread.start()
        thread.join()
        assert applied_model(robot) is mine
    assert len(seen) == 2 and all(m is not mine and identical(r, expected) for m, r in seen)
    copy = pickle.loads(pickle.dumps(robot))
    assert identical(run(copy), expected)
