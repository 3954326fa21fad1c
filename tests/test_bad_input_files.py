"""Inputs that are files and directories (issue 24): a FIFO or a device where a file is expected, symbolic links that
loop, search directories that never end, files far larger than any input. Each is refused in one line naming the
path, in bounded time, never read (a FIFO would block), never a traceback."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

import cli_run
from robotdyn.description.ros_packages import PackageIndex, crawl, package_name
from robotdyn.errors import InputError
from robotdyn.input_files import read_text, regular_file, resolved

ROOT = Path(__file__).resolve().parents[1]
SKID = ROOT / "examples" / "skid_steer.toml"
SKID_XACRO = ROOT / "examples" / "skid_steer.urdf.xacro"
SECONDS = 15
"""A case still running after this long is a hang (each takes well under a second)."""


def run_cli(argv, capsys) -> tuple[int, str, float]:
    """``main(argv)`` under an alarm of :data:`SECONDS`: (exit status, stderr, seconds)."""
    return cli_run.run_cli(argv, capsys, SECONDS)


def one_line(rc: int, err: str, *needles: str) -> None:
    lines = [line for line in err.splitlines() if not line.startswith("robotdyn: warning: ")]
    assert rc == 2, err
    assert len(lines) == 1 and lines[0].startswith("robotdyn: error: "), err
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])


def package(directory: Path, name: str) -> Path:
    directory.mkdir(parents=True)
    (directory / "package.xml").write_text(f"<package format='2'><name>{name}</name></package>")
    return directory


# ------------------------------------------------------------------------------------- crawling for packages
def test_fifo_named_package_xml_is_not_read(tmp_path):
    """A FIFO named package.xml (opening it blocks until a writer comes) is no manifest: skipped, and the real
    package beside it is found."""
    (tmp_path / "a_pipe").mkdir()
    os.mkfifo(tmp_path / "a_pipe" / "package.xml")
    package(tmp_path / "b_real", "real_pkg")
    with cli_run.deadline(SECONDS, "reading a FIFO named package.xml"):
        assert package_name(tmp_path / "a_pipe") is None
        assert crawl(tmp_path) == {"real_pkg": tmp_path / "b_real"}


def test_directory_of_symlinks_to_itself_is_crawled_once(tmp_path):
    """12 links to '.' in one directory: a naive crawl 6 levels deep visits 12^6 ~ 3e6 directories; each
    directory is visited once (by device and inode), so the crawl ends at once and still finds the package."""
    loops = tmp_path / "loops"
    loops.mkdir()
    for i in range(12):
        (loops / f"l{i}").symlink_to(".")
    (loops / "up").symlink_to("..")
    package(tmp_path / "pkg", "pkg")
    start = time.perf_counter()
    assert crawl(tmp_path) == {"pkg": tmp_path / "pkg"}
    assert time.perf_counter() - start < 2.0


def test_huge_search_directory_is_refused_in_one_line(tmp_path, monkeypatch):
    """Beyond MAX_CRAWL_DIRECTORIES directories a search directory is refused, naming it."""
    import robotdyn.description.ros_packages as rp

    monkeypatch.setattr(rp, "MAX_CRAWL_DIRECTORIES", 5)
    for i in range(8):
        (tmp_path / f"d{i}").mkdir()
    with pytest.raises(rp.DescriptionError, match="more than 5 directories") as exc:
        crawl(tmp_path)
    assert str(tmp_path) in str(exc.value)


def _package_toml(tmp_path: Path, extra: str) -> Path:
    text = SKID.read_text().replace('urdf = "skid_steer.urdf.xacro"', f'urdf = "{SKID_XACRO}"')
    path = tmp_path / "robot.toml"
    path.write_text(text + "\n" + extra + "\n" if extra.startswith("[") else
                    text.replace(f'urdf = "{SKID_XACRO}"', f'urdf = "{SKID_XACRO}"\n{extra}'))
    return path


def test_search_directory_with_fifo_and_link_loops_answers_in_one_line(tmp_path, capsys):
    """A constraint file whose description comes from package:// with a search directory holding a FIFO named
    package.xml and a directory of links to itself: the missing package is named, at once (it hung before)."""
    search = tmp_path / "search"
    (search / "pipe").mkdir(parents=True)
    os.mkfifo(search / "pipe" / "package.xml")
    (search / "loops").mkdir()
    for i in range(12):
        (search / "loops" / f"l{i}").symlink_to(".")
    toml = _package_toml(tmp_path, f'package_dirs = ["{search}"]')
    toml.write_text(toml.read_text().replace(f'urdf = "{SKID_XACRO}"', 'urdf = "package://nosuchpkg/r.urdf"'))
    rc, err, seconds = run_cli(["info", "--constraints", toml], capsys)
    one_line(rc, err, "nosuchpkg")
    assert seconds < 5


@pytest.fixture
def loop(tmp_path) -> Path:
    link = tmp_path / "selfloop"
    link.symlink_to("selfloop")
    return link


@pytest.mark.parametrize("how", ["--package DIR", "--package NAME=DIR", "package_dirs", "[packages]"])
def test_symlink_loops_are_one_line(how, loop, tmp_path, capsys):
    """A symbolic link to itself given as a package directory: one line naming it (a RuntimeError traceback
    before)."""
    if how == "--package DIR":
        argv = ["info", "--constraints", _package_toml(tmp_path, ""), "--package", loop]
    elif how == "--package NAME=DIR":
        argv = ["info", "--constraints", _package_toml(tmp_path, ""), "--package", f"foo={loop}"]
    elif how == "package_dirs":
        argv = ["info", "--constraints", _package_toml(tmp_path, f'package_dirs = ["{loop}"]')]
    else:
        argv = ["info", "--constraints", _package_toml(tmp_path, f'[packages]\nfoo = "{loop}"')]
    rc, err, _ = run_cli(argv, capsys)
    one_line(rc, err, str(loop), "loop of symbolic links")


def test_index_refuses_loops(loop):
    with pytest.raises(InputError, match="loop of symbolic links"):
        PackageIndex.create({"foo": loop}, environment=False)
    with pytest.raises(InputError, match="loop of symbolic links"):
        PackageIndex.create(dirs=[loop], environment=False)


# ---------------------------------------------------------------------------------------------- the helpers
def test_helpers_refuse_fifo_device_directory_and_size(tmp_path, loop):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    with pytest.raises(InputError, match="named pipe"):
        read_text(fifo, "sweep file", 100)
    with pytest.raises(InputError, match="device"):
        read_text("/dev/zero", "sweep file", 100)
    with pytest.raises(InputError, match="directory"):
        regular_file(tmp_path, "sweep file", 100)
    big = tmp_path / "big.toml"
    big.write_text("x" * 101)
    with pytest.raises(InputError, match="101 bytes; expected at most 100"):
        read_text(big, "sweep file", 100)
    with pytest.raises(InputError, match="loop of symbolic links"):
        resolved(loop / "x", "--package")
    small = tmp_path / "ok.toml"
    small.write_text("a = 1\n")
    assert read_text(small, "sweep file", 100) == "a = 1\n"
