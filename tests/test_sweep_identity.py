"""A sweep directory's identity and ownership (issue 24): a sweep resumed after a file its description includes
changed (wheel masses x3 in an included Xacro file) reused the old runs ("0 computed, 2 resumed"); a sweep written
into a directory holding another sweep replaced its results without a word; two sweeps could write one directory
at once. Now every run id covers the expanded description (the content of every included file), a directory
holding other runs is refused in one line unless replaced, and the directory is locked while a sweep writes it."""

from __future__ import annotations

from pathlib import Path

import pytest

from robotdyn.cli.commands import main
from robotdyn.errors import OutputError
from robotdyn.sweep import runner as sweep
from robotdyn.sweep import store
from robotdyn.sweep.spec import SweepSpec, parse_axis

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
COMMON = Path(__file__).resolve().parents[1] / "urdf" / "common.xacro"


@pytest.fixture()
def rover(tmp_path) -> Path:
    """The skid-steer example whose wheel mass comes from an included file, ``mass.xacro``."""
    xacro = (EXAMPLES / "skid_steer.urdf.xacro").read_text()
    xacro = xacro.replace('<xacro:include filename="../urdf/common.xacro"/>',
                          f'<xacro:include filename="{COMMON}"/>\n  <xacro:include filename="mass.xacro"/>')
    xacro = xacro.replace('<xacro:property name="mw" value="$(arg m_wheel)"/>', "")
    assert "mass.xacro" in xacro and 'name="mw"' not in xacro
    (tmp_path / "rover.urdf.xacro").write_text(xacro)
    (tmp_path / "mass.xacro").write_text('<robot xmlns:xacro="http://www.ros.org/wiki/xacro">'
                                         '<xacro:property name="mw" value="1.0"/></robot>')
    toml = (EXAMPLES / "skid_steer.toml").read_text().replace('urdf = "skid_steer.urdf.xacro"',
                                                              'urdf = "rover.urdf.xacro"')
    (tmp_path / "rover.toml").write_text(toml)
    return tmp_path / "rover.toml"


def spec(rover: Path, scales: str = "0.5,1") -> SweepSpec:
    return SweepSpec(constraints=str(rover), axes=[parse_axis(f"torque_scale={scales}")], scenarios=["straight"],
                     t_end=0.2, n_out=5, columns=["x"])


def test_a_changed_included_file_is_not_resumed(rover, tmp_path):
    out = tmp_path / "sweep"
    first = sweep.run(spec(rover), out, workers=0, progress=False, plot=False)
    assert (first.computed, first.resumed) == (2, 0)
    again = sweep.run(spec(rover), out, workers=0, progress=False, plot=False)
    assert (again.computed, again.resumed) == (0, 2)  # nothing changed: resumed
    (tmp_path / "mass.xacro").write_text((tmp_path / "mass.xacro").read_text().replace('"1.0"', '"3.0"'))
    with pytest.raises(OutputError, match="an input changed since it ran") as err:
        sweep.run(spec(rover), out, workers=0, progress=False, plot=False)
    assert "\n" not in str(err.value) and "--replace" in str(err.value)
    redone = sweep.run(spec(rover), out, workers=0, progress=False, plot=False, replace=True)
    assert (redone.computed, redone.resumed) == (2, 0)
    # heavier wheels, same torques: the rover covers less ground than with the old masses
    old, new = first.frame().sort_values("torque_scale"), redone.frame().sort_values("torque_scale")
    assert all(new["max.x"].to_numpy() < old["max.x"].to_numpy())
    assert redone.table.num_rows == 2 and len(store.finished(out)) == 2  # the old rows are gone


def test_a_directory_holding_another_sweep_is_refused_unless_replaced(rover, tmp_path, capsys):
    out = tmp_path / "sweep"
    sweep.run(spec(rover), out, workers=0, progress=False, plot=False)
    with pytest.raises(OutputError, match="holds another sweep"):
        sweep.run(spec(rover, "2,3"), out, workers=0, progress=False, plot=False)
    assert sorted(store.finished(out).values()) == ["ok", "ok"]  # untouched
    argv = ["sweep", "--constraints", str(rover), "--vary", "torque_scale=2,3", "--scenario", "straight", "--t-end",
            "0.2", "--n-out", "5", "--column", "x", "--workers", "0", "--out", str(out), "--quiet", "--no-plot"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "holds another sweep" in err[0]
    assert main(argv + ["--replace"]) == 0
    capsys.readouterr()
    table = sweep.load(out)
    assert sorted(table.torque_scale) == [2.0, 3.0]


def test_a_locked_directory_is_refused_naming_the_holder(rover, tmp_path):
    out = store.prepare(tmp_path / "sweep")
    held = store.lock(out)
    try:
        with pytest.raises(OutputError, match=r"is being written by pid \d+ on ") as err:
            sweep.run(spec(rover), out, workers=0, progress=False, plot=False)
        assert "\n" not in str(err.value)
        assert not list((out / "runs").iterdir())  # nothing written
    finally:
        held.release()
    assert sweep.run(spec(rover), out, workers=0, progress=False, plot=False).computed == 2
