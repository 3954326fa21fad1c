"""Visual geometry of a description: every mesh resolved or replaced, so that a robot is never drawn empty.

Each ``<mesh filename=...>`` of a ``<visual>`` is resolved to an absolute file before Pinocchio sees it:
``package://NAME/rest`` through a :class:`~robotdyn.description.ros_packages.PackageIndex`, ``file://`` and absolute paths
as they are, a relative path against the description file's directory. A mesh is *not drawn* when

- it is missing: its package was not found, the file does not exist, or it cannot be loaded (an unreadable or
  unsupported file);
- it is outside the trees the description may read from (the policy of issue 15: a description is data, and must
  not make robotdyn read, and copy into a viewer page, files from elsewhere on disk): the description's own tree
  (the nearest directory above the description file that holds a ``package.xml``, else the description file's
  directory), the packages it uses (``$(find)`` and ``package://``, found by the index), and the directories
  declared to robotdyn (explicit packages and search directories). An absolute path or a ``..`` that leaves them is
  refused; declaring its directory (``package_dirs`` in a constraint file, ``--package DIR``) allows it.

A link whose visual is not drawn gets a stand-in: its ``<collision>`` geometry (primitives, or meshes that
resolve), else the box with the link's mass and central inertia (uniform density; sides
:math:`a_i = \\sqrt{6(\\operatorname{tr} I - 2 I_i)/m}` along the principal axes), else a 2 cm sphere. A
description without any visual gets the inertia boxes of all its links with mass. What was replaced is reported in
one line per kind (:attr:`VisualReport.warnings`), where meshes matter: the viewer warns with them, ``info`` lists
them (not every command that loads the robot).
"""

from __future__ import annotations

import copy
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from .ros_packages import PackageIndex, missing_name

MARKER_RADIUS = 0.02
"""Radius [m] of the sphere standing in for a massless link whose visual is not drawn."""
_STANDIN_RGBA = "0.62 0.62 0.66 1"


@dataclass
class VisualReport:
    """What happened to a description's visual meshes.

    Attributes:
        missing: ``(mesh as written, reason, link)`` of meshes not found or not loadable.
        refused: ``(mesh as written, resolved path, link)`` of meshes outside the allowed trees.
        standins: Link -> what stands in for its visual (``"collision"``, ``"inertia box"``, ``"marker"``).
        missing_packages: Packages named by meshes that were not found.
        roots: The trees meshes may be read from.
        no_visuals: The description has no visual at all (each link is drawn as its inertia box).
    """

    missing: list[tuple[str, str, str]] = field(default_factory=list)
    refused: list[tuple[str, str, str]] = field(default_factory=list)
    standins: dict[str, str] = field(default_factory=dict)
    missing_packages: list[str] = field(default_factory=list)
    roots: list[Path] = field(default_factory=list)
    no_visuals: bool = False

    def __repr__(self) -> str:
        return (f"VisualReport(missing={len(self.missing)}, refused={len(self.refused)}, "
                f"standins={len(self.standins)})")

    def _instead(self, link: str | None) -> str:
        kind = self.standins.get(link)
        return {"collision": f"{link} drawn as its collision geometry", "inertia box": f"{link} drawn as the box of "
                "its inertia", "marker": f"{link} drawn as a {2 * MARKER_RADIUS * 100:g} cm marker"}.get(
                    kind, f"{link} keeps its other visuals")

    @property
    def warnings(self) -> list[str]:
        """One line per kind of problem (empty when every mesh was drawn)."""
        out = []
        if self.missing:
            items = "; ".join(f"{_short(m)} ({why}: {self._instead(link)})" for m, why, link in self.missing[:8])
            more = f"; and {len(self.missing) - 8} more" if len(self.missing) > 8 else ""
            hint = ""
            if self.missing_packages:
                from .ros_packages import HINT

                hint = f". Packages not found: {', '.join(sorted(set(self.missing_packages)))}; {HINT}"
            out.append(f"{len(self.missing)} mesh(es) not drawn: {items}{more}{hint}")
        if self.refused:
            items = "; ".join(f"{_short(m)} -> {p} ({self._instead(link)})" for m, p, link in self.refused[:8])
            more = f"; and {len(self.refused) - 8} more" if len(self.refused) > 8 else ""
            out.append(f"{len(self.refused)} mesh(es) outside the description's packages not read: {items}{more}. "
                       "To allow them, declare their directory (package_dirs in the constraint file, or --package DIR)")
        return out


def _short(ref: str) -> str:
    return ref if len(ref) <= 90 else "..." + ref[-87:]


def description_tree(source: Path | None) -> Path | None:
    """The tree a description file belongs to: the nearest directory above it holding a ``package.xml``, else its
    own directory (None without a file).

    Args:
        source: The description file (``None``: none).

    Returns:
        The tree's root directory, or ``None`` without a source file.
    """
    if source is None:
        return None
    source = Path(source).resolve()
    for d in source.parents:
        if (d / "package.xml").is_file():
            return d
    return source.parent


