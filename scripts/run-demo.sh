#!/usr/bin/env bash
# Installs what is missing, builds into build/, then runs the module's main job on an
# embedded default input: the standard rolled phantom (a 3-turn scroll with three lines
# of text) written as a DICOM series, unwrapped by `virtual-unwrap unwrap`, scored against
# its ground truth. Prints where the results are and how legible the text is.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
OUT="${DEMO_OUT:-${BUILD_DIR}/demo}"
TOOL="${BUILD_DIR}/bin/virtual-unwrap"
rm -rf "${OUT}"
mkdir -p "${OUT}"
start=$(date +%s.%N)
"${TOOL}" phantom standard -o "${OUT}/phantom" --format dicom
"${TOOL}" unwrap "${OUT}/phantom/volume" -o "${OUT}/unwrapped" --ground-truth "${OUT}/phantom"
end=$(date +%s.%N)
echo
echo "run-demo: scan (DICOM series) and ground truth: ${OUT}/phantom"
echo "run-demo: unwrapped results:                     ${OUT}/unwrapped"
echo "run-demo:   texture.png (the flat, readable image), preview.png (slice, mesh cross-section, texture),"
echo "run-demo:   flat.obj + flat.mtl (textured flat mesh), surface.obj/.vtp, layers.tif, report.json"
/usr/bin/python3 - "${OUT}/unwrapped/report.json" "${start}" "${end}" <<'PY'
import json, sys
report = json.load(open(sys.argv[1]))
legibility = report["legibility"]
print("run-demo: legibility: OCR character error rate %.3f, texture NCC %.3f against the ground truth"
      % (legibility["character_error_rate"], legibility["texture_ncc"]))
print("run-demo: OCR read: %s" % " / ".join(legibility["recognized_text"].split("\n")[:3]))
print("run-demo: time: %.1f s in all (%s)" % (float(sys.argv[3]) - float(sys.argv[2]),
      ", ".join("%s %.2f s" % (s["stage"], s["seconds"]) for s in report["stages"])))
PY
