"""Stage 7, simulation: time integration and everything that drives it.

Owns ``engine`` (:func:`simulate`, the scipy engine), ``trajectory`` (:class:`Trajectory`, what every engine
returns), ``progress`` (a run's reporter), ``compiled_engine`` (the C++ integrators), ``stick_slip`` (exact
switching), ``streaming`` (long runs written to a CSV file in segments), ``torque_profile``, ``feedback`` (feedback
laws as data, run compiled), ``scenario``, ``control``, ``many_runs``, ``batch``, ``model_variants`` and ``flight``
(compliant wheels' lift-off and touch-down events). Imports every earlier stage (up to robotdyn.robot).
``robotdyn.simulation.simulate`` and
``robotdyn.simulation.Trajectory`` still work (re-exported lazily from ``engine`` and ``trajectory``).

Import rule (tests/test_layout.py enforces it): the stages are, in order, foundation (robotdyn.errors, robotdyn.inputs,
robotdyn.output) < description < constraints < reduction < fast < contact < robotdyn.robot < simulation <
interfaces < robotdyn.robots < sweep < cli; a module imports from its own stage and earlier ones only, eagerly or lazily.
"""


from .._lazy import lazy_exports

_EXPORTS = {'simulate': 'engine', 'Trajectory': 'trajectory', 'power': 'engine', 'MAX_SAMPLES': 'engine',
            'CsvSink': 'streaming', 'StreamResult': 'streaming', 'stream': 'streaming'}
__getattr__ = lazy_exports(__name__, _EXPORTS)
