"""Inertias implausible for a link's mass and size: placeholder values that pass the validity check but dominate
the dynamics.

A rigid body all of whose points lie within a distance R of its centre of mass has, about every axis through that
centre, a moment of inertia of at most :math:`m R^2` (each point's distance to the axis is at most its distance
to the centre), so its largest radius of gyration :math:`k = \\sqrt{I_{max}/m}` is at most R. A link is reported
when :math:`k` exceeds :data:`FACTOR` times its extent R, taken from

* its geometry, where the description gives it: the bounding boxes of the link's visual and collision shapes
  (meshes as loaded), R = the largest distance from the centre of mass to a box corner;
* else a stated rule: R = the largest of the distance from the centre of mass to the link's joints (its own
  origin and the origins of the joints it carries) and the radius of a sphere of the link's mass at
  :data:`DENSITY_FLOOR` (100 kg/m^3, lighter than any structural material: a link no denser than that is
  larger than any placeholder inertia suggests).

Stand-ins the viewer derives from the inertia itself (inertia boxes, markers) are not geometry here.

Each reported link comes with its share of the robot's effective mass: for a planar or floating root, the mass
:math:`m_{eff} = 1/(J M_r^{-1} J^T)` the base presents along its x axis, its y axis and about its yaw axis (those
it can move along), J the root velocity's row of S, at the neutral configuration; the share is
:math:`1 - m_{eff}'/m_{eff}`, :math:`m_{eff}'` with the link's rotational inertia (about its centre of mass)
removed, and the largest of the three is reported. For a fixed root, the largest share over the diagonal entries of
:math:`M_r` (the inertia each independent velocity meets).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

FACTOR = 2.0
"""How far beyond its extent a link's radius of gyration may be before it is reported (the bound itself is 1)."""
DENSITY_FLOOR = 100.0
"""Density [kg/m^3] of the rule that sizes a link without geometry (see the module text)."""


@dataclass
class ImplausibleInertia:
    """A link whose inertia is implausible for its mass and size.

    Attributes:
        link: The link's name.
        mass: Its mass [kg].
        inertia: Its largest principal moment about its centre of mass [kg m^2].
        gyration: Its largest radius of gyration :math:`\\sqrt{I_{max}/m}` [m].
        extent: The extent it is compared with [m].
        extent_from: ``"geometry"`` or ``"rule"`` (see :mod:`robotdyn.description.inertia_check`).
        share: Its share of the effective mass (0-1), ``None`` where it cannot be computed.
        effective_mass: The effective mass with the link as described [kg, or kg m^2 for a fixed root's rotary
            coordinates], ``None`` as ``share``.
        effective_without: The same with the link's rotational inertia removed.
        along: What the effective mass is measured along (``"base x"``, ``"base y"``, a velocity's name).
    """

    link: str
    mass: float
    inertia: float
    gyration: float
    extent: float
    extent_from: str
    share: float | None = None
    effective_mass: float | None = None
    effective_without: float | None = None
    along: str = ""

    def text(self) -> str:
        """The finding in words, as the load warning prints it.

        Returns:
            One line: the link, its mass [kg] and inertia [kg m^2], the radius of gyration [m] against its extent [m]
            and, where known, its share of the effective mass.
        """
        what = "its geometry" if self.extent_from == "geometry" else "the size rule (no geometry)"
        out = (f"{self.link} ({self.mass:.4g} kg, I = {self.inertia:.4g} kg m^2): radius of gyration "
               f"{self.gyration:.3g} m, {self.gyration / self.extent:.3g} times its extent {self.extent:.3g} m "
               f"from {what}")
        if self.share is not None:
            out += (f", {100 * self.share:.0f} % of the effective mass along {self.along} "
                    f"({self.effective_mass:.4g}; {self.effective_without:.4g} without it)")
        return out


