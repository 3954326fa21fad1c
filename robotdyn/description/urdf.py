"""Robot descriptions: Xacro -> URDF -> Pinocchio model with natural coordinates.

A description is expanded with xacro's Python API (no ROS), validated with yourdfpy, and built into a Pinocchio
model whose configuration vector ``q`` holds *natural coordinates*: every joint has one coordinate and
:math:`\\dot q = v`. To get there:

- ``continuous`` joints become unbounded ``revolute`` joints, so a wheel angle is the angle itself (unwrapped),
  not Pinocchio's (cos, sin) pair;
- the root joint is a chain of one-degree-of-freedom joints on massless links rather than Pinocchio's planar or
  free-flyer joint: ``planar`` gives (x, y, psi), ``floating`` gives (x, y, z, yaw, pitch, roll) with the
  Z-Y-X Euler convention, both in the world frame (m, rad). (Pinocchio 4.1's ``JointModelComposite`` was tried
  and rejected: its frame-Jacobian time variation is wrong, which the rolling contact's drift needs.)
"""

from __future__ import annotations

import io
import math
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import DescriptionError, InputError, RobotDynError

URDF_DIR = Path(__file__).resolve().parents[2] / "urdf"
"""Directory of the Xacro descriptions shipped with robotdyn (``urdf/`` of the repository).

:meta hide-value:
"""

ROOT_KINDS = ("fixed", "planar", "floating")
_UNBOUNDED = 1.0e9
_ROOT_CHAINS = {
    "fixed": [],
    "planar": [("x", "prismatic", "1 0 0"), ("y", "prismatic", "0 1 0"), ("psi", "revolute", "0 0 1")],
    "floating": [
        ("x", "prismatic", "1 0 0"),
        ("y", "prismatic", "0 1 0"),
        ("z", "prismatic", "0 0 1"),
        ("yaw", "revolute", "0 0 1"),
        ("pitch", "revolute", "0 1 0"),
        ("roll", "revolute", "1 0 0"),
    ],
}


_PLAIN_WORD = re.compile(r"[A-Za-z0-9_./:+-]*")
XACRO_NAMES = frozenset(
    ["list", "dict", "map", "len", "str", "float", "int", "bool", "True", "False", "min", "max", "round", "sorted",
     "range", "python", "math", "xacro", "load_yaml", "abs_filename", "dotify"]
    + [k for k in math.__dict__ if not k.startswith("_")])
"""The names xacro 2 binds inside ``${...}`` (``xacro.create_global_symbols``: Python builtins, everything of
:mod:`math` such as ``pi`` and ``e``, xacro's own): a word among them is a value there, not a word."""


def xacro_value(name: str, value, properties=()) -> str:
    """A value for a ``xacro:arg`` as data, never as code.

    xacro substitutes ``$(arg name)`` textually, also inside ``${...}`` expressions, which it evaluates: a value is
    therefore handed over only as a number (finite, in Python's canonical form) or a plain word that no
    expression can read as anything but a name: letters, digits and ``_ . / : + -``, no ``__``; not starting with
    a digit or a point (``1e5j``, ``.5.5``); no ``+`` or ``-`` unless it is a path (holding ``/``: ``1-1``,
    ``r+r`` would be sums); not a name that xacro binds (:data:`XACRO_NAMES`: ``pi``, ``e``, ``max``, ``math.pi``)
    nor one of the description's ``properties``. A choice, a frame name and a ``package://`` path pass.
    Anything else raises :class:`~robotdyn.errors.InputError` before xacro sees it. (A Xacro *file* is code by
    design: only expand descriptions you trust.)

    Args:
        name: The argument's name (for the message).
        value: A number, bool or string.
        properties: Names of the ``xacro:property`` s of the description (a word naming one would be its value).

    Returns:
        The value as xacro text (``true``/``false``, a number's repr, or a plain or quoted string).
    """
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float, np.integer, np.floating)):
        x = float(value)
        if not np.isfinite(x):
            raise InputError(f"xacro argument {name} = {value!r}; expected a finite number")
        return repr(int(x)) if isinstance(value, (int, np.integer)) else repr(x)
    text = str(value)
    try:
        x = float(text)
    except ValueError:
        if not _PLAIN_WORD.fullmatch(text) or "__" in text:
            raise InputError(f"xacro argument {name} = {text!r}; expected a number or a plain word (letters, digits "
                             "and _ . / : + -): robotdyn hands xacro data, never expressions") from None
        head = text.split(".")[0].split("/")[0]
        if (text[:1].isdigit() or text[:1] == "." or ("/" not in text and ("+" in text or "-" in text))
                or head in XACRO_NAMES or head in set(properties)):
            raise InputError(f"xacro argument {name} = {text!r}: xacro would evaluate it inside ${{...}} (an "
                             "expression, or a name it binds); expected a number, or a word that is only a name "
                             "(a choice, a frame, a package:// path)") from None
        return text
    if not np.isfinite(x):
        raise InputError(f"xacro argument {name} = {text!r}; expected a finite number")
    return text if _PLAIN_WORD.fullmatch(text) else repr(x)


