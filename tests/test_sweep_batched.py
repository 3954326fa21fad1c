"""Sweeps whose runs are simulated as variants of one compiled model (robotdyn.sweep.batched): each row is the run
of its model vector alone through ``simulate`` (bit for bit), agrees with the robot built from the run's parameters
to the integrator's accuracy, does not depend on workers, chunks or resumption, and a sweep says which runs were
built one at a time and why."""

from __future__ import annotations

import numpy as np
import pytest

import robotdyn
from robotdyn.errors import RobotDynError
from robotdyn.fast.dispatch import available, use_compiled
from robotdyn.robots import module
from robotdyn.simulation.engine import simulate
from robotdyn.simulation.model_variants import variant
from robotdyn.sweep import batched, runner as sweep
from robotdyn.sweep.plan import plan
from robotdyn.sweep.spec import SweepSpec, parse_axis

pytestmark = pytest.mark.skipif(not available(), reason="compiled extension not built")

QUASIMORO = module("quasimoro")
TIMES = ("wall", "run_wall")


def lhs(n: int = 8, **kw) -> SweepSpec:
    base = dict(robot="quasimoro", sample="lhs", n=n, seed=3, t_end=1.0, columns=["theta3"],
                axes=[parse_axis(a) for a in ("M=4:6", "d=0.1:0.2", "J1=0.15:0.25", "torque_scale=0.5:2")])
    return SweepSpec(**{**base, **kw})


def numbers(res) -> dict:
    return {k: v for k, v in res.table.to_pydict().items() if k not in TIMES}


@pytest.fixture(scope="module")
def always(tmp_path_factory):
    return sweep.run(lhs(), tmp_path_factory.mktemp("always"), workers=0, progress=False, plot=False, batch="always")


def test_a_row_is_its_model_vector_run_alone(always):
    """The batched row's final state is, to the bit, ``simulate`` on the robot of the run's model vector (the
    vectors the sweep planned) with the run's scaled torque profile."""
    assert always.batched == 8 and always.notes == [] and always.statuses["ok"] == 8
    p = plan(lhs())
    vectors = batched.model_vectors(p.context, p.runs, "always").vectors
    base = robotdyn.load("quasimoro")
    frame = always.frame().set_index("run_id")
    names = base.coordinates + base.velocity_names
    sc = QUASIMORO.SCENARIOS["rectilinear"]
    for run in p.runs[:3]:
        robot = variant(base, vectors[run.run_id])
        q0, nu0 = sc.initial_state(robot)
        t_end, n_out = sc.span(1.0, None)
        alone = simulate(robot, t_end, q0, nu0, sc.torque.scaled(run.torque_scale), n_out=n_out, progress=False)
        row = frame.loc[run.run_id]
        assert [row[f"final.{c}"] for c in names] == np.concatenate([alone.q[-1], alone.nu[-1]]).tolist()
        assert row["energy.start"] == alone.energy[0] and row["max.theta3"] == alone.column("theta3").max()


def test_rows_agree_with_robots_built_from_the_parameters(always, tmp_path):
    """Against each run built from its parameters (Xacro, URDF, Pinocchio: batch = never): the starting energy,
    which depends on the model alone, to 1e-12 relative (the fit); the final states to the integration's
    accuracy (rtol 1e-10 over 1 s: 1e-7 relative)."""
    built = sweep.run(lhs(), tmp_path, workers=0, progress=False, plot=False, batch="never")
    assert built.batched == 0 and built.notes == ["batch = never: every run is built from its parameters"]
    a, b = always.frame().sort_values("run_index"), built.frame().sort_values("run_index")
    assert np.allclose(a["energy.start"], b["energy.start"], rtol=1e-12, atol=0)
    for c in ("final.x", "final.theta1", "final.theta3", "final.theta1_dot", "final.theta3_dot", "max.theta3"):
        scale = np.max(np.abs(b[c]))
        assert np.max(np.abs(a[c] - b[c])) <= 1e-7 * scale, c
    assert not np.array_equal(a["final.theta3_dot"], b["final.theta3_dot"])  # two computations, not one


def test_same_bits_on_two_workers_and_after_resuming(always, tmp_path, monkeypatch):
    """The model vectors travel with the chunks: 2 Dask workers, other chunk sizes and an interrupted sweep
    resumed give the in-process rows, bit for bit."""
    two = sweep.run(lhs(), tmp_path / "two", workers=2, chunk_size=3, progress=False, plot=False, batch="always")
    assert numbers(two) == numbers(always) and two.batched == 8
    calls = []
    real = sweep.run_chunk

    def interrupting(ctx, runs, vectors=None):
        calls.append(len(runs))
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(ctx, runs, vectors)

    monkeypatch.setattr(sweep, "run_chunk", interrupting)
    first = sweep.run(lhs(), tmp_path / "resumed", workers=0, chunk_size=3, progress=False, plot=False,
                      batch="always")
    assert first.interrupted and first.computed == 3
    monkeypatch.setattr(sweep, "run_chunk", real)
    again = sweep.run(lhs(), tmp_path / "resumed", workers=0, chunk_size=5, progress=False, plot=False,
                      batch="always")
    assert again.resumed == 3 and again.computed == 5 and numbers(again) == numbers(always)


def test_which_runs_are_built_one_at_a_time_and_why(tmp_path):
    """auto batches a group only when it has at least twice the robots its fit builds; without the compiled path
    nothing is batched; each cause is one line of ``notes``."""
    assert batched.fit_builds(3) == 1 + 3 + 20 + 6
    small = sweep.run(lhs(), tmp_path / "small", workers=0, progress=False, plot=False)
    assert small.batched == 0
    assert small.notes == ["8 runs built one at a time: fewer than twice the 30 robots a fit of M, d, J1 builds "
                           "(batch = always fits anyway)"]
    scales = SweepSpec(robot="quasimoro", axes=[parse_axis("torque_scale=0.5,1,2")], t_end=0.5)
    assert sweep.run(scales, tmp_path / "scales", workers=0, progress=False, plot=False).batched == 3  # no fit
    with use_compiled(False):
        off = sweep.run(lhs(), tmp_path / "off", workers=0, progress=False, plot=False, batch="always")
    assert off.batched == 0 and "compiled fast path is off" in off.notes[0]
    with pytest.raises(RobotDynError, match="batch = 'sometimes'; expected one of auto, always, never"):
        sweep.run(lhs(), tmp_path / "bad", workers=0, progress=False, batch="sometimes")


def test_a_large_enough_sweep_is_batched_by_default(tmp_path):
    """60 runs of a 3-parameter sweep (twice the fit's 30 builds): batched under auto, every run ok."""
    res = sweep.run(lhs(n=60, t_end=0.3), tmp_path, workers=0, progress=False, plot=False)
    assert res.batched == 60 and res.statuses["ok"] == 60 and res.notes == []


def test_guided_chunks_cover_the_runs_in_order_large_first():
    """Batched sweeps go out in guided chunks: every run once, in order, sizes non-increasing from at most the
    cap down to 8 (the last may be smaller), a quarter of what is left per worker."""
    from robotdyn.sweep.runner import _chunks

    runs = list(range(2000))
    chunks = _chunks(runs, 250, 2)
    assert [r for c in chunks for r in c] == runs
    sizes = [len(c) for c in chunks]
    assert sizes[0] == 250 and sizes[1] == 219 and all(a >= b for a, b in zip(sizes, sizes[1:]))
    assert min(sizes[:-1]) == 8 and sizes[-1] <= 8
    assert [len(c) for c in _chunks(runs[:10], 4)] == [4, 4, 2]  # without workers: fixed size
