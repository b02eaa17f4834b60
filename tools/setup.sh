#!/usr/bin/env bash
# Create the project's environment in .venv (Python 3.11) with the pinned dependencies and the
# biped_gait package installed in editable mode, and builds the ROS 2 interfaces of msg_defs/
# into it (the venv is the ROS prefix). Idempotent: a second run only checks.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  "$PYTHON" -m venv .venv
fi
stamp=.venv/.requirements.sha
want=$(cat requirements.txt setup.py setup.cfg pyproject.toml | sha256sum | cut -d' ' -f1)
if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  .venv/bin/python -m pip install --quiet --disable-pip-version-check -r requirements.txt 2>&1 | { grep -v "^WARNING: Location" || true; }
  .venv/bin/python -m pip install --quiet --disable-pip-version-check --no-deps --no-build-isolation -e . 2>&1 | { grep -v "^WARNING: Location" || true; }
  echo "$want" > "$stamp"
fi
# The compiled twins of the ballistic flow and of the sample evaluation (C++ over the wheels'
# Pinocchio), rebuilt when their sources change.
nstamp=.venv/.native.sha
nwant=$(cat biped_gait/core/dynamics/native/*.cpp tools/build_native.sh | sha256sum | cut -d' ' -f1)
if [ "$(cat "$nstamp" 2>/dev/null)" != "$nwant" ] || ! ls biped_gait/core/dynamics/_flow_native*.so > /dev/null 2>&1 \
    || ! ls biped_gait/core/dynamics/_samples_native*.so > /dev/null 2>&1; then
  bash tools/build_native.sh
  echo "$nwant" > "$nstamp"
fi
# The ROS interfaces, rebuilt when their definitions change.
istamp=.venv/.interfaces.sha
iwant=$(find msg_defs tools/build_interfaces.sh -type f -print0 | sort -z | xargs -0 cat | sha256sum | cut -d' ' -f1)
if [ "$(cat "$istamp" 2>/dev/null)" != "$iwant" ]; then
  bash tools/build_interfaces.sh
  echo "$iwant" > "$istamp"
fi
