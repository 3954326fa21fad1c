"""The wheels' normal compliance (robotdyn/contact/compliance.py, issue 23): the constraint file's
``normal_stiffness`` [N/m] and ``normal_damping`` [N s/m] per wheel, checked by the schema, and the default rule
k = m g / (n * 1 mm), c = 2 * 0.3 * sqrt(k m / n) computed here by hand from the robot's total mass."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from robotdyn.contact.compliance import normal_compliance
from robotdyn.interfaces.constraint_file import ConstraintFileError, load_robot
from robotdyn.interfaces.constraint_schema import schema_problem

ROOT = Path(__file__).resolve().parents[1]


def _file(tmp_path, extra: dict[int, str]) -> Path:
    text = (ROOT / "examples/skid_steer.toml").read_text()
    blocks = text.split("[[wheels]]")
    for i, lines in extra.items():
        head, _, rest = blocks[i + 1].partition("\n")
        blocks[i + 1] = head + "\n" + lines + "\n" + rest
    path = tmp_path / "s.toml"
    path.write_text("[[wheels]]".join(blocks).replace('urdf = "skid_steer.urdf.xacro"',
                                                       f'urdf = "{ROOT / "examples/skid_steer.urdf.xacro"}"'))
    return path


def test_default_rule_from_weight_and_one_millimetre(tmp_path):
    robot = load_robot(_file(tmp_path, {}))
    mass = 20.0 + 0.5 + 4 * 1.0  # chassis, front axle, four wheels (examples/skid_steer.urdf.xacro)
    assert math.isclose(pin.computeTotalMass(robot.model), mass, rel_tol=1e-12)
    k = mass * 9.81 / (4 * 1e-3)
    c = 2 * 0.3 * math.sqrt(k * mass / 4)
    out = normal_compliance(robot)
    assert out.names == ("front_left", "front_right", "rear_left", "rear_right")
    np.testing.assert_allclose(out.stiffness, k, rtol=1e-12)
    np.testing.assert_allclose(out.damping, c, rtol=1e-12)
    assert not out.given.any() and "1 mm" in out.rule


def test_given_values_and_damping_from_a_given_stiffness(tmp_path):
    robot = load_robot(_file(tmp_path, {0: "normal_stiffness = 1.0e5\nnormal_damping = 250.0",
                                        1: "normal_stiffness = 4.0e5"}))
    out = normal_compliance(robot)
    mass = 24.5
    assert out.stiffness[0] == 1e5 and out.damping[0] == 250.0
    assert out.stiffness[1] == 4e5 and math.isclose(out.damping[1], 0.6 * math.sqrt(4e5 * mass / 4), rel_tol=1e-12)
    assert list(out.given) == [True, True, False, False]


@pytest.mark.parametrize("data, expected", [
    ({"wheels": [{"name": "w", "normal_stiffness": 0.0}]}, "wheels[0] (w).normal_stiffness = 0.0; expected a normal "
                                                           "(radial) stiffness in N/m, > 0"),
    ({"wheels": [{"name": "w", "normal_stiffness": math.inf}]}, "normal_stiffness = inf; expected"),
    ({"wheels": [{"name": "w", "normal_damping": -1.0}]}, "wheels[0] (w).normal_damping = -1.0; expected a normal "
                                                          "(radial) damping in N s/m, >= 0"),
    ({"wheels": [{"name": "w", "normal_stifness": 1.0}]}, "did you mean 'normal_stiffness'?"),
    # Hunt-Crossley's f = d^n (k + lambda d'): k in N/m^n, lambda in N s/m^(n+1) (the hint said N/m, N s/m)
    ({"wheels": [{"name": "w", "contact_law": "hunt_crossley", "normal_stiffness": 0.0}]},
     "wheels[0] (w).normal_stiffness = 0.0; expected a normal (radial) stiffness in N/m^n (n the contact_exponent)"),
    ({"wheels": [{"name": "w", "contact_law": "hunt_crossley", "normal_damping": -1.0}]},
     "wheels[0] (w).normal_damping = -1.0; expected a normal (radial) damping in N s/m^(n+1) (n the contact_expo"),
])
def test_bad_values_are_one_line(data, expected):
    message = schema_problem(data)
    assert message is not None and expected in message and "\n" not in message


def test_bad_value_in_a_file(tmp_path):
    with pytest.raises(ConstraintFileError, match=r"front_left\)\.normal_damping = -2\.0; expected"):
        load_robot(_file(tmp_path, {0: "normal_damping = -2.0"}))
