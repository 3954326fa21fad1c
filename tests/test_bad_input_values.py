"""Values that were accepted silently or crashed a valid use (issue 24): a robot without motors in ``dump``, Xacro
words that xacro evaluates, parameters beyond their physical range, descriptions too large to load in bounded time.
The one-line refusals themselves are in the corpus (tests/test_bad_input_corpus.py, ``i24-*`` cases)."""

from __future__ import annotations

from pathlib import Path

import pytest

import robotdyn.description.urdf as urdf
from robotdyn.cli.commands import main
from robotdyn.description.urdf import expand_xacro, xacro_value
from robotdyn.errors import DescriptionError, InputError
from robotdyn.robot import Parameter

PENDULUM = """<?xml version="1.0"?><robot name="pend"><link name="base"/>
<link name="arm"><inertial><origin xyz="0.5 0 0"/><mass value="1"/>
<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
<joint name="j" type="continuous"><parent link="base"/><child link="arm"/><axis xyz="0 1 0"/></joint></robot>
"""


@pytest.fixture
def pendulum(tmp_path) -> Path:
    """A pendulum without motors: 1 kg at l = 0.5 m from a y-axis hinge, I_yy = 0.01 kg m^2 about its centre."""
    (tmp_path / "pend.urdf").write_text(PENDULUM)
    toml = tmp_path / "pend.toml"
    toml.write_text('name = "pend"\nurdf = "pend.urdf"\nroot = "fixed"\n')
    return toml


def test_dump_of_a_robot_without_motors(pendulum, capsys):
    """It raised TypeError: 'int' object is not iterable in _matrix_text. Closed form at q = 0 (arm along +x,
    gravity -z): M = I_yy + m l^2 = 0.01 + 0.25 = 0.26 kg m^2; g (generalised gravity force) = -m g l = -4.905 N m
    about +y (the weight at +x turns the arm about +y); B is stated as none."""
    assert main(["dump", "--constraints", str(pendulum), "--v", "0.5"]) == 0
    out = capsys.readouterr().out
    assert "B: none (the robot has no motors)" in out
    assert main(["dump", "--constraints", str(pendulum), "--v", "0.5", "--json"]) == 0
    import json

    data = json.loads(capsys.readouterr().out)
    assert data["M"][0] == pytest.approx([0.26], abs=1e-12)
    assert data["g"] == pytest.approx([-1 * 9.81 * 0.5], abs=1e-12)
    assert data["motors"] == [] and data["B"] == [[]]
    assert main(["dump", "--constraints", str(pendulum), "--v", "0.5", "--a", "1"]) == 0
    out = capsys.readouterr().out
    assert "motor torques: none" in out
    assert "-4.645" in out  # tau = M a + C v + g = 0.26 - 4.905 (C v = 0 for one hinge)


# --------------------------------------------------------------------------------------- xacro words
@pytest.mark.parametrize("word", ["1-1", "r+r", "pi", "e", "math.pi", "max", "1e5j", "5x", "rho"])
def test_words_xacro_would_evaluate_are_refused(word):
    with pytest.raises(InputError, match="xacro would evaluate it"):
        xacro_value("x", word, properties=["rho"])


@pytest.mark.parametrize("word", ["axle", "com", "half", "left_wheel", "package://my-pkg/urdf/a.xacro", "a.xacro"])
def test_plain_words_still_pass(word):
    assert xacro_value("x", word, properties=["rho"]) == word


def test_pi_no_longer_becomes_a_mass(tmp_path):
    """rho = 'pi' in ${$(arg rho) * 10} gave a link of 31.4 kg, silently."""
    description = tmp_path / "t.urdf.xacro"
    description.write_text(
        '<?xml version="1.0"?><robot name="t" xmlns:xacro="http://www.ros.org/wiki/xacro">'
        '<xacro:arg name="rho" default="0.1"/><link name="base"><inertial><mass value="${$(arg rho) * 10}"/>'
        '<inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>')
    assert 'value="1.0"' in expand_xacro(description, {"rho": "0.1"})
    for word in ("pi", "1-1", "rho+rho"):
        with pytest.raises(InputError, match="xacro argument rho"):
            expand_xacro(description, {"rho": word})


# --------------------------------------------------------------------------------------------- ranges
def test_parameter_maximum_and_angle_bound():
    mu = Parameter("mu", 1.0, "-", minimum=0.0, maximum=1e6)
    assert mu.convert("0.7") == 0.7
    for bad, text in (("-1", ">= 0"), ("1e300", r"<= 1e\+06")):
        with pytest.raises(InputError, match=text):
            mu.convert(bad)
    angle = Parameter("theta0", 0.5, "rad")
    assert angle.convert(-6.0) == -6.0
    with pytest.raises(InputError, match="magnitude <= 6.28"):
        angle.convert(1e6)


def test_description_size_and_links(tmp_path, monkeypatch):
    """A 60 MB URDF ran past a minute, 3000 links ended in a MemoryError after 54 s: both are refused before
    parsing (here with the limits lowered, to keep the test small)."""
    big = tmp_path / "big.urdf"
    big.write_text(PENDULUM.replace("</robot>", "<!--" + "x" * 5000 + "--></robot>"))
    monkeypatch.setattr(urdf, "MAX_DESCRIPTION_BYTES", 4000)
    with pytest.raises(DescriptionError, match="bytes; expected at most 4,000"):
        expand_xacro(big)
    monkeypatch.setattr(urdf, "MAX_DESCRIPTION_BYTES", 10_000_000)
    monkeypatch.setattr(urdf, "MAX_LINKS", 1)
    with pytest.raises(DescriptionError, match="2 links; expected at most 1"):
        expand_xacro(big)
