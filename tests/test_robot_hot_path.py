"""The API's hot path around the compiled calls (Robot.checked_state, the compiled model's cache in
robotdyn.fast.dispatch, robotdyn.fast.compiled_derivatives' wrapping): it refuses exactly what the one-by-one checks
refuse, returns the binding's numbers untouched, and never reads a compiled model or bounds that a change of the
robot made stale (gravity, a wheel radius, the terrain, the constraint list, joint limits)."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from test_dynamics_derivatives import admissible_state

import robotdyn
from robotdyn.constraints.posture import set_terrain
from robotdyn.constraints.terrain import BumpTerrain
from robotdyn.errors import InputError
from robotdyn.fast.compiled import available
from robotdyn.fast.dispatch import compiled_model, use_compiled
from robotdyn.inputs import MAX_FORCE, MAX_POSITION, MAX_VELOCITY, as_vector

compiled_only = pytest.mark.skipif(not available(), reason="compiled extension not built")
FIELDS = ("nudot", "dq", "dnu", "dtau", "qdot", "dqdot_dq", "S")


@pytest.fixture(scope="module")
def quasimoro():
    return robotdyn.load("quasimoro")


def _message(call) -> str | None:
    try:
        call()
    except InputError as exc:
        return str(exc)
    return None


def test_checked_state_refuses_what_the_three_checks_refuse(quasimoro):
    """At each bound the three checks draw (MAX_POSITION, MAX_VELOCITY, MAX_FORCE; the joint ranges: below), on it
    and one ulp beyond, NaN and inf in each vector, wrong lengths and other types:
    checked_state gives the checks' own message, or their arrays bit for bit (as copies)."""
    r = quasimoro
    q0, nu0, tau0 = r.neutral(), np.full(r.mobility, 0.3), np.full(len(r.motors), 0.1)
    cases = [(part, size - 1, value) for part, size, bound in (
        ("q", r.nq, MAX_POSITION), ("nu", r.mobility, MAX_VELOCITY), ("tau", len(r.motors), MAX_FORCE))
        for value in (bound, -bound, np.nextafter(bound, np.inf), -np.nextafter(bound, np.inf), np.nan, np.inf, -np.inf)]
    for part, i, value in cases:
        q, nu, tau = q0.copy(), nu0.copy(), tau0.copy()
        {"q": q, "nu": nu, "tau": tau}[part][i] = value
        want = _message(lambda: (r.check_q(q), r.check_nu(nu), r.check_tau(tau)))
        got = _message(lambda: r.checked_state(q, nu, tau))
        assert got == want, (part, value)
        if want is None:
            out = r.checked_state(q, nu, tau)
            for x, ref in zip(out, (q, nu, tau)):
                assert x.tobytes() == ref.tobytes() and not np.shares_memory(x, ref)
    refused = sum(_message(lambda: r.checked_state(*s)) is not None for s in (
        (q0[:-1], nu0, tau0), (q0, nu0[:-1], tau0), (q0, nu0, np.append(tau0, 1.0)),
        (q0.astype(np.float32), nu0, tau0), (list(q0), nu0, "1 x")))
    assert refused == 4  # the float32 q is accepted by check_q (converted), the others are not
    assert np.array_equal(r.checked_state(list(q0), nu0.astype(int), tuple(tau0))[1], nu0.astype(int))


def test_as_vector_fast_path_keeps_its_refusals():
    """The vectorised test of as_vector's common case refuses NaN and inf with any limit (an infinite one too)."""
    for limit in (None, 1e6, np.inf):
        for bad in (np.nan, np.inf, -np.inf):
            with pytest.raises(InputError, match="not finite"):
                as_vector(np.array([0.0, bad]), 2, "x", limit=limit)
    with pytest.raises(InputError, match="beyond"):
        as_vector(np.array([0.0, 2e6]), 2, "x", limit=1e6)
    x = np.array([1.0, -1e6])
    assert as_vector(x, 2, "x", limit=1e6).tobytes() == x.tobytes()


def test_checked_state_follows_joint_limits_changed_in_place():
    """The bounds are cached per robot; a joint range narrowed in place is seen at the next call (a stale cache
    would accept the configuration), with check_q's 1e-12 slack exactly: on it accepted, one ulp beyond refused."""
    r = robotdyn.load("quasimoro")
    q, nu, tau = r.neutral(), np.zeros(r.mobility), np.zeros(len(r.motors))
    r.checked_state(q, nu, tau)
    i = r.coordinates.index("theta3")
    q[i] = 0.2
    r.description.lower[i], r.description.upper[i] = -0.1, 0.1
    with pytest.raises(InputError, match=r"q\[theta3\] = 0.2 is outside its joint range"):
        r.checked_state(q, nu, tau)
    with pytest.raises(InputError, match=r"q\[theta3\] = 0.2 is outside its joint range"):
        r.dynamics_derivatives(q, nu, tau)
    for edge in (-0.1 - 1e-12, 0.1 + 1e-12):
        q[i] = edge
        assert r.checked_state(q, nu, tau)[0][i] == edge and r.check_q(q)[i] == edge
        q[i] = np.nextafter(edge, np.sign(edge) * np.inf)
        want = _message(lambda: r.check_q(q))
        assert want is not None and _message(lambda: r.checked_state(q, nu, tau)) == want


