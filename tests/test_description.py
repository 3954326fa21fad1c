"""The description layer: xacro expansion, URDF validation and natural coordinates."""

from __future__ import annotations

import io

import numpy as np
import pinocchio as pin
import pytest
import yourdfpy

from robotdyn.description.urdf import URDF_DIR, build_description, expand_xacro
from robotdyn.errors import DescriptionError


def test_natural_coordinates_match_pinocchio_planar_joint():
    """The (x, y, psi) chain and unbounded revolute wheels place every frame where Pinocchio's own planar joint
    (x, y, cos, sin) and continuous joints (cos, sin) do, and where yourdfpy's forward kinematics does."""
    urdf = expand_xacro(URDF_DIR / "quasimoro.urdf.xacro")
    ours = build_description(urdf, "planar")
    ref = pin.buildModelFromXML(urdf, pin.JointModelPlanar())
    assert ours.model.nq == ours.model.nv == 6 and ref.nq == 4 + 3 * 2
    d1, d2 = ours.model.createData(), ref.createData()
    rng = np.random.default_rng(0)
    for _ in range(10):
        q = rng.uniform(-3, 3, 6)
        qref = np.zeros(ref.nq)
        qref[:4] = [q[0], q[1], np.cos(q[2]), np.sin(q[2])]
        for name, value in zip(ours.joint_names, q):
            jid = ref.getJointId(name) if ref.existJointName(name) else None
            if jid is not None and ref.joints[jid].nq == 2:  # continuous joints in Pinocchio: (cos, sin)
                qref[ref.joints[jid].idx_q:ref.joints[jid].idx_q + 2] = [np.cos(value), np.sin(value)]
        pin.framesForwardKinematics(ours.model, d1, q)
        pin.framesForwardKinematics(ref, d2, qref)
        for frame in ("wheel_A", "wheel_B", "body_com"):
            a = d1.oMf[ours.model.getFrameId(frame)]
            b = d2.oMf[ref.getFrameId(frame)]
            assert np.allclose(a.homogeneous, b.homogeneous, atol=1e-12)
        # yourdfpy's forward kinematics agrees too (validates the URDF independently of Pinocchio)
        ydf = yourdfpy.URDF.load(io.StringIO(urdf), build_scene_graph=True, load_meshes=False)
        cfg = {n: q[i] for i, n in enumerate(ours.joint_names) if n in ydf.actuated_joint_names}
        ydf.update_cfg(cfg)
        base = pin.SE3(pin.rpy.rpyToMatrix(0, 0, q[2]), np.array([q[0], q[1], 0.0]))
        for frame in ("wheel_A", "body_com"):
            T = base.homogeneous @ ydf.get_transform(frame, "base")
            assert np.allclose(T, d1.oMf[ours.model.getFrameId(frame)].homogeneous, atol=1e-12)


def test_malformed_and_missing_descriptions(tmp_path):
    bad = tmp_path / "bad.urdf.xacro"
    bad.write_text('<robot name="x" xmlns:xacro="http://www.ros.org/wiki/xacro"><link name="a"></robot>')
    with pytest.raises(DescriptionError, match="cannot expand xacro bad.urdf.xacro"):
        expand_xacro(bad)
    with pytest.raises(DescriptionError, match="not found"):
        expand_xacro(tmp_path / "nothing.xacro")
    undefined = tmp_path / "undef.urdf.xacro"
    undefined.write_text('<robot name="x" xmlns:xacro="http://www.ros.org/wiki/xacro"><link name="${nope}"/></robot>')
    with pytest.raises(DescriptionError, match="nope"):
        expand_xacro(undefined)
    with pytest.raises(DescriptionError, match="unknown root joint kind"):
        build_description(expand_xacro(URDF_DIR / "quasimoro.urdf.xacro"), "spherical")


def test_error_messages_are_one_line(tmp_path):
    bad = tmp_path / "bad.urdf.xacro"
    bad.write_text("<robot><link name='a'/><joint name='j' type='revolute'><parent link='a'/></joint></robot>")
    with pytest.raises(DescriptionError) as err:
        build_description(expand_xacro(bad))
    assert "\n" not in str(err.value)


def test_units_follow_joint_types():
    import robotdyn

    units = robotdyn.load("quasimoro").units
    assert units["x"] == "m" and units["psi"] == "rad" and units["theta1_dot"] == "rad/s"
    units = robotdyn.load("mmr12_eod").units
    assert units["lambda2"] == "m" and units["lambda2_dot"] == "m/s" and units["theta1"] == "rad"


def test_every_placeholder_inertia_is_named_at_once(tmp_path):
    """Two links with impossible inertials: both are named in one line, with the hint to declare them massless."""
    from robotdyn.description.urdf import validate_urdf
    from robotdyn.errors import DescriptionError

    bad = ('<inertial><mass value="1e-6"/><inertia ixx="-1e-8" iyy="1e-9" izz="1e-9" ixy="0" ixz="0" iyz="0"/>'
           '</inertial>')
    urdf = (f'<robot name="r"><link name="base"/><link name="antenna_l">{bad}</link><link name="antenna_r">{bad}'
            '</link><joint name="a" type="fixed"><parent link="base"/><child link="antenna_l"/></joint>'
            '<joint name="b" type="fixed"><parent link="base"/><child link="antenna_r"/></joint></robot>')
    with pytest.raises(DescriptionError) as exc:
        validate_urdf(urdf)
    msg = str(exc.value)
    assert "\n" not in msg and "2 links" in msg and "antenna_l" in msg and "antenna_r" in msg
    assert 'massless = ["antenna_l", "antenna_r"]' in msg
