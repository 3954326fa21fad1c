"""The robot ``mmr12_eod``: its model and its paper (see the modules of this package)."""

from .model import *  # noqa: F401,F403
from .model import _ARMS  # noqa: F401
