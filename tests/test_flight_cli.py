"""The command line with springs and compliant wheels: simulate reports the wheels' flight phases (lift-off and
touch-down per wheel) instead of stopping at lift-off, and the work of friction and dampers; bad springs and
compliant-wheel entries are one-line errors with exit status 2; the compiled engine runs such robots and refuses
in one line what it cannot run (e.g. torques given as a Python function)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "robotdyn", *args], capture_output=True, text=True, timeout=300)


def test_simulate_reports_flight_phases():
    out = run("simulate", "--constraints", str(EXAMPLES / "bump_base.toml"), "--scenario", "bump", "--t-end", "0.1",
              "--quiet", "--json")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    lifts = {e["wheel"]: e["t"] for e in data["flight"] if e["event"] == "lift-off"}
    # both front wheels leave the crest of the bump together (the base is symmetric), the rear ones not yet
    assert set(lifts) == {"front_left", "front_right"}
    assert lifts["front_left"] == pytest.approx(lifts["front_right"], abs=1e-9)
    assert 0.06 < lifts["front_left"] < 0.08
    assert "stopped" not in data  # the run goes on: the wheels fly
    assert data["damper_work"] < 0 and data["friction_work"] <= 0


def test_flight_summary_lines():
    from robotdyn.simulation.flight import flight_summary

    phases = [{"t": 0.1, "wheel": "a", "event": "lift-off"}, {"t": 0.2, "wheel": "b", "event": "touch-down"},
              {"t": 0.3, "wheel": "a", "event": "touch-down"}]
    assert flight_summary(phases, ["b"]) == ["wheel b: in the air at the start, touch-down 0.2 s",
                                             "wheel a: lift-off 0.1 s, touch-down 0.3 s"]


@pytest.mark.parametrize("entry, message", [
    ('[[springs]]\njoint = "nope"\nstiffness = 1.0\n', "springs[4]: joint: no joint named 'nope'"),
    ('[[springs]]\njoint = "front_left_suspension"\nstiffness = -1.0\n', "springs[4].stiffness = -1.0; expected a "
                                                                         "stiffness in N/m or N m/rad, >= 0"),
    ('[[springs]]\njoint = "front_left_suspension"\nstifness = 1.0\n', "unknown key 'stifness'; did you mean "
                                                                       "'stiffness'?"),
])
def test_bad_springs_are_one_line(tmp_path, entry, message):
    text = (EXAMPLES / "sprung_car.toml").read_text().replace('urdf = "sprung_car.urdf.xacro"',
                                                              f'urdf = "{EXAMPLES / "sprung_car.urdf.xacro"}"')
    path = tmp_path / "car.toml"
    path.write_text(text + "\n" + entry)
    out = run("info", "--constraints", str(path))
    assert out.returncode == 2
    assert len(out.stderr.strip().splitlines()) == 1 and message in out.stderr, out.stderr


def test_compliant_wheel_with_stick_slip_is_one_line(tmp_path):
    """A compliant wheel takes friction = rolling (it rolls while in contact, robotdyn.contact.compliant_rolling),
    coulomb or linear; stick_slip is refused in one line (it was 'rolling' that was refused before rolling while
    compliant was modelled)."""
    text = (EXAMPLES / "bump_base.toml").read_text().replace('urdf = "skid_steer.urdf.xacro"',
                                                             f'urdf = "{EXAMPLES / "skid_steer.urdf.xacro"}"')
    path = tmp_path / "base.toml"
    path.write_text(text.replace('friction = "linear"', 'friction = "stick_slip"', 1).replace(
        "stiffness = 5.0         #", "#", 1))
    out = run("info", "--constraints", str(path))
    assert out.returncode == 2
    assert len(out.stderr.strip().splitlines()) == 1
    assert "contact = 'compliant' takes friction = 'rolling' (rolls while in contact), 'coulomb' or 'linear'" \
        in out.stderr, out.stderr


def test_compiled_engine_runs_springs_and_refuses_a_python_torque_in_one_line():
    from robotdyn.errors import RobotDynError
    from robotdyn.fast.compiled import available
    from robotdyn.interfaces.constraint_file import read
    from robotdyn.simulation.engine import simulate

    cf = read(EXAMPLES / "sprung_car.toml")
    robot = cf.robot()
    q0, nu0 = cf.SCENARIOS["brake"].initial_state(robot)
    with pytest.raises(RobotDynError, match="^engine = 'compiled' cannot run this simulation: the torques are a "
                                            "Python function"):
        simulate(robot, 0.1, q0, nu0, lambda t, q, nu: np.zeros(4), engine="compiled", progress=False)
    traj = simulate(robot, 0.1, q0, nu0, progress=False)  # auto: the compiled engine where it is built
    assert traj.stats["engine"] == ("compiled (adams)" if available() else "scipy (DOP853)")
    assert np.isfinite(traj.q).all() and traj.damper_work is not None


def test_dump_applies_the_springs():
    """At its design height the sprung car's preloaded springs carry the chassis: zero heave and pitch
    accelerations at rest, from dump as from the API (dump ignored the springs before: -9.81 m/s^2)."""
    from robotdyn.interfaces.constraint_file import load_robot

    out = run("dump", "--constraints", str(EXAMPLES / "sprung_car.toml"), "--v", "0", "0", "0", "0", "--tau", "0", "0", "0", "0", "--forces",
              "--json")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    robot = load_robot(EXAMPLES / "sprung_car.toml")
    expected = robot.forward_dynamics(robot.neutral(), np.zeros(4), np.zeros(4))
    assert np.allclose(data["a"], expected, atol=1e-12)
    assert np.max(np.abs(expected)) < 1e-9
    total = sum(w["normal"] for w in data["forces"]["wheels"].values())
    import pinocchio as pin
    assert total == pytest.approx(pin.computeTotalMass(robot.model) * 9.81, rel=1e-12)


def test_dump_inverse_names_the_springs():
    """dump --a on the sprung car at rest: the generalised forces are M a + C v + g less the springs' forces, and
    the label says so (it printed "M a + C v + g" while taking the springs off); at rest on its preloaded springs
    they vanish (no torque needed to hold it), as the forward dynamics' zero accelerations say."""
    out = run("dump", "--constraints", str(EXAMPLES / "sprung_car.toml"), "--v", "0", "0", "0", "0", "--a", "0", "0",
              "0", "0")
    assert out.returncode == 0, out.stderr
    assert "tau (generalised forces M a + C v + g - Q_springs/contacts):" in out.stdout
    out = run("dump", "--constraints", str(EXAMPLES / "sprung_car.toml"), "--v", "0", "0", "0", "0", "--a", "0", "0",
              "0", "0", "--json")
    data = json.loads(out.stdout)
    assert np.max(np.abs(data["tau"])) < 1e-6  # the chassis' weight, ~1e4 N, is carried by the springs


