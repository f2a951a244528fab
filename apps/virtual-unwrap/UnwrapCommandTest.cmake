# Runs `virtual-unwrap unwrap` as a user would, on a phantom written as a DICOM series:
# every output is written, the text reads back (OCR character error rate and texture NCC
# against the ground truth, from report.json), and bad input fails with one line on
# stderr, a non-zero exit and no output left behind; the input is never modified.
# Usage: cmake -DTOOL=<virtual-unwrap> -DWORK=<scratch> -DPRESET=<phantom preset>
#              -DMAX_CER=<limit> -DMIN_NCC=<limit> [-DEXTRA_ARGS=<unwrap options>]
#              [-DEXPECT_WARNING=<text>] -P UnwrapCommandTest.cmake
# The flattening warns in report.json only when it did not finish (a phase stopped at its
# step limit, triangles turned over): never on a clean run; with EXPECT_WARNING, a warning
# holding that text must be there.
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

include(${CMAKE_CURRENT_LIST_DIR}/CommandTestHelpers.cmake)

execute_process(COMMAND ${TOOL} phantom ${PRESET} -o ${WORK}/phantom --format dicom
  RESULT_VARIABLE result ERROR_VARIABLE error OUTPUT_QUIET)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "phantom ${PRESET} failed: ${error}")
endif()
vu_file_stamps(${WORK}/phantom stamps)

execute_process(COMMAND ${TOOL} unwrap ${WORK}/phantom/volume -o ${WORK}/out --ground-truth ${WORK}/phantom
  ${EXTRA_ARGS} RESULT_VARIABLE result OUTPUT_VARIABLE output ERROR_VARIABLE error)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "unwrap of ${PRESET} failed: ${error}")
endif()
vu_expect_files(${WORK}/out texture.png texture.tif mask.png layers.tif surface.obj surface.vtp flat.obj flat.mtl
  preview.png report.json)
file(GLOB leftovers ${WORK}/out/.partial*)
if(leftovers)
  message(FATAL_ERROR "temporary files left in the output: ${leftovers}")
endif()
file(READ ${WORK}/out/report.json json)
string(JSON cer GET "${json}" legibility character_error_rate)
string(JSON ncc GET "${json}" legibility texture_ncc)
string(JSON nWarnings LENGTH "${json}" warnings)
set(flattenWarnings "")
set(expectedFound FALSE)
if(nWarnings GREATER 0)
  math(EXPR last "${nWarnings} - 1")
  foreach(i RANGE ${last})
    string(JSON w GET "${json}" warnings ${i})
    if(w MATCHES "^flatten: ")
      list(APPEND flattenWarnings "${w}")
    endif()
    if(DEFINED EXPECT_WARNING)
      string(FIND "${w}" "${EXPECT_WARNING}" at)
      if(at GREATER -1)
        set(expectedFound TRUE)
      endif()
    endif()
  endforeach()
endif()
if(DEFINED EXPECT_WARNING AND NOT expectedFound)
  message(FATAL_ERROR "${PRESET}: no warning holds '${EXPECT_WARNING}' in report.json")
elseif(NOT DEFINED EXPECT_WARNING AND flattenWarnings)
  message(FATAL_ERROR "${PRESET}: the flattening warns on a clean run: ${flattenWarnings}")
endif()
string(JSON p95 GET "${json}" distortion edge_strain p95)
# The automatic texture choices are recorded: side, core subtraction and every candidate's
# ink contrast.
string(JSON side GET "${json}" parameters texture side)
string(JSON core GET "${json}" parameters texture subtract_core)
string(JSON candidates LENGTH "${json}" parameters texture selection candidates)
# With --restore the PSF it undid is recorded; without, restore is false.
string(JSON restore GET "${json}" parameters texture restore)
if(EXTRA_ARGS MATCHES "--restore")
  string(JSON restored GET "${json}" parameters texture restore psf_fwhm_mm)
  message(STATUS "${PRESET}: restored, PSF FWHM ${restored} mm")
elseif(NOT restore STREQUAL "OFF")
  message(FATAL_ERROR "${PRESET}: restore is '${restore}' without --restore")
endif()
message(STATUS "${PRESET}: character error rate ${cer}, texture NCC ${ncc}, edge strain p95 ${p95}, "
  "texture side ${side}, core subtracted ${core}, ${candidates} candidates")
if(candidates LESS 1)
  message(FATAL_ERROR "${PRESET}: no texture candidate recorded in report.json")
endif()
if(cer GREATER ${MAX_CER} OR ncc LESS ${MIN_NCC})
  message(FATAL_ERROR "${PRESET}: character error rate ${cer} (limit ${MAX_CER}), NCC ${ncc} (limit ${MIN_NCC})")
endif()
# Same vertices, same order, same faces in surface.obj and flat.obj.
file(STRINGS ${WORK}/out/surface.obj surfaceFaces REGEX "^f ")
file(STRINGS ${WORK}/out/flat.obj flatFaces REGEX "^f ")
list(LENGTH surfaceFaces nSurface)
list(LENGTH flatFaces nFlat)
if(NOT nSurface EQUAL nFlat OR nSurface EQUAL 0)
  message(FATAL_ERROR "surface.obj has ${nSurface} faces, flat.obj ${nFlat}")
endif()

# The input is untouched.
vu_file_stamps(${WORK}/phantom stampsAfter)
if(NOT stamps STREQUAL stampsAfter)
  message(FATAL_ERROR "the input changed")
endif()

file(MAKE_DIRECTORY ${WORK}/empty)
vu_expect_failure(unwrap missing "no such file" ${WORK}/no-such-scan -o ${WORK}/bad1 -q)
vu_expect_failure(unwrap empty "empty" ${WORK}/empty -o ${WORK}/bad2 -q)
vu_expect_failure(unwrap threshold "threshold" ${WORK}/phantom/volume -o ${WORK}/bad3 --threshold lots -q)
vu_expect_failure(unwrap nothing "threshold" ${WORK}/phantom/volume -o ${WORK}/bad4 --threshold 100000 -q)
vu_expect_failure(unwrap smooth "--smooth" ${WORK}/phantom/volume -o ${WORK}/bad5 --smooth lots -q)
vu_expect_failure(unwrap evenlayers "odd number" ${WORK}/phantom/volume -o ${WORK}/bad6 --layers 4 -q)
vu_expect_failure(unwrap restore "--restore" ${WORK}/phantom/volume -o ${WORK}/bad7 --restore -0.1 -q)
vu_expect_failure(unwrap restoresmooth "--smooth" ${WORK}/phantom/volume -o ${WORK}/bad8 --restore 0.1 --smooth 0.1 -q)
foreach(bad bad1 bad2 bad3 bad4 bad5 bad6 bad7 bad8)
  file(GLOB contents ${WORK}/${bad}/*)
  if(contents)
    message(FATAL_ERROR "${bad}: a failed run left ${contents}")
  endif()
endforeach()
