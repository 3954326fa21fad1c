"""The Quasimoro (Staicu, virtual powers): the model and the paper, kept apart.

- :mod:`robotdyn.robots.quasimoro.model`: what robotdyn derives from ``urdf/quasimoro.urdf.xacro`` -- ``SPEC`` (parameters of section 3,
  wheels, motors), the torque pulse of eq 19 and the two section-3 manoeuvres (``SCENARIOS``), ``drift``.
- :mod:`robotdyn.robots.quasimoro.paper`: the paper's closed forms (eqs 23-31) and printed values, transcribed
  (Staicu, ``docs/bibliography.md``).
- :mod:`robotdyn.robots.quasimoro.comparison`: ``compare``, the model against the paper (``docs/errata/quasimoro.md``).
- :mod:`robotdyn.robots.quasimoro.optimal_motion`: ``rest_to_rest``, the minimum-effort motion over a distance with
  torque and body-pitch bounds (trajectory optimisation; not re-exported: import it from there).

The names of all three are re-exported here (``robotdyn.robots.module("quasimoro")``).
"""

from .comparison import *  # noqa: F401,F403
from .model import *  # noqa: F401,F403
from .model import _pulse  # noqa: F401
from .paper import *  # noqa: F401,F403
