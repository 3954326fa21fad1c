"""One story, spot-checked (session 30): the same robot, state and torques through the API (compiled and Python
path), ``dump --forces``, ``simulate`` (its first sample) and a sweep give the same numbers, for a robot on compliant
tyres (examples/bump_base.toml) and for a statically indeterminate rigid four-wheel chassis under a Coulomb law
(examples/husky_like.toml, loads from the rigid limit of compliance).

The sweep was the door that told another story: on husky_like it batched the runs on the compiled model, whose
slipping wheels had no friction there (their friction is not compiled on an indeterminate chassis, the model's
``slip_refusal``), so the base stood still while its wheels spun freely (yaw 0 and wheel speed 3.39 rad/s after
5 ms, against 0.091 rad/s and 0.61 rad/s from ``simulate``). Such runs are now built one at a time, and
``simulate_many`` refuses them in one line.
"""

from __future__ import annotations

import csv
import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from robotdyn.cli import main
from robotdyn.errors import RobotDynError
from robotdyn.fast.dispatch import use_compiled
from robotdyn.interfaces.constraint_file import read

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
CASES = [("bump_base.toml", "bump", 0.05), ("husky_like.toml", "turn_in_place", 0.005)]


def _robot(name: str, scenario: str):
    cf = read(EXAMPLES / name)
    robot = cf.robot()
    sc = cf.SCENARIOS[scenario]
    q0, nu0 = sc.initial_state(robot)
    return robot, sc, q0, nu0, np.asarray(sc.torque(0.0, q0, nu0), float)


def _out(capsys, argv) -> str:
    assert main(argv) == 0, capsys.readouterr().err
    return capsys.readouterr().out


@pytest.mark.parametrize("name, scenario, t_end", CASES)
def test_every_door_gives_the_same_accelerations_and_loads(name, scenario, t_end, capsys, tmp_path):
    robot, sc, q0, nu0, tau = _robot(name, scenario)
    with use_compiled(True):
        a, forces = robot.forward_dynamics(q0, nu0, tau), robot.contact_forces(q0, nu0, tau)
    with use_compiled(False):
        a_py, forces_py = robot.forward_dynamics(q0, nu0, tau), robot.contact_forces(q0, nu0, tau)
    loads = np.array([w.normal for w in forces.wheels])
    assert loads.min() > 10  # (every wheel carries load: the comparison is not of zeros)
    np.testing.assert_allclose(a_py, a, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose([w.normal for w in forces_py.wheels], loads, rtol=1e-12)
    numbers = lambda x: [repr(float(v)) for v in x]  # noqa: E731
    path = str(EXAMPLES / name)
    dump = json.loads(_out(capsys, ["dump", "--constraints", path, "--q", *numbers(q0), "--v", *numbers(nu0), "--tau",
                                    *numbers(tau), "--forces", "--json"]))
    np.testing.assert_allclose(dump["a"], a, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose([dump["forces"]["wheels"][w.name]["normal"] for w in forces.wheels], loads, rtol=1e-12)
    _out(capsys, ["simulate", "--constraints", path, "--scenario", scenario, "--t-end", str(t_end), "--quiet",
                  "--csv", str(tmp_path / "run.csv")])
    with open(tmp_path / "run.csv") as fh:
        first = next(csv.DictReader(line for line in fh if not line.startswith("#")))
    np.testing.assert_allclose([float(first[f"{w.name}.normal"]) for w in forces.wheels], loads, rtol=1e-12)


@pytest.mark.parametrize("name, scenario, t_end", CASES)
def test_a_sweep_run_is_the_simulate_run(name, scenario, t_end, capsys, tmp_path):
    """A one-run sweep (torque scale 1) ends where the API's run of the scenario ends, bit for bit (on husky_like
    the sweep used to batch it on a compiled model without the wheels' friction)."""
    import pyarrow.parquet as pq

    robot, sc, *_ = _robot(name, scenario)
    traj = sc.run(robot, t_end=t_end, n_out=11, progress=False)
    _out(capsys, ["sweep", "--constraints", str(EXAMPLES / name), "--scenario", scenario, "--vary", "torque_scale=1",
                  "--t-end", str(t_end), "--n-out", "11", "--out", str(tmp_path / "sweep"), "--workers", "0",
                  "--quiet", "--no-plot"])
    row = pq.read_table(tmp_path / "sweep" / "results.parquet").to_pylist()[0]
    assert row["status"] == "ok", row["error"]
    final = np.concatenate([traj.q[-1], traj.nu[-1]])
    got = [row[f"final.{c}"] for c in traj.coordinates + traj.velocity_names]
    np.testing.assert_array_equal(got, final)


def test_simulate_many_refuses_slipping_wheels_whose_friction_is_not_compiled():
    from robotdyn.simulation.many_runs import simulate_many

    robot, sc, q0, nu0, _ = _robot("husky_like.toml", "turn_in_place")
    with pytest.raises(RobotDynError, match="slipping wheels"):
        simulate_many(robot, 0.005, q0[None], nu0[None], sc.torque, n_out=3)
