#!/usr/bin/env bash
# Build the interface packages of msg_defs/ (ament_cmake, rosidl: tf2_msgs and
# biped_gait_interfaces) against the ROS 2 Jazzy wheels and install them into the venv ($VENV,
# default .venv), which is the ROS prefix. Needs cmake and a C/C++ compiler.
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=$(realpath "${VENV:-.venv}")
PY=$VENV/bin/python
# The wheels' exported CMake files name the wheel builder's include directories (its Python's,
# e.g. /opt/python/cp312-cp312/include/python3.12, and NumPy's); point them at this
# interpreter's, whatever its version (msg_defs/README.md). None may be left.
py_include=$("$PY" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')
np_include=$("$PY" -c 'import numpy; print(numpy.get_include())')
builder='/opt/python/cp3[0-9]+-cp3[0-9]+'
{ grep -rlE --include='*.cmake' "$builder/" "$VENV/share" 2>/dev/null || true; } | while read -r f; do
  sed -i -E -e "s|$builder/lib/python3\.[0-9]+/site-packages/numpy/_?core/include|$np_include|g" \
            -e "s|$builder/include/python3\.[0-9]+|$py_include|g" "$f"
done
if grep -rE --include='*.cmake' "$builder/" "$VENV/share" 2>/dev/null; then
  echo "tools/build_interfaces.sh: the wheels' CMake files name other paths of their builder (above)" >&2
  exit 1
fi
export AMENT_PREFIX_PATH=$VENV
build() {  # one package: configure, build, install (logs under build/<venv>/<package>/)
  local pkg=$1 build=build/${VENV##*/}/$1
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
