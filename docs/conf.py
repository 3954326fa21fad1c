"""Sphinx configuration of robotdyn's documentation site (``make docs``).

The source directory is the repository root (``sphinx-build -c docs . docs/_build/html``) so that the notebooks
(``notebooks/``) and the README are documents in place: no copies, notebooks run from their own folder, and the
Markdown files' relative links (``../notebooks/x.ipynb``) resolve. Only ``include_patterns`` are read.

Nothing here names a robotdyn module: the API reference is generated recursively from the ``robotdyn`` package
(``docs/api.rst``), the robot list for the viewer gallery comes from ``robotdyn list`` (``docs/_ext``), so that a
reorganisation of the package needs no edit here.
"""

from __future__ import annotations

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))

project = "robotdyn"
author = "the robotdyn authors"
copyright = "robotdyn authors, BSD-3-Clause"
try:
    from importlib.metadata import version as _version

    release = _version("robotdyn")
except Exception:  # pragma: no cover - not installed: the build fails later on autodoc anyway
    release = "unknown"

root_doc = "docs/index"
include_patterns = ["README.md", "docs/**", "notebooks/*.ipynb"]
exclude_patterns = ["docs/_build/**", "docs/_templates/**", "docs/_ext/**", "**/.ipynb_checkpoints/**"]
templates_path = [str(DOCS / "_templates")]  # absolute: autosummary resolves it against the source dir, HTML against docs/

extensions = [
    "myst_nb",  # Markdown pages (MyST) and notebooks, executed at build time
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",  # Google-style docstrings
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",  # MathJax 3 shipped in the package and copied into _static: math renders offline
    "sphinx.ext.viewcode",
    "robotdyn_docs",  # viewer pages from `robotdyn view --html`, embedded in the gallery
    "robotdyn_site",  # alt text for every figure, no lock objects in the API reference
]

# ----------------------------------------------------------------------------------------------- notebooks
# Outputs of a notebook whose code cells are unchanged are reused from the jupyter-cache that `make test` fills
# (tools/notebook_cache.py, which `make docs` runs first to drop outputs older than robotdyn's code); any other
# notebook is executed here, in its own folder, and cached. SPHINXOPTS="-D nb_execution_mode=force" runs them all.
nb_execution_mode = "cache"
nb_execution_cache_path = str(DOCS / "_build" / ".jupyter_cache")  # the Makefile's NB_CACHE
nb_execution_timeout = 900  # per cell [s]
nb_execution_raise_on_error = True  # a failing notebook fails the build
nb_execution_show_tb = True
nb_merge_streams = True
myst_enable_extensions = ["dollarmath", "amsmath"]
myst_heading_anchors = 3
nb_render_markdown_format = "myst"  # Markdown printed by a cell (the generated reference tables) parsed as MyST

# ------------------------------------------------------------------------------------------- API reference
autosummary_generate = True
autosummary_ignore_module_all = True
autodoc_default_options = {"members": True, "show-inheritance": True, "ignore-module-all": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_class_signature = "separated"
napoleon_google_docstring = True
napoleon_numpy_docstring = False
napoleon_use_rtype = False

# ---------------------------------------------------------------------------------------------------- HTML
html_theme = "pydata_sphinx_theme"
html_title = f"robotdyn {release}"  # the version in every page's header (pyproject.toml, via the metadata)
html_theme_options = {"show_toc_level": 2, "navigation_depth": 3, "secondary_sidebar_items": ["page-toc"]}
html_show_sourcelink = False
html_static_path = ["_static"]
html_css_files = ["robotdyn.css"]
