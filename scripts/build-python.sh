#!/usr/bin/env bash
# Build ITK 5.2.1 with Python wrapping from Debian's source package, then this module as an
# external ITK module with its wrapping, then run the Python tests.
#
#   scripts/build-python.sh            # every stage; resumes where a previous run stopped
#   scripts/build-python.sh --tests    # only (re)build the module and run the Python tests
#
# Everything goes under VU_ITK_PYTHON_ROOT (default /var/cache/virtual-unwrapping/itk-python):
#   src/          Debian source package insighttoolkit5 (5.2.1)
#   itk-build/    ITK build tree with ITK_WRAP_PYTHON=ON (about 2 GB; reused by later runs)
#   module-build-<hash>/ this module (one per source tree) built against itk-build, with
#                 its Python wrapping
#   times.log     wall time of each stage
# The ITK build takes one to two hours on two cores; it is incremental, so an interrupted
# run continues where it stopped. scripts/run-tests.sh runs the Python tests whenever
# the ITK build is complete.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
root="${VU_ITK_PYTHON_ROOT:-/var/cache/virtual-unwrapping/itk-python}"
src_dir="$root/src/insighttoolkit5-5.2.1"
itk_build="$root/itk-build"
# One module build per source tree (a clone configures its own against the shared ITK).
module_build="$root/module-build-$(printf '%s' "$here" | md5sum | cut -c1-8)"
tool="${BUILD_DIR:-$here/build}/bin/virtual-unwrap"
python=/usr/bin/python3
jobs="${VU_JOBS:-$(nproc)}"
only_tests=0
[[ "${1:-}" == "--tests" ]] && only_tests=1

log() { printf '[build-python] %s\n' "$*"; }
die() {
  printf 'build-python: error: %s\n' "$*" >&2
  exit 1
}
timed() { # timed NAME COMMAND...: runs COMMAND and appends its wall time to times.log
  local name="$1" start end
  shift
  start=$(date +%s)
  "$@"
  end=$(date +%s)
  printf '%s %s %d s\n' "$(date -u +%FT%TZ)" "$name" $((end - start)) >>"$root/times.log"
  log "$name: $((end - start)) s"
}

mkdir -p "$root/src"

