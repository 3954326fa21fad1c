"""The lean sampling pass of a compiled run (Evaluator.sample, robotdyn/_compiled.cpp): after a run that kept its row
choice, each sample's energy and holonomic residual come from a configuration pass without the gravity torques, the
motors' columns and the projection's condition and span checks. Its numbers are observe's (the whole configuration
pass) bit for bit: the same CRBA, rows, LU factors and solves. Checked at states along runs of robots whose
independent velocities are a selection of v (Quasimoro, the linkage rover with its loop closures, MMR12-EOD) and
operational (the omni platform with its caster), and on the energy and residual columns of compiled trajectories."""

from __future__ import annotations

import numpy as np
import pytest

import robotdyn
from robotdyn.fast import dispatch
from robotdyn.fast.dispatch import compiled_model
from robotdyn.simulation.engine import simulate


def _run(name: str, t_end: float, n_out: int):
    """A short compiled run of ``name`` from its neutral posture with small independent velocities and no torque."""
    robot = robotdyn.load(name)
    q0 = robot.neutral()
    nu0 = 0.1 * np.random.default_rng(2).normal(size=robot.mobility)
    traj = simulate(robot, t_end, q0, nu0, None, n_out=n_out, progress=False, engine="compiled")
    return robot, traj


@pytest.mark.parametrize("name", ["quasimoro", "linkage_suspension", "mmr12_eod", "omni_caster"])
def test_sample_is_observe_bit_for_bit(name):
    if not dispatch.enabled():
        pytest.skip("the compiled fast path is off")
    robot, traj = _run(name, 0.2, 5)
    assert traj.stats["engine"].startswith("compiled")
    ev = compiled_model(robot).ev
    for q, nu, energy, residual in zip(traj.q, traj.nu, traj.energy, traj.residual):
        y = np.concatenate([q, nu])
        lean, full = ev.sample(y), ev.observe(y)
        assert lean == full  # (energy [J], residual [m or rad]): the same bits
        assert (energy, residual) == full  # the trajectory's columns: the lean pass (the run kept its rows)
    assert np.ptp(traj.energy) > 0.0 or name == "mmr12_eod"  # the states differ (not one state checked 5 times)


def test_sample_energy_is_pinocchio_mechanical_energy():
    """An independent reference: Pinocchio's kinetic + potential energy at v = S nu (Robot.energy), to rounding."""
    if not dispatch.enabled():
        pytest.skip("the compiled fast path is off")
    robot, traj = _run("linkage_suspension", 0.2, 3)
    ev = compiled_model(robot).ev
    for q, nu in zip(traj.q, traj.nu):
        energy, residual = ev.sample(np.concatenate([q, nu]))
        v = robot.velocity(q, nu)
        assert energy == pytest.approx(robot.energy(q, v), rel=1e-12, abs=1e-12)
        rows = robot.rows_at(q)
        assert residual == pytest.approx(np.max(np.abs(rows.residual[rows.holonomic])), rel=1e-9, abs=1e-15)


def test_sample_refuses_a_state_of_the_wrong_length():
    if not dispatch.enabled():
        pytest.skip("the compiled fast path is off")
    robot = robotdyn.load("quasimoro")
    fast = compiled_model(robot)
    fast.compute(robot.neutral(), np.zeros(robot.mobility))
    with pytest.raises(ValueError, match="wrong length"):
        fast.ev.sample(np.zeros(robot.nq))
