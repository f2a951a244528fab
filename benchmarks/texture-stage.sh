#!/usr/bin/env bash
# The texture stage of `unwrap` end to end on a small scan (docs/benchmarks.md, section 6):
# the standard phantom 30 mm wide (994 x 605 texture pixels, 9 layers), unwrapped ROUNDS
# times; the stage's seconds from report.json and its samples per second (texture pixels x
# layers / stage seconds), median, least and most. Given a second library folder (a build of
# libVirtualUnwrapping.so.0 to compare with), runs alternate between it and BUILD_DIR's
# library with the same tool, so both see the same machine load.
# Usage: benchmarks/texture-stage.sh [BUILD_DIR] [ROUNDS] [BASELINE_LIBRARY_DIR]   (defaults: build 10)
set -euo pipefail
BUILD_DIR="$(cd "${1:-build}" && pwd)"
ROUNDS="${2:-10}"
BASELINE="${3:-}"
TOOL="${BUILD_DIR}/bin/virtual-unwrap"
WORK="$(mktemp -d)"
trap 'rm -rf "${WORK}"' EXIT
"${TOOL}" phantom standard --width 30 -o "${WORK}/phantom" --format mha >/dev/null
variants=(current)
if [ -n "${BASELINE}" ]; then
  variants=(baseline current)
fi
for round in $(seq 1 "${ROUNDS}"); do
  for variant in "${variants[@]}"; do
    library="${BUILD_DIR}/lib"
    if [ "${variant}" = baseline ]; then
      library="$(cd "${BASELINE}" && pwd)"
    fi
    LD_LIBRARY_PATH="${library}" "${TOOL}" unwrap "${WORK}/phantom/volume.mha" -o "${WORK}/${variant}-${round}" -q
  done
done
/usr/bin/python3 - "${WORK}" "${ROUNDS}" "${variants[@]}" <<'EOF'
import json, statistics, sys
work, rounds, variants = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
print("| library | texture stage median (s) | least | most | samples/s at the median |")
print("|---|---|---|---|---|")
for variant in variants:
    reports = [json.load(open(f"{work}/{variant}-{r}/report.json")) for r in range(1, rounds + 1)]
    seconds = [x["seconds"] for rep in reports for x in rep["stages"] if x["stage"] == "texture"]
    size = reports[0]["texture"]["size"]
    samples = size[0] * size[1] * reports[0]["parameters"]["texture"]["layers"]
    median = statistics.median(seconds)
    print(f"| {variant} | {median:.4f} | {min(seconds):.4f} | {max(seconds):.4f} | {samples / median:.3g} |")
EOF
