"""Start-up of the CLI (issue 17): `robotdyn info` imports neither scipy nor yourdfpy once the description was
validated before (robotdyn.description.urdf keeps a cache of validated URDF texts), the cache never lets an invalid
description through, and `make bench` reports the wall time."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from robotdyn.description.urdf import validate_urdf
from robotdyn.errors import DescriptionError

PROBE = ("import sys, io, contextlib, robotdyn.cli.commands as c\n"
         "with contextlib.redirect_stdout(io.StringIO()): rc = c.main(['info', 'quasimoro'])\n"
         "print(rc, 'scipy' in sys.modules, 'yourdfpy' in sys.modules, 'matplotlib' in sys.modules)")


def test_info_imports_no_scipy_yourdfpy_or_matplotlib(tmp_path):
    env = {**os.environ, "ROBOTDYN_CACHE": str(tmp_path)}
    first = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, env=env, check=True)
    rc, _, with_yourdfpy, _ = first.stdout.split()
    assert (rc, with_yourdfpy) == ("0", "True")  # validated once, with yourdfpy (which imports scipy)
    again = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, env=env, check=True)
    assert again.stdout.split() == ["0", "False", "False", "False"]
    assert (tmp_path / "validated-urdf.txt").read_text().count("yourdfpy-") == 1


def test_cache_never_admits_an_invalid_description(tmp_path, monkeypatch):
    monkeypatch.setenv("ROBOTDYN_CACHE", str(tmp_path))
    good = ('<robot name="r"><link name="a"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" '
            'ixz="0" iyz="0"/></inertial></link></robot>')
    validate_urdf(good)
    validate_urdf(good)  # from the cache
    bad = good.replace('mass value="1"', 'mass value="-1"')
    for _ in range(2):
        with pytest.raises(DescriptionError):
            validate_urdf(bad)
