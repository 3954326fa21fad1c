"""A robot straight from its ROS repository (issue 14): packages, meshes, the root's height, rows dropped as
redundant, body twists and torques by motor name, on fixtures laid out as a ROS workspace
(``examples/ros_ws/src``: two packages, one in a directory named differently from the package, ``$(find)``
includes, ``package://`` meshes, a Gazebo-only path), written for these tests.

Dynamics are checked against closed forms derived independently with sympy (``tests/oracles/
wheeled_bases_sympy.py``: Lagrange-d'Alembert on hand-written admissible velocities), static balance by hand, and
energy balance.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from oracles.wheeled_bases_sympy import Body, Wheel, mecanum, synchro, unicycle
from robotdyn.cli.commands import main
from robotdyn.fast.dispatch import use_compiled
from robotdyn.interfaces.constraint_file import ConstraintFileError, load_robot, read
from robotdyn.description.urdf import expand_xacro
from robotdyn.errors import ConstraintError, RobotDynWarning
from robotdyn.constraints.joint_coupling import JointCoupling
from robotdyn.robot import Robot
from robotdyn.description.ros_packages import MissingPackagesError, PackageIndex, required_packages
from robotdyn.interfaces.scene_page import pack_scene, page_commands, unpack_scene
from robotdyn.interfaces.viewer import Viewer

WS = Path(__file__).resolve().parent.parent / "examples" / "ros_ws"
SRC = WS / "src"
PKG = SRC / "demo_description"
TOML = PKG / "robotdyn"
G = 9.81


@pytest.fixture(autouse=True)
def no_ros_environment(monkeypatch):
    """Nothing from the machine's ROS set-up: each test gives its packages."""
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    monkeypatch.delenv("AMENT_PREFIX_PATH", raising=False)


