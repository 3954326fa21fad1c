"""The analytic derivative set, the linearisation and the contact-force derivatives (issue 26) called from several
threads at once: on one Robot shared by four threads, and on four Robot objects of the same robot, at different
states and in different orders, every result equals the same call made serially, bit for bit (each thread
evaluates its own compiled model, ``robotdyn.fast.dispatch.compiled_model``, with the row choice the serial call
made). Also interleaved with compiled simulations of the same Robot, which run without the GIL (a feedback law as
data, an operational-space controller that adds frames to its thread's model), and with simulate()'s start checks
and their refusals (robotdyn.simulation.start_checks).

One race was found and fixed: the lazily chosen manifold coordinates of a compiled result
(robotdyn.fast.compiled_derivatives._CompiledDerivatives), read from two threads at once.
"""

from __future__ import annotations

import numpy as np
import pytest
from concurrency import hammer, race
from test_dynamics_derivatives import START, admissible_state

import robotdyn
from robotdyn.errors import RobotDynError
from robotdyn.fast.compiled import available
from robotdyn.reduction.linearization import linearize, lqr
from robotdyn.robot import Robot
from robotdyn.robots import module
from robotdyn.simulation.engine import simulate
from robotdyn.simulation.feedback import lqr_law
from robotdyn.simulation.start_checks import start_offsets
from robotdyn.simulation.torque_profile import Constant

pytestmark = pytest.mark.skipif(not available(), reason="compiled extension not built")


def derivatives(robot, state) -> list:
    d = robot.dynamics_derivatives(*state)
    return [d.nudot, d.dq, d.dnu, d.dtau, d.qdot, d.dqdot_dq, d.S, d.positions, d.tangent, d.dq_manifold]


def unchecked(robot, state) -> list:
    d = robot.dynamics_derivatives(*state, check=False)
    return [d.nudot, d.dq, d.dnu, d.dtau, d.dqdot_dq]


def linear(robot, state) -> list:
    m = linearize(robot, *state)
    return [m.A, m.B, m.x0, m.xdot0, m.position_index, m.states]


def forces(robot, state) -> list:
    f = robot.contact_force_derivatives(*state)
    return [f.force, f.dforce_dq, f.dforce_dnu, f.dforce_dtau, f.required_mu, f.dmu_dq]


def forward(robot, state) -> list:
    return [robot.forward_dynamics(*state)]


KINDS = {"derivatives": derivatives, "unchecked": unchecked, "linear": linear, "forces": forces, "forward": forward}


@pytest.mark.parametrize("name", ["linkage_suspension", "mmr12_eod", "omni_caster", "adaptable_wheel"])
@pytest.mark.parametrize("shared", [True, False], ids=["one Robot", "four Robots"])
def test_derivatives_linearisation_and_force_derivatives_from_four_threads(name, shared):
    """Four threads, each making every kind of call at four states in its own order, twice: 136-168 concurrent
    calls per robot (the omni platform's operational velocities have no contact-force derivatives)."""
    robots = [Robot(module(name).SPEC)] * 4 if shared else [Robot(module(name).SPEC) for _ in range(4)]
    rng = np.random.default_rng(7)
    states = [admissible_state(robots[0], START[name], rng) for _ in range(4)]
    kinds = [k for k in KINDS if not (k == "forces" and robots[0].operational is not None)]
    calls, lanes = {}, []
    for t, robot in enumerate(robots):
        names = [f"{k} {i} on robot {id(robot)}" for k in kinds for i in range(len(states))]
        for k in kinds:
            for i, s in enumerate(states):
                calls[f"{k} {i} on robot {id(robot)}"] = lambda f=KINDS[k], r=robot, s=s: f(r, s)
        # (each thread starts with a derivative set, which lets its compiled model choose its rows: a thread's first
        # reduced-model evaluation, e.g. by forward_dynamics, is the Python reference's, equal to round-off only)
        lanes.append([names[0]] + list(np.random.default_rng(t).permutation(names)))
    problems, made = hammer(calls, lanes, reps=2)
    assert problems == [] and made == 4 * 2 * (len(kinds) * len(states) + 1)


