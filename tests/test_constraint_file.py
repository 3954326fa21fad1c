"""Constraint files (robotdyn.interfaces.constraint_file): equivalence with a robot module's RobotSpec, generic options
(locked joints, massless links), and one clear line for each mistake."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import robotdyn
from robotdyn.cli.commands import main
from robotdyn.interfaces.constraint_file import ConstraintFileError, load_robot, read
from robotdyn.errors import RobotDynError

ROOT = Path(__file__).resolve().parent.parent
QUASIMORO_TOML = ROOT / "examples" / "quasimoro.toml"
XACRO = ROOT / "urdf" / "quasimoro.urdf.xacro"

# a minimal file for the error tests: Quasimoro's wheels, nothing else
BASE = f"""
urdf = "{XACRO}"
root = "planar"

[[parameters]]
name = "r"
default = 0.3

[[wheels]]
name = "A"
joint = "theta1"
radius = "r"

[[wheels]]
name = "B"
frame = "wheel_B"
radius = 0.3
"""


def write(tmp_path: Path, text: str, name: str = "robot.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def error_of(path: Path, **kwargs) -> str:
    with pytest.raises(ConstraintFileError) as info:
        load_robot(path, **kwargs)
    msg = str(info.value)
    assert "\n" not in msg and msg.startswith(str(path)), msg  # one line, naming the file
    return msg


# ------------------------------------------------------------------------------------------ equivalence
@pytest.mark.parametrize("params", [{}, {"r": 0.25, "d": 0.15}, {"inertia_about": "com", "rho": 0.4}])
def test_quasimoro_file_equals_the_module(params):
    """examples/quasimoro.toml builds the same reduced dynamics as robotdyn.load('quasimoro') at random states."""
    a = load_robot(QUASIMORO_TOML, params=params)
    b = robotdyn.load("quasimoro", params)
    assert a.coordinates == b.coordinates and a.velocity_names == b.velocity_names
    assert a.params == b.params
    rng = np.random.default_rng(7)
    for _ in range(20):
        q = rng.uniform(-np.pi, np.pi, a.nq)
        nu = rng.normal(size=3) * 2
        ra, rb = a.reduced(q, nu, coriolis=True), b.reduced(q, nu, coriolis=True)
        for x, y in ((ra.M, rb.M), (ra.h, rb.h), (ra.g, rb.g), (ra.B, rb.B), (ra.C, rb.C), (ra.S, rb.S)):
            np.testing.assert_allclose(x, y, rtol=0, atol=1e-13)


def test_spec_fields_from_file():
    cf = read(QUASIMORO_TOML)
    spec = cf.SPEC
    assert isinstance(spec, robotdyn.RobotSpec)
    assert [w.frame for w in spec.wheels] == ["wheel_A", "wheel_B"]  # the joint entry resolves to its child link
    assert [w.axis for w in spec.wheels] == [(0.0, 1.0, 0.0)] * 2  # default axle: the spin joint's axis
    assert [(m.joint, m.reaction) for m in spec.motors] == [("theta1", "body"), ("theta2", "body")]
    assert {p.name: p.xacro for p in spec.parameters}["g"] is False
    assert {p.name: p.xacro for p in spec.parameters}["rho"] is True


# -------------------------------------------------------------------------------------- generic options
def test_locked_joint_equals_the_full_model_restricted(tmp_path):
    """Locking theta3 = 0.3: M and the bias of the locked tree are the full tree's at theta3 = 0.3, restricted."""
    locked = load_robot(write(tmp_path, BASE + '\n[locked]\ntheta3 = 0.3\n'))
    full = load_robot(write(tmp_path, BASE, "full.toml"))
    assert "theta3" not in locked.coordinates and locked.mobility == 2
    keep = [full.coordinate_index(c) for c in locked.coordinates]
    rng = np.random.default_rng(3)
    for _ in range(5):
        ql, vl = rng.normal(size=locked.nq), rng.normal(size=locked.nq)
        qf, vf = np.zeros(full.nq), np.zeros(full.nq)
        qf[keep], vf[keep] = ql, vl
        qf[full.coordinate_index("theta3")] = 0.3
        Mf = pin.crba(full.model, full.data, qf)
        bf = pin.rnea(full.model, full.data, qf, vf, np.zeros(full.nq))
        Ml = pin.crba(locked.model, locked.data, ql)
        bl = pin.rnea(locked.model, locked.data, ql, vl, np.zeros(locked.nq))
        np.testing.assert_allclose(Ml, Mf[np.ix_(keep, keep)], atol=1e-12)
        np.testing.assert_allclose(bl, bf[keep], atol=1e-12)