def quiet(fn, *args, **kwargs):
    """Call with robotdyn's warnings recorded; returns (result, [messages])."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = fn(*args, **kwargs)
    return out, [str(w.message) for w in caught if issubclass(w.category, RobotDynWarning)]


@pytest.fixture(scope="module")
def diff_drive():
    return load_robot(TOML / "diff_drive.toml")


@pytest.fixture(scope="module")
def mecanum_robot():
    return load_robot(TOML / "mecanum.toml")


@pytest.fixture(scope="module")
def swerve():
    return load_robot(TOML / "swerve3.toml")


# ---------------------------------------------------------------------------------------------- packages
def test_package_index_finds_packages_by_manifest_name_by_directory_and_by_environment(tmp_path, monkeypatch):
    index = PackageIndex.create(dirs=[SRC], environment=False)
    assert index.find("demo_sensors") == (SRC / "sensors").resolve()  # package.xml <name>, not the directory name
    assert index.find("demo_description") == PKG.resolve()
    assert index.find("sensors") == (SRC / "sensors").resolve()  # a directory named so (Pinocchio's convention)
    assert index.find("nothing_here") is None
    assert PackageIndex.create({"demo_sensors": PKG}, [SRC], environment=False).find("demo_sensors") == PKG.resolve()
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(SRC))
    assert PackageIndex.create().find("demo_sensors") == (SRC / "sensors").resolve()
    monkeypatch.delenv("ROS_PACKAGE_PATH")
    (tmp_path / "share" / "demo_ament").mkdir(parents=True)
    monkeypatch.setenv("AMENT_PREFIX_PATH", str(tmp_path))
    assert PackageIndex.create().find("demo_ament") == (tmp_path / "share" / "demo_ament").resolve()


def test_find_resolves_through_the_index_and_xacro_is_restored():
    import xacro.substitution_args as sa

    before = sa._eval_find
    text = expand_xacro(PKG / "urdf" / "diff_drive.urdf.xacro", packages=PackageIndex.create(dirs=[SRC]))
    assert sa._eval_find is before
    assert 'name="lidar_link"' in text  # from the second package, found by its package.xml
    assert f"{(SRC / 'sensors').resolve()}/config/lidar.yaml" in text  # $(find) in text: the package's directory
    assert "nonexistent-ros-package" not in text  # the conditional include of demo_gazebo is off: not looked up


def test_every_missing_package_named_at_once():
    path = PKG / "urdf" / "missing_packages.urdf.xacro"
    with pytest.raises(MissingPackagesError) as err:
        expand_xacro(path, packages=PackageIndex.create(dirs=[SRC]))
    msg = str(err.value)
    assert err.value.names == ["demo_arm_description", "demo_bumper_description"]  # not the conditional demo_gazebo
    assert "\n" not in msg and "--package NAME=DIR" in msg and "ROS_PACKAGE_PATH" in msg
    # without the workspace, the two packages of the workspace are missing too
    with pytest.raises(MissingPackagesError) as err:
        expand_xacro(path, packages=PackageIndex.create(environment=False))
    assert err.value.names == ["demo_arm_description", "demo_bumper_description", "demo_description", "demo_sensors"]
    assert required_packages(path, PackageIndex.create(dirs=[SRC])) == {"demo_arm_description",
                                                                       "demo_bumper_description"}


def test_packages_from_the_cli_and_the_constraint_file(tmp_path, capsys):
    toml = tmp_path / "robot.toml"
    body = (TOML / "diff_drive.toml").read_text().replace('package_dirs = ["../.."]', "")
    body = body.replace("package://demo_description/urdf/diff_drive.urdf.xacro", str(PKG / "urdf" / "diff_drive.urdf.xacro"))
    toml.write_text(body)
    assert main(["info", "--constraints", str(toml)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "packages not found: demo_description, demo_sensors" in err
    assert main(["info", "--constraints", str(toml), "--package", f"demo_description={PKG}",
                 "--package", f"demo_sensors={SRC / 'sensors'}"]) == 0
    assert main(["info", "--constraints", str(toml), "--package", str(SRC)]) == 0
    assert main(["info", "--constraints", str(toml), "--package", str(tmp_path / "absent")]) == 2
    assert "package_dirs: " in capsys.readouterr().err
    capsys.readouterr()
    table = f'[packages]\ndemo_description = "{PKG}"\ndemo_sensors = "{SRC / "sensors"}"\n\n[[wheels]]'
    toml.write_text(body.replace("[[wheels]]", table, 1))
    assert load_robot(toml).description.root_height == pytest.approx(0.08)
    toml.write_text(body.replace("[[wheels]]", table.replace(str(SRC / "sensors"), str(tmp_path / "absent")), 1))
    with pytest.raises(ConstraintFileError, match="packages.*no such directory"):
        read(toml)


# ------------------------------------------------------------------------------------------------ meshes
def test_meshes_missing_or_outside_are_reported_with_stand_ins(capsys):
    robot, on_load = quiet(load_robot, TOML / "diff_drive.toml", urdf=str(PKG / "urdf" / "meshes_broken.urdf.xacro"))
    assert on_load == []  # said where meshes matter (the viewer, info), not on every load (it was, on every command)
    _, messages = quiet(Viewer, robot)
    report = robot.description.visual_report
    assert report.standins == {"bumper": "collision", "antenna": "inertia box", "mast": "marker",
                               "cover": "collision", "plate": "inertia box"}
    assert len(messages) == 2 and all("\n" not in m for m in messages)
    assert "bumper.stl (file not found" in messages[0] and "antenna.dae" in messages[0]
    assert "Packages not found: demo_mast_description" in messages[0]
    assert "outside the description's packages not read" in messages[1] and "package_dirs" in messages[1]
    assert {Path(p) for _, p, _ in report.refused} == {(WS / "outside" / "elsewhere.stl").resolve()}
    # the CLI: info lists them, dump says nothing of them
    argv = ["--constraints", str(TOML / "diff_drive.toml"), "--urdf", str(PKG / "urdf" / "meshes_broken.urdf.xacro")]
    assert main(["info", *argv]) == 0
    out = capsys.readouterr()
    assert [line for line in out.out.splitlines() if line.startswith("meshes: ")] == [f"meshes: {m}" for m in messages]
    assert main(["dump", *argv, "--v", "0", "0"]) == 0
    assert "mesh" not in capsys.readouterr().err
    shapes = {g.name.rsplit("_", 1)[0]: g for g in robot.description.visual.geometryObjects}
    assert set(shapes) >= {"base_link", "left_wheel_link", "right_wheel_link", "lidar_link", "caster_link",
                           "bumper", "antenna", "mast", "cover", "plate"}
    # the antenna's box has its inertia (uniform box: I_xx = m (b^2 + c^2) / 12), checked from its sides
    sides = 2.0 * np.asarray(shapes["antenna"].geometry.halfSide)
    I = np.sort(0.1 * (np.sum(sides**2) - sides**2) / 12.0)
    assert I == pytest.approx(np.sort([3.4e-4, 3.4e-4, 1e-5]), rel=1e-9)
    # a page of the robot shows every link and holds no byte of the refused file
    page = Viewer(robot).static_html()
    objects = [c for c in page_commands(page) if b"set_object" in c and b"robotdyn/robot/visuals" in c]
    assert len(objects) == len(shapes)
    secret = (WS / "outside" / "elsewhere.stl").read_bytes()
    assert not any(secret[:200] in c for c in page_commands(page))


def test_a_mesh_that_cannot_be_loaded_is_replaced(tmp_path):
    shutil.copytree(SRC, tmp_path / "src")
    (tmp_path / "src/demo_description/meshes/wheel.stl").write_bytes(b"not a mesh\x00\x01")
    robot = load_robot(tmp_path / "src/demo_description/robotdyn/diff_drive.toml")
    _, messages = quiet(Viewer, robot)
    assert robot.description.visual_report.standins == {"left_wheel_link": "collision",
                                                        "right_wheel_link": "collision"}
    assert len(messages) == 1 and messages[0].count("cannot be loaded") == 2
    kinds = {g.name: type(g.geometry).__name__ for g in robot.description.visual.geometryObjects}
    assert kinds["left_wheel_link_0"] == kinds["right_wheel_link_0"] == "Cylinder"  # the collision cylinders


def test_meshes_outside_allowed_by_declaring_their_directory():
    robot = load_robot(TOML / "diff_drive.toml", urdf=str(PKG / "urdf" / "meshes_broken.urdf.xacro"),
                       package_dirs=[WS / "outside"])
    _, messages = quiet(Viewer, robot)
    assert not robot.description.visual_report.refused
    assert robot.description.visual_report.standins.get("cover") is None
    assert len(messages) == 1 and "outside" not in messages[0]


def test_compact_page_stores_a_shared_mesh_once(diff_drive):
    viewer = Viewer(diff_drive)
    commands = viewer._window.commands()
    page = viewer.static_html()
    assert page_commands(page) == commands  # exact round trip
    wheel = (PKG / "meshes" / "wheel.stl").read_bytes()
    assert sum(c.count(wheel) for c in commands) == 2  # two wheels draw the same file
    import zlib

    raw = zlib.decompress(pack_scene(commands))
    assert raw.count(wheel) == 1
    assert len(pack_scene(commands)) < 0.5 * sum(map(len, commands))
    assert unpack_scene(pack_scene([b"", b"x" * 5000, b"x" * 5000])) == [b"", b"x" * 5000, b"x" * 5000]


@pytest.mark.skipif(shutil.which("node") is None, reason="node not installed (the browser tests check the page)")
def test_page_unpacker_script_gives_the_same_commands(diff_drive, tmp_path):
    """The page's own JavaScript (inflate and unpack), run by node: byte for byte the commands Python packed, and
    zlib's output inflated exactly for stored, fixed-Huffman and dynamic-Huffman blocks."""
    import base64
    import hashlib
    import json
    import zlib

    from robotdyn.interfaces.scene_page import _UNPACK_JS

    page = Viewer(diff_drive).static_html()
    scene = re.search(r'var robotdyn_scene = "[^"]*";', page).group(0)
    rng = np.random.default_rng(0)
    samples = [b"", b"a", b"abcabcabc" * 50, rng.bytes(70000), bytes(rng.choice([97, 98], 100000).astype(np.uint8)),
               (PKG / "meshes" / "wheel.stl").read_bytes(), bytes(300000)]
    cases = [[base64.b64encode(zlib.compress(b, level)).decode(), hashlib.sha256(b).hexdigest()]
             for b in samples for level in (0, 1, 9)]
    script = tmp_path / "unpack.js"
    script.write_text(scene + "\n" + _UNPACK_JS + f"\nconst cases = {json.dumps(cases)};\n" + """
const crypto = require('crypto');
const sha = (b) => crypto.createHash('sha256').update(b).digest('hex');
console.log(robotdyn_unpack(robotdyn_scene).map(sha).join(' '));
console.log(cases.every(([z, h]) => sha(robotdyn_inflate(new Uint8Array(Buffer.from(z, 'base64')))) === h));
""")
    out = subprocess.run(["node", str(script)], capture_output=True, text=True, timeout=60)
    lines = out.stdout.splitlines()
    assert lines[0].split() == [hashlib.sha256(c).hexdigest() for c in page_commands(page)], out.stderr
    assert lines[1] == "true", out.stderr