def test_simulate_method_option_runs_cvode_and_refuses_an_unknown_one():
    """--method reaches simulate: CVODE (SUNDIALS' BDF) on the compliant base gives the default dopri5's flight
    phases to its tolerance (the API's own comparison is tests/test_cvode.py); an unknown name is one line, exit 2."""
    base = ("simulate", "--constraints", str(EXAMPLES / "bump_base.toml"), "--scenario", "bump", "--t-end", "0.1",
            "--quiet", "--json")
    runs = {m: run(*base, *(("--method", m) if m else ())) for m in (None, "cvode")}
    for out in runs.values():
        assert out.returncode == 0, out.stderr
    data = {m: json.loads(out.stdout) for m, out in runs.items()}
    lifts = {m: sorted((e["wheel"], e["t"]) for e in d["flight"] if e["event"] == "lift-off") for m, d in data.items()}
    assert [w for w, _ in lifts["cvode"]] == [w for w, _ in lifts[None]] == ["front_left", "front_right"]
    assert np.allclose([t for _, t in lifts["cvode"]], [t for _, t in lifts[None]], atol=1e-6)
    bad = run(*base, "--method", "cvod")
    assert bad.returncode == 2
    error = bad.stderr.splitlines()  # (the example loads silently: it gives its independent velocities)
    assert len(error) == 1 and "method = 'cvod'; expected one of" in error[0] and "Traceback" not in bad.stderr