def test_massless_link(tmp_path):
    robot = load_robot(write(tmp_path, 'massless = ["wheel_A"]\n' + BASE))
    full = load_robot(write(tmp_path, BASE, "full.toml"))
    m_wheel = robotdyn.load("quasimoro").params["m"]
    assert pin.computeTotalMass(full.model) - pin.computeTotalMass(robot.model) == pytest.approx(m_wheel, abs=1e-12)


def test_glob_lock_and_scenario(tmp_path):
    text = BASE + '''
[locked]
"theta[3-9]" = -0.2

[[motors]]
name = "mA"
joint = "theta1"

[[scenarios]]
name = "push"
t_end = 0.5
torque = [0.1]
nu0 = { theta2 = 1.0 }
'''
    cf = read(write(tmp_path, text))
    assert cf.SPEC.locked == {"theta3": -0.2}
    robot = cf.robot()
    q0, nu0 = cf.SCENARIOS["push"].initial_state(robot)
    assert nu0[robot.velocity_names.index("theta2_dot")] == 1.0


# ---------------------------------------------------------------------------------------------- errors
def test_unknown_keys(tmp_path):
    msg = error_of(write(tmp_path, "motorz = []\n" + BASE))
    assert "unknown key 'motorz'" in msg and "did you mean 'motors'" in msg
    msg = error_of(write(tmp_path, BASE + "radus = 0.3\n"))
    assert "wheels[1] (B)" in msg and "unknown key 'radus'" in msg and "did you mean 'radius'" in msg


def test_wheel_joint_that_does_not_exist(tmp_path):
    msg = error_of(write(tmp_path, BASE.replace('joint = "theta1"', 'joint = "theta4"')))
    assert "wheels[0] (A)" in msg and "no joint named 'theta4'" in msg and "did you mean" in msg


def test_frame_name_typo(tmp_path):
    msg = error_of(write(tmp_path, BASE.replace('frame = "wheel_B"', 'frame = "wheel_b"')))
    assert "wheels[1] (B)" in msg and "no frame named 'wheel_b'" in msg and "did you mean 'wheel_B'" in msg


@pytest.mark.parametrize("radius", ["0.0", "-0.1"])
def test_radius_not_positive(tmp_path, radius):
    msg = error_of(write(tmp_path, BASE.replace("radius = 0.3", f"radius = {radius}")))
    assert "wheels[1] (B)" in msg and "> 0" in msg


def test_radius_parameter_not_positive(tmp_path):
    msg = error_of(write(tmp_path, BASE.replace("default = 0.3", "default = -0.3")))
    assert "wheels[0] (A)" in msg and "radius -0.3 is not > 0" in msg


def test_radius_override_not_positive_at_build_time(tmp_path):
    """A bad --param value is caught by the core; the message still names the file."""
    msg = error_of(write(tmp_path, BASE), params={"r": -1})
    assert "r=-1" in msg and "radius='-1.0'" in msg


def test_closure_between_frames_of_the_same_body(tmp_path):
    text = BASE + '\n[[closures]]\nname = "loop"\nframe1 = "body"\nframe2 = "body_com"\n'
    msg = error_of(write(tmp_path, text))
    assert "closures[0] (loop)" in msg and "same rigid body" in msg
    # locking a joint merges bodies too
    text = "locked = { theta3 = 0.0 }\n" + BASE + '\n[[closures]]\nframe1 = "axle"\nframe2 = "body_com"\n'
    msg = error_of(write(tmp_path, text))
    assert "closures[0]" in msg and "same rigid body" in msg


def test_zero_length_axis(tmp_path):
    msg = error_of(write(tmp_path, BASE.replace('frame = "wheel_B"', 'frame = "wheel_B"\naxis = [0, 0, 0]')))
    assert "wheels[1] (B)" in msg and "zero length" in msg


@pytest.mark.parametrize(
    "change, expected",
    [
        (('joint = "theta1"', 'joint = "axle_height"'), "is fixed"),  # a fixed caster is not a wheel
        (('root = "planar"', 'root = "planr"'), "did you mean 'planar'"),
        (("[[wheels]]\nname = \"B\"", "[[wheels]]\nname = \"B\"\nkind = \"omny\""), "did you mean 'omni'"),
        (('radius = "r"', 'radius = "R"'), "radius 'R' is not a parameter"),
        (('frame = "wheel_B"', 'frame = "wheel_B"\naxis = [1, 0]'), "expected 3 numbers"),
        (('default = 0.3', 'default = "big"'), "expected a finite number"),
        (('urdf = "', 'urdf = "/nonexistent/'), "description file not found"),
        (('root = "planar"', 'root = "planar"\nlocked = { "arm_*" = 0.0 }'), "no moving joint"),
        (('root = "planar"', 'root = "planar"\nindependent = ["theta9"]'), "no coordinate named 'theta9'"),
        (('root = "planar"', 'root = [1'), "not valid TOML"),
    ],
)
def test_other_mistakes(tmp_path, change, expected):
    assert change[0] in BASE
    msg = error_of(write(tmp_path, BASE.replace(*change)))
    assert expected in msg, msg


