"""The fast traction pass (robotdyn.contact.traction_fast) against the per-sample reference (constraint_forces at every
sample): the same loads, tangential forces, required and minimum friction, events and undetermined wheels on every
built-in robot's scenarios; the automatic choice (slipping wheels, no compiled model: the reference); samples it
cannot serve computed by the reference, with the reference's errors; the exact minimum over one direction of
undetermined splits; no per-sample force objects."""

from __future__ import annotations

import tracemalloc
from dataclasses import replace

import numpy as np
import pytest

import robotdyn.contact.traction_fast as traction_fast
from robotdyn.contact.contact_forces import cone_minimum
from robotdyn.contact.traction import traction
from robotdyn.contact.traction_fast import _cone_minimum, _cone_minimum_1d, wheel_loads
from robotdyn.errors import InputError
from robotdyn.fast.compiled import Fallback
from robotdyn.fast.dispatch import compiled_model, use_compiled
from robotdyn.robot import Robot
from robotdyn.robots import module
from robotdyn.simulation.engine import simulate

ROBOTS = ["quasimoro", "omni_caster", "linkage_suspension", "adaptable_wheel", "mmr12_eod"]
CASES = [(name, sc) for name in ROBOTS for sc in module(name).SCENARIOS]
RTOL = 1e-9
MU_RTOL = 1e-7
"""The minimum mu: the reference's bounded scalar search stops within sqrt(eps) |z| + 1e-12 scale of the best
split, which at a kink of max_i (two cones crossing) leaves up to ~1e-8 of the minimum; the fast pass's value is
exact there (never above the reference's)."""


def _run(name: str, scenario: str, t_end: float = 0.4, n_out: int = 21):
    """A short run of a built-in scenario: (robot, scenario, trajectory)."""
    mod = module(name)
    sc = mod.SCENARIOS[scenario]
    robot = Robot(mod.SPEC)
    traj = sc.run(robot, t_end=min(t_end, sc.t_end), n_out=n_out, progress=False)
    return robot, sc, traj


def _close(a: np.ndarray, b: np.ndarray, what: str) -> None:
    """Equal to RTOL relative to each column's largest magnitude (values at rest are rounding noise around
    zero), with the same infinite entries."""
    assert a.shape == b.shape, what
    assert np.array_equal(np.isinf(a), np.isinf(b)), what
    finite = np.isfinite(b)
    scale = np.broadcast_to(np.max(np.where(finite, np.abs(b), 0.0), axis=0, initial=0.0), b.shape)
    assert np.all(np.abs(a - b)[finite] <= RTOL * scale[finite] + 1e-300), what


def assert_same(fast, ref) -> None:
    """Two :class:`Traction` results agree: wheels, undetermined ones, determined friction, loads, tangential
    forces, required and minimum mu, events."""
    assert fast.wheels == ref.wheels and fast.undetermined == ref.undetermined
    assert np.array_equal(fast.friction_determined, ref.friction_determined)
    np.testing.assert_array_equal(fast.t, ref.t)
    np.testing.assert_array_equal(fast.mu, ref.mu)
    _close(fast.normal, ref.normal, "normal")
    _close(fast.tangential, ref.tangential, "tangential")
    _close(fast.required_mu, ref.required_mu, "required mu")
    assert (fast.minimum_mu is None) == (ref.minimum_mu is None)
    if ref.minimum_mu is not None:
        scale = np.max(ref.minimum_mu[np.isfinite(ref.minimum_mu)], initial=0.0)
        np.testing.assert_array_equal(np.isinf(fast.minimum_mu), np.isinf(ref.minimum_mu))
        finite = np.isfinite(ref.minimum_mu)
        assert np.all(np.abs(fast.minimum_mu - ref.minimum_mu)[finite] <= MU_RTOL * scale)
        assert np.all(fast.minimum_mu[finite] <= ref.minimum_mu[finite] + 1e-12 * scale)  # exact: never above
    assert [(e.kind, e.wheel) for e in fast.events] == [(e.kind, e.wheel) for e in ref.events]
    for e, r in zip(fast.events, ref.events):
        assert e.t == pytest.approx(r.t, rel=RTOL, abs=1e-12) and e.value == pytest.approx(r.value, rel=RTOL)
    assert fast.summary() == ref.summary()


