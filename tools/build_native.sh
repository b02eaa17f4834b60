#!/usr/bin/env bash
# Build the compiled twins of the core, biped_gait/core/dynamics/_flow_native (the RK8 flow,
# biped_gait/core/dynamics/native/flow.cpp) and biped_gait/core/dynamics/_samples_native (many states evaluated at
# once, biped_gait/core/dynamics/native/samples.cpp), against the Pinocchio, Eigen and Boost headers and
# libraries of the pinned cmeel wheels in .venv. Arguments: the sources to build (default: both).
set -euo pipefail
cd "$(dirname "$0")/.."
PY=.venv/bin/python
prefix=$("$PY" -c 'import sysconfig, os; print(os.path.join(sysconfig.get_paths()["purelib"], "cmeel.prefix"))')
suffix=$("$PY" -c 'import sysconfig; print(sysconfig.get_config_var("EXT_SUFFIX"))')
py_include=$("$PY" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')
pybind_include=$("$PY" -c 'import pybind11; print(pybind11.get_include())')
sources=("$@")
(( ${#sources[@]} )) || sources=(flow.cpp samples.cpp)
for name in "${sources[@]}"; do
  module=_${name%.cpp}_native
  out=biped_gait/core/dynamics/$module$suffix
  g++ -O2 -std=c++17 -shared -fPIC -DNDEBUG -Wno-deprecated-declarations \
    -DPINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION -DBOOST_MPL_LIMIT_LIST_SIZE=30 -DBOOST_MPL_LIMIT_VECTOR_SIZE=30 \
    -DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS -DBOOST_FUSION_INVOKE_MAX_ARITY=12 \
    -I"$py_include" -I"$pybind_include" -I"$prefix/include" -I"$prefix/include/eigen3" \
    "biped_gait/core/dynamics/native/$name" -o "$out" \
    -L"$prefix/lib" -Wl,-rpath,"$prefix/lib" -lpinocchio_default -lboost_serialization
  "$PY" -c "import biped_gait.core.dynamics.$module"
  echo "built $out"
done
