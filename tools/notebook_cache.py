"""Execute the notebooks once per CI run: ``make test`` runs them into a jupyter-cache, ``make docs`` renders them
from it.

Usage::

    python tools/notebook_cache.py execute CACHE NOTEBOOK...   # make test: run each, fail if any fails
    python tools/notebook_cache.py drop-stale CACHE            # make docs: forget outputs older than the code

``execute`` empties the cache ``CACHE`` (outputs of older code are never kept), then runs the notebooks with
jupyter-cache's ``temp-parallel`` executor (one process per CPU; ``temp-serial`` on one CPU): each in the venv's
kernel, in a fresh temporary directory (outside the repository), each cell allowed 900 s, as the docs build
allows. A notebook that runs through is stored in the cache; one that fails is named with its error, and the
command exits with status 1 after running the rest.

``CACHE`` is MyST-NB's ``nb_execution_cache_path`` (``docs/conf.py``, ``nb_execution_mode = "cache"``): the docs
build looks each notebook up with jupyter-cache's own key (the code cells' source and the kernel spec), renders
the stored outputs when it matches, and otherwise executes the notebook itself and stores it. So a notebook edited
after ``make test`` is executed again by ``make docs``, and ``make docs`` alone, on a machine where ``make test``
never ran, executes every notebook.

The key does not cover robotdyn's code, which the notebooks import. ``drop-stale`` therefore empties the cache when
a file of the package, its robot descriptions or examples (or ``pyproject.toml``/``setup.py``) is newer than the
moment the cached outputs started being computed (the stamp ``execute`` writes, or ``drop-stale`` itself when the
cache was empty), so that ``make docs`` never shows outputs of older code.
"""

from __future__ import annotations

import logging
import os
import re
import shutil
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
CODE = ("robotdyn", "urdf", "examples", "pyproject.toml", "setup.py")
"""What the notebooks' outputs depend on besides their own source (relative to the repository)."""
STAMP = "robotdyn-code.stamp"
"""File in the cache whose modification time is when its outputs started being computed against the code."""
TIMEOUT = 900
"""Time allowed to each cell [s] (``nb_execution_timeout`` in docs/conf.py)."""
EXECUTOR = "temp-serial"
"""jupyter-cache's executor on one CPU: one notebook at a time, each in a fresh temporary directory."""
PARALLEL_EXECUTOR = "temp-parallel"
"""jupyter-cache's executor on several CPUs: the notebooks over a pool of one process per CPU, each in a fresh
temporary directory (its own kernel); used where the machine has more than one CPU."""
ANSI = re.compile(r"\x1b\[[0-9;]*m")
"""Terminal colour codes in the kernel's traceback."""
CELL_ERROR = re.compile(r"^nbclient\.exceptions\.\w+: ", re.MULTILINE)
"""Start of nbclient's error (a failing or timed-out cell) in the traceback jupyter-cache records."""


def newest_code_file(repo: Path = REPO) -> tuple[float, Path | None]:
    """The most recently modified file of :data:`CODE` under ``repo`` (bytecode caches skipped).

    Returns:
        (modification time [s since the epoch], path), or (0.0, None) when there is no such file.
    """
    newest: tuple[float, Path | None] = (0.0, None)
    for name in CODE:
        root = repo / name
        files = [root] if root.is_file() else root.rglob("*")
        for path in files:
            if path.is_file() and "__pycache__" not in path.parts and path.suffix != ".pyc":
                mtime = path.stat().st_mtime
                if mtime > newest[0]:
                    newest = (mtime, path)
    return newest


def drop_stale(cache: Path, repo: Path = REPO) -> bool:
    """Empty ``cache`` when a code file is newer than its stamp (or it has none); stamp it as of now.

    Returns:
        True when cached outputs were dropped.
    """
    stamp = cache / STAMP
    dropped = False
    if cache.exists():
        mtime, path = newest_code_file(repo)
        if not stamp.exists() or mtime > stamp.stat().st_mtime:
            why = f"{path.relative_to(repo)} changed since" if stamp.exists() and path else "no record of when"
            print(f"notebook cache: {why} its notebooks ran: dropped, the docs build executes them again")
            shutil.rmtree(cache)
            dropped = True
    if not stamp.exists():
        cache.mkdir(parents=True, exist_ok=True)
        stamp.touch()
    return dropped


