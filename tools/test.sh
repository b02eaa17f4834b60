#!/usr/bin/env bash
# The README's test command: set up (if needed), then run the whole test suite. ROS processes
# keep discovery on this machine; tests/conftest.py gives the session a domain of its own.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
exec .venv/bin/python -m pytest -q "$@"
