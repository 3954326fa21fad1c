"""Regenerate the viewer screenshots (docs/img/<robot>.png) and the gallery section of docs/viewer.md.

For every registered robot (robotdyn.robots.names(), so new robots appear automatically): the meshcat viewer at
the robot's neutral configuration (or, if that violates its constraints, a scenario's initial state) is exported to standalone HTML and rendered by headless Chromium with its
network switched off (robotdyn.interfaces.viewer.screenshot). The gallery section between the markers in docs/viewer.md
lists each robot's title, paper, scenarios, screenshot and what its notebook shows (its section headings).

Usage::

    .venv/bin/python tools/screenshots.py            # all robots
    .venv/bin/python tools/screenshots.py quasimoro  # some robots (the gallery still lists all)

Needs chromium (``make chromium``).
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
IMG = ROOT / "docs" / "img"
DOC = ROOT / "docs" / "viewer.md"
START, END = "<!-- gallery:start (tools/screenshots.py) -->", "<!-- gallery:end -->"
SIZE = (800, 600)


def pose(robot, scenarios: dict):
    """The neutral configuration, or when it violates the holonomic constraints (e.g. wheels off a curved
    terrain) the scenario initial state that violates them least."""
    import numpy as np

    def worst(q):
        return float(np.max(np.abs(robot.constraint_residual(q)), initial=0.0))

    best = robot.neutral()
    for sc in scenarios.values():
        if worst(best) <= 1e-6:
            break
        q0, _ = sc.initial_state(robot)
        if worst(q0) < worst(best):
            best = q0
    return best


def shoot(name: str, out: Path) -> None:
    import robotdyn
    from robotdyn.robots import module
    from robotdyn.interfaces.viewer import Viewer, screenshot

    robot = robotdyn.load(name)
    viewer = Viewer(robot)
    viewer.display(pose(robot, getattr(module(name), "SCENARIOS", {})))
    viewer.set_camera()
    with tempfile.TemporaryDirectory(prefix="robotdyn-shot-") as tmp:
        page = viewer.save(Path(tmp) / f"{name}.html")
        log = screenshot(page, out, SIZE, budget_ms=1500)
    if "robotdyn: applied" not in log:
        raise SystemExit(f"{name}: the scene script did not run in chromium:\n{log[-1500:]}")


def notebook_sections(name: str) -> list[str]:
    path = ROOT / "notebooks" / f"{name}.ipynb"
    if not path.is_file():
        return []
    cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
    out = []
    for cell in cells:
        if cell["cell_type"] != "markdown":
            continue
        for line in "".join(cell["source"]).splitlines():
            if line.startswith("## "):
                out.append(line[3:].strip())
    return out


def gallery() -> str:
    from robotdyn.robots import module, names

    parts = []
    for name in names():
        mod = module(name)
        spec = mod.SPEC
        lines = [f"### {name}", "", f"{spec.title}", ""]
        if spec.paper:
            lines += [f"Paper: {spec.paper} ([bibliography](bibliography.md))", ""]
        if (IMG / f"{name}.png").is_file():
            lines += [f"![{name} in the meshcat viewer](img/{name}.png)", ""]
        scenarios = getattr(mod, "SCENARIOS", {})
        if scenarios:
            lines += ["Scenarios (`robotdyn view " + name + " --scenario NAME --html out.html`):", ""]
            lines += [f"- `{k}`: {s.description}" for k, s in scenarios.items()] + [""]
        sections = notebook_sections(name)
        if sections:
            lines += [f"Notebook [`notebooks/{name}.ipynb`](../notebooks/{name}.ipynb) shows:", ""]
            lines += [f"- {s}" for s in sections] + [""]
        else:
            lines += ["(no notebook yet)", ""]
        parts.append("\n".join(lines))
    return "\n".join(parts)


def main(argv: list[str]) -> int:
    from robotdyn.robots import names

    wanted = argv or names()
    IMG.mkdir(parents=True, exist_ok=True)
    for name in wanted:
        shoot(name, IMG / f"{name}.png")
        print(f"wrote {(IMG / f'{name}.png').relative_to(ROOT)}")
    text = DOC.read_text(encoding="utf-8")
    if START not in text or END not in text:
        raise SystemExit(f"{DOC} lacks the gallery markers {START} ... {END}")
    head, rest = text.split(START, 1)
    tail = rest.split(END, 1)[1]
    DOC.write_text(f"{head}{START}\n\n{gallery()}\n{END}{tail}", encoding="utf-8")
    print(f"updated the gallery of {DOC.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
