# Runs `virtual-unwrap phantom` as a user would: a good run writes every ground-truth
# file; bad parameters fail with one line on stderr and leave no output behind; an
# existing directory is kept unless --force is given.
# Usage: cmake -DTOOL=<virtual-unwrap> -DWORK=<scratch directory> -P PhantomCommandTest.cmake
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

include(${CMAKE_CURRENT_LIST_DIR}/CommandTestHelpers.cmake)

execute_process(COMMAND ${TOOL} phantom standard -o ${WORK}/good --format mha --mesh-spacing 0.5
  RESULT_VARIABLE result ERROR_VARIABLE error OUTPUT_QUIET)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "standard phantom failed: ${error}")
endif()
vu_expect_files(${WORK}/good volume.mha ground_truth_ink.png ground_truth.json ground_truth_surface.obj
  ground_truth_flat.obj)
file(READ ${WORK}/good/ground_truth.json json)
string(JSON text GET "${json}" text)
string(JSON voxels GET "${json}" volume voxels)
if(NOT text STREQUAL "DIGITAL RESTORATION USING\nVOLUMETRIC SCANNING\nSEALES AND LIN 2004" OR voxels LESS 100000)
  message(FATAL_ERROR "unexpected ground truth: text '${text}', ${voxels} voxels")
endif()

vu_expect_failure(phantom overlap "pitch" standard -o ${WORK}/bad --pitch 0.2)
vu_expect_failure(phantom negative "thickness" standard -o ${WORK}/bad --thickness -1)
vu_expect_failure(phantom preset "unknown preset" scroll -o ${WORK}/bad)
vu_expect_failure(phantom format "unknown format" standard -o ${WORK}/bad --format jpeg)
vu_expect_failure(phantom text "does not fit" standard -o ${WORK}/bad --text NOSPACESTOWRAPATANDFARTOOLONGFORFIFTYMILLIMETRES)
vu_expect_failure(phantom existing "not empty" standard -o ${WORK}/good)
vu_expect_failure(phantom tiltformat "use --format dicom" standard -o ${WORK}/bad --gantry-tilt 15 --format mha)
vu_expect_failure(phantom tiltrange "between -60 and 60" standard -o ${WORK}/bad --gantry-tilt 75)
vu_expect_failure(phantom dropfirst "--drop-slices: slice 0" standard -o ${WORK}/bad --drop-slices 0)
file(GLOB leftovers ${WORK}/bad* ${WORK}/*.partial-*)
if(leftovers)
  message(FATAL_ERROR "failed runs left output behind: ${leftovers}")
endif()
if(NOT EXISTS ${WORK}/good/volume.mha)
  message(FATAL_ERROR "a refused run damaged the existing output")
endif()

execute_process(COMMAND ${TOOL} phantom folded -o ${WORK}/good --format dicom --force --mesh-spacing 0.5
  RESULT_VARIABLE result ERROR_VARIABLE error OUTPUT_QUIET)
file(GLOB slices ${WORK}/good/volume/*.dcm)
list(LENGTH slices count)
if(NOT result EQUAL 0 OR count LESS 50 OR EXISTS ${WORK}/good/volume.mha)
  message(FATAL_ERROR "--force did not replace the output (${result}, ${count} slices): ${error}")
endif()

# A hospital CT series: tilted gantry, spacing changing mid-series, two slices left out;
# ground_truth.json records where every slice was taken.
execute_process(COMMAND ${TOOL} phantom standard -o ${WORK}/hospital --gantry-tilt 12 --second-slice-spacing 0.2
  --drop-slices 20 21 --mesh-spacing 0.5 RESULT_VARIABLE result ERROR_VARIABLE error OUTPUT_QUIET)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "hospital series failed: ${error}")
endif()
file(READ ${WORK}/hospital/ground_truth.json json)
string(JSON tilt GET "${json}" series gantry_tilt_deg)
string(JSON locations LENGTH "${json}" series slice_locations_mm)
file(GLOB slices ${WORK}/hospital/volume/*.dcm)
list(LENGTH slices count)
# 56 slices 0.1 mm apart to the middle (5.5 mm), 27 more 0.2 mm apart, two left out.
if(NOT tilt EQUAL 12 OR NOT count EQUAL locations OR NOT locations EQUAL 81)
  message(FATAL_ERROR "hospital series: tilt ${tilt}, ${count} files for ${locations} slice locations")
endif()
