"""URDF of the biped with physical joint names, for visualization tools (robot_state_publisher,
Foxglove), generated from the same ``BipedParams`` and joint table as the dynamics models.

The URDF is rooted at the pelvis (``base_link``; a floating base in the world). Its moving joints
are the table's (``JointTable.physical_joints``): each leg's hip joints and knee, right then left
(``right_hip``, ``right_knee``, ... for the paper's nine coordinates; ``right_hip_yaw``,
``right_hip_roll``, ``right_hip_pitch`` with hip joints), ``torso_yaw``, the shoulders. Angles
follow the URDF convention (child relative to parent, right-hand rule about the joint's axis),
so a positive hip pitch swings that foot backward, a positive knee angle flexes the knee, a
positive shoulder angle swings that hand backward. Limits are the table's.
"""

from __future__ import annotations

import numpy as np

from .joints import Coordinate, JointSpec, JointTable
from .params import BipedParams, Link


class UrdfJoints:
    """The URDF's moving joints and where each comes from in the model's q (stance leg 1), for a
    right and for a left stance foot. With the left foot in stance the model is the robot's
    mirror image (docs/model.md section 5): legs and arms swap sides and lateral angles (about x
    or z) change sign; a stance leg's coordinate is its joint's inverse rotation."""

    def __init__(self, table: JointTable, coordinates: tuple[Coordinate, ...]) -> None:
        self.names = table.physical_names()
        self._maps = {}
        for stance in ("right", "left"):
            index, sign = [], []
            for spec, side in table.physical_joints():
                model_side = "" if not side else ("stance" if side == stance else "swing")
                k = next(k for k, c in enumerate(coordinates) if c.spec is spec and c.side == model_side)
                mirror = -1.0 if stance == "left" and spec.lateral else 1.0
                index.append(k)
                sign.append((-1.0 if coordinates[k].inverted else 1.0) * mirror)
            self._maps[stance] = (index, np.array(sign))
        self._coordinates = coordinates

    def _map(self, stance_side: str) -> tuple[list[int], np.ndarray]:
        if stance_side not in self._maps:
            raise ValueError(f"stance side must be 'right' or 'left', got {stance_side!r}")
        return self._maps[stance_side]

    def array(self, q: np.ndarray, stance_side: str = "right") -> np.ndarray:
        """URDF joint angles (rad), ``names`` order along the last axis, from the model's q (one
        row or many) for the given stance side. Works for joint velocities too (the map is
        linear)."""
        index, sign = self._map(stance_side)
        return np.asarray(q)[..., index] * sign

    def positions(self, q: np.ndarray, stance_side: str = "right") -> dict[str, float]:
        """URDF joint angles (rad) by joint name (``array``)."""
        return dict(zip(self.names, self.array(q, stance_side).tolist()))

    def roles(self, stance_side: str = "right") -> tuple[tuple[str, float], ...]:
        """Per URDF joint, the model coordinate it is (its name) and the sign: URDF angle =
        sign * that coordinate, with the ``stance_side`` foot in stance."""
        index, sign = self._map(stance_side)
        return tuple((self._coordinates[k].name, float(s)) for k, s in zip(index, sign))


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


def _joint(name: str, spec: JointSpec | None, parent: str, child: str, xyz) -> str:
    kind = "fixed" if spec is None else "revolute"
    body = f'    <parent link="{parent}"/><child link="{child}"/><origin xyz="{_vec(xyz)}" rpy="0 0 0"/>'
    if spec is not None:
        axis = {"x": (1, 0, 0), "y": (0, 1, 0), "z": (0, 0, 1)}[spec.axis]
        lim = spec.limits
        body += (f'\n    <axis xyz="{_vec(axis)}"/><limit lower="{lim.lower:.6g}" upper="{lim.upper:.6g}" '
                 f'effort="{lim.effort:.6g}" velocity="{lim.velocity:.6g}"/>')
    return f'  <joint name="{name}" type="{kind}">\n{body}\n  </joint>'


def make_urdf(p: BipedParams) -> str:
    """URDF text of the biped described by ``p`` (SI units)."""
    s, t, tr, a = p.shin, p.thigh, p.trunk, p.arm
    table = p.joints
    torso = table.role("torso_yaw")
    shoulder = table.role("shoulder")
    out = [
        '<?xml version="1.0"?>',
        f'<robot name="biped_gait_{p.name.replace("-", "_")}">',
        '  <material name="trunk"><color rgba="0.25 0.45 0.75 1"/></material>',
        '  <material name="right"><color rgba="0.85 0.3 0.25 1"/></material>',
        '  <material name="left"><color rgba="0.3 0.7 0.35 1"/></material>',
        '  <link name="base_link">\n    <visual><geometry><box size="0.06 %.6g 0.06"/></geometry>'
        '<material name="trunk"/></visual>\n  </link>' % (2 * p.hip_half_width),
        _link("torso", tr, tr.com_offset - p.torso_joint_height, "trunk", tr.length / 2, tr.length),
        _joint(torso.name, torso, "base_link", "torso", (0, 0, p.torso_joint_height)),
    ]
    for side, sign in (("right", -1.0), ("left", 1.0)):
        out += [
            _link(f"{side}_arm", a, -a.com_offset, side, -a.length / 2, a.length),
            _joint(shoulder.named(side), shoulder, "torso", f"{side}_arm", (0, sign * p.shoulder_half_width, p.shoulder_height)),
            _link(f"{side}_hand", None, 0, side, 0, 0),
            _joint(f"{side}_hand_fixed", None, f"{side}_arm", f"{side}_hand", (0, 0, -a.length)),
        ]
        out.append(_link(f"{side}_thigh", t, -t.com_offset, side, -t.length / 2, t.length))
        parent, xyz = "base_link", (0, sign * p.hip_half_width, 0)
        for role in table.hip_roles:  # from the pelvis; the joints between them carry massless links
            spec = table.role(role)
            child = f"{side}_thigh" if spec.child == "thigh" else spec.child.replace("{side}", side)
            if spec.child != "thigh":
                out.append(_link(child, None, 0, side, 0, 0))
            out.append(_joint(spec.named(side), spec, parent, child, xyz))
            parent, xyz = child, (0, 0, 0)
        knee = table.role("knee")
        out += [
            _link(f"{side}_shin", s, -s.com_offset, side, -s.length / 2, s.length),
            _joint(knee.named(side), knee, f"{side}_thigh", f"{side}_shin", (0, 0, -t.length)),
            _link(f"{side}_foot", None, 0, side, 0, 0),
            _joint(f"{side}_foot_fixed", None, f"{side}_shin", f"{side}_foot", (0, 0, -s.length)),
        ]
    out.append("</robot>")
    return "\n".join(out) + "\n"
