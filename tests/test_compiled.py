"""The compiled fast path (:mod:`robotdyn.fast.compiled`, ``robotdyn/_compiled.cpp``) against the Python reference path.

Every output of the compiled evaluation (M_r, h, g_r, B_r, S, w, v, the constraint rows A and their residuals, the
projection's condition number, the simulation right-hand side) is compared with the Python path
(``use_compiled(False)``) on every robot the fast path serves, at random states off the constraint manifold too;
plus the cases where the fast path must step aside (``why_not``, rebuilds, ``Fallback``, the model self-check).
"""

from __future__ import annotations

import os

import numpy as np
import pytest

import robotdyn
from robotdyn.fast import compiled, dispatch
from robotdyn.fast.compiled import Fallback, LazyProjection, why_not
from robotdyn.fast.dispatch import compiled_model, use_compiled
from robotdyn.errors import SingularConstraintError
from robotdyn.robots import names


@pytest.fixture(autouse=True)
def _needs_compiled(request):
    """Every test but test_available needs the fast path on (test_available reports why it is not)."""
    if request.node.name != "test_available" and not dispatch.enabled():
        pytest.skip("the compiled fast path is off (ROBOTDYN_COMPILED=0 or the extension was not built)")


TOL = 1e-12  # relative to max(1, |ref|max): the same formulas, so round-off only
COND_TOL = 1e-9
RNG_SEED = 20261122

# the linkage's suspension joints: moving them alone makes the closures rank-deficient (SingularConstraintError)
LINKAGE_JOINTS = ("theta1", "beta1", "theta2", "beta2")
REVOLUTE = {"RX", "RY", "RZ", "RevoluteUnaligned"}


@pytest.fixture(scope="module", params=names())
def robot(request):
    rob = robotdyn.load(request.param)
    reason = why_not(rob)
    if reason is not None:
        pytest.skip(f"{request.param} is not compiled: {reason}")
    return rob


@pytest.fixture(scope="module")
def quasimoro_m():
    return robotdyn.load("quasimoro")


@pytest.fixture(scope="module")
def linkage():
    return robotdyn.load("linkage_suspension")


def _joint_kinds(rob) -> list[str]:
    """Joint type per coordinate (every compiled robot has one-dof joints only)."""
    kinds = []
    for i in range(1, rob.model.njoints):
        kinds.append(rob.model.joints[i].shortname().replace("JointModel", ""))
    assert len(kinds) == rob.nq
    return kinds


