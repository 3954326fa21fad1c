"""Stage 2, constraints: the per-constraint reference formulas (rows A, drift, residual) and the ground.

Owns ``constraint`` (KinematicState, ConstraintRows, the Constraint protocol), ``rolling_contact`` (standard, omni
and support wheels), ``loop_closure``, ``joint_coupling``, ``terrain``, ``posture`` (wheels put on a terrain) and
``redundancy`` (checks of dropped dependent rows). These formulas are the reference; their compiled twins are
the headers of the same names in robotdyn/kernels/ (rolling_contact.hpp, ...; robotdyn.fast), kept in step by tests/test_compiled.py. Imports the foundation and
robotdyn.description only.

Import rule (tests/test_layout.py enforces it): the stages are, in order, foundation (robotdyn.errors, robotdyn.inputs,
robotdyn.output) < description < constraints < reduction < fast < contact < robotdyn.robot < simulation <
interfaces < robotdyn.robots < sweep < cli; a module imports from its own stage and earlier ones only, eagerly or lazily.
"""
