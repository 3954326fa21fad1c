"""A robot: description + parameters + constraints + motors, with the dynamics API.

:class:`RobotSpec` is the declarative description of a robot (what a robot module or a user's constraint file
supplies); :class:`Robot` builds it for given parameter values and evaluates full and reduced dynamics,
forward/inverse dynamics and energies. Configurations are natural coordinates named by
:attr:`Robot.coordinates` (m, rad); velocities of the minimal model are the independent velocities named by
:attr:`Robot.velocity_names` (m/s, rad/s).
"""

from __future__ import annotations

import threading
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pinocchio as pin

from .reduction.actuation import Motor
from .constraints.constraint import ConstraintRows, KinematicState
from .description.urdf import _ROOT_CHAINS, URDF_DIR, Description, build_description, expand_xacro
from .reduction.dynamics import energy
from .errors import ConstraintError, DescriptionError, InputError, NonFiniteError, RobotDynWarning
from .contact.friction import make_law
from .inputs import MAX_ACCELERATION, MAX_ANGLE, MAX_FORCE, MAX_POSITION, MAX_VELOCITY, as_vector, within
from .constraints.loop_closure import LoopClosure
from .reduction.projection import auto_independent
from .fast.dispatch import reduce
from .reduction.reduced_dynamics import ReducedDynamics, checked, solve_mass
from .constraints.rolling_contact import OmniWheel, RollingWheel, SupportWheel
from .contact.sliding import SlippingWheel, sliding_now
from .contact.sliding import forward as forward_sliding
from .contact.stick_slip_wheel import StickSlipWheel
from .contact.applied_forces import has_applied, reduced_applied, stored_energy
from .reduction.joint_springs import build_springs
from .constraints.terrain import FlatTerrain, Terrain


PARAMETER_LIMITS = {"m": 1e4, "kg": 1e9, "kg m^2": 1e9, "m/s^2": 1e4, "rad": MAX_ANGLE}
"""Largest magnitude of a parameter by unit (beyond these no robot is described: the dynamics only overflow; an
angle beyond one turn is a unit mistake)."""


@dataclass
class Parameter:
    """A physical parameter of a robot: name, default, unit, meaning.

    Attributes:
        name: The name used by ``--param NAME=VALUE``, ``sweep --vary`` and ``Robot(spec, params)``.
        default: The default value (a number in ``unit``, or one of ``choices``).
        unit: The unit as text (``m``, ``kg``, ``kg m^2``, ``rad``, ``m/s^2``, ``-``; empty for a choice); masses
            and inertias (``kg``, ``kg m^2``) are >= 0 unless ``minimum`` says otherwise.
        description: One line shown by ``robotdyn info``.
        choices: The allowed strings of a categorical parameter (``None``: a number).
        xacro: Whether the value is passed to the Xacro description as an argument of the same name (``False``: it
            is used only by the robot's Python or constraint file, e.g. g).
        minimum: The smallest physical value in ``unit`` (default ``None``: 0 for masses and inertias, else none).
        positive: Whether the value must be > 0 (a length such as a radius, a link length or a track).
        maximum: The largest physical value in ``unit`` (``None``: only the unit's limit,
            :data:`PARAMETER_LIMITS`), e.g. :data:`~robotdyn.inputs.MAX_FRICTION` for a friction coefficient.
    """

    name: str
    default: float | str
    unit: str = ""
    description: str = ""
    choices: tuple[str, ...] | None = None
    xacro: bool = True
    minimum: float | None = None  # smallest physical value (default: 0 for masses and inertias, by their unit)
    positive: bool = False  # the value must be > 0 (a length such as a radius, a link length or a track)
    maximum: float | None = None  # largest physical value (e.g. a friction coefficient: MAX_FRICTION)

    def convert(self, value) -> float | str:
        """Validate and convert a user value.

        Args:
            value: A number (or a string that parses as one) in the parameter's unit, or one of ``choices``.

        Returns:
            The value as a float (or the choice as a string).

        Raises:
            InputError: Not a number, not finite, not one of the choices, <= 0 where ``positive``, below ``minimum``,
                or beyond :data:`PARAMETER_LIMITS` for its unit.
        """
        if self.choices is not None:
            if str(value) not in self.choices:
                raise InputError(f"parameter {self.name} = {value!r}; expected one of {', '.join(self.choices)}")
            return str(value)
        try:
            out = float(value)
        except (TypeError, ValueError):
            raise InputError(f"parameter {self.name} = {value!r} is not a number [{self.unit}]") from None
        if not np.isfinite(out):
            raise InputError(f"parameter {self.name} = {value!r} is not finite; expected a number [{self.unit}]")
        if self.positive and not out > 0:
            raise InputError(f"parameter {self.name} = {out:g} {self.unit}; expected a value > 0 {self.unit} "
                             f"({self.description or self.name})")
        low = self.minimum if self.minimum is not None else (0.0 if self.unit in ("kg", "kg m^2") else None)
        if low is not None and out < low:
            raise InputError(f"parameter {self.name} = {out:g} {self.unit}; expected a value >= {low:g} "
                             f"({self.description or self.name})")
        if self.maximum is not None and out > self.maximum:
            raise InputError(f"parameter {self.name} = {out:g} {self.unit}; expected a value <= {self.maximum:g} "
                             f"({self.description or self.name})")
        limit = PARAMETER_LIMITS.get(self.unit)
        if limit is not None and abs(out) > limit:
            raise InputError(f"parameter {self.name} = {out:g} {self.unit}; expected a magnitude <= {limit:g} "
                             f"{self.unit} ({self.description or self.name})")
        return out


@dataclass
class Wheel:
    """A wheel: its frame (centre), radius (number or parameter name), axle axis in the frame, kind.

    Attributes:
        frame: The frame (link) whose origin is the wheel centre.
        radius: Radius [m] (> 0), or the name of a :class:`Parameter` giving it.
        axis: Axle direction in the wheel frame's axes (3 numbers, normalised when built; default y).
        kind: ``standard`` (rolls without slipping: longitudinal, lateral and normal rows), ``omni`` (rolls along
            its rollers only: driving and normal rows) or ``support`` (touches the ground only: the normal row).
        roller_angle: Omni wheels: angle [rad] of the rollers' constrained direction from the rolling direction
            (0: a 90-degree omni wheel; pi/4: a mecanum wheel), or a parameter name.
        radius_joint: A prismatic joint whose coordinate [m] adds to the radius (adaptable wheels), or ``None``.
        name: Name in row labels, loads and messages (default ``None``: the frame name).
        mu: Friction coefficient (>= 0) for traction checks and the coulomb law; ``None``: not given.
        friction: ``rolling`` (no slip, default), ``coulomb``, ``linear`` or ``stick_slip``
            (:mod:`robotdyn.contact.friction`).
        slip_velocity: Coulomb law's regularisation velocity [m/s] (``None``: the law's default).
        stiffness: Linear law's slip stiffness [s/m] (``None``: the law's default).
        slip: With a friction law: ``both`` tangential directions follow it, or ``lateral`` (rolls along its
            rolling direction, only the lateral force follows the law).
        normal_stiffness: Normal (radial) stiffness k [N/m] (> 0; N/m^n for ``contact_law = "hunt_crossley"``);
            ``None``: the default rule of :mod:`robotdyn.contact.compliance` (1 mm static deflection under an
            equal share of the weight).
        normal_damping: Normal (radial) damping c [N s/m] (>= 0; :math:`\\lambda` [N s/m^(n+1)] for
            hunt_crossley); ``None``: the default rule (damping ratio 0.3 for linear, :math:`1.5\\alpha k` for
            hunt_crossley).
        contact: ``rigid`` (default: the normal row is a constraint) or ``compliant`` (a force law of the
            penetration: the wheel can fly and land; needs friction ``coulomb`` or ``linear`` with slip ``both``,
            except on a support; :mod:`robotdyn.contact.compliant_contact`).
        contact_law: A compliant wheel's normal law: ``linear`` (default) or ``hunt_crossley``.
        contact_exponent: hunt_crossley's exponent n (>= 1; ``None``: 1.5).
    """

    frame: str
    radius: float | str
    axis: tuple[float, float, float] = (0.0, 1.0, 0.0)
    kind: str = "standard"
    roller_angle: float | str = 0.0
    radius_joint: str | None = None
    name: str | None = None
    mu: float | None = None  # friction coefficient (traction checks, friction laws); None: not given
    friction: str = "rolling"  # rolling (no slip) | coulomb | linear (robotdyn.contact.friction)
    slip_velocity: float | None = None  # coulomb law's regularisation scale [m/s]
    stiffness: float | None = None  # linear law's slip stiffness [s/m]
    slip: str = "both"  # with a friction law: both tangential directions slip, or only the lateral one
    normal_stiffness: float | None = None  # radial (normal) stiffness [N/m]; None: robotdyn.contact.compliance's rule
    normal_damping: float | None = None  # radial (normal) damping [N s/m]; None: robotdyn.contact.compliance's rule
    contact: str = "rigid"  # rigid (the normal row is a constraint) | compliant (a force law: it can fly and land)
    contact_law: str = "linear"  # compliant contact's normal law: linear | hunt_crossley (contact.compliant_contact)
    contact_exponent: float | None = None  # hunt_crossley's exponent n (default 1.5)