@pytest.mark.parametrize("name, scenario", CASES)
def test_fast_pass_equals_the_reference_on_every_scenario(name, scenario):
    """Every built-in scenario traction is computed for (``robotdyn simulate``: the scenario's torque), with the
    wheels' own mu and with a mu half the largest required one (so that slip events occur where friction is
    determined): the fast pass served every sample and equals the per-sample reference."""
    robot, sc, traj = _run(name, scenario)
    loads = wheel_loads(robot, traj.t, traj.q, traj.nu, sc.torque)
    assert loads is not None and loads.fallback == 0
    ref = traction(robot, traj, sc.torque, method="reference")
    fast = traction(robot, traj, sc.torque)
    assert fast.method == "fast" and ref.method == "reference"
    assert_same(fast, ref)
    mus = ref.required_mu[:, ref.friction_determined]
    mus = mus[np.isfinite(mus)]
    if mus.size and mus.max() > 0:
        mu = 0.5 * float(mus.max())
        ref = traction(robot, traj, sc.torque, mu, method="reference")
        assert any(e.kind == "slip" for e in ref.events)
        assert_same(traction(robot, traj, sc.torque, mu), ref)


def test_quasimoro_minimum_mu_and_twin_loads():
    """Quasimoro (planar root: its loads from the floating twin; the lateral split of one axle undetermined, so the
    minimum mu comes from the exact one-direction search) over a longer run with the motors' pulse and after."""
    robot, sc, traj = _run("quasimoro", "rectilinear", t_end=3.0, n_out=301)
    ref = traction(robot, traj, sc.torque, method="reference")
    fast = traction(robot, traj, sc.torque)
    assert ref.minimum_mu is not None and not ref.friction_determined.any() and not ref.undetermined
    assert_same(fast, ref)


def test_disc_events_and_slipping_wheels_use_the_reference():
    """A disc rolling down an incline (events at a given mu, equal on both passes); the same disc with a Coulomb
    wheel (its friction force only the Python path computes): the reference is chosen automatically."""
    from test_contact_forces import _disc_on_ramp
    from test_sliding import disc

    robot, q0 = _disc_on_ramp(0.4)
    traj = simulate(robot, 0.5, q0, np.zeros(robot.mobility), n_out=51, progress=False)
    need = 0.4 * (2 / 9) / (1 + 2 / 9)
    fast, ref = traction(robot, traj, mu=0.99 * need), traction(robot, traj, mu=0.99 * need, method="reference")
    assert fast.method == "fast" and [e.kind for e in fast.events] == ["slip"]
    assert_same(fast, ref)
    robot, q0 = disc(0.0, friction="coulomb", mu=0.3, slip_velocity=1e-3)
    traj = simulate(robot, 0.02, q0, [2.0, 0, 0, 0, 0], n_out=11, progress=False)
    assert wheel_loads(robot, traj.t, traj.q, traj.nu) is None
    tr = traction(robot, traj)
    assert tr.method == "reference" and tr.wheels == ["disc"]
    with pytest.raises(InputError, match="method"):
        traction(robot, traj, method="fastest")


def test_without_the_compiled_model_the_reference_serves():
    robot, sc, traj = _run("linkage_suspension", "straight_line", n_out=6)
    ref = traction(robot, traj, sc.torque, method="reference")
    with use_compiled(False):
        tr = traction(robot, traj, sc.torque)
    assert tr.method == "reference"
    assert_same(tr, ref)


def test_samples_the_fast_pass_cannot_serve_go_to_the_reference(monkeypatch):
    """A compiled fallback at two samples (on the planar model at one, on the floating twin at the other): those
    samples are computed by constraint_forces, the others by the fast pass, and the result equals the reference."""
    robot, sc, traj = _run("quasimoro", "pure_rotation", t_end=2.0, n_out=41)
    ref = traction(robot, traj, sc.torque, method="reference")
    fast_model, twin_model = compiled_model(robot), compiled_model(robot._floating_twin)
    refused = {(robot.nq, float(traj.q[7][2])), (robot._floating_twin.nq, float(traj.q[23][2]))}  # (model, psi)
    for model in (fast_model, twin_model):
        original = model.forces_at
        psi = 2 if model is fast_model else robot._floating_twin.description.joint_names.index("yaw")

        def refusing(q, v, a, tau, original=original, psi=psi):
            if (len(q), float(q[psi])) in refused:
                raise Fallback("refused by the test")
            return original(q, v, a, tau)

        monkeypatch.setattr(model, "forces_at", refusing)
    loads = wheel_loads(robot, traj.t, traj.q, traj.nu, sc.torque)
    assert loads.fallback == 2
    assert_same(traction(robot, traj, sc.torque), ref)


