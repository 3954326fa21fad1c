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


DUMP_PROBE = ("import sys, io, contextlib, robotdyn.cli.commands as c\n"
              "with contextlib.redirect_stdout(io.StringIO()):\n"
              "    rc = c.main('dump quasimoro --q 0 0 0 0 0 0.3 --v 1 0.5 0.2'.split())\n"
              "print(rc, sorted(m for m in sys.modules if m.split('.')[0] in ('scipy', 'yourdfpy', 'trimesh', "
              "'matplotlib') or m.split('.')[:2] == ['numpy', 'ma']))")


def test_dump_imports_no_scipy_package_nor_numpy_ma(tmp_path):
    """`robotdyn dump` takes its pivoted QR and solves from scipy's compiled LAPACK module alone (not the ~0.3 s
    scipy.linalg package), and its index complements without np.unique (whose first call imports numpy.ma)."""
    env = {**os.environ, "ROBOTDYN_CACHE": str(tmp_path)}
    subprocess.run([sys.executable, "-c", DUMP_PROBE], capture_output=True, text=True, env=env, check=True)
    again = subprocess.run([sys.executable, "-c", DUMP_PROBE], capture_output=True, text=True, env=env, check=True)
    assert again.stdout.strip() == "0 []"


LAPACK_PROBE = """
import sys
import numpy as np
from robotdyn.reduction import projection as P

lapack = P._lapack()
assert not [m for m in sys.modules if m.split('.')[0] == 'scipy'], 'scipy imported'
rng = np.random.default_rng(7)
mats = [rng.standard_normal(shape) for shape in ((3, 6), (6, 3), (5, 9), (9, 9), (1, 4))]
low = rng.standard_normal((7, 3)) @ rng.standard_normal((3, 8))  # rank 3
mats += [low, low.T, np.vstack([low[:2], low[:2], 2 * low[:1]]), np.round(rng.standard_normal((6, 6)))]
mats += [np.array([[1.0, 0, 0, 1, 0, 0], [0, 1, 0, 0, 1, 0], [1, 0, 0, 1, 0, 0]])]
ours = [P._pivoted_qr(a) for a in mats]
B = rng.standard_normal((4, 2))
A = rng.standard_normal((4, 4))
x = P.solve(A, B)

import scipy.linalg
import scipy.linalg.lapack

assert lapack.dgeqp3 is scipy.linalg.lapack.dgeqp3 and lapack.dgesv is scipy.linalg.lapack.dgesv
for a, (diag, piv) in zip(mats, ours):
    _, R, ref = scipy.linalg.qr(a, mode='economic', pivoting=True)
    assert np.array_equal(np.diag(R), diag) and np.array_equal(ref, piv), a
assert np.array_equal(x, scipy.linalg.solve(A, B)) or np.array_equal(x, np.linalg.solve(A, B))
print('ok')
"""


def test_lapack_loaded_alone_is_scipys_own():
    """The LAPACK module loaded without the scipy.linalg package holds scipy.linalg.lapack's very functions: the
    same pivots and numbers as scipy.linalg.qr(pivoting=True), bit for bit."""
    out = subprocess.run([sys.executable, "-c", LAPACK_PROBE], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "ok"


def test_lapack_falls_back_to_scipy_linalg(monkeypatch):
    """Where scipy's compiled LAPACK module cannot be loaded alone, scipy.linalg.lapack is imported."""
    import importlib.util

    import scipy.linalg.lapack

    from robotdyn.reduction import projection

    monkeypatch.delitem(sys.modules, "scipy.linalg._flapack", raising=False)
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, package=None: None)
    assert projection._flapack() is scipy.linalg.lapack


def test_complement_without_unique_matches_setdiff1d():
    import numpy as np

    from robotdyn.reduction.projection import _others

    rng = np.random.default_rng(0)
    for _ in range(2000):
        n = int(rng.integers(0, 10))
        idx = rng.integers(-3, 13, size=int(rng.integers(0, 8)))
        ref = np.setdiff1d(np.arange(n), idx)
        got = _others(n, idx)
        assert got.dtype == ref.dtype and np.array_equal(got, ref)


SAMPLES = {
    "list": ["list", "--json"],
    "info": ["info", "quasimoro", "--param", "M=6"],
    "dump": ["dump", "quasimoro", "--q", "0", "0", "0", "0", "0", "0.3", "--v", "1", "0.5", "0.2", "--tau", "1", "2"],
    "simulate": ["simulate", "quasimoro", "--scenario", "rectilinear", "--t-end", "1e-2", "--quiet"],
    "compare": ["compare", "quasimoro"],
    "view": ["view", "quasimoro", "--html", "x.html"],
    "sweep": ["sweep", "quasimoro", "--vary", "M=4,6", "--out", "d"],
    "linearize": ["linearize", "quasimoro", "--set", "theta3=3.14", "--states", "theta3", "theta3_dot"],
    "optimise": ["optimise", "quasimoro", "--t-end", "3", "--end", "x=1", "--bound", "theta3=-0.06:0.06"],
}


def test_a_command_parsed_alone_parses_as_with_all_commands():
    """`robotdyn CMD ...` builds CMD's parser alone (the others cost start-up time): the same arguments, help and
    errors as with the whole parser."""
    from robotdyn.cli.commands import BUILT_IN, build_parser
    from robotdyn.errors import RobotDynError

    full = build_parser()
    assert set(full.commands) == set(BUILT_IN) == set(SAMPLES)
    for name, argv in SAMPLES.items():
        alone = build_parser(name)
        assert list(alone.commands) == [name]
        assert alone.commands[name].format_help() == full.commands[name].format_help()
        assert vars(alone.parse_args(argv)) == vars(full.parse_args(argv))
        for bad in (argv + ["--no-such-option"], [name, "--json", "--json=1"]):
            errors = []
            for parser in (alone, full):
                with pytest.raises(RobotDynError) as exc:
                    parser.parse_args(bad)
                errors.append(str(exc.value))
            assert errors[0] == errors[1]
