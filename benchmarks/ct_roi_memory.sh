#!/usr/bin/env bash
# Peak memory of reading a region of interest of a large TIFF stack with the CT reader.
# Writes a 2 GiB stack of 16-bit TIFF slices (2048 x 2048 x 256) into a temporary
# directory, runs `virtual-unwrap info STACK --roi ... --stats` on a box holding 5% of the
# voxels (and, for comparison, on the whole stack), prints the peak resident memory
# against the stack's size, then deletes the stack.
# Acceptance: the 5% region of interest needs less than 10% of the stack's size.
#
# Usage: benchmarks/ct_roi_memory.sh [BUILD_DIR]   (BUILD_DIR defaults to build/)
set -euo pipefail

REPO_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${1:-${REPO_ROOT}/build}"
TOOL="${BUILD_DIR}/bin/virtual-unwrap"
if [ ! -x "${TOOL}" ]; then
  echo "ct_roi_memory: ${TOOL} not found; build the virtual-unwrap target first" >&2
  exit 1
fi

WIDTH=2048
HEIGHT=2048
SLICES=256
# 1024 x 1024 x 51 of 2048 x 2048 x 256 voxels: 4.98% of the stack.
ROI=(512 512 100 1024 1024 51)

STACK="$(mktemp -d "${TMPDIR:-/tmp}/vu-ct-roi.XXXXXX")"
trap 'rm -rf "${STACK}"' EXIT

echo "ct_roi_memory: writing ${WIDTH}x${HEIGHT}x${SLICES} uint16 TIFF slices to ${STACK}"
/usr/bin/python3 - "${STACK}" "${WIDTH}" "${HEIGHT}" "${SLICES}" <<'PYTHON'
import sys

import numpy as np
import tifffile

directory, width, height, slices = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
y, x = np.mgrid[0:height, 0:width]
for z in range(slices):
    tifffile.imwrite(f"{directory}/slice{z}.tif", ((x + 3 * y + 7 * z) % 4096).astype(np.uint16))
PYTHON
STACK_BYTES="$(du -sb "${STACK}" | cut -f1)"

# Runs the tool under /usr/bin/time -v; prints the peak RSS in bytes.
peak_rss() {
  local log="${STACK}/time.log"
  /usr/bin/time -v "${TOOL}" info "${STACK}" --spacing 0.01 0.01 0.01 --stats "$@" >"${STACK}/info.json" 2>"${log}"
  echo $(($(sed -n 's/.*Maximum resident set size (kbytes): //p' "${log}") * 1024))
}

report() {
  local label="$1" bytes="$2"
  awk -v label="${label}" -v b="${bytes}" -v s="${STACK_BYTES}" \
    'BEGIN { printf "%-34s peak RSS %7.1f MiB = %5.2f%% of the stack\n", label, b / 1048576, 100 * b / s }'
}

echo "ct_roi_memory: stack size $((STACK_BYTES / 1048576)) MiB"
ROI_START=$(date +%s%N)
ROI_PEAK="$(peak_rss --roi "${ROI[@]}")"
ROI_MS=$((($(date +%s%N) - ROI_START) / 1000000))
ROI_STATS="$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["stats"])' "${STACK}/info.json")"
FULL_START=$(date +%s%N)
FULL_PEAK="$(peak_rss)"
FULL_MS=$((($(date +%s%N) - FULL_START) / 1000000))
report "ROI ${ROI[*]} (4.98%) --stats" "${ROI_PEAK}"
echo "  ${ROI_MS} ms, stats ${ROI_STATS}"
report "whole stack --stats" "${FULL_PEAK}"
echo "  ${FULL_MS} ms"
if [ "${ROI_PEAK}" -lt $((STACK_BYTES / 10)) ]; then
  echo "ct_roi_memory: PASS (ROI peak below 10% of the stack)"
else
  echo "ct_roi_memory: FAIL (ROI peak not below 10% of the stack)"
  exit 1
fi
