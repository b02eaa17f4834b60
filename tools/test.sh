#!/usr/bin/env bash
# The README's test command: set up (if needed), then run the whole test suite. ROS processes
# keep discovery on this machine; tests/conftest.py gives the session a domain of its own.
# The tests run in one pytest-xdist worker per core, a test module to a worker (its module's
# nodes and gaits made once), each worker in a ROS domain of its own; a test marked `paced`
# runs with no other beside it (tests/conftest.py). `-n 0` runs them in this process, as `-s`
# (output shown) does.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
parallel=(-n auto --dist loadscope)
for arg in "$@"; do
  case $arg in -s | --capture=no | -n | -n* | --numprocesses*) parallel=() ;; esac
done
exec .venv/bin/python -m pytest -q "${parallel[@]}" "$@"
