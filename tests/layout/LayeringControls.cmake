# SPDX-License-Identifier: Apache-2.0
# Controls of Layering.cmake: it passes on a copy of the tree, and fails, with
# the message the control expects, once the copy is broken in one way:
#   upward-library  core/ includes a header of haptic/
#   upward-inside   render/raster/ includes a header of render/viewer/
#   foreign-detail  render/ includes haptic/shaft/detail/
#   outside-order   a source at render/'s root, in no step of its order
#   empty-step      render/plots/ has no sources (a step that names nothing)
#   no-includes     batch/'s sources include nothing (a folder with nothing to check)
# Run by CTest:
#   cmake -DSOURCE=<root> -DSCRATCH=<dir> -DCONTROL=<name> -P LayeringControls.cmake
cmake_minimum_required(VERSION 3.25)
if(NOT SOURCE OR NOT SCRATCH OR NOT CONTROL)
  message(FATAL_ERROR "LayeringControls.cmake: give -DSOURCE=, -DSCRATCH= and -DCONTROL=")
endif()

# What Layering.cmake reads: the order, the two documents and the libraries' sources.
include(${SOURCE}/cmake/LibraryOrder.cmake)
file(REMOVE_RECURSE ${SCRATCH})
file(COPY ${SOURCE}/cmake/LibraryOrder.cmake DESTINATION ${SCRATCH}/cmake)
file(COPY ${SOURCE}/README.md DESTINATION ${SCRATCH})
file(COPY ${SOURCE}/docs/architecture.md DESTINATION ${SCRATCH}/docs)
foreach(folder IN LISTS VOXHAP_LIBRARY_ORDER)
  file(COPY ${SOURCE}/${folder} DESTINATION ${SCRATCH} FILES_MATCHING PATTERN "*.h" PATTERN "*.cpp" PATTERN "*.in")
endforeach()

function(run_layering rc out)
  execute_process(COMMAND ${CMAKE_COMMAND} -DSOURCE=${SCRATCH} -P ${CMAKE_CURRENT_LIST_DIR}/Layering.cmake
                  RESULT_VARIABLE code OUTPUT_VARIABLE stdout ERROR_VARIABLE stderr)
  set(${rc} ${code} PARENT_SCOPE)
  set(${out} "${stdout}${stderr}" PARENT_SCOPE)
endfunction()

# The unbroken copy passes: whatever fails below fails for the break alone.
run_layering(rc out)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the unbroken copy of the tree already fails the layering:\n${out}")
endif()

# Append @p line to @p file of the copy.
function(append file line)
  file(APPEND ${SCRATCH}/${file} "${line}\n")
endfunction()

if(CONTROL STREQUAL "upward-library")
  append(core/Errors.h "#include \"haptic/servo/Device.h\"")
  set(expect "core/Errors\\.h:[0-9]+: haptic/servo/Device\\.h lies above it in the libraries' order")
elseif(CONTROL STREQUAL "upward-inside")
  append(render/raster/Image.h "#include \"render/viewer/Viewer.h\"")
  set(expect "render/raster/Image\\.h:[0-9]+: render/viewer/Viewer\\.h lies above it in render/'s order")
elseif(CONTROL STREQUAL "foreign-detail")
  append(render/views/ViewFrame.cpp "#include \"haptic/shaft/detail/LeafReader.h\"")
  set(expect "render/views/ViewFrame\\.cpp:[0-9]+: haptic/shaft/detail/LeafReader\\.h is haptic/shaft/'s own detail")
elseif(CONTROL STREQUAL "outside-order")
  file(WRITE ${SCRATCH}/render/Stray.h "#pragma once\n#include \"render/raster/Image.h\"\n")
  set(expect "render/Stray\\.h: lies in no step of render/'s order")
elseif(CONTROL STREQUAL "empty-step")
  file(REMOVE_RECURSE ${SCRATCH}/render/plots)
  set(expect "render/: the step 'plots/' of its order matches no source")
elseif(CONTROL STREQUAL "no-includes")
  file(GLOB_RECURSE sources ${SCRATCH}/batch/*.h ${SCRATCH}/batch/*.cpp)
  foreach(source IN LISTS sources)
    file(READ ${source} text)
    string(REGEX REPLACE "(^|\n)[ \t]*#[ \t]*include[^\n]*" "\\1" text "${text}")
    file(WRITE ${source} "${text}")
  endforeach()
  set(expect "batch/: no sources or no includes found to check")
else()
  message(FATAL_ERROR "LayeringControls.cmake: unknown control '${CONTROL}'")
endif()

run_layering(rc out)
if(rc EQUAL 0)
  message(FATAL_ERROR "control ${CONTROL}: the broken copy passed the layering:\n${out}")
endif()
if(NOT out MATCHES "${expect}")
  message(FATAL_ERROR "control ${CONTROL}: the layering failed, but without '${expect}':\n${out}")
endif()
message(STATUS "control ${CONTROL}: the layering failed as it must")
file(REMOVE_RECURSE ${SCRATCH})
