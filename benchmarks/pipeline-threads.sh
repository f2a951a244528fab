#!/usr/bin/env bash
# The whole `unwrap` pipeline on one and on two threads, back to back (docs/benchmarks.md,
# section 8): the standard phantom at 0.016 mm voxels (526 x 502 x 689 = 182 M voxels, a
# compressed MetaImage), each thread count run ROUNDS times, alternating; per-stage seconds
# from report.json, the ratio of the mean totals, and the texture stage's samples per second
# (texture pixels x layers / stage seconds).
# Usage: benchmarks/pipeline-threads.sh [BUILD_DIR] [ROUNDS]   (defaults: build 3; 6 GiB, ~10 min)
set -euo pipefail
BUILD_DIR="${1:-build}"
ROUNDS="${2:-3}"
TOOL="${BUILD_DIR}/bin/virtual-unwrap"
WORK="$(mktemp -d)"
trap 'rm -rf "${WORK}"' EXIT
"${TOOL}" phantom standard -o "${WORK}/phantom" --format mha --voxel-size 0.016 --slice-spacing 0.016 >/dev/null
for round in $(seq 1 "${ROUNDS}"); do
  for threads in 1 2; do
    ITK_GLOBAL_DEFAULT_NUMBER_OF_THREADS="${threads}" "${TOOL}" unwrap "${WORK}/phantom/volume.mha" \
      -o "${WORK}/unwrap-${threads}-${round}" -q
  done
done
/usr/bin/python3 - "${WORK}" "${ROUNDS}" <<'EOF'
import json, statistics, sys
work, rounds = sys.argv[1], int(sys.argv[2])
stages = ["read", "segment", "mesh", "flatten", "texture", "write"]
print("| threads | " + " | ".join(stages) + " | total (s) | texture samples/s | peak memory (MiB) |")
print("|---" * (len(stages) + 4) + "|")
totals = {}
for threads in (1, 2):
    reports = [json.load(open(f"{work}/unwrap-{threads}-{r}/report.json")) for r in range(1, rounds + 1)]
    seconds = {s: statistics.mean(x["seconds"] for rep in reports for x in rep["stages"] if x["stage"] == s)
               for s in stages}
    totals[threads] = [rep["seconds"] for rep in reports]
    size = reports[0]["texture"]["size"]
    layers = reports[0]["parameters"]["texture"]["layers"]
    rate = size[0] * size[1] * layers / seconds["texture"]
    print(f"| {threads} | " + " | ".join(f"{seconds[s]:.2f}" for s in stages) +
          f" | {statistics.mean(totals[threads]):.2f} | {rate:.2e} | {max(r['peak_memory_mib'] for r in reports):.0f} |")
ratios = [a / b for a, b in zip(totals[1], totals[2])]
print(f"\ntwo threads {statistics.mean(totals[1]) / statistics.mean(totals[2]):.2f} times faster than one "
      f"(rounds: {', '.join(f'{r:.2f}' for r in ratios)})")
EOF
