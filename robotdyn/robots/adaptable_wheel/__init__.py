"""The tricycle with adaptable-radius wheels (Mardani & Ebrahimi 2016): the model and the paper, kept apart.

- :mod:`robotdyn.robots.adaptable_wheel.model`: what robotdyn derives from ``urdf/adaptable_wheel.urdf.xacro`` -- ``SPEC`` (Table 1), the
  terrains, ``SCENARIOS``.
- :mod:`robotdyn.robots.adaptable_wheel.paper`: the paper's closed forms (eqs 1, 3-35) and Table 2, transcribed
  (Mardani & Ebrahimi 2016, ``docs/bibliography.md``).
- :mod:`robotdyn.robots.adaptable_wheel.missions`: the kinematic missions of section 7, solved by the paper's inverse kinematics.
- :mod:`robotdyn.robots.adaptable_wheel.dynamics`: the model driven along those missions, with inertia or sideways friction (beyond the paper).
- :mod:`robotdyn.robots.adaptable_wheel.comparison`: ``compare``, the model against the paper, and the ``ik`` CLI
  (``docs/errata/adaptable_wheel.md``).

The names of all five are re-exported here (``robotdyn.robots.module("adaptable_wheel")``).
"""

from .comparison import *  # noqa: F401,F403
from .dynamics import *  # noqa: F401,F403
from .missions import *  # noqa: F401,F403
from .model import *  # noqa: F401,F403
from .model import _terrain  # noqa: F401
from .paper import *  # noqa: F401,F403
