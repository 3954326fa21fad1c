"""MMR12-EOD's least-friction climbing posture (robotdyn.robots.mmr12_eod.climbing_posture, on
robotdyn.optimisation.posture): IPOPT through CasADi with the analytic force derivatives and with finite
differences reaches the same optimum, equal to the closed-form bound (frictionless rear tips: the drive wheels'
traction is m g sin(psi), their loads m g cos(psi) less the tips', so the peak mu >= m g sin / (m g cos - 2 F_min),
reached when both tips carry exactly F_min), and the optimum holds on the exact model (Robot.contact_forces, the
forward dynamics, the holonomic constraints, the joint ranges)."""

from __future__ import annotations

import numpy as np
import pytest

from robotdyn.errors import InputError
from robotdyn.optimisation.posture import PostureProblem
from robotdyn.robots.mmr12_eod.climbing_posture import (climbing_posture_problem, least_mu_bound,
                                                        locked_climbing_robot, locked_climbing_state, weight)
from robotdyn.robots.mmr12_eod.model import climbing_forces

SLOPE = np.radians(20.0)


@pytest.fixture(scope="module")
def solutions():
    return {d: climbing_posture_problem(SLOPE, derivatives=d).solve() for d in ("analytic", "finite-difference")}


def test_analytic_and_finite_differences_reach_the_closed_form_optimum(solutions):
    a, fd = solutions["analytic"], solutions["finite-difference"]
    assert a.success and fd.success, (a.status, fd.status)
    assert abs(a.peak_mu - fd.peak_mu) <= 1e-6
    robot = locked_climbing_robot(SLOPE)
    f_min = 0.01 * weight(robot)
    bound = least_mu_bound(robot, SLOPE, f_min)
    assert a.peak_mu == pytest.approx(bound, rel=1e-7)  # 0.371885 at 20 deg (tan 20 deg = 0.36397)
    assert bound == pytest.approx(0.371885, abs=1e-6)
    default = climbing_forces(SLOPE).minimum_mu()  # the posture of climbing_state: 0.409582
    assert a.peak_mu < default - 0.03
    assert a.derivative_calls > 0 and fd.derivative_calls == 0


def test_the_optimum_holds_on_the_exact_model(solutions):
    sol = solutions["analytic"]
    robot = locked_climbing_robot(SLOPE)
    zero = np.zeros(robot.mobility)
    assert np.abs(robot.constraint_residual(sol.q)).max() < 1e-10  # on the ramp: wheels and tips touching
    robot.check_q(sol.q)  # within the joint ranges
    assert np.abs(robot.forward_dynamics(sol.q, zero, sol.tau)).max() < 1e-7  # the torques hold it still
    forces = robot.contact_forces(sol.q, zero, sol.tau)
    by = {w.name: w for w in forces.wheels}
    f_min = 0.01 * weight(robot)
    assert by["tip3"].normal == pytest.approx(f_min, rel=1e-6) and by["tip4"].normal == pytest.approx(f_min, rel=1e-6)
    assert forces.minimum_mu() == pytest.approx(sol.peak_mu, rel=1e-7)  # the best split: the mu optimised
    assert by["W_R"].force[0] + by["W_L"].force[0] == pytest.approx(weight(robot) * np.sin(SLOPE), rel=1e-9)


def test_posture_problem_refuses_bad_variables_in_one_line():
    robot = locked_climbing_robot(SLOPE)
    q0 = locked_climbing_state(robot, SLOPE)
    with pytest.raises(InputError, match="not a coordinate"):
        PostureProblem(robot, q0, ["elbow"])
    with pytest.raises(InputError, match="fixed by the holonomic constraints"):
        PostureProblem(robot, q0, ["theta_C3", "theta_C4"])  # the tips' contact ties them, given the base
    with pytest.raises(InputError, match="unknown wheel"):
        PostureProblem(robot, q0, ["lambda2"], friction_wheels=["W_X"])


def test_cli_prints_the_apis_optimum(capsys, solutions):
    """`robotdyn climbing-posture mmr12_eod --slope 20 --json`: the API's optimum (one story through both doors);
    another robot is refused in one line, exit status 2."""
    import json

    from robotdyn.cli import main

    assert main(["climbing-posture", "mmr12_eod", "--slope", "20", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    sol = solutions["analytic"]
    assert out["success"] and out["peak_mu"] == pytest.approx(sol.peak_mu, abs=1e-9)
    assert out["bound"] == pytest.approx(sol.peak_mu, rel=1e-7)
    assert out["default_posture_mu"] == pytest.approx(0.409582, abs=5e-7)
    assert list(out["posture"]) == sol.variables and out["loads"]["tip3"] == pytest.approx(out["min_tip_load"])
    assert main(["climbing-posture", "quasimoro", "--slope", "20"]) == 2
    err = capsys.readouterr().err
    assert "expected mmr12_eod" in err and err.count("\n") == 1
