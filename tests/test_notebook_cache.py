"""``tools/notebook_cache.py``: ``make test`` executes each notebook once, and ``make docs`` renders the outputs.

Checked here:

- a failing notebook fails the run (exit status 1) and is named with its error, after the others ran;
- a notebook that ran is found under the key MyST-NB's cache mode looks up (``myst_nb.core.execute.cache``: the
  source read with ``nbformat.reads(text, as_version=4)``, then jupyter-cache's ``match_cache_notebook``), with
  its outputs;
- once a code cell is edited it is no longer found, so the docs build executes it again;
- the cached outputs are dropped once robotdyn's code is newer than they are;
- the Makefile and ``docs/conf.py`` name the same cache.

Two kernels start (about a second each); myst-nb itself is not needed (it is in the ``docs`` extra only).
"""

from __future__ import annotations

import importlib.util
import os
import re
from pathlib import Path

import nbformat
import pytest
from jupyter_cache import get_cache

ROOT = Path(__file__).resolve().parent.parent


def _tool():
    spec = importlib.util.spec_from_file_location("notebook_cache", ROOT / "tools" / "notebook_cache.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _notebook(path: Path, *code: str) -> Path:
    nb = nbformat.v4.new_notebook()
    nb.metadata["kernelspec"] = {"display_name": "Python 3", "language": "python", "name": "python3"}
    nb.cells = [nbformat.v4.new_markdown_cell("# A title")] + [nbformat.v4.new_code_cell(c) for c in code]
    nbformat.write(nb, path)
    return path


def _as_myst_nb_reads(path: Path) -> nbformat.NotebookNode:
    return nbformat.reads(path.read_text(), as_version=4)


def test_failing_notebook_fails_the_run_and_the_passing_one_is_served_to_the_docs(tmp_path, capsys):
    good = _notebook(tmp_path / "good.ipynb", "x = 6 * 7", "print(x)")
    bad = _notebook(tmp_path / "bad.ipynb", "1 / 0")
    cache = tmp_path / "cache"
    (cache / "executed").mkdir(parents=True)  # a previous run's outputs: emptied first
    assert _tool().main(["execute", str(cache), str(bad), str(good)]) == 1
    out = capsys.readouterr().out
    assert re.search(r"^bad\.ipynb: FAILED(?: in [\d.]+ s)?: ZeroDivisionError: division by zero$", out, re.MULTILINE)
    assert "1 / 0" in out  # the failing cell is shown
    assert re.search(r"^good\.ipynb: passed(?: in [\d.]+ s)?$", out, re.MULTILINE)  # runs despite the failure
    assert "notebooks: 1 of 2 failed" in out

    store = get_cache(str(cache))
    store.match_cache_notebook(_as_myst_nb_reads(good))  # found: raises KeyError otherwise
    _, merged = store.merge_match_into_notebook(_as_myst_nb_reads(good))
    assert merged.cells[2].outputs[0]["text"] == "42\n"
    with pytest.raises(KeyError):
        store.match_cache_notebook(_as_myst_nb_reads(bad))  # not cached: the docs build runs it and fails

    text = _as_myst_nb_reads(good)
    text.cells[0].source = "# Another title"  # prose only: the outputs still hold
    store.match_cache_notebook(text)
    edited = _as_myst_nb_reads(good)
    edited.cells[1].source = "x = 6 * 9"
    with pytest.raises(KeyError):
        store.match_cache_notebook(edited)


def test_outputs_older_than_the_code_are_dropped(tmp_path, capsys):
    tool = _tool()
    code = tmp_path / "robotdyn" / "dynamics.py"
    code.parent.mkdir()
    code.write_text("x = 1\n")
    (tmp_path / "robotdyn" / "__pycache__").mkdir()
    bytecode = tmp_path / "robotdyn" / "__pycache__" / "dynamics.cpython-311.pyc"
    bytecode.write_bytes(b"")
    cache = tmp_path / "cache"
    assert not tool.drop_stale(cache, repo=tmp_path)  # no cache yet: stamped as of now for the docs build
    stamp = cache / tool.STAMP
    t = stamp.stat().st_mtime
    os.utime(code, (t - 10, t - 10))
    os.utime(bytecode, (t + 10, t + 10))  # written by importing the code, not a change of it
    (cache / "global.db").write_bytes(b"")
    assert not tool.drop_stale(cache, repo=tmp_path)
    assert (cache / "global.db").exists()
    os.utime(code, (t + 10, t + 10))
    assert tool.drop_stale(cache, repo=tmp_path)
    assert not (cache / "global.db").exists() and stamp.exists()
    assert "robotdyn/dynamics.py changed since its notebooks ran" in capsys.readouterr().out
    stamp.unlink()
    (cache / "global.db").write_bytes(b"")
    assert tool.drop_stale(cache, repo=tmp_path)  # outputs of unknown age: dropped


def test_the_makefile_and_the_docs_configuration_name_the_same_cache():
    makefile = (ROOT / "Makefile").read_text()
    cache = re.search(r"^NB_CACHE := (\S+)$", makefile, re.MULTILINE).group(1)
    assert "tools/notebook_cache.py execute $(NB_CACHE) notebooks/*.ipynb" in makefile
    assert "tools/notebook_cache.py drop-stale $(NB_CACHE)" in makefile
    conf = (ROOT / "docs" / "conf.py").read_text()
    assert re.search(r'^nb_execution_mode = "cache"', conf, re.MULTILINE)
    path = re.search(r"^nb_execution_cache_path = str\(DOCS / (.+)\)", conf, re.MULTILINE).group(1)
    assert "docs/" + "/".join(re.findall(r'"([^"]+)"', path)) == cache


@pytest.mark.parametrize("text", ["not json", "{}"])
def test_a_missing_or_unreadable_notebook_is_one_line_before_any_kernel(tmp_path, capsys, text):
    """A missing file, and a file that is not a version-4 notebook: exit status 2 and one line naming it, before
    the cache is touched (an unreadable one used to run into jupyter-cache's 40-line traceback, exit 1)."""
    tool = _tool()
    cache = tmp_path / "cache"
    assert tool.main(["execute", str(cache), str(tmp_path / "nosuch.ipynb")]) == 2
    bad = tmp_path / "bad.ipynb"
    bad.write_text(text)
    assert tool.main(["execute", str(cache), str(bad)]) == 2
    out, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert len(lines) == 2 and "nosuch.ipynb" in lines[0] and "bad.ipynb is not a notebook" in lines[1], err
    assert "expected" in lines[1] and not out and not cache.exists()
