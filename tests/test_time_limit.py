"""``robotdyn simulate --time-limit SECONDS`` (issue 24): a wheel of the linear tyre law with stiffness = 1e12 s/m
(allowed by the schema) needs steps of about 1e-14 s, so the run did not end in any useful time and the CLI had no
limit. Past the limit the run stops like an interrupted one: the samples so far are written with the partial
marker, one line on stderr names the limit and the time reached, and the exit status is 124 (in memory and
streamed)."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

from robotdyn.cli import main

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "skid_steer.toml"


@pytest.fixture()
def stiff(tmp_path) -> Path:
    text = EXAMPLE.read_text().replace("stiffness = 5.0", "stiffness = 1e12").replace(
        'urdf = "skid_steer.urdf.xacro"', f'urdf = "{EXAMPLE.parent / "skid_steer.urdf.xacro"}"')
    path = tmp_path / "stiff.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("streamed", [False, True])
def test_time_limit_stops_a_stiff_run_with_a_marked_partial_file(stiff, tmp_path, capsys, monkeypatch, streamed):
    if streamed:  # more samples than a segment: simulate --csv streams
        monkeypatch.setattr("robotdyn.simulation.streaming.SEGMENT", 10)
    csv = tmp_path / "run.csv"
    start = time.perf_counter()
    status = main(["simulate", "--constraints", str(stiff), "--scenario", "straight", "--quiet", "--csv", str(csv),
                   "--time-limit", "1"])
    wall = time.perf_counter() - start
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 124
    assert wall < 20  # the limit (1 s) plus loading and writing; without it the run does not end
    assert len(err) == 2 and err[0].startswith("robotdyn: warning: wheel(s) front_left")  # the stiffness
    assert err[1].startswith("robotdyn: time limit of 1 s reached")
    reached = float(err[1].split("samples up to t = ")[1].split(" s")[0])
    lines = csv.read_text().splitlines()
    assert lines[-1].startswith("# partial: ") and "samples up to t = " in lines[-1]
    assert lines[-1].startswith("# partial: time limit of 1 s reached")  # streamed too (it said "interrupted")
    data = np.loadtxt(lines[1:-1], delimiter=",", ndmin=2)
    assert data[-1, 0] == pytest.approx(reached, abs=1e-12) and reached < 2.0
    assert not (tmp_path / "run.csv.partial").exists()


def test_time_limit_is_documented_and_checked(capsys):
    with pytest.raises(SystemExit):
        main(["simulate", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert "--time-limit SECONDS" in out and "exit status is 124" in out
    assert main(["simulate", "quasimoro", "--scenario", "rectilinear", "--time-limit", "0"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--time-limit" in err[0]


def test_a_run_within_its_limit_is_unchanged(tmp_path, capsys):
    assert main(["simulate", "quasimoro", "--scenario", "rectilinear", "--t-end", "0.5", "--quiet", "--csv",
                 str(tmp_path / "a.csv"), "--time-limit", "60"]) == 0
    assert main(["simulate", "quasimoro", "--scenario", "rectilinear", "--t-end", "0.5", "--quiet", "--csv",
                 str(tmp_path / "b.csv")]) == 0
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()


def test_a_friction_law_too_stiff_for_the_run_is_named_in_one_warning(stiff):
    """k = 1e12 s/m: slip relaxes at k g = 9.81e12 1/s, so 2 s need at least 2e13 steps (> 1e8): one warning naming
    the four wheels and the largest k usable for 2 s, 1e8 / (9.81 * 2) = 5.1e6 s/m. The example's k = 5 s/m (98 steps
    a second) says nothing."""
    import warnings

    from robotdyn.errors import RobotDynWarning
    from robotdyn.interfaces.constraint_file import load_robot
    from robotdyn.simulation.engine import stiff_slip_warning

    robot = load_robot(stiff)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        stiff_slip_warning(robot, 2.0)
    [w] = [w for w in caught if issubclass(w.category, RobotDynWarning)]
    text = str(w.message)
    assert "front_left, front_right, rear_left, rear_right" in text and "k = 1e+12 s/m" in text
    assert "2e+13 integration steps" in text and "k <= 5.1e+06 s/m" in text
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        stiff_slip_warning(load_robot(EXAMPLE), 2.0)
    assert not [w for w in caught if issubclass(w.category, RobotDynWarning)]
