"""Declarative constraint files: any robot from a URDF/Xacro plus a small TOML file.

A constraint file names, for one URDF/Xacro description, the root joint, the wheels, the loop closures, the
motors, the terrain and optionally the independent velocities, locked joints and scenarios. :func:`read` parses
and validates it against the description and returns a :class:`ConstraintFile` whose ``SPEC`` is the same
:class:`~robotdyn.robot.RobotSpec` object a robot module supplies: a user's robot and the built-in robots go
through one path (``Robot(spec)``). Every mistake gives one line naming the file and the entry, e.g.
``tiago.toml: wheels[1] (left): no joint named 'wheel_lft_joint'; did you mean 'wheel_left_joint'?``. Types, shapes,
ranges and key names are checked first against a JSON schema (:mod:`robotdyn.interfaces.constraint_schema`); the names are
then checked against the description. The file is data: nothing in it is evaluated.

Format (all lengths in m, angles in rad, masses in kg; ``#`` starts a comment)::

    name = "tiago"                      # default: the file's stem
    title = "one line"
    urdf = "robot.urdf.xacro"           # relative to this file, absolute, or package://PKG/path (optional when
                                        # the description is given separately, e.g. robotdyn ... --urdf FILE)
    root = "planar"                     # fixed | planar (x, y, psi) | floating (x, y, z, yaw, pitch, roll)
    package_dirs = ["meshes_root"]      # directories searched for ROS packages ($(find PKG), package://PKG; relative
                                        # to this file; ROS_PACKAGE_PATH and AMENT_PREFIX_PATH are searched too), and
                                        # from which meshes may be read (robotdyn/description/ros_packages.py, visual_geometry.py)
    root_height = "auto"                # planar root: height [m] of the root link above the ground (default "auto":
                                        # found from the wheels at the neutral configuration; 0 keeps it on it)
    urdf_damping = true                 # a joint's URDF <dynamics damping> d applied as a joint torque -d q' (as
                                        # Gazebo does; false: left out); its dry friction is not modelled
    massless = ["some_link"]            # links whose URDF inertial is ignored
    independent = ["theta_R", "theta_L"]  # coordinate labels or joint names (default: automatic)
    xacro_args = { wheel_radius = "0.1" }
    labels = { wheel_right_joint = "theta_R" }      # display names of coordinates
    neutral = { torso_lift_joint = 0.1 }            # a valid configuration (default all zero)
    locked = { "arm_*" = 0.0 }                      # joints held fixed (glob patterns allowed)

    [packages]                          # ROS packages by name (directories relative to this file)
    my_robot_description = "../my_robot_description"

    [twist]                             # independent velocities that are a frame's twist instead of `independent`
    frame = "base_link"; components = ["vx", "vy", "wz"]   # default; axes = "body" (default) or "world"
    # names = ["vx", "vy", "wz"]        # display names (default: the components)

    [terrain]                           # default flat z = 0
    kind = "ramp"                       # flat (height) | ramp (slope, heading) | bump (height, x0, width, length)
    slope = 0.1                         # | sine (amplitude, kx, ky, phase)

    [[parameters]]                      # numbers that wheels may refer to; xacro arguments of the description
    name = "r"; default = 0.1; unit = "m"; description = "wheel radius"   # optional: choices, xacro, minimum
                                        # (the smallest physical value; masses and inertias: >= 0 by default)

    [[wheels]]
    name = "right"
    joint = "wheel_right_joint"         # the wheel's spin joint (its child link's origin is the wheel centre)
    # frame = "wheel_right_link"        # ... or the wheel centre frame directly
    radius = 0.0985                     # a number > 0 or a parameter name
    axis = [0, 0, 1]                    # axle in the wheel frame (default: the spin joint's axis; a support
                                        # without one, e.g. a ball: the world y axis at the zero configuration)
    kind = "standard"                   # standard | omni (with roller_angle: rad, or "45 deg") | caster (a wheel on a
                                        # steering joint of the URDF: nothing special) | support (touches the
                                        # ground only: normal row, frictionless, e.g. a free castor or a skid)
    mu = 0.8                            # friction coefficient (traction checks; the coulomb law's mu)
    friction = "rolling"                # rolling (no slip, default) | coulomb (regularised: slip_velocity [m/s],
                                        # default 1e-3) | linear (stiffness [s/m], saturated at mu if given)
    slip = "both"                       # with a friction law: both | lateral (rolls along its rolling direction
                                        # and slides sideways: only the lateral force follows the law)
    normal_stiffness = 2.0e5            # radial stiffness of tyre and wheel [N/m] (default: the robot's weight
                                        # over the number of wheels per 1 mm of static deflection); only the
                                        # ratios between wheels split the loads that rigid-body dynamics leave
                                        # open (robotdyn.contact.compliance, robotdyn.contact.rigid_limit)
    normal_damping = 600.0              # radial damping [N s/m] (default: damping ratio 0.3 of the wheel's share
                                        # of the mass on its default stiffness)
    contact = "rigid"                   # rigid (normal row a constraint, default) | compliant (a force law of the
                                        # penetration: the wheel can fly and land; robotdyn.contact.
                                        # compliant_contact); friction = rolling: it rolls while in contact
                                        # (robotdyn.contact.compliant_rolling), or coulomb / linear
    contact_law = "linear"              # compliant: linear (k delta + c delta') | hunt_crossley (delta^n (k +
                                        # lambda delta'): normal_stiffness in N/m^n, normal_damping lambda)
    contact_exponent = 1.5              # hunt_crossley's n
    [[springs]]                         # a spring and damper on a joint (suspension, rocker, passive axle)
    joint = "front_left_suspension"     # the joint (one coordinate: revolute, continuous or prismatic)
    stiffness = 3.0e4                   # k [N/m or N m/rad]: generalised force -k (q - rest) - c q'
    damping = 3.0e3                     # c [N s/m or N m s/rad] (default 0)
    rest = -0.05                        # rest position [m or rad] (default 0)
    [[closures]]
    frame1 = "a"; frame2 = "b"; components = "x y z"   # subset of x y z rx ry rz in frame1's axes

    [[motors]]
    name = "tau_R"; joint = "wheel_right_joint"; reaction = "base_link"   # reaction optional

    [[scenarios]]                       # constant-torque manoeuvres for robotdyn simulate
    name = "spin"; t_end = 2.0; torque = [0.5, -0.5]; q0 = { psi = 0.0 }; nu0 = { theta_R = 1.0 }
    # torque = { tau_R = 0.5, tau_L = -0.5 }   # ... or by motor name (motors not named: 0)
    # nu0 = { vx = 0.3 }                       # with [twist]: by twist component name
"""

from __future__ import annotations

import difflib
import fnmatch
import inspect
import math
import os
import re
import sysconfig
import tomllib
import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..description.urdf import _ROOT_CHAINS, ROOT_KINDS, expand_xacro
from ..errors import InputError, RobotDynError, RobotDynWarning
from ..inputs import MAX_ANGLE
from ..input_files import resolved
from ..contact.friction import LAWS, make_law
from ..robot import Closure, MotorSpec, Parameter, Robot, RobotSpec, Wheel
from ..description.ros_packages import HINT, PackageIndex
from ..simulation.scenario import Scenario
from ..contact.sliding import SLIP_DIRECTIONS
from ..constraints.terrain import BumpTerrain, FlatTerrain, RampTerrain, SineTerrain, Terrain
from ..simulation.torque_profile import Constant


