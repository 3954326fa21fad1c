"""Stage 3, reduction: projection onto minimal coordinates and the reduced equations of motion, in Python.

Owns ``projection`` (S from the constraint rows, the row choice), ``reduced_dynamics`` (M_r, h, g_r, B_r: the
Python reference of the reduced model, and :func:`~robotdyn.reduction.reduced_dynamics.reference`),
``operational_space`` (independent velocities that are a frame twist), ``actuation`` (motors -> input matrix),
``pull_back`` (back onto the constraint manifold), ``dynamics`` (energy) and ``joint_springs`` (springs and dampers
on joints). It does not know the compiled path:
robotdyn.fast builds on it and chooses. Imports the foundation, description and constraints only.

Import rule (tests/test_layout.py enforces it): the stages are, in order, foundation (robotdyn.errors, robotdyn.inputs,
robotdyn.output) < description < constraints < reduction < fast < contact < robotdyn.robot < simulation <
interfaces < robotdyn.robots < sweep < cli; a module imports from its own stage and earlier ones only, eagerly or lazily.
"""
