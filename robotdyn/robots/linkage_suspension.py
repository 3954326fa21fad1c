"""Six-wheel mobile robot with linkage suspension (Chen, Wang, Zhong, Zhu, Wang).

Paper: "Kinematics Analysis and Simulation of Mobile Robot Based on Linkage Suspension"
(``shared/papers/chen_linkage_suspension_six_wheel.txt``). Description: ``urdf/linkage_suspension.urdf.xacro``
(the mechanism, our reading of Figs. 1-3, and the dimensions, our own: the paper prints none).
"""

from __future__ import annotations

import numpy as np

from ..robot import Closure, MotorSpec, Parameter, RobotSpec, Wheel

THETA0 = np.pi / 3
"""Default nominal rocker angle theta0 [rad] (xacro default)."""

_WHEEL_KIND = {1: "omni", 2: "standard", 3: "omni", 4: "omni", 5: "standard", 6: "omni"}

SPEC = RobotSpec(
    name="linkage_suspension",
    title="Six-wheel robot with linkage suspension on uneven terrain (Chen et al., wheel-centre kinematics)",
    xacro="linkage_suspension.urdf.xacro",
    root="floating",
    paper="chen_linkage_suspension_six_wheel.txt",
    parameters=[
        Parameter("a1", 0.05, "m", "Table 1: rocker pivot D ahead of the body frame R"),
        Parameter("d1", 0.10, "m", "Table 1: rocker pivot D below R"),
        Parameter("a5", 0.20, "m", "Table 1: rocker back arm D -> bogie pivot B2"),
        Parameter("d5", 0.22, "m", "Table 1: half track (lateral offset of bogie and wheels)"),
        Parameter("a6", 0.1232, "m", "Table 1: bogie pivot -> middle wheel"),
        Parameter("a7", 0.15, "m", "Table 1: bogie pivot -> rear wheel"),
        Parameter("theta0", float(THETA0), "rad", "nominal rocker angle (posture on flat ground)"),
        Parameter("r", 0.14, "m", "wheel radius (0.73 m/s / 300 deg/s = 0.139 m, section 3)"),
        Parameter("xF", 0.10, "m", "front-rod pivot F on the body, x in R"),
        Parameter("zF", -0.05, "m", "front-rod pivot F, z in R"),
        Parameter("xW", 0.32, "m", "front wheel centre, x in R (nominal)"),
        Parameter("lam", 0.5, "-", "slider pivot G = F + lam (W - F) on the front rod"),
        Parameter("xO", 0.15, "m", "suspension-link pivot O, x in R"),
        Parameter("zO", 0.10, "m", "suspension-link pivot O, z in R"),
        Parameter("wL", 0.16, "m", "half length of the suspension link"),
        Parameter("hr", 0.20, "m", "connecting-rod length (suspension link -> rocker ball joint)"),
        Parameter("m_body", 25.0, "kg", "body mass"),
        Parameter("m_rocker", 1.2, "kg", "rocker mass (each)"),
        Parameter("m_bogie", 0.8, "kg", "bogie (rear linkage) mass (each)"),
        Parameter("m_rod", 0.6, "kg", "front linkage mass (each)"),
        Parameter("m_wheel", 1.0, "kg", "middle rubber wheel mass (each)"),
        Parameter("m_omni", 0.8, "kg", "omni wheel mass (each)"),
        Parameter("m_link", 0.3, "kg", "suspension link mass"),
        Parameter("rho", 0.0, "rad", "omni roller angle rho of eq 2 (0: 90-degree omni wheel)", xacro=False),
        Parameter("g", 9.81, "m/s^2", "gravitational acceleration", xacro=False),
    ],
    wheels=[
        Wheel(f"wheel{i}", "r", kind=_WHEEL_KIND[i], roller_angle="rho" if _WHEEL_KIND[i] == "omni" else 0.0,
              name=f"wheel{i}")
        for i in range(1, 7)
    ],
    closures=[
        Closure("guide_R", "block_R", ("y", "z", "rx", "ry", "rz"), name="slider_R"),
        Closure("guide_L", "block_L", ("y", "z", "rx", "ry", "rz"), name="slider_L"),
        Closure("ball_R", "rod_R_end", ("x", "y", "z"), name="ball_R"),
        Closure("ball_L", "rod_L_end", ("x", "y", "z"), name="ball_L"),
    ],
    motors=[MotorSpec(f"m{i}", f"wheel{i}_joint") for i in range(1, 7)],
    labels={
        "rocker_R_joint": "theta1", "rocker_L_joint": "theta2",
        "bogie_R_joint": "beta1", "bogie_L_joint": "beta2",
        "front_rod_R_joint": "gamma1", "front_rod_L_joint": "gamma2",
        "slider_R_joint": "sigma1", "slider_L_joint": "sigma2",
        "susp_link_joint": "psi",
        "rod_R_x": "rod1_x", "rod_R_y": "rod1_y", "rod_L_x": "rod2_x", "rod_L_y": "rod2_y",
        **{f"wheel{i}_joint": f"phi{i}" for i in range(1, 7)},
    },
    independent=["phi2", "phi5"],
    neutral={"z": 0.34, "theta1": float(THETA0), "theta2": float(THETA0),
             "beta1": float(THETA0 + np.pi / 2), "beta2": float(THETA0 + np.pi / 2)},
)
