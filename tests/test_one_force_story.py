"""One force story (issue 23, item 4): ``dump`` honours the wheels' friction laws as forward_dynamics and
simulate do, and the traction summary never says the no-slip assumption holds for wheels that slide by design.

On examples/skid_steer.toml at v = (0, 0, 0, 5, 5, 5, 5), tau = 0.3 per wheel the accelerations come from the
coupled solve of accelerations, loads and friction (robotdyn.contact.sliding.forward): the wheels spin down
(-757 and -1046 rad/s^2) instead of the 60 rad/s^2 of the frictionless reduced model; those accelerations given
back to ``dump --a`` give the torques 0.3 with no residual; ``--forces`` with ``--tau`` prints the forces."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from robotdyn.cli.commands import main
from robotdyn.interfaces.constraint_file import read

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "skid_steer.toml"
V = ["0", "0", "0", "5", "5", "5", "5"]


def _dump(capsys, *extra) -> dict:
    assert main(["dump", "--constraints", str(EXAMPLE), "--v", *V, "--json", *extra]) == 0
    return json.loads(capsys.readouterr().out)


def test_dump_honours_the_friction_law(capsys):
    robot = read(EXAMPLE).robot()
    q = robot.neutral()
    nu = np.array([float(x) for x in V])
    tau = np.full(4, 0.3)
    reference = robot.forward_dynamics(q, nu, tau)
    assert reference[3] == pytest.approx(-756.6, abs=0.1) and reference[5] == pytest.approx(-1046.1, abs=0.1)
    out = _dump(capsys, "--tau", "0.3", "0.3", "0.3", "0.3", "--forces")
    np.testing.assert_allclose(out["a"], reference, rtol=1e-12, atol=1e-9)
    assert out["forces"]["wheels"]["front_left"]["normal"] > 0
    back = _dump(capsys, "--a", *[repr(float(x)) for x in reference])
    np.testing.assert_allclose(list(back["motor_torques"].values()), tau, atol=1e-8)
    assert back["motor_residual"] < 1e-8


def test_summary_never_says_holds_for_sliding_wheels(capsys):
    assert main(["simulate", "--constraints", str(EXAMPLE), "--scenario", "straight", "--t-end", "0.05", "--mu", "0.5",
                 "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "holds" not in out and "slide under their friction law" in out
