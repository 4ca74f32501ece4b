# SPDX-License-Identifier: Apache-2.0
# Helpers that give every voxhap target the same warnings and layout.

# Warnings on for our code; library headers are system headers, so they stay quiet.
function(voxhap_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor)
endfunction()

# voxhap_add_library(<folder> SOURCES ... [PUBLIC_DEPS ...] [PRIVATE_DEPS ...])
# Defines voxhap_<folder> with alias voxhap::<folder>; headers are included
# as "<folder>/File.h" from the project root.
function(voxhap_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(voxhap_${name} STATIC ${ARG_SOURCES})
  add_library(voxhap::${name} ALIAS voxhap_${name})
  target_include_directories(voxhap_${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(voxhap_${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  voxhap_warnings(voxhap_${name})
endfunction()

# voxhap_add_test(<name> SOURCES ... DEPS ...): one GoogleTest executable per
# module, each case registered with CTest.
function(voxhap_add_test name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest_main)
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  target_compile_definitions(${name} PRIVATE
    VOXHAP_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    VOXHAP_BINARY_DIR="${PROJECT_BINARY_DIR}")
  voxhap_warnings(${name})
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES LABELS "${ARG_LABELS}")
endfunction()