def random_state(rob, rng, scale: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """q near neutral with random angles (up to +-scale rad on revolute joints, +-0.1 scale m on prismatic ones)
    and random nu; on the linkage the suspension joints stay at neutral (else the closures are singular)."""
    q = rob.neutral().copy()
    for i, kind in enumerate(_joint_kinds(rob)):
        if rob.spec.name == "linkage_suspension" and rob.coordinates[i] in LINKAGE_JOINTS:
            continue
        if rob.spec.name == "linkage_suspension" and kind not in REVOLUTE:
            q[i] += 0.02 * scale * rng.uniform(-1.0, 1.0)
        else:
            q[i] += (scale if kind in REVOLUTE else 0.1 * scale) * rng.uniform(-1.0, 1.0)
    return q, rng.normal(size=rob.mobility)


def _python(rob, q, nu):
    with use_compiled(False):
        return rob.reduced(q, nu)


class _Spy:
    """Counts the calls of a CompiledModel method that returned a result (the fast path was taken)."""

    def __init__(self, fast, name: str) -> None:
        self.fast, self.name = fast, name
        self.inner = getattr(fast, name)
        self.served = 0
        self.calls = 0
        setattr(fast, name, self)

    def __call__(self, *args, **kwargs):
        self.calls += 1
        out = self.inner(*args, **kwargs)
        if out is not None:
            self.served += 1
        return out

    def remove(self) -> None:
        delattr(self.fast, self.name)


def close(got, ref, tol=TOL) -> float:
    got, ref = np.asarray(got, float), np.asarray(ref, float)
    assert got.shape == ref.shape
    if ref.size == 0:
        return 0.0
    return float(np.max(np.abs(got - ref))) / max(1.0, float(np.max(np.abs(ref))))


FIELDS = ("M", "h", "g", "B", "S", "w", "v")


def assert_same(got, ref, where: str = "", condition: bool = True) -> None:
    for name in FIELDS:
        err = close(getattr(got, name), getattr(ref, name))
        assert err <= TOL, f"{name} differs by {err:.3g} {where}"
    for name in ("A", "residual"):
        err = close(getattr(got.jacobian_rows, name), getattr(ref.jacobian_rows, name))
        assert err <= TOL, f"jacobian_rows.{name} differs by {err:.3g} {where}"
    assert list(got.jacobian_rows.labels) == list(ref.jacobian_rows.labels)
    assert np.array_equal(got.jacobian_rows.holonomic, ref.jacobian_rows.holonomic)
    c_got, c_ref = got.projection.condition, ref.projection.condition
    assert not condition or abs(c_got - c_ref) <= COND_TOL * abs(c_ref), f"condition {c_got} != {c_ref} {where}"


def compare_at(rob, q, nu, where: str = ""):
    """The Python path at (q, nu), then robot.reduced on the fast path with the Python path's row choice:
    the same numbers, or the same exception. Returns the reference (None where it raised)."""
    fast = compiled_model(rob)
    assert fast is not None
    try:
        ref = _python(rob, q, nu)
    except SingularConstraintError:
        # the fast path must not produce a model where the Python path finds none
        with pytest.raises(SingularConstraintError):
            rob.reduced(q, nu)
        return None
    # robot.reduced as it comes (the fast path with its last row choice, or a fallback): the same model; the
    # condition number only where the same rows serve
    auto = rob.reduced(q, nu)
    same_rows = np.array_equal(auto.projection.rows, ref.projection.rows)
    assert_same(auto, ref, where + " (as it comes)", condition=same_rows)
    fast.select(ref.projection)
    spy = _Spy(fast, "reduced")
    try:
        got = rob.reduced(q, nu)
    finally:
        spy.remove()
    assert spy.served == 1, f"robot.reduced did not take the compiled path {where}"
    assert_same(got, ref, where)
    return ref


# ----------------------------------------------------------------------------------------------- availability
def test_available():
    if os.environ.get("ROBOTDYN_COMPILED") == "0":
        pytest.skip("ROBOTDYN_COMPILED=0 in the environment")
    assert compiled.available()
    assert dispatch.enabled()
    with use_compiled(False):
        assert not dispatch.enabled()
    assert dispatch.enabled()


def test_every_robot_but_radius_joints_is_served():
    served = {n: why_not(robotdyn.load(n)) for n in names()}
    for n in ("quasimoro", "omni_caster", "linkage_suspension", "mmr12_eod"):
        assert served[n] is None, f"{n}: {served[n]}"


# --------------------------------------------------------------------------------------- against the Python path
def test_first_call_selects_then_compiled():
    rob = robotdyn.load("quasimoro")
    fast = compiled_model(rob)
    assert fast is not None and not fast.ready
    q, nu = random_state(rob, np.random.default_rng(1))
    assert fast.reduced(q, nu) is None  # no row choice yet: the Python path decides
    first = rob.reduced(q, nu)  # the Python path, which selects its projection
    assert fast.ready
    spy = _Spy(fast, "reduced")
    second = rob.reduced(q, nu)
    spy.remove()
    assert spy.served == 1
    assert_same(second, first)
    assert_same(first, _python(rob, q, nu))


def test_reduced_equals_python_path(robot):
    rng = np.random.default_rng(RNG_SEED)
    n_ok = 0
    states = [(robot.neutral(), rng.normal(size=robot.mobility))]
    states += [random_state(robot, rng) for _ in range(24)]
    for i, (q, nu) in enumerate(states):
        ref = compare_at(robot, q, nu, f"({robot.spec.name}, state {i})")
        n_ok += ref is not None
    assert n_ok >= 20


def test_evaluate_tuple_equals_python_path(robot):
    """The raw outputs of evaluate with the Python projection's rows; the condition number and the inverse are
    K^-1 for operational velocities, and for selected velocities those of the LazyProjection robot.reduced
    returns (computed from A on request)."""
    rng = np.random.default_rng(11)
    fast = compiled_model(robot)
    for _ in range(5):
        q, nu = random_state(robot, rng)
        ref = _python(robot, q, nu)
        fast.select(ref.projection)
        M, h, g, B, S, w, v, A, residual, cond, inv = fast.evaluate(q, nu)
        if cond is None:  # selected velocities: the compiled path's own projection object
            assert inv is None
            proj = fast.reduced(q, nu).projection
            cond, inv = proj.condition, proj.Ad_inv
        for name, x in zip(FIELDS, (M, h, g, B, S, w, v)):
            assert close(x, getattr(ref, name)) <= TOL, name
        assert close(A, ref.jacobian_rows.A) <= TOL
        assert close(residual, ref.jacobian_rows.residual) <= TOL
        assert abs(cond - ref.projection.condition) <= COND_TOL * ref.projection.condition
        ref_inv = getattr(ref.projection, "Ad_inv", None)
        if ref_inv is None:
            ref_inv = getattr(ref.projection, "_inv", None)
        assert ref_inv is not None
        assert close(inv, ref_inv) <= 1e-10


def test_linkage_singular_states_raise_like_python(linkage):
    """Moving a suspension joint alone makes the closures rank-deficient: both paths refuse."""
    rng = np.random.default_rng(4)
    compare_at(linkage, linkage.neutral(), rng.normal(size=2))  # a row choice exists
    n_sing = 0
    for name in LINKAGE_JOINTS:
        q = linkage.neutral().copy()
        q[linkage.coordinates.index(name)] += 0.05
        n_sing += compare_at(linkage, q, rng.normal(size=2)) is None
    assert n_sing == len(LINKAGE_JOINTS)


def test_ramp_terrain():
    """Wheels on a sloped plane (the linkage's floating base follows it) and on a raised plane: nonzero residuals
    and slope-dependent drift; the planar bases cannot follow a slope, so both paths find them singular there."""
    from robotdyn.constraints.terrain import RampTerrain

    rng = np.random.default_rng(8)
    cases = [("linkage_suspension", RampTerrain(0.2, 0.7, 0.01), True),
             ("linkage_suspension", RampTerrain(-0.3, 2.0), True),
             ("quasimoro", RampTerrain(0.0, 0.0, 0.02), True), ("mmr12_eod", RampTerrain(0.0, 0.0, -0.02), True),
             ("omni_caster", RampTerrain(0.0, 0.0, 0.03), True),
             ("quasimoro", RampTerrain(0.2, 0.7), False), ("mmr12_eod", RampTerrain(0.1, -1.0), False)]
    for name, ramp, regular in cases:
        rob = robotdyn.load(name, terrain=ramp)
        assert why_not(rob) is None
        assert all(c.terrain is ramp for c in rob.constraints if hasattr(c, "terrain"))
        residual, n_ok = 0.0, 0
        for i in range(6):
            q, nu = (rob.neutral(), rng.normal(size=rob.mobility)) if i == 0 else random_state(rob, rng, 0.5)
            ref = compare_at(rob, q, nu, f"({name} on {ramp}, state {i})")
            if ref is not None:
                n_ok += 1
                residual = max(residual, float(np.abs(ref.jacobian_rows.residual).max()))
        if regular:
            assert n_ok == 6, f"{name} on {ramp}"
            assert residual > 1e-3  # the wheels are off the plane: the residuals are really compared
        else:
            assert n_ok == 0, f"{name} on {ramp}"


# ---------------------------------------------------------------------------------------------------- why_not
def _user_terrain():
    from robotdyn.constraints.terrain import FunctionTerrain

    return FunctionTerrain(lambda x, y: 0.01 * x * y, lambda x, y: np.array([0.01 * y, 0.01 * x]),
                           lambda x, y: np.array([[0.0, 0.01], [0.01, 0.0]]))


def test_why_not_names_a_terrain_without_compiled_formulas():
    """A terrain given by user callables can never be compiled: the reason names the wheel and the terrain."""
    rob = robotdyn.load("linkage_suspension", terrain=_user_terrain())
    reason = why_not(rob)
    assert reason is not None and "FunctionTerrain" in reason and "wheel" in reason
    assert compiled_model(rob) is None


@pytest.mark.parametrize("kind", ["sine", "bump"])
def test_curved_terrain_named_or_equal(kind):
    """Wheels on a curved terrain (sine, bump): either why_not names the terrain, or (once compiled) the fast path
    equals the Python path (the linkage is regular there only at neutral; adaptable_wheel's floating wheels are)."""
    from robotdyn.constraints.terrain import BumpTerrain, SineTerrain

    make = {"sine": lambda: SineTerrain(0.02, 0.3), "bump": lambda: BumpTerrain(0.05, 0.1, 0.2, 0.5)}[kind]
    rng = np.random.default_rng(12)
    rob = robotdyn.load("linkage_suspension", terrain=make())
    reason = why_not(rob)
    if reason is not None:
        assert type(rob.terrain).__name__ in reason and "wheel" in reason
        assert compiled_model(rob) is None
    else:
        assert compare_at(rob, rob.neutral(), rng.normal(size=2), f"(linkage on {kind}, neutral)") is not None
        for i in range(3):
            compare_at(rob, *random_state(rob, rng, 0.5), f"(linkage on {kind}, state {i})")
    rob = robotdyn.load("adaptable_wheel", terrain=make())
    if why_not(rob) is not None:
        return
    for i in range(6):
        q, nu = (rob.neutral(), rng.normal(size=rob.mobility)) if i == 0 else random_state(rob, rng, 0.5)
        ref = compare_at(rob, q, nu, f"(adaptable_wheel on {kind}, state {i})")
        assert ref is not None


def test_why_not_different_terrains():
    from robotdyn.constraints.terrain import RampTerrain

    rob = robotdyn.load("linkage_suspension")
    wheels = [c for c in rob.constraints if hasattr(c, "terrain")]
    wheels[0].terrain = RampTerrain(0.0, 0.0, 0.01)
    reason = why_not(rob)
    assert reason is not None and "different terrains" in reason
    assert compiled_model(rob) is None


def test_why_not_unsupported_constraint_and_rebuild():
    from robotdyn.constraints.constraint import Constraint
    from robotdyn.constraints.posture import set_terrain
    from robotdyn.constraints.terrain import RampTerrain

    rob = robotdyn.load("quasimoro")
    fast = compiled_model(rob)
    assert fast is not None
    assert compiled_model(rob) is fast  # cached

    class Extra(Constraint):
        name = "extra"

    extra = Extra()
    rob.constraints.append(extra)
    try:
        reason = why_not(rob)
        assert reason is not None and "not compiled" in reason and "Extra" in reason
        assert compiled_model(rob) is None
    finally:
        rob.constraints.remove(extra)
    again = compiled_model(rob)
    assert again is not None and again is not fast

    ramp = RampTerrain(0.0, 0.3, 0.02)
    set_terrain(rob, ramp)  # in place: the same constraint objects, another terrain
    on_ramp = compiled_model(rob)
    assert on_ramp is not None and on_ramp is not again
    assert compiled_model(rob) is on_ramp
    rng = np.random.default_rng(2)
    for i in range(3):
        q, nu = random_state(rob, rng, 0.5)
        ref = compare_at(rob, q, nu, "(quasimoro after set_terrain)")
        assert abs(abs(ref.jacobian_rows.residual).max() - 0.02) < 0.02  # the raised plane is used


def test_why_not_joint_coupling_with_a_user_law():
    """A JointCoupling whose law is a plain callable (no compiled formula) keeps the robot on the Python path."""
    from robotdyn.constraints.joint_coupling import JointCoupling

    rob = robotdyn.load("mmr12_eod")
    assert why_not(rob) is None
    coupling = JointCoupling(rob.description, "theta3_joint", "theta1_joint", lambda x: 0.5 * x + 0.1 * x**3,
                             lambda x: 0.5 + 0.3 * x**2, lambda x: 0.6 * x)
    rob.constraints.append(coupling)
    try:
        reason = why_not(rob)
        assert reason is not None and ("coupling" in reason.lower())
        assert compiled_model(rob) is None
    finally:
        rob.constraints.pop()
    assert why_not(rob) is None and compiled_model(rob) is not None


def test_adaptable_wheel_named_or_equal():
    """adaptable_wheel (radius joints, couplings, a sine terrain): a reason, or once compiled the Python numbers."""
    rob = robotdyn.load("adaptable_wheel")
    reason = why_not(rob)
    if reason is not None:
        assert compiled_model(rob) is None
        assert any(w in reason for w in ("radius joint", "terrain", "coupling", "not compiled"))
        return
    rng = np.random.default_rng(13)
    n_ok = 0
    for i in range(6):
        q = rob.neutral() + (0.0 if i == 0 else 0.01) * rng.normal(size=rob.nq)
        n_ok += compare_at(rob, q, rng.normal(size=rob.mobility), f"(adaptable_wheel, state {i})") is not None
    assert n_ok >= 4


# ------------------------------------------------------------------------------------------------------ rhs
def python_rhs(rob, q, nu, tau, alpha):
    red = _python(rob, q, nu)
    nudot = np.linalg.solve(red.M, red.B @ tau - red.h)
    qdot = red.v
    rows = red.jacobian_rows
    hol = rows.holonomic
    if alpha and hol.any() and rows.residual[hol].any():
        qdot = qdot - alpha * np.linalg.lstsq(rows.A[hol], rows.residual[hol], rcond=None)[0]
    return np.concatenate([qdot, nudot]), red


def test_rhs_equals_python(robot):
    rng = np.random.default_rng(17)
    fast = compiled_model(robot)
    n_stab = 0
    for i in range(8):
        q, nu = random_state(robot, rng, 0.5)
        tau = rng.normal(size=len(robot.motors))
        ref, red = python_rhs(robot, q, nu, tau, 10.0)
        fast.select(red.projection)
        got = fast.rhs(q, nu, tau, 10.0)
        assert close(got, ref) <= 1e-10, f"state {i}: {close(got, ref):.3g}"
        hol = red.jacobian_rows.holonomic
        if hol.any() and np.abs(red.jacobian_rows.residual[hol]).max() > 1e-6:
            n_stab += 1
            plain = fast.rhs(q, nu, tau, 0.0)
            assert close(plain, np.concatenate([red.v, ref[robot.nq:]])) <= 1e-10
            assert close(plain, got) > 1e-6  # the stabilisation term really acted
    if robot.spec.name == "linkage_suspension":
        assert n_stab > 0


def test_rhs_linkage_off_closure(linkage):
    """A perturbed linkage configuration (closures violated, rows still full rank): the pull-back term matters."""
    rng = np.random.default_rng(23)
    for name in ("psi", "rod1_x", "rod2_y", "sigma1", "gamma2"):
        q = linkage.neutral().copy()
        q[linkage.coordinates.index(name)] += 0.03
        nu = rng.normal(size=2)
        tau = rng.normal(size=len(linkage.motors))
        ref, red = python_rhs(linkage, q, nu, tau, 10.0)
        hol = red.jacobian_rows.holonomic
        assert np.abs(red.jacobian_rows.residual[hol]).max() > 1e-4
        fast = compiled_model(linkage)
        fast.select(red.projection)
        got = fast.rhs(q, nu, tau, 10.0)
        assert close(got, ref) <= 1e-10, f"{name}: {close(got, ref):.3g}"
        assert close(got[: linkage.nq], red.v) > 1e-4


# ------------------------------------------------------------------------------------------------ evaluate_many
def test_evaluate_many(robot):
    rng = np.random.default_rng(31)
    fast = compiled_model(robot)
    states = [random_state(robot, rng, 0.5) for _ in range(50)]
    Q = np.array([s[0] for s in states])
    NU = np.array([s[1] for s in states])
    ref0 = _python(robot, Q[0], NU[0])
    fast.select(ref0.projection)
    M, h, g, S, w, B, failed = fast.evaluate_many(Q, NU)
    k, n = robot.mobility, robot.nq
    assert M.shape == (50, k, k) and S.shape == (50, n, k) and B.shape == (50, k, len(robot.motors))
    assert failed == []
    for i in range(50):
        one = fast.evaluate(Q[i], NU[i])
        for x, y in zip((M[i], h[i], g[i], B[i], S[i], w[i]), (one[0], one[1], one[2], one[3], one[4], one[5])):
            assert close(x, y) <= 1e-14
        ref = _python(robot, Q[i], NU[i])
        for name, x in zip(("M", "h", "g", "B", "S", "w"), (M[i], h[i], g[i], B[i], S[i], w[i])):
            assert close(x, getattr(ref, name)) <= TOL, f"state {i}: {name}"


def test_evaluate_many_reports_singular_states(linkage):
    rng = np.random.default_rng(5)
    ref = _python(linkage, linkage.neutral(), np.zeros(2))
    fast = compiled_model(linkage)
    fast.select(ref.projection)
    Q = np.tile(linkage.neutral(), (6, 1))
    Q[2, linkage.coordinates.index("theta1")] += 0.05
    Q[4, linkage.coordinates.index("beta2")] -= 0.05
    NU = rng.normal(size=(6, 2))
    M, h, g, S, w, B, failed = fast.evaluate_many(Q, NU)
    assert sorted(failed) == [2, 4]
    for i in (0, 1, 3, 5):
        red = _python(linkage, Q[i], NU[i])
        assert close(M[i], red.M) <= TOL and close(h[i], red.h) <= TOL and close(S[i], red.S) <= TOL


# ------------------------------------------------------------------------------------------------------ gravity
def test_gravity_change_rebuilds():
    rob = robotdyn.load("mmr12_eod")
    rng = np.random.default_rng(9)
    q, nu = random_state(rob, rng, 0.5)
    before = compare_at(rob, q, nu)
    fast = compiled_model(rob)
    rob.model.gravity.linear = np.array([0.5, -1.0, -3.7])
    assert compiled_model(rob) is not fast
    after = compare_at(rob, q, nu, "(after a gravity change)")
    assert close(after.g, before.g) > 1e-3  # gravity really changed the result
    assert close(after.M, before.M) <= TOL


# --------------------------------------------------------------------------------------------------- self-check
def test_self_check_names_mass_change():
    rob = robotdyn.load("quasimoro")
    fast = compiled.CompiledModel(rob)
    fast._check_model()  # the rebuilt model agrees with Pinocchio's
    i = rob.model.njoints - 1
    Y = rob.model.inertias[i].copy()
    Y.mass = Y.mass * 1.5
    rob.model.inertias[i] = Y
    assert rob.model.inertias[i].mass == Y.mass
    with pytest.raises(RuntimeError, match=r"\bM\b differs"):
        fast._check_model()


def test_self_check_names_gravity_change():
    rob = robotdyn.load("mmr12_eod")
    fast = compiled.CompiledModel(rob)
    rob.model.gravity.linear = np.array([0.0, 0.0, -1.62])
    with pytest.raises(RuntimeError, match=r"\bg\b differs"):
        fast._check_model()


# ----------------------------------------------------------------------------------------------------- simulate
def test_simulate_rectilinear_equals_python(quasimoro_m):
    from robotdyn.robots.quasimoro import SCENARIOS

    scenario = SCENARIOS["rectilinear"]
    rob = quasimoro_m
    scenario.run(rob, t_end=0.01, progress=False)  # the projection gets chosen
    fast = compiled_model(rob)
    spy = _Spy(fast, "rhs")
    try:
        fast_traj = scenario.run(rob, t_end=3.0, progress=False, engine="scipy")  # scipy's loop, compiled rhs
    finally:
        spy.remove()
    assert spy.served > 50 and spy.served == spy.calls
    with use_compiled(False):
        ref = scenario.run(rob, t_end=3.0, progress=False, engine="scipy")
    assert fast_traj.q.shape == ref.q.shape
    assert np.abs(fast_traj.q - ref.q).max() <= 1e-8
    assert np.abs(fast_traj.nu - ref.nu).max() <= 1e-8
    nf, nr = fast_traj.stats["nfev"], ref.stats["nfev"]
    assert 0.5 * nr <= nf <= 2.0 * nr


@pytest.mark.parametrize("name, coordinate, value, nu0", [
    ("quasimoro", "theta3", 0.4, [1.0, -0.5, 0.3]),
    ("omni_caster", None, 0.0, [0.3, -0.2, 0.5]),  # operational velocities
])
def test_simulate_energy_conserved(name, coordinate, value, nu0):
    """A torque-free run with the compiled rhs conserves energy and really moves."""
    from robotdyn.simulation.engine import simulate

    rob = robotdyn.load(name)
    q0 = rob.neutral()
    if coordinate is not None:
        q0[rob.coordinates.index(coordinate)] = value
    nu0 = np.array(nu0)
    rob.reduced(q0, nu0)
    fast = compiled_model(rob)
    spy = _Spy(fast, "rhs")
    try:
        traj = simulate(rob, 3.0, q0, nu0, None, n_out=301, progress=False, engine="scipy")
    finally:
        spy.remove()
    assert spy.served == spy.calls > 0
    assert np.abs(traj.energy - traj.energy[0]).max() / abs(traj.energy[0]) < 1e-8
    assert np.ptp(traj.q, axis=0).max() > 0.1  # it really moved


# ------------------------------------------------------------------------------------------------------ fallback
def test_fallback_at_singular_linkage_state(linkage):
    rng = np.random.default_rng(41)
    ref = _python(linkage, linkage.neutral(), np.zeros(2))
    fast = compiled_model(linkage)
    fast.select(ref.projection)
    q = linkage.neutral().copy()
    q[linkage.coordinates.index("theta2")] += 0.05
    nu = rng.normal(size=2)
    with pytest.raises(Fallback):
        fast.evaluate(q, nu)
    with pytest.raises(Fallback):
        fast.rhs(q, nu, np.zeros(len(linkage.motors)), 10.0)
    assert fast.reduced(q, nu) is None
    with pytest.raises(SingularConstraintError):
        linkage.reduced(q, nu)
    with use_compiled(False), pytest.raises(SingularConstraintError):
        linkage.reduced(q, nu)


def test_fallback_bad_row_choice(robot):
    """A row choice that is singular at the state (chosen where another configuration made those rows regular):
    evaluate/rhs raise Fallback, robot.reduced gives the Python path's result, re-selects and is fast again."""
    from robotdyn.reduction.projection import _build

    rng = np.random.default_rng(43)
    for _ in range(10):
        q, nu = random_state(robot, rng, 0.3)
        try:
            ref = _python(robot, q, nu)
            break
        except SingularConstraintError:
            continue
    proj = ref.projection
    A = ref.jacobian_rows.A
    operational = robot.operational is not None

    def singular(rows) -> bool:
        # Python's block: A_d = A[rows][:, dependent]; operational: K = [A[rows]; J_o], singular if A[rows] is
        block = A[rows] if operational else A[rows][:, proj.dependent]
        s = np.linalg.svd(block, compute_uv=False)
        return s[-1] <= 1e-13 * max(1.0, s[0])

    # rows whose block is singular here: the chosen rows with one replaced by another row
    bad = None
    for out in range(proj.rows.size):
        for extra in np.setdiff1d(np.arange(A.shape[0]), proj.rows):
            rows = np.sort(np.r_[np.delete(proj.rows, out), extra])
            if singular(rows):
                bad = rows
                break
        if bad is not None:
            break
    if bad is None:
        pytest.skip(f"no singular row choice of this size at this state of {robot.spec.name} (e.g. every row is used)")
    if operational:
        from robotdyn.reduction.operational_space import OperationalProjection

        other = OperationalProjection(proj.S, bad, proj.condition, proj._inv)
    else:
        # the projection of an (artificial) configuration where those rows are regular
        A_elsewhere = A.copy()
        A_elsewhere[bad] += rng.normal(size=(bad.size, A.shape[1]))
        other = _build(A_elsewhere, proj.independent, proj.dependent, bad, list(robot.velocity_names))
    fast = compiled_model(robot)
    fast.select(other)
    with pytest.raises(Fallback):
        fast.evaluate(q, nu)
    with pytest.raises(Fallback):
        fast.rhs(q, nu, np.zeros(len(robot.motors)), 10.0)
    assert fast.reduced(q, nu) is None
    got = robot.reduced(q, nu)  # the Python path re-chooses the rows and selects them for the fast path
    assert_same(got, ref, "(after a fallback)")
    assert fast._hint is not other and not np.array_equal(fast._hint.rows, bad)
    spy = _Spy(fast, "reduced")
    try:
        again = robot.reduced(q, nu)
    finally:
        spy.remove()
    assert spy.served == 1
    assert_same(again, ref, "(fast again after a fallback)")


def _compute_views(fast, q, nu) -> list[np.ndarray]:
    """(M, h, g, B, S, w, v) from the no-copy evaluation, whichever form it has (CompiledModel.compute returning
    views, or ev.compute then the evaluator's view attributes); copies."""
    out = fast.compute(q, nu) if hasattr(fast, "compute") else fast.ev.compute(q, nu)
    if isinstance(out, tuple) and len(out) >= 7:
        return [np.array(x) for x in out[:7]]
    return [np.array(getattr(fast.ev, n)) for n in FIELDS]


def test_compute_views(robot):
    """The no-copy evaluation gives evaluate's numbers, and the next call's numbers (not stale buffers)."""
    if not (hasattr(compiled.CompiledModel, "compute") or hasattr(compiled_model(robot).ev, "compute")):
        pytest.skip("no compute entry point any more")
    rng = np.random.default_rng(53)
    fast = compiled_model(robot)
    states = [random_state(robot, rng, 0.3) for _ in range(3)]
    fast.select(_python(robot, *states[0]).projection)
    first = _compute_views(fast, *states[0])
    for q, nu in states + states[:1]:
        ref = fast.evaluate(q, nu)
        got = _compute_views(fast, q, nu)
        for name, x, y in zip(FIELDS, got, ref[:7]):
            assert x.shape == np.shape(y), name
            assert close(x, y) <= 1e-14, name
    assert close(first[1], _compute_views(fast, *states[1])[1]) > 1e-6  # different states, different h
    py = _python(robot, *states[2])
    fast.select(py.projection)
    for name, x in zip(FIELDS, _compute_views(fast, *states[2])):
        assert close(x, getattr(py, name)) <= TOL, name


# ------------------------------------------------------------------------------------------ later changes, more
def test_cosine_coupling_named_or_equal():
    """A JointCoupling with a CosineLaw on mmr12 (one velocity less): named by why_not, or compiled and equal."""
    jc = pytest.importorskip("robotdyn.constraints.joint_coupling")
    if not hasattr(jc, "CosineLaw"):
        pytest.skip("no CosineLaw in robotdyn.constraints.joint_coupling")
    rob = robotdyn.load("mmr12_eod")
    coupling = jc.JointCoupling(rob.description, "theta3_joint", "theta1_joint", jc.CosineLaw(0.3, 1.5, 0.2, -0.1))
    rob.constraints.append(coupling)
    i3 = rob.coordinates.index("theta3")
    rob.independent_indices = np.array([i for i in rob.independent_indices if i != i3])
    rob.velocity_names = [rob.velocity_labels[i] for i in rob.independent_indices]
    reason = why_not(rob)
    if reason is not None:
        assert "coupling" in reason.lower() or "JointCoupling" in reason
        return
    rng = np.random.default_rng(61)
    for i in range(6):
        q, nu = random_state(rob, rng, 0.5)
        ref = compare_at(rob, q, nu, f"(mmr12 with a cosine coupling, state {i})")
        assert ref is not None and ref.M.shape == (11, 11)
        assert abs(ref.jacobian_rows.residual[-1]) > 1e-3  # the coupling is violated: its residual is compared
        tau = rng.normal(size=len(rob.motors))
        want, red = python_rhs(rob, q, nu, tau, 10.0)
        assert close(compiled_model(rob).rhs(q, nu, tau, 10.0), want) <= 1e-10


def test_radius_change_rebuilds():
    """A wheel radius changed in place (as a parameter study would): a new compiled model, the new numbers."""
    rob = robotdyn.load("quasimoro")
    rng = np.random.default_rng(67)
    q, nu = random_state(rob, rng, 0.5)
    before = compare_at(rob, q, nu)
    fast = compiled_model(rob)
    wheel = next(c for c in rob.constraints if hasattr(c, "radius"))
    wheel.radius = 1.2 * wheel.radius
    assert compiled_model(rob) is not fast
    after = compare_at(rob, q, nu, "(after a radius change)")
    assert close(after.S, before.S) > 1e-3


def test_other_independent_velocities_use_the_python_choice():
    """Changing robot.independent_indices after the fast path chose its rows: the results follow the new choice."""
    rob = robotdyn.load("mmr12_eod")
    rng = np.random.default_rng(71)
    q, nu = random_state(rob, rng, 0.3)
    compare_at(rob, q, nu)
    fast = compiled_model(rob)
    old = rob.independent_indices
    assert fast.reduced(q, nu, old.copy()) is not None  # the same indices, another array: still fast
    # swap one independent wheel velocity for the planar heading rate
    new = old.copy()
    new[0] = rob.coordinates.index("psi")
    assert fast.reduced(q, nu, new) is None
    rob.independent_indices = new
    rob.velocity_names = [rob.velocity_labels[i] for i in new]
    got = rob.reduced(q, nu)
    ref = _python(rob, q, nu)
    assert_same(got, ref, "(new independent velocities)")
    assert np.array_equal(got.S[new], np.eye(len(new)))
    compare_at(rob, *random_state(rob, rng, 0.3), "(new independent velocities, compiled)")


def test_coriolis_request_takes_the_python_path(robot):
    """coriolis=True needs C_r (the Python path); its M, h, ... equal the compiled ones."""
    rng = np.random.default_rng(73)
    q, nu = random_state(robot, rng, 0.3)
    fast_red = compare_at(robot, q, nu)
    full = robot.reduced(q, nu, coriolis=True)
    assert full.C is not None
    assert_same(robot.reduced(q, nu), full)
    # C_r nu + g_r = h (the bias from one RNEA call)
    assert close(full.C @ nu + full.g, fast_red.h) <= 1e-10



def test_simulate_linkage_equals_python(linkage, monkeypatch):
    """The linkage's straight_line scenario (motors tracking a speed profile, loop closures, stabilised residuals)
    over 0.5 s: the compiled right-hand side gives the Python path's trajectory."""
    from robotdyn.robots.linkage_suspension import SCENARIOS

    scenario = SCENARIOS["straight_line"]
    calls = []
    inner = compiled.CompiledModel.rhs

    def rhs(self, *args):  # the scenario may set its terrain, so a new compiled model serves the run
        out = inner(self, *args)
        calls.append(self)
        return out

    monkeypatch.setattr(compiled.CompiledModel, "rhs", rhs)
    got = scenario.run(linkage, t_end=0.5, progress=False, engine="scipy")  # the compiled rhs in the scipy loop
    assert len(calls) >= 0.9 * got.stats["nfev"] > 50  # all but the first evaluations (which choose the rows)
    monkeypatch.undo()
    with use_compiled(False):
        ref = scenario.run(linkage, t_end=0.5, progress=False)
    assert np.ptp(ref.q[:, 0]) > 1e-3  # it drives
    assert np.abs(got.q - ref.q).max() <= 1e-8
    assert np.abs(got.nu - ref.nu).max() <= 1e-8
    assert 0.5 * ref.stats["nfev"] <= got.stats["nfev"] <= 2.0 * ref.stats["nfev"]


def test_condition_estimate_bounds_the_exact_number(robot):
    """The compiled path decides singularity by LAPACK's estimate of the 1-norm condition number below 1e8: a
    lower bound of the exact number (robot.reduced's projection.condition), and here within a factor 3 of it."""
    if robot.operational is not None:
        pytest.skip("operational velocities: the compiled path computes the exact number")
    rng = np.random.default_rng(5)
    fast = compiled_model(robot)
    checked = 0
    for _ in range(30):
        q, nu = random_state(robot, rng)
        try:
            red = robot.reduced(q, nu)
        except SingularConstraintError:
            continue
        if not isinstance(red.projection, LazyProjection) or not red.projection.rows.size:
            continue
        exact, estimate = red.projection.condition, fast.ev.condition
        assert estimate <= exact * (1 + 1e-9)
        assert estimate >= exact / 3
        checked += 1
    assert checked >= 10
