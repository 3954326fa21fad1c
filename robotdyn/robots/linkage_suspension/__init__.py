"""The six-wheel robot with linkage suspension (Chen et al.): the model and the paper, kept apart.

- :mod:`robotdyn.robots.linkage_suspension.model`: what robotdyn derives from ``urdf/linkage_suspension.urdf.xacro`` -- ``SPEC``, the section-3
  wheel-speed profile and kinematic runs, ``TERRAINS``, ``SCENARIOS``, the ``linkage-posture`` CLI, the
  posture-versus-rigid-chassis study.
- :mod:`robotdyn.robots.linkage_suspension.paper`: the paper's closed forms (Table 1, eqs 1-4, 10) and section 3's printed numbers, transcribed
  (Chen et al., ``docs/bibliography.md``).
- :mod:`robotdyn.robots.linkage_suspension.comparison`: ``compare``, the model against the paper (``docs/errata/linkage_suspension.md``).

The names of all three are re-exported here (``robotdyn.robots.module("linkage_suspension")``).
"""

from .comparison import *  # noqa: F401,F403
from .model import *  # noqa: F401,F403
from .paper import *  # noqa: F401,F403