def unreadable(path: Path) -> str | None:
    """Why ``path`` cannot be read as a version-4 notebook (its reader's message, first line), or None.

    Args:
        path: A notebook file.

    Returns:
        The reason, or None for a readable notebook.
    """
    import nbformat

    try:
        nb = nbformat.read(str(path), as_version=4)
        if not isinstance(nb.get("cells"), list):
            return "no cells"
    except Exception as exc:  # noqa: BLE001 - any reader error (JSON, schema, encoding) is the same answer
        return (str(exc).strip().splitlines() or [type(exc).__name__])[0][:200]
    return None


def execute(cache: Path, notebooks: list[Path]) -> int:
    """Run ``notebooks`` into an emptied ``cache`` and print one line per notebook.

    Returns:
        0 when every notebook ran through, 1 otherwise (each failing one named with its error).
    """
    from jupyter_cache import get_cache
    from jupyter_cache.executors import load_executor

    missing = [str(nb) for nb in notebooks if not nb.is_file()]
    if missing or not notebooks:
        print(f"notebook cache: expected notebook files, got {' '.join(missing) or 'none'}", file=sys.stderr)
        return 2
    for nb in notebooks:  # before any kernel starts: an unreadable file was jupyter-cache's 40-line traceback
        problem = unreadable(nb)
        if problem:
            print(f"notebook cache: {nb} is not a notebook ({problem}); expected a Jupyter notebook (nbformat 4)",
                  file=sys.stderr)
            return 2
    if cache.exists():
        shutil.rmtree(cache)
    cache.mkdir(parents=True)
    (cache / STAMP).touch()
    store = get_cache(str(cache))
    logger = logging.getLogger("notebook_cache")
    logger.addHandler(logging.StreamHandler(sys.stderr))
    logger.setLevel(logging.ERROR)  # our own line per notebook; the executor's own failures still shown
    parallel = (os.cpu_count() or 1) > 1 and len(notebooks) > 1
    executor = load_executor(PARALLEL_EXECUTOR if parallel else EXECUTOR, store, logger=logger)
    failed: list[str] = []
    start = time.perf_counter()
    uris = [store.add_nb_to_project(str(nb.resolve())).uri for nb in notebooks]
    batches = [uris] if parallel else [[uri] for uri in uris]  # in parallel: no time per notebook
    for batch in batches:
        tic = time.perf_counter()
        result = executor.run_and_cache(filter_uris=batch, timeout=TIMEOUT, allow_errors=False, force=True)
        took = "" if parallel else f" in {time.perf_counter() - tic:.1f} s"
        for uri in batch:
            name = Path(uri).name
            if uri in result.succeeded:
                print(f"{name}: passed{took}", flush=True)
                continue
            trace = ANSI.sub("", store.get_project_record(uri).traceback or "(no traceback: see the error above)")
            cell = CELL_ERROR.search(trace)  # from nbclient's error on (the failing cell), without its own frames
            trace = trace[cell.start():] if cell else trace
            last = [line for line in trace.strip().splitlines() if line.strip()][-1]
            print(f"{name}: FAILED{took}: {last}\n{trace}", flush=True)
            failed.append(f"{name}: {last}")
    total = time.perf_counter() - start
    if failed:
        print(f"notebooks: {len(failed)} of {len(notebooks)} failed ({total:.0f} s):\n  " + "\n  ".join(failed))
        return 1
    print(f"notebooks: {len(notebooks)} passed in {total:.0f} s (outputs cached in {cache} for make docs)")
    return 0


def main(argv: list[str] | None = None) -> int:
    """Command line: ``execute CACHE NOTEBOOK...`` or ``drop-stale CACHE``; returns the exit status."""
    args = sys.argv[1:] if argv is None else argv
    if len(args) >= 2 and args[0] == "execute":
        return execute(Path(args[1]), [Path(a) for a in args[2:]])
    if len(args) == 2 and args[0] == "drop-stale":
        drop_stale(Path(args[1]))
        return 0
    print("usage: notebook_cache.py execute CACHE NOTEBOOK... | drop-stale CACHE", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main())
