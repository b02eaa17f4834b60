"""URDF of the biped with physical joint names, for visualization tools (robot_state_publisher,
Foxglove), generated from the same ``BipedParams`` as the dynamics models.

The URDF is rooted at the pelvis (``base_link``; a floating base in the world). Joints:
``torso_yaw`` (about the pelvis z), ``{right,left}_hip``, ``{right,left}_knee``,
``{right,left}_shoulder`` (about y). Angles follow the URDF convention (child relative to
parent, right-hand rule), so a positive hip angle swings that foot backward, a positive knee
angle flexes the knee, a positive shoulder angle swings that hand backward.
"""

from __future__ import annotations

import numpy as np

from .biped import JOINT_NAMES
from .params import BipedParams, Link

PHYSICAL_JOINTS = (
    "right_hip",
    "right_knee",
    "left_hip",
    "left_knee",
    "torso_yaw",
    "right_shoulder",
    "left_shoulder",
)


# Where each of PHYSICAL_JOINTS comes from in the model's q (stance leg 1): (index, sign), for a
# right and for a left stance foot. With the left foot in stance the model is the robot's mirror
# image (docs/model.md section 5): legs and arms swap and yaw changes sign.
_FROM_MODEL = {
    "right": ((3, -1.0), (2, -1.0), (7, 1.0), (8, 1.0), (4, 1.0), (5, 1.0), (6, 1.0)),
    "left": ((7, 1.0), (8, 1.0), (3, -1.0), (2, -1.0), (4, -1.0), (6, 1.0), (5, 1.0)),
}


def physical_joint_array(q: np.ndarray, stance_side: str = "right") -> np.ndarray:
    """URDF joint angles (rad), PHYSICAL_JOINTS order along the last axis, from the model's q
    (stance leg 1; one row or many) for the given stance side. Works for joint velocities too
    (the map is linear)."""
    if stance_side not in _FROM_MODEL:
        raise ValueError(f"stance side must be 'right' or 'left', got {stance_side!r}")
    index, sign = zip(*_FROM_MODEL[stance_side])
    return np.asarray(q)[..., list(index)] * np.array(sign)


def joint_roles(stance_side: str = "right") -> tuple[tuple[str, float], ...]:
    """Per joint of PHYSICAL_JOINTS, the model coordinate it is (a name of ``model.JOINT_NAMES``)
    and the sign: URDF angle = sign * that coordinate, with the ``stance_side`` foot in stance."""
    if stance_side not in _FROM_MODEL:
        raise ValueError(f"stance side must be 'right' or 'left', got {stance_side!r}")
    return tuple((JOINT_NAMES[index], sign) for index, sign in _FROM_MODEL[stance_side])


def physical_joint_positions(q: np.ndarray, stance_side: str = "right") -> dict[str, float]:
    """URDF joint angles (rad) by joint name from the model's q (stance leg 1) for the given
    stance side (``physical_joint_array``)."""
    return dict(zip(PHYSICAL_JOINTS, physical_joint_array(q, stance_side).tolist()))


def _vec(v) -> str:
    return " ".join(f"{x:.6g}" for x in v)


def _link(name: str, link: Link | None, com_z: float, color: str, visual_z: float, length: float) -> str:
    parts = [f'  <link name="{name}">']
    if link is not None:
        ixx, iyy, izz = link.inertia
        parts.append(
            f'    <inertial><origin xyz="0 0 {com_z:.6g}"/><mass value="{link.mass:.6g}"/>'
            f'<inertia ixx="{ixx:.6g}" ixy="0" ixz="0" iyy="{iyy:.6g}" iyz="0" izz="{izz:.6g}"/></inertial>'
        )
    if length > 0:
        parts.append(
            f'    <visual><origin xyz="0 0 {visual_z:.6g}"/><geometry><cylinder radius="0.035" length="{length:.6g}"/>'
            f'</geometry><material name="{color}"/></visual>'
        )
    parts.append("  </link>")
    return "\n".join(parts)


def _joint(name: str, kind: str, parent: str, child: str, xyz, axis=(0, 1, 0)) -> str:
    body = f'    <parent link="{parent}"/><child link="{child}"/><origin xyz="{_vec(xyz)}" rpy="0 0 0"/>'
    if kind != "fixed":
        body += f'\n    <axis xyz="{_vec(axis)}"/><limit lower="-3.1416" upper="3.1416" effort="1000" velocity="50"/>'
    return f'  <joint name="{name}" type="{kind}">\n{body}\n  </joint>'


def make_urdf(p: BipedParams) -> str:
    """URDF text of the biped described by ``p`` (SI units)."""
    s, t, tr, a = p.shin, p.thigh, p.trunk, p.arm
    out = [
        '<?xml version="1.0"?>',
        f'<robot name="biped_gait_{p.name.replace("-", "_")}">',
        '  <material name="trunk"><color rgba="0.25 0.45 0.75 1"/></material>',
        '  <material name="right"><color rgba="0.85 0.3 0.25 1"/></material>',
        '  <material name="left"><color rgba="0.3 0.7 0.35 1"/></material>',
        '  <link name="base_link">\n    <visual><geometry><box size="0.06 %.6g 0.06"/></geometry>'
        '<material name="trunk"/></visual>\n  </link>' % (2 * p.hip_half_width),
        _link("torso", tr, tr.com_offset - p.torso_joint_height, "trunk", tr.length / 2, tr.length),
        _joint("torso_yaw", "revolute", "base_link", "torso", (0, 0, p.torso_joint_height), (0, 0, 1)),
    ]
    for side, sign in (("right", -1.0), ("left", 1.0)):
        out += [
            _link(f"{side}_arm", a, -a.com_offset, side, -a.length / 2, a.length),
            _joint(f"{side}_shoulder", "revolute", "torso", f"{side}_arm", (0, sign * p.shoulder_half_width, p.shoulder_height)),
            _link(f"{side}_hand", None, 0, side, 0, 0),
            _joint(f"{side}_hand_fixed", "fixed", f"{side}_arm", f"{side}_hand", (0, 0, -a.length)),
            _link(f"{side}_thigh", t, -t.com_offset, side, -t.length / 2, t.length),
            _joint(f"{side}_hip", "revolute", "base_link", f"{side}_thigh", (0, sign * p.hip_half_width, 0)),
            _link(f"{side}_shin", s, -s.com_offset, side, -s.length / 2, s.length),
            _joint(f"{side}_knee", "revolute", f"{side}_thigh", f"{side}_shin", (0, 0, -t.length)),
            _link(f"{side}_foot", None, 0, side, 0, 0),
            _joint(f"{side}_foot_fixed", "fixed", f"{side}_shin", f"{side}_foot", (0, 0, -s.length)),
        ]
    out.append("</robot>")
    return "\n".join(out) + "\n"
