"""Quasimoro: the model against the paper (:func:`compare`) and the model-side helper it needs.

Brings :mod:`robotdyn.robots.quasimoro.model` (Pinocchio's reduced dynamics of ``urdf/quasimoro.urdf.xacro``) and :mod:`robotdyn.robots.quasimoro.paper` (eqs 23-31
of Staicu, ``docs/bibliography.md``) together; disagreements are discussed in
``docs/errata/quasimoro.md``.
"""

from __future__ import annotations

import numpy as np

from ...interfaces.comparison import Comparison, quadratic_coefficients
from ...robot import Robot
from .model import SCENARIOS, SPEC, steady_amplitude
from .paper import (
    _PRODUCTS,
    STEADY_THETA3_AMPLITUDE,
    paper_equations,
    paper_rectilinear_torque,
    paper_rotation_inertia,
)


def model_equations(robot: Robot, q: np.ndarray) -> tuple[np.ndarray, dict[tuple[int, int], np.ndarray], np.ndarray]:
    """The model's (M_r, velocity-product coefficients, g_r) at q, from the Pinocchio path.

    Args:
        robot: The Quasimoro :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (x, y, psi, theta1, theta2, theta3) [m, rad].

    Returns:
        ``(M_r, coefficients, g_r)``: the reduced mass matrix (k, k), a dict of velocity pair (i, j) to its coefficient
        column (k,), and the reduced gravity (k,).
    """
    red = robot.reduced(q, np.zeros(3))
    quad = quadratic_coefficients(lambda nu: robot.reduced(q, nu).h, 3)
    return red.M, quad, red.g


def compare(robot: Robot | None = None, trajectory=None, states: int = 50, seed: int = 0) -> Comparison:
    """The paper's closed forms and printed numbers against the model.

    Coefficients are compared at ``states`` random inclinations theta3; each row shows the paper's and the
    model's value at the inclination where they differ most (tolerance 1e-9, i.e. exact up to round-off). The steady theta3 amplitude comes from the rectilinear run (``trajectory``, simulated if None).

    Args:
        robot: The Quasimoro robot (default ``None``: built with the default parameters).
        trajectory: The rectilinear run (default ``None``: simulated here).
        states: Number of random inclinations theta3 at which the coefficients are compared.
        seed: Seed of those inclinations.

    Returns:
        The :class:`~robotdyn.interfaces.comparison.Comparison`.
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
        STEADY_THETA3_AMPLITUDE,
        steady_amplitude(trajectory),
        5e-5,
        note="paper reads +-0.0129 rad off its Fig. 5: 3 significant digits, so half a unit of the last digit",
    )
    return cmp
