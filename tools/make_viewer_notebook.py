"""Write notebooks/viewer.ipynb (without outputs): the meshcat viewer in a notebook, for every registered robot.

Usage: .venv/bin/python tools/make_viewer_notebook.py   (check with: .venv/bin/python tools/notebook_cache.py execute
/tmp/nb-cache notebooks/viewer.ipynb)
"""

from __future__ import annotations

from pathlib import Path

import nbformat
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

ROOT = Path(__file__).resolve().parent.parent

CELLS = [
    new_markdown_cell(
        "# The 3-D viewer in a notebook\n\n"
        "`robotdyn.interfaces.viewer.Viewer` draws a robot's URDF visuals (placed by Pinocchio), the terrain, the wheels' "
        "contact points with their contact frames, and the link frames. A viewer as the last expression of a cell "
        "renders inline: the standalone HTML export (meshcat's JavaScript inlined, no server, works offline) in an "
        "iframe. Drag to orbit, scroll to zoom; *Open Controls* toggles layers and plays animations. "
        "See `docs/viewer.md`."
    ),
    new_code_cell(
        "import tempfile\n"
        "from pathlib import Path\n\n"
        "import numpy as np\n"
        "from IPython.display import HTML, display\n\n"
        "import robotdyn\n"
        "from robotdyn.robots import module\n"
        "from robotdyn.interfaces.viewer import Viewer\n\n"
        "robot = robotdyn.load(\"quasimoro\")\n"
        "viewer = Viewer(robot)\n"
        "viewer"
    ),
    new_markdown_cell(
        "## A simulated scenario, animated in real time\n\n"
        "The first 3 s of the paper's rectilinear manoeuvre (torque pulses for 1 s, then free). Keys are placed at "
        "the trajectory's times, so the animation lasts as long as the simulation; open the controls to replay it, "
        "scrub the time or change the time scale."
    ),
    new_code_cell(
        "traj = module(\"quasimoro\").SCENARIOS[\"rectilinear\"].run(robot, t_end=3.0, progress=False)\n"
        "viewer.animate(traj)\n"
        "keys = viewer.key_times(traj.t, viewer.fps)\n"
        "print(f\"{len(keys)} keyframes at {viewer.fps:g} per second, from {keys[0]:g} s to {keys[-1]:g} s \"\n"
        "      f\"(simulated {traj.t[-1]:g} s); x moved {traj.column('x')[-1] * 100:.2f} cm\")\n"
        "assert abs(keys[-1] - traj.t[-1]) < 1e-12\n"
        "viewer"
    ),
    new_markdown_cell(
        "## Layers\n\n"
        "`show(layer, visible)` for `robot`, `terrain`, `contacts` (red spheres; t1 red, t2 green, n blue) and "
        "`frames` (every link frame); the same switches are in the browser's controls (Scene → meshcat → robotdyn)."
    ),
    new_code_cell(
        "viewer = Viewer(robot, frames=True)\n"
        "viewer.show(\"terrain\", False)\n"
        "viewer"
    ),
    new_markdown_cell(
        "## A standalone file\n\n"
        "`save` writes the export (open it in any browser, offline, or attach it to a report); "
        "`page.html#t=1.5` opens an animation paused at 1.5 s."
    ),
    new_code_cell(
        "path = Viewer(robot).save(Path(tempfile.gettempdir()) / \"quasimoro.html\")\n"
        "print(f\"wrote {path} ({path.stat().st_size / 1e6:.2f} MB)\")"
    ),
    new_markdown_cell("## Every registered robot\n\nAt its neutral configuration, on its own terrain."),
    new_code_cell(
        "for name in robotdyn.robots_available():\n"
        "    r = robotdyn.load(name)\n"
        "    display(HTML(f\"<h4>{name}: {r.spec.title}</h4>\" + Viewer(r).iframe(height=320)))"
    ),
]


def main() -> None:
    nb = new_notebook(cells=CELLS, metadata={
        "kernelspec": {"display_name": "Python 3", "language": "python", "name": "python3"},
        "language_info": {"name": "python"},
    })
    out = ROOT / "notebooks" / "viewer.ipynb"
    nbformat.write(nb, out)
    print(f"wrote {out.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
