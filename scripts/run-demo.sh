#!/usr/bin/env bash
# Installs what is missing, builds into build/, then runs the module's main job on an
# embedded default input and says where the results are.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
OUT="${DEMO_OUT:-${BUILD_DIR}/demo}"
mkdir -p "${OUT}"
TOOL="${BUILD_DIR}/bin/virtual-unwrap"
"${TOOL}" --version
echo "run-demo: the end-to-end tool is not built yet; the tool's subcommands so far:"
"${TOOL}" --help
