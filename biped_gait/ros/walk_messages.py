"""ROS messages of the walking robot: one ``core.world.WorldState`` (SI units, world frame) as
joint states, odometry, angular momentum and transforms, and the walk's events. No physics."""

from __future__ import annotations

from builtin_interfaces.msg import Time as TimeMsg
from geometry_msgs.msg import Point, Quaternion, Transform, TransformStamped, Vector3
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState
from std_msgs.msg import Header
from tf2_msgs.msg import TFMessage

from biped_gait_interfaces.msg import AngularMomentum, GaitEvent

from ..core.walk import Touchdown
from ..core.world import BASE_FRAME, WORLD_FRAME, Transform as WorldTransform, WorldState


def stamp_msg(stamp_ns: int) -> TimeMsg:
    """builtin_interfaces/Time of ``stamp_ns`` (ns)."""
    return TimeMsg(sec=stamp_ns // 1_000_000_000, nanosec=stamp_ns % 1_000_000_000)


def _vector(v) -> Vector3:
    return Vector3(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def _point(v) -> Point:
    return Point(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def _quaternion(q) -> Quaternion:
    return Quaternion(x=float(q[0]), y=float(q[1]), z=float(q[2]), w=float(q[3]))


def joint_state_msg(world: WorldState, stamp: TimeMsg) -> JointState:
    """The URDF joints' angles (rad) and rates (rad/s); efforts zero (N m): the single support
    is ballistic, no joint torque acts between the impulses of the double supports."""
    n = len(world.joint_names)
    return JointState(header=Header(stamp=stamp), name=list(world.joint_names), position=world.joint_positions,
                      velocity=world.joint_velocities, effort=[0.0] * n)


def odometry_msg(world: WorldState, stamp: TimeMsg) -> Odometry:
    """The pelvis (``base_link``) pose in ``world`` and its twist in ``base_link``."""
    odom = Odometry(header=Header(stamp=stamp, frame_id=WORLD_FRAME), child_frame_id=BASE_FRAME)
    odom.pose.pose.position = _point(world.pelvis_position)
    odom.pose.pose.orientation = _quaternion(world.pelvis_quaternion)
    odom.twist.twist.linear = _vector(world.pelvis_linear_velocity)
    odom.twist.twist.angular = _vector(world.pelvis_angular_velocity)
    return odom


def momentum_msg(world: WorldState, stamp: TimeMsg, step: int, side: str) -> AngularMomentum:
    """Whole-body angular momentum (kg m^2/s, world axes) about the stance foot and the CoM."""
    return AngularMomentum(header=Header(stamp=stamp, frame_id=WORLD_FRAME), stance_foot=_point(world.stance_foot),
                           about_stance_foot=_vector(world.momentum_about_foot), com=_point(world.com),
                           about_com=_vector(world.momentum_about_com), step=step, stance_side=side)


def tf_msg(transforms: list[WorldTransform], stamp: TimeMsg) -> TFMessage:
    """A TFMessage of rigid transforms (m, quaternion x y z w), all stamped ``stamp``."""
    return TFMessage(transforms=[
        TransformStamped(header=Header(stamp=stamp, frame_id=t.parent), child_frame_id=t.child,
                         transform=Transform(translation=_vector(t.translation), rotation=_quaternion(t.quaternion)))
        for t in transforms
    ])


def event_msg(kind: int, step: int, side: str, time_in_step: float, stamp: TimeMsg, message: str = "",
              touchdown: Touchdown | None = None) -> GaitEvent:
    """A GaitEvent; a touchdown's impulses (N m s), W (N m s) and distance to the plan."""
    msg = GaitEvent(header=Header(stamp=stamp, frame_id=WORLD_FRAME), kind=kind, step=step, stance_side=side,
                    time_in_step=time_in_step, message=message)
    if touchdown is not None:
        msg.i_minus, msg.i_plus = touchdown.i_minus.tolist(), touchdown.i_plus.tolist()
        msg.effort_cost, msg.state_error, msg.velocity_miss = touchdown.W, touchdown.state_error, touchdown.velocity_miss
    return msg
