# SPDX-License-Identifier: Apache-2.0
# Helpers that give every voxhap target the same warnings and layout.

# Warnings on for our code; library headers are system headers, so they stay quiet.
# -Wmissing-field-initializers is off: settings structs are filled with C++20
# designated initialisers that name only what differs from the member defaults,
# which GCC 12 reports although every omitted member has its default initialiser.
function(voxhap_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
    -Wno-missing-field-initializers)
endfunction()

# Where the installed package keeps the public headers: include/voxhap/<folder>/File.h,
# so that "<folder>/File.h" reads the same inside the tree and in an embedding
# project, without putting core/, volume/, ... directly under the prefix's include/.
set(VOXHAP_INSTALL_INCLUDEDIR include/voxhap)

# voxhap_add_library(<folder> SOURCES ... [PUBLIC_DEPS ...] [PRIVATE_DEPS ...] [NO_PCH])
# Defines voxhap_<folder> with alias voxhap::<folder>; headers are included
# as "<folder>/File.h" from the project root (or from the installed include/voxhap).
function(voxhap_add_library name)
  cmake_parse_arguments(ARG "NO_PCH" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(voxhap_${name} STATIC ${ARG_SOURCES})
  add_library(voxhap::${name} ALIAS voxhap_${name})
  # voxhap::<folder> in the installed package too (cmake/VoxhapInstall.cmake).
  set_target_properties(voxhap_${name} PROPERTIES EXPORT_NAME ${name})
  target_include_directories(voxhap_${name} PUBLIC
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}> $<INSTALL_INTERFACE:${VOXHAP_INSTALL_INCLUDEDIR}>)
  # The public headers are C++20: an embedding project compiles them as such.
  target_compile_features(voxhap_${name} PUBLIC cxx_std_20)
  target_link_libraries(voxhap_${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  # Every library position-independent: the Python module (a shared object)
  # links them, and the libraries share one precompiled header, which GCC
  # ignores, parsing the headers again, in a target whose -fPIC differs from
  # the header's ("created and used with different settings of -fpie").
  set_target_properties(voxhap_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  voxhap_warnings(voxhap_${name})
  if(NOT ARG_NO_PCH)
    voxhap_precompile(voxhap_${name} library)
  endif()
endfunction()

# Tests and the command-line glue compile at -O1: their speed is not what the
# project measures (bench/ times the libraries, which keep -O2), and it saves
# about a third of their compile time, most of it CLI11 and GoogleTest code.
function(voxhap_glue_optimization target)
  if(CMAKE_BUILD_TYPE STREQUAL "Release")
    target_compile_options(${target} PRIVATE -O1)
  endif()
endfunction()

# Precompiled headers. Parsing <openvdb/openvdb.h> costs about 6 s per
# translation unit, <CLI/CLI.hpp> 7 s and <gtest/gtest.h> 3 s on the 2-core
# CI machine; the build must fit the 15-minute CI budget with the tests. Each
# kind of target (library, tool, test) parses its set once: the first target
# of a kind builds the header, the others reuse it (their extra -D flags do
# not touch these headers, which GCC requires). Only third-party and standard
# headers go here, so the header does not hide a missing include of ours.
# Off with -DVOXHAP_PRECOMPILE=OFF (e.g. for include-what-you-use checks).
option(VOXHAP_PRECOMPILE "Precompile the heavy third-party headers" ON)
set(VOXHAP_PCH_library
  <openvdb/openvdb.h> <Eigen/Core> <Eigen/Geometry> <nlohmann/json.hpp>
  <algorithm> <array> <cmath> <cstdint> <filesystem> <functional> <map> <memory>
  <optional> <sstream> <stdexcept> <string> <string_view> <vector>)
set(VOXHAP_PCH_tool ${VOXHAP_PCH_library} <CLI/CLI.hpp> <iostream>)
set(VOXHAP_PCH_test ${VOXHAP_PCH_library} <gtest/gtest.h>)
# For tests that run the executable and do not link OpenVDB.
set(VOXHAP_PCH_cli_test <gtest/gtest.h> <nlohmann/json.hpp> <filesystem> <string> <vector>)
function(voxhap_precompile target kind)
  if(NOT VOXHAP_PRECOMPILE)
    return()
  endif()
  get_property(owner GLOBAL PROPERTY VOXHAP_PCH_OWNER_${kind})
  if(owner)
    target_precompile_headers(${target} REUSE_FROM ${owner})
  else()
    target_precompile_headers(${target} PRIVATE ${VOXHAP_PCH_${kind}})
    set_property(GLOBAL PROPERTY VOXHAP_PCH_OWNER_${kind} ${target})
  endif()
endfunction()

# voxhap_add_test(<name> SOURCES ... DEPS ... [PCH test|cli_test|none] [SHARED_SUITES s...]): one
# GoogleTest executable per module, each case registered with CTest.
function(voxhap_add_test name)
  cmake_parse_arguments(ARG "" "PCH" "SOURCES;DEPS;LABELS;SHARED_SUITES" ${ARGN})
  if(NOT ARG_PCH)
    set(ARG_PCH test)
  endif()
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest_main)
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  # The same definitions on every test target, so that they share precompiled headers.
  # VOXHAP_PYTHON: Debian's python3, for tests that take pydicom as their reference.
  target_compile_definitions(${name} PRIVATE
    VOXHAP_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    VOXHAP_BINARY_DIR="${PROJECT_BINARY_DIR}"
    VOXHAP_PYTHON="${VOXHAP_PYTHON}")
  voxhap_warnings(${name})
  voxhap_glue_optimization(${name})
  if(NOT ARG_PCH STREQUAL "none") # core's tests: the test header brings OpenVDB, which core does not link
    voxhap_precompile(${name} ${ARG_PCH})
  endif()
  # A suite whose tests share one expensive fixture (a segmented real CT)
  # runs as one ctest entry, in one process: per-test processes would each
  # rebuild the fixture. A GTEST_SKIP in it shows as skipped, as it does for
  # the discovered tests, never as passed; a failure beside it still fails.
  set(filter "")
  foreach(suite IN LISTS ARG_SHARED_SUITES)
    add_test(NAME ${suite} COMMAND ${PROJECT_SOURCE_DIR}/tests/common/skips_exit_77.sh $<TARGET_FILE:${name}>
                                   --gtest_filter=${suite}.*)
    set_tests_properties(${suite} PROPERTIES LABELS "${ARG_LABELS}" SKIP_RETURN_CODE 77)
    string(APPEND filter ":${suite}.*")
  endforeach()
  if(filter)
    string(SUBSTRING "${filter}" 1 -1 filter)
    gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 TEST_FILTER "-${filter}" PROPERTIES LABELS "${ARG_LABELS}")
  else()
    gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES LABELS "${ARG_LABELS}")
  endif()
endfunction()
