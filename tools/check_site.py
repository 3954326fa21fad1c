"""Check the built documentation site (``make docs`` runs it after Sphinx): ``python tools/check_site.py
docs/_build/html``.

Checks, over every HTML page of the build:

- every local link and image resolves: the file exists and, for ``page.html#anchor``, the page has that id;
- no page shows a path outside the repository (the build machine's directories: the repository's own absolute
  path, the home directory, the temporary directory, ``/work/``, ``/home/``, ``/tmp/``, ...);
- every image has alt text;
- no script, style or font is loaded from the network (math is rendered by the MathJax copied into ``_static``);
- then, unless ROBOTDYN_SKIP_BROWSER=1, the landing page, the tutorial and the concepts page are rendered in
  headless Chromium with JavaScript on and the network off: their rendered text must hold no raw TeX (``\\(``,
  ``\\[``, ``$$``), MathJax must have typeset their math, and each must show its figures; the screenshots are
  written to ``<build>/../screenshots/``.

Prints one line per problem and exits with status 1 when there is any (0 otherwise).
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

REPO = Path(__file__).resolve().parent.parent
SCREENSHOT_PAGES = ("docs/index.html", "notebooks/your_own_robot.html", "docs/concepts.html",
                    "docs/getting-started.html")
"""Pages rendered in the browser: the landing page, the tutorial, the concepts page and getting started."""
RAW_TEX = re.compile(r"\\\(|\\\[|\$\$|\$[A-Za-z\\{]")
"""TeX left unrendered in a page's text: ``\\(``, ``\\[``, ``$$``, or ``$`` before a letter, ``\\`` or ``{``."""


def machine_paths() -> re.Pattern:
    """Absolute paths of the build machine that a page must not show."""
    roots = {str(REPO), str(Path.home()), tempfile.gettempdir()}
    literal = "|".join(re.escape(r.rstrip("/") + "/") for r in sorted(roots, key=len, reverse=True) if len(r) > 1)
    return re.compile(rf"(?:{literal}|(?<![\w.:/~-])/(?:work|home|root|tmp|Users|mnt|srv)/[\w.-])")


