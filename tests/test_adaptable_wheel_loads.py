"""Wheel loads of the adaptable-wheel tricycle against sec 5 of Mardani & Ebrahimi 2016.

Sec 5 assumes that on flat ground "the contact forces exerted to each wheel are equal to the one-third of the robot
weight" and builds eq 35 on it. The independent reference here is the lever rule of a rigid body on three point
supports (derived in the test from eq 8's wheel positions), and, on the ramp of mission 2, the equilibrium of the
whole robot with gravity plus the paper's own statics of eqs 25-30 (a different solver:
:func:`robotdyn.contact.statics.solve_contact_forces`). robotdyn's loads come from ``Robot.contact_forces``.
"""

from __future__ import annotations

import numpy as np
import pytest

from robotdyn.robots.adaptable_wheel import comparison as aw_cmp
from robotdyn.robots.adaptable_wheel import paper as aw_paper

WHEELS = ("fr", "fl", "r")


@pytest.mark.parametrize("reading", ["half", "full"])
def test_flat_loads_are_the_lever_rule_not_a_third(reading):
    """Three supports at eq 8's (Lx, -Ly), (Lx, Ly), (-Lx, 0) under a CG at the body origin (all mass lumped there,
    m_wheel = 0). Vertical balance N_fr + N_fl + N_r = m g; pitch balance about the CG Lx (N_fr + N_fl) - Lx N_r = 0;
    roll balance Ly (N_fl - N_fr) = 0. So N_r = m g / 2 and N_fr = N_fl = m g / 4 for any Lx, Ly; sec 5's m g / 3
    is 25 % high on the front wheels and 33 % low on the rear one."""
    robot, q, tau, forces = aw_cmp.hold_loads("flat", "slip", {"L_reading": reading})
    p = robot.params
    mg = p["m"] * p["g"]
    off = aw_paper.offsets(p)
    # the lever rule from the three supports' positions (solve the three balance equations as written above)
    Amat = np.array([[1.0, 1.0, 1.0], [off[t][0] for t in WHEELS], [off[t][1] for t in WHEELS]])
    lever = np.linalg.solve(Amat, [mg, 0.0, 0.0])
    np.testing.assert_allclose(lever, [mg / 4, mg / 4, mg / 2], rtol=1e-14)
    normal = np.array([forces.wheel(t).normal for t in WHEELS])
    np.testing.assert_allclose(normal, lever, atol=1e-9)
    assert all(forces.wheel(t).source == "rigid" and forces.wheel(t).tangential < 1e-9 for t in WHEELS)
    # the contact points lie under the wheel centres at eq 8's offsets (the lever arms used above)
    base = q[[robot.coordinate_index("x"), robot.coordinate_index("y")]]
    for t in WHEELS:
        np.testing.assert_allclose(forces.wheel(t).point[:2] - base, off[t][:2], atol=1e-9)
    share = aw_paper.paper_flat_loads(p)
    np.testing.assert_allclose(normal / share, [0.75, 0.75, 1.5], rtol=1e-9)


def test_flat_holding_torques_are_virtual_work_with_the_lever_loads():
    """Eq 32 with the lever-rule loads: t_i = N_i dR/dq_i, dR/dq from eq 1 by central differences (not eq 33's
    transcription); eq 35 is the same with m g / 3, so robotdyn's torque / eq 35 = 3 N_i / (m g)."""
    robot, q, tau, _ = aw_cmp.hold_loads("flat", "slip")
    p = robot.params
    mg = p["m"] * p["g"]
    angles = np.array([q[robot.coordinate_index(f"q_{t}")] for t in WHEELS])
    h = 1e-6
    dR = (aw_paper.radius_law(angles + h, p["w"]) - aw_paper.radius_law(angles - h, p["w"])) / (2 * h)
    lever = np.array([mg / 4, mg / 4, mg / 2])
    np.testing.assert_allclose(tau[3:], lever * dR, rtol=1e-7)
    np.testing.assert_allclose(tau[:3], 0.0, atol=1e-9)  # no wheel-spin torque at rest
    np.testing.assert_allclose(tau[3:] / aw_paper.paper_torque_eq35(angles, p), [0.75, 0.75, 1.5], rtol=1e-9)


def test_ramp_loads_balance_gravity_and_equal_the_papers_statics():
    """Mission 2's ramp (slope 0.2), body level: the contact normals are all the plane's, so the normal loads sum
    to m g / sqrt(1 + 0.2^2) and the world contact forces to (0, 0, m g). The normal loads equal those of the
    paper's eqs 25-30 solved by least friction at the same configuration (rigid-body statics fix them whatever
    the friction split); the friction the least-squares holding torques need is not the least friction."""
    robot, q, tau, forces = aw_cmp.hold_loads("ramp", "rolling")
    p = robot.params
    mg = p["m"] * p["g"]
    normal = np.array([forces.wheel(t).normal for t in WHEELS])
    assert normal.sum() == pytest.approx(mg / np.sqrt(1 + 0.2 ** 2), rel=1e-12)
    np.testing.assert_allclose(np.sum([w.world for w in forces.wheels], axis=0), [0, 0, mg], atol=1e-9)
    cmd = aw_paper.Commands(0.0, 0.0, 0.15)
    x, _, _ = aw_paper.solve_ik(cmd, p, robot.terrain)
    st = aw_paper.static_torques(cmd, x, p, robot.terrain)
    np.testing.assert_allclose(normal, st.normal, atol=1e-8)
    assert st.ratio.max() < 0.25 < p["mu"]  # least friction: within Table 1's mu_s = 1
    assert forces.minimum_mu() > 4.0  # least-squares torques squeeze the front wheels sideways


def test_compare_rows_of_sec5():
    cmp = aw_cmp.loads_comparison()
    rows = {r.quantity: r for r in cmp.rows}
    r = rows["sec 5: load r, flat ground (m g / 3) [N]"]
    assert r.paper == pytest.approx(98.1 / 3, rel=1e-12) and r.model == pytest.approx(98.1 / 2, rel=1e-9)
    assert all(row.verdict == "differs" for row in cmp.rows)
