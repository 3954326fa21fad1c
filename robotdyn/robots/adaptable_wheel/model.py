"""Three-wheeled robot with adaptable-radius wheels on rough terrain (Mardani & Ebrahimi 2016): the model side.

Description: ``urdf/adaptable_wheel.urdf.xacro``. Paper the parameters come from: A. Mardani, S. Ebrahimi, "A Novel
Multimode Mobile Robot with Adaptable Wheel Geometry for Maneuverability Improvement"
(Mardani & Ebrahimi 2016, ``docs/bibliography.md``), Table 1.

Model (derived by Pinocchio from the description): floating body (x, y, z, yaw, pitch, roll; Z-Y-X Euler) with
three wheels fr, fl, r at the eq-8 positions, each with a spin joint ``theta_<i>`` (wheel motor), an adjustment
angle ``q_<i>`` (adjustment motor, 0-180 deg) and a prismatic radius ``Rch_<i>`` (the close-loop pattern radius).
The wheel radius is :math:`R_T = R_{ru} + R_{ch}` and the mechanism law of eq 1,
:math:`R_{ch} = w\\cos(q/2)\\cos(\\pi/6)`, is a holonomic :class:`~robotdyn.constraints.joint_coupling.JointCoupling` (its own
:class:`~robotdyn.constraints.joint_coupling.CosineLaw`, compared with the paper's :func:`robotdyn.robots.adaptable_wheel.paper.radius_law` in the tests), so
the radius follows the configuration through the constraint layer. Each wheel rolls on the terrain
(:class:`~robotdyn.constraints.rolling_contact.RollingWheel` with ``radius_joint``); ``lateral=slip`` drops the lateral
no-slip row (the paper's kinematic missions turn the robot about a vertical axis away from its wheel axles,
which rolling without lateral slip forbids: see ``docs/errata/adaptable_wheel.md``).

This module holds ``SPEC``, the terrains of Table 1 and mission 2 and ``SCENARIOS``. The paper's transcription
(eqs 1, 3-24, 25-35, Table 2) is in :mod:`robotdyn.robots.adaptable_wheel.paper`, the section-7 missions in :mod:`robotdyn.robots.adaptable_wheel.missions`, the model driven
along them (beyond the paper) in :mod:`robotdyn.robots.adaptable_wheel.dynamics`, the comparison and the ``ik`` CLI in :mod:`robotdyn.robots.adaptable_wheel.comparison`.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

import numpy as np

from ...contact.friction import LinearTyre, RegularisedCoulomb
from ...constraints.joint_coupling import CosineLaw, JointCoupling
from ...inputs import MAX_FRICTION
from ...robot import MotorSpec, Parameter, Robot, RobotSpec
from ...constraints.rolling_contact import OmniWheel, RollingWheel
from ...simulation.scenario import Scenario
from ...contact.sliding import SlippingWheel
from ...constraints.terrain import FlatTerrain, RampTerrain, SineTerrain, Terrain
from ...simulation.torque_profile import Constant

WHEELS = ("fr", "fl", "r")
"""Wheel tags: front right, front left, rear (eq 8)."""
COS30 = float(np.cos(np.pi / 6))
LATERAL_SLIP_VELOCITY = 1e-3
"""Slip-velocity scale [m/s] of the regularised Coulomb law of ``lateral=coulomb`` (mission 1 slides at ~0.6 m/s, so
the law is Coulomb's to a relative 1e-6 there)."""
LATERAL_STIFFNESS = 10.0
"""Slip stiffness [s/m] of the brush law of ``lateral=linear`` (saturated at mu; not in the paper)."""


def _pattern_radius(q: float, w: float) -> float:
    """The mechanism's pattern radius [m] at adjustment angle q [rad] (the neutral configuration's radii)."""
    return w * np.cos(0.5 * q) * COS30


def _terrain(p: dict) -> Terrain:
    if p["terrain"] == "rough":
        return SineTerrain(1.0 / 15.0, 0.5, 0.5)  # Table 1: Z = sin(0.5(x + y))/15
    if p["terrain"] == "ramp":
        return RampTerrain(p["ramp_slope"], p["ramp_heading"])
    return FlatTerrain()


def _wheel_factory(tag: str) -> Callable[[Robot], RollingWheel]:
    def make(robot: Robot) -> RollingWheel:
        lateral = robot.params["lateral"]
        kind = {"rolling": RollingWheel, "slip": partial(OmniWheel, roller_angle=0.0)}.get(lateral)
        if kind is None:  # rolling along t1, sliding sideways under a friction law of coefficient mu
            law = RegularisedCoulomb(robot.params["mu"], LATERAL_SLIP_VELOCITY) if lateral == "coulomb" else \
                LinearTyre(LATERAL_STIFFNESS, robot.params["mu"])
            kind = partial(SlippingWheel, law=law, slip="lateral")
        return kind(robot.description, f"wheel_{tag}", robot.params["R_ru"], axis=(0.0, 1.0, 0.0),
                    terrain=robot.terrain, radius_joint=f"radius_{tag}_joint", name=tag)

    return make


def _coupling_factory(tag: str) -> Callable[[Robot], JointCoupling]:
    def make(robot: Robot) -> JointCoupling:
        w = robot.params["w"]
        # eq 1 as data (radius_law with its derivatives eq 33), so that the compiled path can evaluate it
        return JointCoupling(robot.description, f"radius_{tag}_joint", f"adjust_{tag}_joint",
                             CosineLaw(w * COS30, 0.5), name=f"eq1_{tag}")

    return make


_Q0 = 2 * np.pi / 3
_NEUTRAL_Q = {"fr": 1.9, "fl": 2.3, "r": _Q0}
"""Adjustment angles of the neutral configuration. The front radii differ on purpose: with equal front radii the
lateral rows of the two front wheels coincide on flat ground (a kinematic singularity, see the errata), and the
automatic choice of independent velocities is made at the neutral configuration."""
SPEC = RobotSpec(
    name="adaptable_wheel",
    title="Tricycle with adaptable-radius wheels on rough terrain (Mardani & Ebrahimi 2016)",
    xacro="adaptable_wheel.urdf.xacro",
    root="floating",
    paper=("Mardani & Ebrahimi 2016, "
           "A novel multimode mobile robot with adaptable wheel geometry for maneuverability improvement"),
    parameters=[
        Parameter("m", 10.0, "kg", "total mass (Table 1)", positive=True),
        Parameter("m_wheel", 0.0, "kg", "mass of each wheel hub (paper: all mass lumped in the body)"),
        Parameter("I_adjust", 0.0, "kg m^2", "rotor inertia of each adjustment motor (not in the paper)"),
        Parameter("w", 0.3, "m", "cross-linkage leg length (Table 1, eq 1)", positive=True),
        Parameter("Lx", 0.6, "m", "Table 1 L_x (see L_reading)", positive=True),
        Parameter("Ly", 0.6, "m", "Table 1 L_y (see L_reading)", positive=True),
        Parameter("L_reading", "half", "", "half: Lx, Ly are the eq-8 offsets (body 2Lx x 2Ly); full: body Lx x Ly",
                  choices=("half", "full")),
        Parameter("R_ru", 0.02, "m", "rubber height, added to the pattern radius (Table 1)", minimum=0.0),
        Parameter("body_height", 0.05, "m", "body plate thickness (inertia only; not in the paper)", positive=True),
        Parameter("mu", 1.0, "-", "static friction coefficient (Table 1)", xacro=False, minimum=0.0,
                  maximum=MAX_FRICTION),
        Parameter("g", 9.81, "m/s^2", "gravitational acceleration (not printed in the paper)", xacro=False),
        Parameter("terrain", "rough", "", "rough: Z = sin(0.5(x+y))/15 (Table 1); ramp; flat",
                  choices=("rough", "ramp", "flat"), xacro=False),
        Parameter("ramp_slope", 0.2, "-", "slope of the ramp terrain (mission 2)", xacro=False, minimum=-10.0,
                  maximum=10.0),
        Parameter("ramp_heading", -np.pi / 2, "rad", "direction in which the ramp rises (mission 2)", xacro=False),
        Parameter("lateral", "rolling", "", "rolling: wheels roll without slipping; slip: lateral row dropped "
                  "(frictionless); coulomb, linear: sideways sliding under that friction law with mu",
                  choices=("rolling", "slip", "coulomb", "linear"), xacro=False),
    ],
    constraints=[_wheel_factory(t) for t in WHEELS] + [_coupling_factory(t) for t in WHEELS],
    motors=[MotorSpec(f"spin_{t}", f"wheel_{t}_joint") for t in WHEELS]
    + [MotorSpec(f"adjust_{t}", f"adjust_{t}_joint") for t in WHEELS],
    labels={
        **{f"wheel_{t}_joint": f"theta_{t}" for t in WHEELS},
        **{f"adjust_{t}_joint": f"q_{t}" for t in WHEELS},
        **{f"radius_{t}_joint": f"Rch_{t}" for t in WHEELS},
    },
    terrain=_terrain,
    neutral={
        "z": 0.02 + _pattern_radius(_Q0, 0.3),
        **{f"q_{t}": _NEUTRAL_Q[t] for t in WHEELS},
        **{f"Rch_{t}": _pattern_radius(_NEUTRAL_Q[t], 0.3) for t in WHEELS},
    },
)


# ------------------------------------------------------------------------------------------------ scenarios
class HoldScenario(Scenario):
    """The robot at rest at the path origin (IK of h_CG = 0.15 m, body level) with constant motor torques that
    balance gravity in the reduced model (least squares of :math:`B_r\\tau = g_r`): it must stay at rest."""

    def initial_state(self, robot: Robot) -> tuple[np.ndarray, np.ndarray]:
        from .comparison import model_configuration  # the paper's IK places the robot (eqs 4-24)
        from .paper import Commands, solve_ik

        cmd = Commands(0.0, 0.0, 0.15)
        x, _, _ = solve_ik(cmd, robot.params, robot.terrain)
        q0 = model_configuration(robot, cmd, x)
        red = robot.reduced(q0, np.zeros(robot.mobility))
        tau, *_ = np.linalg.lstsq(red.B, red.g, rcond=None)
        self.holding = tau
        self.torque = Constant(tau)  # torques as data: simulated by the compiled engine
        return q0, np.zeros(robot.mobility)


SCENARIOS = {
    "hold": HoldScenario(
        "hold", "at rest on the terrain (h_CG = 0.15 m, body level) with the static holding torques; stays at rest "
        "(statics through the forward dynamics)", 1.0, n_out=101),
}
