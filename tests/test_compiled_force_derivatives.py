"""The compiled contact-force and required-mu derivatives (robotdyn.contact.compiled_force_derivatives, C++ kernel
robotdyn/kernels/contact_forces_derivatives.hpp).

References, independent of the compiled code:
- the Python path (robotdyn.contact.force_derivatives.contact_force_derivatives: numpy's SVDs, Python frame passes,
  Pinocchio's Python bindings), equal to 1e-10 relative to the largest entry of each array, at random admissible
  states on rolling robots (Quasimoro through its floating twin, MMR12-EOD, the adaptable-wheel tricycle), the
  loop-closure linkage rover, and a statically indeterminate rigid four-wheel chassis (loads split by the rigid
  limit of compliance, with and without a wheel held unloaded by its active set);
- central finite differences with one Richardson step of the compiled forces themselves
  (tests/test_force_derivatives.check_against_differences, <= 1e-7 relative), on the indeterminate chassis with a
  wheel unloaded (the derivative of the active set's branch).
"""

from __future__ import annotations

import numpy as np
import pytest
from test_dynamics_derivatives import START, admissible_state
from test_force_derivatives import check_against_differences, rigid_husky

from robotdyn.constraints.posture import set_terrain, solve_posture
from robotdyn.constraints.terrain import RampTerrain
from robotdyn.contact.force_derivatives import contact_force_derivatives
from robotdyn.fast.compiled import available
from robotdyn.fast.compiled_derivatives import _CompiledDerivatives
from robotdyn.contact.compiled_force_derivatives import compiled_force_derivatives
from robotdyn.robot import Robot
from robotdyn.robots import module

def _has_kernel() -> bool:
    """Whether the built extension holds the kernel (built with ROBOTDYN_FORCE_DERIVATIVES defined)."""
    if not available():
        return False
    from robotdyn import _compiled

    return hasattr(_compiled.Evaluator, "force_layer")


pytestmark = pytest.mark.skipif(not _has_kernel(), reason="extension built without the force-derivative kernel")

ARRAYS = ("force", "dforce_dq", "dforce_dnu", "dforce_dtau", "required_mu", "dmu_dq", "dmu_dnu", "dmu_dtau", "lam",
          "dlam_dq", "dlam_dnu", "dlam_dtau", "dforce_dq_manifold")


def assert_paths_equal(robot, q, nu, tau):
    """The compiled result exists and equals the Python reference (every array to 1e-10 of its largest entry; the
    structure's names and flags exactly)."""
    fast = compiled_force_derivatives(robot, q, nu, tau)
    assert fast is not None and isinstance(fast.dynamics, _CompiledDerivatives)
    ref = contact_force_derivatives(robot, q, nu, tau)
    for name in ARRAYS:
        a, b = getattr(fast, name), getattr(ref, name)
        assert a.shape == b.shape, name
        finite = np.isfinite(b)
        assert np.array_equal(finite, np.isfinite(a)), name
        err = np.abs(a[finite] - b[finite]).max(initial=0.0)
        assert err <= 1e-10 * max(1.0, np.abs(b[finite]).max(initial=0.0)), (name, err)
    for name in ("wheels", "not_smooth", "unloaded", "labels", "source", "numerical"):
        assert getattr(fast, name) == getattr(ref, name), name
    assert np.array_equal(fast.known, ref.known) and np.array_equal(fast.positions, ref.positions)
    return fast


@pytest.mark.parametrize("name", ["quasimoro", "mmr12_eod", "linkage_suspension", "adaptable_wheel"])
def test_compiled_equals_the_python_path_on_built_in_robots(name):
    robot = Robot(module(name).SPEC)
    D = assert_paths_equal(robot, *admissible_state(robot, START[name], np.random.default_rng(5)))
    assert np.abs(D.dforce_dq).max() > 1e-2 and np.abs(D.dforce_dtau).max() > 1e-2  # not a vacuous comparison
    assert D.source == ("floating twin" if name == "quasimoro" else "model")


@pytest.mark.parametrize("deg", [30.0, 44.0])
def test_compiled_equals_the_python_path_on_an_indeterminate_chassis(deg, tmp_path):
    """Four wheels on a rigid chassis across a ramp: loads from the rigid limit of compliance; at 44 deg its
    active set holds the front right wheel unloaded."""
    robot = rigid_husky(tmp_path)
    set_terrain(robot, RampTerrain(np.tan(np.radians(deg))))
    q = solve_posture(robot, {"x": 0.0, "y": 0.0, "yaw": np.pi / 4}, tol=1e-13).q
    nu = np.array([0.3])
    tau = robot.inverse_dynamics(q, nu, np.zeros(1))[1] + np.array([0.5, -0.2, 0.1, 0.3])
    D = assert_paths_equal(robot, q, nu, tau)
    assert D.unloaded == (["front_right"] if deg > 40 else [])
    if deg > 40:  # and against Richardson differences of the compiled forces (Robot's dispatch: compiled)
        assert isinstance(robot.contact_force_derivatives(q, nu, tau).dynamics, _CompiledDerivatives)
        check_against_differences(robot, q, nu, tau)


def test_slipping_and_operational_robots_take_the_python_path():
    """Where the compiled dynamics derivatives do not serve, neither do these (the Python path answers)."""
    robot = Robot(module("omni_caster").SPEC)
    q, nu, tau = admissible_state(robot, START["omni_caster"], np.random.default_rng(2))
    assert compiled_force_derivatives(robot, q, nu, tau) is None
    assert robot.contact_force_derivatives(q, nu, tau).source == "floating twin"
