# SPDX-License-Identifier: Apache-2.0
# Configures voxhap with VOXHAP_WITH_RENDER and VOXHAP_WITH_IGTL OFF and VTK,
# X11 and OpenIGTLink made unfindable, then fails if any link or compile line
# of the generated build still names them (issue 24 item 4). Run by CTest:
#   cmake -DSOURCE=<root> -DBINARY=<scratch dir> -P CoreWithoutGui.cmake
# A configure takes seconds; the full build and test run without the packages
# is measured by hand (README "Layout").
if(NOT SOURCE OR NOT BINARY)
  message(FATAL_ERROR "CoreWithoutGui.cmake: give -DSOURCE= and -DBINARY=")
endif()
file(REMOVE_RECURSE ${BINARY})
execute_process(
  COMMAND ${CMAKE_COMMAND} -S ${SOURCE} -B ${BINARY} -G Ninja -DCMAKE_BUILD_TYPE=Release
          -DVOXHAP_WITH_RENDER=OFF -DVOXHAP_WITH_IGTL=OFF -DVOXHAP_BUILD_BENCH=OFF
          -DCMAKE_DISABLE_FIND_PACKAGE_VTK=ON -DCMAKE_DISABLE_FIND_PACKAGE_OpenIGTLink=ON
          -DCMAKE_DISABLE_FIND_PACKAGE_X11=ON -DCMAKE_DISABLE_FIND_PACKAGE_OpenImageIO=ON
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the core does not configure without VTK, X11 and OpenIGTLink:\n${err}")
endif()
file(READ ${BINARY}/build.ninja ninja)
set(found "")
foreach(pattern "libvtk" "vtk-9" "libX11" "OpenIGTLink" "OpenImageIO")
  string(FIND "${ninja}" "${pattern}" at)
  if(NOT at EQUAL -1)
    list(APPEND found ${pattern})
  endif()
endforeach()
# The targets an embedding user needs must be there.
foreach(target voxhap_volume voxhap_phantoms voxhap_segmentation voxhap_haptic voxhap_assessment voxhap_planning test_haptic)
  string(FIND "${ninja}" "build ${target}:" t1)
  string(FIND "${ninja}" "lib${target}.a" t2)
  string(FIND "${ninja}" "bin/${target}" t3)
  if(t1 EQUAL -1 AND t2 EQUAL -1 AND t3 EQUAL -1)
    list(APPEND missing ${target})
  endif()
endforeach()
file(REMOVE_RECURSE ${BINARY})
if(found)
  message(FATAL_ERROR "the core build still names: ${found}")
endif()
if(missing)
  message(FATAL_ERROR "the core build lacks: ${missing}")
endif()
message(STATUS "core configures without VTK, X11 and OpenIGTLink; no build line names them")
