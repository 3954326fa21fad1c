"""Stage 1, description: a robot's Xacro/URDF text -> a Pinocchio model in natural coordinates.

Owns ``urdf`` (Xacro expansion, URDF validation, the natural coordinates, :func:`build_description`),
``ros_packages`` (``$(find PKG)`` and ``package://`` lookup), ``visual_geometry`` (meshes for the viewer) and
``kinematics`` (frame poses, position IK on the model). Imports only the foundation modules (robotdyn.errors,
robotdyn.inputs, robotdyn.output).

Import rule (tests/test_layout.py enforces it): the stages are, in order, foundation (robotdyn.errors, robotdyn.inputs,
robotdyn.output) < description < constraints < reduction < fast < contact < robotdyn.robot < simulation <
interfaces < robotdyn.robots < sweep < cli; a module imports from its own stage and earlier ones only, eagerly or lazily.
"""


from .._lazy import lazy_exports

_EXPORTS = {'build_description': 'urdf', 'expand_xacro': 'urdf', 'Description': 'urdf', 'xacro_value': 'urdf', 'validate_urdf': 'urdf', 'URDF_DIR': 'urdf', 'ROOT_KINDS': 'urdf'}
__getattr__ = lazy_exports(__name__, _EXPORTS)
