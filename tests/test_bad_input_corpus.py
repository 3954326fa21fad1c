"""A corpus of bad invocations (issue 15): every subcommand, every key of the constraint file, files, numbers and
descriptions. Each case must end with exit status 2 and exactly one line ``robotdyn: error: ...`` on stderr that
names what was wrong (the case's ``needle``), never a traceback, never an exception escaping ``main``, never
accepted silently and never a hang (a case taking more than ``CASE_SECONDS`` fails).

Cases run in-process (``robotdyn.cli.main(argv)``, what the console script calls, see robotdyn/__main__.py); a few
run through ``python -m robotdyn`` to show that the real entry point behaves the same.
"""

from __future__ import annotations

import copy
import os
import signal
import subprocess
import sys
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import pytest
import tomli_w

from robotdyn.cli import main

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
SKID = EXAMPLES / "skid_steer.toml"
SKID_XACRO = EXAMPLES / "skid_steer.urdf.xacro"
CASE_SECONDS = 20
"""A case running longer than this is a hang (the slowest legitimate refusal takes well under a second)."""


@dataclass
class Case:
    """One bad invocation: ``argv`` (``{d}`` stands for the case's temporary directory), the files it needs
    (name -> text, bytes, ``DIR`` for a directory or ``FIFO`` for a named pipe) and a text the one-line message
    must contain."""

    id: str
    argv: list[str]
    needle: str
    files: dict = field(default_factory=dict)


DIR = object()
FIFO = object()
LOOP = object()
CASES: list[Case] = []


def case(id: str, argv, needle: str, files: dict | None = None) -> None:
    CASES.append(Case(id, list(argv), needle, files or {}))


# ------------------------------------------------------------------------------------------ robots, facts
ROBOTS = {  # name: (a scenario, number of independent velocities, nq, motors, a length parameter, a mass parameter)
    "quasimoro": ("rectilinear", 3, 6, 2, "r", "M"),
    "omni_caster": ("circle", 3, 9, 6, "l", "m_pl"),
    "linkage_suspension": ("straight_line", 2, 25, 6, "r", "m_body"),
    "mmr12_eod": ("straight", 12, 16, 12, "r", "m_platform"),
    "adaptable_wheel": ("hold", 3, 15, 6, "Lx", "m"),
}
COMMANDS = ("info", "dump", "simulate", "compare", "view", "sweep")


def _skid(**changes) -> dict:
    """examples/skid_steer.toml as data with an absolute urdf, then ``changes`` (dotted keys; None deletes)."""
    data = tomllib.loads(SKID.read_text())
    data["urdf"] = str(SKID_XACRO)
    for dotted, value in changes.items():
        node, keys = data, dotted.split(".")
        for k in keys[:-1]:
            node = node[int(k)] if isinstance(node, list) else node[k]
        last = int(keys[-1]) if isinstance(node, list) else keys[-1]
        if value is None:
            del node[last]
        else:
            node[last] = value
    return data


def toml_case(id: str, needle: str, data: dict | str | bytes, command: str = "info", extra=()) -> None:
    text = tomli_w.dumps(data) if isinstance(data, dict) else data
    argv = {"info": ["info"], "dump": ["dump", "--v", *["0"] * 7, "--tau", *["0"] * 4], "simulate": ["simulate", "--scenario", "straight",
                                                                                 "--quiet"]}[command]
    case(f"toml-{id}", [*argv, "--constraints", "{d}/robot.toml", *extra], needle, {"robot.toml": text})


def urdf_text(mass: str = "5.0", wheel_mass: str = "1.0", lower: str = "-1", upper: str = "1", ixx: str = "0.1",
              radius: str = "0.1", origin: str = "0 0.2 0", extra: str = "") -> str:
    """A differential-drive base (planar root, two wheels) with an arm joint, its numbers open to corruption."""
    def wheel(side: str, y: str) -> str:
        return f"""
  <link name="{side}_wheel"><inertial><origin xyz="0 0 0"/><mass value="{wheel_mass}"/>
    <inertia ixx="0.01" iyy="0.02" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><geometry><cylinder radius="{radius}" length="0.04"/></geometry></visual></link>
  <joint name="{side}_spin" type="continuous"><parent link="base"/><child link="{side}_wheel"/>
    <origin xyz="{y}" rpy="0 0 0"/><axis xyz="0 1 0"/></joint>"""

    return f"""<?xml version="1.0"?>
<robot name="dd">
  <link name="base"><inertial><origin xyz="0 0 0.1"/><mass value="{mass}"/>
    <inertia ixx="{ixx}" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  {wheel("left", origin)}
  {wheel("right", "0 -0.2 0")}
  <link name="arm"><inertial><origin xyz="0.1 0 0"/><mass value="1"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="arm"/><origin xyz="0 0 0.2"/>
    <axis xyz="0 1 0"/><limit lower="{lower}" upper="{upper}" effort="10" velocity="1"/></joint>
  {extra}
</robot>
"""


DD_TOML = """name = "dd"
urdf = "robot.urdf"
root = "planar"
[[wheels]]
name = "left"
joint = "left_spin"
radius = 0.1
[[wheels]]
name = "right"
joint = "right_spin"
radius = 0.1
[[motors]]
name = "tau_L"
joint = "left_spin"
[[motors]]
name = "tau_R"
joint = "right_spin"
[[motors]]
name = "tau_S"
joint = "shoulder"
[[scenarios]]
name = "go"
t_end = 1.0
torque = [0.1, 0.1, 0.0]
"""


def dd_case(id: str, needle: str, urdf: str | bytes, command=("info",), toml: str = DD_TOML) -> None:
    case(f"urdf-{id}", [*command, "--constraints", "{d}/robot.toml"], needle,
         {"robot.toml": toml, "robot.urdf": urdf})


# ------------------------------------------------------------------------------------- argparse, commands
case("argv-empty", [], "COMMAND")
case("argv-unknown-command", ["frobnicate"], "frobnicate")
case("argv-typo-command", ["simulat", "quasimoro"], "simulat")
case("argv-top-unknown-option", ["--verbose", "list"], "--verbose")
REQUIRED = {"dump": ["--v", "0", "0", "0"], "simulate": ["--scenario", "rectilinear", "--quiet"],
            "view": ["--html", "{d}/v.html"], "fk": ["--q", *["0"] * 6, "--frame", "world"],
            "impulse": ["--q", *["0"] * 9, "--direction", "1", "0", "0"], "sweep": ["--out", "{d}/s", "--workers", "0"]}
"""What each command needs besides the robot, so that a case fails for its own mistake only."""
for cmd in COMMANDS + ("list", "ik", "linkage-posture", "fk", "impulse"):
    robot = [] if cmd in ("list", "linkage-posture") else ["omni_caster" if cmd == "impulse" else "quasimoro"]
    case(f"argv-{cmd}-unknown-option", [cmd, *robot, *REQUIRED.get(cmd, []), "--bogus-flag"], "--bogus-flag")
for cmd in ("info", "dump", "simulate", "compare", "view", "sweep"):
    need = REQUIRED.get(cmd, [])
    case(f"argv-{cmd}-unknown-robot", [cmd, "nosuchrobot", *need], "nosuchrobot")
    case(f"argv-{cmd}-robot-and-constraints", [cmd, "quasimoro", "--constraints", str(SKID), *need],
         "exactly one" if cmd == "sweep" else "not both")
    if cmd != "sweep":
        case(f"argv-{cmd}-urdf-without-constraints", [cmd, "--urdf", str(SKID_XACRO), *need], "--constraints")
        case(f"argv-{cmd}-no-robot", [cmd, *need], "ROBOT")
        case(f"argv-{cmd}-package-builtin", [cmd, "quasimoro", "--package", "{d}", *need], "--package")
    case(f"argv-{cmd}-param-unknown", [cmd, "quasimoro", "--param", "nosuch=1", *need], "nosuch")
    case(f"argv-{cmd}-param-no-equals", [cmd, "quasimoro", "--param", "M", *need], "--param")
    case(f"argv-{cmd}-xacro-arg-no-equals", [cmd, "quasimoro", "--xacro-arg", "r", *need], "--xacro-arg")
    if cmd != "sweep":
        case(f"argv-{cmd}-xacro-arg-builtin", [cmd, "quasimoro", "--xacro-arg", "r=0.2", *need], "--xacro-arg")
    if cmd != "sweep":
        case(f"argv-{cmd}-twist-unknown-frame", [cmd, "quasimoro", "--twist", "nosuchframe", *need], "nosuchframe")
case("argv-dump-missing-v", ["dump", "quasimoro"], "--v")
case("argv-dump-a-and-tau", ["dump", "quasimoro", "--v", "0", "0", "0", "--a", "0", "0", "0", "--tau", "0", "0"],
     "--tau")
case("argv-simulate-missing-scenario", ["simulate", "quasimoro"], "--scenario")
case("argv-simulate-t-end-word", ["simulate", "quasimoro", "--scenario", "rectilinear", "--t-end", "ten"], "--t-end")
case("argv-simulate-mu-word", ["simulate", "quasimoro", "--scenario", "rectilinear", "--mu", "high"], "--mu")
case("argv-simulate-stabilisation-neg", ["simulate", "quasimoro", "--scenario", "rectilinear", "--stabilisation",
                                         "-1"], "--stabilisation")
case("argv-simulate-stabilisation-nan", ["simulate", "quasimoro", "--scenario", "rectilinear", "--stabilisation",
                                         "nan"], "--stabilisation")
case("argv-view-t-end-word", ["view", "quasimoro", "--scenario", "rectilinear", "--t-end", "x", "--html", "{d}/a.html"],
     "--t-end")