_PROPERTY = re.compile(r"<xacro:property\s+name=[\"']([^\"']+)[\"']")


def expand_xacro(path: str | Path, args: dict[str, object] | None = None, packages=None) -> str:
    """Expand a Xacro file into a URDF string.

    Args:
        path: The ``.xacro`` (or plain ``.urdf``) file. Includes are resolved relative to it.
        args: Values of the file's ``xacro:arg`` s, converted with ``str``.
        packages: A :class:`~robotdyn.description.ros_packages.PackageIndex` answering ``$(find PKG)`` (default: one from
            ``ROS_PACKAGE_PATH``/``AMENT_PREFIX_PATH``); no ROS installation is needed.

    Returns:
        The URDF XML text (from :mod:`robotdyn.description.cache` when none of the files it reads changed).

    Raises:
        MissingPackagesError: Packages the description includes were not found (all of them, at once).
        DescriptionError: The file is missing or xacro cannot expand it.
    """
    from . import cache as description_cache
    from .ros_packages import PackageIndex

    from ..input_files import regular_file

    path = Path(path)
    if not path.is_file():
        raise DescriptionError(f"description file not found: {path}")
    try:  # a regular file of bounded size (60 MB ran past a minute)
        regular_file(path, "description", MAX_DESCRIPTION_BYTES)
    except InputError as exc:
        raise DescriptionError(str(exc)) from None
    properties = _PROPERTY.findall(path.read_text(errors="replace")) if args else ()
    mappings = {str(k): xacro_value(str(k), v, properties) for k, v in (args or {}).items()}
    index = packages if packages is not None else PackageIndex.create()
    cached = description_cache.lookup(path, mappings, index)
    if cached is not None:
        check_size(cached, path.name)
        return cached
    import xacro

    from .ros_packages import MISSING_ROOT, MissingPackagesError, required_packages, xacro_find

    with xacro_find(index) as missing:
        try:
            first = len(xacro.all_includes)
            doc = xacro.process_file(str(path), mappings=dict(mappings))  # xacro adds the defaults to it
            read = list(xacro.all_includes[first:])
        except Exception as exc:  # xacro raises a variety of exception types
            msg = " ".join(str(exc).split()) or type(exc).__name__
            needed = {m for m in missing if f"{MISSING_ROOT}/{m}" in msg}
            if needed or missing:  # every package the description includes unconditionally, not only the first
                needed |= required_packages(path, index)
            if needed:
                raise MissingPackagesError(needed, f"cannot expand xacro {path.name}: ") from None
            undefined = re.fullmatch(r"Undefined substitution argument (\w+)", msg)
            if undefined:  # a macro reads $(arg NAME) that the file given here does not declare
                msg += (f"; expected <xacro:arg name=\"{undefined[1]}\" default=\"...\"/> in {path.name} (the "
                        f"description reads $(arg {undefined[1]}): the top-level file declares it, also to set it "
                        "with --xacro-arg or xacro_args)")
            raise DescriptionError(f"cannot expand xacro {path.name}: {msg}") from None
    urdf = doc.toxml()
    check_size(urdf, path.name)
    description_cache.store(path, mappings, index, read, urdf)
    return urdf


