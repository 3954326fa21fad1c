"""Quasimoro in MuJoCo, built from robotdyn's own model, on the 'rectilinear' manoeuvre (make bench, issue 17).

The MJCF is written from the robot's Pinocchio model (masses, centres of mass and central inertias of the body
and the two wheels; the joint placements: wheel centres at (0, +-l/2, r)), so that both simulators integrate the
same rigid bodies. robotdyn's axle frame is massless and turns with the root only, while MuJoCo needs a root body
with mass: the pendulum body is the free-floating root (frame at the axle midpoint C2), and each wheel hangs on it
by a hinge about the axle. The motors then act between wheel and body, which is what robotdyn's motors do
(``MotorSpec(..., reaction="body")``). The wheels are cylinders (radius r, the description's width) touching a
plane with MuJoCo's default soft contact (condim 3, friction 1); nothing else touches the ground.

Coordinates read back in robotdyn's convention: theta3 = -(rotation of the body about +y) (robotdyn's theta3 turns
about -y), theta1 = hinge angle - theta3 (robotdyn's wheel angle is taken from the non-pitching axle frame), x the
axle midpoint's x. Accuracy is measured against robotdyn's trajectory at the same sample times: the steady pitch
amplitude (half the peak-to-peak theta3 after 10 s), the largest forward-position difference, the deepest wheel
penetration r - z(C2) and the rolling drift x - r theta1 (zero for rolling without slip on flat ground).
"""

from __future__ import annotations

import time

import numpy as np

PULSE, PULSE_END = 0.1, 1.0  # the scenario's m1 = m2 = 0.1 sin(pi t) N m for t <= 1 s (Staicu, eq 19)


def mjcf(robot, timestep: float = 0.002, integrator: str | None = None) -> str:
    """MJCF text of ``robot`` (robotdyn's Quasimoro) at its parameters; MuJoCo's defaults except ``timestep``
    and, if given, ``integrator``."""
    model = robot.model
    jid = {name: model.getJointId(name) for name in ("theta1", "theta2", "theta3")}
    c2 = model.jointPlacements[jid["theta3"]].translation  # the axle midpoint above the ground: (0, 0, r)
    r = robot.params["r"]
    width = 0.08 * r / 0.3  # the description's wheel width (urdf/quasimoro.urdf.xacro)

    def inertial(j: int) -> str:
        inertia = model.inertias[j]
        I = inertia.inertia
        full = " ".join(f"{x:.17g}" for x in (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]))
        com = " ".join(f"{x:.17g}" for x in inertia.lever)
        return f'<inertial pos="{com}" mass="{inertia.mass:.17g}" fullinertia="{full}"/>'

    def wheel(name: str) -> str:
        pos = model.jointPlacements[jid[name]].translation - c2
        return (f'<body name="wheel_{name}" pos="{pos[0]:.17g} {pos[1]:.17g} {pos[2]:.17g}">'
                f'<joint name="{name}" type="hinge" axis="0 1 0"/>{inertial(jid[name])}'
                f'<geom type="cylinder" size="{r:.17g} {width / 2:.17g}" quat="0.7071067811865476 0.7071067811865476 0 0"/>'
                "</body>")

    g = -robot.model.gravity.linear[2]
    option = f'timestep="{timestep}" gravity="0 0 {-g:.17g}"' + (f' integrator="{integrator}"' if integrator else "")
    return f"""<mujoco model="quasimoro">
  <option {option}/>
  <worldbody>
    <geom name="floor" type="plane" size="0 0 1"/>
    <body name="body" pos="{c2[0]:.17g} {c2[1]:.17g} {c2[2]:.17g}">
      <freejoint name="root"/>
      {inertial(jid["theta3"])}
      {wheel("theta1")}
      {wheel("theta2")}
    </body>
  </worldbody>
  <actuator>
    <motor name="m1" joint="theta1"/>
    <motor name="m2" joint="theta2"/>
  </actuator>
</mujoco>"""


def simulate(robot, t_end: float, times: np.ndarray, timestep: float = 0.002, integrator: str | None = None) -> dict:
    """The rectilinear manoeuvre in MuJoCo, sampled at ``times`` (multiples of the step): x, z of C2, theta1,
    theta3 [m, rad], and the wall time of the stepping loop [s]."""
    import mujoco

    model = mujoco.MjModel.from_xml_string(mjcf(robot, timestep, integrator))
    data = mujoco.MjData(model)
    hinge = model.jnt_qposadr[model.joint("theta1").id]
    every = int(round((times[1] - times[0]) / timestep))
    if not np.allclose(times, np.arange(len(times)) * every * timestep, atol=1e-12):
        raise ValueError("sample times must be multiples of the step")
    out = np.empty((len(times), 4))
    R = np.empty(9)
    pulse_steps = int(round(PULSE_END / timestep))
    step = 0
    start = time.perf_counter()
    for i in range(len(times)):
        if i:
            if step < pulse_steps:  # the torque pulse: the control set at every step
                for _ in range(every):
                    tau = PULSE * np.sin(np.pi * data.time) if data.time <= PULSE_END else 0.0
                    data.ctrl[:] = tau
                    mujoco.mj_step(model, data)
            else:
                data.ctrl[:] = 0.0
                mujoco.mj_step(model, data, nstep=every)
            step += every
        mujoco.mju_quat2Mat(R, data.qpos[3:7])
        theta3 = -np.arctan2(R[2], R[8])  # rotation about +y: atan2(R[0, 2], R[2, 2])
        out[i] = data.qpos[0], data.qpos[2], data.qpos[hinge] - theta3, theta3
    wall = time.perf_counter() - start
    return {"t": times, "x": out[:, 0], "z": out[:, 1], "theta1": out[:, 2], "theta3": out[:, 3], "wall": wall,
            "steps": step}


def accuracy(run: dict, reference, r: float) -> dict:
    """Errors of a run (MuJoCo's dict, or a robotdyn trajectory as the same dict) against robotdyn's reference
    trajectory: relative pitch-amplitude error, max |x - x_ref| [m], deepest penetration r - z [m], final
    |x - r theta1| [m]."""
    after = reference.t >= 10.0
    ref_amp = 0.5 * np.ptp(reference.column("theta3")[after])
    amp = 0.5 * np.ptp(run["theta3"][after])
    return {"amplitude": ref_amp, "amplitude_error": abs(amp - ref_amp) / ref_amp,
            "x_error": float(np.max(np.abs(run["x"] - reference.column("x")))),
            "penetration": float(np.max(r - run["z"])),
            "rolling_drift": float(abs(run["x"][-1] - r * run["theta1"][-1]))}


def available() -> str | None:
    """MuJoCo's version, or ``None`` without it (it is the optional ``bench`` dependency)."""
    try:
        import mujoco
    except ImportError:
        return None
    return mujoco.__version__
