"""The MMR12-EOD mobile manipulator (Zuniga-Aviles et al. 2014): the model and the paper, kept apart.

- :mod:`robotdyn.robots.mmr12_eod.model`: what robotdyn derives from ``urdf/mmr12_eod.urdf.xacro`` -- ``SPEC``, the control ``SCENARIOS``
  (Table 4 tracking, manipulation, lifting), the climbing balance, the ``fk`` CLI hook.
- :mod:`robotdyn.robots.mmr12_eod.paper`: the paper's closed forms (eqs 1-2, 3-5, 10-14, 26) and printed transforms (eqs 27-31), transcribed
  (Zúñiga-Avilés et al. 2014, ``docs/bibliography.md``).
- :mod:`robotdyn.robots.mmr12_eod.comparison`: ``compare``, the model against the paper (``docs/errata/mmr12_eod.md``).
- :mod:`robotdyn.robots.mmr12_eod.climbing_posture`: the posture on a ramp that needs the least friction (IPOPT),
  the ``climbing-posture`` CLI command.

The names of all three are re-exported here (``robotdyn.robots.module("mmr12_eod")``).
"""

from .comparison import *  # noqa: F401,F403
from .model import *  # noqa: F401,F403
from .model import _ARMS  # noqa: F401
from .paper import *  # noqa: F401,F403
