# Plain-CMake build of the module against an installed ITK that lacks ITK's module
# macros (Debian's libinsighttoolkit5-dev). Reads the module's dependencies from
# itk-module.cmake so that both build modes agree.
set(VU_STANDALONE ON)

if(NOT CMAKE_BUILD_TYPE AND NOT CMAKE_CONFIGURATION_TYPES)
  set(CMAKE_BUILD_TYPE Release CACHE STRING "Build type" FORCE)
endif()

set(CMAKE_RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/bin)
set(CMAKE_LIBRARY_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/lib)
set(CMAKE_ARCHIVE_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/lib)
set(CMAKE_POSITION_INDEPENDENT_CODE ON)
set(CMAKE_EXPORT_COMPILE_COMMANDS ON)

# Record what itk-module.cmake asks for.
macro(itk_module _name)
  cmake_parse_arguments(_vu_mod "ENABLE_SHARED;EXCLUDE_FROM_DEFAULT"
    "" "DEPENDS;PUBLIC_DEPENDS;PRIVATE_DEPENDS;COMPILE_DEPENDS;TEST_DEPENDS;DESCRIPTION;FACTORY_NAMES" ${ARGN})
  set(VU_MODULE_NAME ${_name})
  set(VU_MODULE_DEPENDS ${_vu_mod_DEPENDS} ${_vu_mod_PUBLIC_DEPENDS}
    ${_vu_mod_PRIVATE_DEPENDS} ${_vu_mod_COMPILE_DEPENDS})
  set(VU_MODULE_TEST_DEPENDS ${_vu_mod_TEST_DEPENDS})
endmacro()
include(${CMAKE_CURRENT_SOURCE_DIR}/itk-module.cmake)

# ITK's own GoogleTest target is not installed by Debian: the system GTest serves.
list(REMOVE_ITEM VU_MODULE_TEST_DEPENDS ITKGoogleTest)
set(VU_ITK_COMPONENTS ${VU_MODULE_DEPENDS} ${VU_MODULE_TEST_DEPENDS})
list(REMOVE_DUPLICATES VU_ITK_COMPONENTS)
find_package(ITK 5.2 REQUIRED COMPONENTS ${VU_ITK_COMPONENTS})
include(${ITK_USE_FILE})
# ITK's headers are not ours to warn about.
include_directories(SYSTEM ${ITK_INCLUDE_DIRS})

set(VU_WARNING_FLAGS -Wall -Wextra)

# Sanitizers for the whole build (library, tool, tests, fuzz targets), e.g.
# -DVirtualUnwrapping_SANITIZE=address,undefined (scripts/run-sanitizers.sh). Undefined
# behaviour is built recoverable so that reports from ITK's headers can be suppressed
# (test/sanitizer/ubsan.supp); the run stops at the first other one (halt_on_error).
set(VirtualUnwrapping_SANITIZE "" CACHE STRING "Sanitizers to build with (-fsanitize=...), empty for none")
if(VirtualUnwrapping_SANITIZE)
  add_compile_options(-fsanitize=${VirtualUnwrapping_SANITIZE} -fsanitize-recover=undefined -fno-omit-frame-pointer -g1)
  add_link_options(-fsanitize=${VirtualUnwrapping_SANITIZE})
endif()
# Fuzz targets of every parser of user input. By default a bounded random-mutation driver
# (test/fuzz/vuFuzzDriver.cxx) runs them on their seed corpora as tests; with
# VirtualUnwrapping_USE_LIBFUZZER (Clang only) libFuzzer drives them, coverage-guided, and
# the module's own code is instrumented for it.
option(VirtualUnwrapping_BUILD_FUZZERS "Build the fuzz targets of every parser of user input" ON)
option(VirtualUnwrapping_USE_LIBFUZZER "Build the fuzz targets for libFuzzer (Clang)" OFF)
if(VirtualUnwrapping_USE_LIBFUZZER)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "VirtualUnwrapping_USE_LIBFUZZER needs Clang (CXX=clang++)")
  endif()
  add_compile_options(-fsanitize=fuzzer-no-link)
endif()

function(itk_module_add_library _name)
  add_library(${_name} SHARED ${ARGN})
  target_include_directories(${_name} PUBLIC
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/include>
    $<BUILD_INTERFACE:${PROJECT_BINARY_DIR}/include>
    $<INSTALL_INTERFACE:include/VirtualUnwrapping>)
  target_link_libraries(${_name} PUBLIC ${ITK_LIBRARIES})
  target_compile_options(${_name} PRIVATE ${VU_WARNING_FLAGS})
  set_target_properties(${_name} PROPERTIES VERSION ${PROJECT_VERSION} SOVERSION ${PROJECT_VERSION_MAJOR})
endfunction()

option(BUILD_TESTING "Build the module's tests" ON)
option(VirtualUnwrapping_BUILD_APPS "Build the programs in apps/ (the virtual-unwrap tool)" ON)
option(VirtualUnwrapping_BUILD_EXAMPLES "Build the example programs in examples/" ON)
option(VirtualUnwrapping_BUILD_BENCHMARKS "Build the benchmark programs in benchmarks/" ON)

add_subdirectory(src)

if(BUILD_TESTING)
  enable_testing()
  add_subdirectory(test)
endif()
if(VirtualUnwrapping_BUILD_APPS)
  add_subdirectory(apps)
endif()
if(VirtualUnwrapping_BUILD_EXAMPLES)
  add_subdirectory(examples)
endif()
if(VirtualUnwrapping_BUILD_BENCHMARKS)
  add_subdirectory(benchmarks)
endif()
if(BUILD_TESTING AND VirtualUnwrapping_BUILD_APPS AND VirtualUnwrapping_BUILD_FUZZERS)
  add_subdirectory(test/fuzz)
endif()

# Package configuration so that other projects can find_package(VirtualUnwrapping),
# from this build tree or from an installation.
include(CMakePackageConfigHelpers)
include(GNUInstallDirs)
install(TARGETS VirtualUnwrapping VirtualUnwrappingValidation EXPORT VirtualUnwrappingTargets
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY include/ DESTINATION include/VirtualUnwrapping)
install(EXPORT VirtualUnwrappingTargets NAMESPACE VirtualUnwrapping::
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/VirtualUnwrapping)
export(EXPORT VirtualUnwrappingTargets NAMESPACE VirtualUnwrapping::
  FILE ${PROJECT_BINARY_DIR}/VirtualUnwrappingTargets.cmake)
configure_package_config_file(cmake/VirtualUnwrappingConfig.cmake.in
  ${PROJECT_BINARY_DIR}/VirtualUnwrappingConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/VirtualUnwrapping)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/VirtualUnwrappingConfigVersion.cmake
  COMPATIBILITY SameMajorVersion)
install(FILES ${PROJECT_BINARY_DIR}/VirtualUnwrappingConfig.cmake
  ${PROJECT_BINARY_DIR}/VirtualUnwrappingConfigVersion.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/VirtualUnwrapping)
