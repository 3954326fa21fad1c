"""The per-sample traction pass made cheaper (issue 23 item 4; robotdyn.contact.traction_memo and
robotdyn.contact.traction_minimum), against closed forms and against the pass without them.

- Minimum mu of two wheels on one axle whose lateral forces are split open (f1 = s1 + z, f2 = s2 - z, loads n1, n2,
  no longitudinal force): max(abs(f1)/n1, abs(f2)/n2) is smallest where both ratios are equal, so
  mu_min = abs(s1 + s2) / (n1 + n2). With longitudinal forces too the batch (exact: the candidates where one ratio
  is least or two are equal) equals a ternary search on the convex ratio to 1e-12, and is at most the reference's
  bounded Brent search (contact_forces.cone_minimum), within 1e-8 of it (measured 2.3e-9 below it).
- The memories (a compliant wheel's contact state, the reduced model) reuse a value only at the same arguments bit
  for bit: the pass gives the same arrays, exactly, as without them (a stick-slip disc launched sliding, the
  rolling compliant disc under a torque whose required mu is m r tau / ((I + m r^2) m g), tests/test_compliant_rolling.py),
  each saves one evaluation per sample, and the robot is left as it was.
"""

from __future__ import annotations

import contextlib

import numpy as np
import pytest

import robotdyn.contact.traction as T
from robotdyn.contact.contact_forces import cone_minimum, constraint_forces
from robotdyn.contact.traction_memo import once_per_sample
from robotdyn.contact.traction_minimum import ConeProblem, minimum_mu_many
from robotdyn.errors import InputError
from robotdyn.robot import MotorSpec
from robotdyn.simulation.engine import simulate
from robotdyn.simulation.stick_slip import simulate as hybrid
from robotdyn.simulation.torque_profile import Constant


def _axle(s1, s2, n1, n2, a1=0.0, a2=0.0) -> ConeProblem:
    """Two wheels whose lateral forces s1 + z, s2 - z are split open (longitudinal a1, a2), loads n1, n2 [N]."""
    return ConeProblem(np.array([n1, n2], float), np.array([[a1, s1], [a2, s2]], float),
                       np.array([[[0.0], [1.0]], [[0.0], [-1.0]]]))


def _ternary(p: ConeProblem) -> float:
    """min over z of the convex max_i norm(b_i + T_i z) / fn_i (d = 1) by ternary search to machine precision."""
    phi = lambda z: max(np.linalg.norm(p.b[i] + p.T[i, :, 0] * z) / p.fn[i] for i in range(len(p.fn)))  # noqa: E731
    lo, hi = -1e3, 1e3
    for _ in range(200):
        a, b = lo + (hi - lo) / 3, hi - (hi - lo) / 3
        lo, hi = (lo, b) if phi(a) <= phi(b) else (a, hi)
    return phi(0.5 * (lo + hi))


def test_minimum_mu_of_an_axle_split_is_the_closed_form_and_the_reference():
    cases = [(3.0, 5.0, 100.0, 40.0), (-7.0, 2.0, 30.0, 90.0), (0.0, 0.0, 10.0, 10.0), (12.0, -12.0, 5.0, 50.0)]
    values = minimum_mu_many([_axle(*c) for c in cases] + [None, 0.0, float("inf")])
    for (s1, s2, n1, n2), value in zip(cases, values):
        assert value == pytest.approx(abs(s1 + s2) / (n1 + n2), rel=1e-12, abs=1e-15)
    assert values[-3:] == [None, 0.0, float("inf")]  # (no search needed: passed through)
    with_longitudinal = [_axle(3.0, 5.0, 100.0, 40.0, a1=4.0, a2=-1.0), _axle(-2.0, 9.0, 60.0, 20.0, a1=10.0)]
    for p, value in zip(with_longitudinal, minimum_mu_many(with_longitudinal)):
        assert value == pytest.approx(_ternary(p), rel=1e-12)
        reference = cone_minimum([(p.b[i], p.T[i]) for i in range(2)], p.fn, 1)  # (a bounded Brent search)
        assert reference * (1 - 1e-8) <= value <= reference * (1 + 1e-15)
        assert value > abs(p.b[:, 1].sum()) / p.fn.sum()  # the longitudinal forces add to the need
    rng = np.random.default_rng(3)  # two open directions moving the forces in two ways: the reference's solver
    p = ConeProblem(np.array([50.0, 80.0, 65.0]), rng.normal(size=(3, 2)) * 5, rng.normal(size=(3, 2, 2)))
    assert minimum_mu_many([p])[0] == cone_minimum([(p.b[i], p.T[i]) for i in range(3)], p.fn, 2)


def _without_memo(monkeypatch):
    monkeypatch.setattr(T, "once_per_sample", lambda robot: contextlib.nullcontext(lambda: None))