case("argv-ik-mission-unknown", ["ik", "adaptable_wheel", "--mission", "nosuch"], "--mission")
case("argv-fk-missing-frame", ["fk", "quasimoro", "--q", "0", "0", "0", "0", "0", "0"], "--frame")
case("argv-impulse-missing-direction", ["impulse", "omni_caster", "--q", *["0"] * 9], "--direction")
case("argv-linkage-posture-x-word", ["linkage-posture", "--x", "far"], "--x")
case("argv-sweep-n-word", ["sweep", "quasimoro", "--n", "many", "--out", "{d}/s"], "--n")
case("argv-sweep-sample-unknown", ["sweep", "quasimoro", "--sample", "sobol", "--out", "{d}/s"], "--sample")
case("argv-sweep-workers-word", ["sweep", "quasimoro", "--workers", "all", "--out", "{d}/s"], "--workers")
case("argv-list-extra", ["list", "quasimoro"], "quasimoro")

# ------------------------------------------------------------------------------------ numbers, per robot
BAD_NUMBERS = {"nan": "nan", "inf": "inf", "neginf": "-inf", "word": "abc", "huge": "1e300", "overflow": "1e400"}
for robot, (scenario, nv, nq, nm, length, mass) in ROBOTS.items():
    zeros_v, zeros_q, zeros_m = ["0"] * nv, ["0"] * nq, ["0"] * nm
    case(f"dump-{robot}-v-short", ["dump", robot, "--v", *zeros_v[:-1]], "v")
    case(f"dump-{robot}-v-long", ["dump", robot, "--v", *zeros_v, "0"], "v")
    case(f"dump-{robot}-q-short", ["dump", robot, "--q", *zeros_q[:-1], "--v", *zeros_v], "q")
    case(f"dump-{robot}-a-short", ["dump", robot, "--v", *zeros_v, "--a", *zeros_v[:-1]], "a")
    case(f"dump-{robot}-set-unknown", ["dump", robot, "--v", *zeros_v, "--set", "nosuchcoord=1"], "nosuchcoord")
    case(f"dump-{robot}-set-nan", ["dump", robot, "--v", *zeros_v, "--set", "x=nan"], "--set")
    on_ground = robot != "adaptable_wheel"  # its neutral configuration is off the ground: no dynamics there
    if on_ground:
        case(f"dump-{robot}-tau-short", ["dump", robot, "--v", *zeros_v, "--tau", *zeros_m[:-1]], "tau")
        case(f"dump-{robot}-tau-set-unknown", ["dump", robot, "--v", *zeros_v, "--tau-set", "nosuchmotor=1"],
             "nosuchmotor")
        case(f"dump-{robot}-tau-set-word", ["dump", robot, "--v", *zeros_v, "--tau-set", "nosuchmotor=big"],
             "--tau-set")
        case(f"dump-{robot}-forces-alone", ["dump", robot, "--v", *zeros_v, "--forces"], "--forces")
    for label, bad in BAD_NUMBERS.items():
        case(f"dump-{robot}-v-{label}", ["dump", robot, "--v", bad, *zeros_v[1:]], "v")
        if on_ground:
            case(f"dump-{robot}-tau-{label}", ["dump", robot, "--v", *zeros_v, "--tau", bad, *zeros_m[1:]], "tau")
    for label, bad in (("nan", "nan"), ("huge", "1e300"), ("word", "abc")):
        case(f"dump-{robot}-q-{label}", ["dump", robot, "--q", bad, *zeros_q[1:], "--v", *zeros_v], "q")
        case(f"dump-{robot}-a-{label}", ["dump", robot, "--v", *zeros_v, "--a", bad, *zeros_v[1:]], "a")
    # finite but huge: the results would overflow
    case(f"dump-{robot}-v-1e200", ["dump", robot, "--v", *["1e200"] * nv], "v")
    case(f"dump-{robot}-full-v-1e200", ["dump", robot, "--full", "--v", *["1e200"] * nq], "v")
    sim = ["simulate", robot, "--scenario", scenario, "--quiet"]
    for label, bad in (("nan", "nan"), ("inf", "inf"), ("zero", "0"), ("negative", "-1"), ("1e12", "1e12"),
                       ("1e300", "1e300"), ("1e6", "1e6"), ("1e-300", "1e-300")):
        if label in ("nan", "inf", "zero", "negative", "1e12", "1e6") or robot == "quasimoro":
            case(f"simulate-{robot}-t-end-{label}", [*sim, "--t-end", bad], "--t-end")
    case(f"simulate-{robot}-unknown-scenario", ["simulate", robot, "--scenario", "nosuchscenario"], "nosuchscenario")
    case(f"simulate-{robot}-mu-negative", [*sim, "--mu", "-0.5"], "--mu")
    case(f"simulate-{robot}-mu-nan", [*sim, "--mu", "nan"], "--mu")
    case(f"simulate-{robot}-csv-missing-dir", [*sim, "--csv", "{d}/no/such/dir/out.csv"], "out.csv")
    case(f"simulate-{robot}-csv-is-dir", [*sim, "--csv", "{d}"], "directory")
    case(f"simulate-{robot}-csv-is-fifo", [*sim, "--csv", "{d}/pipe.csv"], "pipe.csv", {"pipe.csv": FIFO})
    case(f"simulate-{robot}-plot-unknown-format", [*sim, "--plot", "{d}/out.xyz"], "out.xyz")
    case(f"simulate-{robot}-plot-is-dir", [*sim, "--plot", "{d}"], "directory")
    case(f"simulate-{robot}-plot-no-extension", [*sim, "--plot", "{d}/figure"], "figure")
    case(f"simulate-{robot}-traction-plot-missing-dir", [*sim, "--traction-plot", "{d}/nodir/t.png"], "t.png")
    for label, value in (("nan", "nan"), ("inf", "inf"), ("word", "big"), ("huge", "1e300")):
        case(f"param-{robot}-{length}-{label}", ["info", robot, "--param", f"{length}={value}"], length)
    if length == "r" and robot != "mmr12_eod":  # a wheel radius (mmr12_eod: see the report, issue 15)
        for label, value in (("zero", "0"), ("negative", "-0.1")):
            case(f"param-{robot}-{length}-{label}", ["info", robot, "--param", f"{length}={value}"], length)
    case(f"param-{robot}-{mass}-negative", ["dump", robot, "--param", f"{mass}=-1", "--v", *zeros_v], mass)
    case(f"param-{robot}-{mass}-huge", ["info", robot, "--param", f"{mass}=1e300"], mass)
    case(f"param-{robot}-g-nan", ["info", robot, "--param", "g=nan"], "g")
    case(f"view-{robot}-html-missing-dir", ["view", robot, "--html", "{d}/nodir/page.html"], "page.html")
    case(f"view-{robot}-html-is-dir", ["view", robot, "--html", "{d}"], "directory")
    case(f"view-{robot}-unknown-scenario", ["view", robot, "--scenario", "nosuchscenario", "--html", "{d}/v.html"],
         "nosuchscenario")
    case(f"view-{robot}-t-end-nan", ["view", robot, "--scenario", scenario, "--t-end", "nan", "--html",
                                     "{d}/v.html", "--quiet"], "--t-end")
    case(f"view-{robot}-t-end-1e12", ["view", robot, "--scenario", scenario, "--t-end", "1e12", "--html",
                                      "{d}/v.html", "--quiet"], "--t-end")
    case(f"compare-{robot}-param-nan", ["compare", robot, "--param", f"{length}=nan"], length)
    if robot != "linkage_suspension":  # (its zero configuration is outside the joint ranges)
        case(f"fk-{robot}-unknown-frame", ["fk", robot, "--q", *zeros_q, "--frame", "nosuchframe"],
             "nosuchframe")
    case(f"fk-{robot}-q-nan", ["fk", robot, "--q", "nan", *zeros_q[1:], "--frame", "world"], "q")
    case(f"fk-{robot}-q-short", ["fk", robot, "--q", *zeros_q[1:], "--frame", "world"], "q")
# every parameter of quasimoro (units m, kg, kg m^2, -) refused when not finite
for name in ("m", "M", "J1", "J2", "r", "d", "rho", "g"):
    case(f"param-quasimoro-each-{name}-inf", ["info", "quasimoro", "--param", f"{name}=inf"], name)
case("param-quasimoro-rho-negative", ["info", "quasimoro", "--param", "rho=-0.5"], "rho")
case("param-quasimoro-J1-negative", ["info", "quasimoro", "--param", "J1=-0.1"], "J1")
case("param-quasimoro-inertia-about", ["info", "quasimoro", "--param", "inertia_about=elbow"], "inertia_about")
case("param-quasimoro-all-masses-zero", ["dump", "quasimoro", "--param", "m=0", "--param", "M=0", "--param", "J1=0",
                                         "--param", "J2=0", "--v", "0", "0", "0", "--tau", "1", "1"], "mass")
case("param-omni-all-masses-zero", ["dump", "omni_caster", "--param", "m_pl=0", "--param", "m_wheel=0", "--param",
                                    "m_link=0", "--param", "I_wheel_axle=0", "--param", "I_wheel_diam=0", "--param",
                                    "I_link_x=0", "--param", "I_link_y=0", "--param", "I_link_z=0",
                                    "--v", "0", "0", "0", "--tau", *["1"] * 6], "mass")
case("param-adaptable-wheel-choice", ["info", "adaptable_wheel", "--param", "terrain=lunar"], "terrain")
# lengths (and the masses that carry the whole robot) that must be > 0: zero and negative values refused, naming
# the parameter and the bound; offsets that may be 0 or < 0 (a1, l3, p, ...) are not in this list
POSITIVE = {"quasimoro": {"r": "m", "rho": "-", "M": "kg"},
            "omni_caster": {"l": "m", "b": "m", "d": "m", "r": "m", "m_pl": "kg"},
            "linkage_suspension": {"a5": "m", "d5": "m", "a6": "m", "a7": "m", "r": "m", "wL": "m", "hr": "m",
                                   "m_body": "kg"},
            "mmr12_eod": {"lambda_C0": "m", "b": "m", "l_cs1": "m", "r": "m", "lambda2_max": "m", "lambda6_max": "m",
                          "m_platform": "kg"},
            "adaptable_wheel": {"m": "kg", "w": "m", "Lx": "m", "Ly": "m", "body_height": "m"}}
