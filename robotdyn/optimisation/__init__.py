"""Stage 8, optimisation: optimal motions on the reduced dynamics.

Owns ``trajectory`` (:class:`TrajectoryProblem`, :class:`TrajectorySolution`: minimum-effort motions by direct
collocation on IPOPT through CasADi, the analytic dynamics derivatives as the constraint Jacobian), ``posture``
(:class:`~robotdyn.optimisation.posture.PostureProblem`: the posture and holding torques at rest with the least
peak required mu, the analytic contact-force derivatives as the constraint Jacobian) and ``callbacks`` (the CasADi
callback plumbing both use). Imports every
earlier stage (up to robotdyn.simulation, for the torque profile of an optimal motion); CasADi only when a problem
is solved.
"""

from .trajectory import TrajectoryProblem, TrajectorySolution

__all__ = ["TrajectoryProblem", "TrajectorySolution"]
