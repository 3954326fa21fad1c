"""The meshcat viewer, checked on what the browser receives: the standalone HTML export's scene commands are
decoded and compared with independent references (yourdfpy forward kinematics of the URDF, the terrain's formula,
the trajectory's own times). Every registered robot is covered (parametrised over robotdyn.robots.names())."""

from __future__ import annotations

import os
import re
import subprocess
from dataclasses import dataclass
import sys
import urllib.request
from pathlib import Path

import numpy as np
import pytest
import umsgpack

import robotdyn
from oracles.urdf_fk import UrdfVisuals
from robotdyn.cli.commands import main
from robotdyn.errors import InputError
from robotdyn.robots import names
from robotdyn.constraints.terrain import FlatTerrain, SineTerrain
from robotdyn.interfaces.scene_page import page_commands
from robotdyn.interfaces.viewer import Viewer

ROBOTS = names()


@pytest.fixture(scope="module")
def robots():
    cache = {}

    def get(name):
        if name not in cache:
            cache[name] = robotdyn.load(name)
        return cache[name]

    return get


# ----------------------------------------------------------------------------------------------- helpers
def decode(page: str) -> list[dict]:
    """The scene commands of a static export, in the order the page applies them."""
    return [umsgpack.unpackb(c) for c in page_commands(page)]


def transforms(cmds: list[dict]) -> dict[str, np.ndarray]:
    """Last set_transform of each path, as 4x4 matrices (meshcat sends them column-major)."""
    return {c["path"]: np.array(c["matrix"], float).reshape(4, 4).T for c in cmds if c["type"] == "set_transform"}


def properties(cmds: list[dict], path: str, prop: str) -> list:
    return [c["value"] for c in cmds if c["type"] == "set_property" and c["path"] == path and c["property"] == prop]


def vertices(obj: dict) -> np.ndarray:
    pos = obj["geometries"][0]["data"]["attributes"]["position"]
    return np.frombuffer(pos["array"].data, dtype=np.float32).reshape(-1, 3).astype(float)


def visual_key(robot, i: int) -> tuple[str, int]:
    """(link, index among the link's visuals) of Pinocchio's i-th visual geometry (named <link>_<k>)."""
    g = robot.description.visual.geometryObjects[i]
    link = robot.model.frames[g.parentFrame].name
    return link, int(g.name.rsplit("_", 1)[1])


def random_q(robot, rng) -> np.ndarray:
    """Random coordinates: within the joint limits where finite, else in [-1.5, 1.5]."""
    lo = np.where(np.isfinite(robot.description.lower), robot.description.lower, -1.5)
    hi = np.where(np.isfinite(robot.description.upper), robot.description.upper, 1.5)
    return rng.uniform(lo, hi)


def quat_matrix(x: float, y: float, z: float, w: float) -> np.ndarray:
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


# ------------------------------------------------------------------------------------------------- tests
@pytest.mark.parametrize("name", ROBOTS)
def test_display_places_every_visual_as_urdf_forward_kinematics(name, robots):
    """Each visual's transform in the export equals yourdfpy's link transform times the URDF visual origin, at
    3 random configurations (to 1e-9 m / rad)."""
    robot = robots(name)
    fk = UrdfVisuals(robot)
    viewer = Viewer(robot)
    rng = np.random.default_rng(7)
    worst = 0.0
    for _ in range(3):
        q = random_q(robot, rng)
        viewer.display(q)
        got = transforms(decode(viewer.static_html()))
        ref = fk.visuals(q)
        n = len(robot.description.visual.geometryObjects)
        assert n == len(ref) > 0
        for i, g in enumerate(robot.description.visual.geometryObjects):
            T = got[f"/meshcat/robotdyn/robot/visuals/{g.name}"]
            worst = max(worst, float(np.max(np.abs(T - ref[visual_key(robot, i)][0]))))
    assert worst < 1e-9, worst


