"""Optimal motions: trajectory optimisation on the reduced dynamics (:mod:`robotdyn.optimisation.trajectory`)."""

from .trajectory import TrajectoryProblem, TrajectorySolution

__all__ = ["TrajectoryProblem", "TrajectorySolution"]
