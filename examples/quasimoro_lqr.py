"""Balance Quasimoro's body upright with an LQR designed on the linearised reduced dynamics.

Quasimoro's intermediate body hangs below the wheel axle at theta3 = 0; at theta3 = pi it stands inverted above it,
an unstable equilibrium (one eigenvalue of A near +6.3 1/s). The steps:

1. linearise the reduced dynamics about (theta3 = pi, nu = 0, tau = 0) (robotdyn.reduction.linearization, built on
   Robot.dynamics_derivatives);
2. keep the states the wheel motors can reach (the body angle and the three velocities; the base's x, y, heading and
   the wheel angles do not enter the dynamics and are not stabilisable by this input);
3. LQR gain from scipy's Riccati solver;
4. simulate the nonlinear robot from 0.2 rad off upright with tau = -K (x - x0), given as data (lqr_law: a
   FeedbackLaw, so the closed loop runs on the compiled integrator).

Run: ``python examples/quasimoro_lqr.py`` (add ``--plot FILE.png`` for a figure). Same model from the command line:
``robotdyn linearize quasimoro --set theta3=3.14159 --states theta3 theta1_dot theta2_dot theta3_dot
--lqr-q 10 1 1 1 --lqr-r 1 1``.
"""

from __future__ import annotations

import argparse

import numpy as np

import robotdyn
from robotdyn.reduction.linearization import linearize, lqr
from robotdyn.simulation.engine import simulate
from robotdyn.simulation.feedback import lqr_law

STATES = ["theta3", "theta1_dot", "theta2_dot", "theta3_dot"]
Q_WEIGHTS = [10.0, 1.0, 1.0, 1.0]  # body angle [1/rad^2], wheel and body rates [s^2/rad^2]
R_WEIGHTS = [1.0, 1.0]  # motor torques [1/(N m)^2]


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=5.0, help="simulated time [s]")
    parser.add_argument("--plot", help="save theta3 - pi and the torques against time to this image")
    args = parser.parse_args(argv)

    robot = robotdyn.load("quasimoro")
    q0 = robot.neutral()
    q0[robot.coordinate_index("theta3")] = np.pi
    model = linearize(robot, q0, np.zeros(robot.mobility), np.zeros(len(robot.motors))).restrict(STATES)
    K, closed = lqr(model, Q_WEIGHTS, R_WEIGHTS)
    print("open-loop eigenvalues [1/s]:  ", np.round(model.eigenvalues, 4))
    print("closed-loop eigenvalues [1/s]:", np.round(closed, 4))
    print("LQR gain K (rows m1, m2; columns " + ", ".join(STATES) + "):\n", np.round(K, 4))

    torque = lqr_law(model, K)  # lqr_torque's law as data: the run is compiled
    start = q0.copy()
    start[robot.coordinate_index("theta3")] += 0.2
    traj = simulate(robot, args.t_end, start, np.zeros(robot.mobility), torque, n_out=501, rtol=1e-8, atol=1e-10,
                    progress=False)
    error = traj.q[:, robot.coordinate_index("theta3")] - np.pi
    print(f"theta3 - pi: {error[0]:.3f} rad at t = 0, {error[-1]:.2e} rad at t = {traj.t[-1]:g} s")
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        taus = np.array([torque(t, q, nu) for t, q, nu in zip(traj.t, traj.q, traj.nu)])
        fig, ax = plt.subplots(2, 1, sharex=True, figsize=(6, 5))
        ax[0].plot(traj.t, error)
        ax[0].set_ylabel("theta3 - pi [rad]")
        ax[1].plot(traj.t, taus, label=["m1", "m2"])
        ax[1].set_ylabel("torque [N m]")
        ax[1].set_xlabel("t [s]")
        ax[1].legend()
        fig.tight_layout()
        fig.savefig(args.plot)
        print(f"figure: {args.plot}")
    return {"error": error, "closed": closed, "K": K}


if __name__ == "__main__":
    main()
