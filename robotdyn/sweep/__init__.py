"""Stage 10, sweep: parameter sweeps on Dask into Parquet.

Owns ``spec`` (the sweep TOML), ``plan`` (runs and their identity), ``chunk`` (what a worker runs), ``batched``
(runs as variants of one compiled model), ``store``
(Parquet), ``plot`` and ``runner`` (:func:`run`, :func:`load`). Imports every earlier stage (robots included),
never robotdyn.cli. ``robotdyn.sweep.run`` and ``robotdyn.sweep.load`` still work (re-exported lazily).

Import rule (tests/test_layout.py enforces it): the stages are, in order, foundation (robotdyn.errors, robotdyn.inputs,
robotdyn.output) < description < constraints < reduction < fast < contact < robotdyn.robot < simulation <
interfaces < robotdyn.robots < sweep < cli; a module imports from its own stage and earlier ones only, eagerly or lazily.
"""


from .._lazy import lazy_exports

_EXPORTS = {'run': 'runner', 'load': 'runner', 'load_trajectory': 'runner', 'SweepResult': 'runner'}
__getattr__ = lazy_exports(__name__, _EXPORTS)
