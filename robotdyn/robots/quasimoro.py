"""Quasimoro (Angeles): two coaxial wheels and a pendulum-like intermediate body.

Paper: Şt. Staicu, "Dynamics of Angeles's Quasimoro mobile robot using principle of virtual powers"
(``shared/papers/staicu_quasimoro_virtual_powers.txt``). Description: ``urdf/quasimoro.urdf.xacro``.

Coordinates (x, y, psi) of the axle midpoint C2 and yaw; theta1, theta2 the wheel angles relative to the axle
frame (about +y, forward rolling positive); theta3 the body's inclination (about -y, mass centre forward positive).
Independent velocities: the paper's (theta1_dot, theta2_dot, theta3_dot).

This module holds the parameters (section 3), the two manoeuvres of section 3 and a transcription of the paper's
closed forms (eqs 23-31), kept apart from the model, which is derived by Pinocchio from the description.
"""

from __future__ import annotations

import numpy as np

from ..interfaces.comparison import Comparison, quadratic_coefficients
from ..robot import MotorSpec, Parameter, Robot, RobotSpec, Wheel
from ..simulation.scenario import Scenario
from ..simulation.torque_profile import Sine

SPEC = RobotSpec(
    name="quasimoro",
    title="Quasimoro: two wheels plus a pendulum body (Staicu, virtual powers)",
    xacro="quasimoro.urdf.xacro",
    root="planar",
    paper="staicu_quasimoro_virtual_powers.txt",
    parameters=[
        Parameter("m", 0.5, "kg", "mass of each wheel"),
        Parameter("M", 5.0, "kg", "mass of the intermediate body"),
        Parameter("J1", 0.2, "kg m^2", "body inertia about x_C (C2 -> G), eq 3"),
        Parameter("J2", 0.4, "kg m^2", "body inertia about y_C and z_C (the axle), eq 3"),
        Parameter("r", 0.3, "m", "wheel radius"),
        Parameter("d", 0.2, "m", "distance from the axle midpoint C2 to the body's mass centre"),
        Parameter("rho", 0.5, "-", "r / l, l = distance between the wheel centres, eq 11"),
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
    0 <= t <= 1 s, zero afterwards."""
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


# ------------------------------------------------------------------------------------ paper transcription
def paper_coefficients(p: dict, theta3: float) -> dict[str, float]:
    """The paper's coefficients A11..A19 (eq 24) at inclination theta3, as printed.

    Args:
        p: Parameters m, M, J1, J2, r, d, rho.
        theta3: Body inclination [rad].
    """
    m, M, J1, J2, r, d, rho = (p[k] for k in ("m", "M", "J1", "J2", "r", "d", "rho"))
    s, c = np.sin(theta3), np.cos(theta3)
    yaw = J1 * c**2 + J2 * s**2
    return {
        "A11": 0.5 * m * r**2 * (3 + rho**2) + rho**2 * yaw + 0.25 * M * r**2,
        "A12": -0.5 * m * r**2 * rho**2 - rho**2 * yaw + 0.25 * M * r**2,
        "A13": 0.5 * M * r * d * c,
        "A14": M * r * d * rho**2 * s,
        "A15": 2 * rho**2 * (J1 - J2) * s * c,
        "A16": -2 * rho**2 * (J1 - J2) * s * c,
        "A17": 0.0,
        "A18": -M * r * d * rho**2 * s,
        "A19": -0.5 * M * r * d * s,
    }


# index pairs (i, j) of nu_i nu_j, nu = (theta1_dot, theta2_dot, theta3_dot), in the paper's order A_4..A_9
_PRODUCTS = [(0, 1), (1, 2), (0, 2), (0, 0), (1, 1), (2, 2)]


def paper_equations(p: dict, theta3: float) -> tuple[np.ndarray, dict[tuple[int, int], np.ndarray], np.ndarray]:
    """The paper's reduced model in nu = (theta1_dot, theta2_dot, theta3_dot), rows = eqs 23, 25, 28.

    Returns:
        ``(M, quad, grav)``: the 3x3 inertia matrix, the velocity-product coefficient vectors
        ``{(i, j): 3-vector}`` and the gravity vector, so that row i reads
        ``M[i] @ nu_dot + sum quad[ij][i] nu_i nu_j + grav[i] = (m1, m2, m1 + m2)[i]``.
    """
    A = paper_coefficients(p, theta3)
    # eq 26: A21 = A12, A22 = A11, A23 = A13, A24 = A14, A25 = A16, A26 = A15, A27 = A18, A28 = A17, A29 = A19
    row1 = [A["A14"], A["A15"], A["A16"], A["A17"], A["A18"], A["A19"]]
    row2 = [A["A14"], A["A16"], A["A15"], A["A18"], A["A17"], A["A19"]]
    s, c = np.sin(theta3), np.cos(theta3)
    k = (p["J1"] - p["J2"]) * p["rho"] ** 2 * s * c  # eq 28: (J1 - J2) rho^2 (th2' - th1')^2 sin cos
    row3 = [-2 * k, 0.0, 0.0, k, k, 0.0]
    quad = {ij: np.array([row1[n], row2[n], row3[n]]) for n, ij in enumerate(_PRODUCTS)}
    half = 0.5 * p["M"] * p["r"] * p["d"] * c
    M = np.array([[A["A11"], A["A12"], A["A13"]], [A["A12"], A["A11"], A["A13"]], [half, half, p["J2"]]])
    grav = np.array([0.0, 0.0, p["M"] * p["g"] * p["d"] * s])
    return M, quad, grav


def paper_rectilinear_torque(p: dict, theta3: float, theta1_ddot: float, theta3_dot: float, theta3_ddot: float) -> float:
    """Eq 29: m1 = m2 = (3m + M) r^2 th1''/2 + M r d (th3'' cos th3 - th3'^2 sin th3)/2 (rectilinear motion)."""
    m, M, r, d = p["m"], p["M"], p["r"], p["d"]
    return 0.5 * (3 * m + M) * r**2 * theta1_ddot + 0.5 * M * r * d * (
        theta3_ddot * np.cos(theta3) - theta3_dot**2 * np.sin(theta3)
    )


def paper_rotation_inertia(p: dict) -> float:
    """Eq 31: :math:`m_1 = |m_2|` = [m r^2 (3/2 + rho^2) + 2 rho^2 J1] th1'' (pure rotation, theta3 = 0)."""
    return p["m"] * p["r"] ** 2 * (1.5 + p["rho"] ** 2) + 2 * p["rho"] ** 2 * p["J1"]


# ------------------------------------------------------------------------------------------ comparison
def model_equations(robot: Robot, q: np.ndarray) -> tuple[np.ndarray, dict[tuple[int, int], np.ndarray], np.ndarray]:
    """The model's (M_r, velocity-product coefficients, g_r) at q, from the Pinocchio path."""
    red = robot.reduced(q, np.zeros(3))
    quad = quadratic_coefficients(lambda nu: robot.reduced(q, nu).h, 3)
    return red.M, quad, red.g


def steady_amplitude(traj, name: str = "theta3", after: float = 10.0) -> float:
    """Half the peak-to-peak range of a coordinate after time ``after`` [s]."""
    x = traj.column(name)[traj.t >= after]
    return 0.5 * float(x.max() - x.min())


def compare(robot: Robot | None = None, trajectory=None, states: int = 50, seed: int = 0) -> Comparison:
    """The paper's closed forms and printed numbers against the model.

    Coefficients are compared at ``states`` random inclinations theta3; each row shows the paper's and the
    model's value at the inclination where they differ most (tolerance 1e-9, i.e. exact up to round-off). The steady theta3 amplitude comes from the rectilinear run (``trajectory``, simulated if None).
    """
    robot = robot or Robot(SPEC)
    p = robot.params
    rng = np.random.default_rng(seed)
    thetas = rng.uniform(-np.pi, np.pi, states)
    i3 = robot.coordinate_index("theta3")
    names = ["theta1", "theta2", "theta3"]
    worst: dict[str, tuple[float, float]] = {}

    def record(label: str, paper: float, model: float) -> None:
        """Keep, per quantity, the (paper, model) pair of the state where they differ most."""
        if label not in worst or abs(paper - model) > abs(worst[label][0] - worst[label][1]):
            worst[label] = (paper, model)

    eq = {0: "eq 23-24", 1: "eq 25-26", 2: "eq 28"}
    for th in thetas:
        q = robot.neutral()
        q[i3] = th
        Mp, quadp, gp = paper_equations(p, th)
        Mm, quadm, gm = model_equations(robot, q)
        for i in range(3):
            for j in range(3):
                record(f"row {i + 1} ({eq[i]}): {names[j]}''", Mp[i, j], Mm[i, j])
            for (a, b) in _PRODUCTS:
                label = f"{names[a]}'^2" if a == b else f"{names[a]}'{names[b]}'"
                record(f"row {i + 1} ({eq[i]}): {label}", quadp[(a, b)][i], quadm[(a, b)][i])
            record(f"row {i + 1} ({eq[i]}): gravity", gp[i], gm[i])
    cmp = Comparison(f"Quasimoro ({robot.params['inertia_about']} reading of J): paper vs model")
    for label, (paper, model) in worst.items():
        cmp.add(label, paper, model, 1e-9, note=f"largest difference over {states} random theta3")
    # eq 29 and eq 31 in their own manoeuvres
    q = robot.neutral()
    q[i3] = 0.3
    red = robot.reduced(q, np.array([0.7, 0.7, 0.4]))
    nudot = np.array([0.5, 0.5, -0.8])
    Q = red.M @ nudot + red.h
    # rectilinear: Q = (m1, m2, m1 + m2); eq 29 gives m1 from the wheel row
    cmp.add("eq 29: m1 (rectilinear, th3=0.3, th3'=0.4)", paper_rectilinear_torque(p, 0.3, 0.5, 0.4, -0.8), Q[0], 1e-9)
    q = robot.neutral()
    red = robot.reduced(q, np.zeros(3))
    model_rot = (red.M @ np.array([1.0, -1.0, 0.0]))[0]
    cmp.add("eq 31: pure-rotation inertia m1/th1''", paper_rotation_inertia(p), model_rot, 1e-9)
    if trajectory is None:
        trajectory = SCENARIOS["rectilinear"].run(robot, progress=False)
    cmp.add(
        "sec 3: steady theta3 amplitude [rad] (rectilinear)",
        0.0129,
        steady_amplitude(trajectory),
        5e-5,
        note="paper reads +-0.0129 rad off its Fig. 5: 3 significant digits, so half a unit of the last digit",
    )
    return cmp


def drift(robot: Robot, traj) -> float:
    """Largest violation of the integrated constraint psi = rho (theta2 - theta1) (eq 11) along a run [rad]."""
    rho = robot.params["rho"]
    return float(np.max(np.abs(traj.column("psi") - rho * (traj.column("theta2") - traj.column("theta1")))))