@pytest.mark.parametrize("name", ["quasimoro", "linkage_suspension"])
def test_one_compiled_result_read_from_four_threads(name):
    """A compiled DynamicsDerivatives chooses its manifold coordinates (positions, tangent, dq_manifold) on first
    access. Before, the first reader took the inputs out of the object before it stored the three, so a second
    thread reading one of them meanwhile got an AttributeError (measured: in 11-20 of 50 rounds of four readers).
    Now they are chosen under a lock and stored together: 40 rounds of four threads read the values of a serial
    read, bit for bit."""
    robot = Robot(module(name).SPEC)
    state = admissible_state(robot, START[name], np.random.default_rng(1))
    first = robot.dynamics_derivatives(*state)
    expected = [first.positions, first.tangent, first.dq_manifold]
    problems = []
    for _ in range(40):
        D = robot.dynamics_derivatives(*state)

        def read(D=D):
            tangent, positions, dq = D.tangent, D.positions, D.dq_manifold
            if not all(np.array_equal(a, b) for a, b in zip([positions, tangent, dq], expected)):
                problems.append("wrong manifold coordinates")

        problems += race([read] * 4)
    assert problems == []


def test_quasimoro_lqr_runs_beside_derivatives_and_linearisations():
    """Quasimoro's LQR as data (lqr_law: the compiled loop, without the GIL) from 0.05-0.15 rad off upright and an
    open-loop compiled run in two threads, while two others take derivatives, linearisations and forward dynamics
    of the same Robot at other states."""
    robot = robotdyn.load("quasimoro")
    q0 = robot.neutral()
    model = linearize(robot, q0, np.zeros(3), np.zeros(2)).restrict(["theta3", "theta1_dot", "theta2_dot",
                                                                      "theta3_dot"])
    law = lqr_law(model, lqr(model, np.eye(4), np.eye(2))[0])
    theta3 = robot.coordinate_index("theta3")
    rng = np.random.default_rng(4)
    states = [admissible_state(robot, None, rng) for _ in range(4)]

    def run(offset):
        q = q0.copy()
        q[theta3] += offset
        tr = simulate(robot, 0.5, q, np.zeros(3), law, n_out=11, progress=False)
        return [tr.q, tr.nu, tr.energy, tr.stats["engine"]]

    calls = {f"lqr {a}": lambda a=a: run(a) for a in (0.05, 0.1, 0.15)}
    calls.update({f"{k} {i}": lambda f=KINDS[k], s=s: f(robot, s) for k in ("derivatives", "linear", "forward")
                  for i, s in enumerate(states)})

    def open_loop():
        tr = simulate(robot, 0.5, q0, np.zeros(3), Constant(np.array([0.2, -0.1])), n_out=11, progress=False)
        return [tr.q, tr.nu, tr.energy, tr.stats["engine"]]

    calls["open loop"] = open_loop
    assert calls["lqr 0.1"]()[3].startswith("compiled") and open_loop()[3].startswith("compiled")
    lanes = [["lqr 0.05", "lqr 0.1", "lqr 0.15"], ["lqr 0.15", "open loop", "lqr 0.05"],
             [f"derivatives {i}" for i in range(4)] * 5, [f"linear {i}" for i in range(4)] * 4 + ["forward 1"] * 4]
    problems, made = hammer(calls, lanes, reps=2)
    assert problems == [] and made == 2 * (3 + 3 + 20 + 20)


