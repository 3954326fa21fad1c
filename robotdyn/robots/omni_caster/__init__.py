"""The robot ``omni_caster``: its model and its paper (see the modules of this package)."""

from .model import *  # noqa: F401,F403

