"""Stage 8, interfaces: robotdyn to and from files and screens.

Owns ``constraint_file`` (TOML constraint files -> RobotSpec), ``plotting``, ``viewer`` and ``scene_page``
(meshcat), ``comparison`` (computed vs paper values). Imports every earlier stage, never robotdyn.robots,
robotdyn.sweep or robotdyn.cli.

Import rule (tests/test_layout.py enforces it): the stages are, in order, foundation (robotdyn.errors, robotdyn.inputs,
robotdyn.output) < description < constraints < reduction < fast < contact < robotdyn.robot < simulation <
interfaces < robotdyn.robots < sweep < cli; a module imports from its own stage and earlier ones only, eagerly or lazily.
"""
