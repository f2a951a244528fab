# Runs `virtual-unwrap segment` as a user would: on a phantom it writes the mask, the
# meshes and a JSON summary; bad input fails with one line on stderr.
# Usage: cmake -DTOOL=<virtual-unwrap> -DWORK=<scratch directory> -P SegmentCommandTest.cmake
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

include(${CMAKE_CURRENT_LIST_DIR}/CommandTestHelpers.cmake)

execute_process(COMMAND ${TOOL} phantom folded -o ${WORK}/phantom --format mha
  RESULT_VARIABLE result ERROR_VARIABLE error OUTPUT_QUIET)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "phantom failed: ${error}")
endif()
execute_process(COMMAND ${TOOL} segment ${WORK}/phantom/volume.mha -o ${WORK}/out --mesh-spacing 0.5,0.8
  RESULT_VARIABLE result ERROR_VARIABLE error OUTPUT_QUIET)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "segment failed: ${error}")
endif()
vu_expect_files(${WORK}/out mask.mha surface.obj surface.vtk segment.json)
file(READ ${WORK}/out/segment.json json)
string(JSON method GET "${json}" method)
string(JSON points GET "${json}" points)
string(JSON threshold GET "${json}" threshold value)
string(JSON along GET "${json}" mesh_spacing_mm along_axis)
if(NOT method STREQUAL "general" OR points LESS 100 OR threshold LESS -900 OR threshold GREATER 0
   OR along LESS 0.7 OR along GREATER 0.9)
  message(FATAL_ERROR "unexpected summary: method ${method}, ${points} points, threshold ${threshold}, "
                      "spacing along the axis ${along}")
endif()

vu_expect_failure(segment missing "no such file or directory" ${WORK}/nothere.mha -o ${WORK}/bad)
vu_expect_failure(segment threshold "nothing at or above the threshold" ${WORK}/phantom/volume.mha -o ${WORK}/bad
  --threshold 9000)
vu_expect_failure(segment spacing "--mesh-spacing must be a number" ${WORK}/phantom/volume.mha -o ${WORK}/bad
  --mesh-spacing fine)
vu_expect_failure(segment method "unknown surface method" ${WORK}/phantom/volume.mha -o ${WORK}/bad --method spiral)