MAX_DESCRIPTION_BYTES = 10_000_000
"""Largest description accepted [bytes], as a file and expanded (real robots' URDFs are well under 1 MB; meshes are
separate files): a larger one is refused before it is parsed."""
MAX_LINKS = 300
"""Most links of a description (humanoids and mobile manipulators have 50 to 150; a chain of 300 takes 15 s to
load): a larger tree is refused in one line before the model is built (3000 links ended in a MemoryError after
54 s)."""
_LINK = re.compile(r"<link[\s/>]")


def check_size(urdf: str, name: str) -> None:
    """Refuse an expanded description beyond :data:`MAX_DESCRIPTION_BYTES` or :data:`MAX_LINKS` links.

    Args:
        urdf: The expanded URDF text.
        name: The description's file name, for the message.

    Raises:
        DescriptionError: Naming the description, its size or link count, and the limit.
    """
    if len(urdf) > MAX_DESCRIPTION_BYTES:
        raise DescriptionError(f"description {name}: {len(urdf):,} characters expanded; expected at most "
                               f"{MAX_DESCRIPTION_BYTES:,}")
    links = len(_LINK.findall(urdf))
    if links > MAX_LINKS:
        raise DescriptionError(f"description {name}: {links:,} links; expected at most {MAX_LINKS:,} (a robot's tree)")


_CHECKS = 3
"""Revision of robotdyn's own checks in :func:`_validate_with_yourdfpy` (raise it when they change, so that the
cache of validated texts does not skip a new check)."""


def _validated_cache() -> Path | None:
    """The file listing the URDF texts (by SHA-256, with yourdfpy's stamp) that passed :func:`validate_urdf`, in
    :func:`robotdyn.description.cache.cache_dir` (None: caching is off)."""
    from .cache import cache_dir

    root = cache_dir()
    return None if root is None else root / "validated-urdf.txt"


def validate_urdf(urdf: str) -> None:
    """Check a URDF string with yourdfpy (parses, one tree, known joint types, physical inertias).

    A text that passed once (same SHA-256, same yourdfpy version) is not checked again: the cache file of
    :func:`_validated_cache` remembers it (importing yourdfpy alone costs about 0.15 s of every command).

    Args:
        urdf: The URDF XML text.

    Raises:
        DescriptionError: naming the first problem found.
    """
    import hashlib

    from .cache import package_stamp

    stamp = hashlib.sha256(package_stamp("yourdfpy").encode()).hexdigest()[:16]
    key = f"{hashlib.sha256(urdf.encode()).hexdigest()} yourdfpy-{stamp} checks-{_CHECKS}"
    cache = _validated_cache()
    try:
        if cache is not None and key in cache.read_text().split("\n"):
            return
    except OSError:
        pass
    _validate_with_yourdfpy(urdf)
    if cache is None:
        return
    try:  # remember it (atomically; a cache that cannot be written only costs time)
        from ..output import atomic_output

        cache.parent.mkdir(parents=True, exist_ok=True)
        lines = cache.read_text().split("\n") if cache.is_file() else []
        with atomic_output(cache, "cache") as tmp:
            tmp.write_text("\n".join([line for line in lines[-999:] if line] + [key]) + "\n")
    except (OSError, RobotDynError):
        pass


MIN_MASS = 1e-9
"""Smallest non-zero link mass accepted [kg] (a microgram: dummy links of real descriptions weigh 1e-9 kg and more);
below it a mass is 0 in effect but its inertia's inverse overflows the dynamics."""
MAX_DESCRIPTION_LENGTH = 1e6
"""Largest offset or size in a description [m] (beyond it the kinematics lose every digit)."""


def _numbers(el, attr: str, count: int, what: str) -> list[float]:
    """``count`` finite numbers of an attribute (one line naming the element otherwise)."""
    text = el.get(attr)
    if text is None:
        return []
    parts = text.split()
    try:
        values = [float(x) for x in parts]
    except ValueError:
        raise DescriptionError(f"{what}: {attr}={text!r} is not {count} number(s)") from None
    if len(values) != count:
        raise DescriptionError(f"{what}: {attr}={text!r} has {len(values)} number(s); expected {count}")
    if not all(math.isfinite(v) for v in values):
        raise DescriptionError(f"{what}: {attr}={text!r} is not finite; expected finite numbers")
    return values