for robot, names in POSITIVE.items():
    for name, unit in names.items():
        for label, value in (("zero", "0"), ("negative", "-0.1")):
            case(f"param-{robot}-{name}-positive-{label}", ["info", robot, "--param", f"{name}={value}"],
                 f"parameter {name} = {float(value):g} {unit}; expected a value > 0 {unit}")
case("param-adaptable-wheel-R_ru-negative", ["info", "adaptable_wheel", "--param", "R_ru=-0.01"],
     "parameter R_ru = -0.01 m; expected a value >= 0")

# ---------------------------------------------------------------------------------- robot-specific commands
case("ik-commands-short", ["ik", "adaptable_wheel", "--commands", "0", "0"], "--commands")
case("ik-commands-nan", ["ik", "adaptable_wheel", "--commands", "nan", "0", "0.3", "0", "0", "0"], "--commands")
case("ik-commands-word", ["ik", "adaptable_wheel", "--commands", "a", "0", "0.3", "0", "0", "0"], "--commands")
case("ik-commands-huge", ["ik", "adaptable_wheel", "--commands", "1e300", "0", "0.3", "0", "0", "0"], "--commands")
case("ik-nothing", ["ik", "adaptable_wheel"], "--commands")
case("ik-csv-missing-dir", ["ik", "adaptable_wheel", "--mission", "mission1", "--csv", "{d}/no/x.csv"],
     "x.csv")
case("linkage-posture-terrain-unknown", ["linkage-posture", "--terrain", "lunar"], "lunar")
case("linkage-posture-x-nan", ["linkage-posture", "--x", "nan"], "coordinate x")
case("linkage-posture-yaw-inf", ["linkage-posture", "--yaw", "inf"], "--yaw")
case("linkage-posture-v-nan", ["linkage-posture", "--v", "nan", "0"], "--v")
case("linkage-posture-param-unknown", ["linkage-posture", "--param", "nosuch=1"], "nosuch")
case("linkage-posture-x-huge", ["linkage-posture", "--x", "1e300"], "coordinate x")
case("impulse-direction-short", ["impulse", "omni_caster", "--q", *["0"] * 9, "--direction", "1"], "direction")
case("impulse-direction-zero", ["impulse", "omni_caster", "--q", *["0"] * 9, "--direction", "0", "0", "0"], "direction")
case("impulse-direction-nan", ["impulse", "omni_caster", "--q", *["0"] * 9, "--direction", "nan", "1", "0"], "direction")
case("impulse-e-negative", ["impulse", "omni_caster", "--q", *["0"] * 9, "--direction", "1", "0", "0", "--e", "-0.5"],
     "--e")
case("impulse-e-above-one", ["impulse", "omni_caster", "--q", *["0"] * 9, "--direction", "1", "0", "0", "--e", "1.5"],
     "--e")
case("impulse-e-nan", ["impulse", "omni_caster", "--q", *["0"] * 9, "--direction", "1", "0", "0", "--e", "nan"], "--e")
case("impulse-speed-inf", ["impulse", "omni_caster", "--q", *["0"] * 9, "--direction", "1", "0", "0", "--speed", "inf"],
     "--speed")
case("impulse-v-short", ["impulse", "omni_caster", "--q", *["0"] * 9, "--direction", "1", "0", "0", "--v", "0"], "v")
case("impulse-q-short", ["impulse", "omni_caster", "--q", "0", "--direction", "1", "0", "0"], "q")

# ------------------------------------------------------------------------------------------------- sweep
SW = ["sweep", "quasimoro", "--workers", "0", "--quiet", "--no-plot", "--out", "{d}/sweep"]
for id, extra, needle in [
    ("vary-unknown", ["--vary", "nosuch=1:2:3"], "nosuch"),
    ("vary-bad-range", ["--vary", "M=a:b"], "M"),
    ("vary-nan", ["--vary", "M=nan:2:3"], "M"),
    ("vary-inverted", ["--vary", "M=6:4:3"], "M"),
    ("vary-negative-mass", ["--vary", "M=-1:2:3"], "M"),
    ("vary-no-equals", ["--vary", "M"], "--vary"),
    ("vary-too-many", ["--vary", "M=4:6:1000", "--vary", "m=0.1:1:1000", "--vary", "d=0.1:0.3:1000"], "runs"),
    ("n-zero", ["--sample", "lhs", "--n", "0", "--vary", "M=4:6"], "--n"),
    ("n-negative", ["--sample", "random", "--n", "-5", "--vary", "M=4:6"], "--n"),
    ("t-end-nan", ["--t-end", "nan", "--vary", "M=4,5"], "t_end"),
    ("t-end-negative", ["--t-end", "-1", "--vary", "M=4,5"], "t_end"),
    ("t-end-huge", ["--t-end", "1e300", "--vary", "M=4,5"], "t_end"),
    ("rtol-negative", ["--rtol", "-1", "--vary", "M=4,5"], "rtol"),
    ("atol-nan", ["--atol", "nan", "--vary", "M=4,5"], "atol"),
    ("n-out-zero", ["--n-out", "0", "--vary", "M=4,5"], "--n-out"),
    ("n-out-huge", ["--n-out", "1000000000000", "--vary", "M=4,5"], "n_out"),
    ("chunk-size-zero", ["--chunk-size", "0", "--vary", "M=4,5"], "--chunk-size"),
    ("workers-negative", ["--workers", "-3", "--vary", "M=4,5"], "--workers"),
    ("scenario-unknown", ["--scenario", "nosuchscenario", "--vary", "M=4,5"], "nosuchscenario"),
    ("terrain-unknown", ["--terrain", "lunar", "--vary", "M=4,5"], "lunar"),
    ("terrain-bad-arg", ["--terrain", "ramp:slop=0.1", "--vary", "M=4,5"], "slop"),
    ("column-unknown", ["--column", "nosuchcolumn", "--vary", "M=4,5"], "nosuchcolumn"),
    ("time-limit-negative", ["--time-limit", "-1", "--vary", "M=4,5"], "time_limit"),
    ("spec-missing", ["--spec", "{d}/nosuch.toml"], "nosuch.toml"),
    ("spec-binary", ["--spec", "{d}/bin.toml"], "bin.toml"),
    ("spec-invalid", ["--spec", "{d}/bad.toml"], "bad.toml"),
    ("spec-unknown-key", ["--spec", "{d}/unknown.toml"], "paramters"),
    ("spec-parameters-list", ["--spec", "{d}/plist.toml"], "parameters"),
    ("spec-dir", ["--spec", "{d}"], "sweep file"),
    ("out-is-file", ["--vary", "M=4,5", "--out", "{d}/file.txt"], "file.txt"),
]:
    case(f"sweep-{id}", [*SW, *extra], needle, {
        "bin.toml": b"\xff\xfe\x00\x81garbage", "bad.toml": "robot = [", "unknown.toml": "paramters = {M = [4, 5]}\n",
        "plist.toml": 'robot = "quasimoro"\nparameters = [1, 2]\n', "file.txt": "x",
    })

# ------------------------------------------------------------------------------------------- TOML files
toml_case("binary", "UTF-8", b"\xff\xfe\x00\x81\x90 garbage")
toml_case("invalid", "not valid TOML", "name = [\n")
toml_case("empty-description", "urdf", "")
toml_case("huge", "bytes", "# " + "x" * 2_000_000 + "\n")
toml_case("deep-nesting", "not valid TOML", "a = " + "[" * 5000 + "]" * 5000 + "\n")
case("toml-is-directory", ["info", "--constraints", "{d}/sub"], "sub", {"sub": DIR})
case("toml-missing", ["info", "--constraints", "{d}/missing.toml"], "missing.toml")
toml_case("unknown-top-key", "wheel", _skid(wheel=[{"name": "x"}]))
toml_case("unknown-wheel-key", "radious", _skid(**{"wheels.0.radious": 0.1}))
toml_case("unknown-motor-key", "reactoin", _skid(**{"motors.0.reactoin": "chassis"}))
toml_case("unknown-scenario-key", "torques", _skid(**{"scenarios.0.torques": [1, 1, 1, 1]}))
toml_case("unknown-parameter-key", "defualt", _skid(**{"parameters.0.defualt": 0.1}))
toml_case("root-unknown", "root", _skid(root="flying"))
toml_case("root-table", "root", _skid(root={"kind": "planar"}))
toml_case("root-list", "root", _skid(root=["planar"]))
toml_case("terrain-kind-table", "kind", _skid(terrain={"kind": {"a": 1}}))
toml_case("terrain-kind-list", "kind", _skid(terrain={"kind": ["flat"]}))
toml_case("terrain-unknown-kind", "kind", _skid(terrain={"kind": "lunar"}))
toml_case("terrain-unknown-arg", "slop", _skid(terrain={"kind": "ramp", "slop": 0.1}))
toml_case("terrain-list", "terrain", _skid(terrain=[1, 2]))
toml_case("terrain-slope-text", "slope", _skid(terrain={"kind": "ramp", "slope": "steep"}))
toml_case("terrain-bump-width-zero", "width", _skid(terrain={"kind": "bump", "height": 0.05, "width": 0.0}))
toml_case("terrain-bump-width-negative", "width", _skid(terrain={"kind": "bump", "height": 0.05, "width": -1.0}))
toml_case("terrain-slope-nan", "slope", "urdf = '%s'\nroot = 'floating'\n[terrain]\nkind = 'ramp'\nslope = nan\n"
          % SKID_XACRO)
toml_case("terrain-height-inf", "height", "urdf = '%s'\nroot = 'floating'\n[terrain]\nkind = 'flat'\nheight = inf\n"
          % SKID_XACRO)
