"""The constraint file's reference: every key of :data:`~robotdyn.interfaces.constraint_schema.SCHEMA` with its
type, what it expects (units and ranges, from the schema), its default and an example, as rows or a Markdown table.

The documentation site builds its file-format page from :func:`markdown_table`, so the page cannot drift from the
schema: a key added to the schema without an entry in :data:`KEYS` (or an entry here for a key the schema no
longer has) makes :func:`rows` raise, which fails the documentation build and ``tests/test_docs_site.py``.
"""

from __future__ import annotations

from dataclasses import dataclass

from .constraint_schema import SCHEMA

KEYS: dict[str, tuple[str, str, str]] = {
    # key path: (what it is, default, example)
    "name": ("the robot's name (shown by info, used in sweeps)", "the file's stem", 'name = "my_rover"'),
    "title": ("one line describing the robot", "stem and description file", 'title = "Differential drive, two casters"'),
    "paper": ("a short reference of the paper the robot comes from", "none", 'paper = "Author 2024, Title"'),
    "urdf": ("the URDF or Xacro description: relative to the file, absolute, or package://PKG/path",
             "required unless given separately (--urdf)", 'urdf = "rover.urdf.xacro"'),
    "root": ("the joint between the world and the root link: fixed; planar (x, y, psi); floating (x, y, z, yaw, "
             "pitch, roll)", "planar", 'root = "floating"'),
    "package_dirs": ("directories searched for ROS packages ($(find PKG), package://PKG), relative to the file; "
                     "ROS_PACKAGE_PATH and AMENT_PREFIX_PATH are searched too", "[]", 'package_dirs = ["../ws/src"]'),
    "packages": ("ROS packages by name: directory of each, relative to the file", "{}",
                 '[packages]\nmy_description = "../my_description"'),
    "root_height": ("planar root: height of the root link above the ground", "auto (from the wheels at the neutral "
                    "configuration)", "root_height = 0.1"),
    "urdf_damping": ("whether a joint's URDF <dynamics damping> d is applied, as a viscous joint torque -d q' (as "
                     "Gazebo, Drake and MuJoCo apply it); false leaves it out (the papers' ideal joints). A joint "
                     "damped by the URDF takes no [[springs]] damping. A joint's dry friction is not modelled",
                     "true", "urdf_damping = false"),
    "massless": ("links whose URDF inertial is ignored", "[]", 'massless = ["sensor_link"]'),
    "independent": ("the coordinates (labels or joint names) whose velocities are the independent ones; as many as "
                    "the mobility", "chosen automatically (info prints the choice)",
                    'independent = ["theta_R", "theta_L"]'),
    "xacro_args": ("fixed xacro arguments of the description", "{}", 'xacro_args = { wheel_radius = "0.1" }'),
    "labels": ("display names of coordinates, by joint", "the joint names", 'labels = { wheel_right_joint = "theta_R" }'),
    "neutral": ("a valid configuration, by coordinate name", "all zero", "neutral = { z = 0.1 }"),
    "locked": ("joints held fixed at a value (glob patterns allowed)", "{}", 'locked = { "arm_*" = 0.0 }'),
    "terrain": ("the ground", "flat, z = 0", '[terrain]\nkind = "ramp"\nslope = 0.1'),
    "terrain.kind": ("flat (height) | ramp (slope, heading) | bump (height, x0, width, length) | sine (amplitude, kx, "
                     "ky, phase)", "flat", 'kind = "bump"'),
    "terrain.height": ("flat, ramp: ground height at the origin; bump: bump height (required by bump)", "0", "height = 0.05"),
    "terrain.slope": ("ramp: rise over run", "required by ramp", "slope = 0.1"),
    "terrain.heading": ("ramp: direction of steepest ascent from the x axis", "0", "heading = 0.5"),
    "terrain.x0": ("bump: position of the rise along x", "0", "x0 = 1.0"),
    "terrain.width": ("bump: width of the smooth rise (a tanh profile)", "0.1", "width = 0.05"),
    "terrain.length": ("bump: length of the plateau before it comes back down", "none (a step up)", "length = 0.3"),
    "terrain.amplitude": ("sine: amplitude", "required by sine", "amplitude = 0.02"),
    "terrain.kx": ("sine: wave number along x", "required by sine", "kx = 6.0"),
    "terrain.ky": ("sine: wave number along y", "0", "ky = 0.0"),
    "terrain.phase": ("sine: phase", "0", "phase = 0.0"),
    "twist": ("independent velocities that are a frame's twist instead of `independent`", "none",
              '[twist]\nframe = "base_link"\ncomponents = ["vx", "wz"]'),
    "twist.frame": ("the frame whose twist is used", "required in [twist]", 'frame = "base_link"'),
    "twist.components": ("components of the twist (vx vy vz wx wy wz)", '["vx", "vy", "wz"]', 'components = ["vx", "wz"]'),
    "twist.axes": ("the axes the twist is expressed in: body (the frame's own) or world", "body", 'axes = "world"'),
    "twist.names": ("display names of the components", "the components", 'names = ["v", "omega"]'),
    "parameters": ("numbers that wheels and the description (xacro arguments) refer to; what sweeps vary", "[]",
                   '[[parameters]]\nname = "r"\ndefault = 0.1\nunit = "m"'),
    "parameters[].name": ("the parameter's name (a xacro argument of the description when xacro = true)", "required",
                          'name = "chassis_mass"'),
    "parameters[].default": ("its value in its unit, or one of its choices", "required", "default = 4.0"),
    "parameters[].unit": ("its unit (shown by info; sweeps accept values with units)", '""', 'unit = "kg"'),
    "parameters[].description": ("one line", '""', 'description = "mass of the chassis"'),
    "parameters[].choices": ("the allowed values of a word-valued parameter", "none (a number)",
                             'choices = ["com", "origin"]'),
    "parameters[].xacro": ("pass it to the description as a xacro argument (so a sweep can vary a URDF mass, "
                           "length, inertia)", "true when the Xacro declares an argument of that name",
                           "xacro = true"),
    "parameters[].minimum": ("the smallest physical value, in the parameter's unit (masses and inertias: 0 by "
                             "default)", "none", "minimum = 0.0"),
    "wheels": ("the wheels touching the ground, one table each", "[]", '[[wheels]]\nname = "left"\n'
               'joint = "left_wheel_joint"\nradius = 0.1'),
    "wheels[].name": ("the wheel's name (CSV columns <name>.normal, forces tables)", "the frame name", 'name = "left"'),
    "wheels[].joint": ("the wheel's spin joint; its child link's origin is the wheel centre", "one of joint or frame",
                       'joint = "left_wheel_joint"'),
    "wheels[].frame": ("the wheel centre's frame (a ball or a fixed caster: no spin joint)", "one of joint or frame",
                       'frame = "ball_link"'),
    "wheels[].radius": ("the radius, a number or a parameter name", "required", 'radius = "r"'),
    "wheels[].axis": ("the axle's direction in the wheel frame (dimensionless, normalised)", "the spin joint's axis",
                      "axis = [0, 1, 0]"),
    "wheels[].kind": ("standard (rolls without slipping) | omni (with roller_angle) | caster (a wheel on a steering "
                      "joint of the URDF) | support (touches the ground only: normal row, frictionless, e.g. a ball "
                      "caster or a skid)", "standard", 'kind = "support"'),
    "wheels[].roller_angle": ("omni: angle of the axis of the roller touching the ground (the "
                              "one direction in which the wheel cannot slip) from the wheel's rolling direction, "
                              "counter-clockwise seen from above; 0: a 90-degree omni wheel; a mecanum wheel whose "
                              "ground roller points forward-right is -45 deg, forward-left +45 deg", "0",
                              'roller_angle = "-45 deg"'),
    "wheels[].radius_joint": ("a prismatic joint that sets the radius (adaptable wheels)", "none",
                              'radius_joint = "leg_joint"'),
    "wheels[].mu": ("friction coefficient (dimensionless): the traction check's limit; the coulomb law's limit and "
                    "stick_slip's cone (required by both); saturates the linear law", "none (not checked; linear: "
                    "unsaturated)", "mu = 0.8"),
    "wheels[].friction": ("rolling (rolls without slipping) | coulomb (regularised Coulomb, mu and slip_velocity) | "
                          "linear (brush tyre, stiffness, saturated at mu) | stick_slip (exact Coulomb with mu: sticks "
                          "while its force is inside the cone mu f_n, slides at mu f_n outside it; rigid contact only)",
                          "rolling", 'friction = "coulomb"'),
    "wheels[].slip_velocity": ("coulomb only: regularisation velocity v_s [m/s], c(s) = mu s / sqrt(s^2 + v_s^2)",
                               "1e-3 m/s", "slip_velocity = 0.001"),
    "wheels[].stiffness": ("linear only: slip stiffness k [s/m], the tangential force per unit load per m/s of slip, "
                           "min(k s, mu) f_n", "required by linear", "stiffness = 5.0"),
    "wheels[].normal_stiffness": ("normal (radial) stiffness k: N/m (linear law; on rigid wheels the rigid limit of "
                                  "normal compliance splits the loads rigid-body dynamics leave open in the ratios "
                                  "of k), N/m^n with contact_law = hunt_crossley",
                                  "m g / (n * 1 mm) [N/m]: the robot's weight over its n wheels at 1 mm static "
                                  "deflection, the same for every wheel; hunt_crossley: (m g / n) / (1 mm)^n [N/m^n], "
                                  "the same deflection", "normal_stiffness = 2.0e5"),
    "wheels[].normal_damping": ("normal (radial) damping: c [N s/m] of the linear law; lambda [N s/m^(n+1)] of "
                                "hunt_crossley (used by compliant wheels only)",
                                "linear: 2 * 0.3 * sqrt(k m / n) [N s/m], damping ratio 0.3 on the wheel's share of "
                                "the mass; hunt_crossley: 1.5 * 0.2 s/m * k (alpha = 0.2 s/m of Marhefka and Orin "
                                "1999)", "normal_damping = 400.0"),
    "wheels[].contact": ("rigid (the normal row is a constraint) | compliant (a force law of the penetration "
                         "[m]: the wheel can fly and land; with friction = rolling it rolls without slipping while "
                         "its normal force is > 0, a plastic tangential impact at each touch-down, or it follows "
                         "friction = coulomb or linear with slip = both; a support is frictionless; not with "
                         "stick_slip)", "rigid", 'contact = "compliant"'),
    "wheels[].contact_law": ("a compliant wheel's normal force law: linear, f = k d + c d' [N] (k in N/m, c in "
                             "N s/m) | hunt_crossley, f = d^n (k + lambda d') [N] (normal_stiffness k in N/m^n, "
                             "normal_damping lambda in N s/m^(n+1)); d the penetration [m], never pulling (f >= 0); "
                             "only with contact = compliant", "linear", 'contact_law = "hunt_crossley"'),
    "wheels[].contact_exponent": ("hunt_crossley's exponent n (dimensionless; 1.5 is Hertz's for a sphere or a "
                                  "crowned tyre on a plane); only with contact_law = hunt_crossley", "1.5",
                                  "contact_exponent = 1.5"),
    "wheels[].slip": ("with a friction law: both directions, or lateral only (rolls along its rolling direction)",
                      "both", 'slip = "lateral"'),
    "closures": ("loop closures: two frames held together", "[]",
                 '[[closures]]\nframe1 = "a"\nframe2 = "b"\ncomponents = "x y z"'),
    "closures[].name": ("the closure's name", "none", 'name = "rocker"'),
    "closures[].frame1": ("the first frame (components are in its axes)", "required", 'frame1 = "link_a_end"'),
    "closures[].frame2": ("the second frame", "required", 'frame2 = "link_b_end"'),
    "closures[].components": ("the closed components, a subset of x y z rx ry rz in frame1's axes", '"x y z"',
                              'components = "x z"'),
    "springs": ("springs and dampers on joints: generalised force -k (q - rest) - c q' on the joint's "
                "coordinate (a joint's URDF <dynamics damping> is applied as such a damper: see urdf_damping)", "[]", '[[springs]]\njoint = "front_left_suspension"\nstiffness = 3.0e4'),
    "springs[].name": ("the spring's name (messages, reports)", "the joint name", 'name = "front_left"'),
    "springs[].joint": ("the moving (not locked) joint it acts on, one coordinate: revolute, continuous or "
                        "prismatic; at most one spring per joint", "required", 'joint = "front_left_suspension"'),
    "springs[].stiffness": ("stiffness k: N/m on a prismatic joint, N m/rad on a revolute one", "0",
                            "stiffness = 3.0e4"),
    "springs[].damping": ("damping c: N s/m on a prismatic joint, N m s/rad on a revolute one", "0",
                          "damping = 3.0e3"),
    "springs[].rest": ("rest position: the coordinate [m or rad] where the spring force is zero", "0",
                       "rest = -0.05"),
    "motors": ("the actuated joints, in the order of the torques", "[]",
               '[[motors]]\nname = "tau_L"\njoint = "left_wheel_joint"'),
    "motors[].name": ("the motor's name (torque tables, CSV)", "the joint name", 'name = "tau_L"'),
    "motors[].joint": ("the driven joint", "required", 'joint = "left_wheel_joint"'),
    "motors[].reaction": ("the frame the motor reacts on", "the joint's parent", 'reaction = "base_link"'),
    "scenarios": ("constant-torque manoeuvres for simulate and sweeps", "[]",
                  '[[scenarios]]\nname = "spin"\nt_end = 2.0\ntorque = [0.5, -0.5]'),
    "scenarios[].name": ("the scenario's name (--scenario NAME)", "required", 'name = "spin"'),
    "scenarios[].description": ("one line", "constant torques [...]", 'description = "turn on the spot"'),
    "scenarios[].t_end": ("duration", "required", "t_end = 2.0"),
    "scenarios[].torque": ("constant torques, in motor order or by motor name (motors not named: 0)", "all zero",
                           "torque = { tau_L = 0.5 }"),
    "scenarios[].q0": ("initial coordinates by name (others: neutral)", "the neutral configuration",
                       "q0 = { psi = 0.5 }"),
    "scenarios[].nu0": ("initial independent velocities by name (with [twist]: by component name)", "zero",
                        "nu0 = { theta_R = 1.0 }"),
}
"""What each key is, its default and an example: the part of the reference the schema cannot say."""


