#!/usr/bin/env bash
# The README's first command: set everything up (venv, pinned dependencies, ROS interfaces),
# then run the demo: the planner and the simulator as ROS 2 nodes over Fast DDS (discovery on
# this machine only), the default gait at L = T = 0.45 s with the optimal arm swing, 20 steps,
# recorded under bags/, then analysed (summary and plots under the recording's analysis/).
set -euo pipefail
cd "$(dirname "$0")/.."
export VENV=${VENV:-.venv}  # the venv, and PYTHON the interpreter that makes it (tools/setup.sh)
bash tools/setup.sh
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
export FASTDDS_BUILTIN_TRANSPORTS=UDPv4  # UDP on loopback alone (biped_gait/ros/environment.py)
export ROS_DOMAIN_ID=${ROS_DOMAIN_ID:-42}
"$VENV"/bin/biped-gait plan --json bags/default_gait.json
"$VENV"/bin/biped-gait-launch --config config/demo.yaml --analyze
