# SPDX-License-Identifier: Apache-2.0
# Two Debian 12 packages whose own CMake files give no usable target
# (toolchain.md), wrapped in imported targets. Used by the build
# (VoxhapDependencies.cmake) and installed with the package, whose
# voxhapConfig.cmake makes the same targets for the static libraries' links.
# Each function sets <found> to TRUE or FALSE; the caller decides whether a
# missing package is an error.

# voxhap_nifti2: niftilib (NIfTI-1/2 headers, qform/sform). Debian 12's
# NIFTIConfig.cmake points at /usr/lib/libznz.so.3.0.0, which the package installs
# elsewhere: find the library and header directly.
function(voxhap_wrap_nifti2 found)
  if(TARGET voxhap_nifti2)
    set(${found} TRUE PARENT_SCOPE)
    return()
  endif()
  find_package(ZLIB QUIET)
  find_library(VOXHAP_NIFTI2_LIBRARY nifti2)
  find_library(VOXHAP_ZNZ_LIBRARY znz)
  find_path(VOXHAP_NIFTI_INCLUDE_DIR nifti2_io.h PATH_SUFFIXES nifti)
  if(NOT (ZLIB_FOUND AND VOXHAP_NIFTI2_LIBRARY AND VOXHAP_ZNZ_LIBRARY AND VOXHAP_NIFTI_INCLUDE_DIR))
    set(${found} FALSE PARENT_SCOPE)
    return()
  endif()
  add_library(voxhap_nifti2 INTERFACE IMPORTED)
  target_include_directories(voxhap_nifti2 SYSTEM INTERFACE ${VOXHAP_NIFTI_INCLUDE_DIR})
  target_link_libraries(voxhap_nifti2 INTERFACE ${VOXHAP_NIFTI2_LIBRARY} ${VOXHAP_ZNZ_LIBRARY} ZLIB::ZLIB m)
  set(${found} TRUE PARENT_SCOPE)
endfunction()

# voxhap_openigtlink: OpenIGTLink 1.11 ships an old-style config without a target,
# and its USE_FILE adds global flags that break other code.
function(voxhap_wrap_openigtlink found)
  if(TARGET voxhap_openigtlink)
    set(${found} TRUE PARENT_SCOPE)
    return()
  endif()
  find_package(Threads QUIET)
  find_package(OpenIGTLink QUIET CONFIG)
  if(OpenIGTLink_FOUND)
    find_library(VOXHAP_IGTL_LIBRARY NAMES OpenIGTLink HINTS ${OpenIGTLink_LIBRARY_DIRS})
  endif()
  if(NOT (Threads_FOUND AND OpenIGTLink_FOUND AND VOXHAP_IGTL_LIBRARY))
    set(${found} FALSE PARENT_SCOPE)
    return()
  endif()
  add_library(voxhap_openigtlink INTERFACE IMPORTED)
  set_target_properties(voxhap_openigtlink PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES "${OpenIGTLink_INCLUDE_DIRS}"
    INTERFACE_LINK_LIBRARIES "${VOXHAP_IGTL_LIBRARY};Threads::Threads")
  set(${found} TRUE PARENT_SCOPE)
endfunction()

# voxhap_itk: the ITK 5.2 modules registration/ uses, without ITK's use-file
# (which would register every IO factory through generated code and add its
# include directories to every target). Transform IO is registered by hand
# (registration/TransformFile.cpp).
function(voxhap_wrap_itk found)
  if(TARGET voxhap_itk)
    set(${found} TRUE PARENT_SCOPE)
    return()
  endif()
  find_package(ITK 5.2 QUIET COMPONENTS ITKCommon ITKRegistrationMethodsv4 ITKMetricsv4 ITKOptimizersv4
    ITKTransform ITKSpatialObjects ITKDistanceMap ITKIOTransformBase ITKIOTransformInsightLegacy)
  if(NOT ITK_FOUND)
    set(${found} FALSE PARENT_SCOPE)
    return()
  endif()
  add_library(voxhap_itk INTERFACE IMPORTED)
  target_include_directories(voxhap_itk SYSTEM INTERFACE ${ITK_INCLUDE_DIRS})
  target_link_libraries(voxhap_itk INTERFACE ${ITK_LIBRARIES})
  set(${found} TRUE PARENT_SCOPE)
endfunction()