@compiled_only
@pytest.mark.parametrize("name", robotdyn.robots_available())
def test_the_doors_return_the_binding_s_arrays(name):
    """Robot.dynamics_derivatives and Robot.reduced return the binding's numbers bit for bit (no conversion on the
    way), and linearize's A and B are the derivatives' blocks as np.block would stack them, on every built-in
    robot (at its neutral configuration, random velocities and torques: off the ground is a state like another)."""
    from robotdyn.reduction.linearization import linearize

    r = robotdyn.load(name)
    rng = np.random.default_rng(4)
    q, nu, tau = r.neutral(), rng.normal(size=r.mobility) * 0.5, rng.normal(size=len(r.motors))
    D = r.dynamics_derivatives(q, nu, tau)
    fast = compiled_model(r)
    for field, x in zip(FIELDS, fast.ev.derivatives(q, nu, tau)):
        assert getattr(D, field).tobytes() == x.tobytes(), field
    red = r.reduced(q, nu)
    for field, x in zip(("M", "h", "g", "B", "S", "w", "v"), fast.ev.evaluate(q, nu)):
        assert getattr(red, field).tobytes() == x.tobytes(), field
    model = linearize(r, q, nu, tau)
    P = D.positions
    A = np.block([[(D.dqdot_dq @ D.tangent)[P], D.S[P]], [D.dq_manifold, D.dnu]])
    B = np.vstack([np.zeros((len(P), D.dtau.shape[1])), D.dtau])
    assert model.A.tobytes() == A.tobytes() and model.B.tobytes() == B.tobytes()
    assert np.abs(A[len(P):]).max() > 0  # not a vacuous comparison


def _same_as_python(r, q, nu, tau):
    fast = r.dynamics_derivatives(q, nu, tau)
    with use_compiled(False):
        slow = r.dynamics_derivatives(q, nu, tau)
    for name in FIELDS:
        ref = getattr(slow, name)
        assert np.abs(getattr(fast, name) - ref).max(initial=0) <= 1e-9 * max(1.0, np.abs(ref).max(initial=0)), name
    return fast


@compiled_only
def test_a_changed_robot_never_reads_a_stale_compiled_model():
    """After each change the compiled derivatives equal the Python path's (which reads the robot live) and differ
    from those before: gravity, a wheel radius, the terrain (set_terrain, on the adaptable wheel: quasimoro's planar
    root takes flat ground only), a constraint list with a wheel replaced by another object."""
    r = robotdyn.load("quasimoro")
    q, nu, tau = admissible_state(r, None, np.random.default_rng(8))
    before = _same_as_python(r, q, nu, tau)
    changes = [lambda: setattr(r.model.gravity, "linear", np.array([0.5, -1.0, -3.7])),
               lambda: setattr(r.constraints[0], "radius", 1.2 * r.constraints[0].radius)]
    for change in changes:
        change()
        after = _same_as_python(r, q, nu, tau)
        assert np.abs(after.dq - before.dq).max() > 1e-6
        before = after
    fast = compiled_model(r)
    r.constraints = list(r.constraints)  # another list of the same constraints: the same compiled model
    assert compiled_model(r) is fast
    wheel = copy.copy(r.constraints[1])  # a wheel replaced by another object (a variant's way)
    wheel.radius = 0.9 * wheel.radius
    r.constraints = [r.constraints[0], wheel]
    after = _same_as_python(r, q, nu, tau)
    assert compiled_model(r) is not fast and np.abs(after.dq - before.dq).max() > 1e-6
    r = robotdyn.load("adaptable_wheel")
    rng = np.random.default_rng(8)
    q, nu, tau = r.neutral(), rng.normal(size=r.mobility), rng.normal(size=len(r.motors))  # (off the ground: any q)
    before = _same_as_python(r, q, nu, tau)
    set_terrain(r, BumpTerrain(0.05, 0.1, 0.2))  # the same constraint objects, another terrain
    after = _same_as_python(r, q, nu, tau)
    assert np.abs(after.dq - before.dq).max() > 1e-6
