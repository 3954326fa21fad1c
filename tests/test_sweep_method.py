"""A sweep file's ``method`` (and ``rtol``/``atol``) reach the integrator of every run, as simulate(method=...)
takes them, and a bad one is refused at load with simulate's own line (one story: a feature of simulate is a key
of the sweep file, checked by the same function)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from robotdyn.errors import RobotDynError
from robotdyn.fast.compiled import available
from robotdyn.interfaces.constraint_file import read
from robotdyn.simulation.compiled_engine import check_method
from robotdyn.simulation.run_options import check_tolerance
from robotdyn.sweep import load, run
from robotdyn.sweep.plan import plan
from robotdyn.sweep.spec import SweepSpecError, from_toml

BUMP = Path(__file__).resolve().parents[1] / "examples" / "bump_base.toml"
OPTIONS = dict(t_end=0.02, n_out=5, rtol=1e-9, atol=1e-11)


def _spec(tmp_path: Path, **keys):
    lines = [f'constraints = "{BUMP}"', 'scenarios = ["bump"]'] + [f"{k} = {v!r}" for k, v in keys.items()]
    path = tmp_path / "study.toml"
    path.write_text("\n".join(lines).replace("'", '"') + "\n")
    return from_toml(path)


@pytest.mark.skipif(not available(), reason="the compiled extension was not built")
def test_cvode_sweep_equals_simulate_cvode(tmp_path):
    """The compliant base's sweep run with method = "cvode" holds the numbers of simulate(method="cvode") bit for
    bit (final state and evaluation count); its default integrator gives other numbers (the key is not ignored)."""
    spec = _spec(tmp_path, method="cvode", **OPTIONS)
    run(spec, tmp_path / "out", workers=0, progress=False, plot=False)
    row = load(tmp_path / "out").iloc[0]
    assert row["status"] == "ok", row["error"]
    robot = read(BUMP).robot()
    scenario = read(BUMP).SCENARIOS["bump"]
    cvode = scenario.run(robot, method="cvode", progress=False, **OPTIONS)
    default = scenario.run(robot, progress=False, **OPTIONS)
    assert cvode.stats["engine"] == "compiled (cvode)" and default.stats["engine"] != cvode.stats["engine"]
    assert row["nfev"] == cvode.stats["nfev"] != default.stats["nfev"]
    final = np.concatenate([cvode.q[-1], cvode.nu[-1]])
    names = list(robot.coordinates) + list(robot.velocity_names)
    assert [row[f"final.{c}"] for c in names] == final.tolist()


@pytest.mark.parametrize("keys, check", [({"method": "cvod"}, lambda: check_method("cvod")),
                                         ({"rtol": 0.0}, lambda: check_tolerance("rtol", 0.0)),
                                         ({"atol": 2.0}, lambda: check_tolerance("atol", 2.0))])
def test_bad_integrator_options_are_refused_at_load_with_simulates_line(tmp_path, keys, check):
    with pytest.raises(RobotDynError) as simulate_says:
        check()
    with pytest.raises(SweepSpecError) as sweep_says:
        plan(_spec(tmp_path, **keys))
    assert str(sweep_says.value) == str(simulate_says.value) and "\n" not in str(sweep_says.value)
