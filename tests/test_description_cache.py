"""The cache of expanded descriptions (robotdyn.description.cache): a hit returns exactly what xacro would, and
any change to what the expansion depends on (an included file, an argument, the packages) is a miss."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from robotdyn.description import cache as description_cache
from robotdyn.description import expand_xacro

MAIN = """<?xml version="1.0"?>
<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:arg name="mass" default="1.0"/>
  <xacro:include filename="part.xacro"/>
  <link name="base"><inertial><mass value="$(arg mass)"/>
    <inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <xacro:part/>
</robot>
"""
PART = """<?xml version="1.0"?>
<robot xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:macro name="part"><link name="PART_NAME"/></xacro:macro>
</robot>
"""


@pytest.fixture
def files(tmp_path, monkeypatch):
    monkeypatch.setenv("ROBOTDYN_CACHE", str(tmp_path / "cache"))
    (tmp_path / "d").mkdir()
    main = tmp_path / "d" / "robot.xacro"
    main.write_text(MAIN)
    (tmp_path / "d" / "part.xacro").write_text(PART.replace("PART_NAME", "wheel"))
    return main


def entries(main):
    return list((main.parent.parent / "cache" / "xacro").glob("*.json"))


def test_hit_is_the_expansion_and_changes_are_misses(files, monkeypatch):
    first = expand_xacro(files, {"mass": 2.0})
    assert '<link name="wheel"/>' in first and 'value="2.0"' in first and len(entries(files)) == 1
    calls = []
    real = description_cache.store
    monkeypatch.setattr(description_cache, "store", lambda *a: (calls.append(1), real(*a)))
    assert expand_xacro(files, {"mass": 2.0}) == first and calls == []  # served from the cache
    assert 'value="3.0"' in expand_xacro(files, {"mass": 3.0}) and calls == [1]  # another argument: expanded
    (files.parent / "part.xacro").write_text(PART.replace("PART_NAME", "castor"))  # an included file changed
    assert '<link name="castor"/>' in expand_xacro(files, {"mass": 2.0}) and calls == [1, 1]


def test_environment_dependent_descriptions_are_never_cached(files, monkeypatch):
    files.write_text(MAIN.replace('default="1.0"', 'default="$(optenv ROBOT_MASS 1.0)"'))
    monkeypatch.setenv("ROBOT_MASS", "4.0")
    assert 'value="4.0"' in expand_xacro(files)
    monkeypatch.setenv("ROBOT_MASS", "5.0")
    assert 'value="5.0"' in expand_xacro(files) and entries(files) == []


def test_a_corrupt_or_foreign_entry_is_a_miss(files):
    good = expand_xacro(files)
    [entry] = entries(files)
    entry.write_text("{not json")
    assert expand_xacro(files) == good
    data = json.loads(entry.read_text())
    data["files"] = {k: "0" * 64 for k in data["files"]}  # hashes of other contents
    data["urdf"] = "<robot name='forged'/>"
    entry.write_text(json.dumps(data))
    assert expand_xacro(files) == good


def test_off_switch_and_no_xacro_import_on_a_hit(files, tmp_path):
    probe = ("import sys; from robotdyn.description import expand_xacro\n"
             f"text = expand_xacro({str(files)!r}); print('xacro' in sys.modules, len(text))")
    env = {**os.environ, "ROBOTDYN_CACHE": str(tmp_path / "cache")}
    runs = [subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env, check=True)
            .stdout.split() for _ in range(2)]
    assert runs[0][0] == "True" and runs[1][0] == "False" and runs[0][1] == runs[1][1]
    off = {**env, "ROBOTDYN_CACHE": "off"}
    again = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=off, check=True)
    assert again.stdout.split()[0] == "True"


def test_the_cache_keeps_a_bounded_number_of_entries(files, monkeypatch):
    """A sweep expands a new variant per run: the oldest entries go beyond MAX_ENTRIES, the newest stay hits."""
    import time

    monkeypatch.setattr(description_cache, "MAX_ENTRIES", 3)
    for mass in (1.0, 2.0, 3.0, 4.0, 5.0):
        expand_xacro(files, {"mass": mass})
        time.sleep(0.01)  # distinct modification times
    assert len(entries(files)) == 3
    calls = []
    real = description_cache.store
    monkeypatch.setattr(description_cache, "store", lambda *a: (calls.append(1), real(*a)))
    expand_xacro(files, {"mass": 5.0})
    assert calls == []  # the newest is still cached
    expand_xacro(files, {"mass": 1.0})
    assert calls == [1]  # the oldest was removed