toml_case("wheels-table", "wheels", _skid(wheels={"name": "x"}))
toml_case("wheels-int", "wheels", _skid(wheels=3))
toml_case("wheel-radius-zero", "radius", _skid(**{"wheels.0.radius": 0.0}))
toml_case("wheel-radius-negative", "radius", _skid(**{"wheels.0.radius": -0.1}))
toml_case("wheel-radius-list", "radius", _skid(**{"wheels.0.radius": [0.1]}))
toml_case("wheel-radius-unknown-param", "radius", _skid(**{"wheels.0.radius": "rr"}))
toml_case("wheel-radius-huge", "radius", _skid(**{"wheels.0.radius": 1e9}))
toml_case("wheel-joint-unknown", "front_left_spn", _skid(**{"wheels.0.joint": "front_left_spn"}))
toml_case("wheel-joint-int", "joint", _skid(**{"wheels.0.joint": 3}))
toml_case("wheel-joint-and-frame", "frame", _skid(**{"wheels.0.frame": "front_left_wheel"}))
toml_case("wheel-axis-two", "axis", _skid(**{"wheels.0.axis": [0, 1]}))
toml_case("wheel-axis-zero", "axis", _skid(**{"wheels.0.axis": [0, 0, 0]}))
toml_case("wheel-axis-text", "axis", _skid(**{"wheels.0.axis": "y"}))
toml_case("wheel-axis-nested", "axis", _skid(**{"wheels.0.axis": [[0], [1], [0]]}))
toml_case("wheel-kind-unknown", "kind", _skid(**{"wheels.0.kind": "mecanum"}))
toml_case("wheel-kind-table", "kind", _skid(**{"wheels.0.kind": {"a": 1}}))
toml_case("wheel-mu-negative", "mu", _skid(**{"wheels.0.mu": -0.5}))
toml_case("wheel-mu-text", "mu", _skid(**{"wheels.0.mu": "high"}))
toml_case("wheel-friction-unknown", "friction", _skid(**{"wheels.0.friction": "sticky"}))
toml_case("wheel-friction-list", "friction", _skid(**{"wheels.0.friction": ["linear"]}))
toml_case("wheel-stiffness-negative", "stiffness", _skid(**{"wheels.0.stiffness": -5.0}))
toml_case("wheel-slip-unknown", "slip", _skid(**{"wheels.0.slip": "sideways"}))
toml_case("wheel-roller-not-omni", "roller_angle", _skid(**{"wheels.0.roller_angle": 0.5}))
toml_case("wheel-duplicate-name", "front_left", _skid(**{"wheels.1.name": "front_left"}))
toml_case("wheel-duplicate-joint", "front_left_spin", _skid(**{"wheels.1.joint": "front_left_spin",
                                                               "wheels.1.name": "other"}))
toml_case("wheels-20000", "bytes", _skid(wheels=[{"name": f"w{i}", "joint": "front_left_spin", "radius": 0.1}
                                                  for i in range(20000)]))
toml_case("motors-int", "motors", _skid(motors=1))
toml_case("motor-joint-unknown", "nosuchjoint", _skid(**{"motors.0.joint": "nosuchjoint"}))
toml_case("motor-joint-fixed", "joint", _skid(**{"motors.0.joint": "chassis"}))
toml_case("motor-reaction-unknown", "nowhere", _skid(**{"motors.0.reaction": "nowhere"}))
toml_case("motor-duplicate-name", "tau_fl", _skid(**{"motors.1.name": "tau_fl"}))
toml_case("motor-name-list", "name", _skid(**{"motors.0.name": ["a"]}))
toml_case("closures-table", "closures", _skid(closures={"frame1": "a"}))
toml_case("closure-frame-unknown", "nosuchframe", _skid(closures=[{"frame1": "nosuchframe", "frame2": "chassis"}]))
toml_case("closure-same-body", "same rigid body", _skid(closures=[{"frame1": "chassis", "frame2": "chassis"}]))
toml_case("closure-components-bad", "components", _skid(closures=[{"frame1": "front_axle", "frame2": "chassis",
                                                                   "components": "x q"}]))
toml_case("closure-components-int", "components", _skid(closures=[{"frame1": "front_axle", "frame2": "chassis",
                                                                   "components": 3}]))
toml_case("closure-root-chain", "closures[0]", _skid(closures=[{"frame1": "x", "frame2": "y",
                                                                "components": "x"}]))
toml_case("independent-unknown", "nosuchcoord", _skid(independent=["nosuchcoord"]))
toml_case("independent-int", "independent", _skid(independent=3))
toml_case("independent-empty", "independent", _skid(independent=[]))
toml_case("independent-duplicate", "independent", _skid(independent=["x", "x", "y", "yaw", "front_left_spin",
                                                                      "front_right_spin", "rear_left_spin"]))
toml_case("independent-too-many", "independent", _skid(independent=["x", "y", "z", "yaw", "pitch", "roll",
                                                                     "axle_roll", "front_left_spin",
                                                                     "front_right_spin", "rear_left_spin",
                                                                     "rear_right_spin"]))
toml_case("labels-list", "labels", _skid(labels=["a"]))
toml_case("labels-unknown-joint", "nosuchjoint", _skid(labels={"nosuchjoint": "a"}))
toml_case("labels-int", "labels", _skid(labels={"axle_roll": 3}))
toml_case("labels-duplicate", "labels", _skid(labels={"axle_roll": "spin", "front_left_spin": "spin"}))
toml_case("labels-shadow", "labels", _skid(labels={"axle_roll": "front_left_spin"}))
toml_case("labels-shadow-root", "labels", _skid(labels={"axle_roll": "x"}))
toml_case("neutral-list", "neutral", _skid(neutral=[0.1]))
toml_case("neutral-unknown", "nosuchcoord", _skid(neutral={"nosuchcoord": 0.1}))
toml_case("neutral-text", "neutral", _skid(neutral={"z": "high"}))
toml_case("neutral-table", "neutral", _skid(neutral={"z": {"a": 1}}))
toml_case("neutral-huge", "neutral", _skid(neutral={"z": 1e300}))
toml_case("locked-list", "locked", _skid(locked=["axle_roll"]))
toml_case("locked-unknown", "nosuchjoint", _skid(locked={"nosuchjoint": 0.0}))
toml_case("locked-text", "locked", _skid(locked={"axle_roll": "zero"}))
toml_case("locked-wheel", "front_left_spin", _skid(locked={"front_left_spin": 0.0}))
toml_case("massless-unknown", "nosuchlink", _skid(massless=["nosuchlink"]))
toml_case("massless-table", "massless", _skid(massless={"a": 1}))
toml_case("massless-all", "mass", _skid(massless=["chassis", "front_axle", "front_left_wheel", "front_right_wheel",
                                                  "rear_left_wheel", "rear_right_wheel"]), "dump")
toml_case("xacro-args-list", "xacro_args", _skid(xacro_args=["a=1"]))
toml_case("xacro-args-unknown", "nosucharg", _skid(xacro_args={"nosucharg": "1"}))
toml_case("xacro-args-code", "a", _skid(xacro_args={"a": "__import__('os').getcwd()"}))
toml_case("xacro-args-code-lambda", "a", _skid(xacro_args={"a": "(lambda: 1)()"}))
toml_case("xacro-args-negative-length", "a", _skid(xacro_args={"a": "-0.25"}))
toml_case("xacro-args-zero-mass", "m_body", _skid(xacro_args={"m_body": "0"}))
toml_case("xacro-args-table", "xacro_args", _skid(xacro_args={"a": {"b": 1}}))
toml_case("xacro-args-param", "r", _skid(xacro_args={"r": "0.2"}))
toml_case("parameters-table", "parameters", _skid(parameters={"name": "r"}))
toml_case("parameter-no-default", "default", _skid(**{"parameters.0.default": None}))
toml_case("parameter-default-text", "default", _skid(**{"parameters.0.default": "big"}))
toml_case("parameter-default-zero-radius", "r", _skid(**{"parameters.0.default": 0.0}))
toml_case("parameter-default-negative-radius", "r", _skid(**{"parameters.0.default": -0.1}))
toml_case("parameter-duplicate", "twice", _skid(parameters=[{"name": "r", "default": 0.1, "xacro": True},
                                                            {"name": "r", "default": 0.1, "xacro": True}]))
toml_case("parameter-choices-code", "r", _skid(**{"parameters.0.default": "__import__('os')",
                                                  "parameters.0.choices": ["__import__('os')", "0.1"]}))
toml_case("parameter-choices-int", "choices", _skid(**{"parameters.0.choices": 3}))
toml_case("parameter-xacro-text", "xacro", _skid(**{"parameters.0.xacro": "yes"}))
toml_case("parameter-name-int", "name", _skid(**{"parameters.0.name": 3}))
toml_case("scenarios-table", "scenarios", _skid(scenarios={"name": "x"}))
toml_case("scenario-duplicate", "straight", _skid(**{"scenarios.0.name": "straight"}))
toml_case("scenario-t-end-zero", "t_end", _skid(**{"scenarios.0.t_end": 0.0}))
toml_case("scenario-t-end-negative", "t_end", _skid(**{"scenarios.0.t_end": -1.0}))
toml_case("scenario-t-end-text", "t_end", _skid(**{"scenarios.0.t_end": "long"}))
toml_case("scenario-t-end-huge", "t_end", _skid(**{"scenarios.0.t_end": 1e300}))
toml_case("scenario-t-end-missing", "t_end", _skid(**{"scenarios.0.t_end": None}))
toml_case("scenario-torque-short", "torque", _skid(**{"scenarios.0.torque": [0.3]}))
toml_case("scenario-torque-int", "torque", _skid(**{"scenarios.0.torque": 3}))
toml_case("scenario-torque-unknown-motor", "tau_xx", _skid(**{"scenarios.0.torque": {"tau_xx": 1.0}}))
toml_case("scenario-torque-text", "torque", _skid(**{"scenarios.0.torque": ["a", "b", "c", "d"]}))
toml_case("scenario-torque-huge", "torque", _skid(**{"scenarios.0.torque": [1e300] * 4}))
toml_case("scenario-q0-list", "q0", _skid(**{"scenarios.0.q0": [0.1]}))
toml_case("scenario-q0-unknown", "nosuchcoord", _skid(**{"scenarios.0.q0": {"nosuchcoord": 0.1}}))
toml_case("scenario-q0-huge", "q0", _skid(**{"scenarios.0.q0": {"x": 1e300}}))
toml_case("scenario-nu0-unknown", "nosuchcoord", _skid(**{"scenarios.0.nu0": {"nosuchcoord": 0.1}}))
toml_case("scenario-nu0-dependent", "axle_roll", _skid(**{"scenarios.0.nu0": {"axle_roll": 0.1}}))
toml_case("scenario-nu0-huge", "nu0", _skid(**{"scenarios.0.nu0": {"x": 1e300}}))
toml_case("scenario-nu0-text", "nu0", _skid(**{"scenarios.0.nu0": {"x": "fast"}}))
toml_case("scenario-name-missing", "name", _skid(**{"scenarios.0.name": None}))
toml_case("twist-list", "twist", _skid(independent=None, twist=["chassis"]))
toml_case("twist-frame-unknown", "nosuchframe", _skid(independent=None, twist={"frame": "nosuchframe"}))
toml_case("twist-components-bad", "components", _skid(independent=None, twist={"frame": "chassis",
                                                                                "components": ["vq"]}))
