"""Trajectory optimisation (issue 26, item 3): Quasimoro's minimum-effort rest-to-rest motion on IPOPT.

References: the optimum with the analytic dynamics derivatives equals the one with central finite differences of
the forward dynamics (the same NLP, only the constraint Jacobian's source differs) to 1e-6 in cost; a re-simulation
of the optimal torques (a piecewise-linear Table, what the collocation assumed) with the exact model and robotdyn's
integrator reaches the target and keeps the bounds within the trapezoidal discretisation error, which is O(h^2):
the test measures it at two node counts.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("casadi")

import robotdyn  # noqa: E402
from robotdyn.errors import InputError  # noqa: E402
from robotdyn.optimisation import TrajectoryProblem  # noqa: E402
from robotdyn.robots.quasimoro.optimal_motion import rest_to_rest  # noqa: E402
from robotdyn.simulation.engine import simulate  # noqa: E402

NODES, PITCH = 11, 0.08  # cheap: ~2 s per solve (0.06 rad, the example's bound, needs more nodes)


@pytest.fixture(scope="module")
def robot():
    return robotdyn.load("quasimoro")


@pytest.fixture(scope="module")
def analytic(robot):
    return rest_to_rest(nodes=NODES, pitch_max=PITCH, robot=robot).solve()


def test_analytic_and_finite_difference_reach_the_same_optimum(robot, analytic):
    fd = rest_to_rest(nodes=NODES, pitch_max=PITCH, robot=robot, derivatives="finite-difference").solve()
    assert analytic.success and fd.success, (analytic.status, fd.status)
    assert abs(analytic.cost - fd.cost) <= 1e-6
    assert np.allclose(analytic.tau, fd.tau, atol=1e-5)
    assert analytic.derivative_calls > 0 and fd.derivative_calls == 0


def test_bounds_and_boundary_conditions_hold_at_the_nodes(analytic):
    s = analytic
    assert s.max_defect < 1e-8
    assert np.all(np.abs(s.tau) <= 0.6 + 1e-9)
    assert np.all(np.abs(s.q[:, 5]) <= PITCH + 1e-9)
    assert np.max(np.abs(s.q[:, 5])) > PITCH - 1e-6  # the pitch bound is active (unbounded: ~0.10 rad)
    assert np.max(np.abs(s.tau)) > 0.6 - 1e-6  # and so is the torque bound
    assert np.allclose(s.q[0], 0) and np.allclose(s.nu[[0, -1]], 0)
    assert np.allclose(s.q[-1, [0, 1, 2, 5]], [1.0, 0.0, 0.0, 0.0])


def _resimulate(robot, s):
    tr = simulate(robot, s.t[-1], s.q[0], s.nu[0], s.profile(), n_out=601, progress=False)
    return tr


def test_resimulation_with_the_exact_model_keeps_the_constraints(robot, analytic):
    """The optimal torques replayed by the integrator: the final state within 2 cm / 0.02 rad/s of rest at 1 m
    (11 nodes), the pitch within its bound plus the discretisation error (0.04 rad at 11 nodes), the torques
    within their bound (a Table interpolates between node values)."""
    tr = _resimulate(robot, analytic)
    assert abs(tr.q[-1, 0] - 1.0) < 2e-2
    assert np.max(np.abs(tr.nu[-1])) < 2e-2
    assert np.max(np.abs(tr.q[:, 5])) < PITCH + 0.04
    tau = analytic.profile().at(tr.t)
    assert np.all(np.abs(tau) <= 0.6 + 1e-9)


def test_resimulation_error_shrinks_as_the_square_of_the_step(robot, analytic):
    """Trapezoidal collocation is second order: doubling the nodes' density divides the gap between the
    collocation and the exact model's motion by about 4 (accept >= 3)."""
    fine = rest_to_rest(nodes=2 * NODES - 1, pitch_max=PITCH, robot=robot, derivatives="finite-difference").solve()

    def gap(s):  # the re-simulated final state against the collocation's
        return np.max(np.abs(_resimulate(robot, s).q[-1] - s.q[-1]))

    assert gap(analytic) / gap(fine) >= 3.0


def test_repr_and_bad_input(robot):
    p = rest_to_rest(nodes=5, robot=robot)
    assert "quasimoro" in repr(p) and "theta3" in repr(p)
    with pytest.raises(InputError, match="nodes"):
        TrajectoryProblem(robot, 3.0, 2, [0] * 6)
    with pytest.raises(InputError, match="t_end"):
        TrajectoryProblem(robot, float("nan"), 5, [0] * 6)
    with pytest.raises(InputError, match="t_end"):
        TrajectoryProblem(robot, "soon", 5, [0] * 6)
    with pytest.raises(InputError, match="nodes"):
        TrajectoryProblem(robot, 3.0, "many", [0] * 6)
    with pytest.raises(InputError, match="bounds names 'pitch'"):
        TrajectoryProblem(robot, 3.0, 5, [0] * 6, bounds={"pitch": (-1, 1)})
    with pytest.raises(InputError, match="q_end"):
        TrajectoryProblem(robot, 3.0, 5, [0] * 6, q_end={"z": 1.0})
    with pytest.raises(InputError, match="derivatives"):
        TrajectoryProblem(robot, 3.0, 5, [0] * 6, derivatives="auto")
    with pytest.raises(InputError, match="tau_bounds"):
        TrajectoryProblem(robot, 3.0, 5, [0] * 6, tau_bounds=(1.0, -1.0))
    with pytest.raises(InputError, match="outside the bounds on theta3"):
        TrajectoryProblem(robot, 3.0, 5, [0] * 6, q_end={"theta3": 0.5}, bounds={"theta3": (-0.1, 0.1)})
    with pytest.raises(InputError, match="pitch_max"):
        rest_to_rest(pitch_max=0.0, robot=robot)