def test_stick_slip_pass_is_unchanged_and_evaluates_the_reduced_model_once(monkeypatch):
    from test_sliding import disc

    robot, q0 = disc(0.0, friction="stick_slip", mu=0.3)
    v = np.zeros(robot.nq)
    v[robot.coordinate_index("x")] = 2.0
    traj = hybrid(robot, 0.3, q0, v, n_out=31, progress=False)
    fast = T.traction(robot, traj)
    assert fast.phases[:, 0].any() and not fast.phases[:, 0].all()  # sliding, then rolling
    assert "reduced" not in robot.__dict__  # (left as it was)
    with monkeypatch.context() as m:
        _without_memo(m)
        plain = T.traction(robot, traj)
    for name in ("normal", "tangential", "required_mu", "phases"):
        np.testing.assert_array_equal(getattr(fast, name), getattr(plain, name))
    assert fast.summary() == plain.summary()
    with once_per_sample(robot) as next_sample:  # one sliding state: constraint_forces and the sliding forward
        from robotdyn.contact.stick_slip_traction import phase_states, phases_of

        with phase_states(robot, traj, phases_of(traj)) as state:
            nu = state(0)
            next_sample()
            constraint_forces(robot, traj.q[0], nu)
        assert next_sample.memos[-1].hits == 1
        with pytest.raises(InputError):  # the reference's own error through the memory
            robot.reduced(traj.q[0][:2], nu)
    assert "reduced" not in robot.__dict__


def test_rolling_compliant_pass_is_unchanged_and_evaluates_each_wheel_once(monkeypatch):
    from test_compliant_rolling import I, M, R, disc, state

    k, g, tau = 2.0e4, 9.81, 0.5
    robot = disc(g=g, motors=[MotorSpec("m", "spin")], normal_stiffness=k, normal_damping=2 * 0.3 * np.sqrt(k * M),
                 mu=0.5)
    q0, nu0 = state(robot, R - M * g / k, vx=1.0, w=1.0 / R)
    traj = simulate(robot, 0.05, q0, nu0, Constant([tau]), n_out=6, rtol=1e-10, atol=1e-13, progress=False)
    tr = T.traction(robot, traj, Constant([tau]))
    np.testing.assert_allclose(tr.required_mu[:, 0], M * R * tau / ((I + M * R**2) * M * g), rtol=1e-8)
    with monkeypatch.context() as m:
        _without_memo(m)
        plain = T.traction(robot, traj, Constant([tau]))
    for name in ("normal", "tangential", "required_mu"):
        np.testing.assert_array_equal(getattr(tr, name), getattr(plain, name))
    wheel = robot.constraints[-1]
    assert "state" not in wheel.__dict__ and "reduced" not in robot.__dict__
    with once_per_sample(robot) as next_sample:
        next_sample()
        constraint_forces(robot, traj.q[0], traj.nu[0], tau=[tau])
        assert [memo.hits for memo in next_sample.memos[:-1]] == [1]  # the forward dynamics' state, reused
    assert "state" not in wheel.__dict__


def test_pass_report_prints_progress_and_which_pass_took_the_time(capsys):
    quiet = T.PassReport(3, False, interval=0.0)
    quiet(0)
    quiet.done("reference")
    assert capsys.readouterr().err == ""
    report = T.PassReport(3, True, interval=0.0)
    report.why = "compliant wheels are evaluated on the Python path"
    report(1)
    report.done("reference")
    lines = capsys.readouterr().err.splitlines()
    assert lines[0] == "traction: sample 1 / 3 (33%), per-sample reference pass"
    assert lines[1].startswith("traction: 3 samples in ") and lines[1].endswith(
        " s by the reference pass (compliant wheels are evaluated on the Python path)")


def test_memories_serve_only_their_own_pass_and_thread():
    import threading

    from test_compliant_rolling import R, disc, state

    robot = disc(g=9.81)
    q0, nu = state(robot, R, vx=1.0, w=1.0 / R)
    with once_per_sample(robot) as outer:
        with once_per_sample(robot) as inner:
            assert inner.memos == []  # a pass inside another leaves the other's memory alone ...
        assert robot.__dict__["reduced"] is outer.memos[-1]  # ... and its exit does not remove it
        assert robot.constraints[-1].__dict__["state"] is outer.memos[0]
        outer()
        first = robot.reduced(q0, nu)
        assert robot.reduced(q0, nu) is first and outer.memos[-1].hits == 1
        other = []
        thread = threading.Thread(target=lambda: other.append(robot.reduced(q0, nu)))
        thread.start()
        thread.join()
        assert other[0] is not first and outer.memos[-1].hits == 1  # another thread's call: computed, not shared
        np.testing.assert_array_equal(other[0].M, first.M)
        outer()
        assert robot.reduced(q0, nu) is not first  # forgotten at the next sample
    assert "reduced" not in robot.__dict__


def test_a_robot_pickled_during_a_pass_carries_no_memory():
    import copy
    import pickle

    from robotdyn.constraints.constraint import KinematicState
    from test_compliant_rolling import R, disc, state

    robot = disc(g=9.81)
    q0, nu = state(robot, R, vx=1.0, w=1.0 / R)
    with once_per_sample(robot) as next_sample:
        next_sample()
        first = robot.reduced(q0, nu)  # (the memory now holds a reduced model, which does not pickle)
        robot.constraints[-1].state(KinematicState(robot.model, robot.data, q0, robot.velocity(q0, nu)))
        for twin in (pickle.loads(pickle.dumps(robot)), copy.deepcopy(robot)):
            assert "reduced" not in twin.__dict__ and "state" not in twin.constraints[-1].__dict__
            np.testing.assert_array_equal(twin.reduced(q0, nu).M, first.M)  # (the method, not a stale memory)
        assert robot.__dict__["reduced"] is next_sample.memos[-1]  # (the pass's own robot keeps its memory)