toml_case("twist-axes-bad", "axes", _skid(independent=None, twist={"frame": "chassis", "axes": "sideways"}))
toml_case("twist-and-independent", "twist", _skid(twist={"frame": "chassis"}))
toml_case("root-height-text", "root_height", _skid(root_height="high"))
toml_case("root-height-huge", "root_height", _skid(root_height=1e9))
toml_case("package-dirs-missing", "package_dirs", _skid(package_dirs=["/no/such/dir"]))
toml_case("package-dirs-int", "package_dirs", _skid(package_dirs=3))
toml_case("packages-list", "packages", _skid(packages=["a"]))
toml_case("packages-missing-dir", "packages", _skid(packages={"pkg": "/no/such/dir"}))
toml_case("urdf-missing", "nosuch.urdf", _skid(urdf="/no/such/nosuch.urdf"))
toml_case("urdf-int", "urdf", _skid(urdf=3))
toml_case("urdf-package-unknown", "nosuchpkg", _skid(urdf="package://nosuchpkg/robot.urdf"))
toml_case("name-list", "name", _skid(name=["a"]))
toml_case("title-table", "title", _skid(title={"a": 1}))
toml_case("paper-list", "paper", _skid(paper=[1]))
case("toml-xacro-arg-cli-code", ["info", "--constraints", str(SKID), "--xacro-arg", "a=__import__('os').getcwd()"],
     "a")
case("toml-xacro-arg-cli-unknown", ["info", "--constraints", str(SKID), "--xacro-arg", "nosucharg=1"], "nosucharg")
case("toml-xacro-arg-cli-negative", ["info", "--constraints", str(SKID), "--xacro-arg", "b=-0.22"], "b")
case("toml-xacro-arg-cli-zero", ["info", "--constraints", str(SKID), "--xacro-arg", "b=0"], "b")
case("toml-xacro-arg-cli-nan", ["info", "--constraints", str(SKID), "--xacro-arg", "b=nan"], "b")
case("toml-param-cli-zero-radius", ["info", "--constraints", str(SKID), "--param", "r=0"], "r")
case("toml-param-cli-negative-radius", ["info", "--constraints", str(SKID), "--param", "r=-0.1"], "r")
case("toml-param-cli-code", ["info", "--constraints", str(SKID), "--param", "r=__import__('os')"], "r")
case("toml-twist-cli-unknown-frame", ["info", "--constraints", str(SKID), "--twist", "nosuchframe"], "nosuchframe")
case("toml-package-cli-missing", ["info", "--constraints", str(SKID), "--package", "/no/such/dir"], "/no/such/dir")
case("toml-simulate-unknown-scenario", ["simulate", "--constraints", str(SKID), "--scenario", "nosuch"], "nosuch")
case("toml-urdf-cli-missing", ["info", "--constraints", str(SKID), "--urdf", "{d}/nosuch.urdf"], "nosuch.urdf")
case("toml-urdf-cli-binary", ["info", "--constraints", str(SKID), "--urdf", "{d}/bin.urdf"], "bin.urdf",
     {"bin.urdf": b"\xff\xfe\x00\x81\x90 garbage"})
case("toml-urdf-cli-directory", ["info", "--constraints", str(SKID), "--urdf", "{d}"], "description")

# ------------------------------------------------------------------------------------------------ linearize
LIN = ["linearize", "quasimoro"]
UPRIGHT = ["--set", "theta3=3.14159", "--states", "theta3", "theta1_dot", "theta2_dot", "theta3_dot"]
case("linearize-unknown-option", [*LIN, "--bogus-flag"], "--bogus-flag")
case("linearize-states-unknown", [*LIN, "--states", "nosuchstate"], "nosuchstate")
case("linearize-v-short", [*LIN, "--v", "0", "0"], "v")
case("linearize-v-nan", [*LIN, "--v", "nan", "0", "0"], "v")
case("linearize-v-word", [*LIN, "--v", "fast", "0", "0"], "v")
case("linearize-tau-short", [*LIN, "--tau", "1"], "tau")
case("linearize-tau-inf", [*LIN, "--tau", "inf", "0"], "tau")
case("linearize-tau-set-unknown", [*LIN, "--tau-set", "nosuchmotor=1"], "nosuchmotor")
case("linearize-q-short", [*LIN, "--q", "0", "0", "0"], "q")
case("linearize-set-unknown", [*LIN, "--set", "nosuchcoord=1"], "nosuchcoord")
case("linearize-off-ground", ["linearize", "adaptable_wheel"], "normal")
case("linearize-lqr-q-alone", [*LIN, *UPRIGHT, "--lqr-q", "1", "1", "1", "1"], "--lqr-r")
case("linearize-lqr-q-short", [*LIN, *UPRIGHT, "--lqr-q", "1", "1", "--lqr-r", "1", "1"], "--lqr-q")
case("linearize-lqr-q-nan", [*LIN, *UPRIGHT, "--lqr-q", "nan", "1", "1", "1", "--lqr-r", "1", "1"], "--lqr-q")
case("linearize-lqr-r-zero", [*LIN, *UPRIGHT, "--lqr-q", "1", "1", "1", "1", "--lqr-r", "0", "1"], "--lqr-r")
case("linearize-lqr-unstabilisable", [*LIN, "--lqr-q", *["1"] * 9, "--lqr-r", "1", "1"], "stabilisable")

# ------------------------------------------------------------ optimise, compliant wheels, joint springs
OPT = ["optimise", "quasimoro", "--t-end", "1", "--nodes", "5"]
case("optimise-end-beyond-reach", [*OPT, "--end", "x=1e9"], "q_end")  # was IPOPT tracebacks at trial points
case("optimise-nodes-huge", ["optimise", "quasimoro", "--t-end", "1", "--nodes", "20000", "--end", "x=0.1"],
     "nodes")  # was a collocation of 20,000 nodes started (10^8: memory exhausted)
case("optimise-end-unknown", [*OPT, "--end", "nosuchcoord=1"], "nosuchcoord")
case("optimise-bound-inverted", [*OPT, "--end", "x=0.1", "--bound", "theta3=0.1:-0.1"], "theta3")
case("optimise-final-outside-bounds", [*OPT, "--end", "x=0.1", "--bound", "x=-1:0.05"], "x")
case("optimise-compliant-wheels", ["optimise", "--constraints", str(EXAMPLES / "bump_base.toml"), "--t-end", "1",
                                   "--nodes", "3", "--end", "x=0.1"], "compliant")  # was a failed IPOPT solve
case("linearize-state-twice", [*LIN, "--states", "theta3", "theta3"], "theta3")  # was accepted as one state


def _bump(**changes) -> dict:
    """examples/bump_base.toml (compliant wheels) as data with an absolute urdf, then ``changes`` (as _skid)."""
    data = tomllib.loads((EXAMPLES / "bump_base.toml").read_text())
    data["urdf"] = str(EXAMPLES / data["urdf"])
    for dotted, value in changes.items():
        keys = dotted.split(".")
        node = data
        for k in keys[:-1]:
            node = node[int(k)] if isinstance(node, list) else node[k]
        node[keys[-1]] = value
    return data


toml_case("compliant-stiffness-zero", "normal_stiffness", _bump(**{"wheels.0.normal_stiffness": 0.0}))
toml_case("compliant-stiffness-inf", "normal_stiffness", _bump(**{"wheels.0.normal_stiffness": float("inf")}))
toml_case("compliant-damping-negative", "normal_damping", _bump(**{"wheels.0.normal_damping": -1.0}))
toml_case("compliant-hunt-crossley-stiffness-zero", "stiffness in N/m^n",  # (Hunt-Crossley's k: N/m^n, not N/m)
          _bump(**{"wheels.0.contact_law": "hunt_crossley", "wheels.0.normal_stiffness": 0.0}))
toml_case("compliant-hunt-crossley-damping-negative", "damping in N s/m^(n+1)",
          _bump(**{"wheels.0.contact_law": "hunt_crossley", "wheels.0.normal_damping": -1.0}))
toml_case("compliant-damping-text", "normal_damping", _bump(**{"wheels.0.normal_damping": "soft"}))
toml_case("compliant-law-unknown", "contact_law", _bump(**{"wheels.0.contact_law": "hertz"}))
toml_case("compliant-exponent-below-one", "contact_exponent",
          _bump(**{"wheels.0.contact_law": "hunt_crossley", "wheels.0.contact_exponent": 0.5}))
toml_case("compliant-key-misspelt", "normal_stiffnes", _bump(**{"wheels.0.normal_stiffnes": 1e5}))
toml_case("compliant-wheel-missing-joint", "nosuch_spin",
          {**_bump(), "wheels": [*_bump()["wheels"], {"name": "ghost", "joint": "nosuch_spin", "radius": 0.1,
                                                      "contact": "compliant"}]})
_SPRING = {"joint": "axle_roll", "stiffness": 100.0, "damping": 1.0}
toml_case("spring-neither-stiffness-nor-damping", "stiffness",
          {**_skid(), "springs": [{"joint": "axle_roll"}]})  # was accepted: a spring that does nothing