def test_view_cli_writes_a_page_with_the_robot(tmp_path, capsys):
    html = tmp_path / "page.html"
    assert main(["view", "--constraints", str(TOML / "diff_drive.toml"), "--urdf",
                 str(PKG / "urdf" / "meshes_broken.urdf.xacro"), "--html", str(html)]) == 0
    err = capsys.readouterr().err
    assert err.count("robotdyn: warning:") == 2
    assert sum(b"robotdyn/robot/visuals" in c for c in page_commands(html.read_text())) >= 10


# ------------------------------------------------------------------------------------------- root height
def test_root_height_found_from_the_wheels(diff_drive, mecanum_robot, swerve):
    for robot, r in ((diff_drive, 0.08), (mecanum_robot, 0.05), (swerve, 0.06)):
        assert robot.description.root_height == pytest.approx(r, abs=1e-12)  # base_link at the axles
        assert robot.root_height_source == "found from the wheels"
        robot.check_constraints(robot.neutral())
        assert max(abs(h) for h in robot.wheel_heights().values()) < 1e-12
    assert diff_drive.info()["root_height"] == pytest.approx(0.08)


def test_wrong_root_height_gets_the_right_advice(tmp_path):
    text = (TOML / "diff_drive.toml").read_text().replace('root = "planar"', 'root = "planar"\nroot_height = 0.0')
    toml = TOML / "_root_height_zero.toml"  # beside the original: package_dirs is relative to the file
    try:
        toml.write_text(text)
        robot = load_robot(toml)
        with pytest.raises(ConstraintError, match=r"every wheel is 0\.08 m below the ground.*root_height = 0\.08"):
            robot.check_constraints(robot.neutral())
        toml.write_text(text.replace("root_height = 0.0", "root_height = 0.08"))
        load_robot(toml).check_constraints(np.zeros(5))
        floating = text.replace('root = "planar"', 'root = "floating"').replace("root_height = 0.0\n", "")
        floating = floating.replace('independent = ["theta_R", "theta_L"]', "")
        toml.write_text(floating)
        robot = load_robot(toml)
        with pytest.raises(ConstraintError, match=r"set z = 0\.08"):
            robot.check_constraints(robot.neutral())
    finally:
        toml.unlink(missing_ok=True)


