"""A root link at the wrong height gets the right advice, in ``info`` and in the one-line error (found on the ROSbot 2's
description, whose ``base_link`` lies on the ground under a chassis fixed at the wheel axles).

Before: with every wheel the same height d off the ground, ``info`` said that "a floating root cannot fix that with
one height" (it can: that is what one height does), the error said "floating root at 0 m" for a root whose z was
0.05 m (it printed the planar root's offset, unused by a floating root), and a root already in place was told to
"set z = 6.93889e-18" (a rounding residue of 0.05 - 0.05).

Fixture: a rigid four-wheel base of this test's own (no description is copied): a 2 kg chassis, four wheels of
radius r = 0.0425 m whose joints sit h = 0.0425 m above ``base_link``, so the wheels touch the ground exactly when
the root's height is 0 (z = 0, or a planar root_height of 0). A root at height z0 puts every contact point at
height z0 (z0 > 0: above the ground), and the fix is z = z0 - z0 = 0.
"""

from __future__ import annotations

import pytest

from robotdyn.errors import ConstraintError
from robotdyn.interfaces.constraint_file import load_robot

pytestmark = pytest.mark.filterwarnings("ignore::robotdyn.errors.RobotDynWarning")  # no 'independent', meshes

R = 0.0425  # wheel radius = height of the wheel joints above base_link [m]

WHEEL = """  <link name="{n}_wheel"><inertial><mass value="0.07"/>
    <inertia ixx="4e-5" ixy="0" ixz="0" iyy="7e-5" iyz="0" izz="4e-5"/></inertial></link>
  <joint name="{n}_joint" type="continuous"><parent link="base_link"/><child link="{n}_wheel"/>
    <origin xyz="{x} {y} {h}"/><axis xyz="0 1 0"/></joint>
"""
URDF = ('<?xml version="1.0"?>\n<robot name="four_wheel_fixture">\n  <link name="base_link">\n    <inertial><origin '
        f'xyz="0 0 {R + 0.02}"/><mass value="2.0"/>\n      <inertia ixx="0.004" ixy="0" ixz="0" iyy="0.0065" iyz="0" '
        'izz="0.009"/></inertial>\n  </link>\n'
        + "".join(WHEEL.format(n=n, x=x, y=y, h=R) for n, x, y in
                  (("fl", 0.053, 0.096), ("fr", 0.053, -0.096), ("rl", -0.053, 0.096), ("rr", -0.053, -0.096)))
        + "</robot>\n")


def _toml(root: str, extra: str = "") -> str:
    wheels = "".join(f'\n[[wheels]]\nname = "{n}"\njoint = "{n}_joint"\nradius = {R}\n' for n in ("fl", "fr", "rl", "rr"))
    return f'name = "four_wheel_fixture"\nurdf = "four_wheel.urdf"\nroot = "{root}"\n{extra}\n{wheels}'


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    path = tmp_path_factory.mktemp("root_height")
    (path / "four_wheel.urdf").write_text(URDF)
    return path


def _load(folder, root: str, extra: str = ""):
    toml = folder / f"{root}_{abs(hash(extra))}.toml"
    toml.write_text(_toml(root, extra))
    return load_robot(toml)


@pytest.mark.parametrize("z0", [0.05, -0.0075])
def test_floating_root_at_the_wrong_height(folder, z0):
    robot = _load(folder, "floating", f"neutral = {{ z = {z0} }}")
    heights = robot.wheel_heights()
    assert all(h == pytest.approx(z0, abs=1e-12) for h in heights.values())  # the fixture's geometry, as stated
    where = "above" if z0 > 0 else "below"
    advice = (f"every wheel is {abs(z0):.6g} m {where} the ground at the neutral configuration: the root link sits at "
              f"the wrong height (floating root at {z0:.6g} m); set z = 0 (neutral = {{ z = ... }} in the constraint file)")
    notes = robot.info()["mobility_notes"]
    assert advice in notes
    assert not any("cannot fix that with one height" in n for n in notes)
    with pytest.raises(ConstraintError) as err:
        robot.check_constraints(robot.neutral())
    assert str(err.value) == advice.replace("at the neutral configuration", "at this configuration")
    fixed = _load(folder, "floating", "neutral = { z = 0 }")  # the advice, followed
    fixed.check_constraints(fixed.neutral())
    assert max(map(abs, fixed.wheel_heights().values())) < 1e-12
    assert not any("ground" in n for n in fixed.info()["mobility_notes"])


def test_planar_root_height_given_wrong(folder):
    robot = _load(folder, "planar", "root_height = 0.01")
    notes = robot.info()["mobility_notes"]
    assert ("every wheel is 0.01 m above the ground at the neutral configuration: the root link sits at the wrong "
            "height (planar root at 0.01 m); set root_height = 0 in the constraint file") in " ".join(notes)
    assert not any("cannot fix that with one height" in n for n in notes)
    with pytest.raises(ConstraintError, match=r"above the ground at this configuration.*set root_height = 0 in"):
        robot.check_constraints(robot.neutral())
    _load(folder, "planar", "root_height = 0").check_constraints(robot.neutral())


def test_wheels_off_by_different_heights_keep_the_old_note(folder):
    """Only one wheel off (its radius wrong by 5 mm): no root height fixes that, and the note says so."""
    text = _toml("floating").replace(f'name = "rr"\njoint = "rr_joint"\nradius = {R}', 'name = "rr"\njoint = '
                                     f'"rr_joint"\nradius = {R + 0.005}')
    (folder / "one_off.toml").write_text(text)
    notes = load_robot(folder / "one_off.toml").info()["mobility_notes"]
    assert any("do not all touch the ground" in n and "rr -0.005 m" in n and "cannot fix that with one height" in n
               for n in notes)