class ConstraintFileError(RobotDynError):
    """A constraint file that cannot be read or does not match its description (one line naming file and entry)."""


TOP_KEYS = (
    "name", "title", "urdf", "root", "package_dirs", "massless", "independent", "xacro_args", "labels", "neutral",
    "locked", "terrain", "parameters", "wheels", "closures", "motors", "scenarios", "paper", "packages",
    "root_height", "twist", "springs", "urdf_damping",
)
TWIST_KEYS = ("frame", "components", "axes", "names")
PARAMETER_KEYS = ("name", "default", "unit", "description", "choices", "xacro", "minimum")
WHEEL_KEYS = ("name", "joint", "frame", "radius", "axis", "kind", "roller_angle", "radius_joint", "mu", "friction",
              "slip_velocity", "stiffness", "slip", "normal_stiffness", "normal_damping",
              "contact", "contact_law", "contact_exponent")
MAX_RADIUS = 1e4
"""Largest wheel radius accepted [m] (larger values only overflow the dynamics)."""
MAX_FILE_BYTES = 1_000_000
"""Largest constraint file read (a robot's description is a few kB; larger files are refused, not parsed)."""
WHEEL_KINDS = ("standard", "omni", "caster", "support")
CLOSURE_KEYS = ("name", "frame1", "frame2", "components")
MOTOR_KEYS = ("name", "joint", "reaction")
SPRING_KEYS = ("name", "joint", "stiffness", "damping", "rest")
SCENARIO_KEYS = ("name", "description", "t_end", "torque", "q0", "nu0")
TERRAINS: dict[str, type[Terrain]] = {
    "flat": FlatTerrain, "ramp": RampTerrain, "bump": BumpTerrain, "sine": SineTerrain,
}
ROTATING = ("revolute", "continuous")


def _suggest(name: str, candidates) -> str:
    close = difflib.get_close_matches(str(name), list(candidates), n=1, cutoff=0.6)
    return f"; did you mean {close[0]!r}?" if close else ""


def package_search_dirs(extra=()) -> list[Path]:
    """Directories where ``package://NAME/...`` is looked up: ``extra``, ``ROS_PACKAGE_PATH``, and the
    ``cmeel.prefix/share`` directory of pip-installed robot data (e.g. example-robot-data), if present.
    (:class:`robotdyn.description.ros_packages.PackageIndex` is the lookup itself.)

    Args:
        extra: Directories searched first (paths or strings).

    Returns:
        The directories, in search order.
    """
    dirs = [Path(d) for d in extra]
    dirs += [Path(d) for d in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if d]
    share = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share"
    if share.is_dir():
        dirs.append(share)
    return dirs


def resolve_path(text: str, base: Path, package_dirs=(), packages: PackageIndex | None = None) -> Path:
    """Resolve a description path: ``package://PKG/rest`` with a :class:`~robotdyn.description.ros_packages.PackageIndex`
    (default: one of ``package_dirs`` and the environment), a relative path against ``base``.

    Args:
        text: The path as written: ``package://PKG/rest``, absolute, relative, or starting with ``~``.
        base: The directory a relative path is relative to (the constraint file's).
        package_dirs: Directories searched for packages when ``packages`` is not given.
        packages: The package index to resolve ``package://`` with (default ``None``: one built from
            ``package_dirs`` and the environment).

    Returns:
        The absolute path of an existing file.

    Raises:
        ConstraintFileError: The package or the file is not found.
    """
    if text.startswith("package://"):
        index = packages if packages is not None else PackageIndex.create(dirs=package_dirs)
        path, missing = index.resolve_uri(text)
        if missing is not None:
            raise ConstraintFileError(f"cannot resolve {text}: packages not found: {missing}; {HINT}")
        if not path.is_file():
            raise ConstraintFileError(f"cannot resolve {text}: no file {path}")
        return path
    path = Path(os.path.expanduser(text))
    if not path.is_absolute():
        path = base / path
    if not path.is_file():
        raise ConstraintFileError(f"description file not found: {path}")
    return path.resolve()


@dataclass
class _Tree:
    """What the constraint file is checked against: links, joints and rigid bodies of the URDF."""

    links: list[str]
    joints: dict[str, dict]  # name -> type, parent, child, axis
    xacro_args: list[str] = field(default_factory=list)

    @classmethod
    def parse(cls, urdf: str, declared: list[str]) -> _Tree:
        tree = ET.fromstring(urdf)
        links = [el.get("name") for el in tree.findall("link")]
        joints = {}
        for j in tree.findall("joint"):
            axis = j.find("axis")
            joints[j.get("name")] = {
                "type": j.get("type"),
                "parent": j.find("parent").get("link"),
                "child": j.find("child").get("link"),
                "axis": [float(x) for x in axis.get("xyz").split()] if axis is not None else [1.0, 0.0, 0.0],
                "rpy": [float(x) for x in (origin.get("rpy") or "0 0 0").split()]
                if (origin := j.find("origin")) is not None else [0.0, 0.0, 0.0],
            }
        return cls(links, joints, declared)

    def rotation(self, frame: str) -> np.ndarray:
        """The rotation of a link (or a joint's frame) relative to the root link at the zero configuration (every
        joint at 0: only the joints' origin rpy), from the URDF alone."""
        R = np.eye(3)
        joint = frame if frame in self.joints else next(
            (n for n, j in self.joints.items() if j["child"] == frame), None)
        seen = set()
        while joint is not None and joint not in seen:
            seen.add(joint)
            roll, pitch, yaw = self.joints[joint]["rpy"]
            cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch),
                                      math.cos(yaw), math.sin(yaw))
            R = np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                          [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                          [-sp, cp * sr, cp * cr]]) @ R
            parent = self.joints[joint]["parent"]
            joint = next((n for n, j in self.joints.items() if j["child"] == parent), None)
        return R

    def movable(self, locked=()) -> list[str]:
        return [n for n, j in self.joints.items() if j["type"] != "fixed" and n not in locked]

    def body_of(self, locked) -> dict[str, str]:
        """Representative link of the rigid body each link belongs to (fixed and locked joints merge bodies)."""
        root = {link: link for link in self.links}

        def find(a: str) -> str:
            while root[a] != a:
                root[a] = root[root[a]]
                a = root[a]
            return a

        for name, j in self.joints.items():
            if j["type"] == "fixed" or name in locked:
                root[find(j["child"])] = find(j["parent"])
        return {link: find(link) for link in self.links}