@pytest.mark.parametrize("name", ROBOTS)
def test_contact_markers_sit_on_the_rim_and_follow_the_terrain_normal(name, robots):
    """Each wheel's contact marker at the neutral configuration: |p - c| = R, (p - c) . axle = 0 (c, axle from
    yourdfpy), its z axis is the terrain normal at p (central differences of the height), and p is on the terrain
    when the robot's holonomic residual there is zero."""
    robot = robots(name)
    wheels = [c for c in robot.constraints if hasattr(c, "contact")]
    if not wheels:
        pytest.skip(f"{name} has no wheels")
    q = robot.neutral()
    fk = UrdfVisuals(robot)
    fk.configure(q)
    cmds = decode(Viewer(robot).static_html())
    got = transforms(cmds)
    on_ground = np.max(np.abs(robot.constraint_residual(q)), initial=0.0) < 1e-9
    for w in wheels:
        T = got[f"/meshcat/robotdyn/contacts/{w.name}"]
        p, n = T[:3, 3], T[:3, 2]
        Tw = fk.link(w.frame)
        c, axle = Tw[:3, 3], Tw[:3, :3] @ w.axis
        R = w.radius + (0.0 if w.radius_index is None else q[w.radius_index])
        assert abs(np.linalg.norm(p - c) - R) < 1e-9
        assert abs((p - c) @ axle) < 1e-9
        h, f = 1e-6, robot.terrain.height
        fx = (f(p[0] + h, p[1]) - f(p[0] - h, p[1])) / (2 * h)
        fy = (f(p[0], p[1] + h) - f(p[0], p[1] - h)) / (2 * h)
        normal = np.array([-fx, -fy, 1.0]) / np.linalg.norm([-fx, -fy, 1.0])
        assert np.allclose(n, normal, atol=1e-7)
        assert np.allclose(T[:3, :3].T @ T[:3, :3], np.eye(3), atol=1e-12)
        if on_ground:
            assert abs(p[2] - f(p[0], p[1])) < 1e-9


def test_animation_keys_are_at_the_trajectory_times(robots):
    """Keys at t0 + k/fps and the last sample (three.js plays key frame f at f/fps s, so the animation lasts
    exactly t_end - t0), and each key's pose equals yourdfpy's at q linearly interpolated by this test."""
    robot = robots("quasimoro")
    rng = np.random.default_rng(3)
    t = np.array([0.2, 0.33, 0.6, 1.2, 1.57])
    Q = np.array([random_q(robot, rng) for _ in t])
    viewer = Viewer(robot)
    fps = 10.0
    viewer.animate((t, Q), fps=fps)
    cmds = decode(viewer.static_html())
    anims = [c for c in cmds if c["type"] == "set_animation"]
    assert len(anims) == 1 and anims[0]["options"]["play"]
    clips = {a["path"]: a["clip"] for a in anims[0]["animations"]}
    expected = np.append(0.2 + np.arange(14) / 10.0, 1.57)  # 0.2, 0.3, ..., 1.5, then 1.57
    fk = UrdfVisuals(robot)
    g = robot.description.visual.geometryObjects
    for i in range(len(g)):
        clip = clips[f"/meshcat/robotdyn/robot/visuals/{g[i].name}"]
        assert clip["fps"] == fps
        tracks = {tr["name"]: tr for tr in clip["tracks"]}
        times = np.array([k["time"] for k in tracks[".position"]["keys"]]) / fps + t[0]
        assert np.allclose(times, expected, atol=1e-12)
        for k, tk in enumerate(expected):
            qk = np.array([np.interp(tk, t, Q[:, j]) for j in range(robot.nq)])
            ref = fk.visuals(qk)[visual_key(robot, i)][0]
            pos = tracks[".position"]["keys"][k]["value"]
            rot = quat_matrix(*tracks[".quaternion"]["keys"][k]["value"])
            assert np.allclose(pos, ref[:3, 3], atol=1e-9)
            assert np.allclose(rot, ref[:3, :3], atol=1e-9)


