"""Trajectory optimisation of a light robot (robotdyn.optimisation.scaling): IPOPT's torques and objective in units
of their own expected size.

Found on a new user's TurtleBot3 Burger (session 32): ``robotdyn optimise`` 0.3 m straight ahead in 2 s ran 500
IPOPT iterations and failed, with 11 and 21 nodes, with analytic and finite-difference Jacobians alike, on feasible
iterates. The fixture here is robotdyn's own (``tests/data/light_diff_drive``, nothing copied): a 1 kg body, two
30 g wheels of radius r = 0.033 m (axle inertia I_w = 2.1e-5 kg m^2) and a frictionless skid of 5 g, on a planar
root. On the old code it fails in the same way (measured: 500 iterations at 11 and at 21 nodes).

Closed form (the reference): straight ahead the robot is a double integrator. Each wheel's torque is
tau = J w' with J = m r^2 / 2 + I_w (m = 1.065 kg, all the mass moves with the body; x'' = r w'), and the
minimum of the effort 2 * integral(tau^2) over rest-to-rest motions of d in T is reached by a linear acceleration,
x''(t) = (6 d / T^2)(1 - 2 t / T), and equals 24 (J / r)^2 d^2 / T^3. The trapezoidal collocation's optimum tends
to it as the square of the step.
"""

from __future__ import annotations

import math
import pathlib

import numpy as np
import pytest

pytest.importorskip("casadi")

from robotdyn.interfaces.constraint_file import load_robot  # noqa: E402
from robotdyn.optimisation import TrajectoryProblem  # noqa: E402
from robotdyn.optimisation import scaling  # noqa: E402
from robotdyn.simulation.engine import simulate  # noqa: E402

DATA = pathlib.Path(__file__).parent / "data"
D, T = 0.3, 2.0  # [m], [s]
M, R, I_W = 1.0 + 2 * 0.03 + 0.005, 0.033, 2.1e-5  # the fixture's mass [kg], wheel radius [m], axle inertia [kg m^2]
J = M * R ** 2 / 2 + I_W  # each wheel's share of the inertia seen at its axle [kg m^2]
EFFORT = 24 * (J / R) ** 2 * D ** 2 / T ** 3  # the continuous optimum [N^2 m^2 s]


@pytest.fixture(scope="module")
def robot():
    return load_robot(DATA / "light_diff_drive.toml")


def _problem(robot, nodes, derivatives="analytic"):
    return TrajectoryProblem(robot, T, nodes, robot.neutral(), q_end={"x": D, "y": 0.0, "psi": 0.0},
                             derivatives=derivatives)


@pytest.fixture(scope="module")
def solved(robot):
    return {n: _problem(robot, n).solve() for n in (11, 21)}


def test_the_light_robot_converges_to_the_closed_form_optimum(solved):
    """11 and 21 nodes converge (old code: Maximum_Iterations_Exceeded after 500), to the closed form's effort
    within the trapezoid's O(h^2) error: the gap shrinks about 4 times when the step halves."""
    for s in solved.values():
        assert s.status == "Solve_Succeeded" and s.iterations < 60, s
        assert s.max_defect < 1e-9
        assert np.allclose(s.q[-1, :3], [D, 0.0, 0.0], atol=1e-12) and np.allclose(s.nu[[0, -1]], 0.0, atol=1e-12)
    gap11, gap21 = solved[11].cost - EFFORT, solved[21].cost - EFFORT
    assert 0 < gap21 < 0.02 * EFFORT  # measured: 1.0 %
    assert 3.5 < gap11 / gap21 < 4.5  # measured: 3.96
    assert np.allclose(solved[21].tau[:, 0], solved[21].tau[:, 1], atol=1e-9 * EFFORT)  # straight: equal wheels


def test_analytic_and_finite_difference_reach_the_same_optimum(robot, solved):
    fd = _problem(robot, 11, "finite-difference").solve()
    assert fd.status == "Solve_Succeeded", fd
    assert abs(fd.cost - solved[11].cost) <= 1e-6 * solved[11].cost  # measured: equal to 12 digits
    assert np.allclose(fd.tau, solved[11].tau, atol=1e-6 * np.max(np.abs(fd.tau)))


