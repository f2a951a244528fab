#!/usr/bin/env bash
# Installs what is missing, builds into build/, then runs every test with ctest. When a
# Python-wrapped build made by scripts/build-python.sh exists on this machine, the Python
# tests run as well (the module is rebuilt there incrementally first).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
(cd "${BUILD_DIR}" && ctest --output-on-failure -j"${JOBS}" --timeout 900)
python_root="${VU_ITK_PYTHON_ROOT:-/var/cache/virtual-unwrapping/itk-python}"
if [[ -f "${python_root}/itk-build/.vu-build-complete" ]]; then
  echo "[run-tests] Python-wrapped build found in ${python_root}: running the Python tests"
  status=0
  bash "$(dirname "${BASH_SOURCE[0]}")/build-python.sh" --tests || status=$?
  if ((status == 3)); then
    echo "[run-tests] the Python-wrapped build predates a module itk-module.cmake needs: Python tests skipped"
  elif ((status != 0)); then
    exit "${status}"
  fi
else
  echo "[run-tests] no Python-wrapped build in ${python_root} (scripts/build-python.sh makes one): Python tests skipped"
fi