@dataclass
class Closure:
    """A loop closure between two frames, closing the given components (in frame1's axes).

    Attributes:
        frame1: The first frame; its axes express the closed components.
        frame2: The second frame, on another body, coinciding with ``frame1`` in the closed components.
        components: Which of ``x y z`` (translations) and ``rx ry rz`` (rotations) are closed (default: the three
            translations: a spherical joint).
        name: Name in row labels and messages (default ``None``: from the frames).
    """

    frame1: str
    frame2: str
    components: Sequence[str] = ("x", "y", "z")
    name: str | None = None


@dataclass
class MotorSpec:
    """A motor on a joint, reacting on ``reaction`` (a link) or on the joint's parent.

    Attributes:
        name: The motor's name (torque vectors are ordered as the spec's motors).
        joint: The driven joint (its torque [N m] or force [N] acts along the joint axis).
        reaction: The link on which the reaction torque acts (default ``None``: the joint's parent link).
    """

    name: str
    joint: str
    reaction: str | None = None


@dataclass
class RobotSpec:
    """Everything needed to build a robot.

    Attributes:
        name: Registry name (``robotdyn list``).
        title: One-line human description.
        xacro: The Xacro/URDF file (relative paths are under ``urdf/``).
        root: ``"fixed"``, ``"planar"`` or ``"floating"``.
        parameters: The physical parameters with defaults and units.
        wheels, closures, motors: The constraint and actuator declarations.
        labels: Display name of a coordinate for a joint name (e.g. ``wheel_left_joint -> theta_L``).
        independent: Coordinate labels whose velocities are the independent ones (``None``: automatic).
        terrain: A terrain, or a function of the parameter values returning one (default: flat z = 0).
        paper: A short reference of the robot's paper (authors, title; full references: ``docs/bibliography.md``).
        neutral: Coordinate values of a valid configuration (default all zero), used e.g. by ``info``.
        xacro_args: Fixed xacro arguments (name -> string) that are not parameters (e.g. from ``--xacro-arg``).
        package_dirs: Directories where ``package://`` URIs (meshes) are resolved.
        locked: Joints replaced by fixed ones at the given values (name -> m or rad), e.g. an arm held still.
        massless: Links whose URDF inertial is ignored.
        constraints: Factories ``make(robot) -> Constraint`` for constraints beyond wheels and closures (e.g. a
            joint coupling, or wheels whose kind depends on the parameters); called with the robot under
            construction (description, params and terrain are set).
        operational: Minimal velocities that are not a subset of v (e.g. a platform twist in body axes): an object
            with ``build(description)`` returning a model with ``names`` and ``reduce(robot, q, nu, coriolis)``,
            such as :class:`robotdyn.reduction.operational_space.OperationalVelocities`; ``None``: ``independent`` is used.
        packages: ROS packages by name (name -> directory) for ``$(find NAME)`` and ``package://NAME/`` (see
            :mod:`robotdyn.description.ros_packages`; ``package_dirs``, ``ROS_PACKAGE_PATH`` and ``AMENT_PREFIX_PATH`` are
            searched for the others).
        root_height: Height [m] of the plane in which a planar root moves its link (the root link's height above
            the ground, z = 0), or of the reference of a floating root's z; ``None``: found from the wheels for a
            planar root (:meth:`Robot.root_height_from_wheels`; the default of constraint files), 0 otherwise.
        springs: :class:`~robotdyn.reduction.joint_springs.JointSpring` declarations: a spring and damper on a
            joint's coordinate each (at most one per joint; default none).
        urdf_damping: Whether a joint's URDF ``<dynamics damping>`` is applied, as a damper of stiffness 0 on its
            coordinate (default ``True``; :mod:`robotdyn.description.joint_dynamics`).
    """

    name: str
    title: str
    xacro: str | Path
    root: str = "planar"
    parameters: list[Parameter] = field(default_factory=list)
    wheels: list[Wheel] = field(default_factory=list)
    closures: list[Closure] = field(default_factory=list)
    motors: list[MotorSpec] = field(default_factory=list)
    labels: dict[str, str] = field(default_factory=dict)
    independent: list[str] | None = None
    terrain: Terrain | Callable[[dict], Terrain] | None = None
    paper: str = ""
    neutral: dict[str, float] = field(default_factory=dict)
    xacro_args: dict[str, str] = field(default_factory=dict)
    package_dirs: list[str] = field(default_factory=list)
    locked: dict[str, float] = field(default_factory=dict)
    massless: list[str] = field(default_factory=list)
    constraints: list[Callable] = field(default_factory=list)
    operational: object | None = None
    packages: dict[str, str] = field(default_factory=dict)
    root_height: float | None = 0.0
    springs: list = field(default_factory=list)  # robotdyn.reduction.joint_springs.JointSpring declarations
    urdf_damping: bool = True  # a joint's URDF <dynamics damping> applied (robotdyn.description.joint_dynamics)

    def parameter(self, name: str) -> Parameter:
        """The declared parameter called ``name``.

        Args:
            name: A parameter name (``robotdyn info ROBOT`` lists them).

        Returns:
            The :class:`Parameter`.

        Raises:
            InputError: No parameter has that name; the message names the declared ones or, where there are none,
                how to declare them.
        """
        for p in self.parameters:
            if p.name == name:
                return p
        if not self.parameters:
            raise InputError(
                f"unknown parameter {name!r}: {self.name} has no parameters to set or sweep; declare them in its "
                "constraint file as [[parameters]] (name, default, unit) and use them by name (e.g. a wheel's "
                "radius = \"r\"); a number of the URDF itself (a link mass, a length) must be a <xacro:arg> of a "
                ".urdf.xacro description, declared with xacro = true")
        raise InputError(
            f"unknown parameter {name!r} for {self.name}; expected one of {', '.join(p.name for p in self.parameters)}"
            " (to vary another number of the description, make it a <xacro:arg> and declare it under [[parameters]] "
            "with xacro = true)"
        )


