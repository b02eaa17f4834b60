"""ROS messages of the walking robot: the sampled topics of one step (``core.walking.world.WorldPictures``,
SI units, world frame) serialized all at once, as joint states, odometry, angular momentum and
transforms; the static transforms and the walk's events. No physics.

Each sampled message is built by a function of a flat vector of its numbers (floats, and ints:
the stamp's seconds and nanoseconds, the step), which ``CdrTemplate`` serializes once with rclpy
to know where the numbers go; a step's messages are then written into copies of those bytes.
"""

from __future__ import annotations

from functools import partial

import numpy as np
from builtin_interfaces.msg import Time as TimeMsg
from geometry_msgs.msg import Point, Quaternion, Transform, TransformStamped, Vector3
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState
from std_msgs.msg import Header
from tf2_msgs.msg import TFMessage

from biped_gait_interfaces.msg import AngularMomentum, GaitEvent

from ..core.walking.events import Touchdown
from ..core.walking.world import BASE_FRAME, ODOM_FRAME, WORLD_FRAME, Transform as WorldTransform, WorldPictures
from ..recording import topics
from .cdr_templates import CdrTemplate

SIDES = ("right", "left")


def stamp_msg(stamp_ns: int) -> TimeMsg:
    """builtin_interfaces/Time of ``stamp_ns`` (ns)."""
    return TimeMsg(sec=stamp_ns // 1_000_000_000, nanosec=stamp_ns % 1_000_000_000)


def stamp_ints(stamps_ns: np.ndarray) -> np.ndarray:
    """(seconds, nanoseconds) of each stamp (ns), as the rows of an n x 2 array."""
    stamps_ns = np.asarray(stamps_ns, dtype=np.int64)
    return np.stack([stamps_ns // 1_000_000_000, stamps_ns % 1_000_000_000], axis=1)


def _time(ints) -> TimeMsg:
    return TimeMsg(sec=int(ints[0]), nanosec=int(ints[1]))


def _vector(v) -> Vector3:
    return Vector3(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def _point(v) -> Point:
    return Point(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def _quaternion(q) -> Quaternion:
    return Quaternion(x=float(q[0]), y=float(q[1]), z=float(q[2]), w=float(q[3]))


def joint_state_msg(names: tuple[str, ...], floats: np.ndarray, ints: np.ndarray) -> JointState:
    """The URDF joints' (``names``) angles (rad, the first third of ``floats``), rates (rad/s, the
    second) and the torques that act (N m, the third: zero in the ballistic single support, the
    balance controller's while standing, a pulse's in a double support that lasts), stamped
    ``ints`` (s, ns)."""
    n = len(names)
    return JointState(header=Header(stamp=_time(ints)), name=list(names), position=floats[:n],
                      velocity=floats[n:2 * n], effort=floats[2 * n:])


def odometry_msg(floats: np.ndarray, ints: np.ndarray) -> Odometry:
    """The pelvis (``base_link``) pose in ``odom`` (REP 105; position m, quaternion x y z w) and its
    twist in ``base_link`` (m/s, rad/s): ``floats`` in that order, stamped ``ints`` (s, ns)."""
    odom = Odometry(header=Header(stamp=_time(ints), frame_id=ODOM_FRAME), child_frame_id=BASE_FRAME)
    odom.pose.pose.position = _point(floats[0:3])
    odom.pose.pose.orientation = _quaternion(floats[3:7])
    odom.twist.twist.linear = _vector(floats[7:10])
    odom.twist.twist.angular = _vector(floats[10:13])
    return odom


def momentum_msg(floats: np.ndarray, ints: np.ndarray, side: str) -> AngularMomentum:
    """Whole-body angular momentum (kg m^2/s, world axes): the stance foot (m), the momentum
    about it, the CoM (m), the momentum about it (``floats`` in that order); stamped ``ints[:2]``
    (s, ns), in step ``ints[2]`` on the ``side`` foot."""
    return AngularMomentum(header=Header(stamp=_time(ints), frame_id=WORLD_FRAME), stance_foot=_point(floats[0:3]),
                           about_stance_foot=_vector(floats[3:6]), com=_point(floats[6:9]),
                           about_com=_vector(floats[9:12]), step=int(ints[2]), stance_side=side)


def tf_msg(transforms: list[WorldTransform], stamp: TimeMsg) -> TFMessage:
    """A TFMessage of rigid transforms (m, quaternion x y z w), all stamped ``stamp``."""
    return TFMessage(transforms=[
        TransformStamped(header=Header(stamp=stamp, frame_id=t.parent), child_frame_id=t.child,
                         transform=Transform(translation=_vector(t.translation), rotation=_quaternion(t.quaternion)))
        for t in transforms
    ])


def _moving_tf_msg(frames: tuple[tuple[str, str], ...], floats: np.ndarray, ints: np.ndarray) -> TFMessage:
    """/tf of the pelvis in ``odom`` and of each (parent, child) link of ``frames``: 7 numbers
    each (translation m, quaternion x y z w), stamped ``ints`` (s, ns)."""
    links = [(ODOM_FRAME, BASE_FRAME), *frames]
    return tf_msg([WorldTransform(parent, child, floats[7 * k:7 * k + 3], floats[7 * k + 3:7 * k + 7])
                   for k, (parent, child) in enumerate(links)], _time(ints))


class SampleMessages:
    """The sampled topics of the walk, serialized a step at a time: ``/joint_states`` (the URDF's
    moving joints ``joint_names``), ``/odom``, ``/angular_momentum`` and ``/tf`` (the pelvis and the
    links of the URDF's moving joints ``link_frames``)."""

    def __init__(self, joint_names: tuple[str, ...], link_frames: tuple[tuple[str, str], ...]) -> None:
        self.joints = CdrTemplate(partial(joint_state_msg, joint_names), 3 * len(joint_names), 2)
        self.odometry = CdrTemplate(odometry_msg, 13, 2)
        self.momentum = {side: CdrTemplate(partial(momentum_msg, side=side), 12, 3) for side in SIDES}
        self.tf = CdrTemplate(partial(_moving_tf_msg, link_frames), 7 * (len(link_frames) + 1), 2)

    def encode(self, world: WorldPictures, stamps_ns: np.ndarray, step: int, side: str) -> dict[str, np.ndarray]:
        """Topic -> the serialized messages of the instants of ``world`` (one row each), stamped
        ``stamps_ns`` (ns), in ``step`` on the ``side`` foot."""
        n = len(world)
        stamps = stamp_ints(stamps_ns)
        pelvis = np.hstack([world.pelvis_position, world.pelvis_quaternion])
        links = np.concatenate([world.link_translations, world.link_quaternions], axis=2).reshape(n, -1)
        return {
            topics.JOINT_STATES: self.joints.encode(
                np.hstack([world.joint_positions, world.joint_velocities, world.joint_efforts]), stamps),
            topics.ODOM: self.odometry.encode(
                np.hstack([pelvis, world.pelvis_linear_velocity, world.pelvis_angular_velocity]), stamps),
            topics.ANGULAR_MOMENTUM: self.momentum[side].encode(
                np.hstack([np.tile(world.stance_foot, (n, 1)), world.momentum_about_foot, world.com,
                           world.momentum_about_com]),
                np.hstack([stamps, np.full((n, 1), step)])),
            topics.TF: self.tf.encode(np.hstack([pelvis, links]), stamps),
        }


def event_msg(kind: int, step: int, side: str, time_in_step: float, stamp: TimeMsg, message: str = "",
              touchdown: Touchdown | None = None, joint_names: tuple[str, ...] = ()) -> GaitEvent:
    """A GaitEvent; a touchdown's impulses (N m s) on the actuated joints ``joint_names``, W (N m s)
    and distance to the plan."""
    msg = GaitEvent(header=Header(stamp=stamp, frame_id=WORLD_FRAME), kind=kind, step=step, stance_side=side,
                    time_in_step=time_in_step, message=message)
    if touchdown is not None:
        msg.i_minus, msg.i_plus = touchdown.i_minus.tolist(), touchdown.i_plus.tolist()
        msg.joint_names = list(joint_names)
        msg.effort_cost, msg.state_error, msg.velocity_miss = touchdown.W, touchdown.state_error, touchdown.velocity_miss
    return msg