def test_long_animation_is_capped_at_max_keys_and_keeps_its_duration(robots):
    """A 100 s run with max_keys=50: at most 50 keys per track, at a uniform rate, the last at 100 s."""
    robot = robots("quasimoro")
    t = np.linspace(0.0, 100.0, 11)
    Q = np.tile(robot.neutral(), (11, 1))
    Q[:, robot.coordinate_index("x")] = 0.01 * t
    viewer = Viewer(robot)
    viewer.animate((t, Q), fps=30, max_keys=50)
    (anim,) = [c for c in decode(viewer.static_html()) if c["type"] == "set_animation"]
    for a in anim["animations"]:
        fps = a["clip"]["fps"]
        for track in a["clip"]["tracks"]:
            times = np.array([k["time"] for k in track["keys"]]) / fps
            assert 2 <= len(times) <= 50
            assert abs(times[-1] - 100.0) < 1e-9 and np.allclose(np.diff(times), 100.0 / 49, rtol=1e-9)


def test_animation_of_a_scenario_lasts_as_long_as_the_simulation(robots):
    """A simulated scenario's animation ends at the simulated t_end, starting from its q0."""
    robot = robots("quasimoro")
    from robotdyn.robots.quasimoro import SCENARIOS

    traj = SCENARIOS["rectilinear"].run(robot, t_end=0.4, progress=False)
    viewer = Viewer(robot)
    viewer.animate(traj, fps=25)
    cmds = decode(viewer.static_html())
    (anim,) = [c for c in cmds if c["type"] == "set_animation"]
    last = max(k["time"] for a in anim["animations"] for tr in a["clip"]["tracks"] for k in tr["keys"])
    assert abs(last / 25 - 0.4) < 1e-12
    assert np.allclose(viewer.q, traj.q[0])


def test_terrain_mesh_samples_the_surface(robots):
    """A curved terrain is drawn as a mesh whose vertices satisfy z = 0.05 sin(2x + y) (float32) and that covers
    the robot; a flat terrain at h is a plane at h; meshcat's grid is hidden."""
    base = robots("quasimoro")
    sine = robotdyn.Robot(base.spec, terrain=SineTerrain(0.05, 2.0, 1.0))
    cmds = decode(Viewer(sine).static_html())
    (obj,) = [c["object"] for c in cmds if c["type"] == "set_object" and c["path"] == "/meshcat/robotdyn/terrain"]
    V = vertices(obj)
    assert len(V) > 1000
    assert np.max(np.abs(V[:, 2] - 0.05 * np.sin(2 * V[:, 0] + V[:, 1]))) < 2e-6
    assert V[:, 0].min() < -1.0 and V[:, 0].max() > 1.0 and V[:, 1].min() < -1.0 and V[:, 1].max() > 1.0
    assert properties(cmds, "/Grid", "visible") == [False]
    flat = robotdyn.Robot(base.spec, terrain=FlatTerrain(0.25))
    cmds = decode(Viewer(flat).static_html())
    (obj,) = [c["object"] for c in cmds if c["type"] == "set_object" and c["path"] == "/meshcat/robotdyn/terrain"]
    assert np.allclose(vertices(obj)[:, 2], 0.25, atol=1e-7)


def test_layers_toggle_and_bad_input_is_one_line(robots):
    robot = robots("quasimoro")
    viewer = Viewer(robot, contacts=True, frames=False)
    viewer.show("contacts", False)
    viewer.show("frames", True)
    cmds = decode(viewer.static_html())
    assert properties(cmds, "/meshcat/robotdyn/contacts", "visible")[-1] is False
    assert properties(cmds, "/meshcat/robotdyn/frames", "visible")[-1] is True
    frames = {c["path"] for c in cmds if c["type"] == "set_object" and c["path"].startswith("/meshcat/robotdyn/frames/")}
    assert "/meshcat/robotdyn/frames/wheel_A" in frames and not any("robotdyn_root" in f for f in frames)
    with pytest.raises(InputError, match="unknown layer"):
        viewer.show("wheels")
    with pytest.raises(InputError, match="expected 6 finite coordinates"):
        viewer.display([0.0, 1.0])
    with pytest.raises(InputError, match="expected finite q and strictly increasing"):
        viewer.animate((np.array([0.0, 0.0]), np.zeros((2, 6))))
    with pytest.raises(InputError, match="expected a Trajectory or a pair"):
        viewer.animate("run.csv")
    with pytest.raises(InputError, match="fps"):
        viewer.animate((np.array([0.0, 1.0]), np.zeros((2, 6))), fps=0)


