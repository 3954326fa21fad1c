"""Derivatives and trajectory optimisation of a robot with joint springs: the sprung car (examples/sprung_car.toml).

Until this test, ``robotdyn optimise`` on the sprung car ran 500 IPOPT iterations and failed: the analytic
dynamics derivatives left the joint springs and dampers out (their nudot was the car without suspension forces,
falling at g), so IPOPT's steps followed a different model from its defects. A second cause, met once the first
was mended: at zero roll the car's no-slip wheels and vertical suspensions leave a roll velocity that no other roll
angle has (the rows change rank), so a trial point or a finite-difference step off roll = 0 is refused; the
optimisation now holds roll and roll_dot at their start values.

References (independent of the code under test):
- Closed forms of heave: moving z at fixed pitch and roll slides every upright along its vertical suspension while
  the wheels stay on the ground, so only the chassis (m_body = 1200 kg, at its centre of mass) moves, against the
  four springs and dampers in parallel: :math:`\\partial\\ddot z/\\partial z = -4k/m_{body} = -100\\ 1/s^2` (along
  the holonomic manifold) and :math:`\\partial\\ddot z/\\partial\\dot z = -4c/m_{body} = -10\\ 1/s`.
- Central finite differences of the forward dynamics (the nudot every other door integrates), in nu and along the
  holonomic level set in q.
- The optimum with analytic derivatives equals the one with finite differences (<= 1e-6 in cost, the same NLP);
  a re-simulation of the optimal torques with the exact model keeps the wheels on the ground and the car level in
  roll, and reaches the target within the trapezoid's discretisation error at 5 nodes.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("casadi")

from robotdyn.errors import InputError, RobotDynWarning  # noqa: E402
from robotdyn.interfaces.constraint_file import read  # noqa: E402
from robotdyn.optimisation import TrajectoryProblem  # noqa: E402
from robotdyn.simulation.engine import simulate  # noqa: E402

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
K, C, M_BODY = 30000.0, 3000.0, 1200.0  # examples/sprung_car.toml, examples/sprung_car.urdf.xacro
NODES, X_END = 5, 0.1


@pytest.fixture(scope="module")
def car():
    return read(EXAMPLES / "sprung_car.toml").robot()


@pytest.fixture(scope="module")
def analytic(car):
    p = TrajectoryProblem(car, 1.0, NODES, car.neutral(), q_end={"x": X_END})
    return p, p.solve()


def _central(f, x, h=1e-6):
    return np.column_stack([(f(x + h * e) - f(x - h * e)) / (2 * h) for e in np.eye(len(x))])


@pytest.mark.parametrize("example", ["sprung_car", "sprung_cornering_car"])
def test_springs_and_dampers_enter_the_dynamics_derivatives(example):
    """nudot of the derivative set is forward dynamics' (the old one omitted the springs: z'' = -g), its nu
    derivative is central differences' (the dampers), and the heave terms are the closed forms above."""
    robot = read(EXAMPLES / f"{example}.toml").robot()
    q = robot.neutral()
    rng = np.random.default_rng(3)
    nu = 0.2 * rng.normal(size=robot.mobility)
    roll = robot.velocity_names.index("roll_dot")
    nu[roll] = 0.0  # a roll velocity leaves the configuration where it is a velocity at all (see the module text)
    tau = 30.0 * rng.normal(size=len(robot.motors))
    d = robot.dynamics_derivatives(q, nu, tau)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RobotDynWarning)  # roll_dot's own column: a dropped row's warning
        ref = robot.forward_dynamics(q, nu, tau)
        dnu = _central(lambda v: robot.forward_dynamics(q, v, tau), nu)
    assert np.abs(d.nudot - ref).max() < 1e-9 * max(1.0, np.abs(ref).max())
    keep = [j for j in range(robot.mobility) if j != roll]
    assert np.abs(d.dnu[:, keep] - dnu[:, keep]).max() < 1e-6 * np.abs(dnu).max()
    z, zd = robot.coordinates.index("z"), robot.velocity_names.index("z_dot")
    if example == "sprung_car":  # uprights and wheels do not heave: the chassis alone, on four springs and dampers
        assert d.dnu[zd, zd] == pytest.approx(-4 * C / M_BODY, rel=1e-9)
        assert d.dq_manifold[zd, list(d.positions).index(z)] == pytest.approx(-4 * K / M_BODY, rel=1e-9)


def test_along_the_manifold_the_q_derivatives_are_finite_differences(car):
    """dq along the holonomic level set (the optimiser's finite differences, which skip the held roll) against
    the analytic set at a moving, braked state."""
    p = TrajectoryProblem(car, 1.0, NODES, car.neutral(), derivatives="finite-difference")
    x = np.concatenate([car.neutral(), [0.8, 0.05, -0.03, 0.0]])
    tau = np.array([-40.0, -40.0, 25.0, 25.0])
    Fx, _ = p._jac_node(x, tau)
    d = car.dynamics_derivatives(x[:car.nq], x[car.nq:], tau)
    cols = [c for c in d.positions if car.coordinates[c] != "roll"]
    analytic = np.vstack([d.dqdot_dq @ d.tangent, d.dq_manifold])[:, [list(d.positions).index(c) for c in cols]]
    assert np.abs(analytic - Fx[:, cols]).max() < 1e-6 * np.abs(analytic).max()


def test_roll_is_held_and_asking_it_to_move_is_one_line(car, analytic):
    p, _ = analytic
    assert p.held == ["roll", "roll_dot"] and "held=['roll', 'roll_dot']" in repr(p)
    for kwargs in ({"q_end": {"x": X_END, "roll": 0.01}}, {"bounds": {"roll_dot": (0.1, 0.2)}}):
        with pytest.raises(InputError) as err:
            TrajectoryProblem(car, 1.0, NODES, car.neutral(), **kwargs)
        assert "change rank along roll" in str(err.value) and "\n" not in str(err.value)


def test_analytic_and_finite_difference_reach_the_same_optimum(car, analytic):
    _, s = analytic
    fd = TrajectoryProblem(car, 1.0, NODES, car.neutral(), q_end={"x": X_END}, derivatives="finite-difference").solve()
    assert s.success and fd.success, (s.status, fd.status)
    assert abs(s.cost - fd.cost) <= 1e-6, (s.cost, fd.cost)
    assert np.allclose(s.tau, fd.tau, atol=1e-4)
    assert s.iterations < 50  # was 500 (the iteration limit) with the springs left out


def test_resimulation_keeps_the_constraints_and_reaches_the_target(car, analytic):
    """The optimal torques replayed by the integrator with the exact model: the wheels stay on the ground
    (holonomic residual), the car level in roll, and the end within 1 cm and 5 mm/s of the collocation's rest at
    0.1 m (measured: 5 mm and 1 mm/s at 5 nodes)."""
    _, s = analytic
    assert s.max_defect < 1e-8 and np.all(s.q[:, car.coordinates.index("roll")] == 0.0)
    tr = simulate(car, s.t[-1], s.q[0], s.nu[0], s.profile(), n_out=21, progress=False)
    assert max(np.abs(car.constraint_residual(q)).max() for q in tr.q) < 1e-6
    assert np.abs(tr.q[:, car.coordinates.index("roll")]).max() < 1e-9
    assert abs(tr.q[-1, 0] - X_END) < 1e-2 and np.abs(tr.nu[-1]).max() < 5e-3
