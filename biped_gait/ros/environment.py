"""Middleware settings applied before rclpy initializes.

DDS discovery multicasts on every interface by default; the project's processes keep it on
this machine with ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``. A user who wants discovery
across a robot's network sets the variable (e.g. ``SUBNET``) before starting the node.

Fast DDS (2.14, Jazzy's) carries traffic between processes of one machine through shared memory
by default, and that transport can leave a restarted process unheard: a node started where a
stopped one was (its port reused) while another node stays up gets no data from that node,
whichever endpoints it makes (eProsima/Fast-DDS#5053). Measured here: a simulator restarted 40
times beside one planner got no plan_gait answer through five fresh clients in 1 of 4 runs of the
fault tests; with UDP alone, in none of 8. The nodes' messages are small (a plan, joint states at
500 Hz), so the project's processes use Fast DDS's UDPv4 transport alone
(``FASTDDS_BUILTIN_TRANSPORTS=UDPv4``, on loopback with the discovery above) unless the caller set
the variable.
"""

from __future__ import annotations

import os

DISCOVERY_VARIABLE = "ROS_AUTOMATIC_DISCOVERY_RANGE"
TRANSPORTS_VARIABLE = "FASTDDS_BUILTIN_TRANSPORTS"


def keep_discovery_local() -> None:
    """Default ``ROS_AUTOMATIC_DISCOVERY_RANGE`` to ``LOCALHOST`` and Fast DDS's transports to
    UDPv4 (call before rclpy.init)."""
    os.environ.setdefault(DISCOVERY_VARIABLE, "LOCALHOST")
    os.environ.setdefault(TRANSPORTS_VARIABLE, "UDPv4")


keep_discovery_local()
