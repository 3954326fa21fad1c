"""What a new user met running robotdyn on public ROS descriptions (Clearpath's Husky and Jackal, as shipped,
session 30), reproduced on our own fixtures (examples/bump_base.toml: a rigid four-wheel base on compliant tyres).

- Over a bump, the run's summary said ``first: lift-off of wheel front_left at t = 0.06722 s`` while its flight
  phases said ``lift-off 0.0720508 s`` for the same wheel (Husky: 0.0664 against 0.0728 s). Both are right about
  different things: a spring-damper tyre's force k d + c d' reaches zero (it never pulls) while the tyre still
  touches (d > 0, d' < 0); it leaves the ground when d = 0. The traction event of a compliant wheel is now called
  what it is, a zero load, and the word lift-off is kept for the instant the wheel leaves the ground.
- Turning the Husky in place under a Coulomb law took 78 s for 1 s simulated, on the scipy engine, and nothing
  said why (its loads are statically indeterminate: the rigid limit of compliance with friction had no compiled
  twin; it has one now). The summary now says why a run is not on the compiled engine.
- On Clearpath's Ridgeback (a mecanum base), ``info`` listed the four omni wheels without their roller angles,
  so a user could not check the handedness (+45/-45 deg) that decides whether the base moves sideways.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np

from robotdyn.cli import main
from robotdyn.contact.traction import traction
from robotdyn.interfaces.constraint_file import read

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def test_a_compliant_wheel_unloads_before_it_lifts_off_and_the_summary_says_so():
    cf = read(EXAMPLES / "bump_base.toml")
    robot = cf.robot()
    scenario = cf.SCENARIOS["bump"]
    traj = scenario.run(robot, t_end=0.1, n_out=201, progress=False)
    tr = traction(robot, traj, scenario.torque)
    lift = {e["wheel"]: e["t"] for e in traj.stats["flight"] if e["event"] == "lift-off"}
    first = tr.events[0]
    assert first.kind == "unloaded" and first.wheel in lift
    j = tr.wheels.index(first.wheel)
    k0, k1 = np.searchsorted(tr.t, first.t), np.searchsorted(tr.t, lift[first.wheel])
    assert k1 - k0 >= 5  # several samples apart (0.0668 against 0.0721 s) ...
    assert np.all(tr.normal[k0:k1, j] == 0.0)  # ... with zero load in between: unloaded, still touching
    text = tr.summary()
    assert "zero load of compliant wheel" in text and "lift-off of wheel" not in text, text


def test_a_run_off_the_compiled_engine_says_why(capsys):
    """(The Husky itself now runs compiled: tests/test_compiled_skid_slip.py; here the fast path is turned off.)"""
    from robotdyn.fast.dispatch import use_compiled

    argv = ["simulate", "quasimoro", "--scenario", "rectilinear", "--t-end", "0.01", "--quiet"]
    with use_compiled(False):
        assert main(argv) == 0
        out = capsys.readouterr().out
        assert "scipy" in out and "(not on the compiled engine: the compiled fast path is turned off" in out, out
        assert main([*argv, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["engine"].startswith("scipy") and "turned off" in data["engine_reason"]
    assert main(["simulate", "quasimoro", "--scenario", "rectilinear", "--t-end", "0.01", "--quiet"]) == 0
    assert "not on the compiled engine" not in capsys.readouterr().out  # (a compiled run: nothing to explain)


def test_info_shows_each_omni_wheel_roller_angle(tmp_path, capsys):
    import tomllib

    import tomli_w

    data = tomllib.loads((EXAMPLES / "skid_steer.toml").read_text())
    data["urdf"] = str(EXAMPLES / "skid_steer.urdf.xacro")
    data.pop("independent")
    for w, angle in zip(data["wheels"], ["45 deg", "-45 deg", "-45 deg", "45 deg"]):
        for key in ("friction", "stiffness", "mu"):
            w.pop(key, None)
        w["kind"], w["roller_angle"] = "omni", angle
    (tmp_path / "mecanum.toml").write_text(tomli_w.dumps(data))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["info", "--constraints", str(tmp_path / "mecanum.toml")]) == 0
    out = capsys.readouterr().out
    assert out.count("roller_angle=45 deg") == 2 and out.count("roller_angle=-45 deg") == 2, out