def test_bad_samples_raise_the_reference_errors():
    """A non-finite coordinate (first sample or a later one) or a torque of the wrong length: the same one-line
    error as the per-sample reference."""
    robot, sc, traj = _run("quasimoro", "rectilinear", n_out=11)
    for k in (0, 6):
        bad = traj.q.copy()
        bad[k, 3] = np.nan
        traj_bad = replace(traj, q=bad)
        with pytest.raises(InputError) as fast_error:
            traction(robot, traj_bad, sc.torque)
        with pytest.raises(InputError) as ref_error:
            traction(robot, traj_bad, sc.torque, method="reference")
        assert str(fast_error.value) == str(ref_error.value)
    with pytest.raises(InputError, match="tau") as fast_error:
        traction(robot, traj, lambda t, q, nu: np.zeros(3))
    with pytest.raises(InputError, match="tau") as ref_error:
        traction(robot, traj, lambda t, q, nu: np.zeros(3), method="reference")
    assert str(fast_error.value) == str(ref_error.value)


def test_no_force_object_per_sample(monkeypatch):
    """The fast pass builds no ConstraintForces where it serves every sample, and its memory does not grow with
    one per sample: a 4x longer trajectory's traced peak stays within a block's working set plus the loads."""
    robot, sc, traj = _run("quasimoro", "rectilinear", t_end=90.0, n_out=8001)
    traction(robot, traj, sc.torque)  # the floating twin, its compiled model, imports: built once

    def forbidden(*args, **kwargs):
        raise AssertionError("constraint_forces called by the fast pass")

    monkeypatch.setattr(traction_fast, "constraint_forces", forbidden)

    def peak(n: int) -> int:
        sub = replace(traj, t=traj.t[:n], q=traj.q[:n], nu=traj.nu[:n])
        tracemalloc.start()
        try:
            traction(robot, sub, sc.torque)
            return tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()

    short, long = peak(2000), peak(8001)
    assert long < short + 8001 * 2 * 8 * 12  # the per-sample arrays only (2 wheels, a dozen numbers each)


def test_exact_minimum_over_one_direction():
    """min over y of max_i |b_i + t_i y| / f_i: the exact candidates against a dense grid, and against the
    reference's solvers (bounded scalar search for one combination, SLSQP for several that move the tangential
    forces along one direction only): never above them, equal to 1e-9."""
    rng = np.random.default_rng(3)
    G, W = 200, 3
    fn = rng.uniform(5.0, 50.0, (G, W))
    b = rng.normal(0.0, 3.0, (G, W, 2))
    t = rng.normal(0.0, 1.0, (G, W, 2))
    t[::4, 1] = 0.0  # a wheel whose force does not move
    exact = _cone_minimum_1d(fn, b, t, np.full(G, np.inf))
    for g in range(0, G, 20):
        def ratio(y, g=g):
            return np.max(np.linalg.norm(b[g][None] + t[g][None] * y[:, None, None], axis=2) / fn[g], axis=1)

        y = np.linspace(-60.0, 60.0, 24001)
        for _ in range(3):  # zoom in around the best grid point
            best, step = y[np.argmin(ratio(y))], y[1] - y[0]
            y = np.linspace(best - 2 * step, best + 2 * step, 10001)
        assert exact[g] <= ratio(y).min() * (1 + 1e-12)
        assert exact[g] == pytest.approx(ratio(y).min(), rel=1e-10)
    T1 = t[:, :, :, None]
    fast = _cone_minimum(fn, b, T1)
    for g in range(0, G, 10):
        ref = cone_minimum([(b[g, w], T1[g, w]) for w in range(W)], fn[g], 1)
        assert fast[g] <= ref * (1 + 1e-12) and fast[g] == pytest.approx(ref, rel=MU_RTOL)
    # two combinations moving the forces along one direction: reduced to that direction
    u = np.array([0.6, 0.8])
    T2 = T1 * u  # (G, W, 2, 2)
    fast2 = _cone_minimum(fn, b, T2)
    for g in range(0, G, 40):
        ref = cone_minimum([(b[g, w], T2[g, w]) for w in range(W)], fn[g], 2)
        assert fast2[g] <= ref * (1 + 1e-9) and fast2[g] == pytest.approx(ref, rel=MU_RTOL)
    # a wheel not pressed on the ground: inf; no undetermined combination: the ratio at zero
    fn[0, 0] = 0.0
    assert _cone_minimum(fn, b, T1)[0] == np.inf
    np.testing.assert_allclose(_cone_minimum(fn[1:], b[1:], np.zeros((G - 1, W, 2, 0))),
                               np.max(np.linalg.norm(b[1:], axis=2) / fn[1:], axis=1), rtol=1e-15)


