"""Stage 7, simulation: time integration and everything that drives it.

Owns ``engine`` (:func:`simulate`, :class:`Trajectory`, the scipy engine), ``compiled_engine`` (the C++ integrators),
``stick_slip`` (exact switching), ``streaming`` (long runs written to a CSV file in segments), ``torque_profile``, ``scenario``, ``control``, ``many_runs``, ``batch`` and
``model_variants``. Imports every earlier stage (up to robotdyn.robot). ``robotdyn.simulation.simulate`` and
``robotdyn.simulation.Trajectory`` still work (re-exported lazily from ``engine``).

Import rule (tests/test_layout.py enforces it): the stages are, in order, foundation (robotdyn.errors, robotdyn.inputs,
robotdyn.output) < description < constraints < reduction < fast < contact < robotdyn.robot < simulation <
interfaces < robotdyn.robots < sweep < cli; a module imports from its own stage and earlier ones only, eagerly or lazily.
"""


_EXPORTS = {'simulate': 'engine', 'Trajectory': 'engine', 'power': 'engine', 'MAX_SAMPLES': 'engine', 'CsvSink': 'streaming', 'StreamResult': 'streaming',
            'stream': 'streaming'}


def __getattr__(name: str):
    """The public names of the former flat module of this name, imported on first use."""
    if name in _EXPORTS:
        import importlib

        return getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