def _check_numbers(urdf: str) -> None:
    """Every number of a URDF that robotdyn reads, checked before any parser sees it: finite and of the right
    count (origins, axes, masses, inertias, limits, geometry), masses >= 0, sizes >= 0, offsets within
    :data:`MAX_DESCRIPTION_LENGTH`, joint limits ordered, a total mass > 0.

    Raises:
        DescriptionError: naming the link or joint and the attribute.
    """
    try:
        tree = ET.fromstring(urdf)
    except ET.ParseError as exc:
        raise DescriptionError(f"invalid URDF (not XML): {exc}") from None
    if tree.tag != "robot":
        raise DescriptionError(f"invalid URDF: root element <{tree.tag}>; expected <robot>")
    total, links = 0.0, 0
    for kind in ("link", "joint"):
        for el in tree.iter(kind):
            name = f"{kind} {el.get('name')!r}"
            for origin in el.iter("origin"):
                xyz = _numbers(origin, "xyz", 3, f"{name} origin")
                _numbers(origin, "rpy", 3, f"{name} origin")
                if xyz and max(map(abs, xyz)) > MAX_DESCRIPTION_LENGTH:
                    raise DescriptionError(f"{name} origin: xyz={origin.get('xyz')!r}; expected offsets of magnitude "
                                           f"<= {MAX_DESCRIPTION_LENGTH:g} m")
            if kind == "link":
                links += 1
                mass = el.find("inertial/mass")
                if mass is not None:
                    m = _numbers(mass, "value", 1, f"{name} mass")
                    if m and m[0] < 0:
                        raise DescriptionError(f"{name} mass: value={m[0]:g} kg; expected a mass >= 0")
                    if m and 0 < m[0] < MIN_MASS:  # (a wheel of 1e-300 kg gave accelerations of 1e302)
                        raise DescriptionError(f"{name} mass: value={m[0]:g} kg; expected 0 (a massless link) or at "
                                               f"least {MIN_MASS:g} kg")
                    total += m[0] if m else 0.0
                inertia = el.find("inertial/inertia")
                if inertia is not None:
                    for attr in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz"):
                        _numbers(inertia, attr, 1, f"{name} inertia")
                for shape in el.iter():
                    if shape.tag in ("box", "cylinder", "sphere", "capsule"):
                        for attr, count in (("size", 3), ("radius", 1), ("length", 1)):
                            values = _numbers(shape, attr, count, f"{name} {shape.tag}")
                            if values and min(values) < 0:
                                raise DescriptionError(f"{name} {shape.tag}: {attr}={shape.get(attr)!r}; expected "
                                                       "sizes >= 0 m")
            else:
                axis = el.find("axis")
                if axis is not None:
                    xyz = _numbers(axis, "xyz", 3, f"{name} axis")
                    if xyz and max(map(abs, xyz)) == 0 and el.get("type") in ("revolute", "continuous", "prismatic"):
                        raise DescriptionError(f"{name} axis: xyz={axis.get('xyz')!r} has zero length; expected a "
                                               "direction")
                limit = el.find("limit")
                if limit is not None:
                    lower = _numbers(limit, "lower", 1, f"{name} limit")
                    upper = _numbers(limit, "upper", 1, f"{name} limit")
                    for attr in ("effort", "velocity"):
                        v = _numbers(limit, attr, 1, f"{name} limit")
                        if v and v[0] < 0:
                            raise DescriptionError(f"{name} limit: {attr}={v[0]:g}; expected a value >= 0")
                    if lower and upper and lower[0] > upper[0] and el.get("type") in ("revolute", "prismatic"):
                        raise DescriptionError(f"{name} limit: lower={lower[0]:g} > upper={upper[0]:g}; expected "
                                               "lower <= upper")
    if links and total <= 0:
        raise DescriptionError("the description's links have a total mass of 0 kg; expected positive masses (a "
                               "robot without mass has no dynamics)")


def _validate_with_yourdfpy(urdf: str) -> None:
    import yourdfpy

    _check_numbers(urdf)

    try:
        robot = yourdfpy.URDF.load(io.StringIO(urdf), build_scene_graph=False, load_meshes=False)
    except Exception as exc:
        raise DescriptionError(f"invalid URDF: {' '.join(str(exc).split())}") from None
    if not robot.validate():
        raise DescriptionError("invalid URDF: yourdfpy validation failed (check links, joints and inertials)")
    problems = [p for p in map(_inertial_problem, robot.robot.links) if p]
    if len(problems) == 1:
        raise DescriptionError(problems[0])
    if problems:
        names = [p.split("'")[1] for p in problems]
        raise DescriptionError(
            f"{len(problems)} links have non-physical inertials: {'; '.join(problems)}. If they are placeholders, "
            f"declare them massless (massless = {names} in a constraint file)".replace("'", '"'))


