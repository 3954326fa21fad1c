"""Issue 24, item 4: a link whose inertia is implausible for its mass and size is named, with its share of the
effective mass.

Reference robot (``tests/data/placeholder_inertia``): a 2.45 kg differential drive (axle half-track b = 0.12 m,
wheel radius r = 0.035 m) with the issue's placeholder values: 0.01 kg wheels with I = 0.001 kg m^2 about the
axle, and a 0.01 kg sonar link with I = 1 kg m^2 against a chassis of 0.33 kg m^2 about the vertical. All centres of
mass lie on the base's x axis, so in (v_x, psi') the kinetic energy is
T = 1/2 [m v_x^2 + I_z psi'^2 + I_L ((v_x - b psi')/r)^2 + I_R ((v_x + b psi')/r)^2], and the effective mass along
x is 1 / (M^-1)_xx of that 2x2 matrix (the closed forms below; the wheels' own yaw inertia included).
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

import robotdyn
from robotdyn.cli import main
from robotdyn.description.inertia_check import implausible_inertias
from robotdyn.errors import RobotDynWarning
from robotdyn.interfaces.constraint_file import read

TOML = Path(__file__).parent / "data" / "placeholder_inertia" / "placeholder.toml"
M_TOTAL, R, B = 2.45, 0.035, 0.12
I_AXLE, I_WHEEL_Z, M_WHEEL = 0.001, 0.0005, 0.01
I_Z = 0.33 + (1.0 + 0.01 * 0.14**2) + 2 * (I_WHEEL_Z + M_WHEEL * B**2)  # chassis, sonar, wheels about the axle middle


def _effective_x(i_left: float, i_right: float, i_z: float = I_Z, axis: int = 0) -> float:
    """Effective mass along x (axis 0) or inertia about the yaw axis (axis 1) of the closed form."""
    e = np.array([[1.0, -B], [1.0, B]]) / R  # wheel rates per (v_x, psi')
    M = np.diag([M_TOTAL, i_z]) + e.T @ np.diag([i_left, i_right]) @ e
    return 1.0 / np.linalg.inv(M)[axis, axis]


@pytest.fixture(scope="module")
def loaded():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = read(TOML).robot({})
    return robot, [str(w.message) for w in caught if issubclass(w.category, RobotDynWarning)]


def test_placeholder_links_named_with_their_share_of_the_effective_mass(loaded):
    robot, messages = loaded
    found = {f.link: f for f in robot.implausible_inertias}
    assert sorted(found) == ["sonar", "wheel_left", "wheel_right"]  # the chassis (k = 0.37 m in 0.5 m) is plausible
    # the numbers: 2.45 kg of robot, 4.08 kg of effective mass along x
    wheel = found["wheel_left"]
    assert wheel.along == "base x" and wheel.effective_mass == pytest.approx(M_TOTAL + 2 * I_AXLE / R**2, rel=1e-9)
    assert wheel.effective_mass == pytest.approx(_effective_x(I_AXLE, I_AXLE), rel=1e-9)
    # without the left wheel's rotational inertia (axle and yaw): the asymmetric closed form
    assert wheel.effective_without == pytest.approx(_effective_x(0.0, I_AXLE, I_Z - I_WHEEL_Z), rel=1e-9)
    assert wheel.share == pytest.approx(0.2017, abs=1e-4)
    # radius of gyration sqrt(I/m) against the wheel cylinder's bounding box seen from its centre
    assert wheel.gyration == pytest.approx(np.sqrt(I_AXLE / M_WHEEL)) and wheel.extent_from == "geometry"
    assert wheel.extent == pytest.approx(np.sqrt(2 * R**2 + 0.01**2), rel=1e-12)
    # the sonar has no geometry: the rule (a sphere of its mass at 100 kg/m^3); its 1 kg m^2 is the yaw inertia's
    # largest part, and removing it takes exactly 1 kg m^2 off (yaw decouples from x: all masses on the x axis)
    sonar = found["sonar"]
    assert sonar.extent_from == "rule" and sonar.extent == pytest.approx((3 * 0.01 / (4 * np.pi * 100)) ** (1 / 3))
    assert sonar.along == "base yaw"
    assert sonar.effective_mass == pytest.approx(_effective_x(I_AXLE, I_AXLE, axis=1), rel=1e-9)
    assert sonar.effective_mass - sonar.effective_without == pytest.approx(1.0, rel=1e-9)
    assert sonar.share > 0.7
    # one warning on load, naming the three
    assert len(messages) == 1 and all(n in messages[0] for n in found) and "chassis" not in messages[0]
    assert "20 % of the effective mass along base x (4.083; 3.259 without it)" in messages[0]


def test_info_shows_it_once_and_as_data(capsys):
    assert main(["info", "--constraints", str(TOML)]) == 0
    err = capsys.readouterr().err
    assert err.count("inertia implausible") == 1
    assert main(["info", "--constraints", str(TOML), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [f["link"] for f in out["implausible_inertias"]] == ["wheel_left", "wheel_right", "sonar"]


@pytest.mark.parametrize("name", robotdyn.robots_available())
def test_built_in_robots_have_plausible_inertias(name):
    assert implausible_inertias(robotdyn.load(name)) == []


def test_a_plausible_wheel_is_not_named(tmp_path):
    """The same robot with a real wheel (a 0.2 kg disc: I = m r^2 / 2) and the sonar's inertia of a 2 cm cube."""
    urdf = (TOML.parent / "placeholder.urdf").read_text()
    urdf = urdf.replace('<mass value="0.01"/><inertia ixx="0.0005" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.0005"/>',
                        '<mass value="0.2"/><inertia ixx="6.125e-5" ixy="0" ixz="0" iyy="1.225e-4" iyz="0" '
                        'izz="6.125e-5"/>')
    urdf = urdf.replace('ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"', 'ixx="6.7e-7" ixy="0" ixz="0" '
                        'iyy="6.7e-7" iyz="0" izz="6.7e-7"')
    (tmp_path / "placeholder.urdf").write_text(urdf)
    (tmp_path / "placeholder.toml").write_text(TOML.read_text())
    with warnings.catch_warnings():
        warnings.simplefilter("error", RobotDynWarning)
        robot = read(tmp_path / "placeholder.toml").robot({})
    assert robot.implausible_inertias == []