def test_static_html_is_self_contained(robots):
    page = Viewer(robots("quasimoro")).static_html()
    assert "MeshCat.Viewer" in page and "robotdyn_scene" in page
    assert not re.search(r"<script[^>]+src=|<link[^>]+href=|<iframe|<img[^>]+src=\s*[\"']?(https?:)?//", page)
    assert not re.search(r"(src|href)\s*=\s*[\"'](https?:)?//", page)


@dataclass
class Run:
    returncode: int
    stdout: str
    stderr: str


@pytest.fixture
def run_cli(capsys):
    """``robotdyn ARGS`` in-process (the console script's main: same parsing, errors and exit codes)."""

    def run(*args):
        code = main(list(args))
        out, err = capsys.readouterr()
        return Run(code, out, err)

    return run


def test_cli_view_exports_html(tmp_path, run_cli):
    out = tmp_path / "q.html"
    res = run_cli("view", "quasimoro", "--scenario", "pure_rotation", "--t-end", "0.3", "--quiet", "--html", str(out))
    assert res.returncode == 0, res.stderr
    assert f"wrote {out} (0.3 s animation)" in res.stdout
    cmds = decode(out.read_text())
    (anim,) = [c for c in cmds if c["type"] == "set_animation"]
    fps = anim["animations"][0]["clip"]["fps"]
    last = max(k["time"] for a in anim["animations"] for tr in a["clip"]["tracks"] for k in tr["keys"])
    assert abs(last / fps - 0.3) < 1e-12
    res = run_cli("view", "quasimoro", "--param", "r=0.2", "--html", str(out))
    assert res.returncode == 0, res.stderr
    wheel = [c for c in decode(out.read_text()) if c["type"] == "set_object" and c["path"].endswith("visuals/wheel_A_0")]
    assert wheel[0]["object"]["geometries"][0]["radiusTop"] == pytest.approx(0.2)


@pytest.mark.parametrize("args, message", [
    (["--scenario", "nope"], "unknown scenario 'nope' for quasimoro; expected one of"),
    (["--scenario", "rectilinear", "--t-end", "-1"], "--t-end: '-1'; expected a positive duration"),
    (["--param", "r=abc"], "parameter r = 'abc' is not a number"),
])
def test_cli_view_bad_input(tmp_path, args, message, run_cli):
    res = run_cli("view", "quasimoro", *args, "--html", str(tmp_path / "x.html"))
    assert res.returncode == 2
    assert res.stderr.count("\n") == 1 and message in res.stderr and "Traceback" not in res.stderr


def test_live_viewer_serves_the_page(robots):
    """live=True starts meshcat's server on localhost; its page is served and close() stops it."""
    viewer = Viewer(robots("quasimoro"), live=True)
    try:
        assert viewer.url.startswith("http://127.0.0.1:")
        proc = viewer._window.live.server_proc
        with urllib.request.urlopen(viewer.url, timeout=10) as resp:
            assert resp.status == 200 and b"meshcat" in resp.read().lower()
    finally:
        viewer.close()
    assert proc.poll() is not None and viewer.url is None


