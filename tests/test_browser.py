"""The viewer as a user sees it: each robot's standalone HTML export rendered by headless Chromium with its
network switched off, screenshotted, and checked for the robot.

The robot is found as the pixels that change between two exports that differ only in the robot layer being
shown or hidden. They must be numerous and lie where the robot's geometry projects: its visuals' bounding-box
corners (from yourdfpy, not from the viewer) seen through meshcat's default camera (perspective, 75 degrees
vertical field of view, z up, looking at the origin from ``viewer.camera_position``).

Chromium comes from ``make chromium`` (Debian's package). Without it these tests FAIL; set
ROBOTDYN_SKIP_BROWSER=1 to skip them explicitly.
"""

from __future__ import annotations

import os
import re
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import robotdyn
from oracles.urdf_fk import UrdfVisuals
from robotdyn.robots import names
from robotdyn.constraints.terrain import SineTerrain
from robotdyn.interfaces.viewer import Viewer, find_chromium, screenshot

TILE = (400, 300)  # each export is shown in an iframe of this size [px]
FOV_DEG = 75.0  # meshcat 0.3.2's default PerspectiveCamera
THRESHOLD = 40  # summed |RGB| difference for a pixel to count as changed
BUDGET_MS = 2500  # virtual time each gallery page gets before its screenshot
PAIRS_PER_PAGE = 6  # 12 WebGL contexts per page (Chromium keeps at most 16 alive)


@pytest.fixture(scope="session")
def chromium():
    if os.environ.get("ROBOTDYN_SKIP_BROWSER") == "1":
        pytest.skip("ROBOTDYN_SKIP_BROWSER=1: browser tests skipped on request")
    exe = find_chromium()
    if exe is None:
        pytest.fail("headless Chromium not found: run `make chromium` (installs Debian's chromium), or set "
                    "ROBOTDYN_SKIP_BROWSER=1 to skip the browser tests explicitly", pytrace=False)
    return exe


@dataclass
class Pair:
    """Two exports rendered side by side (``left`` and ``right`` are file names, possibly with a #t= time)."""

    label: str
    left: str
    right: str
    meta: dict = field(default_factory=dict)
    images: tuple = ()
    error: str = ""
    srcdoc: bool = False  # the scenes run in iframes with srcdoc (their console source is about:srcdoc)
    png: str = ""  # the screenshot of the page holding this pair


def _exports(root: Path) -> dict[str, Pair]:
    """Every robot at its neutral configuration with the robot layer shown / hidden, a curved terrain shown /
    hidden, and an animation paused at 2.5 s / 1.0 s."""
    pairs: dict[str, Pair] = {}
    for name in names():
        try:
            robot = robotdyn.load(name)
            viewer = Viewer(robot)
            left = viewer.save(root / f"{name}.html").name
            viewer.show("robot", False)
            right = viewer.save(root / f"{name}_hidden.html").name
            points = UrdfVisuals(robot).points(robot.neutral())
            pairs[name] = Pair(name, left, right, meta={"camera": viewer.camera_position, "points": points})
        except Exception as exc:  # reported by that robot's test only
            pairs[name] = Pair(name, "", "", error=f"{type(exc).__name__}: {exc}")
    robot = robotdyn.Robot(robotdyn.load("quasimoro").spec, terrain=SineTerrain(0.05, 2.0, 1.0))
    viewer = Viewer(robot)
    left = viewer.save(root / "terrain.html").name
    viewer.show("terrain", False)
    pairs["@terrain"] = Pair("@terrain", left, viewer.save(root / "no_terrain.html").name)
    # the robot stays at its start for 1.5 s, then is 20 m away (out of view) until 10 s
    robot = robotdyn.load("quasimoro")
    t = np.array([0.0, 1.5, 1.6, 10.0])
    Q = np.tile(robot.neutral(), (4, 1))
    Q[2:, robot.coordinate_index("x")] = 20.0
    viewer = Viewer(robot)
    viewer.animate((t, Q), reframe=False)
    page = viewer.save(root / "animation.html").name
    pairs["@animation"] = Pair("@animation", f"{page}#t=2.5", f"{page}#t=1.0", meta={
        "camera": viewer.camera_position, "points": UrdfVisuals(robot).points(robot.neutral())})
    # what a notebook shows: Viewer._repr_html_ (the export in an iframe's srcdoc) inside a page
    viewer = Viewer(robot)
    (root / "notebook.html").write_text(f"<!DOCTYPE html><html><body style='margin: 0; overflow: hidden'>{viewer._repr_html_()}</body></html>")
    viewer.show("robot", False)
    (root / "notebook_hidden.html").write_text(f"<!DOCTYPE html><html><body style='margin: 0; overflow: hidden'>{viewer._repr_html_()}</body></html>")
    pairs["@notebook"] = Pair("@notebook", "notebook.html", "notebook_hidden.html", srcdoc=True, meta={
        "camera": viewer.camera_position, "points": UrdfVisuals(robot).points(robot.neutral())})
    return pairs


def _page(pairs: list[Pair], path: Path) -> Path:
    w, h = TILE
    frame = f'width="{w}" height="{h}" style="border: 0; display: block"'
    rows = "".join(f'<div style="display: flex; height: {h}px"><iframe src="{p.left}" {frame}></iframe>'
                   f'<iframe src="{p.right}" {frame}></iframe></div>' for p in pairs)
    path.write_text(f'<!DOCTYPE html><html><body style="margin: 0">{rows}</body></html>')
    return path