def _inertial_problem(link) -> str | None:
    """What is physically impossible about a link's inertial (negative or non-finite mass, an inertia tensor that
    is not positive semi-definite or violates the triangle inequality), or None."""
    inertial = link.inertial
    if inertial is None or inertial.mass is None:
        return None
    if inertial.mass < 0 or not math.isfinite(inertial.mass):
        return f"link {link.name!r} has mass {inertial.mass}; expected a finite value >= 0"
    inertia = np.asarray(inertial.inertia, dtype=float)
    eig = np.linalg.eigvalsh(inertia)
    if inertial.mass > 0 and (eig.min() < -1e-12 or not np.all(np.isfinite(eig))):
        return (f"link {link.name!r} has a non-positive inertia tensor (eigenvalues {np.round(eig, 6).tolist()}); "
                "expected a positive semi-definite central inertia")
    a, b, c = np.sort(eig)
    if inertial.mass > 0 and c > a + b + 1e-9 * max(c, 1.0):
        return (f"link {link.name!r} violates the triangle inequality of principal inertias "
                f"({a:.6g}, {b:.6g}, {c:.6g}); no rigid body has that inertia")
    return None


def _naturalise(urdf: str, root: str) -> tuple[str, list[str]]:
    """Rewrite continuous joints as unbounded revolute ones and prepend the root chain.

    Returns:
        The new URDF text and the names of the root-chain joints.
    """
    if root not in ROOT_KINDS:
        raise DescriptionError(f"unknown root joint kind {root!r}; expected one of {', '.join(ROOT_KINDS)}")
    try:
        tree = ET.fromstring(urdf)
    except ET.ParseError as exc:
        raise DescriptionError(f"URDF is not well-formed XML: {exc}") from None
    links = {el.get("name") for el in tree.findall("link")}
    children = {j.find("child").get("link") for j in tree.findall("joint") if j.find("child") is not None}
    roots = sorted(links - children)
    if len(roots) != 1:
        raise DescriptionError(f"URDF must have exactly one root link, found {roots}")
    for joint in tree.findall("joint"):
        jtype = joint.get("type")
        if jtype in ("floating", "planar"):
            raise DescriptionError(
                f"joint {joint.get('name')!r} has type {jtype!r}; only revolute, continuous, prismatic and fixed "
                "joints are supported inside the tree (the root joint is chosen separately)"
            )
        if jtype == "continuous":
            joint.set("type", "revolute")
            lim = joint.find("limit")
            if lim is None:
                lim = ET.SubElement(joint, "limit")
                lim.set("effort", "0")
                lim.set("velocity", "0")
            lim.set("lower", str(-_UNBOUNDED))
            lim.set("upper", str(_UNBOUNDED))
    chain = _ROOT_CHAINS[root]
    parent = "robotdyn_world"
    if chain:
        ET.SubElement(tree, "link", name=parent)
    names = []
    for i, (name, jtype, axis) in enumerate(chain):
        child = roots[0] if i == len(chain) - 1 else f"robotdyn_root_{name}"
        if child != roots[0]:
            ET.SubElement(tree, "link", name=child)
        joint = ET.SubElement(tree, "joint", name=name, type=jtype)
        ET.SubElement(joint, "parent", link=parent)
        ET.SubElement(joint, "child", link=child)
        ET.SubElement(joint, "axis", xyz=axis)
        ET.SubElement(joint, "limit", lower=str(-_UNBOUNDED), upper=str(_UNBOUNDED), effort="0", velocity="0")
        names.append(name)
        parent = child
    return ET.tostring(tree, encoding="unicode"), names


