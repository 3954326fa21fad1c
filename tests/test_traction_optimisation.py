"""Traction-limited trajectory optimisation (issue 26, item 3): wheel loads and friction cones as path constraints,
the peak required mu as a cost, robots with holonomic rows; the adaptable-wheel tricycle's radius schedule.

References: the contact rows' forces are those of :meth:`robotdyn.robot.Robot.contact_forces` (every path the rows
take: compiled, the coupled sliding solve, the reference); their Jacobian from
:meth:`~robotdyn.robot.Robot.contact_force_derivatives` equals central differences; the optimum with analytic
derivatives equals the one with finite differences to 1e-6 in cost; the holonomic residuals vanish at every node;
a re-simulation of the optimal torques with the exact model keeps the loads and the required mu within the
collocation's discretisation error of the bounds and the optimum.

The radius schedule's two optima (``tests/data/radius_schedule.npz``: ``fixed_*`` and ``scheduled_*`` ``q``, ``nu``,
``tau`` and ``cost`` of ``radius_schedule.compare(derivatives="finite-difference")``, 5 nodes) are the ones the
notebook ``adaptable_wheel_radius_schedule.ipynb`` solves (measured: 15-35 s per solve, too long to solve again here);
this file re-evaluates them on the current model (zero defects and loop residuals, every bound and contact row held,
the stored cost recomputed) before asserting about them, and solves the fixed-radius problem with analytic
derivatives from the default guess to the stored finite-difference optimum: solve again and ``np.savez`` them where
a change of the model moves the optimum.
"""

from __future__ import annotations

import pathlib
import warnings

import numpy as np
import pytest

pytest.importorskip("casadi")

import robotdyn  # noqa: E402
from robotdyn.errors import InputError  # noqa: E402
from robotdyn.optimisation import TrajectoryProblem  # noqa: E402
from robotdyn.optimisation.trajectory import TrajectorySolution  # noqa: E402
from robotdyn.optimisation.contact_limits import ContactLimits, required_mu  # noqa: E402
from robotdyn.robots.adaptable_wheel import radius_schedule as rs  # noqa: E402

NODES = 5  # the example's 7 in the notebook; 5 keeps the analytic solve to seconds
CACHE = np.load(pathlib.Path(__file__).parent / "data" / "radius_schedule.npz")


@pytest.fixture(scope="module")
def tricycle():
    return rs.start()


def _stored(tag: str, robot) -> TrajectorySolution:
    """The stored optimum ``tag`` (``fixed`` or ``scheduled``) on the current model, after checking that it is a
    feasible point of its problem there with its stored cost: the forces, the effort and the defects computed now."""
    p = rs.radius_schedule(fixed=tag == "fixed", nodes=NODES, derivatives="finite-difference", robot=robot)
    q, nu, tau = (CACHE[f"{tag}_{a}"] for a in ("q", "nu", "tau"))
    assert q.shape[0] == NODES
    forces = np.array([p.limits.forces(*node) for node in zip(q, nu, tau)])
    peak2 = float(np.max(required_mu(forces))) ** 2  # the peak variable at a min-max optimum
    z = np.concatenate([np.hstack([q, nu]).ravel(), tau.ravel(), [peak2]])
    g = p.constraints(z)
    nd = (NODES - 1) * (len(p.keep) + p.mh)
    lo, hi = p.limits.bounds()
    rows = g[nd:].reshape(NODES, -1)
    assert np.all(rows >= lo - 1e-7) and np.all(rows <= hi + 1e-7)  # loads, cones and peak rows
    X = np.hstack([q, nu])
    assert np.all(X >= p.x_lo - 1e-9) and np.all(X <= p.x_hi + 1e-9)  # path box, radii (held or in range)
    assert np.all(tau >= p.tau_lo) and np.all(tau <= p.tau_hi)
    h = rs.T_END / (NODES - 1)
    w = np.full(NODES, h)
    w[[0, -1]] = 0.5 * h
    effort = float(np.sum(w[:, None] * tau ** 2))
    cost = peak2 + rs.EFFORT_WEIGHT * effort + rs.RATE_WEIGHT / h * float(np.sum(np.diff(tau, axis=0) ** 2))
    assert np.isclose(cost, float(CACHE[f"{tag}_cost"]), rtol=1e-6), (cost, float(CACHE[f"{tag}_cost"]))
    return TrajectorySolution(np.linspace(0.0, rs.T_END, NODES), q, nu, tau, cost, "stored", True, 0, 0.0, 0, 0,
                              float(np.max(np.abs(g[:nd]))), "finite-difference", forces=forces,
                              effort=effort, cost_kind="peak-mu")


@pytest.fixture(scope="module")
def fixed_fd(tricycle):
    return _stored("fixed", tricycle[0])