def test_start_off_the_holonomic_manifold_is_refused_in_one_line():
    """Robots with holonomic rows are collocated on their manifold (every node on it): a q0 off it is an error."""
    from robotdyn.errors import ConstraintError

    robot = robotdyn.load("linkage_suspension")
    q0 = robot.neutral()
    q0[robot.coordinate_index("z")] += 0.01
    with pytest.raises(ConstraintError) as err:
        TrajectoryProblem(robot, 1.0, 5, q0)
    assert len(str(err.value).splitlines()) == 1


CLI = ["optimise", "quasimoro", "--t-end", "3", "--nodes", str(NODES), "--end", "x=1", "--end", "y=0", "--end",
       "psi=0", "--end", "theta3=0", "--bound", f"theta3=-{PITCH}:{PITCH}", "--tau-max", "0.6"]


def test_cli_prints_the_apis_optimum_and_writes_the_node_table(analytic, tmp_path, capsys):
    """One story: ``robotdyn optimise`` solves the same problem as the API (same cost, same node torques)."""
    import json

    from robotdyn.cli import main

    csv = tmp_path / "nodes.csv"
    assert main([*CLI, "--json", "--csv", str(csv)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["success"] and abs(out["cost"] - analytic.cost) <= 1e-9
    table = np.loadtxt(csv, delimiter=",", skiprows=1)
    assert table.shape == (NODES, 1 + 6 + 3 + 2)
    assert np.allclose(table[:, -2:], analytic.tau, atol=1e-9)


@pytest.mark.parametrize("extra, needle", [(["--bound", "theta3=0.1"], "LOWER:UPPER"),
                                           (["--bound", "theta3=0.1:-0.1"], "LOWER <= UPPER"),
                                           (["--end", "z=1"], "q_end names 'z'"),
                                           (["--nodes", "2"], "nodes"),
                                           (["--tau-max", "nan"], "--tau-max"),
                                           (["--tau-max", "-1"], "--tau-max"),
                                           (["--derivatives", "exact"], "derivatives")])
def test_cli_bad_input_one_line_exit_2(extra, needle, capsys):
    from robotdyn.cli import main

    assert main([*CLI, *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0], err


def test_small_motion_costs_the_linear_models_minimum_energy(robot):
    """An independent reference: for a small motion (5 mm) the dynamics are linear about rest,
    :math:`\\dot x = Ax + B\\tau` (A, B by central differences of the forward dynamics here), and the least
    :math:`\\int_0^T |\\tau|^2 dt` that brings C x(T) from 0 to c is :math:`c^T (C W C^T)^{-1} c` with the
    reachability Gramian :math:`W = \\int_0^T e^{At}BB^Te^{A^Tt}dt` (Van Loan's matrix exponential). C selects x, psi,
    theta3 and the velocities (y is not reachable to first order: left free; the wheel angles are free). The
    collocation's cost is within its discretisation error of it: measured 1.4 % at 21 nodes (the 1 s body-swing
    period is 7 steps of 0.15 s), 1.1 % at 41, 0.31 % at 81; the same relative gap at 0.5 mm and 5 cm (the motion
    is in the linear range). Checked to 3 % at 21 nodes."""
    from scipy.linalg import expm

    n, k, m = 6, 3, 2
    nx = n + k

    def f(x, u):
        q, nu = x[:n], x[n:]
        return np.concatenate([robot.reduced(q, nu).S @ nu, robot.forward_dynamics(q, nu, u, check=False)])

    x0, u0, e = np.zeros(nx), np.zeros(m), 1e-6
    A = np.column_stack([(f(x0 + e * d, u0) - f(x0 - e * d, u0)) / (2 * e) for d in np.eye(nx)])
    B = np.column_stack([(f(x0, u0 + e * d) - f(x0, u0 - e * d)) / (2 * e) for d in np.eye(m)])
    T, dist = 3.0, 0.005
    E = expm(np.block([[-A, B @ B.T], [np.zeros((nx, nx)), A.T]]) * T)
    W = E[nx:, nx:].T @ E[:nx, nx:]
    C = np.eye(nx)[[0, 2, 5, 6, 7, 8]]
    c = np.zeros(C.shape[0])
    c[0] = dist
    reference = c @ np.linalg.solve(C @ W @ C.T, c)
    s = TrajectoryProblem(robot, T, 21, [0] * 6, q_end={"x": dist, "psi": 0.0, "theta3": 0.0},
                          derivatives="finite-difference").solve()
    assert s.success
    assert abs(s.cost - reference) / reference < 0.03, (s.cost, reference)


def test_cli_infeasible_problem_is_one_line_exit_2_and_no_file(tmp_path, capsys):
    """0.01 N m cannot move the robot 1 m in 3 s: IPOPT reports infeasibility; nothing is printed or written."""
    from robotdyn.cli import main

    csv = tmp_path / "nodes.csv"
    argv = ["optimise", "quasimoro", "--t-end", "3", "--nodes", "11", "--end", "x=1", "--tau-max", "0.01"]
    assert main([*argv, "--csv", str(csv)]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and not csv.exists()
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and "did not converge" in err[0], err
