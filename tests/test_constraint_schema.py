"""The constraint file's schema (robotdyn/interfaces/constraint_schema.py) and the physical ranges of parameters (issue 15):
every shipped constraint file is valid, mistakes are one line naming the entry with a suggestion for a misspelt
key, and a parameter's physical range follows its unit unless the file declares a minimum."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import pytest

from robotdyn.interfaces.constraint_file import ConstraintFileError, load_robot
from robotdyn.interfaces.constraint_schema import schema_problem
from robotdyn.errors import InputError
from robotdyn.robot import Parameter

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = sorted(ROOT.glob("examples/**/*.toml"))


@pytest.mark.parametrize("path", SHIPPED, ids=[str(p.relative_to(ROOT)) for p in SHIPPED])
def test_shipped_constraint_files_are_valid(path):
    data = tomllib.loads(path.read_text())
    if "wheels" not in data and "motors" not in data and "root" not in data:
        pytest.skip("not a constraint file")
    assert schema_problem(data) is None


@pytest.mark.parametrize("data, expected", [
    ({"wheels": [{"name": "left", "radious": 0.1}]}, "wheels[0] (left): unknown key 'radious'; did you mean 'radius'?"),
    ({"rooot": "planar"}, "unknown key 'rooot'; did you mean 'root'?"),
    ({"root": "planer"}, "root = 'planer'; did you mean 'planar'?"),
    ({"wheels": [{"radius": -0.1}]}, "wheels[0].radius = -0.1; expected a radius in m, > 0"),
    ({"wheels": [{"radius": math.nan}]}, "wheels[0].radius = nan; expected a radius in m"),
    ({"wheels": [{"axis": [0, 1]}]}, "wheels[0].axis = [0, 1]; expected 3 numbers"),
    ({"terrain": {"kind": {"a": 1}}}, "terrain.kind = {'a': 1}; expected one of flat, ramp, bump, sine"),
    ({"terrain": {"kind": "bump", "width": 0.0}}, "terrain.width = 0.0; expected a width in m, > 0"),
    ({"scenarios": [{"name": "s", "t_end": 1e300}]}, "scenarios[0] (s).t_end = 1e+300; expected a duration in s"),
    ({"scenarios": [{"name": "s"}]}, "scenarios[0] (s): missing 't_end'"),
    ({"neutral": {"x": math.inf}}, "neutral.x = inf; expected a coordinate in m or rad"),
    ({"labels": ["a"]}, "labels = ['a']; expected a table of display names by joint"),
    ({"motors": {"joint": "j"}}, "motors = {'joint': 'j'}; expected an array of tables ([[motors]])"),
    ({"title": {"a": 1}}, "title = {'a': 1}; expected a string"),
])
def test_mistakes_name_the_entry(data, expected):
    message = schema_problem(data)
    assert message is not None and expected in message and "\n" not in message


def test_parameter_ranges_by_unit_and_declared_minimum():
    assert Parameter("zF", -0.05, "m").convert("0.1") == 0.1  # an offset may change sign
    assert Parameter("x0", 0.1, "m", minimum=-1.0).convert("-0.5") == -0.5
    with pytest.raises(InputError, match="expected a value >= -1"):
        Parameter("x0", 0.1, "m", minimum=-1.0).convert("-2")
    with pytest.raises(InputError, match="expected a magnitude <= 10000 m"):
        Parameter("r", 0.1, "m").convert("1e5")
    with pytest.raises(InputError, match="expected a value >= 0"):
        Parameter("M", 5.0, "kg").convert("-1")


def test_a_declared_minimum_in_a_constraint_file(tmp_path):
    """[[parameters]] minimum: the default must respect it, and so must --param values."""
    text = (ROOT / "examples" / "skid_steer.toml").read_text().replace(
        'urdf = "skid_steer.urdf.xacro"', f'urdf = "{ROOT / "examples" / "skid_steer.urdf.xacro"}"')
    path = tmp_path / "robot.toml"
    path.write_text(text.replace('unit = "m"', 'unit = "m"\nminimum = 0.05'))
    assert load_robot(path, params={"r": 0.06}).params["r"] == 0.06
    with pytest.raises(ConstraintFileError, match="parameter r = 0.04 m; expected a value >= 0.05"):
        load_robot(path, params={"r": 0.04})
    path.write_text(text.replace('unit = "m"', 'unit = "m"\nminimum = 0.5'))
    with pytest.raises(ConstraintFileError, match=r"parameters\[0\] \(r\): default: parameter r = 0.1 m"):
        load_robot(path)