@dataclass(frozen=True)
class KeyRow:
    """One key of the constraint file, as a row of the reference.

    Attributes:
        key: Its path, e.g. ``wheels[].radius`` for a key of every ``[[wheels]]`` table.
        type: Its TOML type(s), e.g. ``number`` or ``string: a | b`` for a choice.
        expected: What the schema accepts (units, ranges).
        required: Whether its table must have it.
        description: What it is.
        default: Its default when absent (text, as the reference prints it).
        example: A TOML example of it.
    """

    key: str
    type: str
    expected: str
    required: bool
    description: str
    default: str
    example: str


def _type(schema: dict) -> str:
    """The TOML type(s) a schema entry accepts."""
    names = {"string": "string", "number": "number", "boolean": "boolean", "array": "array", "object": "table",
             "integer": "integer"}
    if "enum" in schema:
        return "string: " + " | ".join(map(str, schema["enum"]))
    if "const" in schema:
        return f'"{schema["const"]}"'
    if "anyOf" in schema:
        return " or ".join(dict.fromkeys(_type(s) for s in schema["anyOf"]))
    kind = schema.get("type")
    if isinstance(kind, list):
        return " or ".join(names[k] for k in kind)
    if kind == "array":
        items = schema.get("items", {})
        if items.get("type") == "object":
            return "array of tables"
        return f"array of {_type(items) if items else 'values'}s"
    return names.get(kind, "value")