@dataclass
class Description:
    """A Pinocchio model in natural coordinates, with its visual geometry.

    Attributes:
        model: The Pinocchio model (``nq == nv``, :math:`\\dot q = v`).
        visual: The visual geometry model (for the viewer).
        urdf: The URDF text the model was built from (root chain included).
        root: ``"fixed"``, ``"planar"`` or ``"floating"``.
        joint_names: Joint name of each coordinate, in ``q`` order.
        lower, upper: Joint limits of each coordinate (``±inf`` when unbounded).
        visual_report: The :class:`~robotdyn.description.visual_geometry.VisualReport` of its meshes (``None``: not
            built).
        root_height: Height [m] of the root chain above the world origin (:meth:`set_root_height`).
    """

    model: pin.Model
    visual: pin.GeometryModel
    urdf: str
    root: str
    joint_names: list[str] = field(default_factory=list)
    lower: np.ndarray = field(default_factory=lambda: np.zeros(0))
    upper: np.ndarray = field(default_factory=lambda: np.zeros(0))
    visual_report: object = None
    root_height: float = 0.0

    def __repr__(self) -> str:
        return f"Description(model={self.model.name!r}, root={self.root!r}, nq={self.model.nq})"

    def set_root_height(self, height: float) -> None:
        """Raise the root chain by ``height`` [m]: the first root joint's placement gets the translation
        (0, 0, height), so that a planar root moves its link in the plane z = height (a base whose link sits above
        the ground, as most ROS descriptions' ``base_link`` does) and a floating root's z is measured from there.
        The stored URDF text says the same (an ``<origin>`` on that joint).

        Args:
            height: Height [m] of the root chain above the world origin.
        """
        height = float(height)
        if not np.isfinite(height):
            raise DescriptionError(f"root height {height}; expected a finite height in m")
        chain = _ROOT_CHAINS[self.root]
        if not chain:
            if height:
                raise DescriptionError(f"root height {height:g} m with a fixed root; expected a planar or floating root")
            return
        jid = self.model.getJointId(chain[0][0])
        placement = self.model.jointPlacements[jid]
        placement.translation = np.array([0.0, 0.0, height])
        self.model.jointPlacements[jid] = placement
        tree = ET.fromstring(self.urdf)
        for joint in tree.findall("joint"):
            if joint.get("name") == chain[0][0]:
                for old in joint.findall("origin"):
                    joint.remove(old)
                ET.SubElement(joint, "origin", xyz=f"0 0 {height!r}", rpy="0 0 0")
        self.urdf = ET.tostring(tree, encoding="unicode")
        self.root_height = height

    def q_index(self, joint: str) -> int:
        """Index in ``q`` (and ``v``) of a one-degree-of-freedom joint.

        Args:
            joint: The joint's name.

        Returns:
            The index.

        Raises:
            DescriptionError: No such joint.
        """
        if not self.model.existJointName(joint):
            raise DescriptionError(f"no joint named {joint!r}; joints are {', '.join(self.joint_names)}")
        return int(self.model.joints[self.model.getJointId(joint)].idx_q)

    def frame_id(self, frame: str) -> int:
        """Pinocchio frame index of a link or joint frame, with a clear error for a typo.

        Args:
            frame: A link or joint name.

        Returns:
            The frame id.

        Raises:
            DescriptionError: No such frame (the message lists the links).
        """
        if not self.model.existFrame(frame):
            links = sorted({f.name for f in self.model.frames if f.type == pin.FrameType.BODY})
            raise DescriptionError(f"no frame named {frame!r}; links are {', '.join(links)}")
        return int(self.model.getFrameId(frame))


def drop_inertials(urdf: str, links) -> str:
    """Remove the ``<inertial>`` of the named links (they become massless); unknown link names are an error.

    Args:
        urdf: The URDF XML text.
        links: Names of the links made massless.

    Returns:
        The URDF text without those links' inertials (``urdf`` unchanged if there are none).
    """
    links = list(links or [])
    if not links:
        return urdf
    try:
        tree = ET.fromstring(urdf)
    except ET.ParseError as exc:
        raise DescriptionError(f"URDF is not well-formed XML: {exc}") from None
    by_name = {el.get("name"): el for el in tree.findall("link")}
    for name in links:
        if name not in by_name:
            raise DescriptionError(f"massless link {name!r} does not exist; links are {', '.join(sorted(by_name))}")
        for inertial in by_name[name].findall("inertial"):
            by_name[name].remove(inertial)
    return ET.tostring(tree, encoding="unicode")