def test_loads_at_rest_balance_with_the_root_above_the_ground(diff_drive):
    """Static balance by hand: caster load m g |x_G| / 0.25 from moments about the axle, the rest shared by the
    two wheels (the mass centre is on the centre line)."""
    masses = {"base": (10.0, -0.05), "wheels": (1.0, 0.0), "caster": (0.2, -0.25), "lidar": (0.3, 0.1)}
    m = sum(mi for mi, _ in masses.values())
    x_g = sum(mi * xi for mi, xi in masses.values()) / m
    caster = m * G * -x_g / 0.25
    forces = diff_drive.contact_forces(diff_drive.neutral(), np.zeros(2), tau=np.zeros(2))
    normal = {w.name: w.force[2] for w in forces.wheels}
    assert normal["caster"] == pytest.approx(caster, rel=1e-9)
    assert normal["left"] == pytest.approx((m * G - caster) / 2, rel=1e-9)
    assert normal["right"] == pytest.approx((m * G - caster) / 2, rel=1e-9)


# ------------------------------------------------------------------------------------------ dropped rows
def test_dropped_row_violation_named_with_its_size_on_both_paths(swerve):
    """At zero steering the rear lateral rows coincide; its acceleration condition gives the closed form
    a_y - alpha a - s'_i v_x = 0 for each rear wheel i, so the dropped one is violated by |s'_rl - s'_rr| v_x."""
    q = swerve.neutral()
    nu = np.array([1.0, 0.0, 0.5, -0.3])  # x', s'_front, s'_rl, s'_rr
    results = []
    for compiled in (True, False):
        with use_compiled(compiled):
            nudot, messages = quiet(swerve.forward_dynamics, q, nu, np.zeros(4))
        (found,) = swerve.redundant_row_violations(q, nu, nudot)
        assert found.label in ("rear_left.lateral", "rear_right.lateral")
        assert abs(found.acceleration) == pytest.approx(0.8 * 1.0, rel=1e-9)
        assert abs(found.velocity) < 1e-12
        assert len(messages) == 1 and found.label in messages[0] and "0.8 m/s^2" in messages[0]
        results.append((found.label, found.acceleration, nudot))
    assert results[0][0] == results[1][0] and results[0][1] == pytest.approx(results[1][1], rel=1e-12)
    # rear wheels steered at the same rate: the rows stay dependent, nothing to say
    nudot, messages = quiet(swerve.forward_dynamics, q, np.array([1.0, 0.3, 0.5, 0.5]), np.zeros(4))
    assert messages == [] and swerve.redundant_row_violations(q, [1.0, 0.3, 0.5, 0.5], nudot) == []
    assert any("mobility changes at the neutral configuration: 4 here, 3" in n for n in swerve.mobility_check()[1])