def _moving_state(robot, q0, rng):
    nu = 0.3 * rng.standard_normal(robot.mobility)
    tau = rng.standard_normal(len(robot.motors))
    return q0, nu, tau


def test_contact_rows_take_the_reference_forces_on_every_path(tricycle):
    """The compiled path (the tricycle) and the coupled sliding solve (the skid steer) give
    :meth:`Robot.contact_forces`' numbers."""
    rng = np.random.default_rng(3)
    robot, q0, _ = tricycle
    limits = ContactLimits(robot, q0, min_load=1.0)
    assert limits._compiled is not None
    q, nu, tau = _moving_state(robot, q0, rng)
    reference = np.array([w.force for w in robot.contact_forces(q, nu, tau=tau).wheels])
    assert np.allclose(limits.forces(q, nu, tau), reference, rtol=1e-9, atol=1e-9)
    skid = robotdyn.load_robot("examples/skid_steer.toml")
    limits = ContactLimits(skid, skid.neutral(), mu_max=0.5)
    assert limits._coupled
    q, nu, tau = _moving_state(skid, skid.neutral(), rng)
    reference = np.array([w.force for w in skid.contact_forces(q, nu, tau=tau).wheels])
    assert np.allclose(limits.forces(q, nu, tau), reference, rtol=1e-9, atol=1e-9)
    assert np.allclose(required_mu(reference), skid.contact_force_derivatives(q, nu, tau).required_mu, rtol=1e-9)


def test_contact_rows_jacobian_analytic_equals_central_differences(tricycle):
    """Loads, cones and peak rows: Jacobian from Robot.contact_force_derivatives against central differences of
    the forces (step ~6e-6: truncation ~1e-10 relative)."""
    rng = np.random.default_rng(4)
    robot, q0, holding = tricycle
    nu = 0.2 * rng.standard_normal(robot.mobility)
    tau = holding + 0.3 * rng.standard_normal(len(robot.motors))
    out = []
    for d in ("analytic", "finite-difference"):
        limits = ContactLimits(robot, q0, min_load=1.0, mu_max=0.5, peak=True, derivatives=d)
        out.append(limits.jacobian(q0, nu, tau, 0.01))
    for a, b in zip(*out):
        assert np.allclose(a, b, rtol=1e-6, atol=1e-7 * np.abs(b).max()), np.abs(a - b).max()


