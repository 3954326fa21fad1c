"""The documentation's promises that can be checked without building the site (seconds): one version everywhere,
the pointers a newcomer needs (``--version``, ``--help`` naming the file-format page, ``load("x.toml")`` naming
``load_robot``), the constraint-file reference covering the schema exactly, no mention of folders outside the
repository, notebooks importing nothing from ``tests/``, and the site checker (``tools/check_site.py``, run by
``make docs`` on the built site) failing on each kind of defect it exists to catch.
"""

from __future__ import annotations

import importlib.util
import json
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

import robotdyn
from robotdyn.cli.commands import main
from robotdyn.errors import RobotDynError
from robotdyn.interfaces import constraint_reference
from robotdyn.interfaces.constraint_schema import SCHEMA

ROOT = Path(__file__).resolve().parent.parent
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())


def _check_site():
    spec = importlib.util.spec_from_file_location("check_site", ROOT / "tools" / "check_site.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_one_version_everywhere(capsys):
    version = PYPROJECT["project"]["version"]
    assert robotdyn.__version__ == version
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    assert capsys.readouterr().out.strip() == f"robotdyn {version}"
    cff = (ROOT / "CITATION.cff").read_text()
    assert re.search(r"^version: (\S+)$", cff, re.M).group(1) == version
    assert f"## {version}" in (ROOT / "CHANGELOG.md").read_text()


def test_licence_file_matches_the_declared_licence():
    assert PYPROJECT["project"]["license"] == "BSD-3-Clause"
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("BSD 3-Clause License")
    assert "Neither the name of the copyright holder" in text  # the third clause


def test_help_names_the_file_format_page(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    out = capsys.readouterr().out
    page = re.search(r"(docs/reference/[\w-]+\.md)", out).group(1)
    assert (ROOT / page).is_file()


def test_load_of_a_file_names_load_robot():
    with pytest.raises(RobotDynError, match=r"robotdyn\.load_robot"):
        robotdyn.load("my.toml")
    assert robotdyn.load_robot.__module__ == "robotdyn.interfaces.constraint_file"


def test_constraint_reference_covers_the_schema_exactly(monkeypatch):
    keys = [r.key for r in constraint_reference.rows()]
    assert len(keys) == len(set(keys)) == len(constraint_reference.KEYS)
    top = [k for k in keys if "." not in k]
    assert top == list(SCHEMA["properties"])  # every top-level key, in the schema's order
    assert "wheels[].radius" in keys and "terrain.kind" in keys and "twist.axes" in keys
    table = constraint_reference.markdown_table()
    assert table.count("\n") == len(keys) + 1
    # a key the schema gains without a reference entry fails the docs build (and this test)
    missing = dict(constraint_reference.KEYS)
    del missing["wheels[].mu"]
    monkeypatch.setattr(constraint_reference, "KEYS", missing)
    with pytest.raises(KeyError, match=r"wheels\[\]\.mu"):
        constraint_reference.rows()


def _tracked(*patterns: str) -> list[Path]:
    out = subprocess.run(["git", "ls-files", *patterns], cwd=ROOT, capture_output=True, text=True, check=True).stdout
    return [ROOT / p for p in out.split()]


def test_no_mention_of_folders_outside_the_repository():
    files = _tracked("README.md", "docs", "notebooks", "robotdyn", "urdf", "tools", "examples")
    hits = [f"{p.relative_to(ROOT)}:{i}" for p in files if p.suffix in (".md", ".py", ".ipynb", ".xacro", ".toml", ".rst")
            for i, line in enumerate(p.read_text(errors="replace").splitlines(), 1)
            if re.search(r"shared/(papers|notes)", line)]
    assert not hits, hits


def test_notebooks_import_nothing_from_tests():
    for path in _tracked("notebooks/*.ipynb"):
        for cell in json.loads(path.read_text())["cells"]:
            if cell["cell_type"] == "code":
                src = "".join(cell["source"])
                assert not re.search(r"\boracles\b|[\"']tests[\"']|/ *\"tests\"|Path\.cwd\(\)", src), (path.name, src[:200])


def test_notebooks_are_valid_nbformat_with_cell_ids():
    """Every notebook validates against nbformat 4.5+ with an id on each cell (nbformat warns today, and will refuse
    a notebook without them)."""
    import warnings

    import nbformat

    for path in _tracked("notebooks/*.ipynb"):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            nb = nbformat.read(path, as_version=4)
            nbformat.validate(nb)
        assert (nb.nbformat, nb.nbformat_minor) >= (4, 5), path.name
        assert all("id" in cell for cell in nb.cells), path.name


def _site(tmp_path: Path, index_body: str, other_body: str = "<h1 id='top'>x</h1>") -> Path:
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "index.html").write_text(f"<html><body>{index_body}</body></html>")
    (tmp_path / "docs" / "other.html").write_text(f"<html><body>{other_body}</body></html>")
    (tmp_path / "docs" / "fig.png").write_bytes(b"png")
    return tmp_path


def test_site_checker_passes_a_clean_site(tmp_path):
    site = _site(tmp_path, "<a href='other.html#top'>a</a> <img src='fig.png' alt='a figure of the robot'>"
                            "<script src='_static/x.js'></script>")
    (site / "docs" / "_static").mkdir()
    (site / "docs" / "_static" / "x.js").write_text("")
    assert _check_site().check_static(site) == []


@pytest.mark.parametrize("body, expected", [
    ("<a href='missing.html'>a</a>", "broken link"),
    ("<a href='other.html#nowhere'>a</a>", "broken anchor"),
    ("<img src='fig.png' alt='fig.png'>", "no alt text"),
    ("<img src='fig.png'>", "no alt text"),
    ("<p>wrote /tmp/tmpab12/run.csv</p>", "outside the repository"),
    (f"<p>{ROOT}/examples/x.toml</p>", "outside the repository"),
    ("<script src='https://cdn.example.org/mathjax.js'></script>", "from the network"),
])
def test_site_checker_catches_each_defect(tmp_path, body, expected):
    problems = _check_site().check_static(_site(tmp_path, body))
    assert len(problems) == 1 and expected in problems[0], problems


def test_site_checker_raw_tex_pattern():
    raw = _check_site().RAW_TEX
    assert raw.search(r"the map \(S(q)\)") and raw.search("$M_r$") and raw.search("$$x$$")
    assert not raw.search("$ robotdyn list") and not raw.search("$(arg chassis_mass)")
    page = _check_site().Page()
    page.feed("<p>prose $x$</p><pre>${side}</pre><code>$y</code><script>var a='$b'</script>")
    assert "".join(page.text) == "prose $x$"  # code and scripts are not searched for raw TeX
