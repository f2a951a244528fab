#!/usr/bin/env bash
# Generation time of every phantom preset in every volume format (docs/phantoms.md).
# Usage: benchmarks/phantom-presets.sh [BUILD_DIR]   (default: build)
set -euo pipefail
BUILD_DIR="${1:-build}"
TOOL="${BUILD_DIR}/bin/virtual-unwrap"
WORK="$(mktemp -d)"
trap 'rm -rf "${WORK}"' EXIT
printf '| preset | voxels | volume (s) | dicom (s) | tiff (s) | mha (s) | nrrd (s) |\n|---|---|---|---|---|---|---|\n'
for preset in standard tight squashed folded canvas-medical papyrus-microct; do
  row="| ${preset} |"
  times=()
  for format in dicom tiff mha nrrd; do
    start=$(date +%s%N)
    "${TOOL}" phantom "${preset}" -o "${WORK}/${preset}-${format}" --format "${format}" >/dev/null
    end=$(date +%s%N)
    centiseconds=$(((end - start) / 10000000))
    times+=("$((centiseconds / 100)).$(printf '%02d' $((centiseconds % 100)))")
  done
  json="${WORK}/${preset}-mha/ground_truth.json"
  voxels=$(/usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['volume']['voxels'])" "${json}")
  volume=$(/usr/bin/python3 -c "import json,sys; print('%.2f' % json.load(open(sys.argv[1]))['timing_seconds']['volume'])" "${json}")
  echo "${row} ${voxels} | ${volume} | ${times[0]} | ${times[1]} | ${times[2]} | ${times[3]} |"
done