toml_case("spring-stiffness-negative", "stiffness", {**_skid(), "springs": [{**_SPRING, "stiffness": -1.0}]})
toml_case("spring-damping-nan", "damping", {**_skid(), "springs": [{**_SPRING, "damping": float("nan")}]})
toml_case("spring-unknown-joint", "nosuchjoint", {**_skid(), "springs": [{**_SPRING, "joint": "nosuchjoint"}]})
toml_case("spring-twice-on-a-joint", "axle_roll", {**_skid(), "springs": [_SPRING, _SPRING]})
toml_case("spring-unknown-key", "preload", {**_skid(), "springs": [{**_SPRING, "preload": 3.0}]})

# --------------------------------------------------------------------------------------------- descriptions
dd_case("valid-control", "", urdf_text())  # (replaced below: the control must pass; see test_control_is_valid)
CASES.pop()
dd_case("binary", "robot.urdf", b"\xff\xfe\x00\x81\x90 garbage")
dd_case("not-xml", "robot.urdf", "<robot name='x'><link name='a'>")
dd_case("empty", "robot.urdf", "")
dd_case("not-robot", "robot.urdf", "<?xml version='1.0'?><html/>")
dd_case("joint-missing-parent", "robot.urdf", urdf_text(extra='<joint name="j" type="fixed"><child link="arm"/>'
                                                               '</joint>'))
dd_case("joint-unknown-link", "nolink", urdf_text(extra='<joint name="j" type="fixed"><parent link="nolink"/>'
                                                        '<child link="arm"/></joint>'))
dd_case("mass-negative", "mass", urdf_text(mass="-5"))
dd_case("mass-nan", "mass", urdf_text(mass="nan"))
dd_case("mass-text", "mass", urdf_text(mass="heavy"))
dd_case("mass-inf", "mass", urdf_text(mass="inf"))
dd_case("inertia-negative", "inertia", urdf_text(ixx="-0.1"))
dd_case("inertia-nan", "inertia", urdf_text(ixx="nan"))
dd_case("limits-inverted", "shoulder", urdf_text(lower="1", upper="-1"))
dd_case("limits-nan", "shoulder", urdf_text(lower="nan"))
dd_case("origin-nan", "origin", urdf_text(origin="0 nan 0"))
dd_case("origin-short", "origin", urdf_text(origin="0 0.2"))
dd_case("origin-huge", "origin", urdf_text(origin="0 1e300 0"))
dd_case("all-masses-zero", "mass", urdf_text(mass="0", wheel_mass="0").replace('<mass value="1"/>',
                                                                              '<mass value="0"/>'),
        ("dump", "--v", "0", "0", "0", "--tau", "1", "1", "0"))
dd_case("all-masses-zero-simulate", "mass", urdf_text(mass="0", wheel_mass="0").replace('<mass value="1"/>',
                                                                                       '<mass value="0"/>'),
        ("simulate", "--scenario", "go", "--quiet"))
dd_case("wheel-radius-huge", "radius", urdf_text(), toml=DD_TOML.replace("radius = 0.1", "radius = 1e300", 1))
dd_case("dump-v-1e200", "v", urdf_text(), ("dump", "--v", "1e200", "1e200", "1e200"))
dd_case("dump-tau-1e300", "tau", urdf_text(), ("dump", "--v", "0", "0", "0", "--tau", "1e300", "1e300", "1e300"))
dd_case("simulate-t-end-1e300", "--t-end", urdf_text(), ("simulate", "--scenario", "go", "--quiet", "--t-end",
                                                         "1e300"))
dd_case("damping-twice", "urdf_damping = false",  # the URDF's <dynamics damping> and a [[springs]] damping on one joint
        urdf_text().replace('<axis xyz="0 1 0"/><limit', '<axis xyz="0 1 0"/><dynamics damping="0.5"/><limit'),
        toml=DD_TOML + '[[springs]]\njoint = "shoulder"\ndamping = 0.5\n')
dd_case("damping-negative", "shoulder",  # was refused as a "spring" the user never declared
        urdf_text().replace('<axis xyz="0 1 0"/><limit', '<axis xyz="0 1 0"/><dynamics damping="-0.5"/><limit'))
dd_case("damping-1e300", "shoulder",  # was accepted: accelerations of 1e301
        urdf_text().replace('<axis xyz="0 1 0"/><limit', '<axis xyz="0 1 0"/><dynamics damping="1e300"/><limit'),
        ("dump", "--v", "0", "0", "0", "--tau", "0", "0", "0"))


# -------------------------------------------------------------------------------- issue 24: cases named there
SKID_ARGS = ["--constraints", str(SKID)]
case("i24-dump-forces-full", ["dump", "quasimoro", "--full", "--v", *["0"] * 6, "--tau", *["0"] * 6, "--forces"],
     "--forces")
case("i24-dump-a-tau-set", ["dump", "quasimoro", "--v", "0", "0", "0", "--a", "0", "0", "0", "--tau-set", "m1=1"],
     "--tau-set")
case("i24-linkage-posture-v-words", ["linkage-posture", "--v", "a", "b"], "--v")
case("i24-impulse-speed-1e308", ["impulse", "omni_caster", "--q", *["0"] * 9, "--direction", "1", "0", "0",
                                 "--speed", "1e308"], "--speed")
case("i24-impulse-speed-and-v", ["impulse", "omni_caster", "--q", *["0"] * 9, "--direction", "1", "0", "0",
                                 "--speed", "2", "--v", "1", "0", "0"], "--speed")
case("i24-ik-mission-and-commands", ["ik", "adaptable_wheel", "--mission", "mission1", "--commands", *["0"] * 6],
     "--commands")
case("i24-ik-angle-one-turn", ["ik", "adaptable_wheel", "--commands", "0", "0", "0.3", "0", "0", "100"], "q_zd")
for robot in ("adaptable_wheel", "mmr12_eod"):  # the robots with a friction parameter mu
    case(f"i24-{robot}-mu-negative", ["info", robot, "--param", "mu=-1"], "mu")
    case(f"i24-{robot}-mu-1e300", ["info", robot, "--param", "mu=1e300"], "mu")
case("i24-sweep-mu-negative", ["sweep", "adaptable_wheel", "--vary", "mu=-1,-0.5", "--workers", "0", "--out",
                               "{d}/s"], "mu")
case("i24-linkage-rocker-1e6", ["info", "linkage_suspension", "--param", "theta0=1e6"], "theta0")
case("i24-sweep-angle-1e300", ["sweep", "linkage_suspension", "--vary", "theta0=1e300 rad", "--workers", "0",
                               "--out", "{d}/s"], "theta0")
for word in ("1-1", "r+r", "pi", "math.pi", "e", "1e5j"):  # values xacro would evaluate inside ${...}
    case(f"i24-xacro-arg-word-{word}", ["info", *SKID_ARGS, "--xacro-arg", f"m_body={word}"], "m_body")
toml_case("i24-xacro-args-word-pi", "m_body", _skid(xacro_args={"m_body": "pi"}))
toml_case("i24-root-height-floating", "root_height", _skid(root_height=0.1))
toml_case("i24-roller-angle-1e300-rad", "roller_angle", _skid(**{"wheels.0.kind": "omni", "wheels.0.roller_angle":
                                                                 "1e300 rad", "wheels.0.friction": None,
                                                                 "wheels.0.stiffness": None, "wheels.0.mu": None}))
case("i24-sweep-scheduler-ucx", ["sweep", "quasimoro", "--workers", "0", "--out", "{d}/s", "--scheduler",
                                 "ucx://127.0.0.1:9"], "ucx://127.0.0.1:9")
case("i24-sweep-scheduler-tls", ["sweep", "quasimoro", "--workers", "0", "--out", "{d}/s", "--scheduler",
                                 "tls://127.0.0.1:9"], "tls://127.0.0.1:9")
case("i24-sweep-spec-fifo", ["sweep", "--spec", "{d}/fifo.toml", "--workers", "0", "--out", "{d}/s"], "fifo.toml",
     {"fifo.toml": FIFO})
case("i24-sweep-spec-dev-zero", ["sweep", "--spec", "/dev/zero", "--workers", "0", "--out", "{d}/s"], "/dev/zero")
case("i24-sweep-spec-height-nan", ["sweep", "--spec", "{d}/nan.toml", "--workers", "0", "--out", "{d}/s"], "height",
     {"nan.toml": 'robot = "quasimoro"\nterrains = [{kind = "flat", height = nan}]\n[parameters]\nM = [4.0, 5.0]\n'})
case("i24-constraints-package-loop", ["info", *SKID_ARGS, "--package", "{d}/loop"], "loop", {"loop": LOOP})
case("i24-constraints-fifo", ["info", "--constraints", "{d}/fifo.toml"], "fifo.toml", {"fifo.toml": FIFO})
case("i24-constraints-loop", ["info", "--constraints", "{d}/loop"], "loop", {"loop": LOOP})
case("i24-package-dirs-loop", ["info", "--constraints", "{d}/robot.toml"], "loop", {
    "loop": LOOP, "robot.toml": SKID.read_text().replace('urdf = "skid_steer.urdf.xacro"',
                                                        f'urdf = "{SKID_XACRO}"\npackage_dirs = ["loop"]')})
case("i24-sweep-constraints-loop", ["sweep", "--constraints", "{d}/loop", "--workers", "0", "--out", "{d}/s"], "loop",
     {"loop": LOOP})
case("i24-sweep-spec-constraints-loop", ["sweep", "--spec", "{d}/spec.toml", "--workers", "0", "--out", "{d}/s"],
     "loop", {"loop": LOOP, "spec.toml": 'constraints = "loop"\n'})
dd_case("i24-wheel-mass-1e-300", "mass", urdf_text(wheel_mass="1e-300"))
dd_case("i24-wheel-zero-mass-with-inertia", "left", urdf_text(wheel_mass="0"))
dd_case("i24-links-3000", "links", urdf_text(extra="".join(
    f'<link name="x{i}"/><joint name="xj{i}" type="fixed"><parent link="arm"/><child link="x{i}"/></joint>'
    for i in range(3000))))