def lock_joints(model: pin.Model, visual: pin.GeometryModel, locked: dict[str, float]):
    """Replace the named one-DOF joints by fixed ones at the given values (m or rad), merging the inertias.

    Uses ``pin.buildReducedModel``; the remaining joints keep their natural coordinates.

    Args:
        model: The Pinocchio model.
        visual: Its visual geometry model.
        locked: Joint name -> value [m or rad] at which it is held.

    Returns:
        The reduced ``(model, visual)`` pair of ``pin.buildReducedModel``.
    """
    ids, q_ref = [], np.zeros(model.nq)
    for name, value in locked.items():
        names = list(model.names)[1:]
        if name not in names:
            raise DescriptionError(f"locked joint {name!r} does not exist; joints are {', '.join(names)}")
        jid = int(model.getJointId(name))
        i = int(model.joints[jid].idx_q)
        lo, hi = model.lowerPositionLimit[i], model.upperPositionLimit[i]
        value = float(value)
        if not np.isfinite(value) or value < lo - 1e-12 or value > hi + 1e-12:
            raise DescriptionError(f"locked joint {name!r} = {value:g} is outside its range [{lo:.6g}, {hi:.6g}]")
        ids.append(jid)
        q_ref[i] = value
    return pin.buildReducedModel(model, visual, sorted(ids), q_ref)


def build_description(
    urdf: str,
    root: str = "planar",
    package_dirs: list[str] | None = None,
    locked: dict[str, float] | None = None,
    massless: list[str] | None = None,
    packages=None,
    source: str | Path | None = None,
    root_height: float = 0.0,
) -> Description:
    """Build a :class:`Description` from URDF text.

    Args:
        urdf: URDF XML (already expanded from Xacro).
        root: Root joint kind: ``"fixed"``, ``"planar"`` (x, y, psi) or ``"floating"``
            (x, y, z, yaw, pitch, roll).
        package_dirs: Directories searched for the packages of ``package://`` meshes (used when ``packages`` is
            not given) and from which meshes may be read.
        locked: Joints to lock (name -> value in m or rad): they become fixed, their bodies merge with the parent.
        massless: Links whose inertial is dropped (e.g. a third-party URDF's placeholder with a non-physical
            inertia tensor).
        packages: A :class:`~robotdyn.description.ros_packages.PackageIndex` for ``package://`` meshes (default: one of
            ``package_dirs`` and the environment's ROS paths).
        source: The description file (relative mesh paths and the description's own tree; see
            :mod:`robotdyn.description.visual_geometry`).
        root_height: Height [m] of the root link's plane above the world's z = 0 (planar root), or of the
            reference of the z coordinate (floating root); see :meth:`Description.set_root_height`.

    Returns:
        The :class:`Description`: the Pinocchio model, its visual geometry, the URDF text, root kind, joint names and
        limits.
    """
    from .ros_packages import PackageIndex
    from .visual_geometry import build_visual

    urdf = drop_inertials(urdf, massless)
    validate_urdf(urdf)
    text, _ = _naturalise(urdf, root)
    try:
        model = pin.buildModelFromXML(text)
    except Exception as exc:
        raise DescriptionError(f"Pinocchio cannot build the model: {' '.join(str(exc).split())}") from None
    if model.nq != model.nv:
        raise DescriptionError("internal: natural coordinates require nq == nv")
    index = packages if packages is not None else PackageIndex.create(dirs=package_dirs or [])
    visual, report = build_visual(model, text, index, Path(source) if source is not None else None,
                                  allowed=package_dirs or [])
    if locked:
        model, visual = lock_joints(model, visual, locked)
    names: list[str] = [""] * model.nq
    for jid in range(1, model.njoints):
        joint = model.joints[jid]
        names[joint.idx_q] = model.names[jid]
    lower = np.where(model.lowerPositionLimit <= -_UNBOUNDED, -np.inf, model.lowerPositionLimit)
    upper = np.where(model.upperPositionLimit >= _UNBOUNDED, np.inf, model.upperPositionLimit)
    out = Description(model, visual, text, root, names, np.array(lower), np.array(upper), visual_report=report)
    if root_height:
        out.set_root_height(root_height)
    return out

