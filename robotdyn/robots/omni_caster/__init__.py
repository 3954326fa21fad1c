"""The omni caster platform (Chung, Yi, Kim, Han): the model and the paper, kept apart.

- :mod:`robotdyn.robots.omni_caster.model`: what robotdyn derives from ``urdf/omni_caster.urdf.xacro`` -- ``SPEC`` (Tables 1-2), the NOC
  variant (eq A9), the section-5 trajectories and ``SCENARIOS``, the impulse study on the model, the CLI.
- :mod:`robotdyn.robots.omni_caster.paper`: the paper's closed forms (eqs 12-19, 43, 48-51, 60, A7-A9) and the matrices printed in section 5,
  transcribed (Chung, Yi, Kim & Han, ``docs/bibliography.md``).
- :mod:`robotdyn.robots.omni_caster.comparison`: ``compare``, the model against the paper, with the derived offset-link terms
  (``docs/errata/omni_caster.md``).

The names of all three are re-exported here (``robotdyn.robots.module("omni_caster")``).
"""

from .comparison import *  # noqa: F401,F403
from .model import *  # noqa: F401,F403
from .paper import *  # noqa: F401,F403
