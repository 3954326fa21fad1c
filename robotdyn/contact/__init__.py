"""Stage 5, contact: what the wheels transmit: constraint and contact forces, friction laws, slip.

Owns ``contact_forces`` (the multipliers at a state), ``friction`` (laws), ``sliding`` (wheels that slip),
``stick_slip_wheel`` (wheels that stick or slide; their engine is robotdyn.simulation.stick_slip), ``traction``
(loads and required friction along a trajectory), ``impulse`` (impacts), ``statics``, ``compliant_contact`` (wheels
whose normal contact is a force law: they fly and land) and ``applied_forces`` (the state-dependent forces of joint
springs and compliant wheels, through S^T on every door). Imports the foundation, description, constraints, reduction and fast only (not robotdyn.robot: the layer above).

Import rule (tests/test_layout.py enforces it): the stages are, in order, foundation (robotdyn.errors, robotdyn.inputs,
robotdyn.output) < description < constraints < reduction < fast < contact < robotdyn.robot < simulation <
interfaces < robotdyn.robots < sweep < cli; a module imports from its own stage and earlier ones only, eagerly or lazily.
"""
