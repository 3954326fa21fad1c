"""The API's dynamics calls answer a vector of the wrong length with one line naming the entries expected
(before: numpy's ``matmul`` shape error from deep inside the projection)."""

import pytest

import robotdyn
from robotdyn.errors import InputError


@pytest.fixture(scope="module")
def robot():
    return robotdyn.load("quasimoro")


@pytest.mark.parametrize("call, expected", [
    (lambda r: r.reduced(r.neutral(), [1.0, 2.0]), "nu has 2 values; expected 3 values (theta1_dot, theta2_dot"),
    (lambda r: r.reduced([0.0, 0.0], [1.0, 2.0, 3.0]), "q has 2 values; expected 6 values (x, y, psi"),
    (lambda r: r.forward_dynamics(r.neutral(), [1.0, 2.0, 3.0], [1.0]), "tau has 1 values; expected 2 values"),
    (lambda r: r.forward_dynamics(r.neutral(), [1.0], [1.0, 1.0]), "nu has 1 values; expected 3 values"),
    (lambda r: r.inverse_dynamics(r.neutral(), [0.0, 0.0, 0.0], [1.0]), "nudot has 1 values; expected 3 values"),
    (lambda r: r.velocity(r.neutral(), [0.0] * 4), "nu has 4 values; expected 3 values"),
])
def test_wrong_length_is_one_line(robot, call, expected):
    with pytest.raises(InputError) as err:
        call(robot)
    assert expected in str(err.value) and "\n" not in str(err.value)


def test_right_lengths_unchanged(robot):
    """The guard changes no number: equal torques on a robot at rest accelerate both wheels alike."""
    nudot = robot.forward_dynamics(robot.neutral(), (0.0, 0.0, 0.0), (0.1, 0.1))
    assert abs(nudot[0] - nudot[1]) < 1e-12
