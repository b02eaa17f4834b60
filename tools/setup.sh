#!/usr/bin/env bash
# Create the project's environment in a venv (.venv by default) with the pinned dependencies and
# the biped_gait package installed in editable mode, and builds the ROS 2 interfaces of msg_defs/
# into it (the venv is the ROS prefix). Idempotent: a second run only checks.
#
# Python 3.11 or 3.12: PYTHON names the interpreter that makes the venv (default python3), VENV
# the venv (default .venv), e.g. `PYTHON=python3.12 VENV=.venv-3.12 bash tools/setup.sh`; the
# tools run in VENV (tools/test.sh, tools/demo.sh). A venv of another Python than PYTHON's is
# refused (remove it, or name another).
#
# The steps overlap on two cores: pip installs first the four wheels the native modules compile
# against (with what they require, at the pinned versions), then the ROS 2 wheels (likewise),
# then the rest; the native modules (tools/build_native.sh) compile from the first point on, the
# ROS interfaces (tools/build_interfaces.sh) from the second. Each background step logs to
# build/<venv>/<step>.log, shown if it fails. Figures: docs/development.md.
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=${VENV:-.venv}
export VENV=${VENV%/}
version() {  # the Python version of an interpreter, e.g. 3.12
  "$1" -c 'import sys; print("%d.%d" % sys.version_info[:2])'
}
if [ ! -x "$VENV/bin/python" ]; then
  "${PYTHON:-python3}" -m venv "$VENV"
elif [ -n "${PYTHON:-}" ] && [ "$(version "$PYTHON")" != "$(version "$VENV/bin/python")" ]; then
  echo "tools/setup.sh: $VENV is a venv of Python $(version "$VENV/bin/python"), not of $PYTHON ($(version "$PYTHON")):" \
    "remove it, or give another VENV" >&2
  exit 2
fi
pip_install() {
  "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check "$@" 2>&1 | { grep -v "^WARNING: Location" || true; }
}

logs=build/${VENV##*/}
mkdir -p "$logs"
pending=()  # "step pid stamp-file stamp" of each step running in the background
start() {  # step stamp-file stamp command...: run the command in the background
  local step=$1 file=$2 value=$3
  shift 3
  "$@" > "$logs/$step.log" 2>&1 &
  pending+=("$step $! $file $value")
}
stop_pending() {  # on an early exit, the background steps and their compilers stop too
  local job step pid
  for job in "${pending[@]}"; do
    read -r step pid _ <<< "$job"
    pkill -TERM -P "$pid" 2> /dev/null || true
    kill -TERM "$pid" 2> /dev/null || true
  done
}
trap stop_pending EXIT
finish() {  # wait for every background step; stamp those that succeeded
  local failed=0 job step pid file value
  for job in "${pending[@]}"; do
    read -r step pid file value <<< "$job"
    if wait "$pid"; then
      echo "$value" > "$file"
    else
      echo "tools/setup.sh: $step failed ($logs/$step.log):" >&2
      tail -40 "$logs/$step.log" >&2
      failed=1
    fi
  done
  pending=()
  return "$failed"
}

stamp=$VENV/.requirements.sha
want=$(cat requirements.txt setup.py setup.cfg pyproject.toml | sha256sum | cut -d' ' -f1)
requirements_current=no
[ "$(cat "$stamp" 2>/dev/null)" = "$want" ] && requirements_current=yes
# The compiled twins of the ballistic flow and of the sample evaluation (C++ over the wheels'
# Pinocchio), rebuilt when their sources, their build or the wheels they compile against change.
native_wheels=$(grep -E '^(libpinocchio|cmeel-boost|cmeel-eigen|pybind11)==' requirements.txt)
nstamp=$VENV/.native.sha
nwant=$({ cat biped_gait/core/dynamics/native/*.cpp tools/build_native.sh; echo "$native_wheels"; } | sha256sum | cut -d' ' -f1)
suffix=$("$VENV/bin/python" -c 'import sysconfig; print(sysconfig.get_config_var("EXT_SUFFIX"))')
if [ "$(cat "$nstamp" 2>/dev/null)" != "$nwant" ] || [ ! -f "biped_gait/core/dynamics/_flow_native$suffix" ] \
    || [ ! -f "biped_gait/core/dynamics/_samples_native$suffix" ]; then
  if [ "$requirements_current" = no ]; then
    # shellcheck disable=SC2086  # one argument per pinned wheel
    pip_install -c requirements.txt $native_wheels
  fi
  start native "$nstamp" "$nwant" bash tools/build_native.sh
fi
# The ROS interfaces, rebuilt when their definitions change.
istamp=$VENV/.interfaces.sha
iwant=$(find msg_defs tools/build_interfaces.sh -type f -print0 | sort -z | xargs -0 cat | sha256sum | cut -d' ' -f1)
if [ "$(cat "$istamp" 2>/dev/null)" != "$iwant" ]; then
  if [ "$requirements_current" = no ]; then
    # shellcheck disable=SC2046  # one argument per ROS 2 wheel (and catkin_pkg, which ament_cmake
    # imports without requiring it)
    pip_install -c requirements.txt $(grep -oE '^(ros-[A-Za-z0-9-]+|catkin-pkg)' requirements.txt)
  fi
  start interfaces "$istamp" "$iwant" bash tools/build_interfaces.sh
fi
if [ "$requirements_current" = no ]; then
  pip_install -r requirements.txt
  pip_install --no-deps --no-build-isolation -e .
  echo "$want" > "$stamp"
fi
# The package's bytecode: where PYTHONDONTWRITEBYTECODE=1 no .pyc is written at import, and
# every process a test or a launch starts would compile the package again (pip and the
# interfaces' install compile what they put in site-packages). Up-to-date files are skipped.
"$VENV/bin/python" -m compileall -q biped_gait
finish