def test_dump_and_simulate_warn_about_the_dropped_row(capsys):
    toml = str(TOML / "swerve3.toml")
    assert main(["dump", "--constraints", toml, "--v", "2", "0", "0.5", "-0.3", "--tau-set", "drive_front=0.1",
                 "--json"]) == 0
    out = capsys.readouterr()
    import json

    (found,) = json.loads(out.out)["dropped_row_violations"]
    assert abs(found["acceleration"]) == pytest.approx(1.6, rel=1e-9)
    assert out.err.count("robotdyn: warning:") == 1 and "lateral by 1.6 m/s^2" in out.err


# ------------------------------------------------------------------------------------------- body twist
MECANUM_WHEELS = [Wheel(0.25, 0.2, 0.6, 0.0009, 0.0006, 0.05, -np.pi / 4),
                  Wheel(0.25, -0.2, 0.6, 0.0009, 0.0006, 0.05, np.pi / 4),
                  Wheel(-0.25, 0.2, 0.6, 0.0009, 0.0006, 0.05, np.pi / 4),
                  Wheel(-0.25, -0.2, 0.6, 0.0009, 0.0006, 0.05, -np.pi / 4)]


def test_mecanum_body_twist_against_the_closed_form(mecanum_robot):
    robot = mecanum_robot
    assert robot.velocity_names == ["vx", "vy", "wz"]
    bodies = [Body(12.0, 0.03, 0.01, 0.4)]
    rng = np.random.default_rng(14)
    for k in range(4):
        q = robot.neutral()
        q[:3] = rng.uniform(-2.0, 2.0, 3)
        q[3:] = rng.uniform(-3.0, 3.0, 4)
        nu = rng.normal(size=3)
        M, h, J = mecanum(bodies, MECANUM_WHEELS, q[2], nu)
        red = robot.reduced(q, nu, coriolis=True)
        assert np.abs(red.S[3:] - J).max() < 1e-12  # inverse kinematics: wheel rates per body twist
        assert np.abs(red.M - M).max() < 1e-12 and np.abs(red.h - h).max() < 1e-12
        assert np.abs(red.C @ nu - h).max() < 1e-12
        for compiled in (True, False):
            with use_compiled(compiled):
                fast = robot.reduced(q, nu)
            assert np.abs(fast.M - M).max() < 1e-12 and np.abs(fast.h - h).max() < 1e-12
    # the textbook inverse kinematics of an X-arranged mecanum base, r phi' = vx -+ vy -+ (a + b) wz
    assert J * 0.05 == pytest.approx(np.array([[1, -1, -0.45], [1, 1, 0.45], [1, 1, -0.45], [1, -1, 0.45]]))