def _inertials(urdf: str) -> dict[str, tuple[float, np.ndarray, np.ndarray]]:
    """Link name -> (mass, centre of mass in the link frame, inertia about it in link axes) from the URDF."""
    out = {}
    for link in ET.fromstring(urdf).iter("link"):
        el = link.find("inertial")
        if el is None or el.find("mass") is None or el.find("inertia") is None:
            continue
        m = float(el.find("mass").get("value", "0"))
        a = el.find("inertia")
        g = {k: float(a.get(k, "0")) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
        inertia = np.array([[g["ixx"], g["ixy"], g["ixz"]], [g["ixy"], g["iyy"], g["iyz"]],
                            [g["ixz"], g["iyz"], g["izz"]]])
        origin = el.find("origin")
        xyz = np.fromstring(origin.get("xyz", "0 0 0"), sep=" ") if origin is not None else np.zeros(3)
        rpy = np.fromstring(origin.get("rpy", "0 0 0"), sep=" ") if origin is not None else np.zeros(3)
        R = pin.rpy.rpyToMatrix(*rpy) if rpy.size == 3 else np.eye(3)
        out[link.get("name")] = (m, xyz if xyz.size == 3 else np.zeros(3), R @ inertia @ R.T)
    return out


def _box(geometry: ET.Element) -> np.ndarray | None:
    """Half sides of the bounding box of a URDF primitive (box, cylinder along z, sphere) [m], None otherwise."""
    for kind in ("box", "cylinder", "sphere"):
        el = geometry.find(kind)
        if el is None:
            continue
        try:
            if kind == "box":
                half = 0.5 * np.fromstring(el.get("size", ""), sep=" ")
            else:
                r = float(el.get("radius", "nan"))
                half = np.array([r, r, 0.5 * float(el.get("length", "nan")) if kind == "cylinder" else r])
        except ValueError:
            return None
        return half if half.size == 3 and np.all(np.isfinite(half)) else None
    return None


def _primitive_corners(urdf: str) -> dict[str, list[np.ndarray]]:
    """Link name -> the corners of the bounding boxes of its visual and collision primitives, in the link frame."""
    out: dict[str, list[np.ndarray]] = {}
    for link in ET.fromstring(urdf).iter("link"):
        for shape in [*link.iter("visual"), *link.iter("collision")]:
            geometry = shape.find("geometry")
            half = _box(geometry) if geometry is not None else None
            if half is None:
                continue
            origin = shape.find("origin")
            xyz = np.fromstring(origin.get("xyz", "0 0 0"), sep=" ") if origin is not None else np.zeros(3)
            rpy = np.fromstring(origin.get("rpy", "0 0 0"), sep=" ") if origin is not None else np.zeros(3)
            if xyz.size != 3 or rpy.size != 3:
                continue
            R = pin.rpy.rpyToMatrix(*rpy)
            for c in np.array(np.meshgrid(*zip(-half, half))).reshape(3, -1).T:
                out.setdefault(link.get("name"), []).append(xyz + R @ c)
    return out


def _extent(model: pin.Model, shapes: dict, children: dict, standins: dict, name: str, fid: int,
            com_joint: np.ndarray, mass: float) -> tuple[float, str]:
    """The link's extent from its centre of mass [m] and where it came from (geometry or the rule); ``shapes``:
    frame name -> the visual model's geometry objects on it; ``children``: frame id -> the positions of the joints
    it carries (in its parent joint's frame)."""
    place = model.frames[fid].placement
    corners = [place.act(c) for c in shapes.get(("primitives", name), ())]
    if standins.get(name) not in ("inertia box", "marker"):
        for go in shapes.get(name, ()):
            try:
                go.geometry.computeLocalAABB()
                lo, hi = np.array(go.geometry.aabb_local.min_), np.array(go.geometry.aabb_local.max_)
            except (AttributeError, RuntimeError):
                continue
            if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
                continue
            for c in np.array(np.meshgrid(*zip(lo, hi))).reshape(3, -1).T:
                corners.append(go.placement.act(c))
    if corners:
        return float(max(np.linalg.norm(c - com_joint) for c in corners)), "geometry"
    points = [model.frames[fid].placement.translation, *children.get(fid, ())]
    kinematic = max(float(np.linalg.norm(p - com_joint)) for p in points)
    return max(kinematic, (3.0 * mass / (4.0 * np.pi * DENSITY_FLOOR)) ** (1.0 / 3.0)), "rule"


def implausible_inertias(robot) -> list[ImplausibleInertia]:
    """The links of ``robot`` whose largest radius of gyration exceeds :data:`FACTOR` times their extent, with
    their share of the effective mass (see the module text).

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.

    Returns:
        One :class:`ImplausibleInertia` per such link, in description order (empty: every inertia plausible).
    """
    desc = robot.description
    model = desc.model
    standins = getattr(desc.visual_report, "standins", {}) or {}
    shapes: dict[str, list] = {}
    for go in (desc.visual.geometryObjects if desc.visual is not None else ()):
        shapes.setdefault(model.frames[go.parentFrame].name, []).append(go)
    for name, corners in _primitive_corners(desc.urdf).items():
        shapes[("primitives", name)] = corners
    children: dict[int, list] = {}
    for f in model.frames:
        if f.type in (pin.FrameType.JOINT, pin.FrameType.FIXED_JOINT):
            children.setdefault(f.parentFrame, []).append(f.placement.translation)
    found = []
    for name, (mass, com, inertia) in _inertials(desc.urdf).items():
        if mass <= 0 or not model.existFrame(name):
            continue
        fid = model.getFrameId(name)
        eig = np.linalg.eigvalsh(0.5 * (inertia + inertia.T))
        if eig[-1] <= 0:
            continue
        k = float(np.sqrt(eig[-1] / mass))
        place = model.frames[fid].placement
        extent, source = _extent(model, shapes, children, standins, name, fid, place.act(com), mass)
        if k > FACTOR * extent:
            found.append(ImplausibleInertia(name, mass, float(eig[-1]), k, extent, source))
    if found:
        _shares(robot, found)
    return found


def _effective(robot, q: np.ndarray, S: np.ndarray, model: pin.Model) -> dict[str, float]:
    """The base's effective mass along x, y and about its yaw axis (those it can move along) [kg, kg m^2]."""
    M = S.T @ pin.crba(model, model.createData(), q) @ S
    M = 0.5 * (M + M.T)
    out = {}
    names = robot.description.joint_names
    for axis, label in (("x", "base x"), ("y", "base y"), ("psi", "base yaw"), ("yaw", "base yaw")):
        if axis not in names:
            continue
        J = S[names.index(axis)]
        if np.abs(J).max() > 1e-12:
            try:
                out[label] = float(1.0 / (J @ np.linalg.solve(M, J)))
            except np.linalg.LinAlgError:
                continue
    return out


def _shares(robot, found: list[ImplausibleInertia]) -> None:
    """Fill in each link's share of the effective mass (leaves ``None`` where it cannot be computed)."""
    model = robot.model
    try:
        q = robot.neutral()
        S = robot.reduced(q, np.zeros(robot.mobility)).S
    except Exception:  # noqa: BLE001 - a robot whose neutral configuration is singular: no share, still a warning
        return
    inertials = _inertials(robot.description.urdf)
    base = _effective(robot, q, S, model) if robot.spec.root in ("planar", "floating") else {}
    M_r = S.T @ pin.crba(model, model.createData(), q) @ S
    for item in found:
        mass, com, inertia = inertials[item.link]
        frame = model.frames[model.getFrameId(item.link)]
        stripped = model.copy()
        rotational = frame.placement.act(pin.Inertia(0.0, com, inertia))
        stripped.inertias[frame.parentJoint] = stripped.inertias[frame.parentJoint] - rotational
        if base:
            without = _effective(robot, q, S, stripped)
            along = max((a for a in base if a in without), key=lambda a: 1.0 - without[a] / base[a], default=None)
            if along is not None:
                item.effective_mass, item.effective_without, item.along = base[along], without[along], along
                item.share = 1.0 - without[along] / base[along]
            continue
        M_w = S.T @ pin.crba(stripped, stripped.createData(), q) @ S
        d, dw = np.diag(M_r), np.diag(M_w)
        with np.errstate(divide="ignore", invalid="ignore"):
            shares = np.where(d > 0, 1.0 - dw / d, 0.0)
        i = int(np.argmax(shares))
        item.share, item.effective_mass, item.effective_without = float(shares[i]), float(d[i]), float(dw[i])
        item.along = robot.velocity_names[i]


SMALL_SHARE = 0.01
"""Links whose share of the effective mass is below this are named in one list (their details are in the data)."""


def message(found: list[ImplausibleInertia]) -> str:
    """One line naming every link of :func:`implausible_inertias`: those that matter (share of the effective mass
    of at least :data:`SMALL_SHARE`, or unknown) with their numbers, the others by name.

    Args:
        found: The links :func:`implausible_inertias` found (an empty list gives an empty line).

    Returns:
        The warning's text, one line.
    """
    big = [f for f in found if f.share is None or f.share >= SMALL_SHARE]
    small = [f.link for f in found if f not in big]
    text = "; ".join(f.text() for f in big)
    if small:
        text += ("; " if text else "") + (f"{len(small)} link(s) with a share of the effective mass below "
                                           f"{100 * SMALL_SHARE:g} % each: {', '.join(small)}")
    return (f"inertia implausible for the link's mass and size (radius of gyration more than {FACTOR:g} times "
            f"the link's extent; placeholder values?): {text}")
