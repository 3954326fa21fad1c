"""Every key of a constraint file given a value of the wrong type or shape (a list where a table belongs, a table
where a number belongs, deep nesting, ...) is refused in one line naming the file, never a traceback and never
accepted silently (issue 15). The mutations are generated from examples/skid_steer.toml, key by key."""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path

import pytest
import tomli_w

from robotdyn.cli.commands import main

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "skid_steer.toml"
WRONG = {"list": [1, 2], "table": {"a": 1}, "nested": {"a": {"b": {"c": [[1]]}}}, "bool": True, "text": "x(",
         "negative": -1.0, "huge": 1e308, "empty": ""}


def _paths(data, prefix=()):
    for key, value in data.items():
        yield (*prefix, key)
        if isinstance(value, list) and value and isinstance(value[0], dict):
            for i, item in enumerate(value[:1]):  # the first entry of each array of tables
                yield from _paths(item, (*prefix, key, i))
        elif isinstance(value, dict):
            yield from _paths(value, (*prefix, key))


def _cases():
    base = tomllib.loads(EXAMPLE.read_text())
    base["urdf"] = str(EXAMPLE.parent / "skid_steer.urdf.xacro")
    for path in _paths(base):
        if path == ("urdf",):
            continue
        for label, wrong in WRONG.items():
            data = copy.deepcopy(base)
            node = data
            for key in path[:-1]:
                node = node[key]
            if node[path[-1]] == wrong or (label == "text" and path[-1] in ("name", "description", "title")):
                continue  # not wrong there (a name may be any text)
            node[path[-1]] = wrong
            yield ".".join(map(str, path)) + f"={label}", data


CASES = list(_cases())


def test_enough_cases():
    assert len(CASES) >= 150


@pytest.mark.parametrize("case, data", CASES, ids=[c for c, _ in CASES])
def test_wrong_value_is_one_line(tmp_path, capsys, case, data):
    path = tmp_path / "robot.toml"
    path.write_text(tomli_w.dumps(data))
    rc = main(["info", "--constraints", str(path)])
    err = capsys.readouterr().err
    assert "Traceback" not in err
    if rc == 0:  # accepted: only where the wrong value is still a valid one for that key
        assert case.split("=")[0].rsplit(".", 1)[-1] in ACCEPTABLE, f"{case} was accepted"
    else:
        assert rc == 2 and err.count("\n") == 1 and err.startswith("robotdyn: error: ")


ACCEPTABLE = {"description", "title", "t_end", "mu", "stiffness", "default", "unit", "torque", "xacro", "z",
              "name"}
"""Keys where some of the 'wrong' values are legitimate (a huge t_end or mu, a negative torque or height, a name
that is any text): accepting those is right."""


def _omni(tmp_path, angle):
    data = tomllib.loads(EXAMPLE.read_text())
    data["urdf"] = str(EXAMPLE.parent / "skid_steer.urdf.xacro")
    data.pop("independent")
    for w in data["wheels"]:
        for key in ("friction", "stiffness", "mu"):
            w.pop(key, None)
        w["kind"], w["roller_angle"] = "omni", angle
    path = tmp_path / "omni.toml"
    path.write_text(tomli_w.dumps(data))
    return path


def test_angles_with_units(tmp_path, capsys):
    """roller_angle = "45 deg" is pi/4 rad; a bare 45 (degrees without their unit) is refused, not taken as rad."""
    from robotdyn.interfaces.constraint_file import read

    rows = {}
    for label, angle in (("deg", "45 deg"), ("rad", 0.7853981633974483), ("rad-string", "0.7853981633974483 rad")):
        robot = read(_omni(tmp_path, angle)).robot()
        rows[label] = robot.rows_at(robot.neutral()).A
    assert abs(rows["deg"] - rows["rad"]).max() < 1e-15 and abs(rows["rad-string"] - rows["rad"]).max() == 0
    for bad, message in ((45, "write '45 deg' for degrees"), ("45 grad", "expected a number in rad or a string")):
        assert main(["info", "--constraints", str(_omni(tmp_path, bad))]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and message in err