install_packages() {
  local needed=() p
  for p in castxml swig python3-dev python3-numpy dpkg-dev cmake g++ make libgdcm-dev libfreetype-dev xz-utils; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || needed+=("$p")
  done
  if ((${#needed[@]})); then
    [[ $EUID -eq 0 ]] || die "missing packages ${needed[*]}; run as root or install them"
    log "installing ${needed[*]}"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${needed[@]}" >/dev/null
  fi
}

fetch_source() {
  [[ -f "$src_dir/CMakeLists.txt" ]] && return 0
  if ! apt-get source --print-uris -qq insighttoolkit5 >/dev/null 2>&1 ||
    [[ -z "$(apt-get source --print-uris -qq insighttoolkit5 2>/dev/null)" ]]; then
    [[ $EUID -eq 0 ]] || die "no deb-src entry for bookworm; run as root to add one"
    log "adding a deb-src entry for bookworm (/etc/apt/sources.list.d/vu-bookworm-src.sources)"
    cat >/etc/apt/sources.list.d/vu-bookworm-src.sources <<'EOF'
Types: deb-src
URIs: http://deb.debian.org/debian
Suites: bookworm
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
EOF
    apt-get update -qq
  fi
  log "downloading Debian's insighttoolkit5 source (283 MB)"
  (cd "$root/src" && apt-get source -qq insighttoolkit5) || die "apt-get source insighttoolkit5 failed"
  [[ -f "$src_dir/CMakeLists.txt" ]] || die "expected the ITK 5.2.1 source in $src_dir"
}

patch_source() {
  # ITK 5.2.1 uses np.bool, which numpy 1.24 (Debian bookworm) removed: import itk fails.
  local types="$src_dir/Wrapping/Generators/Python/itk/support/types.py"
  if grep -q 'np\.bool)' "$types"; then
    log "patching np.bool -> np.bool_ in $types"
    sed -i 's/np\.bool)/np.bool_)/' "$types"
  fi
}

# The ITK modules this module depends on (DEPENDS and TEST_DEPENDS of itk-module.cmake),
# plus NumPy bridging; nothing else is built or wrapped.
itk_modules() {
  sed -n '/^ *DEPENDS/,/^ *DESCRIPTION/p' "$here/itk-module.cmake" | grep -o 'ITK[A-Za-z0-9]*' | sort -u
  echo ITKBridgeNumPy
}

# The ITK modules wrapped for Python: what a user of this module touches (images, meshes,
# IO, numpy bridge, the transforms and interpolators of the wrapped API, FlipImageFilter
# and CastImageFilter) and what their wrapping needs. The other modules this module links
# are built but not wrapped: wrapping all of them (registration, metrics, optimizers,
# morphology, label maps...) would take several times longer.
VU_WRAPPED_ITK_MODULES="ITKPyBase ITKPyUtils ITKCommon ITKStatistics ITKImageFilterBase ITKTransform
  ITKImageFunction ITKImageGrid ITKImageSources ITKMesh ITKQuadEdgeMesh ITKBridgeNumPy ITKTestKernel
  ITKIOImageBase ITKIOBMP ITKIOGDCM ITKIOGIPL ITKIOJPEG ITKIOMeta ITKIONIFTI ITKIONRRD ITKIOPNG ITKIOTIFF
  ITKIOVTK ITKIOMeshBase ITKIOMeshBYU ITKIOMeshFreeSurfer ITKIOMeshGifti ITKIOMeshOBJ ITKIOMeshOFF ITKIOMeshVTK"

restrict_wrapping() {
  # ITK wraps every enabled module that has a wrapping/ directory; set the others aside.
  local file name dir changed=0
  while IFS= read -r file; do
    dir="$(dirname "$file")"
    name="$(sed -n 's/^ *itk_module( *\([A-Za-z0-9]*\).*/\1/p' "$file" | head -1)"
    [[ -n "$name" && -d "$dir/wrapping" ]] || continue
    if ! grep -qw "$name" <<<"$VU_WRAPPED_ITK_MODULES"; then
      mv "$dir/wrapping" "$dir/wrapping.vu-not-wrapped"
      changed=1
    fi
  done < <(find "$src_dir/Modules" -name itk-module.cmake)
  remove_stale_indexes
  if ((changed)) && [[ -f "$itk_build/CMakeCache.txt" ]]; then
    log "wrapping restricted to the modules this module needs: reconfiguring"
    cmake "$itk_build" >>"$root/itk-configure.log" 2>&1 || die "ITK reconfigure failed; see $root/itk-configure.log"
  fi
}

remove_stale_indexes() {
  # A module wrapped by an earlier configuration leaves its master index (.mdx) behind; an
  # external module's wrapping would then list it as wrapped and look for its typedefs.
  local file dir
  while IFS= read -r file; do
    dir="$(dirname "$file")"
    [[ -d "$dir/wrapping.vu-not-wrapped" ]] || continue
    rm -f "$itk_build/Wrapping/Typedefs/$(sed -n 's/^ *itk_module( *\([A-Za-z0-9]*\).*/\1/p' "$file" | head -1).mdx"
  done < <(find "$src_dir/Modules" -name itk-module.cmake)
}

# The modules itk-module.cmake needs that the existing ITK build has not enabled.
missing_itk_modules() {
  local m
  for m in $(itk_modules); do
    [[ -f "$itk_build/lib/cmake/ITK-5.2/Modules/$m.cmake" ]] || echo "$m"
  done
}

configure_itk() {
  local args=() m
  if [[ -f "$itk_build/CMakeCache.txt" ]]; then
    # A module added to itk-module.cmake since the last build is switched on in place;
    # the build that follows compiles only what it adds.
    for m in $(missing_itk_modules); do args+=("-DModule_$m=ON"); done
    ((${#args[@]} == 0)) && return 0
    log "enabling ${args[*]} in the existing ITK build"
    cmake "${args[@]}" "$itk_build" >>"$root/itk-configure.log" 2>&1 || die "ITK reconfigure failed; see $root/itk-configure.log"
    return 0
  fi
  for m in $(itk_modules); do args+=("-DModule_$m=ON"); done
  mkdir -p "$itk_build"
  cmake -S "$src_dir" -B "$itk_build" \
    -DCMAKE_BUILD_TYPE=Release \
    -DBUILD_SHARED_LIBS=ON \
    -DBUILD_TESTING=OFF \
    -DBUILD_EXAMPLES=OFF \
    -DITK_BUILD_DEFAULT_MODULES=OFF \
    "${args[@]}" \
    -DITK_WRAP_PYTHON=ON \
    -DITK_USE_SYSTEM_SWIG=ON \
    -DITK_USE_SYSTEM_CASTXML=ON \
    -DITK_USE_SYSTEM_GDCM=ON \
    -DITK_WRAP_IMAGE_DIMS="2;3" \
    -DITK_WRAP_unsigned_char=ON \
    -DITK_WRAP_signed_short=ON \
    -DITK_WRAP_float=ON \
    -DITK_WRAP_double=OFF \
    -DITK_WRAP_unsigned_short=OFF \
    -DPython3_EXECUTABLE="$python" \
    -DITK_LEGACY_REMOVE=OFF >"$root/itk-configure.log" 2>&1 ||
    {
      rm -f "$itk_build/CMakeCache.txt"
      die "ITK configure failed; see $root/itk-configure.log"
    }
}

build_itk() {
  rm -f "$itk_build/.vu-build-complete"
  make -C "$itk_build" -j"$jobs" >"$root/itk-build.log" 2>&1 ||
    die "ITK build failed; see $root/itk-build.log (rerun this script to continue)"
  touch "$itk_build/.vu-build-complete"
}

build_module() {
  remove_stale_indexes
  cmake -S "$here" -B "$module_build" \
    -DCMAKE_BUILD_TYPE=Release \
    -DITK_DIR="$itk_build" \
    -DBUILD_TESTING=ON \
    -DVirtualUnwrapping_WRAPPING_TESTS_ONLY=ON \
    -DITK_USE_CLANG_FORMAT=OFF \
    -DITK_USE_KWSTYLE=OFF \
    -DITK_USE_SYSTEM_SWIG=ON \
    -DITK_USE_SYSTEM_CASTXML=ON \
    -DITK_FORBID_DOWNLOADS=ON \
    -DVirtualUnwrapping_TOOL="$tool" \
    -DPython3_EXECUTABLE="$python" >"$root/module-configure.log" 2>&1 ||
    die "module configure failed; see $root/module-configure.log"
  cmake --build "$module_build" -j"$jobs" >"$root/module-build.log" 2>&1 ||
    die "module build failed; see $root/module-build.log"
}

run_python_tests() {
  (cd "$module_build" && ctest -R Python --output-on-failure) || die "Python tests failed"
}

install_packages
if ((!only_tests)); then
  timed fetch-source fetch_source
  patch_source
  restrict_wrapping
  timed configure-itk configure_itk
  timed build-itk build_itk
fi
[[ -f "$itk_build/.vu-build-complete" ]] || die "no finished ITK build in $itk_build; run without --tests first"
missing="$(missing_itk_modules | xargs)"
if [[ -n "$missing" ]]; then
  # Exit status 3: the wrapped build is older than itk-module.cmake (run-tests.sh skips).
  printf 'build-python: the ITK build in %s lacks %s (new in itk-module.cmake): run scripts/build-python.sh without --tests\n' \
    "$itk_build" "$missing" >&2
  exit 3
fi
if [[ ! -x "$tool" ]]; then
  log "building the C++ tool the pipeline test compares with ($tool)"
  source "$here/scripts/setup.sh"
fi
timed build-module build_module
timed python-tests run_python_tests
du -sh "$itk_build" "$module_build" | sed 's/^/[build-python] disk: /'
log "done; Python: PYTHONPATH=$itk_build/Wrapping/Generators/Python LD_LIBRARY_PATH=$itk_build/lib $python"
