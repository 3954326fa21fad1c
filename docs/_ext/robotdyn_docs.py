"""Sphinx extension of robotdyn's documentation: the viewer pages and their gallery.

At the start of an HTML build every registered robot (``robotdyn list --json``) is exported with
``robotdyn view NAME --html`` into a staging folder that is copied to ``<html>/viewer/NAME.html``; the directive
``robotdyn-viewer-gallery`` embeds each page in an iframe. The command line is the interface used on purpose: the
documentation depends on what a user runs, not on robotdyn's module layout. A root ``index.html`` redirects to the
documentation's start page (the source directory is the repository root).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from docutils import nodes
from sphinx.application import Sphinx
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

logger = logging.getLogger(__name__)

_REDIRECT = """<!DOCTYPE html>
<html><head><meta charset="utf-8"><meta http-equiv="refresh" content="0; url={target}">
<title>robotdyn</title></head><body><a href="{target}">robotdyn documentation</a></body></html>
"""


def _robotdyn(*args: str) -> str:
    """Run ``python -m robotdyn ARGS`` and return its standard output (a failure stops the build)."""
    proc = subprocess.run([sys.executable, "-m", "robotdyn", *args], capture_output=True, text=True,
                          env={**os.environ, "MPLBACKEND": "Agg"}, check=False)
    if proc.returncode != 0:
        raise RuntimeError(f"robotdyn {' '.join(args)} failed ({proc.returncode}): {proc.stderr.strip()}")
    return proc.stdout


def _export_viewer_pages(app: Sphinx) -> None:
    robots = json.loads(_robotdyn("list", "--json"))["robots"]
    app.env.robotdyn_robots = robots  # read by the gallery directive
    if app.builder.format != "html":
        return
    stage = Path(app.outdir).parent / "_extra"
    (stage / "viewer").mkdir(parents=True, exist_ok=True)
    for name in robots:
        page = stage / "viewer" / f"{name}.html"
        logger.info(f"robotdyn view {name} --html {page}")
        _robotdyn("view", name, "--html", str(page))
        page.chmod(0o644)  # the export is written atomically from a private temporary file
    target = app.builder.get_target_uri(app.config.root_doc)
    (stage / "index.html").write_text(_REDIRECT.format(target=target), encoding="utf-8")
    app.config.html_extra_path = [*app.config.html_extra_path, str(stage)]


class ViewerGallery(SphinxDirective):
    """``robotdyn-viewer-gallery``: one section per registered robot with its viewer page in an iframe.

    Option ``height`` (pixels, default 420).
    """

    option_spec = {"height": int}

    def run(self) -> list[nodes.Node]:
        robots = getattr(self.env, "robotdyn_robots", None) or json.loads(_robotdyn("list", "--json"))["robots"]
        height = self.options.get("height", 420)
        up = "../" * self.env.docname.count("/")
        out: list[nodes.Node] = []
        for name, title in robots.items():
            section = nodes.section(ids=[nodes.make_id(f"viewer-{name}")])
            section += nodes.title(text=name)
            section += nodes.paragraph(text=title)
            src = f"{up}viewer/{name}.html"
            section += nodes.raw(
                "", f'<iframe src="{src}" title="{name} in the meshcat viewer" loading="lazy" '
                    f'style="width: 100%; height: {height}px; border: 1px solid #ccc"></iframe>\n'
                    f'<p><a href="{src}">Open the page on its own</a> '
                    f'(<code>robotdyn view {name} --html {name}.html</code>)</p>', format="html")
            out.append(section)
        return out


def setup(app: Sphinx) -> dict:
    app.connect("builder-inited", _export_viewer_pages)
    app.add_directive("robotdyn-viewer-gallery", ViewerGallery)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
