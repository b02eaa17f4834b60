"""QoS profiles as rosbag2 records them (``offered_qos_profiles`` in ``metadata.yaml`` and in the
MCAP channels' metadata): plain dictionaries, so that recording needs no ROS code."""

from __future__ import annotations

INFINITE = {"sec": 2147483647, "nsec": 4294967295}  # rosbag2's "infinite" duration


def qos_description(history: str, depth: int, reliability: str, durability: str) -> dict:
    """One offered QoS profile in rosbag2's keys: history ``keep_last``/``keep_all``, the depth,
    reliability ``reliable``/``best_effort``, durability ``volatile``/``transient_local``; the
    other policies at their defaults (infinite deadline and lifespan, automatic liveliness)."""
    return {
        "history": history, "depth": int(depth), "reliability": reliability, "durability": durability,
        "deadline": dict(INFINITE), "lifespan": dict(INFINITE), "liveliness": "automatic",
        "liveliness_lease_duration": dict(INFINITE), "avoid_ros_namespace_conventions": False,
    }

