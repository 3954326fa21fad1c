"""The constraint file's schema: types, shapes, ranges and allowed keys of every entry, checked with jsonschema
before anything reads the file (:mod:`robotdyn.interfaces.constraint_file` then checks the names against the description).

A constraint file is data: nothing in it is evaluated (xacro argument values are checked to be numbers or plain
words by :func:`robotdyn.description.xacro_value` before xacro sees them). A value of the wrong type or shape, out
of its range, or a key that does not exist gives one line naming the entry, the value and what was expected, with a
suggestion for a misspelt key, e.g. ``wheels[0] (left): unknown key 'radious'; did you mean 'radius'?``.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Iterable

import jsonschema
from jsonschema import validators

from ..description import ROOT_KINDS
from ..inputs import MAX_FORCE, MAX_POSITION, MAX_VELOCITY

MAX_RADIUS = 1e4
"""Largest wheel radius accepted [m] (larger values only overflow the dynamics)."""
MAX_LENGTH = 1e4
"""Largest length accepted in a constraint file [m] (heights, terrain sizes)."""
MAX_DURATION = 1e6
"""Longest scenario accepted in a constraint file [s] (simulate also bounds its output samples by memory)."""
MAX_ENTRIES = 256
"""Most wheels, closures, motors, parameters or scenarios in one file (no robot has more; far more is an error)."""
WHEEL_KINDS = ("standard", "omni", "caster", "support")
CLOSURE_COMPONENTS = ("x", "y", "z", "rx", "ry", "rz")
TWIST_COMPONENTS = ("vx", "vy", "vz", "wx", "wy", "wz")


def _number(expected: str, minimum: float | None = None, maximum: float | None = None,
            exclusive_minimum: float | None = None) -> dict:
    """A finite number (``finite`` is this schema's own keyword: JSON Schema lets NaN through its ranges)."""
    out: dict = {"type": "number", "finite": True, "expected": expected}
    if minimum is not None:
        out["minimum"] = minimum
    if exclusive_minimum is not None:
        out["exclusiveMinimum"] = exclusive_minimum
    if maximum is not None:
        out["maximum"] = maximum
    return out


def _bounded(expected: str, limit: float) -> dict:
    return _number(f"{expected} of magnitude <= {limit:g}", -limit, limit)


def _by_law(entry: dict, hunt_crossley: str) -> dict:
    """A wheel's normal-law number whose unit depends on its table's ``contact_law``: ``hunt_crossley`` is the
    expectation where the law is Hunt-Crossley's, f = d^n (k + lambda d') (k in N/m^n, lambda in N s/m^(n+1))."""
    return {**entry, "expected_when": {"contact_law": {"hunt_crossley": hunt_crossley}}}


def _string(expected: str = "a non-empty string") -> dict:
    return {"type": "string", "minLength": 1, "expected": expected}


def _strings(expected: str, min_items: int = 0, items: dict | None = None) -> dict:
    """A list of strings, or one string of words separated by spaces."""
    return {"anyOf": [{"type": "string"},
                      {"type": "array", "items": items or {"type": "string", "minLength": 1}, "minItems": min_items,
                       "maxItems": 10_000}],
            "expected": expected}


def _table(properties: dict, required: Iterable[str] = (), expected: str = "a table") -> dict:
    return {"type": "object", "properties": properties, "additionalProperties": False, "required": list(required),
            "expected": expected}


def _table_of(values: dict, expected: str) -> dict:
    return {"type": "object", "additionalProperties": values, "expected": expected, "maxProperties": 10_000}


def _array_of(item: dict, key: str) -> dict:
    return {"type": "array", "items": item, "maxItems": MAX_ENTRIES,
            "expected": f"an array of tables ([[{key}]]) of at most {MAX_ENTRIES} entries"}


_ANGLE = {"anyOf": [{"type": "number", "finite": True}, {"type": "string", "minLength": 1}],
          "expected": "a number in rad, a string like '45 deg', or a parameter name"}
_TERRAIN_NUMBERS = {
    "height": _bounded("a height in m", MAX_LENGTH),
    "slope": _number("a slope (rise over run) in [-10, 10]", -10.0, 10.0),
    "heading": _bounded("an angle in rad", 1e3),
    "x0": _bounded("a position in m", MAX_LENGTH),
    "width": _number(f"a width in m, > 0 and <= {MAX_LENGTH:g}", None, MAX_LENGTH, 0.0),
    "length": _number(f"a length in m, > 0 and <= {MAX_LENGTH:g}", None, MAX_LENGTH, 0.0),
    "amplitude": _bounded("an amplitude in m", MAX_LENGTH),
    "kx": _bounded("a wave number in rad/m", 1e6),
    "ky": _bounded("a wave number in rad/m", 1e6),
    "phase": _bounded("a phase in rad", 1e3),
}

SCHEMA: dict = _table({
    "name": _string("a non-empty name"),
    "title": {"type": "string", "expected": "a string"},
    "paper": {"type": "string", "expected": "a string (a short reference of the robot's paper: authors, title)"},
    "urdf": _string("a path or package://PKG/... to the URDF/Xacro description"),
    "root": {"enum": list(ROOT_KINDS), "expected": f"one of {', '.join(ROOT_KINDS)}"},
    "package_dirs": _strings("a list of directories"),
    "packages": _table_of(_string("a directory"), "a table of ROS package directories by name"),
    "root_height": {"anyOf": [{"const": "auto"}, _bounded("a height in m", MAX_LENGTH)],
                    "expected": f"'auto' or a height in m of magnitude <= {MAX_LENGTH:g}"},
    "urdf_damping": {"type": "boolean", "expected": "true (the URDF's joint <dynamics damping> applied) or false"},
    "massless": _strings("a list of link names"),
    "independent": _strings("a non-empty list of coordinate names", 1),
    "xacro_args": _table_of({"type": ["string", "number", "boolean"], "expected": "a number, a word or a boolean"},
                            "a table of xacro arguments (name = value)"),
    "labels": _table_of(_string("a non-empty label"), "a table of display names by joint"),
    "neutral": _table_of(_bounded("a coordinate in m or rad", MAX_POSITION), "a table of coordinates by name"),
    "locked": _table_of(_bounded("a joint value in m or rad", MAX_POSITION), "a table of joint values by pattern"),
    "terrain": {**_table({"kind": {"enum": ["flat", "ramp", "bump", "sine"],
                                   "expected": "one of flat, ramp, bump, sine"}, **_TERRAIN_NUMBERS},
                         expected="a table with kind and its numbers"),
                "additionalProperties": True},  # keys by kind: robotdyn.interfaces.constraint_file names the kind's own
    "twist": _table({
        "frame": _string("a frame name"),
        "components": _strings(f"distinct entries of {' '.join(TWIST_COMPONENTS)}", 1),
        "axes": {"enum": ["body", "local", "world"], "expected": "'body' or 'world'"},
        "names": _strings("a list of display names"),
    }, expected="a table: frame, components, axes, names"),
    "parameters": _array_of(_table({
        "name": _string("a parameter name"),
        "default": {"anyOf": [{"type": "number", "finite": True}, {"type": "string"}],
                    "expected": "a finite number, or one of the choices"},
        "unit": {"type": "string", "expected": "a unit, e.g. 'm'"},
        "description": {"type": "string", "expected": "a string"},
        "choices": {"type": "array", "items": {"type": "string"}, "minItems": 1,
                    "expected": "a non-empty list of strings"},
        "xacro": {"type": "boolean", "expected": "true or false"},
        "minimum": _number("the smallest physical value of the parameter"),
    }, ("name", "default")), "parameters"),
    "wheels": _array_of(_table({
        "name": _string("a wheel name"),
        "joint": _string("the wheel's spin joint"),
        "frame": _string("the wheel centre's frame"),
        "radius": {"anyOf": [_number("", None, MAX_RADIUS, 0.0), {"type": "string", "minLength": 1}],
                   "expected": f"a radius in m, > 0 and <= {MAX_RADIUS:g}, or a parameter name"},
        "axis": {"type": "array", "items": _bounded("a number", 1e6), "minItems": 3, "maxItems": 3,
                 "expected": "3 numbers (the axle in the wheel frame)"},
        "kind": {"enum": list(WHEEL_KINDS), "expected": f"one of {', '.join(WHEEL_KINDS)}"},
        "roller_angle": _ANGLE,
        "radius_joint": _string("a prismatic joint setting the radius"),
        "mu": _number("a friction coefficient >= 0", 0.0, 1e6),
        "friction": _string("a friction law: rolling, coulomb, linear or stick_slip"),
        "slip_velocity": _number("a slip velocity in m/s, > 0", None, 1e6, 0.0),
        "stiffness": _number("a stiffness in s/m, > 0", None, 1e12, 0.0),
        "slip": {"enum": ["both", "lateral"], "expected": "both or lateral"},
        "normal_stiffness": _by_law(_number("a normal (radial) stiffness in N/m, > 0 and <= 1e12", None, 1e12, 0.0),
                                    "a normal (radial) stiffness in N/m^n (n the contact_exponent), > 0 and <= 1e12"),
        "normal_damping": _by_law(_number("a normal (radial) damping in N s/m, >= 0 and <= 1e12", 0.0, 1e12),
                                  "a normal (radial) damping in N s/m^(n+1) (n the contact_exponent), >= 0 and "
                                  "<= 1e12"),
        "contact": {"enum": ["rigid", "compliant"], "expected": "rigid or compliant"},
        "contact_law": {"enum": ["linear", "hunt_crossley"], "expected": "linear or hunt_crossley"},
        "contact_exponent": _number("an exponent n >= 1 and <= 10", 1.0, 10.0),
    }, (), "a table: name, joint or frame, radius, ..."), "wheels"),
    "closures": _array_of(_table({
        "name": _string("a closure name"),
        "frame1": _string("a frame name"),
        "frame2": _string("a frame name"),
        "components": _strings(f"distinct entries of {' '.join(CLOSURE_COMPONENTS)}", 1),
    }, ("frame1", "frame2")), "closures"),
    "springs": _array_of(_table({
        "name": _string("a spring name"),
        "joint": _string("the joint the spring acts on"),
        "stiffness": _number("a stiffness in N/m or N m/rad, >= 0 and <= 1e12", 0.0, 1e12),
        "damping": _number("a damping in N s/m or N m s/rad, >= 0 and <= 1e12", 0.0, 1e12),
        "rest": _bounded("a rest position in m or rad", MAX_POSITION),
    }, ("joint",)), "springs"),
    "motors": _array_of(_table({
        "name": _string("a motor name"),
        "joint": _string("the driven joint"),
        "reaction": _string("the frame the motor reacts on"),
    }, ("joint",)), "motors"),
    "scenarios": _array_of(_table({
        "name": _string("a scenario name"),
        "description": {"type": "string", "expected": "a string"},
        "t_end": _number(f"a duration in s, > 0 and <= {MAX_DURATION:g}", None, MAX_DURATION, 0.0),
        "torque": {"anyOf": [{"type": "array", "items": _bounded("", MAX_FORCE), "maxItems": MAX_ENTRIES},
                             _table_of(_bounded("", MAX_FORCE), "")],
                   "expected": f"torques in N m (or N) of magnitude <= {MAX_FORCE:g}, a list in motor order or a "
                               "table by motor name"},
        "q0": _table_of(_bounded("a coordinate in m or rad", MAX_POSITION), "a table of coordinates by name"),
        "nu0": _table_of(_bounded("a velocity in m/s or rad/s", MAX_VELOCITY), "a table of velocities by name"),
    }, ("name", "t_end")), "scenarios"),
}, expected="a table of constraint-file keys")


def _finite(validator, value, instance, schema):
    if value and isinstance(instance, float) and not math.isfinite(instance):
        yield jsonschema.ValidationError(f"{instance!r} is not finite")


def _ignore(validator, value, instance, schema):
    return iter(())


_Validator = validators.extend(jsonschema.Draft202012Validator, {"finite": _finite, "expected": _ignore,
                                                                  "expected_when": _ignore})
_VALIDATOR = _Validator(SCHEMA)


def _where(path, data) -> str:
    """``wheels[1] (left).radius`` for the path of an entry (the entry's name when it has one)."""
    out, node = "", data
    for key in path:
        if isinstance(key, int):
            out += f"[{key}]"
            node = node[key] if isinstance(node, list) and key < len(node) else None
            if isinstance(node, dict) and isinstance(node.get("name"), str):
                out += f" ({node['name']})"
        else:
            out += f".{key}" if out else str(key)
            node = node.get(key) if isinstance(node, dict) else None
    return out


def _show(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _suggest(name: str, candidates) -> str:
    close = difflib.get_close_matches(str(name), list(candidates), n=1, cutoff=0.6)
    return f"; did you mean {close[0]!r}?" if close else ""


def _message(error: jsonschema.ValidationError, data) -> str:
    where = _where(error.absolute_path, data)
    schema, value = error.schema, error.instance
    if error.validator == "additionalProperties" and schema.get("properties"):
        allowed = list(schema["properties"])
        unknown = [k for k in value if k not in allowed]
        key = unknown[0]
        return (f"{where + ': ' if where else ''}unknown key {key!r}{_suggest(key, allowed)} "
                f"(allowed: {', '.join(allowed)})")
    if error.validator == "required":
        missing = [k for k in error.validator_value if k not in value][0]
        return f"{where + ': ' if where else ''}missing {missing!r} ({schema['properties'][missing]['expected']})"
    if error.validator == "enum":
        return f"{where} = {_show(value)}{_suggest(value, error.validator_value)}; expected {schema['expected']}"
    expected = _table_expected(error, data) or schema.get("expected") or _parent_expected(error) or "a valid value"
    return f"{where or 'file'} = {_show(value)}; expected {expected}"


def _table_expected(error: jsonschema.ValidationError, data) -> str | None:
    """The expectation an entry's ``expected_when`` gives for the other keys of its table (e.g. a wheel's
    ``contact_law``), or None."""
    when = error.schema.get("expected_when")
    if not when or not error.absolute_path:
        return None
    table = data
    for key in list(error.absolute_path)[:-1]:
        try:
            table = table[key]
        except (KeyError, IndexError, TypeError):
            return None
    if not isinstance(table, dict):
        return None
    for key, by_value in when.items():
        value = table.get(key)
        if isinstance(value, str) and value in by_value:
            return by_value[value]
    return None


def _parent_expected(error: jsonschema.ValidationError) -> str | None:
    parent = error.parent
    while parent is not None:
        if parent.schema.get("expected"):
            return parent.schema["expected"]
        parent = parent.parent
    return None


def terrain_problem(table: dict) -> str | None:
    """The first problem of a terrain table ``{kind = ..., ARG = number, ...}`` (a sweep's terrain) against the
    constraint file's ``[terrain]`` schema (the same ranges: finite heights, positive widths, bounded slopes), as
    one line, or None.

    Args:
        table: ``{"kind": KIND, ARG: number, ...}``.

    Returns:
        The problem in one line, or None when the table is valid.
    """
    errors = sorted(_VALIDATOR.evolve(schema=SCHEMA["properties"]["terrain"]).iter_errors(table),
                    key=lambda e: [str(k) for k in e.absolute_path])
    return None if not errors else _message(errors[0], table)


def schema_problem(data: dict) -> str | None:
    """The first problem of a parsed constraint file against :data:`SCHEMA` as one line, or None.

    Args:
        data: The parsed TOML document.

    Returns:
        ``None`` when the file's types, shapes and ranges are valid; otherwise a message naming the entry (e.g.
        ``wheels[0] (left).radius = -0.1; expected a radius in m, > 0 ...``).
    """
    errors = sorted(_VALIDATOR.iter_errors(data), key=lambda e: [str(k) for k in e.absolute_path])
    if not errors:
        return None
    # the shallowest, first entry in file order; anyOf errors stay at their node (its 'expected' says it all)
    return _message(errors[0], data)


__all__ = ["SCHEMA", "schema_problem", "terrain_problem", "MAX_RADIUS", "MAX_LENGTH", "MAX_DURATION", "MAX_ENTRIES"]
