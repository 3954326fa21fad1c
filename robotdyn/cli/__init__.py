"""Stage 11, cli: the ``robotdyn`` command line (``python -m robotdyn``), the top of the pipeline.

Owns ``commands`` (the parser and the subcommands), ``sweep`` (``robotdyn sweep``) and ``fk`` (``robotdyn fk``, which
robot modules register). May import every other stage. ``robotdyn.cli.main`` still works (re-exported lazily).

Import rule (tests/test_layout.py enforces it): the stages are, in order, foundation (robotdyn.errors, robotdyn.inputs,
robotdyn.output) < description < constraints < reduction < fast < contact < robotdyn.robot < simulation <
interfaces < robotdyn.robots < sweep < cli; a module imports from its own stage and earlier ones only, eagerly or lazily.
"""


from .._lazy import lazy_exports

_EXPORTS = {'main': 'commands', 'build_parser': 'commands'}
__getattr__ = lazy_exports(__name__, _EXPORTS)