def test_missing_file():
    with pytest.raises(ConstraintFileError, match="constraint file not found"):
        read("/nonexistent/robot.toml")


def test_xacro_arg_that_is_a_parameter(tmp_path):
    msg = error_of(QUASIMORO_TOML, xacro_args={"rho": "0.4"})
    assert "set it with --param rho=VALUE" in msg


# ------------------------------------------------------------------------------------------------- CLI
def test_cli_constraint_file_matches_module(capsys):
    assert main(["dump", "--constraints", str(QUASIMORO_TOML), "--json", "--q", "0", "0", "0", "0.2", "0", "0",
                 "--v", "1", "0.5", "0.1"]) == 0
    from_file = capsys.readouterr().out
    assert main(["dump", "quasimoro", "--json", "--q", "0", "0", "0", "0.2", "0", "0", "--v", "1", "0.5", "0.1"]) == 0
    assert capsys.readouterr().out == from_file


def test_cli_urdf_override(capsys):
    assert main(["info", "--urdf", str(XACRO), "--constraints", str(QUASIMORO_TOML), "--json"]) == 0
    assert '"independent_velocities"' in capsys.readouterr().out


@pytest.mark.parametrize(
    "argv, expected",
    [
        (["info"], "no robot given"),
        (["info", "quasimoro", "--constraints", str(QUASIMORO_TOML)], "not both"),
        (["info", "--urdf", str(XACRO)], "--urdf needs --constraints"),
        (["info", "--constraints", "nope.toml"], "constraint file not found"),
    ],
)
def test_cli_errors_are_one_line(capsys, argv, expected):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("robotdyn: error: ") and expected in err, err


def test_cli_bad_wheel_is_one_line(tmp_path, capsys):
    path = write(tmp_path, BASE.replace('joint = "theta1"', 'joint = "theta4"'))
    assert main(["info", "--constraints", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(path) in err and "wheels[0] (A)" in err


def test_errors_are_robotdyn_errors():
    assert issubclass(ConstraintFileError, RobotDynError)


def test_xacro_args_reach_the_description(tmp_path, capsys):
    """--xacro-arg rho=0.4 (not a parameter of the file) sets the track l = r/rho of the Quasimoro xacro."""
    path = write(tmp_path, BASE)
    for rho in (0.5, 0.4):
        robot = load_robot(path, xacro_args={"rho": str(rho)})
        pin.framesForwardKinematics(robot.model, robot.data, robot.neutral())
        y = robot.data.oMf[robot.model.getFrameId("wheel_A")].translation[1]
        assert y == pytest.approx(0.3 / rho / 2, abs=1e-12)
    assert main(["info", "--constraints", str(path), "--xacro-arg", "rho=0.4", "--json"]) == 0


def test_terrain_and_wheel_kinds(tmp_path):
    from robotdyn.constraints.rolling_contact import OmniWheel, RollingWheel
    from robotdyn.constraints.terrain import RampTerrain

    text = BASE.replace('name = "B"', 'name = "B"\nkind = "omni"\nroller_angle = 0.7').replace(
        'name = "A"', 'name = "A"\nkind = "caster"') + '\n[terrain]\nkind = "ramp"\nslope = 0.1\n'
    robot = load_robot(write(tmp_path, text))
    assert isinstance(robot.terrain, RampTerrain) and robot.terrain.slope == 0.1
    a, b = robot.constraints
    assert type(a) is RollingWheel and isinstance(b, OmniWheel) and b.roller_angle == 0.7
    msg = error_of(write(tmp_path, BASE + '\n[terrain]\nkind = "ramp"\nslop = 0.1\n', "t.toml"))
    assert "terrain (ramp)" in msg and "did you mean 'slope'" in msg
    msg = error_of(write(tmp_path, BASE.replace('radius = "r"', 'radius = "r"\nroller_angle = 0.1'), "u.toml"))
    assert "roller_angle is only meaningful for kind = 'omni'" in msg
