"""Sphinx extension of robotdyn's documentation: site-wide fixes that no page should have to remember.

- Alt text: an image without one (a figure that a notebook cell draws gets its file name as alt text from
  docutils) is described by where it stands: the figure's caption if any, else the section title and the page
  title. Pages that know better say so themselves (``mystnb: image: alt:`` on the cell, ``:alt:`` on an image).
- Locks: a module-level lock (``threading.Lock()``) is left out of the API reference: its value is an object of
  the built-in ``_thread`` module, whose source viewcode cannot show (a broken link on the module index).
"""

from __future__ import annotations

import threading

from docutils import nodes
from sphinx.application import Sphinx

_LOCK_TYPES = (type(threading.Lock()), type(threading.RLock()))


def _title(node: nodes.Node) -> str:
    for child in node.children:
        if isinstance(child, nodes.title):
            return child.astext().strip()
    return ""


def _alt_text(app: Sphinx, doctree: nodes.document, docname: str) -> None:
    page = next((_title(s) for s in doctree.findall(nodes.section)), docname)
    for image in doctree.findall(nodes.image):
        alt, uri = (image.get("alt") or "").strip(), image.get("uri", "")
        if alt and alt != uri and not uri.endswith(alt.rsplit("/", 1)[-1]):
            continue
        figure = image.parent if isinstance(image.parent, nodes.figure) else None
        caption = next((c.astext() for c in figure.findall(nodes.caption)), "") if figure is not None else ""
        section, parent = "", image.parent
        while parent is not None and not section:
            if isinstance(parent, nodes.section):
                section = _title(parent)
            parent = parent.parent
        if caption:
            image["alt"] = caption
        elif section and section != page:
            image["alt"] = f"Figure of the section “{section}” of the page “{page}”"
        else:
            image["alt"] = f"Figure of the page “{page}”"


def _skip_locks(app, what, name, obj, skip, options):
    if isinstance(obj, _LOCK_TYPES):
        return True
    return None


def setup(app: Sphinx) -> dict:
    app.connect("doctree-resolved", _alt_text)
    app.connect("autodoc-skip-member", _skip_locks)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
