"""A 3-D viewer for any registered robot, built on meshcat: configurations, animations, standalone HTML.

:class:`Viewer` draws a :class:`~robotdyn.robot.Robot`'s visual geometry (the ``<visual>`` elements of its
URDF, placed by Pinocchio's forward kinematics), the terrain (a ground plane for a horizontal
:class:`~robotdyn.constraints.terrain.FlatTerrain`, otherwise the surface z = f(x, y) sampled into a triangle mesh), the wheel
contact points with their contact frames (t1 rolling direction, t2 lateral, n normal; red/green/blue) and the link
frames. Every layer is a node of meshcat's scene tree, so it can be switched on and off from Python
(:meth:`Viewer.show`) and from the browser (the "Open Controls" menu, folder Scene/meshcat/robotdyn).

Scenes are recorded in-process, so :meth:`Viewer.static_html` (a standalone page with meshcat's JavaScript
inlined: it opens offline, e.g. attached to a report; shared meshes stored once, compressed:
:mod:`robotdyn.interfaces.scene_page`) needs no server. ``live=True`` additionally starts meshcat's
local server (``Viewer.url``) and mirrors every command to it, for interactive use.

Animations use meshcat's (three.js) keyframe animations, so they play in the browser in real time: a trajectory
sample at time t [s] becomes a key at frame ``(t - t0) * fps``, which three.js plays at ``frame / fps`` seconds.
An export opened as ``page.html#t=1.5`` shows the animation paused at 1.5 s (the controls menu resumes it).

World frame: z up, metres. The camera looks at the world origin (meshcat 0.3.2 cannot move the orbit target).

Example (in a notebook)::

    from robotdyn.robot import Robot
    from robotdyn.robots import module
    from robotdyn.interfaces.viewer import Viewer

    robot = Robot(module("quasimoro").SPEC)
    viewer = Viewer(robot)
    viewer.display(robot.neutral())
    viewer            # renders inline (static export in an iframe)
"""

from __future__ import annotations

import html
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import InputError, RobotDynError, RobotDynWarning
from ..output import atomic_output
from .scene_page import _meshcat, static_page

_ROOT = "robotdyn"
LAYERS = ("robot", "terrain", "contacts", "frames")
"""Names of the scene layers :meth:`Viewer.show` toggles (nodes ``/meshcat/robotdyn/<layer>``)."""

_CONTACT_COLOR = 0xD62728
_TERRAIN_LOW = np.array([0.35, 0.55, 0.30])
_TERRAIN_HIGH = np.array([0.80, 0.72, 0.50])
_GROUND = np.array([0.78, 0.78, 0.74])


class _SceneRecorder:
    """Stands in for meshcat's server window: keeps the scene tree (as meshcat's server does) and forwards every
    command to a live server window, if any."""

    def __init__(self, live=None) -> None:
        mc = _meshcat()
        self._tree_mod = mc.servers.tree
        self.tree = self._tree_mod.SceneTree()
        self.live = live
        self.web_url = getattr(live, "web_url", None)
        self.count = 0

    def send(self, command) -> None:
        import umsgpack

        data = command.lower()
        packed = umsgpack.packb(data)
        kind = data["type"]
        path = [p for p in data.get("path", "").split("/") if p]
        tree = self._tree_mod
        if kind == "set_transform":
            tree.find_node(self.tree, path).transform = packed
        elif kind == "set_object":
            node = tree.find_node(self.tree, path)
            node.object = packed
            node.properties = []
        elif kind == "set_property":
            tree.find_node(self.tree, path).properties.append(packed)
        elif kind == "set_animation":
            tree.find_node(self.tree, path).animation = packed
        elif kind == "delete":
            if path:
                parent = tree.find_node(self.tree, path[:-1])
                parent.pop(path[-1], None)
            else:
                self.tree = tree.SceneTree()
        self.count += 1
        if self.live is not None:
            self.live.send(command)

    def commands(self) -> list[bytes]:
        """The scene as msgpack commands: objects, properties, transforms, then animations last."""
        out, animations = [], []
        for node in self._tree_mod.walk(self.tree):
            if node.object is not None:
                out.append(node.object)
            out.extend(node.properties)
            if node.transform is not None:
                out.append(node.transform)
            if node.animation is not None:
                animations.append(node.animation)
        return out + animations

    def get_scene(self) -> str:
        return static_page(self.commands())

    def close(self) -> None:
        """Close the socket to the live server (dropping unsent messages, so that nothing waits for them at
        exit) and stop the server."""
        if self.live is None:
            return
        sock = getattr(self.live, "zmq_socket", None)
        if sock is not None and not sock.closed:
            sock.close(linger=0)
        if getattr(self.live, "server_proc", None) is not None:
            proc = self.live.server_proc
            proc.kill()
            proc.wait()
            self.live.server_proc = None