def _inside(path: Path, roots) -> bool:
    real = os.path.realpath(path)
    return any(real == str(r) or real.startswith(str(r).rstrip(os.sep) + os.sep) for r in roots)


class _Resolver:
    def __init__(self, index: PackageIndex, source: Path | None, allowed) -> None:
        self.index = index
        self.base = Path(source).resolve().parent if source is not None else None
        tree = description_tree(source)
        self.extra = [Path(os.path.realpath(p)) for p in [*([tree] if tree else []), *allowed]]
        self.report = VisualReport()

    def roots(self) -> list[Path]:
        return sorted({*self.extra, *(Path(os.path.realpath(p)) for p in self.index.roots())})

    def resolve(self, ref: str) -> tuple[Path | None, str | None, bool]:
        """``(path, reason it cannot be drawn, refused)``."""
        if ref.startswith("package://"):
            path, pkg = self.index.resolve_uri(ref)
            if path is None:
                self.report.missing_packages.append(pkg)
                return None, f"package {pkg} not found", False
        elif ref.startswith("file://"):
            path = Path(ref[len("file://"):])
        elif missing_name(ref):
            self.report.missing_packages.append(missing_name(ref))
            return None, f"package {missing_name(ref)} not found", False
        elif os.path.isabs(ref):
            path = Path(ref)
        elif self.base is not None:
            path = self.base / ref
        else:
            return None, "a relative path, and no description file to resolve it against", False
        if not _inside(path, self.roots()):
            return Path(os.path.realpath(path)), "outside", True
        if not path.is_file():
            return None, "file not found", False
        return path.resolve(), None, False


def prepare_visuals(urdf: str, index: PackageIndex, source: Path | None = None, allowed=(),
                    unreadable: set[str] | None = None) -> tuple[str, VisualReport]:
    """The URDF with every visual mesh resolved to an absolute path, and stand-ins where one cannot be drawn.

    Args:
        urdf: The URDF text.
        index: Where packages are.
        source: The description file (the base of relative paths and the description's own tree).
        allowed: Further directories meshes may be read from.
        unreadable: Resolved mesh paths known not to load (replaced like missing ones).

    Returns:
        ``(urdf text, report)``.
    """
    tree = ET.fromstring(urdf)
    res = _Resolver(index, source, allowed)
    unreadable = unreadable or set()
    any_visual = False
    for link in tree.findall("link"):
        failed = False
        for visual in link.findall("visual"):
            any_visual = True
            mesh = visual.find("geometry/mesh")
            if mesh is None:
                continue
            ref = mesh.get("filename", "")
            path, why, refused = res.resolve(ref)
            if why is None and str(path) in unreadable:
                why = "cannot be loaded"
            if why is None:
                mesh.set("filename", str(path))
                continue
            if refused:
                res.report.refused.append((ref, str(path), link.get("name")))
            else:
                res.report.missing.append((ref, why, link.get("name")))
            link.remove(visual)
            failed = True
        if failed and not link.findall("visual"):
            res.report.standins[link.get("name")] = _stand_in(link, res, unreadable)
    if not any_visual:
        res.report.no_visuals = True
        for link in tree.findall("link"):
            if _inertia_box(link) is not None:
                link.append(_inertia_box(link))
                res.report.standins[link.get("name")] = "inertia box"
    res.report.roots = res.roots()
    return ET.tostring(tree, encoding="unicode"), res.report


def _stand_in(link: ET.Element, res: _Resolver, unreadable: set[str]) -> str:
    """Append a stand-in visual to ``link`` and say which."""
    found = False
    for col in link.findall("collision"):
        geom = col.find("geometry")
        if geom is None or len(geom) == 0:
            continue
        visual = copy.deepcopy(col)
        visual.tag = "visual"
        visual.attrib.pop("name", None)
        mesh = visual.find("geometry/mesh")
        if mesh is not None:
            path, why, _ = res.resolve(mesh.get("filename", ""))
            if why is not None or str(path) in unreadable:
                continue
            mesh.set("filename", str(path))
        _material(visual)
        link.append(visual)
        found = True
    if found:
        return "collision"
    box = _inertia_box(link)
    if box is not None:
        link.append(box)
        return "inertia box"
    visual = ET.SubElement(link, "visual")
    ET.SubElement(ET.SubElement(visual, "geometry"), "sphere", radius=str(MARKER_RADIUS))
    _material(visual)
    return "marker"


def _material(visual: ET.Element) -> None:
    for old in visual.findall("material"):
        visual.remove(old)
    mat = ET.SubElement(visual, "material", name="robotdyn_standin")
    ET.SubElement(mat, "color", rgba=_STANDIN_RGBA)


def _floats(text: str | None, n: int) -> np.ndarray:
    values = [float(x) for x in (text or "").split()] if text else []
    return np.array(values if len(values) == n else [0.0] * n)


