"""The middleware settings every ROS process of the project starts with (biped_gait/ros/environment.py):
discovery on this machine and UDP alone, unless the caller chose otherwise."""

from __future__ import annotations

import os
import subprocess
import sys

PROBE = ("import os, biped_gait.ros.environment; "
         "print(os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'], os.environ['FASTDDS_BUILTIN_TRANSPORTS'])")


def _settings(**chosen: str) -> list[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("ROS_AUTOMATIC_DISCOVERY_RANGE", "FASTDDS_BUILTIN_TRANSPORTS")}
    proc = subprocess.run([sys.executable, "-c", PROBE], env={**env, **chosen}, capture_output=True, text=True,
                          timeout=60, check=True)
    return proc.stdout.split()


def test_a_process_keeps_discovery_local_and_talks_over_udp_by_default():
    assert _settings() == ["LOCALHOST", "UDPv4"]


def test_what_the_caller_chose_is_kept():
    assert _settings(ROS_AUTOMATIC_DISCOVERY_RANGE="SUBNET", FASTDDS_BUILTIN_TRANSPORTS="DEFAULT") == ["SUBNET", "DEFAULT"]
