"""The documentation site's promises to a newcomer that can be checked without building it (well under a second):

- every example of code or command on the pages is executed when the site is built (a MyST-NB ``{code-cell}``,
  run by ``make docs`` with ``nb_execution_raise_on_error``, so a page whose code no longer runs fails the build):
  the how-to page has no other kind of code block, and the few unexecuted blocks elsewhere (the install commands
  that must run before robotdyn exists, the viewer's interactive session) are listed here, so that a new one is a
  decision, not an accident;
- the how-to page covers its six tasks, each with code and links to the concepts and the API reference;
- every API reference of the pages (``{py:func}`...``` and the like) names an object that exists;
- the constraint-file reference states a unit for every numeric key, and the default rules of the compliant
  contact's keys quote the code's own constants.
"""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import pytest

from robotdyn.contact import compliant_contact
from robotdyn.constraints import wheel_compliance
from robotdyn.interfaces import constraint_reference

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
HOW_TO = DOCS / "how-to.md"
FENCE = re.compile(r"^(`{3,})(\S*)[^\n]*\n(.*?)^\1\s*$", re.M | re.S)
"""A fenced block: its backticks, its info string's first word (``{code-cell}``, ``python``, ...), its body."""
ROLE = re.compile(r"\{py:(func|class|meth|mod|attr|data|exc)\}`~?([\w.]+)`")
"""An API reference of MyST: ``{py:func}`robotdyn.load```."""
DIRECTIVES = ("{code-cell}", "{toctree}", "{image}", "{include}", "{literalinclude}", "{robotdyn-viewer-gallery}")
"""Fenced blocks that are not examples: executed cells and Sphinx directives."""
NOT_EXECUTED = {
    ("getting-started.md", ""): 2,  # `git clone` + `make demo`, and the command line before robotdyn is on PATH
    ("viewer.md", "sh"): 1,  # `robotdyn view ... --html`, which the gallery runs for every robot
    ("viewer.md", "python"): 2,  # a live meshcat session (a browser window): viewer.ipynb executes the same calls
    ("troubleshooting.md", "text"): None,  # quoted messages: tests/test_troubleshooting.py checks each against the code
    ("troubleshooting.md", "toml"): None,  # fixes to a constraint file
    ("troubleshooting.md", "xml"): None,
}
"""Unexecuted code blocks allowed, by (page, language): how many (``None``: any number)."""
TASKS = ["Wheel loads on a rigid four-wheel base", "A wheel that flies and lands over a bump",
         "Linearise a robot and design an LQR", "A trajectory within traction limits",
         "A controller on the compiled path", "Read the errata"]
"""The how-to page's sections, in order (the tasks a newcomer comes with)."""


def pages() -> list[Path]:
    return sorted(DOCS.rglob("*.md"))


def blocks(text: str) -> list[tuple[str, str]]:
    """(info word, body) of every fenced block of a Markdown page."""
    return [(m.group(2), m.group(3)) for m in FENCE.finditer(text)]


def unexecuted(path: Path) -> list[str]:
    """The languages of a page's fenced blocks that are neither executed cells nor directives."""
    return [lang for lang, _ in blocks(path.read_text(encoding="utf-8")) if lang not in DIRECTIVES]


def test_fence_pattern_sees_executed_and_plain_blocks():
    text = "a\n```{code-cell} ipython3\nx = 1\n```\nb\n```python\nimport robotdyn\n```\n````text\n```\n````\n"
    assert [lang for lang, _ in blocks(text)] == ["{code-cell}", "python", "text"]


def test_how_to_page_runs_every_block():
    """Every code block of the how-to page is an executed cell: no example there can drift from the code."""
    text = HOW_TO.read_text(encoding="utf-8")
    found = blocks(text)
    assert sum(lang == "{code-cell}" for lang, _ in found) >= 12
    assert unexecuted(HOW_TO) == []
    assert text.startswith("---\nfile_format: mystnb\n")  # without it MyST reads the cells as plain code


def test_unexecuted_blocks_elsewhere_are_the_listed_ones():
    counts: dict[tuple[str, str], int] = {}
    for path in pages():
        for lang in unexecuted(path):
            key = (str(path.relative_to(DOCS)), lang)
            counts[key] = counts.get(key, 0) + 1
    extra = {k: n for k, n in counts.items() if k not in NOT_EXECUTED or NOT_EXECUTED[k] not in (None, n)}
    assert not extra, f"code blocks that are not executed when the site is built (make them {{code-cell}}s): {extra}"


