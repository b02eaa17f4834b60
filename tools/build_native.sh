#!/usr/bin/env bash
# Build the compiled twins of the core, biped_gait/core/dynamics/_flow_native (the RK8 flow,
# biped_gait/core/dynamics/native/flow.cpp) and biped_gait/core/dynamics/_samples_native (many states evaluated at
# once, biped_gait/core/dynamics/native/samples.cpp), against the Pinocchio, Eigen and Boost headers and
# libraries of the pinned cmeel wheels in the venv ($VENV, default .venv). Arguments: the sources to build (default: both).
#
# The sources are compiled at once, one g++ each (about 2 GB of memory each). Their calls take
# the argument types of the instantiations libpinocchio_default ships (declared extern by
# PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION), so what is compiled here is the bindings, the loop
# around the algorithms and the model's deserialization; measured options in docs/development.md.
# Only those wheels and pybind11 need be installed (tools/setup.sh builds while pip installs the rest):
# each module is checked by loading it alone.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${VENV:-.venv}/bin/python
prefix=$("$PY" -c 'import sysconfig, os; print(os.path.join(sysconfig.get_paths()["purelib"], "cmeel.prefix"))')
suffix=$("$PY" -c 'import sysconfig; print(sysconfig.get_config_var("EXT_SUFFIX"))')
py_include=$("$PY" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')
pybind_include=$("$PY" -c 'import pybind11; print(pybind11.get_include())')
sources=("$@")
(( ${#sources[@]} )) || sources=(flow.cpp samples.cpp)
build() {  # source name -> the module beside biped_gait/core/dynamics/, loaded once
  local module=_${1%.cpp}_native
  local out=biped_gait/core/dynamics/$module$suffix
  g++ -O2 -std=c++17 -shared -fPIC -DNDEBUG -Wno-deprecated-declarations \
    -DPINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION -DBOOST_MPL_LIMIT_LIST_SIZE=30 -DBOOST_MPL_LIMIT_VECTOR_SIZE=30 \
    -DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS -DBOOST_FUSION_INVOKE_MAX_ARITY=12 \
    -I"$py_include" -I"$pybind_include" -I"$prefix/include" -I"$prefix/include/eigen3" \
    "biped_gait/core/dynamics/native/$1" -o "$out.tmp" \
    -L"$prefix/lib" -Wl,-rpath,"$prefix/lib" -lpinocchio_default -lboost_serialization
  "$PY" -c 'import importlib.machinery as m, importlib.util as u, sys
loader = m.ExtensionFileLoader(sys.argv[1], sys.argv[2])
loader.exec_module(u.module_from_spec(u.spec_from_loader(sys.argv[1], loader)))' "$module" "$out.tmp"
  mv "$out.tmp" "$out"
  echo "built $out"
}
pids=()
for name in "${sources[@]}"; do
  build "$name" &
  pids+=($!)
done
failed=0
for pid in "${pids[@]}"; do
  wait "$pid" || failed=1
done
exit "$failed"
