#!/usr/bin/env bash
# Build the interface packages of msg_defs/ (ament_cmake, rosidl: tf2_msgs and
# biped_gait_interfaces) against the ROS 2 Jazzy wheels and install them into the venv, which is
# the ROS prefix. Needs cmake and a C/C++ compiler.
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=$(pwd)/.venv
PY=$VENV/bin/python
# The wheels' exported CMake files name the wheel builder's include directories; point them
# at this interpreter's (msg_defs/README.md).
py_include=$("$PY" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')
np_include=$("$PY" -c 'import numpy; print(numpy.get_include())')
{ grep -rl --include='*.cmake' '/opt/python/cp311-cp311/' "$VENV/share" 2>/dev/null || true; } | while read -r f; do
  sed -i -e "s|/opt/python/cp311-cp311/lib/python3.11/site-packages/numpy/_core/include|$np_include|g" \
         -e "s|/opt/python/cp311-cp311/include/python3.11|$py_include|g" "$f"
done
export AMENT_PREFIX_PATH=$VENV
build() {  # one package: configure, build, install (logs under build/<package>/)
  local pkg=$1 build=build/$1
  mkdir -p "$build"
  cmake -S "msg_defs/$pkg" -B "$build" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_PREFIX_PATH="$VENV" -DCMAKE_INSTALL_PREFIX="$VENV" -DPython3_EXECUTABLE="$PY" \
    -DBUILD_TESTING=OFF > "$build/configure.log" 2>&1 || { cat "$build/configure.log"; return 1; }
  cmake --build "$build" -j "$(nproc)" > "$build/build.log" 2>&1 || { tail -50 "$build/build.log"; return 1; }
  cmake --install "$build" > "$build/install.log" 2>&1 || { tail -50 "$build/install.log"; return 1; }
}
# The two packages do not depend on each other: they build at once.
build tf2_msgs & tf2=$!
build biped_gait_interfaces & ours=$!
failed=0
wait "$tf2" || failed=1
wait "$ours" || failed=1
(( failed == 0 )) || exit 1
"$PY" -c 'import tf2_msgs.msg, biped_gait_interfaces.srv, biped_gait_interfaces.msg, biped_gait_interfaces.action'