def test_unicycle_in_its_body_twist_against_the_closed_form():
    robot = read(TOML / "diff_drive.toml", twist="base_link:vx,wz").robot()
    assert robot.velocity_names == ["vx", "wz"]
    wheels = [Wheel(0.0, -0.2, 0.5, 0.0016, 0.001, 0.08), Wheel(0.0, 0.2, 0.5, 0.0016, 0.001, 0.08)]
    bodies = [Body(10.0, -0.05, 0.0, 0.25), Body(0.2, -0.25, 0.0, 7.2e-5), Body(0.3, 0.1, 0.0, 2e-4)]
    rng = np.random.default_rng(3)
    for _ in range(3):
        q = robot.neutral()
        q[2], q[3:] = rng.uniform(-3, 3), rng.uniform(-3, 3, 2)
        nu = rng.normal(size=2)
        M, h = unicycle(bodies, wheels, q[2], nu)
        red = robot.reduced(q, nu, coriolis=True)
        assert np.abs(red.M - M).max() < 1e-12 and np.abs(red.h - h).max() < 1e-12
    # by hand: m = 11.5 kg plus the wheels' spin 2 I_s / r^2; the mass centre behind the axle couples v and w
    assert M[0, 0] == pytest.approx(11.5 + 2 * 0.0016 / 0.08**2)


def test_synchro_drive_against_the_closed_form():
    """The three steering joints coupled one to one: the wheels stay parallel, the base never yaws, and in
    (phi', s') the reduced model is diag(m r^2 + 3 I_s, 3 (I_steer + I_d)) with no velocity terms."""
    f = read(TOML / "swerve3.toml")
    same = (lambda x: x, lambda x: 1.0, lambda x: 0.0)
    couplings = [lambda rb, j=j: JointCoupling(rb.description, j, "front_steer_joint", *same)
                 for j in ("rear_left_steer_joint", "rear_right_steer_joint")]
    robot = Robot(replace(f.SPEC, independent=["front_wheel_joint", "front_steer_joint"], constraints=couplings))
    wheels = [Wheel(0.3, 0.0, 0.5, 0.0009, 0.0005, 0.06), Wheel(-0.3, 0.25, 0.5, 0.0009, 0.0005, 0.06),
              Wheel(-0.3, -0.25, 0.5, 0.0009, 0.0005, 0.06)]
    bodies = [Body(15.0, 0.0, 0.0, 0.5)] + [Body(0.4, w.x, w.y, 0.0) for w in wheels]
    rng = np.random.default_rng(5)
    for _ in range(3):
        q = robot.neutral()
        q[2], s = rng.uniform(-3, 3), rng.uniform(-3, 3)
        for j in ("front_steer_joint", "rear_left_steer_joint", "rear_right_steer_joint"):
            q[robot.coordinate_index(j)] = s
        nu = rng.normal(size=2)
        M, h = synchro(bodies, wheels, 0.002, q[2], s, nu)
        red = robot.reduced(q, nu, coriolis=True)
        assert np.abs(red.M - M).max() < 1e-14 and np.abs(red.h - h).max() < 1e-14
    assert M == pytest.approx(np.diag([17.7 * 0.06**2 + 3 * 0.0009, 3 * (0.002 + 0.0005)]))


