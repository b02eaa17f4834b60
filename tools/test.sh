#!/usr/bin/env bash
# The README's test command: set up (if needed), then run the whole test suite. ROS processes
# keep discovery on this machine; tests/conftest.py gives the session a domain of its own.
# The tests run in one pytest-xdist worker per core, a test module to a worker (its module's
# nodes and gaits made once), the longest modules first (tests/conftest.py), each worker in a ROS
# domain of its own; a test marked `paced` runs with no other beside it (tests/conftest.py).
# `-n 0` runs them in this process, as `-s` (output shown) does.
set -euo pipefail
cd "$(dirname "$0")/.."
export VENV=${VENV:-.venv}  # the venv, and PYTHON the interpreter that makes it (tools/setup.sh)
bash tools/setup.sh
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
export FASTDDS_BUILTIN_TRANSPORTS=UDPv4  # UDP on loopback alone (biped_gait/ros/environment.py)
# Fast DDS's shared-memory ports and segments of nodes that were killed (the fault tests kill
# some) stay in /dev/shm; after many runs on one machine, a new node could be left unmatched by
# an old client. Fast DDS's own tool removes only those whose owner is gone (their lock is free),
# so other sessions' nodes keep theirs.
"$VENV"/bin/fastdds shm clean > /dev/null 2>&1 || true
parallel=(-n auto --dist loadscope --no-loadscope-reorder)
for arg in "$@"; do
  case $arg in -s | --capture=no | -n | -n* | --numprocesses*) parallel=() ;; esac
done
exec "$VENV"/bin/python -m pytest -q "${parallel[@]}" "$@"
