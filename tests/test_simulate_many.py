"""Many simulations in one call (robotdyn.simulation.batch.simulate_many) and the model variants behind per-run parameters
(robotdyn.simulation.model_variants): every run equals the same run alone through the compiled simulate, bit for bit, on
1 or 2 threads; a parameter variant's model equals the robot rebuilt from its description (Xacro) with those
values; what cannot vary without a rebuild is refused in one line."""

from __future__ import annotations

import pickle
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import robotdyn
from robotdyn.simulation.batch import simulate_many
from robotdyn.fast.dispatch import available
from robotdyn.errors import InputError, RobotDynError
from robotdyn.simulation.model_variants import ParameterModel, model_vector, variant
from robotdyn.robots import module
from robotdyn.simulation.engine import simulate
from robotdyn.simulation.torque_profile import Constant, Sine

pytestmark = pytest.mark.skipif(not available(), reason="compiled extension not built")

PULSE = module("quasimoro").SCENARIOS["rectilinear"].torque


def _params(N: int, seed: int = 0) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    return {"M": rng.uniform(4.5, 5.5, N), "m": rng.uniform(0.4, 0.6, N), "d": rng.uniform(0.15, 0.22, N),
            "r": rng.uniform(0.27, 0.33, N), "J1": rng.uniform(0.18, 0.22, N), "g": rng.uniform(9.7, 9.9, N)}


def test_parameter_variants_equal_rebuilt_robots(quasimoro):
    """The fitted model vectors equal those of robots built from the Xacro with the same values (to round-off),
    and their trajectories equal the rebuilt robots' to 1e-9."""
    params = _params(5)
    fit = ParameterModel(quasimoro, {k: (v.min(), v.max()) for k, v in params.items()})
    V = fit.vectors(np.column_stack(list(params.values())))
    for i in range(5):
        rebuilt = robotdyn.load("quasimoro", {k: float(v[i]) for k, v in params.items()})
        ref = model_vector(rebuilt)
        assert np.max(np.abs(V[i] - ref)) <= 1e-13 * max(1.0, np.max(np.abs(ref)))
    runs = simulate_many(quasimoro, 3.0, torque=PULSE, params=params, n_out=31, threads=2)
    for i in (0, 3):
        rebuilt = robotdyn.load("quasimoro", {k: float(v[i]) for k, v in params.items()})
        alone = simulate(rebuilt, 3.0, rebuilt.neutral(), np.zeros(3), PULSE, n_out=31, progress=False)
        assert np.max(np.abs(alone.q - runs.q[i])) <= 1e-9 and np.max(np.abs(alone.nu - runs.nu[i])) <= 1e-9


def test_runs_are_bitwise_alone_and_thread_independent(quasimoro):
    params = _params(6, seed=1)
    one = simulate_many(quasimoro, 3.0, torque=PULSE, params=params, n_out=31, threads=1)
    two = simulate_many(quasimoro, 3.0, torque=PULSE, params=params, n_out=31, threads=2)
    for key in ("q", "nu", "energy", "residual", "nfev"):
        assert np.array_equal(getattr(one, key), getattr(two, key)), key
    assert one.ok.all() and one.stats["threads"] == 1 and two.stats["threads"] == 2
    for i in (0, 5):  # the run's own model vector (the fit's round-off included) on a robot of its own
        alone = simulate(variant(quasimoro, two.models[i]), 3.0, quasimoro.neutral(), np.zeros(3), PULSE, n_out=31,
                         progress=False)
        assert np.array_equal(alone.q, two.q[i]) and np.array_equal(alone.nu, two.nu[i])
        assert np.array_equal(alone.energy, two.energy[i])


def test_states_and_profiles_per_run_equal_simulate(quasimoro):
    rng = np.random.default_rng(2)
    N = 4
    Q0 = np.tile(quasimoro.neutral(), (N, 1))
    Q0[:, quasimoro.coordinate_index("theta3")] = rng.uniform(-0.3, 0.3, N)
    NU0 = rng.normal(scale=0.3, size=(N, 3))
    profiles = [Constant([0.05 * i, -0.02]) + Sine([0.1, 0.1], 2.0 + i, start=0.0, stop=1.0) for i in range(N)]
    runs = simulate_many("quasimoro", 2.0, Q0, NU0, profiles, n_out=21, threads=2)
    for i in range(N):
        alone = simulate(quasimoro, 2.0, Q0[i], NU0[i], profiles[i], n_out=21, progress=False)
        assert np.array_equal(alone.q, runs.q[i]) and np.array_equal(alone.nu, runs.nu[i])
    again = pickle.loads(pickle.dumps(runs))  # plain arrays: a Dask worker returns it
    assert np.array_equal(again.q, runs.q) and again.messages == runs.messages


def test_list_of_robots(quasimoro):
    robots = [robotdyn.load("quasimoro", {"M": 4.0 + i, "rho": 0.4 + 0.05 * i}) for i in range(3)]
    runs = simulate_many(quasimoro, 2.0, torque=PULSE, robots=robots, n_out=21)
    for i, r in enumerate(robots):
        alone = simulate(r, 2.0, r.neutral(), np.zeros(3), PULSE, n_out=21, progress=False)
        assert np.max(np.abs(alone.q - runs.q[i])) == 0.0
    other = robotdyn.load("omni_caster")
    with pytest.raises(RobotDynError, match=r"robots\[0\] differs"):
        simulate_many(quasimoro, 1.0, robots=[other])