# ----------------------------------------------------------- generated: every flag of every subcommand (item 7)
GENERATED_ROBOT = {"impulse": "omni_caster", "ik": "adaptable_wheel", "list": None, "linkage-posture": None,
                   "climbing-posture": "mmr12_eod"}
"""The robot each command's generated cases use (default quasimoro; None: the command takes none)."""
GENERATED_BASE = {**REQUIRED, "ik": [], "sweep": ["--out", "{d}/s", "--workers", "0", "--quiet", "--no-plot"],
                  "optimise": ["--t-end", "3", "--nodes", "5", "--end", "x=0.1"], "climbing-posture": ["--slope", "20"]}
"""What each command needs besides the flag under test (so that a case fails for that flag only)."""
FLAG_CASES: dict = {
    # flag: (the bad arguments, texts the one line may name: any one of them), for every command taking the flag
    "ROBOT": (["nosuchrobot"], ("nosuchrobot",)),
    "--urdf": (["--urdf", "{d}/nosuch.urdf"], ("--urdf",)),
    "--xacro-arg": (["--xacro-arg", "r"], ("--xacro-arg", "xacro argument")),
    "--constraints": (["--constraints", "{d}/nosuch.toml"], ("nosuch.toml", "--constraints")),
    "--param": (["--param", "nosuch=1"], ("nosuch",)),
    "--package": (["--package", "{d}/nosuchdir"], ("--package", "nosuchdir")),
    "--twist": (["--twist", "nosuchframe"], ("nosuchframe", "--twist")),
    "--q": (["--q", "abc"], ("q",)),
    "--set": (["--set", "nosuchcoord=1"], ("nosuchcoord",)),
    "--v": (["--v", "abc"], ("v",)),
    "--a": (["--a", "abc"], ("a",)),
    "--tau": (["--tau", "abc"], ("tau",)),
    "--tau-set": (["--tau-set", "nosuchmotor=1"], ("nosuchmotor",)),
    "--scenario": (["--scenario", "nosuchscenario"], ("nosuchscenario",)),
    "--t-end": (["--t-end", "abc"], ("--t-end",)),
    "--csv": (["--csv", "{d}/no/dir/x.csv"], ("x.csv", "--csv")),
    "--plot": (["--plot", "{d}/p.xyz"], ("p.xyz",)),
    "--traction-plot": (["--traction-plot", "{d}/p.xyz"], ("p.xyz",)),
    "--stabilisation": (["--stabilisation", "-1"], ("--stabilisation",)),
    "--method": (["--method", "nosuchmethod"], ("nosuchmethod",)),
    "--mu": (["--mu", "-1"], ("--mu",)),
    "--html": (["--html", "{d}/no/dir/v.html"], ("v.html",)),
    "--spec": (["--spec", "{d}/nosuch.toml"], ("nosuch.toml",)),
    "--vary": (["--vary", "M"], ("--vary",)),
    "--terrain": (["--terrain", "lunar"], ("lunar",)),
    "--sample": (["--sample", "sobol"], ("--sample",)),
    "--n": (["--n", "many"], ("--n",)),
    "--seed": (["--seed", "-1"], ("seed",)),
    "--n-out": (["--n-out", "0"], ("--n-out",)),
    "--rtol": (["--rtol", "-1"], ("rtol",)),
    "--atol": (["--atol", "nan"], ("atol",)),
    "--column": (["--column", "nosuchcolumn"], ("nosuchcolumn",)),
    "--plot-column": (["--plot-column", "nosuchcolumn"], ("nosuchcolumn",)),
    "--out": (["--out", "{d}/file.txt"], ("file.txt",)),
    "--workers": (["--workers", "-3"], ("--workers",)),
    "--scheduler": (["--scheduler", "http://127.0.0.1:9"], ("http://127.0.0.1:9",)),
    "--chunk-size": (["--chunk-size", "0"], ("--chunk-size",)),
    "--time-limit": (["--time-limit", "-1"], ("time_limit",)),
    "--batch": (["--batch", "sometimes"], ("--batch",)),
    "--commands": (["--commands", "a"], ("commands",)),
    "--mission": (["--mission", "nosuchmission"], ("--mission",)),
    "--x": (["--x", "far"], ("--x",)),
    "--y": (["--y", "far"], ("--y",)),
    "--yaw": (["--yaw", "far"], ("--yaw",)),
    "--frame": (["--frame", "nosuchframe"], ("nosuchframe",)),
    "--base": (["--base", "nosuchframe"], ("nosuchframe",)),
    "--direction": (["--direction", "abc"], ("direction",)),
    "--e": (["--e", "-0.5"], ("--e",)),
    "--speed": (["--speed", "-1"], ("--speed",)),
    "--states": (["--states", "nosuchstate"], ("nosuchstate",)),
    "--lqr-q": (["--lqr-q", "abc"], ("lqr",)),
    "--lqr-r": (["--lqr-r", "abc"], ("lqr",)),
    "--nodes": (["--nodes", "1"], ("nodes",)),
    "--q0": (["--q0", "abc"], ("--q0",)),
    "--end": (["--end", "nosuch=1"], ("nosuch",)),
    "--bound": (["--bound", "theta3=1:0"], ("--bound",)),
    "--tau-max": (["--tau-max", "-1"], ("--tau-max",)),
    "--derivatives": (["--derivatives", "bogus"], ("--derivatives",)),
    "--min-load": (["--min-load", "-1"], ("--min-load",)),
    "--mu-max": (["--mu-max", "nan"], ("--mu-max",)),
    "--cost": (["--cost", "bogus"], ("--cost",)),
    "--slope": (["--slope", "90"], ("--slope",)),
    "--min-tip-load": (["--min-tip-load", "-5"], ("--min-tip-load",)),
}
FLAG_CASE_OVERRIDES: dict = {  # (command, flag): a different bad use where the generic one does not fit
    ("sweep", "--t-end"): (["--t-end", "nan"], ("t_end",)),
    ("sweep", "--scenario"): (["--scenario", "nosuchscenario", "--vary", "M=4,5"], ("nosuchscenario",)),
    ("linkage-posture", "--v"): (["--v", "a", "b"], ("--v",)),
    ("linkage-posture", "--terrain"): (["--terrain", "lunar"], ("lunar",)),
}
SWITCHES = ("--json", "--full", "--forces", "--quiet", "--frames", "--open", "--trajectories", "--no-plot",
            "--retry-errors", "--replace")
"""Flags without a value: their bad use is a value (``--json=1``, refused by argparse)."""


def _parser_flags() -> dict[str, list[str]]:
    """Every command's flags (and ``ROBOT`` for its robot argument), from the CLI's own parser with the robot
    modules' commands: a flag added to any parser appears here."""
    import argparse

    from robotdyn.cli.commands import build_parser

    parser = build_parser()
    parser.robot_commands()
    out = {}
    for name, sub in parser.commands.items():
        flags = []
        for action in sub._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            flags.append(max(action.option_strings, key=len) if action.option_strings else action.metavar or
                         action.dest.upper())
        out[name] = flags
    return out


def _flag_case(command: str, flag: str) -> tuple[list[str], tuple[str, ...]]:
    if flag in SWITCHES:
        return [f"{flag}=1"], (flag,)
    return FLAG_CASE_OVERRIDES.get((command, flag)) or FLAG_CASES[flag]


GENERATED_FLAGS: list[tuple[str, str]] = []
for _command, _flags in _parser_flags().items():
    for _flag in _flags:
        if (_command, _flag) in GENERATED_FLAGS:
            continue
        GENERATED_FLAGS.append((_command, _flag))
        if _flag not in SWITCHES and (_command, _flag) not in FLAG_CASE_OVERRIDES and _flag not in FLAG_CASES:
            continue  # (reported by test_every_flag_has_a_bad_input_case)
        _bad, _needles = _flag_case(_command, _flag)
        _robot = GENERATED_ROBOT.get(_command, "quasimoro")
        _base = list(GENERATED_BASE.get(_command, []))
        _flag_names = {a for a in _bad if a.startswith("--")} | {_flag}
        for _given in _flag_names:  # the base's own use of the flag under test is dropped
            if _given in _base:
                i = _base.index(_given)
                j = i + 1
                while j < len(_base) and not _base[j].startswith("--"):
                    j += 1
                del _base[i:j]
        if _flag == "ROBOT":
            _argv = [_command, *_bad, *_base]
        elif _flag in ("--constraints", "--urdf") or _robot is None:
            _argv = [_command, *_base, *_bad]
        else:
            _argv = [_command, _robot, *_base, *_bad]
        case(f"gen-{_command}-{_flag.lstrip('-').lower()}", _argv, "|".join(_needles), {"file.txt": "x"})


# ------------------------------------------------- generated: every key of the constraint file's schema (item 7)
def _schema_keys(schema: dict, path: tuple = ()):
    """(path, schema) of every key of the constraint-file schema, tables and arrays of tables descended."""
    for key, sub in schema.get("properties", {}).items():
        yield path + (key,), sub
        if sub.get("type") == "object" and "properties" in sub:
            yield from _schema_keys(sub, path + (key,))
        if sub.get("type") == "array" and "properties" in sub.get("items", {}):
            yield from _schema_keys(sub["items"], path + (key, 0))


def _bad_value(sub: dict):
    """A value the schema entry ``sub`` refuses: an unknown choice, a non-finite number, a wrong type."""
    if "enum" in sub:
        return "nosuch_value"
    kind = sub.get("type")
    if kind == "number":
        return float("nan")
    if kind == "string":
        return 3
    if kind == "boolean":
        return "yes"
    if kind in ("array", "object"):
        return "x" if kind == "array" and sub.get("items", {}).get("type") != "string" else 3
    if "anyOf" in sub:
        return [[1]]  # (no alternative of this schema is a list of lists)
    raise KeyError(f"no bad value for the schema entry {sub!r}")


