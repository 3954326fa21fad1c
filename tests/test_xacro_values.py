"""Values robotdyn hands to xacro are data, never code (issue 15): numbers as numbers, plain words as words,
anything else refused in one line before xacro evaluates it, whether it comes from the API, the CLI
(--xacro-arg, --param) or a TOML constraint file."""

from __future__ import annotations

from pathlib import Path

import pytest

from robotdyn.cli.commands import main
from robotdyn.description.urdf import expand_xacro, xacro_value
from robotdyn.errors import InputError

PAYLOADS = [
    "().__class__",
    "1 if open('/tmp/robotdyn_pwned', 'w') else 0",
    "__import__('os').system('touch /tmp/robotdyn_pwned')",
    "[c for c in ()]",
    "0.1 * 2",
    "${0.1}",
    "$(arg other)",
    "a b",
    "0.1;1",
]


@pytest.mark.parametrize("payload", PAYLOADS)
def test_expressions_are_refused(payload, tmp_path):
    description = tmp_path / "t.urdf.xacro"
    description.write_text(
        '<?xml version="1.0"?><robot name="t" xmlns:xacro="http://www.ros.org/wiki/xacro">'
        '<xacro:arg name="rho" default="0.1"/><link name="base"><inertial><mass value="${$(arg rho) * 10}"/>'
        '<inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>')
    with pytest.raises(InputError, match="xacro argument rho") as exc:
        expand_xacro(description, {"rho": payload})
    assert "\n" not in str(exc.value)
    assert not Path("/tmp/robotdyn_pwned").exists()


@pytest.mark.parametrize("value, text", [(0.1, "0.1"), ("0.25", "0.25"), (3, "3"), ("1e-3", "1e-3"), (True, "true"),
                                         ("axle", "axle"), ("package://pkg/urdf/a.xacro", "package://pkg/urdf/a.xacro"),
                                         ("-2.5", "-2.5")])
def test_numbers_and_plain_words_pass(value, text):
    assert xacro_value("x", value) == text


@pytest.mark.parametrize("value", [float("nan"), "inf", float("-inf")])
def test_non_finite_numbers_are_refused(value):
    with pytest.raises(InputError, match="finite"):
        xacro_value("x", value)


def test_cli_and_constraint_file_values_are_checked(tmp_path, capsys):
    example = Path(__file__).resolve().parents[1] / "examples" / "skid_steer.toml"
    assert main(["info", "--constraints", str(example), "--xacro-arg", "a=().__class__"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "xacro argument a" in err
    toml = tmp_path / "evil.toml"
    toml.write_text(example.read_text().replace('urdf = "skid_steer.urdf.xacro"',
                                                f'urdf = "{example.parent / "skid_steer.urdf.xacro"}"\n'
                                                'xacro_args = {{ b = "[x for x in ()]" }}'.replace("{{", "{").replace("}}", "}")))
    assert main(["info", "--constraints", str(toml)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "xacro argument b" in err and "Traceback" not in err