def test_linkage_controller_run_start_checks_and_derivatives_on_one_robot():
    """The six-wheel linkage rover (loop closures: holonomic rows) shared by four threads: its compiled
    ``straight_line`` run (wheel-speed feedback as data), derivatives and linearisations, contact-force
    derivatives, and simulate()'s start checks at a clean start (compiled residuals), one 1e-9 off (the Python rows)
    and one 1e-3 off (the refusal, the same one-line message from a direct simulate)."""
    robot = robotdyn.load("linkage_suspension")
    scenario = module("linkage_suspension").SCENARIOS["straight_line"]
    q0, nu0 = scenario.initial_state(robot)
    rng = np.random.default_rng(4)
    states = [admissible_state(robot, None, rng) for _ in range(3)]
    beta = robot.coordinate_index("beta1")
    starts = {"clean": q0, "near": q0 + 1e-9 * np.eye(robot.nq)[beta], "far": q0 + 1e-3 * np.eye(robot.nq)[beta]}

    def run():
        tr = scenario.run(robot, t_end=0.2, n_out=5, progress=False)
        return [tr.q, tr.nu, tr.stats["engine"]]

    def check(q):
        try:
            return [sorted(start_offsets(robot, q, 10.0).items())]
        except RobotDynError as exc:
            return [f"{type(exc).__name__}: {exc}"]

    def refused():
        try:
            simulate(robot, 0.05, starts["far"], nu0, scenario.torque, n_out=3, progress=False)
        except RobotDynError as exc:
            return [f"{type(exc).__name__}: {exc}"]
        return ["no error"]

    calls = {"run": run, "refused": refused}
    calls.update({f"start {k}": lambda q=q: check(q) for k, q in starts.items()})
    calls.update({f"{k} {i}": lambda f=KINDS[k], s=s: f(robot, s) for k in KINDS for i, s in enumerate(states)})
    assert run()[2].startswith("compiled")
    assert check(starts["clean"]) == check(starts["near"]) == [[]]
    assert refused()[0].startswith("ConstraintError: q violates constraint") and refused() == check(starts["far"])
    lanes = [["run", "forward 0"], [f"derivatives {i}" for i in range(3)] + [f"unchecked {i}" for i in range(3)],
             [f"linear {i}" for i in range(3)] + [f"forces {i}" for i in range(3)],
             ["start clean", "start near", "start far", "refused"] * 3]
    problems, made = hammer(calls, lanes, reps=2)
    assert problems == [] and made == 2 * (2 + 6 + 6 + 12)


def test_operational_controller_run_beside_derivatives_on_one_robot():
    """MMR12-EOD's ``orientation`` run (an operational-space controller that adds its task frames to the thread's
    compiled model) in one lane followed by derivatives in the same thread, while other threads take derivatives,
    linearisations and contact-force derivatives of the same Robot: the frames added leave every number unchanged."""
    robot = robotdyn.load("mmr12_eod")
    scenario = module("mmr12_eod").SCENARIOS["orientation"]
    rng = np.random.default_rng(2)
    states = [admissible_state(robot, START["mmr12_eod"], rng) for _ in range(3)]

    def run():
        tr = scenario.run(robot, t_end=0.1, n_out=6, progress=False)
        return [tr.q, tr.nu, tr.stats["engine"]]

    calls = {"run": run}
    calls.update({f"{k} {i}": lambda f=KINDS[k], s=s: f(robot, s) for k in KINDS for i, s in enumerate(states)})
    assert run()[2].startswith("compiled")
    lanes = [["run", "derivatives 0", "forces 1"], ["run", "linear 2", "unchecked 1"],
             [f"derivatives {i}" for i in range(3)] + [f"forces {i}" for i in range(3)],
             [f"linear {i}" for i in range(3)] + [f"unchecked {i}" for i in range(3)]]
    problems, made = hammer(calls, lanes, reps=2)
    assert problems == [] and made == 2 * (3 + 3 + 6 + 6)


def test_simulate_many_from_two_threads_beside_reduced():
    """simulate_many (its own C++ worker threads, two each) called from two Python threads at once on one Robot, while
    a third evaluates the reduced model: 4 calls of 4 runs each and 60 evaluations, each equal to the serial one."""
    from robotdyn.simulation.many_runs import simulate_many

    robot = robotdyn.load("quasimoro")
    q0 = robot.neutral()

    def many(a):
        runs = simulate_many(robot, 0.3, q0=np.tile(q0, (4, 1)), nu0=[[a, 0, 0], [0, a, 0], [0, 0, a], [a, a, 0]],
                             torque=Constant(np.array([0.1, -0.1])), n_out=5, threads=2, progress=False)
        return [runs.q, runs.nu, runs.ok]

    calls = {f"many {a}": lambda a=a: many(a) for a in (0.1, 0.2)}
    calls.update({f"reduced {i}": lambda i=i: [robot.reduced(q0, np.array([0.1 * i, 0.2, 0.0])).h.copy()]
                  for i in range(3)})
    lanes = [["many 0.1", "many 0.2"], ["many 0.2", "many 0.1"], ["reduced 0", "reduced 1", "reduced 2"] * 20]
    problems, made = hammer(calls, lanes, reps=1)
    assert problems == [] and made == 4 + 60
