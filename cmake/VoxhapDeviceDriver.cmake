# SPDX-License-Identifier: Apache-2.0
# A haptic device's driver as a library of its own, built only when its vendor's
# SDK is found at configure time (haptic/devices/drivers/TemplateDevice.h says how to
# write the driver itself):
#
#   voxhap_add_device_driver(<name> SOURCES <files...> [PACKAGE <find_package arguments...>] [LINK <targets...>])
#
# defines voxhap_device_<name> (alias voxhap::device_<name>) above voxhap::haptic,
# and the cache option VOXHAP_WITH_<NAME>: AUTO (the default) builds it when
# find_package(<PACKAGE>) succeeds and says in one configure line when it does
# not; ON requires the SDK; OFF skips it. The SDK's targets (LINK) are linked
# privately: nothing that includes the driver's header sees the vendor's headers.
# For example, with an SDK that installs a CMake config:
#
#   voxhap_add_device_driver(acme SOURCES devices/drivers/AcmeDevice.cpp PACKAGE AcmeSdk 2.1 CONFIG LINK AcmeSdk::AcmeSdk)
#
# A program registers the driver's kind by calling its register function
# (registerTemplateDevice() for the template) when voxhap::device_<name> exists.
# Drivers live in haptic/devices/drivers/ and are built in the tree; the
# installed package does not carry them (cmake/VoxhapInstall.cmake).
function(voxhap_add_device_driver name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PACKAGE;LINK" ${ARGN})
  string(TOUPPER "${name}" upper)
  set(VOXHAP_WITH_${upper} AUTO CACHE STRING "Build the ${name} device driver: AUTO (when its SDK is found), ON or OFF")
  set_property(CACHE VOXHAP_WITH_${upper} PROPERTY STRINGS AUTO ON OFF)
  if(VOXHAP_WITH_${upper} STREQUAL "OFF")
    return()
  endif()
  if(ARG_PACKAGE)
    list(GET ARG_PACKAGE 0 package)
    if(VOXHAP_WITH_${upper} STREQUAL "ON")
      find_package(${ARG_PACKAGE} REQUIRED)
    else()
      find_package(${ARG_PACKAGE} QUIET)
    endif()
    if(NOT ${package}_FOUND)
      message(STATUS "device driver ${name}: ${package} not found, not built (VOXHAP_WITH_${upper}=ON requires it)")
      return()
    endif()
  endif()
  voxhap_add_library(device_${name} SOURCES ${ARG_SOURCES} PUBLIC_DEPS voxhap::haptic PRIVATE_DEPS ${ARG_LINK})
endfunction()
