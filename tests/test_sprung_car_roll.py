"""examples/sprung_car.toml braked harder on one side (issue 23): its chassis starts to roll, and on vertical
suspensions a rolled chassis cambers its wheels and moves their contact points sideways, which rolling-without-slip
wheels cannot follow (at the level configuration their sideways rows are dependent: mobility 4; rolled: 3). The run
stopped with "4 independent velocities chosen ... leave 3; expected exactly the mobility", which did not say why or
what to do. Now the one line says that the motion left the configuration where the rows were dependent and names
the remedy, and the remedy (tyres sliding sideways under a linear law, slip = "lateral", as
examples/sprung_cornering_car.toml) runs the same braking."""

from __future__ import annotations

from pathlib import Path

import pytest

from robotdyn.cli.commands import main
from robotdyn.fast.dispatch import use_compiled

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
UNEVEN = """
[[scenarios]]
name = "uneven"
description = "braking from 15 m/s, the left wheels three times harder than the right"
t_end = 0.5
torque = [-600.0, -200.0, -600.0, -200.0]
nu0 = { x = 15.0 }
"""


def car(tmp_path: Path, tyres: bool) -> Path:
    text = (EXAMPLES / "sprung_car.toml").read_text().replace('urdf = "', f'urdf = "{EXAMPLES}/') + UNEVEN
    if tyres:
        text = text.replace("mu = 1.0\n", 'mu = 1.0\nfriction = "linear"\nslip = "lateral"\nstiffness = 5.0\n')
        text = text.replace('independent = ["x", "z", "pitch", "roll"]',
                            'independent = ["x", "y", "z", "yaw", "pitch", "roll"]')
    path = tmp_path / "car.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("compiled", [True, False])
def test_rolling_the_rigid_sprung_car_says_what_to_do(tmp_path, capsys, compiled):
    with use_compiled(compiled):
        assert main(["simulate", "--constraints", str(car(tmp_path, False)), "--scenario", "uneven", "--quiet",
                     "--t-end", "0.05"]) == 2
    errors = capsys.readouterr().err.strip().splitlines()
    assert len(errors) == 1 and errors[0].startswith("robotdyn: error: at t = ")
    line = errors[0]
    assert "but the constraints leave 3" in line and "the motion has left the configuration it started in" in line
    assert "slip = 'lateral'" in line


def test_sprung_car_with_tyres_rolls_under_uneven_braking(tmp_path, capsys):
    import json

    assert main(["simulate", "--constraints", str(car(tmp_path, True)), "--scenario", "uneven", "--quiet",
                 "--t-end", "0.05", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert abs(out["final"]["roll"]) > 1e-5 and out["t_end"] == pytest.approx(0.05)
