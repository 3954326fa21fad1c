"""The wheels' normal (radial) compliance: a stiffness and a damping per wheel, given or by a stated rule.

The rule and its functions live in :mod:`robotdyn.constraints.wheel_compliance` (an earlier stage, so that the
compiled model reads the same values); this module is their name in the contact stage, next to the rigid limit of
the loads (:mod:`robotdyn.contact.rigid_limit`) that uses them.
"""

from __future__ import annotations

from ..constraints.wheel_compliance import (DAMPING_RATIO, STATIC_DEFLECTION, NormalCompliance, normal_compliance,
                                            weight, wheel_stiffness)

__all__ = ["NormalCompliance", "normal_compliance", "wheel_stiffness", "weight", "STATIC_DEFLECTION", "DAMPING_RATIO"]