def test_radius_schedule_same_optimum_with_analytic_and_finite_difference_derivatives(tricycle, fixed_fd):
    """The fixed-radius problem (the comparison) solved with both Jacobians: the same cost to 1e-6, the same peak mu."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        an = rs.radius_schedule(fixed=True, nodes=NODES, derivatives="analytic", robot=tricycle[0]).solve()
    assert an.success and fixed_fd.success, (an.status, fixed_fd.status)
    assert abs(an.cost - fixed_fd.cost) <= 1e-6
    assert abs(rs.peak_mu(an) - rs.peak_mu(fixed_fd)) <= 1e-5
    assert an.force_calls > 0 and an.derivative_calls > 0


def test_nodes_on_the_manifold_and_within_the_bounds(tricycle, fixed_fd):
    robot, q0, _ = tricycle
    s = fixed_fd
    assert s.max_defect < 1e-8
    assert max(np.max(np.abs(robot.constraint_residual(q))) for q in s.q) < 1e-9
    assert np.min(s.forces[..., 2]) >= rs.MIN_LOAD - 1e-7
    for tag in rs.WHEELS:  # the radii held
        i = robot.coordinate_index(f"q_{tag}")
        assert np.allclose(s.q[:, i], q0[i], atol=1e-9)
    peak = rs.peak_mu(s)
    assert np.sum(s.required_mu > peak - 1e-6) >= 2  # a min-max: the peak is reached more than once
    # at the first node (at rest, contact normals parallel to 1e-3 deg) the three wheels share the whole robot's ratio
    # of tangential to normal ground force: the least peak any share of the total force allows
    cf = robot.contact_forces(s.q[0], s.nu[0], tau=s.tau[0])
    total = np.sum([w.world for w in cf.wheels], axis=0)
    n = np.mean([w.frame[:, 2] for w in cf.wheels], axis=0)
    n /= np.linalg.norm(n)
    ratio = np.linalg.norm(total - (total @ n) * n) / (total @ n)
    assert np.allclose(s.required_mu[0], ratio, rtol=1e-4)


def test_schedule_costs_at_most_the_fixed_radii(tricycle, fixed_fd):
    """Started from the fixed-radius optimum (a feasible point of it), the schedule's optimum (stored, re-checked on
    the current model) costs at most the fixed one's; its peak required mu is the fixed one's within the
    discretisation error (the peak is the whole robot's ratio of tangential to normal ground force, which the radii
    do not change) and its effort lower."""
    s = _stored("scheduled", tricycle[0])
    assert s.max_defect < 1e-8
    assert s.cost <= fixed_fd.cost + 1e-9
    assert abs(rs.peak_mu(s) - rs.peak_mu(fixed_fd)) <= 0.01 * rs.peak_mu(fixed_fd)
    assert s.effort < 0.9 * fixed_fd.effort
    assert np.min(s.forces[..., 2]) >= rs.MIN_LOAD - 1e-7


def test_bad_input_is_one_line():
    robot = robotdyn.load("quasimoro")
    with pytest.raises(InputError, match="cost"):
        TrajectoryProblem(robot, 3.0, 5, [0] * 6, cost="mu")
    with pytest.raises(InputError, match="mu_max"):
        TrajectoryProblem(robot, 3.0, 5, [0] * 6, mu_max=-0.1)
    with pytest.raises(InputError, match="min_load"):
        TrajectoryProblem(robot, 3.0, 5, [0] * 6, min_load=float("nan"))
    with pytest.raises(InputError, match="force_derivatives"):
        TrajectoryProblem(robot, 3.0, 5, [0] * 6, mu_max=0.5, force_derivatives="exact")
    with pytest.raises(InputError, match="joint range"):
        rs.radius_schedule(fixed=False, q_range=(-1.0, -0.5), nodes=3)
    with pytest.raises(InputError, match="lateral = slip"):
        rs.start(robotdyn.load("adaptable_wheel"))


def test_replay_with_the_exact_model_keeps_the_constraints(tricycle, fixed_fd):
    """The optimal torques re-simulated with the exact model (the adjustment motors also tracking the schedule:
    the massless mechanism has no stiffness of its own): every wheel stays loaded above the bound, the required mu
    stays within the collocation's discretisation error of the optimum's peak, the robot arrives near its goal."""
    robot = tricycle[0]
    traj, forces, mu, tau = rs.replay(fixed_fd, robot)
    assert np.min(forces[..., 2]) >= rs.MIN_LOAD
    assert np.max(mu) <= rs.peak_mu(fixed_fd) * 1.05, (np.max(mu), rs.peak_mu(fixed_fd))
    ix = [robot.coordinate_index(c) for c in ("x", "y", "yaw")]
    assert np.max(np.abs(traj.q[-1, ix] - fixed_fd.q[-1, ix])) < 0.05


def test_cli_solves_the_apis_problem_with_traction_limits(tricycle, capsys):
    """One story: ``robotdyn optimise --min-load --cost peak-mu`` (fixed radii through --bound) solves the API's
    problem: the same cost, loads above the bound, the printed peak mu the nodes' largest."""
    import json

    from robotdyn.cli import main

    robot, q0, _ = tricycle
    e = rs.DISTANCE / np.sqrt(2.0)
    bounds = {"x": (-0.03, e + 0.02), "y": (-0.03, e + 0.02), "yaw": (rs.HEADING - 0.02, rs.HEADING + 0.02)}
    for tag in rs.WHEELS:
        v = q0[robot.coordinate_index(f"q_{tag}")]
        bounds[f"q_{tag}"] = (v, v)
    end = {"x": e, "y": e, "yaw": rs.HEADING}
    argv = ["optimise", "adaptable_wheel", "--param", "lateral=slip", "--q0", *[repr(float(v)) for v in q0],
            "--t-end", "3", "--nodes", "4", "--min-load", "5", "--cost", "peak-mu", "--derivatives",
            "finite-difference", "--json"]
    argv += [a for k, v in end.items() for a in ("--end", f"{k}={float(v)!r}")]
    argv += [a for k, (lo, hi) in bounds.items() for a in ("--bound", f"{k}={float(lo)!r}:{float(hi)!r}")]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        api = TrajectoryProblem(robot, 3.0, 4, q0, q_end=end, bounds=bounds, min_load=5.0, cost="peak-mu",
                                derivatives="finite-difference").solve()
    assert out["success"] and abs(out["cost"] - api.cost) <= 1e-9
    assert np.min(np.array(out["forces"])[..., 2]) >= 5.0 - 1e-7
    assert abs(np.max(out["required_mu"]) - rs.peak_mu(api)) <= 1e-9


@pytest.mark.parametrize("extra, needle", [(["--mu-max", "-0.1"], "--mu-max"), (["--min-load", "nan"], "--min-load"),
                                           (["--cost", "mu"], "--cost")])
def test_cli_traction_options_bad_input_one_line_exit_2(extra, needle, capsys):
    from robotdyn.cli import main

    argv = ["optimise", "quasimoro", "--t-end", "3", "--nodes", "5", "--end", "x=1", *extra]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0], err