class Page(HTMLParser):
    """The ids, links, images, scripts and text of one HTML page."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.ids: set[str] = set()
        self.links: list[str] = []
        self.images: list[tuple[str, str | None]] = []
        self.remote: list[str] = []
        self.text: list[str] = []  # prose: outside script, style, pre and code (code may hold "$" legitimately)
        self._skip = 0

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        for key in ("id", "name"):
            if a.get(key) and (key == "id" or tag == "a"):
                self.ids.add(a[key])
        if tag == "a" and a.get("href") is not None:
            self.links.append(a["href"])
        if tag == "img":
            self.images.append((a.get("src") or "", a.get("alt")))
            self.links.append(a.get("src") or "")
        if tag in ("script", "link", "iframe") and (a.get("src") or a.get("href")):
            url = a.get("src") or a.get("href")
            if tag != "link" or "stylesheet" in (a.get("rel") or "") or "preload" in (a.get("rel") or ""):
                if urlsplit(url).scheme in ("http", "https") or url.startswith("//"):
                    self.remote.append(url)
                elif tag != "link" or "stylesheet" in (a.get("rel") or ""):
                    self.links.append(url)
        if tag in ("script", "style", "pre", "code"):
            self._skip += 1

    def handle_endtag(self, tag):
        if tag in ("script", "style", "pre", "code") and self._skip:
            self._skip -= 1

    def handle_data(self, data):
        if not self._skip:
            self.text.append(data)


def parse(path: Path) -> Page:
    page = Page()
    page.feed(path.read_text(encoding="utf-8", errors="replace"))
    return page


def check_static(root: Path) -> list[str]:
    """Links, anchors, machine paths, alt text, network loads of every page under ``root``."""
    problems = []
    pages = {p: parse(p) for p in sorted(root.rglob("*.html"))
             if "_static" not in p.relative_to(root).parts and "_sources" not in p.relative_to(root).parts}
    paths = machine_paths()
    for path, page in pages.items():
        rel = path.relative_to(root)
        text = path.read_text(encoding="utf-8", errors="replace")
        for m in paths.finditer(text):
            line = text.count("\n", 0, m.start()) + 1
            problems.append(f"{rel}:{line}: a path outside the repository: {text[m.start():m.start() + 60]!r}")
        for src, alt in page.images:
            alt = (alt or "").strip()
            if not alt or alt == src or src.endswith(alt.rsplit("/", 1)[-1]):
                problems.append(f"{rel}: image {src!r} has no alt text (none, or its file name)")
        for url in page.remote:
            problems.append(f"{rel}: loads {url} from the network")
        for href in page.links:
            parts = urlsplit(href)
            if parts.scheme or href.startswith("//") or not href:
                continue
            target = path if not parts.path else (path.parent / unquote(parts.path)).resolve()
            if target.is_dir():
                target = target / "index.html"
            if not target.exists():
                problems.append(f"{rel}: broken link {href!r}")
                continue
            if parts.fragment and target.suffix == ".html":
                ids = pages[target].ids if target in pages else parse(target).ids
                if unquote(parts.fragment) not in ids:
                    problems.append(f"{rel}: broken anchor {href!r} (no id {parts.fragment!r} in "
                                    f"{target.relative_to(root) if target.is_relative_to(root) else target.name})")
    return problems


def check_browser(root: Path, shots: Path) -> list[str]:
    """Render the pages of :data:`SCREENSHOT_PAGES` in headless Chromium (network off): typeset math, no raw TeX,
    figures present; write their screenshots to ``shots``."""
    sys.path.insert(0, str(REPO))
    from robotdyn.interfaces.viewer import CHROMIUM_FLAGS, find_chromium

    exe = find_chromium()
    if exe is None:
        return ["headless Chromium not found: run `make chromium`, or set ROBOTDYN_SKIP_BROWSER=1 to skip this check"]
    shots.mkdir(parents=True, exist_ok=True)
    problems = []
    for name in SCREENSHOT_PAGES:
        page = root / name
        if not page.is_file():
            problems.append(f"{name}: not built")
            continue
        png = shots / (name.replace("/", "_").removesuffix(".html") + ".png")
        with tempfile.TemporaryDirectory(prefix="robotdyn-chromium-") as profile:
            common = [exe, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", "--window-size=1280,1600",
                      "--virtual-time-budget=15000"]
            dom = subprocess.run([*common, "--dump-dom", page.as_uri()], capture_output=True, text=True,
                                 timeout=180).stdout
            subprocess.run([*common, f"--screenshot={png}", page.as_uri()], capture_output=True, text=True,
                           timeout=180)
        rendered = Page()
        rendered.feed(dom)
        text = "".join(rendered.text)
        if "<mjx-container" not in dom:
            problems.append(f"{name}: no math typeset by MathJax in the browser")
        for m in RAW_TEX.finditer(text):
            problems.append(f"{name}: raw TeX in the rendered page: {text[m.start():m.start() + 60]!r}")
        if not rendered.images:
            problems.append(f"{name}: no figure in the rendered page")
        if not png.is_file() or png.stat().st_size < 10_000:
            problems.append(f"{name}: no screenshot written ({png.name})")
    return problems


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print("usage: python tools/check_site.py BUILD_DIR (e.g. docs/_build/html)", file=sys.stderr)
        return 2
    root = Path(argv[0]).resolve()
    if not (root / "docs" / "index.html").is_file():
        print(f"check_site: {argv[0]} holds no built site (docs/index.html); expected the output of make docs",
              file=sys.stderr)
        return 2
    problems = check_static(root)
    if os.environ.get("ROBOTDYN_SKIP_BROWSER") != "1":
        problems += check_browser(root, root.parent / "screenshots")
    for p in problems:
        print(f"check_site: {p}")
    pages = sum(1 for _ in root.rglob("*.html"))
    print(f"check_site: {pages} pages, {len(problems)} problem(s)" + (
        "" if os.environ.get("ROBOTDYN_SKIP_BROWSER") != "1" else " (browser check skipped)"))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