_SCHEMA_BASES = {  # a valid table to corrupt, for the tables that the skid-steer example does not have
    "closures": {"frame1": "front_axle", "frame2": "chassis"},
    "terrain": {"kind": "ramp"},
    "twist": {"frame": "chassis"},
    "springs": {"joint": "front_left_spin", "stiffness": 1.0},
}


def _schema_case(path: tuple, sub: dict) -> None:
    data = _skid()
    bad = _bad_value(sub)
    node = data
    for i, key in enumerate(path[:-1]):
        if isinstance(key, int):
            continue
        if key not in node or (isinstance(path[i + 1], int) and not node[key]):
            node[key] = [dict(_SCHEMA_BASES[key])] if isinstance(path[i + 1], int) else dict(_SCHEMA_BASES[key])
        node = node[key][0] if isinstance(path[i + 1], int) else node[key]
    node[path[-1]] = bad
    toml_case("gen-" + ".".join(str(k) for k in path), str(path[-1]), data)


from robotdyn.interfaces.constraint_schema import SCHEMA  # noqa: E402

SCHEMA_KEYS = [path for path, _ in _schema_keys(SCHEMA)]
SCHEMA_KEYS_WITHOUT_CASE = []
for _path, _sub in _schema_keys(SCHEMA):
    try:
        _schema_case(_path, _sub)
    except KeyError:  # a kind of entry the generator cannot corrupt yet (test_every_schema_key_has_a_case)
        SCHEMA_KEYS_WITHOUT_CASE.append(_path)

# --------------------------------------------------------- generated: every key of the sweep file (item 7)
SPEC_BASE = 'robot = "quasimoro"\nt_end = 0.2\n'
SPEC_CASES = {  # key: (TOML lines replacing or adding that key, the text the one line names)
    "robot": ("robot = 3", "robot"),
    "constraints": ('constraints = "nosuch.toml"', "constraint"),
    "urdf": ("urdf = 3", "urdf"),
    "xacro_args": ("xacro_args = [1]", "xacro_args"),
    "fixed": ("fixed = [1]", "fixed"),
    "parameters": ("parameters = [1, 2]", "parameters"),
    "scenarios": ("scenarios = 3", "scenarios"),
    "terrains": ("terrains = 3", "terrains"),
    "sample": ('sample = "sobol"', "sample"),
    "n": ('n = "many"', "n ="),
    "seed": ("seed = -1\nsample = \"random\"\nn = 2\nparameters = {d = {min = 0.1, max = 0.3}}", "seed"),
    "t_end": ('t_end = "long"', "t_end"),
    "n_out": ("n_out = 0", "n_out"),
    "rtol": ("rtol = -1.0", "rtol"),
    "atol": ("atol = nan", "atol"),
    "method": ('method = "cvod"', "cvod"),
    "columns": ("columns = 3", "columns"),
    "trajectories": ('trajectories = "yes"', "trajectories"),
    "plot_column": ("plot_column = 3", "plot_column"),
    "time_limit": ("time_limit = -1.0", "time_limit"),
    "parameters.min": ('parameters = {M = {min = "abc", max = 6.0, n = 3}}', "M"),
    "parameters.max": ("parameters = {M = {min = 4.0, max = nan, n = 3}}", "M"),
    "parameters.n": ("parameters = {M = {min = 4.0, max = 6.0, n = 0}}", "n ="),
    "parameters.scale": ('parameters = {M = {min = 4.0, max = 6.0, n = 3, scale = "cubic"}}', "scale"),
}
for _key, (_lines, _needle) in SPEC_CASES.items():
    _text = SPEC_BASE
    for _line in _lines.splitlines():
        _name = _line.split("=")[0].strip()
        _text = "\n".join(x for x in _text.splitlines() if x.split("=")[0].strip() != _name) + "\n" + _line + "\n"
    if _key == "constraints":
        _text = _text.replace('robot = "quasimoro"\n', "")
    case(f"gen-spec-{_key}", ["sweep", "--spec", "{d}/spec.toml", "--workers", "0", "--quiet", "--no-plot",
                              "--out", "{d}/s"], _needle, {"spec.toml": _text})


def _materialise(c: Case, tmp_path: Path) -> list[str]:
    for name, content in c.files.items():
        p = tmp_path / name
        if content is DIR:
            p.mkdir()
        elif content is FIFO:
            os.mkfifo(p)
        elif content is LOOP:  # a symbolic link to itself
            p.symlink_to(name)
        elif isinstance(content, bytes):
            p.write_bytes(content)
        else:
            p.write_text(content)
    return [a.replace("{d}", str(tmp_path)) for a in c.argv]


class _Hang(BaseException):
    pass


def _alarm(signum, frame):
    raise _Hang


def test_corpus_size():
    """At least 300 cases, on every subcommand."""
    assert len(CASES) >= 300
    assert len({c.id for c in CASES}) == len(CASES)
    commands = {c.argv[0] for c in CASES if c.argv}
    assert commands >= {"info", "dump", "simulate", "compare", "view", "sweep", "list", "ik", "linkage-posture",
                        "fk", "impulse"}


def test_every_flag_has_a_bad_input_case():
    """Every flag of every subcommand (read from the CLI's parsers, the robot modules' commands included) has a
    generated bad-input case: a flag added without one fails here."""
    missing = [f"{command} {flag}" for command, flag in GENERATED_FLAGS
               if flag not in SWITCHES and flag not in FLAG_CASES and (command, flag) not in FLAG_CASE_OVERRIDES]
    assert not missing, f"flags without a bad-input case (add them to FLAG_CASES or SWITCHES): {missing}"
    ids = {c.id for c in CASES}
    assert all(f"gen-{command}-{flag.lstrip('-').lower()}" in ids for command, flag in GENERATED_FLAGS)
    assert len(GENERATED_FLAGS) >= 100


def test_every_schema_key_has_a_case():
    """Every key of the constraint file (read from its schema, tables and arrays of tables descended) has a
    generated case: a key added to the schema without a way to corrupt it fails here."""
    assert not SCHEMA_KEYS_WITHOUT_CASE, SCHEMA_KEYS_WITHOUT_CASE
    ids = {c.id for c in CASES}
    assert all("toml-gen-" + ".".join(map(str, path)) in ids for path in SCHEMA_KEYS)
    assert {p[-1] for p in SCHEMA_KEYS} >= {"radius", "mu", "t_end", "frame1", "kind", "slope", "components"}


def test_every_sweep_file_key_has_a_case():
    """Every key of the sweep file (robotdyn.sweep.spec.TOP_KEYS, and the keys of a range) has a case."""
    from robotdyn.sweep.spec import RANGE_KEYS, TOP_KEYS

    assert set(TOP_KEYS) <= set(SPEC_CASES), set(TOP_KEYS) - set(SPEC_CASES)
    assert {f"parameters.{k}" for k in RANGE_KEYS} <= set(SPEC_CASES)


def test_control_is_valid(tmp_path, capsys):
    """The uncorrupted description and constraint file the description cases start from are accepted (so that the
    cases fail for their corruption, not for the base)."""
    (tmp_path / "robot.toml").write_text(DD_TOML)
    (tmp_path / "robot.urdf").write_text(urdf_text())
    assert main(["dump", "--constraints", str(tmp_path / "robot.toml"), "--v", "0.1", "0", "0.2", "--tau", "0.1",
                 "0", "0"]) == 0, capsys.readouterr().err
    data = _skid()
    (tmp_path / "skid.toml").write_text(tomli_w.dumps(data))
    assert main(["info", "--constraints", str(tmp_path / "skid.toml")]) == 0, capsys.readouterr().err


@pytest.mark.parametrize("c", CASES, ids=[c.id for c in CASES])
def test_bad_input_is_refused_in_one_line(c: Case, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv = _materialise(c, tmp_path)
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(CASE_SECONDS)
    try:
        rc = main(argv)
    except _Hang:
        pytest.fail(f"{c.id}: still running after {CASE_SECONDS} s")
    except SystemExit as exc:  # argparse's own exit (e.g. --help) would land here
        pytest.fail(f"{c.id}: SystemExit({exc.code}) escaped main")
    except BaseException as exc:  # noqa: BLE001 - any exception escaping main is a traceback for the user
        pytest.fail(f"{c.id}: {type(exc).__name__} escaped main: {exc}")
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    out, err = capsys.readouterr()
    lines = [line for line in err.splitlines() if not line.startswith("robotdyn: warning: ")]
    assert rc == 2, f"{c.id}: exit status {rc}; stderr {err!r}; stdout {out[:300]!r}"
    assert len(lines) == 1 and lines[0].startswith("robotdyn: error: "), f"{c.id}: stderr {err!r}"
    assert "Traceback" not in err
    assert any(_names(n.replace("{d}", str(tmp_path)), lines[0]) for n in c.needle.split("|")), \
        f"{c.id}: {c.needle!r} not in {lines[0]!r}"


def _names(needle: str, message: str) -> bool:
    """Whether the message names the needle (an option --t-end is named as --t-end or as its value t_end)."""
    def norm(text: str) -> str:
        return text.lower().replace("-", "_")

    return norm(needle) in norm(message) or norm(needle.lstrip("-")) in norm(message)


SUBPROCESS_CASES = ["argv-empty", "argv-simulate-t-end-word", "toml-binary", "simulate-quasimoro-t-end-1e300",
                    "dump-quasimoro-v-1e200", "toml-wheel-kind-table", "urdf-all-masses-zero"]


@pytest.mark.parametrize("id", SUBPROCESS_CASES)
def test_real_entry_point_agrees(id, tmp_path):
    """``python -m robotdyn`` gives the same exit status and the same one line as the in-process call."""
    c = next(c for c in CASES if c.id == id)
    argv = _materialise(c, tmp_path)
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    p = subprocess.run([sys.executable, "-m", "robotdyn", *argv], capture_output=True, text=True, timeout=120,
                       cwd=tmp_path, env=env)
    lines = [line for line in p.stderr.splitlines() if not line.startswith("robotdyn: warning: ")]
    assert p.returncode == 2, p.stderr
    assert len(lines) == 1 and lines[0].startswith("robotdyn: error: "), p.stderr
    assert _names(c.needle, lines[0])
