#!/usr/bin/env bash
# Installs what is missing, builds into build/, then runs every test with ctest.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
cd "${BUILD_DIR}"
ctest --output-on-failure -j"${JOBS}" --timeout 900