def test_cli_csv_columns_equal_the_reference(tmp_path, monkeypatch):
    """``robotdyn simulate --csv`` in memory and streamed in segments (each segment's traction columns from its own
    traction() call): the same header and numbers as with the per-sample reference."""
    from robotdyn.cli.commands import main
    import robotdyn.contact.traction as traction_module

    def run(path, streamed: bool, reference: bool):
        with monkeypatch.context() as m:
            if streamed:
                m.setattr("robotdyn.simulation.streaming.SEGMENT", 50)
            if reference:
                m.setattr(traction_module, "wheel_loads", lambda *args, **kwargs: None)
            assert main(["simulate", "quasimoro", "--scenario", "pure_rotation", "--t-end", "6", "--quiet", "--csv",
                         str(path)]) == 0
        lines = path.read_text().splitlines()
        return lines[0], np.loadtxt(lines[1:], delimiter=",")

    for streamed in (False, True):
        head, fast = run(tmp_path / "fast.csv", streamed, False)
        head_ref, ref = run(tmp_path / "ref.csv", streamed, True)
        assert head == head_ref and "wheel_A.normal" in head and "mu_required_min" in head
        scale = np.max(np.abs(ref), axis=0)
        assert np.all(np.abs(fast - ref) <= RTOL * scale + 1e-300)


def test_cone_minimum_with_two_open_combinations_equals_its_closed_form():
    """d = 2 (SLSQP with its exact gradients): two pairs of wheels pushing against each other sideways, each pair
    along its own combination, fn = 1 and 2. Pair 1: max(|3 + z1|, |1 - z1|) is smallest at z1 = -1 (value 2); pair
    2: max(|5 + z2|, |z2 - 1|) / 2 is smallest at z2 = -2 (value 1.5); the minimum is the larger, 2. Mixing the
    combinations by a rotation (another orthonormal basis of the open space) changes nothing."""
    e1 = np.array([[0.0, 0.0], [1.0, 0.0]])
    e2 = np.array([[0.0, 0.0], [0.0, 1.0]])
    base = [(np.array([0.0, 3.0]), e1), (np.array([0.0, 1.0]), -e1), (np.array([0.0, 5.0]), e2),
            (np.array([0.0, -1.0]), e2)]
    fn = np.array([1.0, 1.0, 2.0, 2.0])
    c, s = np.cos(0.3), np.sin(0.3)
    for R in (np.eye(2), np.array([[c, -s], [s, c]])):
        assert cone_minimum([(b, T @ R) for b, T in base], fn, 2) == pytest.approx(2.0, abs=1e-7)
    base[2] = (np.array([0.0, 9.0]), e2)  # pair 2 now max(|9 + z2|, |z2 - 1|) / 2: at z2 = -4, 2.5 > 2
    assert cone_minimum(base, fn, 2) == pytest.approx(2.5, abs=1e-7)


def test_events_at_one_instant_come_in_a_fixed_order():
    """A wheel's slip and the any-split slip it sets, 1e-16 s apart either way (crossings interpolated in one sample
    interval), come in the same order: lift-offs, named wheels in the robot's order, then the any-split slip; events
    apart by more than 1e-12 s keep their time order."""
    from robotdyn.contact.traction import ANY_SPLIT, TractionEvent, _in_time_order

    wheels = ["w1", "w2"]
    t = 0.3247878101591285
    for dt in (1e-16, -1e-16):
        events = [TractionEvent("slip", ANY_SPLIT, t, 0.04), TractionEvent("slip", "w2", t + dt, 0.04),
                  TractionEvent("lift-off", "w1", t - dt, 0.0), TractionEvent("slip", "w1", t - 1e-9, 0.03)]
        order = [(e.kind, e.wheel) for e in _in_time_order(events, wheels)]
        assert order == [("slip", "w1"), ("lift-off", "w1"), ("slip", "w2"), ("slip", ANY_SPLIT)]
