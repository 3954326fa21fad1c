"""Independent forward kinematics of a robot's visual geometry, with yourdfpy (not Pinocchio).

Used to check what the viewer draws: every visual of link L sits at T_world_L(q) @ T_visual (the URDF's
``<visual><origin>``), and its local bounding box follows from the URDF primitive's dimensions.
"""

from __future__ import annotations

import io

import numpy as np
import yourdfpy


class UrdfVisuals:
    """yourdfpy model of a robot's (naturalised) URDF; ``q`` maps to joint values by the robot's joint names."""

    def __init__(self, robot) -> None:
        self.robot = robot
        self.urdf = yourdfpy.URDF.load(io.StringIO(robot.description.urdf), build_scene_graph=True,
                                       load_meshes=False, build_collision_scene_graph=False)
        self.base = self.urdf.base_link

    def configure(self, q) -> None:
        cfg = {name: 0.0 for name in self.urdf.actuated_joint_names}
        for name, value in getattr(self.robot.spec, "locked", {}).items():
            cfg[name] = float(value)
        for name, value in zip(self.robot.description.joint_names, q):
            cfg[name] = float(value)
        self.urdf.update_cfg(cfg)

    def link(self, name: str) -> np.ndarray:
        """4x4 world transform of a link at the configured q."""
        return np.asarray(self.urdf.get_transform(frame_to=name, frame_from=self.base), dtype=float)

    def visuals(self, q) -> dict[tuple[str, int], tuple[np.ndarray, np.ndarray]]:
        """``{(link, k): (4x4 world transform of its k-th visual, half extents of its local box)}`` at q."""
        self.configure(q)
        out = {}
        for link in self.urdf.robot.links:
            if not link.visuals:
                continue
            T = self.link(link.name)
            for k, vis in enumerate(link.visuals):
                origin = np.eye(4) if vis.origin is None else np.asarray(vis.origin, dtype=float)
                out[(link.name, k)] = (T @ origin, _half_extents(vis.geometry))
        return out

    def points(self, q) -> np.ndarray:
        """Corners of every visual's local bounding box, world frame (m), at q."""
        signs = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)], dtype=float)
        pts = [(T[:3, :3] @ (signs * half).T).T + T[:3, 3] for T, half in self.visuals(q).values()]
        return np.vstack(pts)


def _half_extents(geometry) -> np.ndarray:
    if geometry.box is not None:
        return 0.5 * np.asarray(geometry.box.size, dtype=float)
    if geometry.cylinder is not None:
        r, h = geometry.cylinder.radius, geometry.cylinder.length
        return np.array([r, r, 0.5 * h])
    if geometry.sphere is not None:
        return np.full(3, geometry.sphere.radius)
    return np.full(3, 0.05)  # meshes: not loaded here; a small box around the origin
