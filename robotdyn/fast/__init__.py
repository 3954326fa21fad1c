"""Stage 4, fast: the compiled evaluator (robotdyn._compiled, built from robotdyn/_compiled.cpp) and the one place that
chooses it.

Owns ``compiled`` (:class:`~robotdyn.fast.compiled.CompiledModel`, ``why_not``, ``Fallback``, ``available``) and
``dispatch`` (``ROBOTDYN_COMPILED``, ``use_compiled``, ``enabled``, ``compiled_model``, ``reduce``): every
caller that could take the compiled path asks robotdyn.fast.dispatch; ``compiled_applied`` (joint springs and
compliant wheels encoded for the evaluator) and ``applied_model`` (the compiled simulation's model of such robots). Imports the foundation, description,
constraints and reduction only.

Import rule (tests/test_layout.py enforces it): the stages are, in order, foundation (robotdyn.errors, robotdyn.inputs,
robotdyn.output) < description < constraints < reduction < fast < contact < robotdyn.robot < simulation <
interfaces < robotdyn.robots < sweep < cli; a module imports from its own stage and earlier ones only, eagerly or lazily.
"""
