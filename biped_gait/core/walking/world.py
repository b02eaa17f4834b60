"""The walking robot in the world frame: from a walker sample (model coordinates, stance leg 1)
to what visualization and other nodes need, with the right or left foot in stance.

World frame: x forward, y left, z up, origin at the first stance foot's... lateral midline: the
feet are at y = -/+ hip_half_width. A step's model axes are the world's turned by the walk's
heading about the vertical (zero on straight gaits) and, with the left foot in stance, mirrored
(y -> -y): the model is then the mirror image of the robot, positions mirror, axial vectors
(angular velocity, angular momentum) map to (-x, y, -z) of the model's, and the URDF's joints
swap sides (``urdf.UrdfJoints.array``).
Link transforms are computed from the URDF by Pinocchio, as robot_state_publisher would. Many
instants are computed in one call (``WorldView.pictures``, in the compiled twin when it is built).
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np
import pinocchio as pin

from ..dynamics.samples import JointPlacements, SampleEvaluator
from ..model.biped import BipedModel
from ..model.exchange import world_axes
from ..model.urdf import UrdfJoints, make_urdf

WORLD_FRAME = "world"
ODOM_FRAME = "odom"  # REP 105: world -> odom (static, the identity: the simulated odometry is exact) -> base_link
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
    joint_efforts: list[float]  # N m: the torques that act at the joints
    pelvis_position: np.ndarray
    pelvis_quaternion: np.ndarray
    pelvis_linear_velocity: np.ndarray  # in the pelvis frame (m/s), as nav_msgs/Odometry's twist
    pelvis_angular_velocity: np.ndarray  # in the pelvis frame (rad/s)
    stance_foot: np.ndarray
    com: np.ndarray
    momentum_about_foot: np.ndarray  # kg m^2/s, world axes
    momentum_about_com: np.ndarray
    link_transforms: list[Transform]


@dataclass(frozen=True, eq=False)
class WorldPictures:
    """Many instants of the walk in world terms, one per row, for one stance foot: what a
    ``WorldState`` holds for one instant (SI units; quaternions x, y, z, w)."""

    joint_names: tuple[str, ...]  # the URDF's moving joints
    joint_positions: np.ndarray  # n x joints, ``joint_names`` order (rad)
    joint_velocities: np.ndarray  # n x joints (rad/s)
    joint_efforts: np.ndarray  # n x joints (N m): the torques that act at the joints
    pelvis_position: np.ndarray  # n x 3, world (m)
    pelvis_quaternion: np.ndarray  # n x 4, pelvis in world
    pelvis_linear_velocity: np.ndarray  # n x 3, in the pelvis frame (m/s)
    pelvis_angular_velocity: np.ndarray  # n x 3, in the pelvis frame (rad/s)
    stance_foot: np.ndarray  # 3, world (m)
    com: np.ndarray  # n x 3, world (m)
    momentum_about_foot: np.ndarray  # n x 3, kg m^2/s, world axes
    momentum_about_com: np.ndarray  # n x 3
    link_frames: tuple[tuple[str, str], ...]  # (parent, child) link of each moving URDF joint
    link_translations: np.ndarray  # n x joints x 3: each joint's child link in its parent link (m)
    link_quaternions: np.ndarray  # n x joints x 4

    def __len__(self) -> int:
        return len(self.pelvis_position)

    def rows(self, start: int, stop: int) -> "WorldPictures":
        """The instants ``start`` to ``stop`` (excluded) alone."""
        return replace(self, **{name: getattr(self, name)[start:stop] for name in _PER_INSTANT})

    def state(self, i: int) -> WorldState:
        """The ``i``-th instant as a ``WorldState``."""
        links = [Transform(ODOM_FRAME, BASE_FRAME, self.pelvis_position[i], self.pelvis_quaternion[i])]
        links += [Transform(parent, child, translation, quaternion) for (parent, child), translation, quaternion
                  in zip(self.link_frames, self.link_translations[i], self.link_quaternions[i])]
        return WorldState(
            joint_names=self.joint_names,
            joint_positions=self.joint_positions[i].tolist(),
            joint_velocities=self.joint_velocities[i].tolist(),
            joint_efforts=self.joint_efforts[i].tolist(),
            pelvis_position=self.pelvis_position[i],
            pelvis_quaternion=self.pelvis_quaternion[i],
            pelvis_linear_velocity=self.pelvis_linear_velocity[i],
            pelvis_angular_velocity=self.pelvis_angular_velocity[i],
            stance_foot=self.stance_foot.copy(),
            com=self.com[i],
            momentum_about_foot=self.momentum_about_foot[i],
            momentum_about_com=self.momentum_about_com[i],
            link_transforms=links,
        )


_PER_INSTANT = tuple(f.name for f in fields(WorldPictures) if f.name not in ("joint_names", "stance_foot", "link_frames"))


def _quaternion(rotation: np.ndarray) -> np.ndarray:
    return pin.Quaternion(rotation).coeffs().copy()  # x, y, z, w


class WorldView:
    """Computes ``WorldPictures`` and ``WorldState`` from model states; holds the URDF's Pinocchio
    model. ``native``: evaluate in the compiled twin (``samples``; None: when it is built)."""

    def __init__(self, bm: BipedModel, native: bool | None = None) -> None:
        self.bm = bm
        self.urdf = make_urdf(bm.params)
        self.urdf_model = pin.buildModelFromXML(self.urdf)
        self.samples = SampleEvaluator(bm, native)
        self.placements = JointPlacements(self.urdf_model, native)
        self.joints = UrdfJoints(bm.params.joints, bm.coordinates)
        self._columns = [self.urdf_model.joints[self.urdf_model.getJointId(name)].idx_q for name in self.joints.names]
        # (parent link, child link) of every moving joint, in the URDF model's order.
        self.link_frames = tuple(
            (BASE_FRAME if self.urdf_model.parents[jid] == 0 else self._link_of_joint(self.urdf_model.parents[jid]),
             self._link_of_joint(jid))
            for jid in range(1, self.urdf_model.njoints)
        )

    def _link_of_joint(self, jid: int) -> str:
        """The URDF link whose frame is joint ``jid``'s frame (its child link)."""
        for frame in self.urdf_model.frames:
            if frame.type == pin.FrameType.BODY and frame.parentJoint == jid and frame.placement.isIdentity():
                return frame.name
        raise LookupError(f"no link at joint {self.urdf_model.names[jid]}")

    def static_transforms(self) -> list[Transform]:
        """``world`` -> ``odom`` (the identity: the walk's odometry is exact, REP 105) and the URDF's
        fixed joints (hands and feet), for /tf_static."""
        out = [Transform(WORLD_FRAME, ODOM_FRAME, np.zeros(3), np.array([0.0, 0.0, 0.0, 1.0]))]
        for frame in self.urdf_model.frames:
            if frame.type == pin.FrameType.BODY and not frame.placement.isIdentity():
                parent = self._link_of_joint(frame.parentJoint)
                out.append(Transform(parent, frame.name, frame.placement.translation.copy(), _quaternion(frame.placement.rotation)))
        return out

    def pictures(self, q: np.ndarray, qd: np.ndarray, stance_side: str, stance_foot: np.ndarray,
                 heading: float = 0.0, torque: np.ndarray | None = None) -> WorldPictures:
        """The world pictures of model states (rows of ``q``, ``qd``) with the ``stance_side``
        foot at ``stance_foot`` and the step's model frame at ``heading`` (rad), the joint torques
        ``torque`` acting (rows, N m, model coordinates; None: none), evaluated in one call. A
        joint's torque maps as its rate does (the same sign: the power is the same)."""
        q, qd = np.atleast_2d(q), np.atleast_2d(qd)
        torque = np.zeros(q.shape) if torque is None else np.atleast_2d(torque)
        mirror = np.diag(world_axes(stance_side))  # positions: (x, y, z) -> (x, -/+ y, z)
        axial = -mirror if stance_side == "left" else np.ones(3)  # axial vectors under the mirror
        poses = self.samples.poses(q, qd, mirrored=stance_side == "left")
        positions = self.joints.array(q, stance_side)
        urdf_q = np.zeros((len(q), self.urdf_model.nq))
        urdf_q[:, self._columns] = positions
        translations, quaternions = self.placements.local(urdf_q)
        h_com = poses.angular_momentum - np.cross(poses.com, poses.momentum)
        turn = _Turn(heading)
        return WorldPictures(
            joint_names=self.joints.names,
            joint_positions=positions,
            joint_velocities=self.joints.array(qd, stance_side),
            joint_efforts=self.joints.array(torque, stance_side),
            pelvis_position=stance_foot + turn.vectors(mirror * poses.pelvis_position),
            pelvis_quaternion=turn.quaternions(poses.pelvis_quaternion),
            pelvis_linear_velocity=mirror * poses.pelvis_linear_velocity,
            pelvis_angular_velocity=axial * poses.pelvis_angular_velocity,
            stance_foot=np.array(stance_foot, dtype=float),
            com=stance_foot + turn.vectors(mirror * poses.com),
            momentum_about_foot=turn.vectors(axial * poses.angular_momentum),
            momentum_about_com=turn.vectors(axial * h_com),
            link_frames=self.link_frames,
            link_translations=translations,
            link_quaternions=quaternions,
        )

    def state(self, q: np.ndarray, qd: np.ndarray, stance_side: str, stance_foot: np.ndarray,
              heading: float = 0.0) -> WorldState:
        """The world picture of one model state (q, qd) with ``stance_side`` foot at ``stance_foot``
        and the step's model frame at ``heading`` (rad)."""
        return self.pictures(q, qd, stance_side, stance_foot, heading).state(0)


class _Turn:
    """The walk's heading (rad) applied to world vectors and orientations (rows): nothing at 0."""

    def __init__(self, heading: float) -> None:
        self.heading = heading
        c, s = np.cos(heading), np.sin(heading)
        self.rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])

    def vectors(self, rows: np.ndarray) -> np.ndarray:
        return rows if self.heading == 0.0 else rows @ self.rotation.T

    def quaternions(self, rows: np.ndarray) -> np.ndarray:
        """Quaternions (x, y, z, w rows) turned by the heading about the vertical: q_turn q."""
        if self.heading == 0.0:
            return rows
        c, s = np.cos(self.heading / 2), np.sin(self.heading / 2)  # q_turn = (0, 0, s, c)
        x, y, z, w = rows.T
        return np.column_stack([c * x - s * y, c * y + s * x, c * z + s * w, c * w - s * z])