@dataclass
class _Marker:
    """A contact marker: the constraint whose contact point it shows and its node path."""

    constraint: object
    path: str


class Viewer:
    """Meshcat viewer of a robot.

    Args:
        robot: The :class:`~robotdyn.robot.Robot` to draw (its visual geometry, terrain and wheels).
        live: Also start meshcat's local web server (see :attr:`url`) and mirror the scene to it.
        contacts: Show the wheel contact points and contact frames initially.
        frames: Show the link frames initially.
        extent: Half-width [m] of the terrain patch drawn around the robot (default: from the robot's size).

    Attributes:
        robot: The robot.
        vis: The underlying ``meshcat.Visualizer`` (for adding your own objects; they are exported too).
        q: The configuration last displayed (natural coordinates).
        fps: Keyframe rate of the last animation [1/s].
        url: The live viewer's address (``None`` without ``live``).
        tile: Edge [m] of the ground's checker tiles (about 0.4 times the robot's size, rounded to 1, 2 or 5).
        camera_position: Where :meth:`set_camera` put the camera (world frame, m); it looks at the origin with
            meshcat's default perspective (75 degrees vertical field of view, z up on screen).

    Example:
        >>> import robotdyn
        >>> from robotdyn.interfaces.viewer import Viewer
        >>> robot = robotdyn.load("quasimoro")
        >>> viewer = Viewer(robot)             # live=True also serves it at viewer.url
        >>> viewer.display(robot.neutral())
        >>> viewer.save("quasimoro.html").name  # a page that works offline
        'quasimoro.html'
        >>> viewer.close()
    """

    def __init__(self, robot, live: bool = False, contacts: bool = True, frames: bool = False,
                 extent: float | None = None) -> None:
        if extent is not None and not (np.isfinite(extent) and extent >= 0):
            raise InputError(f"extent = {extent}; expected a terrain margin >= 0 in m")
        mc = _meshcat()
        from pinocchio.visualize import MeshcatVisualizer  # lazy: imports trimesh (~0.65 s)

        report = getattr(robot.description, "visual_report", None)
        for message in report.warnings if report is not None else ():  # meshes not drawn: said where they matter
            warnings.warn(message, RobotDynWarning, stacklevel=2)      # (here and in info, not on every load)
        self.robot = robot
        self.model = robot.model
        self.data = self.model.createData()
        self.visual = robot.description.visual
        self.visual_data = pin.GeometryData(self.visual)
        live_window = None
        if live:
            try:
                import contextlib
                import io

                with contextlib.redirect_stdout(io.StringIO()):  # meshcat prints the URL; we report it ourselves
                    live_window = mc.visualizer.ViewerWindow(zmq_url=None, start_server=True, server_args=[])
            except Exception as exc:  # port or process problems
                raise RobotDynError(f"cannot start the meshcat server: {' '.join(str(exc).split())}") from None
        self._window = _SceneRecorder(live_window)
        self.url = self._window.web_url
        self.vis = mc.Visualizer(window=self._window)
        self._pin = MeshcatVisualizer(self.model, None, self.visual, data=self.data, visual_data=self.visual_data)
        self._pin.initViewer(viewer=self.vis)
        self._pin.loadViewerModel(rootNodeName=f"{_ROOT}/robot")
        self._visual_prefix = f"{_ROOT}/robot/visuals"
        self._markers = [
            _Marker(c, f"{_ROOT}/contacts/{getattr(c, 'name', None) or c.frame}")
            for c in robot.constraints if hasattr(c, "contact")
        ]
        self._frame_ids = [
            i for i, f in enumerate(self.model.frames)
            if f.type == pin.FrameType.BODY and not f.name.startswith("robotdyn_")
        ]
        self._extent = extent
        self.fps = 0.0
        self.q = robot.neutral()
        self._size = self._robot_size(self.q)
        self.tile = _nice(0.4 * self._size)
        self._draw_markers()
        self._draw_terrain(self._terrain_box(self.q[None, :]))
        self.show("contacts", contacts)
        self.show("frames", frames)
        self.display(self.q)
        self.set_camera()

    # ---------------------------------------------------------------------------------------------- scene
    def __repr__(self) -> str:
        return f"Viewer({self.robot.spec.name!r}, live={self.url is not None}, commands={self._window.count})"

    def _robot_size(self, q: np.ndarray) -> float:
        """Radius [m] of a sphere about the robot's geometric centre containing its visual geometry."""
        pts = self._geometry_points(q)
        if len(pts) == 0:
            return 0.5
        centre = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
        return float(max(np.max(np.linalg.norm(pts - centre, axis=1)), 0.05))

    def _geometry_points(self, q: np.ndarray) -> np.ndarray:
        """Corners of each visual geometry's local bounding box, in the world frame at q (m)."""
        pin.forwardKinematics(self.model, self.data, q)
        pin.updateGeometryPlacements(self.model, self.data, self.visual, self.visual_data)
        pts = []
        signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)
        for i, g in enumerate(self.visual.geometryObjects):
            half = _half_extents(g)
            M = self.visual_data.oMg[i]
            pts.append((M.rotation @ (signs * half).T).T + M.translation)
        pts.append(np.array([self.data.oMi[j].translation for j in range(1, self.model.njoints)]))
        return np.vstack(pts) if pts else np.zeros((0, 3))

    def placements(self, q) -> dict[str, np.ndarray]:
        """The 4x4 world transforms of every scene node the configuration q moves (visuals, contacts, frames).

        Args:
            q: Natural coordinates (robot.coordinates order; m, rad).

        Returns:
            ``{node path: 4x4 homogeneous matrix}`` (paths relative to the viewer root ``/meshcat``).
        """
        from pinocchio.visualize.meshcat_visualizer import applyScalingOnHomegeneousTransform

        from ..constraints.constraint import KinematicState

        q = self._check_q(q)
        out: dict[str, np.ndarray] = {}
        pin.forwardKinematics(self.model, self.data, q)
        pin.updateGeometryPlacements(self.model, self.data, self.visual, self.visual_data)
        pin.updateFramePlacements(self.model, self.data)
        for i, g in enumerate(self.visual.geometryObjects):
            T = applyScalingOnHomegeneousTransform(self.visual_data.oMg[i].homogeneous, g.meshScale)
            out[f"{self._visual_prefix}/{g.name}"] = T
        for fid in self._frame_ids:
            out[f"{_ROOT}/frames/{self.model.frames[fid].name}"] = self.data.oMf[fid].homogeneous
        if self._markers:
            kin = KinematicState(self.model, self.data, q, np.zeros(self.model.nv))
            for m in self._markers:
                c = m.constraint.contact(kin)
                T = np.eye(4)
                T[:3, :3] = c["E"]
                T[:3, 3] = c["p"]
                out[m.path] = T
        return out

    def _check_q(self, q) -> np.ndarray:
        q = np.asarray(q, dtype=float)
        if q.shape != (self.model.nq,) or not np.all(np.isfinite(q)):
            raise InputError(
                f"q has shape {q.shape}; expected {self.model.nq} finite coordinates ({', '.join(self.robot.coordinates)})"
            )
        return q

    def _draw_markers(self) -> None:
        mc = _meshcat()
        g = mc.geometry
        for m in self._markers:
            R = float(getattr(m.constraint, "radius", 0.1)) or 0.1
            node = self.vis[m.path]
            node["point"].set_object(g.Sphere(0.08 * R), g.MeshLambertMaterial(color=_CONTACT_COLOR))
            node["frame"].set_object(_triad(0.6 * R))
        scale = 0.25 * self._size
        for fid in self._frame_ids:
            self.vis[f"{_ROOT}/frames/{self.model.frames[fid].name}"].set_object(_triad(scale))

    def _terrain_box(self, Q: np.ndarray) -> tuple[float, float, float, float]:
        """(xmin, xmax, ymin, ymax) of the terrain patch covering the robot at all configurations Q."""
        lo, hi = np.full(2, np.inf), np.full(2, -np.inf)
        for q in Q[:: max(1, len(Q) // 50)].tolist() + [Q[-1].tolist()]:
            pts = self._geometry_points(np.asarray(q))[:, :2]
            lo, hi = np.minimum(lo, pts.min(axis=0)), np.maximum(hi, pts.max(axis=0))
        margin = self._extent if self._extent is not None else max(1.0, 2.0 * self._size)
        return lo[0] - margin, hi[0] + margin, lo[1] - margin, hi[1] + margin

    def _draw_terrain(self, box: tuple[float, float, float, float]) -> None:
        """The ground over ``box`` as a triangle mesh with a checker pattern of square tiles (edge
        :attr:`tile` m, so motion is visible): a horizontal plane for :class:`~robotdyn.constraints.terrain.FlatTerrain`,
        otherwise the surface z = f(x, y) sampled on a grid (cells of at most 6 cm, at most 160 x 160), coloured
        from low (green) to high (sand). Meshcat's own grid (z = 0) is hidden: the ground replaces it."""
        from ..constraints.terrain import FlatTerrain

        mc = _meshcat()
        g = mc.geometry
        terrain = self.robot.terrain
        tile = self.tile
        x0, x1, y0, y1 = (np.floor(box[0] / tile) * tile, np.ceil(box[1] / tile) * tile,
                          np.floor(box[2] / tile) * tile, np.ceil(box[3] / tile) * tile)
        flat = isinstance(terrain, FlatTerrain)
        if flat:
            nx, ny = int(round((x1 - x0) / tile)), int(round((y1 - y0) / tile))
        else:
            nx = int(np.clip(np.ceil((x1 - x0) / min(tile, 0.06)), 20, 160))
            ny = int(np.clip(np.ceil((y1 - y0) / min(tile, 0.06)), 20, 160))
        xs, ys = np.linspace(x0, x1, nx + 1), np.linspace(y0, y1, ny + 1)
        if flat:
            Z = np.full((nx + 1, ny + 1), terrain.h)
        else:
            Z = np.array([[terrain.height(x, y) for y in ys] for x in xs], dtype=float)
        if not np.all(np.isfinite(Z)):
            raise InputError(f"terrain {terrain!r} has non-finite heights in x [{x0:g}, {x1:g}], y [{y0:g}, {y1:g}] m")
        i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
        i, j = i.ravel(), j.ravel()
        if flat:
            # few large cells: each has its own four vertices, so that it has a flat checker colour
            corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]
            verts = np.stack([np.column_stack([xs[a], ys[b], Z[a, b]]) for a, b in corners], axis=1).reshape(-1, 3)
            k = 4 * np.arange(i.size)
            parity = (np.floor(0.5 * (xs[i] + xs[i + 1]) / tile) + np.floor(0.5 * (ys[j] + ys[j + 1]) / tile)) % 2
            colors = np.repeat(_GROUND * (1.0 - 0.12 * parity[:, None]), 4, axis=0)
            faces = np.concatenate([np.column_stack([k, k + 1, k + 2]), np.column_stack([k, k + 2, k + 3])])
        else:
            # many small cells: shared vertices (a third of the size), colour by height and checker tile
            X, Y = np.meshgrid(xs, ys, indexing="ij")
            verts = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
            k = i * (ny + 1) + j
            faces = np.concatenate([np.column_stack([k, k + ny + 1, k + ny + 2]), np.column_stack([k, k + ny + 2, k + 1])])
            span = np.ptp(Z)
            h = (Z.ravel() - Z.min()) / span if span > 0 else np.zeros(Z.size)
            parity = (np.floor((X.ravel() + 1e-9) / tile) + np.floor((Y.ravel() + 1e-9) / tile)) % 2
            colors = (_TERRAIN_LOW + h[:, None] * (_TERRAIN_HIGH - _TERRAIN_LOW)) * (1.0 - 0.12 * parity[:, None])
        self.vis["/Grid"].set_property("visible", False)
        self.vis["/Axes"].set_property("scale", [self._size] * 3)  # meshcat world axes: 0.5 m -> half the robot size
        self.vis[f"{_ROOT}/terrain"].set_object(
            g.TriangularMeshGeometry(verts, faces, color=colors), g.MeshLambertMaterial(vertexColors=True)
        )

    # -------------------------------------------------------------------------------------------- public
    def show(self, layer: str, visible: bool = True) -> None:
        """Show or hide a layer: ``robot``, ``terrain``, ``contacts`` or ``frames``.

        Args:
            layer: ``robot``, ``terrain``, ``contacts`` or ``frames``.
            visible: Show (True) or hide (False).
        """
        if layer not in LAYERS:
            raise InputError(f"unknown layer {layer!r}; expected one of {', '.join(LAYERS)}")
        self.vis[f"{_ROOT}/{layer}"].set_property("visible", bool(visible))

    def display(self, q) -> None:
        """Draw the robot at configuration q (natural coordinates in robot.coordinates order; m, rad).

        The contact markers sit at each wheel's contact point with the terrain, oriented along its contact frame.

        Args:
            q: Natural coordinates (n,) [m, rad].
        """
        q = self._check_q(q)
        self.q = q.copy()
        self._reach = float(np.linalg.norm(self._geometry_points(q).mean(axis=0)))
        self._pin.display(q)
        for path, T in self.placements(q).items():
            if not path.startswith(self._visual_prefix):
                self.vis[path].set_transform(T)

    def set_camera(self, direction=(1.4, 1.0, 0.8), distance: float | None = None) -> None:
        """Place the camera along ``direction`` (world frame) from the world origin, at ``distance`` [m]
        (default: 2.6 times the robot's size plus the largest distance of the robot's centre from the origin in
        the configuration displayed or the animation, so the robot stays in view). It looks at the origin.
        :meth:`display` does not move the camera (call this again after it); :meth:`animate` re-frames it unless
        told not to.

        Args:
            direction: Direction (3,) from the origin to the camera, world frame (normalised here).
            distance: Distance [m] from the origin (default ``None``: from the robot's size).
        """
        d = np.asarray(direction, dtype=float)
        if d.shape != (3,) or not np.all(np.isfinite(d)) or np.linalg.norm(d) == 0:
            raise InputError(f"camera direction {np.asarray(direction).tolist()}; expected a non-zero 3-vector")
        if distance is None:
            distance = 2.6 * self._size + self._reach
        p = d / np.linalg.norm(d) * float(distance)
        self.camera_position = p
        # meshcat's camera node is rotated (three.js y up): world (x, y, z) is (x, z, -y) there
        self.vis["/Cameras/default/rotated/<object>"].set_property("position", [p[0], p[2], -p[1]])

    def animate(self, trajectory, fps: float = 30.0, play: bool = True, repetitions: int = 1,
                reframe: bool = True, max_keys: int = 1200) -> None:
        """Animate a trajectory in real time (meshcat keyframe animation; the controls menu has play/pause, a
        time scrubber and a time scale).

        Args:
            trajectory: A :class:`~robotdyn.simulation.trajectory.Trajectory`, or a pair ``(t, q)`` of times (N,) [s]
                and natural coordinates (N, nq).
            fps: Keyframes per second; q is linearly interpolated between the trajectory's samples at the
                times t0 + k / fps (and the last sample time).
            play: Start playing when the page opens.
            repetitions: How many times it plays.
            reframe: Move the camera (:meth:`set_camera`) so the whole motion stays in view.
            max_keys: At most this many keyframes (long runs get a lower ``fps``: 1200 keys keep a 90 s run at
                13 fps and a 6-wheel robot's export near 10 MB). Rotations are interpolated along the shortest
                arc, so a body turning more than half a turn between keys needs a higher rate.
        """
        mc = _meshcat()
        try:
            t, Q = (trajectory.t, trajectory.q) if hasattr(trajectory, "q") else trajectory
            t = np.asarray(t, dtype=float)
            Q = np.asarray(Q, dtype=float)
        except (TypeError, ValueError):
            raise InputError("trajectory: expected a Trajectory or a pair (t, q) of numeric arrays") from None
        if t.ndim != 1 or Q.shape != (len(t), self.model.nq) or len(t) < 2:
            raise InputError(f"trajectory: t {t.shape}, q {Q.shape}; expected N >= 2 times and an N x {self.model.nq} q")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(Q)) and np.all(np.diff(t) > 0)):
            raise InputError("trajectory: expected finite q and strictly increasing times")
        if not (np.isfinite(fps) and fps > 0):
            raise InputError(f"fps = {fps}; expected a positive number of frames per second")
        if int(max_keys) < 2:
            raise InputError(f"max_keys = {max_keys}; expected at least 2 keyframes")
        fps = min(float(fps), (int(max_keys) - 1) / (t[-1] - t[0]))
        self.fps = fps
        times = self.key_times(t, fps)
        Qs = np.column_stack([np.interp(times, t, Q[:, j]) for j in range(Q.shape[1])])
        self._draw_terrain(self._terrain_box(Qs))
        anim = mc.animation.Animation(default_framerate=fps)
        for tk, qk in zip(times, Qs):
            with anim.at_frame(self.vis, (tk - t[0]) * fps) as frame:
                for path, T in self.placements(qk).items():
                    frame[path].set_transform(T)
        self.display(Qs[0])
        self._reach = max(float(np.linalg.norm(self._geometry_points(np.asarray(qk)).mean(axis=0)))
                          for qk in Qs[:: max(1, len(Qs) // 50)].tolist() + [Qs[-1]])
        if reframe:
            self.set_camera()
        self.vis.set_animation(anim, play=play, repetitions=repetitions)

    @staticmethod
    def key_times(t: np.ndarray, fps: float) -> np.ndarray:
        """Key times [s]: t0 + k / fps up to the last sample time, which is always included.

        Args:
            t: Sample times (N,) [s], increasing.
            fps: Keyframe rate [1/s].

        Returns:
            The key times (K,) [s], increasing.
        """
        n = int(np.floor((t[-1] - t[0]) * fps + 1e-9))
        times = t[0] + np.arange(n + 1) / fps
        if t[-1] - times[-1] > 1e-9:
            times = np.append(times, t[-1])
        return times

    def static_html(self) -> str:
        """The scene as a standalone HTML page (meshcat's JavaScript inlined; opens offline).

        Returns:
            The HTML page as one string.
        """
        return static_page(self._window.commands(), f"robotdyn: {self.robot.spec.name}")

    def save(self, path: str | Path) -> Path:
        """Write :meth:`static_html` to ``path`` and return the path.

        Args:
            path: The HTML file (written atomically).

        Returns:
            ``path`` as a :class:`~pathlib.Path`.
        """
        path = Path(path)
        try:
            with atomic_output(path, "HTML page") as tmp:
                tmp.write_text(self.static_html(), encoding="utf-8")
        except OSError as exc:
            raise InputError(f"cannot write {path}: {exc.strerror}") from None
        return path

    def iframe(self, height: int = 420) -> str:
        """HTML of an iframe holding the static export (for notebooks).

        Args:
            height: Height of the iframe [px].

        Returns:
            The HTML text.
        """
        doc = html.escape(self.static_html(), quote=True)
        return (f'<iframe srcdoc="{doc}" style="width: 100%; height: {int(height)}px; border: none" '
                'loading="lazy"></iframe>')

    def _repr_html_(self) -> str:
        return self.iframe()

    def close(self) -> None:
        """Stop the live server, if this viewer started one."""
        self._window.close()
        self.url = None


def _half_extents(g) -> np.ndarray:
    """Half sizes of a geometry object's local bounding box [m] (meshes: its vertices' box; else 0.05)."""
    geom = g.geometry
    try:
        import coal

        if isinstance(geom, coal.Cylinder):
            return np.array([geom.radius, geom.radius, geom.halfLength])
        if isinstance(geom, coal.Box):
            return np.asarray(geom.halfSide, float)
        if isinstance(geom, coal.Sphere):
            return np.full(3, geom.radius)
        if isinstance(geom, coal.Capsule):
            return np.array([geom.radius, geom.radius, geom.halfLength + geom.radius])
        geom.computeLocalAABB()
        box = geom.aabb_local
        return 0.5 * (np.asarray(box.max_) - np.asarray(box.min_)) + np.abs(0.5 * (np.asarray(box.max_) + np.asarray(box.min_)))
    except Exception:
        return np.full(3, 0.05)


def _triad(scale: float):
    """Three line segments along x (red), y (green), z (blue) of length ``scale`` [m]."""
    mc = _meshcat()
    g = mc.geometry
    pos = np.array([[0, 0, 0], [1, 0, 0], [0, 0, 0], [0, 1, 0], [0, 0, 0], [0, 0, 1]], np.float32) * scale
    col = np.array([[1, 0, 0], [1, 0, 0], [0, 0.7, 0], [0, 0.7, 0], [0, 0, 1], [0, 0, 1]], np.float32)
    return g.LineSegments(g.PointsGeometry(pos.T, color=col.T), g.LineBasicMaterial(vertexColors=True, linewidth=2))


# ------------------------------------------------------------------------------------------ headless browser
CHROMIUM_FLAGS = (
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--host-resolver-rules=MAP * ~NOTFOUND , EXCLUDE 127.0.0.1", "--enable-logging=stderr", "--v=0",
)
"""Headless Chromium flags: no sandbox or GPU (containers), and no network (every host name fails to resolve)."""


def find_chromium() -> str | None:
    """Path of a Chromium/Chrome executable (``$ROBOTDYN_CHROMIUM`` first), or None.

    Returns:
        The executable's path, or ``None`` if none is found.
    """
    import os
    import shutil

    env = os.environ.get("ROBOTDYN_CHROMIUM")
    if env:
        return env if shutil.which(env) else None
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        found = shutil.which(name)
        if found:
            return found
    return None


def screenshot(page: str | Path, png: str | Path, size: tuple[int, int] = (800, 600), budget_ms: int = 5000,
               chromium: str | None = None, timeout: float = 60.0) -> str:
    """Render an HTML file (e.g. :meth:`Viewer.save`'s export) in headless Chromium with its network switched off
    and save a PNG screenshot.

    Args:
        page: The HTML file.
        png: The screenshot to write.
        size: Window width and height [px].
        budget_ms: Virtual time the page gets before the screenshot [ms].
        chromium: The browser executable (default: :func:`find_chromium`).
        timeout: Wall-clock limit [s].

    Returns:
        Chromium's log (stderr), which includes the page's console messages.

    Raises:
        RobotDynError: No browser found, or it failed to write the screenshot.
    """
    import subprocess
    import tempfile

    exe = chromium or find_chromium()
    if exe is None:
        raise RobotDynError("headless Chromium not found; install Debian's chromium (make chromium) or set ROBOTDYN_CHROMIUM")
    page, png = Path(page).resolve(), Path(png).resolve()
    if not page.is_file():
        raise InputError(f"no such HTML file: {page}")
    png.unlink(missing_ok=True)
    with tempfile.TemporaryDirectory(prefix="robotdyn-chromium-") as profile:
        cmd = [exe, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", f"--window-size={size[0]},{size[1]}",
               f"--virtual-time-budget={int(budget_ms)}", f"--screenshot={png}", page.as_uri()]
        try:
            proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            raise RobotDynError(f"chromium took more than {timeout:g} s to render {page.name}") from None
    if not png.is_file():
        tail = " | ".join(proc.stderr.strip().splitlines()[-3:])
        raise RobotDynError(f"chromium (exit {proc.returncode}) wrote no screenshot of {page.name}: {tail}")
    return proc.stderr


def _nice(x: float) -> float:
    """The number of the form {1, 2, 5} x 10^k nearest to x (> 0) in ratio."""
    k = np.floor(np.log10(x))
    cands = np.array([1.0, 2.0, 5.0, 10.0]) * 10.0**k
    return float(cands[np.argmin(np.abs(np.log(cands / x)))])