class _Reader:
    """Validation helpers that prefix every message with the file and the entry."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def fail(self, where: str, msg: str) -> None:
        raise ConstraintFileError(f"{self.path}: {where}: {msg}" if where else f"{self.path}: {msg}")

    def keys(self, where: str, table, allowed) -> None:
        if not isinstance(table, dict):
            self.fail(where, f"expected a table, got {type(table).__name__} {table!r}")
        for k in table:
            if k not in allowed:
                self.fail(where, f"unknown key {k!r}{_suggest(k, allowed)} (allowed: {', '.join(allowed)})")

    def number(self, where: str, x, what: str) -> float:
        if isinstance(x, bool) or not isinstance(x, (int, float)) or not np.isfinite(x):
            self.fail(where, f"{what} = {x!r}; expected a finite number")
        return float(x)

    def angle(self, where: str, x, what: str) -> float:
        """An angle in rad: a number in [-pi, pi], or a string with its unit ("45 deg", "0.785 rad"); a bare
        number beyond pi is refused (it is almost always degrees written without their unit)."""
        if isinstance(x, str):
            match = re.fullmatch(r"\s*([-+]?[0-9.]+(?:[eE][-+]?[0-9]+)?)\s*(deg|rad)\s*", x)
            if not match:
                self.fail(where, f"{what} = {x!r}; expected a number in rad or a string like '45 deg' or '0.79 rad'")
            value = self.number(where, float(match.group(1)), what)
            value = float(np.radians(value)) if match.group(2) == "deg" else value
            if abs(value) > MAX_ANGLE:  # (1e300 rad was accepted)
                self.fail(where, f"{what} = {x!r}; expected an angle within one turn (|angle| <= 360 deg)")
            return value
        value = self.number(where, x, what)
        if abs(value) > np.pi:
            self.fail(where, f"{what} = {value:g}; a bare number is in rad and expected in [-pi, pi]: write "
                             f"'{value:g} deg' for degrees")
        return value

    def string(self, where: str, x, what: str) -> str:
        if not isinstance(x, str) or not x:
            self.fail(where, f"{what} = {x!r}; expected a non-empty string")
        return x

    def strings(self, where: str, x, what: str) -> list[str]:
        if isinstance(x, str):
            x = x.split()
        if not isinstance(x, list) or not all(isinstance(s, str) for s in x):
            self.fail(where, f"{what} = {x!r}; expected a list of strings")
        return list(x)

    def table_list(self, data: dict, key: str) -> list[dict]:
        items = data.get(key, [])
        if not isinstance(items, list) or not all(isinstance(t, dict) for t in items):
            self.fail(key, f"expected an array of tables ([[{key}]])")
        return items


@dataclass
class ConstraintFile:
    """A validated constraint file: the robot's :class:`RobotSpec` and scenarios (module-like: ``SPEC``,
    ``SCENARIOS``), plus where they came from.

    Attributes:
        path: The constraint file.
        SPEC: The robot's :class:`~robotdyn.robot.RobotSpec` (what ``Robot(spec)`` builds).
        SCENARIOS: The file's ``[[scenarios]]`` by name (:class:`~robotdyn.simulation.scenario.Scenario`).
    """

    path: Path
    SPEC: RobotSpec
    SCENARIOS: dict[str, Scenario] = field(default_factory=dict)

    def robot(self, params: dict | None = None, terrain: Terrain | None = None) -> Robot:
        """Build the robot; core errors are prefixed with the file name.

        Without ``independent`` in the file (and no ``[twist]``) the independent velocities are chosen
        automatically; a :class:`~robotdyn.errors.RobotDynWarning` names them and the line that chooses them, unless
        they are the motor joints.

        Args:
            params: Parameter values by name (default ``None``: the file's defaults).
            terrain: A terrain replacing the file's ``[terrain]`` (default ``None``).

        Returns:
            The :class:`~robotdyn.robot.Robot`.

        Raises:
            ConstraintFileError: The robot cannot be built, or ``independent`` or a scenario's ``nu0`` does not fit it
                (one line naming the file).
        """
        try:
            robot = Robot(self.SPEC, params, terrain)
        except ConstraintFileError:
            raise
        except RobotDynError as exc:
            raise ConstraintFileError(f"{self.path}: {exc}") from None
        independent = self.SPEC.independent
        if independent is None and self.SPEC.operational is None:  # silent only where it picked the motor joints
            message = automatic_independent_message(robot, self.path)
            if message:
                warnings.warn(message, RobotDynWarning, stacklevel=2)
        held = _sliding_rows(robot)  # stick-slip wheels: counted sliding, their freest phase
        if independent:  # more independent velocities than the constraints leave free cannot be independent
            A = robot.rows_at(robot.neutral()).A
            free = robot.nq - (int(np.linalg.matrix_rank(A)) if A.size else 0)
            if len(independent) > free:
                raise ConstraintFileError(
                    f"{self.path}: independent: {len(independent)} coordinates ({', '.join(independent)}) but the "
                    f"constraints leave {free} velocities free at the neutral configuration (n = {robot.nq}, rank A = "
                    f"{robot.nq - free}); expected at most {free}")
        held.restore()
        for i, sc in enumerate(self.SCENARIOS.values()):
            for name in sc.nu0:
                if name not in robot.velocity_names and not (held.wheels and name in robot.velocity_labels):
                    raise ConstraintFileError(
                        f"{self.path}: scenarios[{i}] ({sc.name}): nu0 {name.removesuffix('_dot')!r} is not an "
                        "independent velocity; expected one of "
                        f"{', '.join(v.removesuffix('_dot') for v in robot.velocity_names)}"
                    )
        return robot


def automatic_independent_message(robot: Robot, path: str | Path) -> str:
    """The warning for a constraint file without ``independent``: which velocities were chosen automatically
    (the best-conditioned set at the neutral configuration, which may be a caster's swivel and spin rather than
    the drive wheels) and the line that chooses them, suggesting the motor joints where they form a valid set.

    Args:
        robot: The robot built from the file (its automatic choice made).
        path: The constraint file (named in the message).

    Returns:
        One line; empty where the automatic choice is the motor joints (nothing to warn about).
    """
    chosen = [robot.coordinates[i] for i in robot.independent_indices]
    A = robot.rows_at(robot.neutral()).A
    rank = int(np.linalg.matrix_rank(A)) if A.size else 0
    motors = []
    for m in robot.motors:
        label = robot.spec.labels.get(m.joint, m.joint)
        if label in robot.coordinates and label not in motors:
            motors.append(label)
    idx = [robot.coordinates.index(c) for c in motors]
    rest = [i for i in range(robot.nq) if i not in idx]
    valid = len(idx) == robot.nq - rank and (not A.size or int(np.linalg.matrix_rank(A[:, rest])) == rank)
    if valid and set(motors) == set(chosen):
        return ""
    suggestion = motors if valid else None
    text = (f"{path}: no 'independent' given: the independent velocities are those of {', '.join(chosen)} (chosen "
            "automatically: best conditioned at the neutral configuration); to choose them, add independent = "
            f"[{', '.join(repr(c) for c in (suggestion or chosen))}]")
    return text + (" (the motor joints)" if suggestion else "") + " to the file"


class _sliding_rows:  # noqa: N801 (used as a statement: held = _sliding_rows(robot) ... held.restore())
    """Put a robot's stick-slip wheels in their sliding phase (only the normal row constrains) until
    :meth:`restore`: the freest phase, which bounds the independent velocities a stick-slip vehicle may be given
    (all sticking it may be held, with none free)."""

    def __init__(self, robot) -> None:
        from ..contact.stick_slip_wheel import stick_slip_wheels

        self.wheels = stick_slip_wheels(robot)
        self.phases = [(w.phase, getattr(w, "direction", None)) for w in self.wheels]
        for w in self.wheels:
            w.set_phase("slide", np.array([1.0, 0.0]))

    def restore(self) -> None:
        for w, (phase, direction) in zip(self.wheels, self.phases):
            w.set_phase(phase, direction)


def read(
    path: str | Path,
    urdf: str | Path | None = None,
    xacro_args: dict[str, str] | None = None,
    package_dirs=(),
    packages: dict[str, str] | None = None,
    twist: str | None = None,
) -> ConstraintFile:
    """Read and validate a constraint file.

    Args:
        path: The TOML file.
        urdf: The URDF/Xacro description (overrides the file's ``urdf``); a relative path is relative to the
            current directory; ``package://PKG/...`` is resolved with the packages (:mod:`robotdyn.description.ros_packages`).
        xacro_args: Xacro arguments (override the file's ``xacro_args``).
        package_dirs: Extra directories searched for ROS packages (``$(find)``, ``package://``).
        packages: Extra ROS packages by name (name -> directory; override the file's ``[packages]``).
        twist: Independent velocities that are a body twist instead (overrides the file's ``independent`` and
            ``twist``): ``FRAME`` (components vx vy wz) or ``FRAME:vx,vy,wz``.

    Returns:
        The :class:`ConstraintFile` (its ``SPEC`` and ``SCENARIOS``; :meth:`ConstraintFile.robot` builds it).

    Raises:
        ConstraintFileError: one line naming the file, the entry and what was expected.

    Example:
        >>> from pathlib import Path
        >>> import robotdyn
        >>> from robotdyn.interfaces.constraint_file import read
        >>> cf = read(Path(robotdyn.__file__).parents[1] / "examples" / "quasimoro.toml")
        >>> [w.name for w in cf.SPEC.wheels], [m.name for m in cf.SPEC.motors]
        (['wheel_A', 'wheel_B'], ['m1', 'm2'])
    """
    path = Path(path)
    r = _Reader(path)
    from ..input_files import read_text

    if not path.exists() and not path.is_symlink():
        raise ConstraintFileError(f"constraint file not found: {path}")
    try:  # a regular file of bounded size, read at most that far (a FIFO would block, a device never end)
        text = read_text(path, "constraint file", MAX_FILE_BYTES)
    except InputError as exc:
        raise ConstraintFileError(str(exc)) from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConstraintFileError(f"{path}: not valid TOML: {exc}") from None
    except UnicodeDecodeError:
        raise ConstraintFileError(f"{path}: not UTF-8 text; expected a TOML constraint file") from None
    except OSError as exc:
        raise ConstraintFileError(f"{path}: cannot read: {exc.strerror}") from None
    except RecursionError:
        raise ConstraintFileError(f"{path}: not valid TOML: nested too deeply; expected a constraint file of "
                                  "ordinary depth") from None
    from .constraint_schema import schema_problem

    problem = schema_problem(data)  # types, shapes, ranges and keys, before anything reads a value
    if problem is not None:
        raise ConstraintFileError(f"{path}: {problem}")
    try:
        return _read(path, r, data, urdf, xacro_args, package_dirs, packages or {}, twist)
    except (TypeError, AttributeError, KeyError, IndexError, ValueError, RecursionError) as exc:
        if isinstance(exc, RobotDynError):
            raise
        # the last line of defence: a value of a shape the reader did not expect is an error of the file
        raise ConstraintFileError(f"{path}: malformed constraint file ({type(exc).__name__}: "
                                  f"{' '.join(str(exc).split())}); see the format in robotdyn/interfaces/constraint_file.py"
                                  ) from None


class _Context:
    """What the steps of :func:`_read` share: the reader, the parsed TOML, and what earlier steps found (the
    description, its tree, locked joints, coordinate names), with the checks of a frame, joint or coordinate name.

    Args:
        path: The constraint file.
        r: Its :class:`_Reader`.
        data: The parsed TOML.
    """

    def __init__(self, path: Path, r: _Reader, data: dict) -> None:
        self.path, self.r, self.data = path, r, data
        self.base = path.resolve().parent

    def frame(self, where: str, name, what: str) -> str:
        """A frame of the description (a link, a joint or a frame of the root's own coordinates)."""
        name = self.r.string(where, name, what)
        if name not in self.frames:
            self.r.fail(where, f"{what}: no frame named {name!r} in {self.desc.name}{_suggest(name, self.frames)}")
        return name

    def joint(self, where: str, name, what: str, movable: bool = True) -> str:
        """A joint of the description (with ``movable``, not a fixed one)."""
        r, joints = self.r, self.tree.joints
        name = r.string(where, name, what)
        if name not in joints and not joints:  # e.g. a file of Xacro macros that nothing calls
            r.fail(where, f"{what}: no joint named {name!r} in {self.desc.name}, which has no joints at all; expected "
                   "the description's top-level file (a file of Xacro macros defines a robot only where it is called)")
        if name not in joints:
            r.fail(where, f"{what}: no joint named {name!r} in {self.desc.name}{_suggest(name, joints)}")
        if movable and joints[name]["type"] == "fixed":
            r.fail(where, f"{what}: joint {name!r} is fixed in {self.desc.name}; expected a moving joint")
        return name

    def body_of_frame(self, name: str) -> str | None:
        """The rigid body (its representative link) a frame is on."""
        if name in self.tree.joints:
            return self.body[self.tree.joints[name]["child"]]
        return self.body.get(name)

    def coordinate(self, where: str, name) -> str:
        """A coordinate of the robot (by joint name or label), not a locked one."""
        name = self.r.string(where, name, "coordinate")
        if name in self.locked:
            self.r.fail(where, f"coordinate {name!r} is locked")
        if name not in self.names:
            self.r.fail(where, f"no coordinate named {name!r}{_suggest(name, self.names)}; coordinates are "
                               f"{', '.join(self.names)}")
        return name


def _read(path: Path, r: _Reader, data: dict, urdf, xacro_args, package_dirs, packages, twist) -> ConstraintFile:
    """The body of :func:`read`, on the parsed TOML data: one step per table of the file, in the order that
    decides which of several problems is reported."""
    r.keys("", data, TOP_KEYS)
    cx = _Context(path, r, data)
    _description(cx, urdf, xacro_args, package_dirs, packages)
    params = _parameters(cx)
    _tree(cx, params)
    _locked(cx)
    massless = _massless(cx)
    cx.body = cx.tree.body_of(cx.locked)
    _labels(cx)
    wheels = _wheels(cx, {p.name: p.default for p in params})
    closures = _closures(cx)
    motors = _motors(cx)
    springs = _springs(cx)
    urdf_damping = cx.data.get("urdf_damping", True)
    if not isinstance(urdf_damping, bool):
        r.fail("urdf_damping", f"{urdf_damping!r}; expected true (the URDF's joint <dynamics damping> applied, the "
                               "default) or false")
    independent = _independent(cx)
    neutral = _neutral(cx)
    terrain = _terrain(cx)
    root_height = _root_height(cx)
    operational, independent = _twist(cx, twist, independent)
    spec = RobotSpec(
        name=r.string("name", data.get("name", path.stem), "name"),
        title=str(data.get("title", f"{path.stem} (from {path.name} and {cx.desc.name})")),
        xacro=cx.desc,
        root=cx.root,
        parameters=params,
        wheels=wheels,
        closures=closures,
        motors=motors,
        labels=dict(cx.labels),
        independent=independent,
        terrain=terrain,
        paper=str(data.get("paper", "")),
        neutral=neutral,
        xacro_args=cx.xargs,
        package_dirs=cx.pdirs,
        locked=cx.locked,
        massless=massless,
        packages=cx.named,
        root_height=root_height,
        operational=operational,
        springs=springs,
        urdf_damping=urdf_damping,
    )
    return ConstraintFile(path, spec, _scenarios(cx, motors, operational))


def _description(cx: _Context, urdf, xacro_args, package_dirs, packages) -> None:
    """``package_dirs``, ``[packages]``, ``urdf``, ``root`` and ``[xacro_args]``: sets ``cx.pdirs``, ``cx.named``,
    ``cx.index``, ``cx.desc``, ``cx.root``, ``cx.xargs`` and ``cx.declared`` (the description's Xacro arguments)."""
    r, data, base = cx.r, cx.data, cx.base
    listed = r.strings("package_dirs", data.get("package_dirs", []), "package_dirs")
    try:  # a loop of symbolic links is one line naming the entry (never a RuntimeError)
        pdirs = [str(resolved(base / d, "package_dirs")) for d in listed]
        pdirs += [str(resolved(d, "--package")) for d in package_dirs]
    except InputError as exc:
        r.fail("package_dirs", str(exc))
    for d in pdirs:
        if not Path(d).is_dir():
            r.fail("package_dirs", f"{d}: no such directory; expected directories holding ROS packages (or --package "
                                   "DIR)")
    pkg_table = data.get("packages", {})
    r.keys("packages", pkg_table, list(pkg_table))
    dirs = {k: r.string(f"packages.{k}", v, "directory") for k, v in pkg_table.items()}
    try:
        named = {k: str(resolved(base / v, f"packages.{k}")) for k, v in dirs.items()}
        named.update({k: str(resolved(v, f"--package {k}")) for k, v in packages.items()})
    except InputError as exc:
        r.fail("packages", str(exc))
    try:
        index = PackageIndex.create(named, pdirs)
    except RobotDynError as exc:
        r.fail("packages", str(exc))
    if urdf is not None:
        desc = resolve_path(str(urdf), Path.cwd(), pdirs, index)
    elif "urdf" in data:
        try:
            desc = resolve_path(r.string("urdf", data["urdf"], "urdf"), base, pdirs, index)
        except ConstraintFileError as exc:
            r.fail("urdf", str(exc))
    else:
        r.fail("", "no description: give --urdf FILE or a 'urdf' key in the file")
    root = data.get("root", "planar")
    if root not in ROOT_KINDS:
        r.fail("root", f"{root!r}{_suggest(root, ROOT_KINDS)}; expected one of {', '.join(ROOT_KINDS)}")
    file_args = data.get("xacro_args", {})
    r.keys("xacro_args", file_args, list(file_args))
    cx.pdirs, cx.named, cx.index, cx.desc, cx.root = pdirs, named, index, desc, root
    cx.xargs = {str(k): str(v) for k, v in {**file_args, **(xacro_args or {})}.items()}
    cx.declared = re.findall(r"<xacro:arg\s+name=\"([^\"]+)\"", desc.read_text(errors="replace"))


def _parameters(cx: _Context) -> list[Parameter]:
    """``[[parameters]]``: each with a default that is a physical value of it, declared once."""
    r = cx.r
    params: list[Parameter] = []
    for i, p in enumerate(r.table_list(cx.data, "parameters")):
        where = f"parameters[{i}]"
        r.keys(where, p, PARAMETER_KEYS)
        name = r.string(where, p.get("name"), "name")
        where = f"parameters[{i}] ({name})"
        if "default" not in p:
            r.fail(where, "missing 'default'")
        choices = p.get("choices")
        if choices is not None:
            choices = tuple(r.strings(where, choices, "choices"))
            if str(p["default"]) not in choices:
                r.fail(where, f"default {p['default']!r} is not one of the choices {', '.join(choices)}")
            default = str(p["default"])
        else:
            default = r.number(where, p["default"], "default")
        use_xacro = p.get("xacro", name in cx.declared)
        if not isinstance(use_xacro, bool):
            r.fail(where, f"xacro = {use_xacro!r}; expected true or false")
        if any(q.name == name for q in params):
            r.fail(where, f"parameter {name!r} is declared twice")
        minimum = p.get("minimum")
        param = Parameter(name, default, str(p.get("unit", "")), str(p.get("description", "")), choices, use_xacro,
                          None if minimum is None else float(minimum))
        try:  # the default itself must be a physical value of the parameter
            param.convert(default)
        except RobotDynError as exc:
            r.fail(where, f"default: {exc}")
        params.append(param)
    return params


def _tree(cx: _Context, params: list[Parameter]) -> None:
    """The Xacro arguments against the parameters and the description, then the expanded description: sets
    ``cx.tree``, ``cx.chain`` (the root's own coordinates) and ``cx.frames``."""
    r, desc, declared = cx.r, cx.desc, cx.declared
    for name in cx.xargs:
        if any(p.name == name and p.xacro for p in params):
            r.fail("xacro_args", f"{name!r} is a parameter of this file; set it with --param {name}=VALUE")
        if name not in declared:
            r.fail("xacro_args", f"{name!r} is not an argument of {desc.name}{_suggest(name, declared)}; expected "
                                 f"one of {', '.join(declared) or '(none declared with <xacro:arg>)'}")
    try:
        text = expand_xacro(desc, {**cx.xargs, **{p.name: p.default for p in params if p.xacro}}, cx.index)
        cx.tree = _Tree.parse(text, declared)
    except RobotDynError as exc:
        raise ConstraintFileError(f"{cx.path}: {exc}") from None
    except (ET.ParseError, AttributeError, ValueError) as exc:
        raise ConstraintFileError(f"{cx.path}: description {desc.name} is not a valid URDF: {exc}") from None
    cx.chain = [name for name, _, _ in _ROOT_CHAINS[cx.root]]
    cx.frames = cx.tree.links + list(cx.tree.joints) + cx.chain


def _locked(cx: _Context) -> None:
    """``[locked]``: joint name patterns and the values they are locked at; sets ``cx.movable`` (the moving
    joints of the description) and ``cx.locked`` (joint -> value)."""
    r, data = cx.r, cx.data
    cx.locked = locked = {}
    lock_table = data.get("locked", {})
    r.keys("locked", lock_table, list(lock_table))
    cx.movable = movable = cx.tree.movable()
    for pattern, value in lock_table.items():
        where = f"locked.{pattern}"
        value = r.number(where, value, "value")
        hits = [j for j in movable if fnmatch.fnmatchcase(j, pattern)]
        if not hits:
            r.fail(where, f"no moving joint of {cx.desc.name} matches {pattern!r}{_suggest(pattern, movable)}")
        for j in hits:
            locked[j] = value


def _massless(cx: _Context) -> list[str]:
    """``massless``: links of the description."""
    massless = cx.r.strings("massless", cx.data.get("massless", []), "massless")
    for name in massless:
        if name not in cx.tree.links:
            cx.r.fail("massless", f"no link named {name!r} in {cx.desc.name}{_suggest(name, cx.tree.links)}")
    return massless


def _labels(cx: _Context) -> None:
    """``[labels]``: distinct new names of coordinates; sets ``cx.labels`` and ``cx.names`` (every name a
    coordinate goes by)."""
    r, chain = cx.r, cx.chain
    labels = cx.data.get("labels", {})
    r.keys("labels", labels, list(labels))
    for j, label in labels.items():
        if j not in chain:
            cx.joint(f"labels.{j}", j, "label")
        r.string(f"labels.{j}", label, "label")
    coordinates = chain + [j for j in cx.movable if j not in cx.locked]
    seen: dict[str, str] = {}
    for j, label in labels.items():
        if label in seen:
            r.fail(f"labels.{j}", f"label {label!r} is also the label of {seen[label]!r}; expected distinct labels")
        if label != j and label in coordinates:
            r.fail(f"labels.{j}", f"label {label!r} is the name of another coordinate; expected a new name")
        seen[label] = j
    cx.labels = labels
    cx.names = coordinates + [labels[j] for j in labels]


def _wheels(cx: _Context, pvalues: dict) -> list[Wheel]:
    """``[[wheels]]``: one wheel per spin joint (frame), unique names."""
    wheels: list[Wheel] = []
    for i, w in enumerate(cx.r.table_list(cx.data, "wheels")):
        where = f"wheels[{i}]" + (f" ({w['name']})" if isinstance(w, dict) and "name" in w else "")
        wheel, spin = _wheel(cx, where, w, pvalues)
        for other in wheels:
            if other.name == wheel.name:
                cx.r.fail(where, f"a second wheel named {wheel.name!r}; expected unique wheel names")
            if other.frame == wheel.frame:
                cx.r.fail(where, f"wheel centre {wheel.frame!r}" + (f" (spin joint {spin!r})" if spin else "")
                          + f" is also wheel {other.name!r}'s; expected one wheel per spin joint (frame)")
        wheels.append(wheel)
    return wheels


def _wheel(cx: _Context, where: str, w, pvalues: dict) -> tuple[Wheel, str | None]:
    """One ``[[wheels]]`` entry: the wheel and its spin joint (``None``: a frame without one)."""
    r, tree = cx.r, cx.tree
    r.keys(where, w, WHEEL_KEYS)
    if ("joint" in w) == ("frame" in w):
        r.fail(where, "give exactly one of 'joint' (the spin joint) or 'frame' (the wheel centre)")
    spin = None
    if "joint" in w:
        spin = cx.joint(where, w["joint"], "joint", movable=False)
        if tree.joints[spin]["type"] not in ROTATING:
            child = tree.joints[spin]["child"]
            r.fail(where, f"joint {spin!r} is {tree.joints[spin]['type']}; a wheel spins about a revolute or "
                          "continuous joint. For a ball caster, skid or other support without a spin joint, name its "
                          f"centre frame instead: frame = {child!r} (with kind = 'support'; no axis needed)")
        if spin in cx.locked:
            r.fail(where, f"joint {spin!r} is locked; a wheel must spin")
        fname = tree.joints[spin]["child"]
    else:
        fname = cx.frame(where, w["frame"], "frame")
        parents = [n for n, j in tree.joints.items() if j["child"] == fname and j["type"] in ROTATING]
        spin = parents[0] if parents else None
    if "axis" in w:
        axis = w["axis"]
        if not isinstance(axis, list) or len(axis) != 3:
            r.fail(where, f"axis = {axis!r}; expected 3 numbers")
        axis = [r.number(where, a, "axis component") for a in axis]
    elif spin is not None:
        axis = tree.joints[spin]["axis"]
    elif w.get("kind") == "support":  # a ball or skid: any axle horizontal at rest puts the contact straight below
        axis = (tree.rotation(fname).T @ np.array([0.0, 1.0, 0.0])).tolist()  # the world y axis, in the frame
    else:
        r.fail(where, f"frame {fname!r} has no spin joint: give 'axis' (the axle in the wheel frame), or "
                      "kind = 'support' for a ball caster or skid (then no axis is needed)")
    if np.linalg.norm(axis) < 1e-12:
        r.fail(where, f"axis {axis} has zero length; expected the axle direction in the wheel frame")
    if "radius" not in w:
        r.fail(where, "missing 'radius' (a number in m or a parameter name)")
    radius = w["radius"]
    if isinstance(radius, str):
        if radius not in pvalues:
            r.fail(where, f"radius {radius!r} is not a parameter{_suggest(radius, pvalues)}; "
                          "expected a number in m or a declared parameter")
        rv = pvalues[radius]
    else:
        rv = radius = r.number(where, radius, "radius")
    if "radius_joint" in w:
        cx.joint(where, w["radius_joint"], "radius_joint")
    elif not isinstance(rv, (int, float)) or not rv > 0:
        r.fail(where, f"radius {rv!r} is not > 0; expected a positive radius in m")
    elif rv > MAX_RADIUS:
        r.fail(where, f"radius {rv!r} m is above {MAX_RADIUS:g} m; expected a wheel radius in m")
    kind = w.get("kind", "standard")
    if kind not in WHEEL_KINDS:
        r.fail(where, f"kind {kind!r}{_suggest(kind, WHEEL_KINDS)}; expected one of {', '.join(WHEEL_KINDS)}")
    roller = w.get("roller_angle", 0.0)
    if "roller_angle" in w:
        if kind != "omni":
            r.fail(where, "roller_angle is only meaningful for kind = 'omni'")
        if not (isinstance(roller, str) and roller in pvalues):
            roller = r.angle(where, roller, "roller_angle")
    friction = w.get("friction", "rolling")
    if not isinstance(friction, str):
        r.fail(where, f"friction = {friction!r}; expected one of rolling, {', '.join(LAWS)}")
    numbers = {key: r.number(where, w[key], key) for key in ("mu", "slip_velocity", "stiffness", "normal_stiffness",
                                                             "normal_damping", "contact_exponent") if key in w}
    numbers.update({key: w[key] for key in ("contact", "contact_law") if key in w})
    slip = w.get("slip", "both")
    if slip not in SLIP_DIRECTIONS:
        r.fail(where, f"slip = {slip!r}; expected one of {', '.join(SLIP_DIRECTIONS)}")
    wheel = Wheel(fname, radius, tuple(float(a) for a in axis), kind if kind in ("omni", "support") else "standard",
                  roller, w.get("radius_joint"), w.get("name", fname), friction=friction, slip=slip, **numbers)
    try:  # the friction keys' physics (mu >= 0, a known law with its parameters) in one line
        if wheel.contact == "rigid":
            _check_friction(wheel)
            if "contact_law" in w or "contact_exponent" in w:
                raise InputError("contact_law/contact_exponent need contact = 'compliant'")
    except InputError as exc:
        r.fail(where, str(exc))
    return wheel, spin


def _check_friction(wheel: Wheel) -> None:
    """A wheel's friction keys: a known law with its parameters on a standard wheel, mu >= 0.

    Raises:
        InputError: They do not fit (one line, without the entry's name).
    """
    friction, slip = wheel.friction, wheel.slip
    if friction != "rolling":
        if wheel.kind != "standard":
            raise InputError(f"friction law {friction!r} on a {wheel.kind} wheel; expected a standard wheel "
                             "(support wheels are frictionless, omni wheels roll on their rollers)")
        make_law(friction, wheel.mu, wheel.slip_velocity, wheel.stiffness, wheel.name)
        if friction == "stick_slip" and slip != "both":
            raise InputError("slip = 'lateral' with friction = 'stick_slip'; exact stick-slip switches the "
                             "whole tangential force (expected slip = 'both')")
    elif slip != "both":
        raise InputError("slip = 'lateral' needs friction = 'coulomb' or 'linear'")
    elif wheel.mu is not None and not (math.isfinite(wheel.mu) and wheel.mu >= 0):
        raise InputError(f"mu = {wheel.mu}; expected a friction coefficient >= 0")
    elif wheel.slip_velocity is not None or wheel.stiffness is not None:
        raise InputError("slip_velocity/stiffness need friction = 'coulomb' or 'linear'")


def _closures(cx: _Context) -> list[Closure]:
    """``[[closures]]``: two frames on different bodies and the components they close."""
    r, chain = cx.r, cx.chain
    closures: list[Closure] = []
    for i, c in enumerate(r.table_list(cx.data, "closures")):
        where = f"closures[{i}]" + (f" ({c['name']})" if isinstance(c, dict) and "name" in c else "")
        r.keys(where, c, CLOSURE_KEYS)
        f1, f2 = cx.frame(where, c.get("frame1"), "frame1"), cx.frame(where, c.get("frame2"), "frame2")
        if f1 in chain and f2 in chain:
            r.fail(where, f"{f1!r} and {f2!r} are both frames of the {cx.root} root's own coordinates; a closure "
                          "joins two bodies of the description")
        if f1 not in chain and f2 not in chain and cx.body_of_frame(f1) == cx.body_of_frame(f2):
            r.fail(where, f"{f1!r} and {f2!r} are on the same rigid body; a closure joins two different bodies")
        comps = r.strings(where, c.get("components", ["x", "y", "z"]), "components")
        allowed = ("x", "y", "z", "rx", "ry", "rz")
        bad = [s for s in comps if s not in allowed]
        if bad or not comps or len(set(comps)) != len(comps):
            r.fail(where, f"components {comps} invalid; expected distinct entries of {' '.join(allowed)}")
        closures.append(Closure(f1, f2, tuple(comps), c.get("name")))
    return closures


def _springs(cx: _Context) -> list:
    """``[[springs]]``: a moving joint each (at most one spring per joint), k and c >= 0, a rest position."""
    from ..reduction.joint_springs import JointSpring

    r = cx.r
    out: list = []
    for i, sp in enumerate(r.table_list(cx.data, "springs")):
        where = f"springs[{i}]" + (f" ({sp['name']})" if isinstance(sp, dict) and "name" in sp else "")
        r.keys(where, sp, SPRING_KEYS)
        j = cx.joint(where, sp.get("joint"), "joint")
        if j in cx.locked:
            r.fail(where, f"joint {j!r} is locked; a spring needs a moving joint")
        if any(o.joint == j for o in out):
            r.fail(where, f"a second spring on joint {j!r}; expected one spring per joint (add the stiffnesses)")
        numbers = {key: r.number(where, sp[key], key) for key in ("stiffness", "damping", "rest") if key in sp}
        for key in ("stiffness", "damping"):
            if numbers.get(key, 0.0) < 0:
                r.fail(where, f"{key} = {numbers[key]}; expected a number >= 0")
        if "stiffness" not in numbers and "damping" not in numbers:  # a spring that does nothing: a slip of the pen
            r.fail(where, "neither stiffness nor damping given; expected stiffness (N/m or N m/rad) and/or damping")
        out.append(JointSpring(j, name=sp.get("name", j), **numbers))
    return out


def _motors(cx: _Context) -> list[MotorSpec]:
    """``[[motors]]``: a moving joint each, unique names, an optional reaction frame."""
    r = cx.r
    motors: list[MotorSpec] = []
    for i, m in enumerate(r.table_list(cx.data, "motors")):
        where = f"motors[{i}]" + (f" ({m['name']})" if isinstance(m, dict) and "name" in m else "")
        r.keys(where, m, MOTOR_KEYS)
        j = cx.joint(where, m.get("joint"), "joint")
        if any(mm.name == m.get("name", j) for mm in motors):
            r.fail(where, f"a second motor named {m.get('name', j)!r}; expected unique motor names")
        if j in cx.locked:
            r.fail(where, f"joint {j!r} is locked; a motor needs a moving joint")
        reaction = m.get("reaction")
        if reaction is not None:
            reaction = cx.frame(where, reaction, "reaction")
        motors.append(MotorSpec(r.string(where, m.get("name", j), "name"), j, reaction))
    return motors


def _independent(cx: _Context) -> list[str] | None:
    """``independent``: distinct coordinates (``None``: chosen automatically)."""
    r = cx.r
    independent = cx.data.get("independent")
    if independent is not None:
        independent = [cx.coordinate("independent", x) for x in r.strings("independent", independent, "independent")]
        twice = sorted({x for x in independent if independent.count(x) > 1})
        if twice:
            r.fail("independent", f"{', '.join(map(repr, twice))} listed twice; expected distinct coordinates")
        if not independent:
            r.fail("independent", "empty; expected the names of the independent coordinates (or no 'independent' "
                                  "key: chosen automatically)")
    return independent


def _neutral(cx: _Context) -> dict[str, float]:
    """``[neutral]``: values by coordinate name."""
    r = cx.r
    neutral_table = cx.data.get("neutral", {})
    r.keys("neutral", neutral_table, list(neutral_table))
    return {cx.coordinate(f"neutral.{k}", k): r.number(f"neutral.{k}", v, "value") for k, v in neutral_table.items()}


def _terrain(cx: _Context) -> Terrain | None:
    """``[terrain]``: a kind of :data:`TERRAINS` and its constructor's arguments (``None``: no table)."""
    r, data = cx.r, cx.data
    if "terrain" not in data:
        return None
    t = dict(data["terrain"]) if isinstance(data["terrain"], dict) else r.fail("terrain", "expected a table")
    kind = t.pop("kind", "flat")
    if not isinstance(kind, str):
        r.fail("terrain", f"kind = {kind!r}; expected one of {', '.join(TERRAINS)}")
    if kind not in TERRAINS:
        r.fail("terrain", f"kind {kind!r}{_suggest(kind, TERRAINS)}; expected one of {', '.join(TERRAINS)}")
    cls = TERRAINS[kind]
    allowed = [a for a in inspect.signature(cls.__init__).parameters if a != "self"]
    r.keys(f"terrain ({kind})", t, allowed)
    try:
        return cls(**{k: r.number("terrain", v, k) for k, v in t.items()})
    except TypeError as exc:
        r.fail(f"terrain ({kind})", f"{exc}; arguments are {', '.join(allowed)}")


def _root_height(cx: _Context) -> float | None:
    """``root_height`` [m] (``None``: "auto")."""
    r = cx.r
    root_height = cx.data.get("root_height", "auto")
    if root_height == "auto":
        return None
    root_height = r.number("root_height", root_height, "root_height")
    if cx.root == "fixed":
        r.fail("root_height", "a fixed root has no height; expected root = 'planar' or 'floating'")
    if cx.root == "floating":  # (it was ignored): a floating root's height is a coordinate
        r.fail("root_height", f"{root_height:g} m: a floating root's height is its coordinate z; expected neutral = "
                              f"{{ z = {root_height:g} }} (and q0 of the scenarios), or root = 'planar'")
    if abs(root_height) > MAX_RADIUS:
        r.fail("root_height", f"{root_height:g} m; expected the root link's height above the ground in m")
    return root_height


def _twist(cx: _Context, twist: str | None, independent: list[str] | None) -> tuple:
    """``[twist]`` (or the ``twist`` argument of :func:`read`, which overrides it and ``independent``): the
    operational velocities (``None``: none) and the independent coordinates that remain."""
    r = cx.r
    twist_table = cx.data.get("twist")
    if twist is not None:
        frame_name, _, comps = str(twist).partition(":")
        twist_table = {"frame": frame_name, **({"components": comps.replace(",", " ")} if comps else {})}
        independent = None
    if twist_table is None:
        return None, independent
    from ..reduction.operational_space import COMPONENTS, OperationalVelocities

    r.keys("twist", twist_table, TWIST_KEYS)
    if independent is not None:
        r.fail("twist", "give either 'independent' (coordinates) or 'twist' (a body twist), not both")
    tframe = cx.frame("twist", twist_table.get("frame"), "frame")
    comps = r.strings("twist", twist_table.get("components", ["vx", "vy", "wz"]), "components")
    if not comps or len(set(comps)) != len(comps) or any(c not in COMPONENTS for c in comps):
        r.fail("twist", f"components {comps}; expected distinct entries of {' '.join(COMPONENTS)}")
    axes = twist_table.get("axes", "body")
    if axes not in ("body", "local", "world"):
        r.fail("twist", f"axes = {axes!r}; expected 'body' (the frame's own axes) or 'world'")
    tnames = r.strings("twist", twist_table.get("names", comps), "names")
    if len(tnames) != len(comps) or len(set(tnames)) != len(tnames):
        r.fail("twist", f"names {tnames}; expected {len(comps)} distinct names, one per component")
    return OperationalVelocities(tframe, tuple(comps), "world" if axes == "world" else "local", tnames), independent


def _scenarios(cx: _Context, motors: list[MotorSpec], operational) -> dict[str, Scenario]:
    """``[[scenarios]]``: constant torques [N m or N] (a list or a table by motor name), q0 by coordinate, nu0 by
    coordinate or twist component."""
    r, labels = cx.r, cx.labels
    scenarios: dict[str, Scenario] = {}
    for i, s in enumerate(r.table_list(cx.data, "scenarios")):
        where = f"scenarios[{i}]"
        r.keys(where, s, SCENARIO_KEYS)
        name = r.string(where, s.get("name"), "name")
        if name in scenarios:
            r.fail(where, f"a second scenario named {name!r}; expected unique scenario names")
        where = f"scenarios[{i}] ({name})"
        for key in ("q0", "nu0"):
            if not isinstance(s.get(key, {}), dict):
                r.fail(where, f"{key} = {s[key]!r}; expected a table of values by coordinate name")
        t_end = r.number(where, s.get("t_end"), "t_end")
        if t_end <= 0:
            r.fail(where, f"t_end = {t_end}; expected a positive duration in s")
        tau = s.get("torque", [0.0] * len(motors))
        motor_names = [m.name for m in motors]
        if isinstance(tau, dict):  # by motor name, the others zero
            r.keys(f"{where}: torque", tau, motor_names)
            tau = [tau.get(name, 0.0) for name in motor_names]
        if not isinstance(tau, list) or len(tau) != len(motors):
            r.fail(where, f"torque = {tau!r}; expected {len(motors)} numbers ({', '.join(motor_names)}) or a table "
                          "by motor name")
        tau = np.array([r.number(where, x, "torque") for x in tau])
        q0 = {cx.coordinate(where, k): r.number(where, v, k) for k, v in s.get("q0", {}).items()}
        nu0 = {}
        for k, v in s.get("nu0", {}).items():
            if operational is not None:
                if k not in operational.names:
                    r.fail(where, f"nu0 {k!r} is not a twist component; expected one of {', '.join(operational.names)}")
                nu0[k] = r.number(where, v, k)
                continue
            label = cx.coordinate(where, k)
            nu0[f"{labels.get(label, label)}_dot"] = r.number(where, v, k)
        scenarios[name] = Scenario(name, str(s.get("description", f"constant torques {tau.tolist()}")), t_end,
                                   Constant(tau), q0, nu0)  # torques as data: simulated compiled
    return scenarios


def load_robot(
    path: str | Path,
    urdf: str | Path | None = None,
    xacro_args: dict[str, str] | None = None,
    params: dict | None = None,
    terrain: Terrain | None = None,
    package_dirs=(),
) -> Robot:
    """Read a constraint file (see :func:`read`) and build its :class:`~robotdyn.robot.Robot`.

    Args:
        path: The TOML constraint file.
        urdf: The URDF/Xacro description, overriding the file's ``urdf`` (default ``None``).
        xacro_args: Xacro arguments by name (strings), overriding the file's ``xacro_args``.
        params: Parameter values by name (the file's ``[[parameters]]``; default ``None``: their defaults).
        terrain: A :class:`~robotdyn.constraints.terrain.Terrain` replacing the file's (default ``None``).
        package_dirs: Extra directories searched for ROS packages.

    Returns:
        The :class:`~robotdyn.robot.Robot`, the same object :func:`robotdyn.load` returns for a built-in robot.

    Raises:
        ConstraintFileError: One line naming the file, the entry and what was expected.

    Example:
        >>> from pathlib import Path
        >>> import robotdyn
        >>> from robotdyn.interfaces.constraint_file import load_robot
        >>> examples = Path(robotdyn.__file__).parents[1] / "examples"
        >>> robot = load_robot(examples / "quasimoro.toml")
        >>> robot.velocity_names
        ['theta1_dot', 'theta2_dot', 'theta3_dot']
    """
    return read(path, urdf, xacro_args, package_dirs).robot(params, terrain)


__all__ = ["ConstraintFile", "ConstraintFileError", "read", "load_robot", "package_search_dirs", "resolve_path"]
