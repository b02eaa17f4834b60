"""The walking robot in the world frame: from a walker sample (model coordinates, stance leg 1)
to what visualization and other nodes need, with the right or left foot in stance.

World frame: x forward, y left, z up, origin at the first stance foot's... lateral midline: the
feet are at y = -/+ hip_half_width. With the left foot in stance the model is the mirror image
of the robot (y -> -y): positions mirror, axial vectors (angular velocity, angular momentum)
map to (-x, y, -z) of the model's, and the URDF's joints swap sides (``urdf.physical_joint_positions``).
Link transforms are computed from the URDF by Pinocchio, as robot_state_publisher would.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .hybrid import mirror_for
from .model import BipedModel, cross
from .urdf import PHYSICAL_JOINTS, make_urdf, physical_joint_positions

WORLD_FRAME = "world"
BASE_FRAME = "base_link"


@dataclass
class Transform:
    """A rigid transform from ``parent`` to ``child`` frame: translation (m), quaternion (x, y, z, w)."""

    parent: str
    child: str
    translation: np.ndarray
    quaternion: np.ndarray


@dataclass
class WorldState:
    """One instant of the walk in world terms (SI units; quaternions x, y, z, w)."""

    joint_names: tuple[str, ...]
    joint_positions: list[float]
    joint_velocities: list[float]
    pelvis_position: np.ndarray
    pelvis_quaternion: np.ndarray
    pelvis_linear_velocity: np.ndarray  # in the pelvis frame (m/s), as nav_msgs/Odometry's twist
    pelvis_angular_velocity: np.ndarray  # in the pelvis frame (rad/s)
    stance_foot: np.ndarray
    com: np.ndarray
    momentum_about_foot: np.ndarray  # kg m^2/s, world axes
    momentum_about_com: np.ndarray
    link_transforms: list[Transform]


def _quaternion(rotation: np.ndarray) -> np.ndarray:
    return pin.Quaternion(rotation).coeffs().copy()  # x, y, z, w


class WorldView:
    """Computes ``WorldState`` from model states; holds the URDF's Pinocchio model."""

    def __init__(self, bm: BipedModel) -> None:
        self.bm = bm
        self.urdf = make_urdf(bm.params)
        self.urdf_model = pin.buildModelFromXML(self.urdf)
        self.urdf_data = self.urdf_model.createData()
        self._pelvis = bm.single.getJointId("stance_hip")
        self._index = {name: self.urdf_model.joints[self.urdf_model.getJointId(name)].idx_q for name in PHYSICAL_JOINTS}
        # (joint id, parent link, child link) of every moving joint, in the URDF model's order.
        self._joints = [
            (jid, BASE_FRAME if self.urdf_model.parents[jid] == 0 else self._link_of_joint(self.urdf_model.parents[jid]),
             self._link_of_joint(jid))
            for jid in range(1, self.urdf_model.njoints)
        ]

    def _link_of_joint(self, jid: int) -> str:
        """The URDF link whose frame is joint ``jid``'s frame (its child link)."""
        for frame in self.urdf_model.frames:
            if frame.type == pin.FrameType.BODY and frame.parentJoint == jid and frame.placement.isIdentity():
                return frame.name
        raise LookupError(f"no link at joint {self.urdf_model.names[jid]}")

    def static_transforms(self) -> list[Transform]:
        """The URDF's fixed joints (hands and feet), for /tf_static."""
        out = []
        for frame in self.urdf_model.frames:
            if frame.type == pin.FrameType.BODY and not frame.placement.isIdentity():
                parent = self._link_of_joint(frame.parentJoint)
                out.append(Transform(parent, frame.name, frame.placement.translation.copy(), _quaternion(frame.placement.rotation)))
        return out

    def state(self, q: np.ndarray, qd: np.ndarray, stance_side: str, stance_foot: np.ndarray) -> WorldState:
        """The world picture of model state (q, qd) with ``stance_side`` foot at ``stance_foot``."""
        bm, model, data = self.bm, self.bm.single, self.bm.single_data
        m = mirror_for(stance_side)
        pin.forwardKinematics(model, data, q, qd)
        pelvis = data.oMi[self._pelvis]
        rotation = m @ pelvis.rotation @ m
        velocity = pin.getVelocity(model, data, self._pelvis, pin.ReferenceFrame.LOCAL)
        axial = -m if stance_side == "left" else np.eye(3)  # axial vectors under the mirror
        xd = np.concatenate([np.zeros(3), qd])
        p, h_foot, com = bm.momentum(q, xd)
        h_com = h_foot - cross(com, p)
        positions = physical_joint_positions(q, stance_side)
        velocities = physical_joint_positions(qd, stance_side)
        urdf_q = np.zeros(self.urdf_model.nq)
        for name, value in positions.items():
            urdf_q[self._index[name]] = value
        pin.forwardKinematics(self.urdf_model, self.urdf_data, urdf_q)
        links = [Transform(WORLD_FRAME, BASE_FRAME, stance_foot + m @ pelvis.translation, _quaternion(rotation))]
        for jid, parent, child in self._joints:
            placement = self.urdf_data.liMi[jid]
            links.append(Transform(parent, child, placement.translation.copy(), _quaternion(placement.rotation)))
        return WorldState(
            joint_names=PHYSICAL_JOINTS,
            joint_positions=[positions[n] for n in PHYSICAL_JOINTS],
            joint_velocities=[velocities[n] for n in PHYSICAL_JOINTS],
            pelvis_position=stance_foot + m @ pelvis.translation,
            pelvis_quaternion=_quaternion(rotation),
            pelvis_linear_velocity=m @ velocity.linear,
            pelvis_angular_velocity=axial @ velocity.angular,
            stance_foot=stance_foot.copy(),
            com=stance_foot + m @ com,
            momentum_about_foot=axial @ h_foot,
            momentum_about_com=axial @ h_com,
            link_transforms=links,
        )