def _walk(schema: dict, prefix: str = "", required=()):
    for key, sub in schema.get("properties", {}).items():
        path = f"{prefix}{key}"
        yield path, sub, key in required
        if sub.get("type") == "object" and "properties" in sub:
            yield from _walk(sub, f"{path}.", sub.get("required", ()))
        elif sub.get("type") == "array" and sub.get("items", {}).get("type") == "object":
            yield from _walk(sub["items"], f"{path}[].", sub["items"].get("required", ()))


def rows() -> list[KeyRow]:
    """Every key of the schema, in the schema's order.

    Returns:
        One :class:`KeyRow` per key.

    Raises:
        KeyError: the schema and :data:`KEYS` disagree (a key missing on either side), naming the keys.
    """
    found = list(_walk(SCHEMA, required=SCHEMA.get("required", ())))
    paths = [p for p, _, _ in found]
    missing, extra = [p for p in paths if p not in KEYS], [p for p in KEYS if p not in paths]
    if missing or extra:
        raise KeyError(f"constraint-file reference out of date: keys of the schema without an entry in KEYS: "
                       f"{missing}; entries of KEYS that the schema does not have: {extra}")
    return [KeyRow(p, _type(s), str(s.get("expected", "")), req, *KEYS[p]) for p, s, req in found]


def markdown_table() -> str:
    """The reference as one Markdown table: key and type, what it is and what it accepts (units, ranges), default,
    example.

    Returns:
        The Markdown table as one string (header, separator, one line per key).
    """

    def cell(text: str) -> str:
        return text.replace("|", "\\|").replace("\n", "<br>")

    lines = ["| key (type) | what it is; what it accepts (units, range) | default | example |", "|---|---|---|---|"]
    for r in rows():
        default = "**required**" if r.required else cell(r.default)
        lines.append(f"| `{r.key}`<br>({cell(r.type)}) | {cell(r.description)}; accepts {cell(r.expected)} | {default} | "
                     f"<code>{cell(r.example)}</code> |")
    return "\n".join(lines)


__all__ = ["KEYS", "KeyRow", "rows", "markdown_table"]
