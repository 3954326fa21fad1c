"""User-facing errors.

Every error a user can trigger with bad input derives from :class:`RobotDynError`; its message is one line that
names what was wrong and what was expected. The CLI prints that line and exits with status 2.
"""

from __future__ import annotations


class RobotDynError(ValueError):
    """Base class of all user-facing robotdyn errors (one-line message)."""


class UnknownRobotError(RobotDynError):
    """A robot name that is not registered."""


class InputError(RobotDynError):
    """A vector of the wrong length, a non-finite number, an unknown parameter or option."""


class DescriptionError(RobotDynError):
    """A Xacro/URDF description that cannot be expanded, parsed or turned into a valid model."""


class ConstraintError(RobotDynError):
    """A configuration where the constraints cannot be satisfied (e.g. a wheel that cannot touch the terrain)."""


class SingularConstraintError(ConstraintError):
    """The dependent block of the constraint Jacobian is singular (or too ill-conditioned) at this state.

    Attributes:
        condition: Condition number of the dependent block (``inf`` when exactly singular).
    """

    def __init__(self, message: str, condition: float = float("inf")) -> None:
        super().__init__(message)
        self.condition = condition


class NonFiniteError(RobotDynError):
    """A computed result that is not finite (NaN or infinite): never returned as a number."""


class TimeLimitError(RobotDynError):
    """A simulation that exceeded its wall-clock time limit (``simulate(..., time_limit=...)``)."""


class OutputError(RobotDynError):
    """An output file that cannot be written (missing directory, a directory, no permission, full disk, format)."""


class RobotDynWarning(UserWarning):
    """Something robotdyn worked around or could not check, said in one line (the CLI prints
    ``robotdyn: warning: ...``): e.g. meshes not drawn, or a row dropped as redundant that a state violates."""
