"""The QoS profiles of the project's topics, in one place for the nodes, and their rosbag2
description for the recordings."""

from __future__ import annotations

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from ..recording.qos import qos_description

# Reliable, transient-local, depth 1: a late subscriber gets the latest message (plans, the
# robot description, static transforms), as ROS 2 "latched" topics.
LATCHED = QoSProfile(
    depth=1,
    history=HistoryPolicy.KEEP_LAST,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
STREAM = QoSProfile(depth=50)  # reliable, volatile: joint states, odometry, momentum, /tf
EVENTS = QoSProfile(depth=100)  # reliable, volatile: gait events, recorded service calls
# /clock: best effort, keep last 1, volatile, as rclcpp's ClockQoS (Gazebo, ros2 bag play)
CLOCK = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)


def describe(profile: QoSProfile) -> list[dict]:
    """``profile`` as rosbag2's ``offered_qos_profiles`` (a list of one dictionary)."""
    return [qos_description(
        "keep_all" if profile.history == HistoryPolicy.KEEP_ALL else "keep_last",
        profile.depth,
        "best_effort" if profile.reliability == ReliabilityPolicy.BEST_EFFORT else "reliable",
        "transient_local" if profile.durability == DurabilityPolicy.TRANSIENT_LOCAL else "volatile",
    )]