def test_resimulation_with_the_exact_model_reaches_the_target(robot, solved):
    """The optimal torques replayed by the integrator end at rest within the collocation's error at D: 0.3 % of D
    at 21 nodes (measured 0.24 %; 0.93 % at 11 nodes, second order), and straight (y, psi stay 0)."""
    s = solved[21]
    tr = simulate(robot, T, s.q[0], s.nu[0], s.profile(), n_out=201, progress=False)
    assert abs(tr.q[-1, 0] - D) < 3e-3 * D
    assert np.max(np.abs(tr.q[:, 1:3])) < 1e-9
    assert np.max(np.abs(tr.nu[-1])) < 1e-9 * np.max(np.abs(tr.nu))


def test_guessed_torques_are_the_closed_form_of_the_guessed_motion(robot):
    """The scaling's torques follow the guess's ramp x = D (1 - cos(pi t / T)) / 2 through tau = J w', with w' the
    central difference over the nodes of w = x' / r: (pi^2 D / (2 T^2 r)) cos(pi t / T) sin(pi h / T) / (pi h / T)."""
    p = _problem(robot, 21)
    X, _ = p._split(p._initial())
    tau = scaling.guessed_torques(p, X)
    t, h = np.linspace(0, T, 21), T / 20
    w_dot = math.pi ** 2 * D / (2 * T ** 2 * R) * np.cos(math.pi * t / T) * math.sin(math.pi * h / T) / (math.pi * h / T)
    assert np.allclose(tau[1:-1], (J * w_dot)[1:-1, None], rtol=1e-9, atol=1e-12)
    units, factor = scaling.effort_units(p, p._initial())
    rms = np.sqrt(np.mean(tau ** 2, axis=0))
    assert np.all(np.abs(np.log2(units / rms)) <= 0.5) and np.all(np.log2(units) == np.round(np.log2(units)))
    effort = T * np.sum(rms ** 2)
    assert abs(math.log2(factor * scaling.OBJECTIVE_SHARE * effort)) <= 0.5


def _solution(status: str, success: bool, max_defect: float):
    from robotdyn.optimisation.trajectory import TrajectorySolution

    z = np.zeros((3, 1))
    return TrajectorySolution(np.arange(3.0), z, z, z, 0.0, status, success, 500, 0.0, 0, 0, max_defect, "analytic")


@pytest.mark.parametrize("status, success, defect, needle", [
    ("Solve_Succeeded", True, 0.0, ""),
    ("Solved_To_Acceptable_Level", True, 1e-12, ""),
    ("Maximum_Iterations_Exceeded", False, 1.8e-5, "iteration limit came before the constraints held: looser"),
    ("Maximum_Iterations_Exceeded", False, 1e-9, "on feasible points (the constraints held) before the optimum: a "
                                                  "badly scaled problem"),
    ("Infeasible_Problem_Detected", False, 0.3, "locally infeasible: looser bounds"),
    ("Restoration_Failed", False, 0.3, "restoration phase could not reduce"),
    ("Solve_Succeeded; held rows' largest defect 0.01", False, 0.01, "leaves a coordinate held"),
    ("Invalid_Number_Detected", False, 0.0, "non-finite number"),
    ("Search_Direction_Becomes_Too_Small", False, 0.0, "stopped before convergence (Search_Direction"),
])
def test_the_failure_diagnosis_says_what_happened(status, success, defect, needle):
    text = _solution(status, success, defect).diagnosis
    assert (needle in text) if needle else text == ""
    assert "\n" not in text


def test_cli_iteration_limit_on_feasible_points_is_not_called_infeasible(monkeypatch, capsys):
    """The old hint (looser bounds, more time or more nodes) came with every failure, also where the iterates met
    the constraints (the TurtleBot3's largest defect: 1.8e-5). Here IPOPT is given 3 iterations on the light robot,
    whose first step already meets the constraints."""
    from robotdyn.cli import main

    monkeypatch.setattr(TrajectoryProblem.solve, "__defaults__", (1e-9, 3, False))  # (tol, max_iter, verbose)
    argv = ["optimise", "--constraints", str(DATA / "light_diff_drive.toml"), "--t-end", "2", "--nodes", "11",
            "--end", "x=0.3", "--end", "y=0", "--end", "psi=0"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "Maximum_Iterations_Exceeded after 3 iterations" in err[0], err
    assert "on feasible points" in err[0] and "looser bounds" not in err[0], err