class Robot:
    """A built robot.

    Args:
        spec: Its :class:`RobotSpec`.
        params: Parameter overrides (name -> value); unknown names are an error.
        terrain: Terrain override.

    Attributes:
        coordinates: Names of the natural coordinates q (m, rad).
        velocity_names: Names of the independent velocities nu.
        params: Resolved parameter values.
        model, data: The Pinocchio model and data (natural coordinates, nq == nv).
        constraints, motors: The constraint and motor objects.
        implausible_inertias: Links whose inertia is implausible for their mass and size, with their share of the
            effective mass (:mod:`robotdyn.description.inertia_check`; a warning names them on load).
    """

    def __init__(self, spec: RobotSpec, params: dict | None = None, terrain: Terrain | None = None) -> None:
        self.spec = spec
        values = {p.name: p.convert(p.default) for p in spec.parameters}
        for name, value in (params or {}).items():
            values[name] = spec.parameter(name).convert(value)
        self.params = values
        path = Path(spec.xacro)
        if not path.is_absolute():
            path = URDF_DIR / path
        xacro_args = {**spec.xacro_args, **{p.name: values[p.name] for p in spec.parameters if p.xacro}}
        from .description.ros_packages import PackageIndex

        dirs = [str(d) for d in spec.package_dirs]
        self.packages = PackageIndex.create(spec.packages, dirs)
        try:
            self.description: Description = build_description(
                expand_xacro(path, xacro_args, self.packages), spec.root, dirs, spec.locked, spec.massless,
                packages=self.packages, source=path, root_height=spec.root_height or 0.0,
            )
        except DescriptionError as exc:
            if not params:
                raise
            given = ", ".join(f"{k}={v}" for k, v in params.items())
            raise DescriptionError(f"with the parameters {given}: {exc}") from None
        self.model = self.description.model
        self._local = threading.local()  # per-thread Pinocchio data and compiled model (see ``data``)
        self.model.gravity.linear = np.array([0.0, 0.0, -float(values.get("g", 9.81))])
        self.coordinates = [spec.labels.get(j, j) for j in self.description.joint_names]
        self.velocity_labels = [f"{c}_dot" for c in self.coordinates]
        if terrain is None:
            terrain = spec.terrain(values) if callable(spec.terrain) else spec.terrain
        self.terrain = terrain if terrain is not None else FlatTerrain()
        self.constraints = [self._wheel(w) for w in spec.wheels] + [
            LoopClosure(self.description, c.frame1, c.frame2, c.components, c.name) for c in spec.closures
        ] + [make(self) for make in spec.constraints]
        self.root_height_source = "given" if spec.root_height is not None else "none"
        if spec.root_height is None and spec.root == "planar":
            height, _ = self.root_height_from_wheels()
            if height:  # the twin and copies of this robot (e.g. contact forces' floating twin) keep this height
                self.description.set_root_height(height)
                self.spec = spec = replace(spec, root_height=height)
                self.root_height_source = "found from the wheels"
        self.motors = [Motor(self.description, m.name, m.joint, m.reaction) for m in spec.motors]
        from .description.joint_dynamics import urdf_dampers

        dampers = urdf_dampers(self.model) if spec.urdf_damping else []  # the URDF's <dynamics damping>, applied
        self.springs = build_springs(self, spec.springs, dampers)  # robotdyn.reduction.joint_springs
        if spec.independent is not None:
            self.independent_indices = np.array([self.coordinate_index(c) for c in spec.independent], dtype=int)
        else:
            self.independent_indices = auto_independent(self.rows_at(self.neutral()).A)
        self.velocity_names = [self.velocity_labels[i] for i in self.independent_indices]
        self._projection_hint = None  # the last projection, whose row choice the next one tries first
        self.operational = spec.operational.build(self.description) if spec.operational is not None else None
        if self.operational is not None:
            self.velocity_names = list(self.operational.names)
        from .description.inertia_check import implausible_inertias, message

        self.implausible_inertias = implausible_inertias(self)  # placeholder inertias (issue 24): data, and a warning
        if self.implausible_inertias:
            warnings.warn(message(self.implausible_inertias), RobotDynWarning, stacklevel=2)

    def __getstate__(self) -> dict:
        """Pickle without the per-thread caches (Pinocchio data and compiled models are rebuilt on use), nor a
        traction pass's memory of the reduced model (an instance attribute ``reduced`` over the method,
        :mod:`robotdyn.contact.traction_memo`: a copy made during a pass is the robot as it is outside it)."""
        state = self.__dict__.copy()
        for key in ("_local", "_constraint_set", "_compiled_model", "_floating_twin", "reduced", "_state_bounds"):
            state.pop(key, None)
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._local = threading.local()

    @property
    def data(self) -> pin.Data:
        """Pinocchio's data for the calling thread (each thread gets its own, so that one Robot may be used from
        several threads: Pinocchio's algorithms write their results into it)."""
        data = getattr(self._local, "data", None)
        if data is None:
            data = self._local.data = self.model.createData()
        return data

    def __repr__(self) -> str:
        return (
            f"Robot({self.spec.name!r}, coordinates={self.coordinates}, independent={self.velocity_names}, "
            f"constraints={len(self.constraints)}, motors={[m.name for m in self.motors]})"
        )

    # ----------------------------------------------------------------------------------------------- set-up
    def _value(self, x) -> float:
        return float(self.params[x]) if isinstance(x, str) else float(x)

    def _wheel(self, w: Wheel):
        kw = dict(axis=w.axis, terrain=None, radius_joint=w.radius_joint, name=w.name)
        kw["terrain"] = self.terrain
        name = w.name or w.frame
        if self.model.existFrame(w.frame):  # the body the wheel turns with: a mass with its inertia, or neither
            body = self.model.inertias[self.model.frames[self.model.getFrameId(w.frame)].parentJoint]
            if body.mass == 0 and np.max(np.abs(body.inertia)) > 0:
                raise InputError(f"wheel {name!r}: its body has mass 0 but an inertia (largest entry "
                                 f"{np.max(np.abs(body.inertia)):.3g} kg m^2); expected a positive mass with its "
                                 "inertia, or a massless wheel (mass and inertia 0)")
        if w.contact != "rigid":
            from .contact.compliant_contact import compliant_wheel

            return compliant_wheel(self, w, self._value(w.radius), self._value(w.roller_angle), **kw)
        if w.mu is not None and not (np.isfinite(float(w.mu)) and float(w.mu) >= 0):
            raise InputError(f"wheel {name!r}: mu = {w.mu}; expected a friction coefficient >= 0")
        if w.friction not in ("rolling", None):
            if w.kind != "standard":
                raise InputError(f"wheel {name!r}: friction law {w.friction!r} on a {w.kind} wheel; expected a "
                                 "standard wheel (support wheels are frictionless, omni wheels roll on rollers)")
            law = make_law(w.friction, w.mu, w.slip_velocity, w.stiffness, wheel=name)
            if w.friction == "stick_slip":
                if w.slip != "both":
                    raise InputError(f"wheel {name!r}: slip = {w.slip!r} with friction = 'stick_slip'; exact "
                                     "stick-slip switches the whole tangential force (expected slip = 'both')")
                return StickSlipWheel(self.description, w.frame, self._value(w.radius), law.mu, **kw)
            return SlippingWheel(self.description, w.frame, self._value(w.radius), law, slip=w.slip, **kw)
        if w.slip_velocity is not None or w.stiffness is not None or w.slip != "both":
            raise InputError(f"wheel {name!r}: slip_velocity/stiffness/slip given but friction = 'rolling'; expected "
                             "friction = 'coulomb' or 'linear'")
        if w.kind == "omni":
            return OmniWheel(self.description, w.frame, self._value(w.radius), self._value(w.roller_angle), **kw)
        if w.kind == "support":
            return SupportWheel(self.description, w.frame, self._value(w.radius), **kw)
        if w.kind != "standard":
            raise InputError(f"wheel {w.frame!r}: kind {w.kind!r}; expected 'standard', 'omni' or 'support'")
        return RollingWheel(self.description, w.frame, self._value(w.radius), **kw)

    # ------------------------------------------------------------------------------------------ coordinates
    @property
    def nq(self) -> int:
        """Number of natural coordinates (= number of full velocities)."""
        return self.model.nq

    @property
    def mobility(self) -> int:
        """Number of independent velocities."""
        return len(self.velocity_names)

    @property
    def units(self) -> dict[str, str]:
        """Unit of each coordinate and velocity by name: m and m/s for prismatic joints, rad and rad/s otherwise
        (operational velocities are listed as given by their model)."""
        out = {}
        for label, joint in zip(self.coordinates, self.description.joint_names):
            jid = self.model.getJointId(joint)
            unit = "m" if "P" in self.model.joints[jid].shortname().replace("JointModel", "") else "rad"
            out[label], out[f"{label}_dot"] = unit, f"{unit}/s"
        return out

    def coordinate_index(self, label: str) -> int:
        """Index of a coordinate in q.

        Args:
            label: The coordinate's display name (:attr:`coordinates`) or its URDF joint name.

        Returns:
            Its index in q (and in the full velocity v).

        Raises:
            InputError: No coordinate has that name.
        """
        if label in self.coordinates:
            return self.coordinates.index(label)
        if label in self.description.joint_names:
            return self.description.joint_names.index(label)
        raise InputError(f"unknown coordinate {label!r}; expected one of {', '.join(self.coordinates)}")

    def neutral(self) -> np.ndarray:
        """A valid configuration: the spec's ``neutral`` values, zero elsewhere.

        Returns:
            The configuration q (nq,), in coordinate order.
        """
        q = np.zeros(self.nq)
        for label, value in self.spec.neutral.items():
            q[self.coordinate_index(label)] = self._value(value)
        return q

    def check_q(self, q) -> np.ndarray:
        """Validate a configuration (length, finiteness, joint limits).

        Args:
            q: Natural coordinates (n,) [m, rad], ordered as :attr:`coordinates`.

        Returns:
            q as a float array.

        Raises:
            InputError: Wrong length, a non-finite or huge value, or a coordinate outside its joint range.
        """
        q = as_vector(q, self.nq, "q", self.coordinates, MAX_POSITION, "m or rad")
        lo, hi = self.description.lower, self.description.upper
        bad = np.flatnonzero((q < lo - 1e-12) | (q > hi + 1e-12))
        if bad.size:
            i = bad[0]
            raise InputError(
                f"q[{self.coordinates[i]}] = {q[i]:.6g} is outside its joint range [{lo[i]:.6g}, {hi[i]:.6g}]"
            )
        return q

    def check_nu(self, nu, what: str = "v") -> np.ndarray:
        """Validate a vector of independent velocities (or accelerations).

        Args:
            nu: Independent velocities (k,) [m/s, rad/s] (or accelerations [m/s^2, rad/s^2]), ordered as
                :attr:`velocity_names`.
            what: Its name in messages; ``"a"`` or ``"nudot"`` checks against the acceleration limit instead of the
                velocity limit.

        Returns:
            nu as a float array.

        Raises:
            InputError: Wrong length, or a non-finite or huge value.
        """
        limit = MAX_ACCELERATION if what in ("a", "nudot") else MAX_VELOCITY
        return as_vector(nu, self.mobility, what, self.velocity_names, limit)

    def check_tau(self, tau) -> np.ndarray:
        """Validate motor torques.

        Args:
            tau: One torque [N m] (or force [N] for a prismatic joint) per motor, ordered as :attr:`motors`.

        Returns:
            tau as a float array.

        Raises:
            InputError: Wrong length, or a non-finite or huge value.
        """
        return as_vector(tau, len(self.motors), "tau", [m.name for m in self.motors], MAX_FORCE, "N m or N")

    def checked_state(self, q, nu, tau) -> tuple:
        """:meth:`check_q`, :meth:`check_nu` and :meth:`check_tau` at once: where all three are float arrays of the
        right lengths, one vectorised test of their concatenation against the bounds those checks accept (the hot
        path of a caller evaluating many states, e.g. :meth:`dynamics_derivatives`); anything else goes through the
        three checks, whose one-line errors name the mistake.

        Args:
            q: Natural coordinates (n,) [m, rad], ordered as :attr:`coordinates`.
            nu: Independent velocities (k,) [m/s, rad/s], ordered as :attr:`velocity_names`.
            tau: Motor torques [N m] or forces [N], one per motor, ordered as :attr:`motors`.

        Returns:
            ``(q, nu, tau)`` as float arrays (copies: the caller's arrays may change afterwards).

        Raises:
            InputError: As :meth:`check_q`, :meth:`check_nu`, :meth:`check_tau`.
        """
        if type(q) is np.ndarray and type(nu) is np.ndarray and type(tau) is np.ndarray \
                and q.dtype == nu.dtype == tau.dtype == np.float64:
            lo, hi = self.description.lower, self.description.upper
            key = (lo.tobytes(), hi.tobytes(), self.mobility, len(self.motors))
            bounds = self.__dict__.get("_state_bounds")
            if bounds is None or bounds[0] != key:  # the bounds check_q/check_nu/check_tau accept, concatenated
                lower = np.concatenate((np.maximum(lo - 1e-12, -MAX_POSITION), np.full(key[2], -MAX_VELOCITY),
                                        np.full(key[3], -MAX_FORCE)))
                upper = np.concatenate((np.minimum(hi + 1e-12, MAX_POSITION), np.full(key[2], MAX_VELOCITY),
                                        np.full(key[3], MAX_FORCE)))
                bounds = self._state_bounds = (key, lower, upper)
            n, k = lo.size, key[2]
            if q.shape == (n,) and nu.shape == (k,) and tau.shape == (key[3],):
                x = np.concatenate((q, nu, tau))
                if within(x, bounds[1], bounds[2]):
                    return x[:n], x[n:n + k], x[n + k:]
        return self.check_q(q), self.check_nu(nu), self.check_tau(tau)

    def _state(self, q, nu, tau=None, what: str = "nu") -> tuple:
        """``q``, ``nu`` (and ``tau``) as float arrays, their lengths checked (a wrong length is a one-line
        :class:`~robotdyn.errors.InputError` from :meth:`check_q`/:meth:`check_nu`/:meth:`check_tau`, never
        numpy's shape error deep inside); values are not range-checked here (the API's hot path)."""
        try:
            q_, nu_ = np.asarray(q, float), np.asarray(nu, float)
        except (TypeError, ValueError):  # not numbers: the checks name the entry
            q_, nu_ = self.check_q(q), self.check_nu(nu, what)
        if q_.shape != (self.nq,):
            self.check_q(q)
        if nu_.shape != (self.mobility,):
            self.check_nu(nu, what)
        if tau is None:
            return q_, nu_
        try:
            tau_ = np.asarray(tau, float)
        except (TypeError, ValueError):
            tau_ = self.check_tau(tau)
        if tau_.shape != (len(self.motors),):
            self.check_tau(tau)
        return q_, nu_, tau_

    # ------------------------------------------------------------------------------------------ constraints
    def constraint_rows(self, kin: KinematicState) -> ConstraintRows:
        """All constraint rows at the state of ``kin``.

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v).

        Returns:
            The stacked :class:`~robotdyn.constraints.constraint.ConstraintRows` (A, Adot, residual, labels), in the
            order of :attr:`constraints`.
        """
        return ConstraintRows.stack([c.rows(kin) for c in self.constraints], self.model.nv)

    def rows_at(self, q) -> ConstraintRows:
        """All constraint rows at configuration q (at rest, so ``Adot`` is zero).

        Args:
            q: Natural coordinates (n,) [m, rad].

        Returns:
            The stacked :class:`~robotdyn.constraints.constraint.ConstraintRows`.
        """
        return self.constraint_rows(KinematicState(self.model, self.data, q, np.zeros(self.model.nv)))

    def constraint_residual(self, q) -> np.ndarray:
        """Position residuals of the holonomic constraint rows at q.

        Args:
            q: Natural coordinates (n,) [m, rad].

        Returns:
            One residual per holonomic row [m or rad] (0 where the constraint holds).
        """
        rows = self.rows_at(q)
        return rows.residual[rows.holonomic]

    def check_constraints(self, q, tol: float = 1e-6, rows: ConstraintRows | None = None) -> None:
        """Raise :class:`ConstraintError` if q violates a holonomic constraint by more than ``tol``, with the advice
        that fits: a root at the wrong height when every wheel misses the ground by the same amount, else the
        wheels or closures that do not close.

        Args:
            q: Natural coordinates (n,) [m, rad].
            tol: Largest accepted residual [m or rad].
            rows: :meth:`rows_at` of q, when the caller has them (default ``None``: computed here).

        Raises:
            ConstraintError: A holonomic row's residual exceeds ``tol`` (one line naming the row and the fix).
        """
        rows = self.rows_at(q) if rows is None else rows
        if not (rows.residual.size and np.max(np.abs(rows.residual)) > tol):
            return
        i = int(np.argmax(np.abs(rows.residual)))
        heights = self.wheel_heights(q)
        values = np.array(list(heights.values()))
        if rows.labels[i].rsplit(".", 1)[0] in heights and np.ptp(values) <= tol and self.spec.root != "fixed":
            raise ConstraintError(self._root_height_advice(q, values, "at this configuration"))
        what = ("the wheels must touch the ground: check the radii and joint values, or solve the posture "
                "(robotdyn.constraints.posture)" if rows.labels[i].rsplit(".", 1)[0] in heights else
                "solve the closures first (robotdyn.constraints.posture solves the holonomic constraints for the free coordinates)")
        raise ConstraintError(
            f"q violates constraint {rows.labels[i]} by {rows.residual[i]:.3g}; expected |residual| <= {tol:g}; {what}"
        )

    def _root_height_advice(self, q, heights, when: str) -> str:
        """What to do when every wheel misses the ground by the same height: the root link's height and its fix.

        Args:
            q: Natural coordinates (n,) [m, rad] at which the wheels were measured.
            heights: Each wheel's contact-point height above the terrain [m] (:meth:`wheel_heights`), all equal.
            when: Where they were measured, e.g. "at the neutral configuration".

        Returns:
            One line: how far the wheels are off, where the root is, and the value to set (rounded to 1e-9 m, so
            that a root already in place reads 0, not a rounding residue).
        """
        d = float(np.mean(heights))
        where = "above" if d > 0 else "below"
        if self.spec.root == "planar":
            now = self.description.root_height
            fix = (f"set root_height = {round(now - d, 9) + 0.0:.6g} in the constraint file (RobotSpec.root_height; leave "
                   "it out to have it found from the wheels)")
        else:
            now = float(np.asarray(q, float)[self.coordinate_index("z")])
            fix = f"set z = {round(now - d, 9) + 0.0:.6g} (neutral = {{ z = ... }} in the constraint file)"
        return (f"every wheel is {abs(d):.6g} m {where} the ground {when}: the root link sits at the wrong height "
                f"({self.spec.root} root at {now:.6g} m); {fix}")

    def wheel_heights(self, q=None) -> dict[str, float]:
        """Each wheel's contact-point height above the terrain [m] (its holonomic residual); 0 when it touches,
        positive when it floats above.

        Args:
            q: Natural coordinates (n,) [m, rad] (default ``None``: the neutral configuration).

        Returns:
            Height [m] by wheel name.
        """
        kin = KinematicState(self.model, self.data, self.neutral() if q is None else np.asarray(q, float),
                             np.zeros(self.model.nv))
        out = {}
        for c in self.constraints:
            if hasattr(c, "contact"):
                rows = c.jacobian(kin)
                if rows.holonomic.any():
                    out[rows.labels[0].rsplit(".", 1)[0]] = float(rows.residual[rows.holonomic][0])
        return out

    def root_height_from_wheels(self, tol: float = 1e-6) -> tuple[float, dict[str, float]]:
        """How much to raise a planar root so that its wheels touch the ground at the neutral configuration.

        Most ROS descriptions put ``base_link`` above the ground (at the wheel axles, or the chassis' bottom
        plate), while a planar root moves the root link in the plane z = 0. When every wheel's contact point is the
        same height d below (or above) the terrain at the neutral configuration, the root belongs at -d [m].

        Args:
            tol: Agreement [m] within which the wheels' heights count as one height (and below which a height is 0).

        Returns:
            ``(height, wheel heights)``: the height (0 when the wheels already touch, or when they disagree by
            more than ``tol``: then no single height makes them all touch) and :meth:`wheel_heights`.
        """
        heights = self.wheel_heights()
        if not heights:
            return 0.0, heights
        values = np.array(list(heights.values()))
        if np.max(np.abs(values)) <= tol or np.ptp(values) > tol:
            return 0.0, heights
        return -float(np.mean(values)), heights

    # ------------------------------------------------------------------------------------------- dynamics
    def reduced(self, q, nu, coriolis: bool = False) -> ReducedDynamics:
        """The minimal-coordinate model at (q, nu): :math:`M_r\\dot\\nu + C_r\\nu + g_r = B_r\\tau` with
        :math:`v = S(q)\\nu`; see :mod:`robotdyn.reduction.reduced_dynamics` (compiled where the robot allows it:
        :func:`robotdyn.fast.dispatch.reduce`).

        Args:
            q: Natural coordinates (n,) [m, rad], ordered as :attr:`coordinates`; should satisfy the holonomic
                constraints (:meth:`check_constraints`).
            nu: Independent velocities (k,) [m/s, rad/s], ordered as :attr:`velocity_names`.
            coriolis: Also compute the matrix :math:`C_r` (k, k) and :math:`\\dot S` (default: only the bias
                :math:`h = C_r\\nu + g_r`, which is cheaper).

        Returns:
            The :class:`~robotdyn.reduction.reduced_dynamics.ReducedDynamics` (``M``, ``h``, ``g``, ``B``, ``S``, ...).

        Raises:
            InputError: ``q`` or ``nu`` of the wrong length (one line naming the entries expected).
            NonFiniteError: The state gives non-finite numbers.

        Example:
            >>> import robotdyn
            >>> robot = robotdyn.load("quasimoro")
            >>> red = robot.reduced([0, 0, 0, 0, 0, 0.1], [1.0, 1.0, 0.0])
            >>> red.M.shape, red.h.shape, red.B.shape
            ((3, 3), (3,), (3, 2))
            >>> bool(abs(red.M - red.M.T).max() < 1e-12)  # symmetric
            True
        """
        q, nu = self._state(q, nu)
        return checked(reduce(self, q, nu, coriolis), q, nu)

    def full(self, q, v) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Full-coordinate M(q), C(q, v), g(q) of the unconstrained tree (Pinocchio), without the constraints.

        Args:
            q: Natural coordinates (n,) [m, rad].
            v: Full velocities (n,) [m/s, rad/s].

        Returns:
            ``(M, C, g)``: the mass matrix (n, n), the Coriolis matrix (n, n) and the gravity vector (n,).
        """
        q, v = np.asarray(q, float), np.asarray(v, float)
        M = pin.crba(self.model, self.data, q).copy()
        C = pin.computeCoriolisMatrix(self.model, self.data, q, v).copy()
        g = pin.computeGeneralizedGravity(self.model, self.data, q).copy()
        return M, C, g

    def forward_dynamics(self, q, nu, tau, check: bool = True) -> np.ndarray:
        """Independent accelerations :math:`\\dot\\nu = M_r^{-1}(B_r\\tau - C_r\\nu - g_r)` (with slipping
        wheels, together with their normal loads and friction: :func:`robotdyn.contact.sliding.forward`).

        With ``check``, rows the projection dropped as redundant are checked at the velocity and acceleration
        level (:mod:`robotdyn.constraints.redundancy`): where the mobility changes (e.g. steerable wheels all parallel) these
        accelerations can violate them, and a :class:`~robotdyn.errors.RobotDynWarning` names each row and by
        how much.

        Args:
            q: Natural coordinates (n,) [m, rad].
            nu: Independent velocities (k,) [m/s, rad/s].
            tau: Motor torques [N m] (forces [N] on prismatic joints), one per motor in the order of :attr:`motors`.
            check: Check the dropped redundant rows (default True).

        Returns:
            The independent accelerations (k,) [m/s^2, rad/s^2].

        Raises:
            InputError: ``q``, ``nu`` or ``tau`` of the wrong length (one line naming the entries expected).
            NonFiniteError: The accelerations are not finite.

        Example:
            >>> import robotdyn
            >>> robot = robotdyn.load("quasimoro")
            >>> nudot = robot.forward_dynamics([0, 0, 0, 0, 0, 0], [0.0, 0.0, 0.0], [0.1, 0.1])
            >>> nudot.shape
            (3,)
            >>> bool(abs(nudot[0] - nudot[1]) < 1e-12)  # equal torques: the wheels accelerate alike
            True
        """
        q, nu, tau = self._state(q, nu, self.check_tau(tau) if tau is None else tau)
        if sliding_now(self):
            return forward_sliding(self, q, nu, tau).nudot
        red = self.reduced(q, nu)
        if any(getattr(c, "rolling", False) for c in self.constraints):  # robotdyn.contact.compliant_rolling
            from .contact.compliant_rolling import forward as rolling_forward

            return rolling_forward(self, q, nu, tau, red=red).nudot
        out = solve_mass(red.M, red.B @ tau - red.h + reduced_applied(self, red, q)[0])
        if not np.isfinite(out).all():
            raise NonFiniteError("the accelerations at this state are not finite (the state or torques are beyond "
                                 "what double precision holds)")
        if check:
            self._warn_dropped(red, out, q)
            self.warn_conditioning(red, out)
        return out

    def dynamics_derivatives(self, q, nu, tau, check: bool = True):
        """:math:`\\dot\\nu` and its derivatives in q (natural coordinates, and along the holonomic manifold in
        independent position coordinates), :math:`\\nu` and :math:`\\tau`: a
        :class:`~robotdyn.reduction.dynamics_derivatives.DynamicsDerivatives` (compiled where the compiled model
        serves, :mod:`robotdyn.fast.compiled_derivatives`, operational-space velocities and slipping wheels included,
        else the Python reference :func:`robotdyn.reduction.dynamics_derivatives.dynamics_derivatives`; with
        slipping wheels :func:`robotdyn.contact.sliding_derivatives.sliding_derivatives`).

        Args:
            q: Natural coordinates (n,) [m, rad] in the order of :attr:`coordinates`, on the holonomic constraint
                manifold for ``dq_manifold`` to be the derivative along it.
            nu: Independent velocities (k,) [m/s, rad/s] in the order of :attr:`velocity_names`.
            tau: Motor torques/forces (n_motors,) [N m or N] in the order of :attr:`motors`.
            check: Validate q, nu and tau (lengths, finiteness, joint ranges) and the constraints' derivative
                rules (default True). ``False`` is the fast entry for a caller that validated them once and
                evaluates many states (an optimiser, a controller): float arrays of the right lengths expected.

        Returns:
            A :class:`~robotdyn.reduction.dynamics_derivatives.DynamicsDerivatives`.

        Raises:
            InputError: Wrong sizes (with ``check=False`` too), or a constraint without derivatives (a stick-slip
                wheel, exact Coulomb friction, a user's own constraint class).
            SingularConstraintError: Slipping wheels whose coupled system is singular (Painlevé).
            NonFiniteError: A non-finite result.
        """
        from .fast.compiled_derivatives import compiled_derivatives

        sliding = bool(sliding_now(self))
        if check:
            from .constraints.row_derivatives import kind  # (the checked call's only: not on the fast entry)

            q, nu, tau = self.checked_state(q, nu, tau)
            if sliding:
                from .contact.sliding_derivatives import smooth_sliding

                smooth_sliding(self)  # the one-line refusal of stick-slip and exact Coulomb friction, on either path
            for c in self.constraints:
                kind(c, sliding=sliding)  # the one-line refusal of a constraint without derivatives, on either path
        else:  # lengths only (a one-line InputError, never the binding's TypeError); values are the caller's
            q, nu, tau = self._state(q, nu, self.check_tau(tau) if tau is None else tau)
        fast = compiled_derivatives(self, q, nu, tau)  # the compiled twin where the compiled model serves
        if fast is not None:
            return fast
        if sliding:
            from .contact.sliding_derivatives import sliding_derivatives

            return sliding_derivatives(self, q, nu, tau)
        from .reduction.dynamics_derivatives import dynamics_derivatives

        return dynamics_derivatives(self, q, nu, tau)

    def contact_force_derivatives(self, q, nu, tau):
        """The wheel contact forces (normal load, tangential components in the contact frame) and each wheel's
        required mu under motor torques ``tau``, with their derivatives in q (natural coordinates, and along the
        holonomic manifold in the independent position coordinates of :meth:`dynamics_derivatives`), nu and tau:
        a :class:`~robotdyn.contact.force_derivatives.ContactForceDerivatives` (compiled where the compiled
        dynamics derivatives serve, :mod:`robotdyn.contact.compiled_force_derivatives`, else the Python reference
        :func:`robotdyn.contact.force_derivatives.contact_force_derivatives`).

        Args:
            q: Natural coordinates (n,) [m, rad] in the order of :attr:`coordinates`.
            nu: Independent velocities (k,) [m/s, rad/s] in the order of :attr:`velocity_names`.
            tau: Motor torques/forces (n_motors,) [N m or N] in the order of :attr:`motors`.

        Returns:
            A :class:`~robotdyn.contact.force_derivatives.ContactForceDerivatives` (forces [N]).
        """
        from .contact.force_derivatives import checked, contact_force_derivatives
        from .contact.compiled_force_derivatives import compiled_force_derivatives

        q, nu, tau = checked(self, q, nu, tau)
        fast = compiled_force_derivatives(self, q, nu, tau)  # the compiled twin where the compiled model serves
        return fast if fast is not None else contact_force_derivatives(self, q, nu, tau)

    def conditioning(self, q, nu, tau=None) -> list:
        """The ill-conditioned parts of the reduced solve at (q, nu) (the projection's :math:`A_d`, the reduced
        mass matrix :math:`S^TMS`) that make its results (with motor torques ``tau``: the accelerations they
        give) beyond what the state can produce, as data: a list of
        :class:`~robotdyn.reduction.conditioning.IllConditioned`, empty where they are within it
        (:mod:`robotdyn.reduction.conditioning`).

        Args:
            q: Natural coordinates (n,) [m, rad], ordered as :attr:`coordinates`.
            nu: Independent velocities (k,) [m/s, rad/s], ordered as :attr:`velocity_names`.
            tau: Motor torques/forces (motors,) [N m or N], ordered as the motors (default ``None``: the
                accelerations are not judged, only the parts' conditioning).

        Returns:
            The ill-conditioned parts, a list of :class:`~robotdyn.reduction.conditioning.IllConditioned`.
        """
        from .reduction.conditioning import ill_conditioned

        red = self.reduced(q, nu)
        nudot = None if tau is None else solve_mass(red.M, red.B @ np.asarray(tau, float) - red.h)
        return ill_conditioned(red, self.velocity_names, nudot)

    def warn_conditioning(self, red, nudot=None, extra: list | None = None, forward: bool = True) -> list:
        """Warn (one :class:`~robotdyn.errors.RobotDynWarning`) when the results of ``red`` (with the accelerations
        ``nudot`` computed from it) are beyond what the state can produce (:mod:`robotdyn.reduction.conditioning`).

        Args:
            red: The :class:`~robotdyn.reduction.reduced_dynamics.ReducedDynamics` the results come from.
            nudot: The independent accelerations (k,) [m/s^2, rad/s^2] computed from it (default ``None``: only
                the parts' conditioning is judged).
            extra: Ill-conditioned parts found by the caller (e.g. the force system), added where not already found.
            forward: Whether ``nudot`` was solved from the mass matrix (else its conditioning is not a cause).

        Returns:
            The parts found (a list of :class:`~robotdyn.reduction.conditioning.IllConditioned`; empty: no warning).
        """
        from .reduction.conditioning import ill_conditioned, message

        found = ill_conditioned(red, self.velocity_names, nudot, forward)
        found += [e for e in (extra or []) if e.part not in {f.part for f in found}]
        if found:
            warnings.warn(message(found), RobotDynWarning, stacklevel=3)
        return found

    def redundant_row_violations(self, q, nu, nudot=None) -> list:
        """The constraint rows dropped as redundant at q that the velocities ``nu`` (and the accelerations
        ``nudot``, if given) violate. See :mod:`robotdyn.constraints.redundancy`.

        Args:
            q: Natural coordinates (n,) [m, rad].
            nu: Independent velocities (k,) [m/s, rad/s].
            nudot: Independent accelerations (k,) [m/s^2, rad/s^2] (default ``None``: velocities only).

        Returns:
            A list of :class:`~robotdyn.constraints.redundancy.RowViolation` (empty where the state is consistent).
        """
        from .constraints.redundancy import violations

        return violations(self.reduced(q, nu), nudot)

    def _warn_dropped(self, red, nudot, q) -> None:
        from .constraints.redundancy import message
        from .fast.dropped_rows import violations  # the exact check, its Adot pass skipped where it cannot fire

        found = violations(self, red, q, nudot)
        if found:
            warnings.warn(message(found), RobotDynWarning, stacklevel=3)

    def inverse_dynamics(self, q, nu, nudot) -> tuple[np.ndarray, np.ndarray, float]:
        """Generalised forces and motor torques for given independent accelerations.

        Args:
            q: Natural coordinates (n,) [m, rad].
            nu: Independent velocities (k,) [m/s, rad/s].
            nudot: Independent accelerations (k,) [m/s^2, rad/s^2].

        Returns:
            ``(Q, tau, residual)``: :math:`Q = M_r\\dot\\nu + C_r\\nu + g_r` (k,), the motor torques tau solving
            :math:`B_r\\tau = Q` in least squares, and the norm of what the motors cannot produce (0 when the
            motion is feasible).

        Raises:
            InputError: ``q``, ``nu`` or ``nudot`` of the wrong length (one line naming the entries expected).

        Example:
            >>> import robotdyn
            >>> robot = robotdyn.load("quasimoro")
            >>> q, nu = [0, 0, 0, 0, 0, 0], [0.0, 0.0, 0.0]
            >>> Q, tau, residual = robot.inverse_dynamics(q, nu, robot.forward_dynamics(q, nu, [0.1, 0.1]))
            >>> [round(float(t), 9) for t in tau]  # the torques that produced the motion
            [0.1, 0.1]
        """
        red = self.reduced(q, nu)
        nudot = np.asarray(nudot, float)
        if nudot.shape != (self.mobility,):
            self.check_nu(nudot, "nudot")
        self._refuse_rolling_contact(q, red.v, "inverse dynamics")
        Q = red.M @ nudot + red.h - reduced_applied(self, red, np.asarray(q, float))[0]
        self._warn_dropped(red, nudot, q)
        if red.B.shape[1] == 0:
            return Q, np.zeros(0), float(np.linalg.norm(Q))
        tau, *_ = np.linalg.lstsq(red.B, Q, rcond=None)
        return Q, tau, float(np.linalg.norm(red.B @ tau - Q))

    def _refuse_rolling_contact(self, q, v, what: str) -> None:
        """One-line InputError where compliant wheels roll in contact at (q, v) (their tangential rows are
        constraints on top of the projection, :mod:`robotdyn.contact.compliant_rolling`), for ``what`` that does
        not take those rows."""
        if not any(getattr(c, "rolling", False) for c in self.constraints):
            return
        from .contact.compliant_rolling import contact_set

        touching = contact_set(self, np.asarray(q, float), np.asarray(v, float))
        if touching:
            raise InputError(f"{what} with compliant wheels rolling in contact ({', '.join(touching)}) is not "
                             "available: their rolling rows' forces and the motor torques are not separated by the "
                             "accelerations here; expected motor torques (forward dynamics), or wheels in the air")

    def contact_forces(self, q, nu, tau=None, nudot=None, twin: bool = True):
        """Wheel-ground contact forces and loop-closure forces at (q, nu) for motor torques ``tau`` (forward
        dynamics) or independent accelerations ``nudot`` (inverse dynamics); see
        :func:`robotdyn.contact.contact_forces.constraint_forces`.

        Args:
            q: Natural coordinates (n,) [m, rad].
            nu: Independent velocities (k,) [m/s, rad/s].
            tau: Motor torques [N m or N], one per motor (default ``None``: zero, or from ``nudot``).
            nudot: Independent accelerations (k,) [m/s^2, rad/s^2] (default ``None``: from ``tau``).
            twin: For a planar root, take the normal loads the planar model leaves undetermined from its floating
                twin (default True).

        Returns:
            The :class:`~robotdyn.contact.contact_forces.ConstraintForces` (per wheel: normal load [N] and friction
            force [N] in its contact frame).

        Example:
            >>> import robotdyn
            >>> robot = robotdyn.load("quasimoro")
            >>> forces = robot.contact_forces([0, 0, 0, 0, 0, 0], [0.0, 0.0, 0.0], tau=[0.0, 0.0])
            >>> [round(w.normal, 2) for w in forces.wheels]  # (2 m + M) g / 2 on each wheel at rest [N]
            [29.43, 29.43]
        """
        from .contact.contact_forces import constraint_forces

        return constraint_forces(self, q, nu, tau=tau, nudot=nudot, twin=twin)

    def velocity(self, q, nu) -> np.ndarray:
        """Full velocity v = S(q) nu.

        Args:
            q: Natural coordinates (n,) [m, rad].
            nu: Independent velocities (k,) [m/s, rad/s].

        Returns:
            The full velocity (n,) [m/s, rad/s], admissible (A(q) v = 0).
        """
        return self.reduced(q, nu).v

    def energy(self, q, v) -> float:
        """Total mechanical energy [J]: kinetic + gravity's potential + the elastic energy of joint springs and
        compliant contacts (:func:`robotdyn.contact.applied_forces.stored_energy`).

        Args:
            q: Natural coordinates (n,) [m, rad].
            v: Full velocities (n,) [m/s, rad/s] (e.g. :meth:`velocity`).

        Returns:
            Kinetic plus potential energy [J] (gravity's potential zero at z = 0; springs' zero at their rest).
        """
        kinetic, potential = energy(self.model, self.data, np.asarray(q, float), np.asarray(v, float))
        if has_applied(self):
            potential += stored_energy(self, q)
        return kinetic + potential

    def mobility_check(self) -> tuple[int, list[str]]:
        """The mobility n - rank A at the neutral configuration, and plain-language notes where the wheels lock
        the base (no admissible motion turns it, or moves it at all, at the neutral configuration and at the other
        admissible ones :func:`~robotdyn.constraints.base_mobility.reachable_motion` finds), e.g. a skid-steer base
        whose non-steering wheels roll without slipping, or where that holds only at the neutral configuration
        (steerable wheels parallel there); and joint-origin angles that look like a rounded multiple of pi/2
        (:mod:`robotdyn.description.rounded_angles`).

        Returns:
            ``(mobility, notes)``: n - rank A (an int) and the notes (one string each; empty if none).
        """
        A = self.rows_at(self.neutral()).A
        rank = int(np.linalg.matrix_rank(A)) if A.size else 0
        notes = []
        if self.spec.root in ("planar", "floating") and A.size:
            _, sv, Vt = np.linalg.svd(A)
            null = Vt[rank:]  # admissible velocities at the neutral configuration
            names = self.description.joint_names
            yaw = names.index("psi" if "psi" in names else "yaw")
            xy = [names.index("x"), names.index("y")]
            from .constraints.base_mobility import reachable_motion

            if not np.any(np.abs(null[:, yaw]) > 1e-9):
                elsewhere = reachable_motion(self, names[yaw])
                if elsewhere is None:
                    notes.append("the base cannot turn: in every motion its wheels allow (rolling without slipping) "
                                 "the yaw rate is zero, at the neutral configuration and at the other admissible "
                                 "ones searched (steering moved), so turning requires slip; give the wheels a "
                                 "friction law (friction = 'linear' or 'coulomb', README: 'Wheel forces, slip and "
                                 "friction')")
                else:
                    moved = self._moved(elsewhere)
                    notes.append("the base cannot turn at the neutral configuration (e.g. its steerable wheels are "
                                 f"parallel there), but it can without slip at other admissible ones, e.g. {moved}: "
                                 "steer the wheels first")
            if not np.any(np.abs(null[:, xy]) > 1e-9):
                if all(reachable_motion(self, names[i]) is None for i in xy):
                    notes.append("the base cannot translate: its wheels allow no horizontal motion of the base")
                else:
                    notes.append("the base cannot translate at the neutral configuration, but it can at other "
                                 "admissible ones (steer the wheels first)")
        from .description.rounded_angles import hint, rounded_angles

        rounded = rounded_angles(self.description.urdf)
        if rounded:
            notes.append(hint(rounded))
        nearby = self._nearby_rank(rank)
        if nearby > rank:
            notes.append(f"the mobility changes at the neutral configuration: {self.nq - rank} here, "
                         f"{self.nq - nearby} at configurations near it (rows that are independent nearby become "
                         "dependent here, e.g. steerable wheels all parallel); the projection drops them as redundant, "
                         "and velocities or accelerations that leave this configuration violate them (robotdyn warns, "
                         "naming the row: Robot.redundant_row_violations)")
        return self.nq - rank, notes

    def _moved(self, q) -> str:
        """The coordinates of q that differ from the neutral configuration, as text (name = value rad/m)."""
        q0 = self.neutral()
        return ", ".join(f"{c} = {x:.3g}" for c, x, x0 in zip(self.coordinates, q, q0) if abs(x - x0) > 1e-3)

    def _nearby_rank(self, rank: int, samples: int = 3, step: float = 0.1) -> int:
        """The largest rank of the constraint rows at a few valid configurations near the neutral one, to tell a
        configuration where the mobility changes. Moved (by about ``step``) are the joint coordinates that no
        holonomic row involves (e.g. steering and spin angles), so that the configurations stay valid; one that
        does not (residual above 1e-6) is not counted."""
        q0 = self.neutral()
        rows = self.rows_at(q0)
        root = {name for name, _, _ in _ROOT_CHAINS[self.spec.root]}
        free = np.array([j not in root for j in self.description.joint_names])
        if rows.A.size and rows.holonomic.any():
            free &= ~np.any(np.abs(rows.A[rows.holonomic]) > 1e-12, axis=0)
        if not free.any() or not rows.A.size:
            return rank
        rng = np.random.default_rng(0)
        best = rank
        lo, hi = self.description.lower, self.description.upper
        for _ in range(samples):
            q = np.clip(q0 + step * rng.standard_normal(self.nq) * free, lo, hi)
            near = self.rows_at(q)
            if near.residual.size and np.max(np.abs(near.residual)) > 1e-6:
                continue
            best = max(best, int(np.linalg.matrix_rank(near.A)))
        return best

    def info(self) -> dict:
        """Coordinates, independent velocities, parameters (value, unit) and actuators, as plain data.

        Returns:
            A JSON-ready dict of plain Python values.
        """
        mobility, notes = self.mobility_check()
        report = self.description.visual_report
        from .description.joint_dynamics import joint_dynamics_notes

        heights = self.wheel_heights() if self.spec.root != "fixed" else {}
        values = list(heights.values())
        if values and max(map(abs, values)) > 1e-6:
            if np.ptp(values) <= 1e-6:  # all off by the same height: the root's
                notes.append(self._root_height_advice(self.neutral(), values, "at the neutral configuration"))
            else:
                listed = ", ".join(f"{k} {v:+.4g} m" for k, v in heights.items())
                notes.append(f"at the neutral configuration the wheels do not all touch the ground (contact heights "
                             f"above it: {listed}); a {self.spec.root} root cannot fix that with one height: check the "
                             "radii, the joint values (neutral) or the terrain")
        notes += joint_dynamics_notes(self.model, self.spec.urdf_damping)
        if self.spec.root != "fixed":  # an axis in the wrong axes (robotdyn.constraints.rolling_contact.lying_flat)
            from .constraints.rolling_contact import lying_flat

            notes += lying_flat(self.constraints, KinematicState(self.model, self.data, self.neutral(),
                                                                 np.zeros(self.model.nv)))
        return {
            "mobility_at_neutral": mobility,
            "mobility_notes": notes,
            "root": self.spec.root,
            "root_height": self.description.root_height,
            "root_height_source": self.root_height_source,
            "visual_warnings": report.warnings if report is not None else [],
            "implausible_inertias": [vars(f) for f in self.implausible_inertias],  # warned on load, not repeated
            "robot": self.spec.name,
            "title": self.spec.title,
            "paper": self.spec.paper,
            "coordinates": self.coordinates,
            "independent_velocities": self.velocity_names,
            "mobility": self.mobility,
            "parameters": {
                p.name: {"value": self.params[p.name], "unit": p.unit, "description": p.description}
                for p in self.spec.parameters
            },
            "actuators": [
                {"name": m.name, "joint": self.spec.labels.get(m.joint, m.joint), "reaction": m.reaction}
                for m in self.motors
            ],
            "constraints": [repr(c) for c in self.constraints],
            "springs": [repr(sp) for sp in getattr(self, "springs", ())],
            "terrain": repr(self.terrain),
        }