def test_mecanum_scenario_conserves_energy_and_runs_from_the_cli(mecanum_robot, tmp_path, capsys):
    sc = read(TOML / "mecanum.toml").SCENARIOS["spin_strafe"]
    traj = sc.run(mecanum_robot, n_out=101, progress=False)
    assert traj.nu[0] == pytest.approx([0.0, 0.3, 0.5])
    assert np.ptp(traj.energy) < 1e-6 * traj.energy[0]  # unpowered, no slip: kinetic energy is constant
    csv = tmp_path / "strafe.csv"
    assert main(["simulate", "--constraints", str(TOML / "mecanum.toml"), "--scenario", "strafe", "--quiet", "--t-end", "0.4",
                 "--csv", str(csv), "--json"]) == 0
    import json

    out = json.loads(capsys.readouterr().out)
    final = out["final"]
    assert final["vy"] > 0.05  # sideways, to the left (the mass centre's offset adds a little vx and wz)
    # constant torques: the work is tau . (wheel angles travelled), which the energy must have gained
    tau = {"front_left_wheel_joint": -0.1, "front_right_wheel_joint": 0.1, "rear_left_wheel_joint": 0.1,
           "rear_right_wheel_joint": -0.1}
    work = sum(t * final[j] for j, t in tau.items())  # the wheels start at 0 rad
    assert out["energy_end"] - out["energy_start"] == pytest.approx(work, rel=1e-5)


def test_twist_from_the_cli_and_its_errors(tmp_path, capsys):
    toml = str(TOML / "diff_drive.toml")
    assert main(["dump", "--constraints", toml, "--twist", "base_link:vx,wz", "--v", "0.5", "0.2", "--json"]) == 0
    import json

    out = json.loads(capsys.readouterr().out)
    assert out["coordinates"] == ["vx", "wz"]
    assert main(["dump", "--constraints", toml, "--twist", "base_lnk", "--v", "0.5", "0.2"]) == 2
    assert "did you mean 'base_link'" in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    text = (TOML / "mecanum.toml").read_text().replace('package_dirs = ["../.."]', f'package_dirs = ["{SRC}"]')
    text = text.replace("package://demo_description", str(PKG))
    for old, new, expected in [
        ('components = ["vx", "vy", "wz"]', 'components = ["vx", "vq"]', "expected distinct entries"),
        ('[twist]', 'independent = ["x"]\n[twist]', "either 'independent'"),
        ('frame = "base_link"', 'frame = "base_link"\naxes = "tool"', "expected 'body'"),
        ('nu0 = { vy = 0.3, wz = 0.5 }', 'nu0 = { v_y = 0.3 }', "not a twist component"),
    ]:
        bad.write_text(text.replace(old, new, 1) if "independent" not in new else
                       new.split("\n")[0] + "\n" + text.replace(old, "[twist]", 1))
        with pytest.raises(ConstraintFileError, match=re.escape(expected)):
            read(bad)


# ------------------------------------------------------------------------------------ torques by name
def test_torques_by_motor_name(diff_drive, capsys):
    sc = read(TOML / "diff_drive.toml").SCENARIOS["arc"]
    assert sc.torque(0.0, None, None).tolist() == [0.4, 0.2]  # motors in file order: tau_R, tau_L
    toml = str(TOML / "diff_drive.toml")
    assert main(["dump", "--constraints", toml, "--v", "0", "0", "--tau-set", "tau_L=0.2", "--json"]) == 0
    import json

    a_named = json.loads(capsys.readouterr().out)["a"]
    assert main(["dump", "--constraints", toml, "--v", "0", "0", "--tau", "0", "0.2", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["a"] == a_named
    assert main(["dump", "--constraints", toml, "--v", "0", "0", "--tau-set", "tau_X=1"]) == 2
    assert "no motor named 'tau_X'; motors are tau_R, tau_L" in capsys.readouterr().err
    text = (TOML / "diff_drive.toml").read_text().replace("tau_L = 0.2 }", "tau_l = 0.2 }")
    bad = TOML / "_bad_torque.toml"
    try:
        bad.write_text(text)
        with pytest.raises(ConstraintFileError, match=r"scenarios\[0\] \(arc\): torque: unknown key 'tau_l'.*allowed: tau_R, tau_L"):
            read(bad)
    finally:
        bad.unlink(missing_ok=True)
