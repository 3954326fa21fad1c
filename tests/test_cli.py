"""The command line as a user meets it: outputs, JSON keys, and one-line errors with exit status 2."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

import robotdyn


def run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "robotdyn", *args], capture_output=True, text=True, timeout=300)


Q = ["0", "0", "0", "0.1", "-0.2", "0.3"]  # x y psi theta1 theta2 theta3 (the order info lists)


def test_list_and_info():
    out = json.loads(run("list", "--json").stdout)
    assert "quasimoro" in out["robots"]
    info = json.loads(run("info", "quasimoro", "--json").stdout)
    robot = robotdyn.load("quasimoro")
    assert info["coordinates"] == robot.coordinates
    assert info["independent_velocities"] == ["theta1_dot", "theta2_dot", "theta3_dot"]
    assert info["parameters"]["M"] == {"value": 5.0, "unit": "kg", "description": robot.spec.parameter("M").description}


def test_dump_json_equals_the_python_api():
    res = run("dump", "quasimoro", "--q", *Q, "--v", "1", "0.5", "0.2", "--a", "0.1", "0.2", "0.3", "--json")
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    assert set(["coordinates", "M", "C", "g", "tau"]) <= set(out)
    robot = robotdyn.load("quasimoro")
    assert robot.coordinates == ["x", "y", "psi", "theta1", "theta2", "theta3"]
    red = robot.reduced(np.array(Q, float), [1, 0.5, 0.2], coriolis=True)
    assert np.allclose(out["M"], red.M, atol=1e-14) and np.allclose(out["C"], red.C, atol=1e-14)
    assert np.allclose(out["tau"], red.M @ [0.1, 0.2, 0.3] + red.h, atol=1e-14)
    # forward dynamics round trip: the motor torques of a feasible motion give back its accelerations
    res = run("dump", "quasimoro", "--q", *Q, "--v", "1", "0.5", "0.2", "--tau", "0.1", "-0.05", "--json")
    a = json.loads(res.stdout)["a"]
    Q_r = red.M @ a + red.h
    assert np.allclose(Q_r, red.B @ [0.1, -0.05], atol=1e-12)


def test_dump_full_is_the_unconstrained_tree():
    v = ["0.1", "0.2", "0.3", "0.4", "0.5", "0.6"]
    out = json.loads(run("dump", "quasimoro", "--q", *Q, "--v", *v, "--full", "--json").stdout)
    M, C, g = robotdyn.load("quasimoro").full(np.array(Q, float), np.array(v, float))
    assert np.allclose(out["M"], M) and np.allclose(out["C"], C) and np.allclose(out["g"], g)


def test_simulate_writes_csv_and_plot(tmp_path):
    csv, png = tmp_path / "r.csv", tmp_path / "r.png"
    res = run("simulate", "quasimoro", "--scenario", "rectilinear", "--t-end", "2", "--csv", str(csv),
              "--plot", str(png), "--quiet")
    assert res.returncode == 0, res.stderr
    header = csv.read_text().splitlines()[0].split(",")
    robot = robotdyn.load("quasimoro")
    # then the traction columns: normal loads (from the floating twin) and the smallest mu that admits a split of
    # the two wheels' lateral forces in both cones (robotdyn.contact.traction)
    assert header == ["t", *robot.coordinates, "theta1_dot", "theta2_dot", "theta3_dot", "wheel_A.normal",
                      "wheel_B.normal", "mu_required_min"]
    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    assert data[-1, 0] == pytest.approx(2.0) and png.stat().st_size > 10_000


@pytest.mark.parametrize(
    "args, message",
    [
        (["info", "quasimodo"], "unknown robot 'quasimodo'"),
        (["dump", "quasimoro", "--q", "0", "0", "--v", "1", "1", "1"], "q has 2 values; expected 6 values"),
        (["dump", "quasimoro", "--q", *Q, "--v", "1", "1"], "v has 2 values; expected 3 values"),
        (["dump", "quasimoro", "--q", *Q[:-1], "nan", "--v", "1", "1", "1"], "is not finite"),
        (["dump", "quasimoro", "--q", *Q[:-1], "abc", "--v", "1", "1", "1"], "'abc' is not a number"),
        (["dump", "quasimoro", "--q", *Q, "--v", "1", "1", "1", "--tau", "1"], "tau has 1 values; expected 2"),
        (["info", "quasimoro", "--param", "mass=3"], "unknown parameter 'mass'"),
        (["info", "quasimoro", "--param", "M=heavy"], "parameter M = 'heavy' is not a number"),
        (["info", "quasimoro", "--param", "J2=0.01"], "non-positive inertia"),
        (["info", "quasimoro", "--param", "inertia_about=wheel"], "expected one of axle, com"),
        (["simulate", "quasimoro", "--scenario", "loop"], "unknown scenario 'loop'"),
        (["simulate", "quasimoro", "--scenario", "rectilinear", "--t-end", "-1"], "expected a positive duration"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(args, message):
    res = run(*args)
    assert res.returncode == 2
    assert "Traceback" not in res.stderr
    lines = [line for line in res.stderr.splitlines() if not line.startswith("robotdyn: warning")]
    assert len(lines) == 1 and message in lines[0], res.stderr
