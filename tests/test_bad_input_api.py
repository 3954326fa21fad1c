"""Hostile inputs through the API on the newest pieces (issue 23's compliant runs, issue 26's derivatives and
optimiser): each is refused with a one-line :class:`~robotdyn.errors.RobotDynError` naming what is wrong and what
was expected, never a result computed from it (a NaN tolerance used to run), never numpy's, pybind11's or
CasADi's own error. Each case below failed on the code before it (it returned a result or raised another error).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import robotdyn
from robotdyn.errors import InputError, RobotDynError
from robotdyn.interfaces.constraint_file import read
from robotdyn.simulation.engine import simulate

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.fixture(scope="module")
def rolling_bump():
    """The rigid base on compliant rolling wheels (its runs take the compiled switching engine), at its start."""
    cf = read(EXAMPLES / "bump_base_rolling.toml")
    robot = cf.robot()
    q0, nu0 = cf.SCENARIOS["bump"].initial_state(robot)
    return robot, q0, nu0


def _one_line(exc: pytest.ExceptionInfo, *names: str) -> None:
    message = str(exc.value)
    assert "\n" not in message and "expected" in message, message
    assert all(n in message for n in names), message


@pytest.mark.parametrize("method", [None, "rosenbrock4", "dopri5", "DOP853"])
@pytest.mark.parametrize("option, value", [("rtol", 0.0), ("rtol", -1e-6), ("rtol", float("nan")), ("rtol", 1.5),
                                           ("atol", -1.0), ("atol", float("inf")), ("n_out", 5.5)])
def test_simulate_refuses_bad_integrator_options(rolling_bump, method, option, value):
    """rtol/atol outside (0, 1) (the sweep file's rule) and a fractional sample count: refused before any engine
    runs, on the compiled rolling compliant path (default dopri5, rosenbrock4) and the scipy path alike."""
    robot, q0, nu0 = rolling_bump
    with pytest.raises(RobotDynError) as exc:
        simulate(robot, 0.01, q0, nu0, None, **{"n_out": 3, option: value}, method=method, progress=False)
    _one_line(exc, option)


def test_simulate_refuses_an_unknown_method(rolling_bump):
    """An unknown method name: one line listing both engines' methods (was scipy's ValueError with its dict)."""
    robot, q0, nu0 = rolling_bump
    with pytest.raises(RobotDynError) as exc:
        simulate(robot, 0.01, q0, nu0, None, n_out=3, method="rk4", progress=False)
    _one_line(exc, "rk4", "rosenbrock4", "DOP853")


@pytest.mark.parametrize("bad", ["q_short", "nu_long", "tau_short", "q_2d", "q_text", "tau_none"])
def test_unchecked_derivatives_refuse_wrong_shapes(bad):
    """``dynamics_derivatives(check=False)`` skips value checks, not shapes: a wrong length or a non-number is an
    InputError naming the vector (was the binding's ValueError/TypeError or numpy's)."""
    robot = robotdyn.load("quasimoro")
    q, nu, tau = robot.neutral(), np.zeros(3), np.zeros(2)
    args = {"q_short": (q[:-1], nu, tau), "nu_long": (q, np.zeros(4), tau), "tau_short": (q, nu, tau[:1]),
            "q_2d": (q[None], nu, tau), "q_text": (["a"] * 6, nu, tau), "tau_none": (q, nu, None)}[bad]
    with pytest.raises(InputError) as exc:
        robot.dynamics_derivatives(*args, check=False)
    _one_line(exc, bad.split("_")[0])


def test_forward_dynamics_refuses_missing_torques():
    """``forward_dynamics(q, nu, None)``: an InputError naming tau and the motors (was an unpacking ValueError)."""
    robot = robotdyn.load("quasimoro")
    with pytest.raises(InputError) as exc:
        robot.forward_dynamics(robot.neutral(), np.zeros(3), None)
    _one_line(exc, "tau", "m1", "m2")


def test_trajectory_problem_refuses_unreachable_sizes():
    """A final coordinate beyond what any robot reaches and a collocation too large for memory are refused up
    front (were IPOPT tracebacks at its trial points, and a 10^8-node problem that exhausted memory)."""
    from robotdyn.optimisation.trajectory import MAX_NODES, TrajectoryProblem

    robot = robotdyn.load("quasimoro")
    with pytest.raises(InputError) as exc:
        TrajectoryProblem(robot, 1.0, 5, robot.neutral(), q_end={"x": 1e9})
    _one_line(exc, "q_end", "x")
    with pytest.raises(InputError) as exc:
        TrajectoryProblem(robot, 1.0, MAX_NODES + 1, robot.neutral(), q_end={"x": 0.1})
    _one_line(exc, "nodes")


def test_a_model_error_at_a_trial_point_is_kept_not_printed(capfd):
    """A constraint callback whose model raises at a point IPOPT tries returns NaN (IPOPT backtracks or stops with
    its status) and keeps the first error for the one-line report; nothing is printed (CasADi used to print the
    Python traceback and a dump of the point)."""
    import casadi as ca

    from robotdyn.optimisation.callbacks import refusal, sparse_callback

    def values(z):
        if z[0] > 1:
            raise InputError("q[x] = 2 m is beyond what this toy reaches; expected abs(x) <= 1")
        return np.array([z[0] ** 2])

    keep: list = []
    g = sparse_callback("toy", 1, 1, values, lambda z: np.array([2 * z[0]]), np.array([0]), np.array([0]), keep)
    assert float(g(ca.DM([0.5]))) == 0.25 and refusal(keep) is None
    assert np.isnan(float(g(ca.DM([2.0]))))
    assert refusal(keep) == "InputError: q[x] = 2 m is beyond what this toy reaches; expected abs(x) <= 1"
    out, err = capfd.readouterr()
    assert "Traceback" not in out + err
