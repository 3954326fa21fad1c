"""Output files (robotdyn.output): written atomically (a failure leaves an existing file as it was and no
temporary file behind), and bad targets refused in one line before any work is done."""

from __future__ import annotations

import numpy as np
import pytest

import robotdyn
from robotdyn.cli.commands import main
from robotdyn.errors import OutputError
from robotdyn.output import atomic_output, check_target


def test_failed_write_leaves_the_old_file(tmp_path, monkeypatch):
    robot = robotdyn.load("quasimoro")
    from robotdyn.robots import module

    traj = module("quasimoro").SCENARIOS["rectilinear"].run(robot, t_end=0.2, progress=False)
    target = tmp_path / "run.csv"
    target.write_text("precious\n")

    def broken(fname, *args, **kwargs):
        with open(fname, "w") as f:
            f.write("half a fi")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(np, "savetxt", broken)
    with pytest.raises(OutputError, match="No space left on device"):
        traj.to_csv(target)
    assert target.read_text() == "precious\n"
    assert [p.name for p in tmp_path.iterdir()] == ["run.csv"]
    monkeypatch.undo()
    traj.to_csv(target)
    assert target.read_text().startswith("t,x,y,psi")


def test_atomic_output_replaces_only_on_success(tmp_path):
    target = tmp_path / "a.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_output(target) as tmp:
            tmp.write_text("new")
            raise RuntimeError("stopped")
    assert target.read_text() == "old"
    with atomic_output(target) as tmp:
        tmp.write_text("new")
    assert target.read_text() == "new" and len(list(tmp_path.iterdir())) == 1


@pytest.mark.parametrize("args, message", [
    (["--csv", "{d}/missing/x.csv"], "does not exist"),
    (["--csv", "{d}"], "is a directory"),
    (["--plot", "{d}/x.xyz"], "unknown format '.xyz'"),
    (["--plot", "{d}/x"], "unknown format '(no extension)'"),
    (["--traction-plot", "{d}"], "is a directory"),
    (["--t-end", "1e300"], "output samples"),
    (["--t-end", "nan"], "expected a positive duration"),
    (["--t-end", "-1"], "expected a positive duration"),
    (["--t-end", "abc"], "--t-end: 'abc' is not a number"),
    (["--bogus"], "unrecognized arguments: --bogus"),
])
def test_simulate_bad_outputs_and_numbers_are_one_line(tmp_path, capsys, args, message):
    argv = ["simulate", "quasimoro", "--scenario", "rectilinear", "--quiet",
            *[a.format(d=tmp_path) for a in args]]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("robotdyn: error: ") and message in err
    assert "Traceback" not in err and "usage:" not in err


def test_argparse_errors_are_one_line(capsys):
    for argv in (["frobnicate"], ["dump", "quasimoro"], [], ["simulate"]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith("robotdyn: error: ") and "usage:" not in err


@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")
def test_huge_states_are_refused_not_returned(capsys):
    robot = robotdyn.load("quasimoro")
    with pytest.raises(robotdyn.errors.NonFiniteError, match="not finite"):
        robot.reduced(robot.neutral(), [1e300, 1.0, 1.0])
    assert main(["dump", "quasimoro", "--q", "0", "0", "0", "0", "0", "0.3", "--v", "1e200", "1e200", "1e200",
                 "--tau", "1", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "v[theta1_dot] = 1e+200" in err and "expected |v| <= 1e+06" in err
    assert main(["simulate", "omni_caster", "--scenario", "circle", "--t-end", "inf", "--quiet"]) == 2
    assert "expected a positive duration" in capsys.readouterr().err


def test_check_target_accepts_a_plain_file_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert check_target("out.png", suffixes=("png",)).name == "out.png"


def test_negative_numbers_in_scientific_notation_are_values(capsys):
    assert main(["dump", "quasimoro", "--q", "0", "0", "0", "0", "0", "0.3", "--v", "1e-5", "-2e-5", "-.5E+1"]) == 0
    out = capsys.readouterr().out
    assert "theta1_dot" in out
    # every number of a table keeps a space on its left (no '-1.23457e-05-1.23457e-05' runs): rows of M, C and B
    # split into a label and exactly as many numbers as there are columns
    rows = [line.split() for line in out.splitlines() if line.startswith("    theta")]
    assert rows and all(len(r) in (2, 3, 4) and all(float(x) == float(x) for x in r[1:]) for r in rows)
    assert main(["dump", "quasimoro", "--q", "0", "0", "0", "0", "0", "0.3", "--v", "-1e-5", "-2e-5", "-3e-5"]) == 0
    rows = [line.split() for line in capsys.readouterr().out.splitlines() if line.startswith("    theta")]
    assert all(len(r) in (2, 3, 4) for r in rows)


@pytest.mark.parametrize("params, message", [
    (["M=0", "m=0", "J1=0", "J2=0"], "parameter M = 0 kg; expected a value > 0 kg"),  # the body carries the robot
    (["m=-1"], "parameter m = -1 kg; expected a value >= 0"),
    (["J2=-0.4"], "parameter J2 = -0.4 kg m^2; expected a value >= 0"),
    (["r=0"], "parameter r = 0 m; expected a value > 0 m"),
])
def test_physically_impossible_parameters_are_one_line(capsys, params, message):
    argv = ["dump", "quasimoro", "--q", "0", "0", "0", "0", "0", "0.3", "--v", "1", "0.5", "0.2", "--tau", "0.1", "0.1"]
    for p in params:
        argv += ["--param", p]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err and "Traceback" not in err
    assert main(["simulate", "quasimoro", "--scenario", "rectilinear", "--t-end", "0.5", "--quiet",
                 *[x for p in params for x in ("--param", p)]]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err


def test_dump_values_by_name(capsys):
    """--set NAME=VALUE sets coordinates by name (from the neutral configuration or --q), with one-line errors."""
    assert main(["dump", "quasimoro", "--set", "theta3=0.3", "--v", "1", "0.5", "0.2", "--json"]) == 0
    import json

    by_name = json.loads(capsys.readouterr().out)
    assert main(["dump", "quasimoro", "--q", "0", "0", "0", "0", "0", "0.3", "--v", "1", "0.5", "0.2", "--json"]) == 0
    by_position = json.loads(capsys.readouterr().out)
    assert by_name["M"] == by_position["M"] and by_name["q"] == by_position["q"]
    assert main(["dump", "quasimoro", "--set", "theta9=0.3", "--v", "1", "0.5", "0.2"]) == 2
    assert "unknown coordinate 'theta9'" in capsys.readouterr().err
    assert main(["dump", "quasimoro", "--set", "theta3=abc", "--v", "1", "0.5", "0.2"]) == 2
    assert "not a number" in capsys.readouterr().err
