"""Quasimoro (Angeles): the model side -- parameters, motors, the section-3 manoeuvres as scenarios.

Description: ``urdf/quasimoro.urdf.xacro``; Pinocchio derives the dynamics from it (nothing here is a closed form).
Paper the parameters and manoeuvres come from: Şt. Staicu, "Dynamics of Angeles's Quasimoro mobile robot using
principle of virtual powers" (Staicu, ``docs/bibliography.md``): parameter values of
section 3, the torque pulse of eq 19, the two manoeuvres of section 3 (1° rectilinear, 2° pure rotation).

Coordinates (x, y, psi) of the axle midpoint C2 and yaw; theta1, theta2 the wheel angles relative to the axle
frame (about +y, forward rolling positive); theta3 the body's inclination (about -y, mass centre forward positive).
Independent velocities: the paper's (theta1_dot, theta2_dot, theta3_dot).

The paper's closed forms (eqs 23-31) are in :mod:`robotdyn.robots.quasimoro.paper`, their comparison with this model in :mod:`robotdyn.robots.quasimoro.comparison`.
"""

from __future__ import annotations

import numpy as np

from ...robot import MotorSpec, Parameter, Robot, RobotSpec, Wheel
from ...simulation.scenario import Scenario
from ...simulation.torque_profile import Sine


SPEC = RobotSpec(
    name="quasimoro",
    title="Quasimoro: two wheels plus a pendulum body (Staicu, virtual powers)",
    xacro="quasimoro.urdf.xacro",
    root="planar",
    paper="Staicu, Dynamics of Angeles's Quasimoro mobile robot using principle of virtual powers",
    parameters=[
        Parameter("m", 0.5, "kg", "mass of each wheel"),
        Parameter("M", 5.0, "kg", "mass of the intermediate body", positive=True),
        Parameter("J1", 0.2, "kg m^2", "body inertia about x_C (C2 -> G), eq 3"),
        Parameter("J2", 0.4, "kg m^2", "body inertia about y_C and z_C (the axle), eq 3"),
        Parameter("r", 0.3, "m", "wheel radius", positive=True),
        Parameter("d", 0.2, "m", "distance from the axle midpoint C2 to the body's mass centre (0 is valid: mass centre on the axle)"),
        Parameter("rho", 0.5, "-", "r / l, l = distance between the wheel centres, eq 11", positive=True),
        Parameter(
            "inertia_about", "axle", "", "point about which diag(J1, J2, J2) is taken: axle (C2) or com (G)",
            choices=("axle", "com"),
        ),
        Parameter("g", 9.81, "m/s^2", "gravitational acceleration (the paper does not print it)", xacro=False),
    ],
    wheels=[Wheel("wheel_A", "r", name="wheel_A"), Wheel("wheel_B", "r", name="wheel_B")],
    motors=[MotorSpec("m1", "theta1", reaction="body"), MotorSpec("m2", "theta2", reaction="body")],
    independent=["theta1", "theta2", "theta3"],
)

PULSE_AMPLITUDE = 0.1
"""Torque pulse amplitude m_i° [N m] of eq 19 (section 3)."""


def _pulse(t: float) -> float:
    """Eq 19: m° sin(pi t) for 0 <= t <= 1 s, zero afterwards."""
    return PULSE_AMPLITUDE * np.sin(np.pi * t) if 0.0 <= t <= 1.0 else 0.0


def pulse(signs: tuple[float, float]) -> Sine:
    """Eq 19 on both motors as a torque profile (compiled: robotdyn.simulation.torque_profile): m_i = sign_i m° sin(pi t) for
    0 <= t <= 1 s, zero afterwards.

    Args:
        signs: The sign (+1 or -1) of each motor's pulse (m1, m2).

    Returns:
        A :class:`~robotdyn.simulation.torque_profile.Sine` profile [N m].
    """
    return Sine([signs[0] * PULSE_AMPLITUDE, signs[1] * PULSE_AMPLITUDE], np.pi, start=0.0, stop=1.0)


SCENARIOS = {
    "rectilinear": Scenario(
        "rectilinear",
        "section 3, 1°: m1 = m2 = 0.1 sin(pi t) N m for t <= 1 s, then free; robot initially at rest (90 s)",
        90.0,
        torque=pulse((1.0, 1.0)),
        plot=["theta1", "theta3", "theta1_dot", "theta3_dot"],  # Figs. 2-9
        zoom=4.0,  # the paper's window 0 .. dt + 3 s
        references={"theta3": [(0.0129, "paper: +-0.0129 rad"), (-0.0129, "")]},
    ),
    "pure_rotation": Scenario(
        "pure_rotation",
        "section 3, 2°: m1 = -m2 = 0.1 sin(pi t) N m for t <= 1 s, then free; robot initially at rest (90 s)",
        90.0,
        torque=pulse((1.0, -1.0)),
        plot=["theta1", "theta1_dot", "psi", "theta3"],  # Figs. 10-13, plus psi and the level body
        zoom=4.0,
    ),
}


def steady_amplitude(traj, name: str = "theta3", after: float = 10.0) -> float:
    """Half the peak-to-peak range of a coordinate after time ``after`` [s].

    Args:
        traj: The :class:`~robotdyn.simulation.trajectory.Trajectory`.
        name: The coordinate's name.
        after: Start of the steady window [s].

    Returns:
        The half range [unit of the coordinate].
    """
    x = traj.column(name)[traj.t >= after]
    return 0.5 * float(x.max() - x.min())


def drift(robot: Robot, traj) -> float:
    """Largest violation of the integrated constraint psi = rho (theta2 - theta1) (eq 11) along a run [rad].

    Args:
        robot: The Quasimoro :class:`~robotdyn.robot.Robot` (its rho).
        traj: Its :class:`~robotdyn.simulation.trajectory.Trajectory`.

    Returns:
        The largest violation [rad].
    """
    rho = robot.params["rho"]
    return float(np.max(np.abs(traj.column("psi") - rho * (traj.column("theta2") - traj.column("theta1")))))