def test_how_to_page_covers_the_tasks_with_links():
    text = HOW_TO.read_text(encoding="utf-8")
    heads = re.findall(r"^## (.+)$", text, re.M)
    assert heads == TASKS
    sections = re.split(r"^## .+$", text, flags=re.M)[1:]
    for head, body in zip(heads, sections):
        assert "```{code-cell}" in body, head
        assert "concepts.md" in body or ROLE.search(body) or "errata" in body, head
    anchors = re.findall(r"\]\(#([\w-]+)\)", text)  # the table of contents at the top
    assert anchors == [re.sub(r"[^\w\- ]", "", h).lower().replace(" ", "-") for h in TASKS]
    for page in ("index.md", "getting-started.md"):  # a newcomer finds it from the start pages
        assert "how-to.md" in (DOCS / page).read_text(encoding="utf-8"), page
    assert re.search(r"^how-to$", (DOCS / "index.md").read_text(encoding="utf-8"), re.M)  # in the toctree


def documented_attribute(cls: type, name: str) -> bool:
    """Whether ``name`` is an instance attribute that the class docstring's ``Attributes:`` section documents (the
    API reference renders it, and a reference to it resolves)."""
    section = (cls.__doc__ or "").split("Attributes:", 1)[-1] if "Attributes:" in (cls.__doc__ or "") else ""
    return bool(re.search(rf"^\s+(\w+, )*{re.escape(name)}(, \w+)*:", section, re.M))


def resolve(target: str) -> object:
    """The object a dotted API reference names (a module, an attribute of one, or a documented instance attribute
    of a class), or raise."""
    parts = target.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ModuleNotFoundError:
            continue
        for i, name in enumerate(parts[cut:]):
            if not hasattr(obj, name) and isinstance(obj, type) and cut + i == len(parts) - 1 \
                    and documented_attribute(obj, name):
                return obj
            obj = getattr(obj, name)
        return obj
    raise ModuleNotFoundError(target)


def test_api_references_name_existing_objects():
    refs = {(p.name, m.group(2)) for p in pages() for m in ROLE.finditer(p.read_text(encoding="utf-8"))}
    assert len(refs) >= 15
    missing = []
    for page, target in sorted(refs):
        try:
            resolve(target)
        except (ImportError, AttributeError):
            missing.append(f"{page}: {target}")
    assert not missing, missing
    with pytest.raises(AttributeError):  # the check can fail
        resolve("robotdyn.robot.Robot.no_such_method")


UNIT = re.compile(r" in (m|rad|s|N|kg)\b|\[[^\]]*\]|dimensionless|rise over run|in (its|the parameter's) unit")
"""How a reference row states the unit of a number: ``in m``, ``[N/m]``, ``dimensionless``, ..."""


def test_every_numeric_key_of_the_constraint_file_states_its_unit():
    rows = [r for r in constraint_reference.rows() if "number" in r.type]
    assert len(rows) >= 25
    silent = [r.key for r in rows if not UNIT.search(" ".join((r.description, r.expected, r.default)))]
    assert not silent, f"numeric keys whose reference states no unit: {silent}"
    assert not UNIT.search("the axle in the wheel frame")  # the check can fail


def test_compliance_defaults_quote_the_codes_constants():
    """The reference's default rules of normal_stiffness and normal_damping are the code's: 1 mm of static deflection,
    damping ratio 0.3 (linear law), Hunt-Crossley's alpha 0.2 s/m and exponent 1.5."""
    keys = constraint_reference.KEYS
    stiffness, damping = keys["wheels[].normal_stiffness"][1], keys["wheels[].normal_damping"][1]
    assert f"{wheel_compliance.STATIC_DEFLECTION * 1e3:g} mm" in stiffness
    assert "(m g / n) / (1 mm)^n [N/m^n]" in stiffness  # hunt_crossley: the same deflection
    assert f"2 * {wheel_compliance.DAMPING_RATIO:g} * sqrt(k m / n)" in damping
    assert f"1.5 * {compliant_contact.HUNT_CROSSLEY_ALPHA:g} s/m * k" in damping
    assert keys["wheels[].contact_exponent"][1] == f"{compliant_contact.HUNT_CROSSLEY_EXPONENT:g}"
    assert keys["wheels[].slip_velocity"][1].startswith("1e-3 m/s")
