#!/usr/bin/env bash
# The sanitizer run: the library, the tool, every test and the fuzz targets built under
# AddressSanitizer and UndefinedBehaviorSanitizer in build-sanitize/, the whole test suite
# run there, each fuzz target for VU_FUZZ_SECONDS (default 60) among the tests. GCC builds
# it: Debian's ITK 5.2 headers refuse every compiler but GCC (itk_compiler_detection.h),
# so libFuzzer (Clang's) cannot be used and the fuzz targets run under the project's
# random-mutation driver.
# Passes only when every test passes and no sanitizer wrote a report: reports go to
# build-sanitize/sanitizer-reports/ (a tool that reports and exits non-zero could
# otherwise pass a test that expects a refusal), and the script lists them.
set -euo pipefail
REPO_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${VU_SANITIZE_BUILD_DIR:-${REPO_ROOT}/build-sanitize}"
JOBS="$(nproc)"
FUZZ_SECONDS="${VU_FUZZ_SECONDS:-60}"

if [ ! -f "${BUILD_DIR}/CMakeCache.txt" ]; then
  # -O1 and line tables only: a build twice as fast as -O2 -g, stack traces with lines.
  cmake -S "${REPO_ROOT}" -B "${BUILD_DIR}" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS_RELEASE=-O1 \
    -DVirtualUnwrapping_SANITIZE=address,undefined -DVirtualUnwrapping_BUILD_BENCHMARKS=OFF \
    -DVU_FUZZ_SECONDS="${FUZZ_SECONDS}" -DVU_FUZZ_RUNS=0 -DVU_FUZZ_SEED=
else
  cmake "${BUILD_DIR}" -DVU_FUZZ_SECONDS="${FUZZ_SECONDS}" -DVU_FUZZ_RUNS=0 >/dev/null
fi
cmake --build "${BUILD_DIR}" -j"${JOBS}"

reports="${BUILD_DIR}/sanitizer-reports"
rm -rf "${reports}"
mkdir -p "${reports}"
# Leaks are reported too; exitcode 86 marks a sanitizer's exit apart from a refusal's 1.
export ASAN_OPTIONS="log_path=${reports}/asan:exitcode=86:detect_leaks=1:allocator_may_return_null=1:detect_stack_use_after_return=0:suppressions=${REPO_ROOT}/test/sanitizer/asan.supp"
export LSAN_OPTIONS="suppressions=${REPO_ROOT}/test/sanitizer/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="log_path=${reports}/ubsan:exitcode=86:print_stacktrace=1:halt_on_error=1:suppressions=${REPO_ROOT}/test/sanitizer/ubsan.supp"

status=0
# ConsumerProject builds a separate project against this build's library: a consumer of a
# sanitized library must be built with the same compiler and sanitizers, which that test
# (a check of the package files, run in the plain build) does not do.
(cd "${BUILD_DIR}" && ctest --output-on-failure -j"${JOBS}" --timeout 1800 -E "^ConsumerProject\\.") || status=$?
if compgen -G "${reports}/*" >/dev/null; then
  echo "run-sanitizers: sanitizer reports:" >&2
  for f in "${reports}"/*; do
    echo "== ${f}" >&2
    head -40 "${f}" >&2
  done
  status=1
fi
if ((status == 0)); then
  echo "run-sanitizers: every test passed under AddressSanitizer and UndefinedBehaviorSanitizer, no report"
fi
exit "${status}"