def test_what_cannot_vary_is_refused_in_one_line(quasimoro):
    # rho = r / l places the wheels at r / (2 rho): not a polynomial of rho
    with pytest.raises(InputError, match="rho enter the model other than as a polynomial") as err:
        simulate_many(quasimoro, 1.0, params={"rho": np.linspace(0.4, 0.6, 4)})
    assert "\n" not in str(err.value)
    with pytest.raises(InputError, match="choice"):
        simulate_many(quasimoro, 1.0, params={"inertia_about": ["axle", "com"]})
    with pytest.raises(RobotDynError, match="Python function"):
        simulate_many(quasimoro, 1.0, torque=[lambda t, q, nu: np.zeros(2)])
    with pytest.raises(RobotDynError, match="expected one length"):
        simulate_many(quasimoro, 1.0, params={"M": [5.0, 6.0], "m": [0.5]})
    with pytest.raises(RobotDynError, match=r"nu0 has shape \(2, 3\); expected \(3, 3\)"):
        simulate_many(quasimoro, 1.0, q0=np.zeros((3, 6)), nu0=np.zeros((2, 3)))
    with pytest.raises(InputError, match="outside the fitted range"):
        simulate_many(quasimoro, 1.0, params={"M": [5.0, 6.0]}, bounds={"M": (4.0, 5.5)})


def test_unphysical_runs_are_flagged_and_the_others_run(quasimoro):
    """With the axle reading the body's principal central inertias are (J2 - M d^2, J2 - M d^2, J1): the
    triangle inequality needs 2 (J2 - M d^2) >= J1, which the last run (2 x 0.1338 < 0.3) breaks. It is flagged
    with the reason; the others run."""
    params = {"M": np.array([5.0, 4.5, 5.5]), "d": np.array([0.2, 0.15, 0.22]), "J1": np.array([0.2, 0.18, 0.3])}
    runs = simulate_many(quasimoro, 1.0, params=params, n_out=11)
    assert list(runs.ok) == [True, True, False]
    assert "not physical" in runs.messages[2] and np.isnan(runs.q[2]).all() and runs.messages[0] == ""


def test_a_run_violating_its_constraints_fails_alone():
    robot = robotdyn.load("linkage_suspension")
    q0, nu0 = module("linkage_suspension").SCENARIOS["ramp_free"].initial_state(robot)
    Q0 = np.tile(q0, (2, 1))
    Q0[1, robot.coordinate_index("z")] += 1e-3  # lifted off the terrain
    runs = simulate_many(robot, 0.2, Q0, nu0, n_out=5)
    assert list(runs.ok) == [True, False] and "q0 violates constraint" in runs.messages[1]


INTERRUPTED = """
import numpy as np, robotdyn
from robotdyn.simulation.batch import simulate_many
from robotdyn.robots import module
robot = robotdyn.load("quasimoro")
print("ready", flush=True)
runs = simulate_many(robot, 60.0, torque=module("quasimoro").SCENARIOS["rectilinear"].torque,
                     nu0=np.random.default_rng(0).normal(scale=0.1, size=(4000, 3)), threads=2)
print(int(runs.ok.sum()), len(runs), runs.stats.get("partial"))
"""


def test_ctrl_c_keeps_the_finished_runs():
    proc = subprocess.Popen([sys.executable, "-c", INTERRUPTED], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert proc.stdout.readline().strip() == "ready"
    time.sleep(2.0)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    done, total, *partial = out.split()
    assert 0 < int(done) < int(total) == 4000 and "interrupted" in " ".join(partial)


def test_model_vectors_per_run_are_the_params_runs(quasimoro):
    """Model vectors given directly (as a sweep's chunk sends them) give the runs that params give, bit for bit;
    each run's integration wall time is reported."""
    params = _params(4, seed=3)
    by_params = simulate_many(quasimoro, 2.0, torque=PULSE, params=params, n_out=21, threads=1)
    by_models = simulate_many(quasimoro, 2.0, torque=PULSE, models=by_params.models, n_out=21, threads=2)
    assert np.array_equal(by_params.q, by_models.q) and np.array_equal(by_params.nu, by_models.nu)
    assert np.array_equal(by_models.models, by_params.models)
    assert by_models.walls.shape == (4,) and np.all(by_models.walls > 0)
    with pytest.raises(RobotDynError, match=r"models has shape \(4, 3\); expected \(N, \d+\)"):
        simulate_many(quasimoro, 2.0, torque=PULSE, models=np.zeros((4, 3)))
    with pytest.raises(RobotDynError, match="not more than one"):
        simulate_many(quasimoro, 2.0, params=params, models=by_params.models)


def test_a_run_past_its_time_limit_is_flagged_and_named(quasimoro):
    """A wall-clock limit per run: the long run stops (checked about every 50 ms) with a message naming the limit
    and the time reached; the short one finishes."""
    runs = simulate_many(quasimoro, 5000.0, torque=[PULSE, PULSE], q0=quasimoro.neutral(),
                         nu0=[[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]], n_out=3, threads=1, time_limit=0.1)
    assert not runs.ok.any()
    assert all(m.startswith("the run exceeded its time limit of 0.1 s at t = ") and m.endswith("s of 5000 s")
               for m in runs.messages)
    assert np.all(runs.walls < 1.0)
    assert simulate_many(quasimoro, 1.0, torque=PULSE, n_out=3, time_limit=5.0).ok.all()
    with pytest.raises(RobotDynError, match="time_limit = -1 s"):
        simulate_many(quasimoro, 1.0, time_limit=-1)