def test_cli_view_live_serves_until_interrupted():
    """Without --html, `robotdyn view` prints the live URL, serves the page, and stops cleanly on Ctrl-C."""
    import signal

    env = {**os.environ, "PYTHONFAULTHANDLER": "1"}  # on SIGABRT the child prints where each thread is
    # Ctrl-C as in a terminal: a test run started in the background (`make test &` from a script) ignores SIGINT,
    # and a child would inherit that, so the child gets the default disposition back
    proc = subprocess.Popen([sys.executable, "-m", "robotdyn", "view", "quasimoro", "--json"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        lines = []
        while not (lines and lines[-1].startswith("}")):
            line = proc.stdout.readline()
            assert line, proc.stderr.read()
            lines.append(line)
        info = __import__("json").loads("".join(lines))
        assert info["url"].startswith("http://127.0.0.1:") and info["html"] is None
        with urllib.request.urlopen(info["url"], timeout=10) as resp:
            assert resp.status == 200
        servers = children(proc.pid)
        assert servers, "the meshcat server should be a child process of robotdyn view"
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            code = proc.wait(timeout=20)
        except subprocess.TimeoutExpired:  # say where it hangs, then fail
            proc.send_signal(signal.SIGABRT)
            _, err = proc.communicate(timeout=20)
            pytest.fail(f"robotdyn view did not stop within 20 s of Ctrl-C; its threads:\n{err[-6000:]}")
    err = proc.stderr.read()
    assert code == 0 and "Traceback" not in err, err
    alive = [pid for pid in servers if running(pid)]
    assert not alive, f"meshcat server(s) {alive} left running"


def running(pid: int) -> bool:
    """Whether a process exists and is not a zombie (Linux /proc)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except (OSError, IndexError):
        return False


def children(pid: int) -> list[int]:
    """PIDs whose parent is ``pid`` (Linux /proc)."""
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            out.append(int(stat.parent.name))
    return out


@pytest.mark.parametrize("name", ROBOTS)
def test_every_robot_animates_its_first_scenario(name, robots):
    """0.2 s of the robot's first scenario: one clip per visual, lasting 0.2 s, first and last keys at the
    trajectory's first and last poses (yourdfpy)."""
    from robotdyn.robots import module

    scenarios = getattr(module(name), "SCENARIOS", {})
    if not scenarios:
        pytest.skip(f"{name} has no scenario")
    robot = robots(name)
    traj = next(iter(scenarios.values())).run(robot, t_end=0.2, progress=False)
    viewer = Viewer(robot)
    viewer.animate(traj)
    (anim,) = [c for c in decode(viewer.static_html()) if c["type"] == "set_animation"]
    clips = {a["path"]: a["clip"] for a in anim["animations"]}
    fk = UrdfVisuals(robot)
    first, last = fk.visuals(traj.q[0]), fk.visuals(traj.q[-1])
    for i, g in enumerate(robot.description.visual.geometryObjects):
        clip = clips[f"/meshcat/robotdyn/robot/visuals/{g.name}"]
        keys = {tr["name"]: tr["keys"] for tr in clip["tracks"]}[".position"]
        assert abs(keys[-1]["time"] / clip["fps"] - (traj.t[-1] - traj.t[0])) < 1e-12
        assert np.allclose(keys[0]["value"], first[visual_key(robot, i)][0][:3, 3], atol=1e-9)
        assert np.allclose(keys[-1]["value"], last[visual_key(robot, i)][0][:3, 3], atol=1e-9)


def test_cli_view_of_a_constraint_file_robot(tmp_path, run_cli):
    """A robot described by the user (URDF + TOML constraint file) is viewed like a registered one."""
    out = tmp_path / "own.html"
    res = run_cli("view", "--constraints", str(Path(__file__).resolve().parent.parent / "examples" / "quasimoro.toml"),
                  "--html", str(out))
    assert res.returncode == 0, res.stderr
    cmds = decode(out.read_text())
    visuals = {c["path"] for c in cmds if c["type"] == "set_object" and "/robotdyn/robot/visuals/" in c["path"]}
    contacts = {c["path"] for c in cmds if c["type"] == "set_object" and "/robotdyn/contacts/" in c["path"]}
    assert len(visuals) >= 3 and len(contacts) >= 2, (visuals, contacts)
