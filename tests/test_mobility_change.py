"""A steerable base leaving its parallel-wheel configuration during ``simulate`` (issue 24): the project's swerve3
example at neutral has its three wheels parallel (mobility 4, one more than anywhere near it); torques that steer
the rear wheels apart take it where the independent velocities chosen there no longer fit. The compiled engine let
``robotdyn._compiled.Fallback: row choice no longer spans`` escape as a traceback, and the scipy engine said one
line without the time. Now both say the same one line, with the simulated time."""

from __future__ import annotations

from pathlib import Path

import pytest

from robotdyn.cli.commands import main
from robotdyn.simulation.compiled_engine import MOBILITY_DROP

TOML = Path(__file__).resolve().parents[1] / "examples" / "ros_ws" / "src" / "demo_description" / "robotdyn"


@pytest.fixture()
def swerve(tmp_path) -> Path:
    text = (TOML / "swerve3.toml").read_text().replace('package_dirs = ["../.."]',
                                                        f'package_dirs = ["{TOML.parents[1]}"]')
    text += '''
[[scenarios]]
name = "split"
description = "drive forwards, steer the rear wheels apart"
t_end = 1.0
torque = [0.1, 0.0, 0.01, -0.01]
nu0 = { x = 0.5 }
'''
    path = tmp_path / "swerve3.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("compiled", ["1", "0"])
def test_leaving_the_parallel_configuration_is_one_line_with_the_time(swerve, capsys, compiled):
    from robotdyn.fast.dispatch import use_compiled

    with use_compiled(compiled == "1"):
        assert main(["simulate", "--constraints", str(swerve), "--scenario", "split", "--quiet"]) == 2
    errors = [line for line in capsys.readouterr().err.splitlines() if line.startswith("robotdyn: error:")]
    assert len(errors) == 1
    line = errors[0]
    assert line.startswith("robotdyn: error: at t = ")
    t = float(line.split("at t = ")[1].split(" s:")[0])
    assert 0 < t < 1.0
    assert line.endswith("4 independent velocities chosen (x_dot, front_steer_joint_dot, rear_left_steer_joint_dot, "
                         "rear_right_steer_joint_dot) but the constraints leave 3 (n = 9, rank A = 6); expected "
                         "exactly the mobility" + MOBILITY_DROP)