def inertia_box(mass: float, inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Sides [m] and principal axes (columns, a rotation) of the uniform box with ``mass`` [kg] and central
    ``inertia`` [kg m^2] (3x3): :math:`I_i = m(a_j^2 + a_k^2)/12`, so :math:`a_i^2 = 6(\\operatorname{tr}I - 2I_i)/m`;
    None for a massless or non-physical inertia.

    Args:
        mass: Mass [kg].
        inertia: Central inertia tensor (3, 3) [kg m^2].

    Returns:
        ``(sides, axes)``: sides (3,) [m] and axes (3, 3) (columns, in the frame of ``inertia``), or ``None`` for a
        massless or non-physical inertia.
    """
    if not (np.isfinite(mass) and mass > 0) or not np.all(np.isfinite(inertia)):
        return None
    eig, axes = np.linalg.eigh(0.5 * (inertia + inertia.T))
    sides2 = 6.0 * (eig.sum() - 2.0 * eig) / mass
    if np.any(sides2 < -1e-12) or eig.max() <= 0:
        return None
    if np.linalg.det(axes) < 0:
        axes[:, 2] *= -1.0
    return np.sqrt(np.maximum(sides2, 1e-6)), axes


def _inertia_box(link: ET.Element) -> ET.Element | None:
    inertial = link.find("inertial")
    if inertial is None or inertial.find("mass") is None or inertial.find("inertia") is None:
        return None
    try:
        mass = float(inertial.find("mass").get("value"))
        el = inertial.find("inertia")
        ixx, iyy, izz, ixy, ixz, iyz = (float(el.get(k, 0.0)) for k in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz"))
    except (TypeError, ValueError):
        return None
    origin = inertial.find("origin")
    xyz = _floats(origin.get("xyz") if origin is not None else None, 3)
    rpy = _floats(origin.get("rpy") if origin is not None else None, 3)
    box = inertia_box(mass, np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]))
    if box is None:
        return None
    sides, axes = box
    R = pin.rpy.rpyToMatrix(*rpy) @ axes
    visual = ET.Element("visual")
    ET.SubElement(visual, "origin", xyz=" ".join(f"{x:.17g}" for x in xyz),
                  rpy=" ".join(f"{x:.17g}" for x in pin.rpy.matrixToRpy(R)))
    ET.SubElement(ET.SubElement(visual, "geometry"), "box", size=" ".join(f"{s:.17g}" for s in sides))
    _material(visual)
    return visual


def build_visual(model: pin.Model, urdf: str, index: PackageIndex, source: Path | None = None,
                 allowed=()) -> tuple[pin.GeometryModel, VisualReport]:
    """Pinocchio's visual geometry of ``urdf`` (already naturalised, for ``model``), never empty of the robot:
    missing, unloadable and refused meshes are replaced (see the module docstring) and reported.

    Args:
        model: The Pinocchio model built from ``urdf``.
        urdf: The (naturalised) URDF XML text.
        index: The :class:`~robotdyn.description.ros_packages.PackageIndex` resolving ``package://`` meshes.
        source: The description file, whose tree meshes may be read from (default ``None``).
        allowed: More directories meshes may be read from.

    Returns:
        ``(geometry, report)``: the ``pin.GeometryModel`` and the :class:`VisualReport` of what was replaced and why.
    """
    text, report = prepare_visuals(urdf, index, source, allowed)
    loader = _mesh_loader()
    try:
        return pin.buildGeomFromUrdfString(model, text, pin.GeometryType.VISUAL, package_dirs=[],
                                           mesh_loader=loader), report
    except Exception:
        pass
    # some mesh does not load: find which (each file once), replace them, try again
    bad = set()
    for mesh in ET.fromstring(text).iter("mesh"):
        path = mesh.get("filename", "")
        if path in bad:
            continue
        try:
            _mesh_loader().load(path, np.ones(3))
        except Exception:
            bad.add(path)
    text, report = prepare_visuals(urdf, index, source, allowed, unreadable=bad)
    try:
        return pin.buildGeomFromUrdfString(model, text, pin.GeometryType.VISUAL, package_dirs=[],
                                           mesh_loader=loader), report
    except Exception as exc:  # a primitive Pinocchio refuses: boxes of the inertias only
        tree = ET.fromstring(text)
        for link in tree.findall("link"):
            for visual in link.findall("visual"):
                link.remove(visual)
            if _inertia_box(link) is not None:
                link.append(_inertia_box(link))
                report.standins[link.get("name")] = "inertia box"
        report.missing.append(("visual geometry", " ".join(str(exc).split())[:120], None))
        return pin.buildGeomFromUrdfString(model, ET.tostring(tree, encoding="unicode"), pin.GeometryType.VISUAL,
                                           package_dirs=[]), report


def _mesh_loader():
    import coal

    return coal.CachedMeshLoader()


__all__ = ["VisualReport", "prepare_visuals", "build_visual", "description_tree", "inertia_box", "MARKER_RADIUS"]
