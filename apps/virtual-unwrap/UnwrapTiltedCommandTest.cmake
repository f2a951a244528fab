# The hospital CT acceptance: the standard phantom written as a CT with a 15 degree gantry
# tilt whose slice spacing changes from 0.1 to 0.15 mm mid-series unwraps, with default
# options, as well as the regular scan: character error rate MAX_CER at most, texture NCC
# at most MAX_NCC_LOSS below the regular scan's. report.json names the tilt and the
# spacing change and the grid it resampled onto; --no-resample refuses the series in one
# line naming both.
# Usage: cmake -DTOOL=<virtual-unwrap> -DWORK=<scratch> -DMAX_CER=<limit>
#              -DMAX_NCC_LOSS=<limit> -P UnwrapTiltedCommandTest.cmake
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
include(${CMAKE_CURRENT_LIST_DIR}/CommandTestHelpers.cmake)

# A number in [0, 10) as millionths (CMake's arithmetic is integer).
function(vu_millionths value out)
  if(NOT value MATCHES "^([0-9])(\\.([0-9]*))?")
    message(FATAL_ERROR "not a number in [0, 10): ${value}")
  endif()
  set(whole ${CMAKE_MATCH_1})
  set(fraction "${CMAKE_MATCH_3}000000")
  string(SUBSTRING "${fraction}" 0 6 fraction)
  math(EXPR result "${whole} * 1000000 + ${fraction}")
  set(${out} ${result} PARENT_SCOPE)
endfunction()

set(ncc "")
foreach(scan regular tilted)
  set(hospital "")
  if(scan STREQUAL "tilted")
    set(hospital --gantry-tilt 15 --second-slice-spacing 0.15)
  endif()
  execute_process(COMMAND ${TOOL} phantom standard -o ${WORK}/${scan} ${hospital}
    RESULT_VARIABLE result ERROR_VARIABLE error OUTPUT_QUIET)
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "phantom ${scan} failed: ${error}")
  endif()
  execute_process(COMMAND ${TOOL} unwrap ${WORK}/${scan}/volume -o ${WORK}/${scan}-out --ground-truth ${WORK}/${scan} -q
    RESULT_VARIABLE result ERROR_VARIABLE error)
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "unwrap of the ${scan} scan failed: ${error}")
  endif()
  file(READ ${WORK}/${scan}-out/report.json json)
  string(JSON cer_${scan} GET "${json}" legibility character_error_rate)
  string(JSON ncc_${scan} GET "${json}" legibility texture_ncc)
  message(STATUS "${scan}: character error rate ${cer_${scan}}, texture NCC ${ncc_${scan}}")
endforeach()

vu_millionths(${ncc_regular} regular)
vu_millionths(${ncc_tilted} tilted)
vu_millionths(${MAX_NCC_LOSS} allowed)
math(EXPR loss "${regular} - ${tilted}")
message(STATUS "texture NCC loss of the tilted scan: ${loss} millionths (limit ${allowed})")
if(cer_tilted GREATER ${MAX_CER} OR loss GREATER allowed)
  message(FATAL_ERROR "tilted scan: character error rate ${cer_tilted} (limit ${MAX_CER}), NCC ${ncc_tilted} against "
    "${ncc_regular} for the regular scan (loss limit ${MAX_NCC_LOSS})")
endif()

# What was found and done is in report.json.
string(JSON warnings GET "${json}" warnings)
foreach(part "sheared slice stack (gantry/detector tilt of about 15 degrees, GantryDetectorTilt 15)"
    "uneven slice spacing: 0.1 mm from -5.5 mm" "0.15 mm from 0 mm" "resampled 92 slices onto a regular grid")
  string(FIND "${warnings}" "${part}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "report.json does not say '${part}': ${warnings}")
  endif()
endforeach()
string(JSON size GET "${json}" input geometry_corrections resampled size)
string(JSON runs LENGTH "${json}" input geometry_corrections spacing_runs)
if(NOT runs EQUAL 2)
  message(FATAL_ERROR "report.json: ${runs} spacing runs, expected 2")
endif()

vu_expect_failure(unwrap noresample "sheared slice stack.*non-uniform slice spacing: 0.1 mm"
  ${WORK}/tilted/volume -o ${WORK}/refused --no-resample -q)
file(GLOB contents ${WORK}/refused/*)
if(contents)
  message(FATAL_ERROR "a refused run left ${contents}")
endif()
