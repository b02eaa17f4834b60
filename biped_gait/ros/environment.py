"""Middleware settings applied before rclpy initializes.

DDS discovery multicasts on every interface by default; the project's processes keep it on
this machine with ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``. A user who wants discovery
across a robot's network sets the variable (e.g. ``SUBNET``) before starting the node.
"""

from __future__ import annotations

import os

DISCOVERY_VARIABLE = "ROS_AUTOMATIC_DISCOVERY_RANGE"


def keep_discovery_local() -> None:
    """Default ``ROS_AUTOMATIC_DISCOVERY_RANGE`` to ``LOCALHOST`` (call before rclpy.init)."""
    os.environ.setdefault(DISCOVERY_VARIABLE, "LOCALHOST")


keep_discovery_local()
