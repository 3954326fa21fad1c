"""Exact stick-slip switching (robotdyn.simulation.stick_slip) against the closed forms of a disc: launched sliding on flat
ground it sticks at t* = v0 k / (mu g (1 + k)) with v* = v0 / (1 + k) and loses m v0^2 k / (2 (1 + k)) (for a solid
disc k = 1/2: t* = v0 / (3 mu g), v* = 2 v0 / 3, m v0^2 / 6); on an incline it rolls iff
tan(alpha) <= mu (1 + k) / k (3 mu for a solid disc), else it slides at g (sin a - mu cos a) along the slope."""

from __future__ import annotations

import numpy as np
import pytest

from robotdyn.simulation.engine import simulate

from test_sliding import G, K, M, disc


def _launch(mu=0.3, v0=2.0, t_end=0.3):
    robot, q0 = disc(0.0, friction="stick_slip", mu=mu)
    v = np.zeros(robot.nq)
    v[robot.coordinate_index("x")] = v0
    from robotdyn.simulation.stick_slip import simulate as hybrid

    return robot, hybrid(robot, t_end, q0, v, n_out=31, progress=False)


@pytest.mark.parametrize("mu, v0", [(0.3, 2.0), (0.8, 1.0)])
def test_launched_disc_sticks_exactly(mu, v0):
    robot, traj = _launch(mu, v0)
    t_star = v0 * K / (mu * G * (1 + K))
    [switch] = traj.stats["switches"]
    assert switch["phase"] == "stick" and switch["wheel"] == "disc"
    # the event is located on the integrator's dense output: its error (~1e-8 s) times the slip deceleration is the
    # interpolant's error in s, about rtol * v0
    assert switch["t"] == pytest.approx(t_star, rel=1e-7)
    assert traj.column("x_dot")[-1] == pytest.approx(v0 / (1 + K), rel=1e-9)
    assert traj.column("spin_dot")[-1] * 0.3 == pytest.approx(v0 / (1 + K), rel=1e-9)  # rolling: R spin = v
    loss = M * v0**2 * K / (2 * (1 + K))
    assert traj.energy[0] - traj.energy[-1] == pytest.approx(loss, rel=1e-9)
    np.testing.assert_allclose(traj.energy - traj.energy[0], traj.friction_work, atol=1e-9 * loss)
    # before t*: Coulomb's constant deceleration mu g (no regularisation)
    early = traj.t < t_star
    np.testing.assert_allclose(traj.column("x_dot")[early], v0 - mu * G * traj.t[early], rtol=1e-9)


@pytest.mark.parametrize("slope", [0.5, 1.0])
def test_disc_on_incline_rolls_iff_cone_allows(slope):
    alpha = np.arctan(slope)
    mu_c = np.tan(alpha) * K / (1 + K)
    for mu, expect in [(1.01 * mu_c, "roll"), (0.99 * mu_c, "slide")]:
        robot, q0 = disc(slope, independent=None, friction="stick_slip", mu=mu)  # rolling at first: mobility 3
        traj = simulate(robot, 0.4, q0, np.zeros(robot.mobility), n_out=9, progress=False)
        along = G * np.sin(alpha) / (1 + K) if expect == "roll" else G * (np.sin(alpha) - mu * np.cos(alpha))
        x_expected = -0.5 * along * np.cos(alpha) * traj.t**2  # down the slope: -x
        np.testing.assert_allclose(traj.column("x"), x_expected, atol=1e-9)
        switches = traj.stats["switches"]
        assert switches == ([] if expect == "roll" else [{"t": 0.0, "wheel": "disc", "phase": "slide"}])


def test_stick_slip_needs_mu_and_no_regularisation():
    """friction = "stick_slip" is accepted with mu and refused without it, or with a regularisation, in one line."""
    from robotdyn.errors import InputError

    with pytest.raises(InputError, match="stick_slip law needs mu"):
        disc(0.0, friction="stick_slip")
    with pytest.raises(InputError, match="no slip_velocity"):
        disc(0.0, friction="stick_slip", mu=0.3, slip_velocity=1e-3)
