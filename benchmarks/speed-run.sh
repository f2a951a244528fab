#!/usr/bin/env bash
# Every speed figure of docs/benchmarks.md from one run, back to back on one machine: the
# flattening methods on the same meshes (mass-spring integrators, ITK's parameterisation,
# CGAL's LSCM and ARAP), the 1M-vertex roll against CGAL LSCM, the stability map, the explicit
# step's throughput, time to convergence from 10k to 10M vertices, the texture stage of
# `unwrap` on a small scan, the whole pipeline on one and two threads on the 182 M-voxel
# phantom, and the enough-model sweep. Writes the CSVs and the stage tables into OUT_DIR,
# then the markdown tables (OUT_DIR/tables.md, by benchmarks/speed_tables.py) and the charts
# (scripts/plot-benchmarks.py, into docs/images/).
#
# Usage: benchmarks/speed-run.sh [BUILD_DIR] [OUT_DIR]   (defaults: build docs/benchmarks)
# About 45 minutes on 2 cores and 16 GiB of memory at its peak (the 10M-vertex roll). The
# CGAL rows need vuCgalFlatteningBenchmark, built when libcgal-dev is installed.
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
BUILD_DIR="$(cd "${1:-build}" && pwd)"
OUT="${2:-${HERE}/../docs/benchmarks}"
mkdir -p "${OUT}"
OUT="$(cd "${OUT}" && pwd)"
BIN="${BUILD_DIR}/bin"
for program in vuFlatteningBenchmark vuCgalFlatteningBenchmark vuStabilityMapBenchmark vuStepThroughputBenchmark \
  vuScalingBenchmark virtual-unwrap; do
  if [ ! -x "${BIN}/${program}" ]; then
    echo "speed-run: ${BIN}/${program} is missing (build it first; CGAL's needs libcgal-dev)" >&2
    exit 1
  fi
done
LOG="${OUT}/run.log"
: >"${LOG}"
step() {
  echo "[$(date -u +%H:%M:%S)] $*" | tee -a "${LOG}"
}
step "machine: $(nproc) cores, $(free -g | awk '/^Mem:/{print $2}') GiB; commit $(git -C "${HERE}" rev-parse --short HEAD 2>/dev/null || echo unknown)"

step "flattening methods: roll-10k, dome-10k (every method)"
"${BIN}/vuFlatteningBenchmark" --meshes roll-10k,dome-10k --csv "${OUT}/flattening.csv"
# ITK's parameterisation (VNL's iterative solver) does not finish on the 100k roll in minutes.
step "flattening methods: roll-100k (mass-spring)"
"${BIN}/vuFlatteningBenchmark" --meshes roll-100k --methods implicit,explicit --csv "${OUT}/flattening-100k.csv"
step "flattening: roll-1M (mass-spring, implicit), then CGAL on every mesh"
"${BIN}/vuFlatteningBenchmark" --meshes roll-1M --methods implicit --csv "${OUT}/flattening-1M.csv"
"${BIN}/vuCgalFlatteningBenchmark" --meshes roll-10k,dome-10k,roll-100k,roll-1M --csv "${OUT}/flattening-cgal.csv"

step "stability map of the explicit integrators"
"${BIN}/vuStabilityMapBenchmark" --steps 20000 --csv "${OUT}/stability.csv" >/dev/null

step "explicit step throughput"
"${BIN}/vuStepThroughputBenchmark" --steps 20 >"${OUT}/step-throughput.csv"

step "time to convergence, 10k to 4M on one and two threads, 10M on two"
"${BIN}/vuScalingBenchmark" --csv "${OUT}/scaling.csv"
"${BIN}/vuScalingBenchmark" --sizes 10M --threads 2 --csv "${OUT}/scaling-10M.tmp"
tail -n +2 "${OUT}/scaling-10M.tmp" >>"${OUT}/scaling.csv"
rm -f "${OUT}/scaling-10M.tmp"

step "texture stage of unwrap on the 30 mm standard phantom, 10 runs"
bash "${HERE}/texture-stage.sh" "${BUILD_DIR}" 10 >"${OUT}/texture-stage.md"

step "whole pipeline on one and two threads, 182 M-voxel phantom, 3 rounds"
bash "${HERE}/pipeline-threads.sh" "${BUILD_DIR}" 3 >"${OUT}/pipeline-threads.md"

step "pipeline profile of the demo (standard phantom, DICOM series, with its ground truth)"
"${BIN}/virtual-unwrap" phantom standard -o "${OUT}/demo.tmp/phantom" --format dicom >/dev/null
"${BIN}/virtual-unwrap" unwrap "${OUT}/demo.tmp/phantom/volume" -o "${OUT}/demo.tmp/unwrapped" \
  --ground-truth "${OUT}/demo.tmp/phantom" -q
cp "${OUT}/demo.tmp/unwrapped/report.json" "${OUT}/demo-report.json"
rm -rf "${OUT}/demo.tmp"

if command -v xvfb-run >/dev/null && [ -x "${BIN}/virtual-unwrap-workbench" ]; then
  step "workbench frame rate under Xvfb (software OpenGL), 100k and 1M particles"
  : >"${OUT}/workbench-frames.txt"
  for case in "100000 symplectic-euler" "100000 implicit-euler" "1000000 symplectic-euler" "1000000 implicit-euler"; do
    set -- ${case}
    echo "particles=$1 integrator=$2" >>"${OUT}/workbench-frames.txt"
    LIBGL_ALWAYS_SOFTWARE=1 xvfb-run -a -s "-screen 0 1920x1200x24" "${BIN}/virtual-unwrap-workbench" \
      --benchmark-frames "$1" --seconds 10 --integrator "$2" >>"${OUT}/workbench-frames.txt" 2>&1
  done
  echo "particles=1000000 integrator=none" >>"${OUT}/workbench-frames.txt"
  LIBGL_ALWAYS_SOFTWARE=1 xvfb-run -a -s "-screen 0 1920x1200x24" "${BIN}/virtual-unwrap-workbench" \
    --benchmark-frames 1000000 --seconds 10 --render-only >>"${OUT}/workbench-frames.txt" 2>&1
fi

step "enough model"
/usr/bin/python3 "${HERE}/enough_model.py" --build "${BUILD_DIR}" --csv "${OUT}/enough-model.csv" >/dev/null

step "tables and charts"
/usr/bin/python3 "${HERE}/speed_tables.py" "${OUT}" >"${OUT}/tables.md"
/usr/bin/python3 "${HERE}/../scripts/plot-benchmarks.py" "${OUT}"
step "done: ${OUT}/tables.md"