@pytest.fixture(scope="session")
def gallery(chromium, tmp_path_factory) -> dict[str, Pair]:
    """All exports rendered in as few Chromium runs as possible (start-up dominates), two runs at a time."""
    root = tmp_path_factory.mktemp("browser")
    pairs = _exports(root)
    ok = [p for p in pairs.values() if not p.error]
    pages = [ok[i : i + PAIRS_PER_PAGE] for i in range(0, len(ok), PAIRS_PER_PAGE)]

    def run(job):
        k, group = job
        page = _page(group, root / f"gallery{k}.html")
        png = root / f"gallery{k}.png"
        log = screenshot(page, png, (2 * TILE[0], TILE[1] * len(group)), BUDGET_MS, chromium=chromium, timeout=180)
        img = np.asarray(Image.open(png).convert("RGB"), dtype=int)
        for i, p in enumerate(group):
            tile = img[i * TILE[1] : (i + 1) * TILE[1]]
            p.images = (tile[:, : TILE[0]], tile[:, TILE[0] :])
            p.png = str(png)
            if p.srcdoc:
                if len(re.findall(r'"robotdyn: applied \d+ scene commands", source: about:srcdoc', log)) < 2:
                    p.error += "the scene scripts in the srcdoc iframes did not run; "
            for f in [] if p.srcdoc else {p.left.split("#")[0], p.right.split("#")[0]}:
                if not re.search(rf'"robotdyn: applied \d+ scene commands", source: \S*/{re.escape(f)}[ #]', log):
                    p.error += f"the scene script of {f} did not run; "
            bad = [line for line in log.splitlines() if "Uncaught" in line and (p.left in line or p.right in line)]
            if bad:
                p.error += " | ".join(bad)
        return log

    with ThreadPoolExecutor(max_workers=2) as pool:
        list(pool.map(run, enumerate(pages)))
    return pairs


def rendered(gallery, label: str) -> tuple[np.ndarray, np.ndarray, dict]:
    p = gallery[label]
    assert not p.error, p.error
    return p.images[0], p.images[1], {**p.meta, "png": p.png}


def changed(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.abs(a - b).sum(axis=2) > THRESHOLD


def project(points: np.ndarray, camera: np.ndarray, size: tuple[int, int] = TILE) -> np.ndarray:
    """Pixel coordinates (u right, v down) of world points seen from ``camera`` looking at the origin, in a
    viewport of ``size`` pixels."""
    w, h = size
    f = -camera / np.linalg.norm(camera)
    s = np.cross(f, [0.0, 0.0, 1.0])
    s /= np.linalg.norm(s)
    up = np.cross(s, f)
    rel = points - camera
    depth = rel @ f
    assert np.all(depth > 0), "part of the robot is behind the camera"
    k = 1.0 / np.tan(np.radians(FOV_DEG) / 2) * h / 2
    return np.column_stack([w / 2 + k * (rel @ s) / depth, h / 2 - k * (rel @ up) / depth])


def assert_robot_where_expected(mask: np.ndarray, uv: np.ndarray, label: str, margin: int = 8) -> None:
    h, w = mask.shape
    u0, v0 = np.clip(uv.min(axis=0) - margin, 0, [w, h])
    u1, v1 = np.clip(uv.max(axis=0) + margin, 0, [w, h])
    ys, xs = np.nonzero(mask)
    assert mask.sum() >= 0.01 * mask.size, f"{label}: only {mask.sum()} robot pixels"
    inside = (xs >= u0) & (xs <= u1) & (ys >= v0) & (ys <= v1)
    assert inside.mean() >= 0.97, f"{label}: {1 - inside.mean():.1%} of the robot's pixels outside its projection"
    # the drawing fills its projected box (not a speck): widths and heights at least 40 % of it
    assert xs.max() - xs.min() >= 0.4 * (u1 - u0) and ys.max() - ys.min() >= 0.4 * (v1 - v0), label


@pytest.mark.parametrize("name", names())
def test_robot_is_visible_where_its_geometry_projects(name, gallery):
    shown, hidden, meta = rendered(gallery, name)
    assert_robot_where_expected(changed(shown, hidden), project(meta["points"], meta["camera"]), f"{name} ({meta['png']})")


def test_terrain_mesh_is_visible(gallery):
    """A curved terrain (0.05 sin(2x + y)) is drawn: hiding it changes a third of the image or more, and the
    pixels it covers are terrain-coloured (green to sand: red and green above blue), not sky."""
    shown, hidden, meta = rendered(gallery, "@terrain")
    mask = changed(shown, hidden)
    assert mask.mean() > 0.33, (mask.mean(), meta["png"])
    r, g, b = (shown[mask][:, i].mean() for i in range(3))
    assert r > b and g > b, (r, g, b)


def test_animation_time_base_in_the_browser(gallery):
    """A trajectory holds the robot at its start for 1.5 s, then puts it 20 m away (out of view) until 10 s.
    Opened paused at 1.0 s (page.html#t=1.0) the robot is at its start; at 2.5 s it is gone. A wrong time base
    (keys read as seconds at 30 fps, or frames at 1 fps) fails one of the two."""
    late, early, meta = rendered(gallery, "@animation")
    assert_robot_where_expected(changed(early, late), project(meta["points"], meta["camera"]), f"animation ({meta['png']})")


def test_notebook_inline_display_shows_the_robot(gallery):
    """The viewer's notebook rendering (the export in an iframe's srcdoc) shows the robot where it projects.
    The inline iframe is 420 px high and as wide as its 400 px tile, so the projection uses that size."""
    shown, hidden, meta = rendered(gallery, "@notebook")
    mask = changed(shown, hidden)
    assert_robot_where_expected(mask, project(meta["points"], meta["camera"], size=(TILE[0], 420)),
                                f"notebook ({meta['png']})")
