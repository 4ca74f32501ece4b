# SPDX-License-Identifier: Apache-2.0
# Every dependency comes from Debian 12 packages (docs: toolchain.md).

# TBB first: otherwise OpenVDB's FindTBB defines TBB::* and VTK's config fails.
find_package(TBB 2021 CONFIG REQUIRED)
list(APPEND CMAKE_MODULE_PATH "/usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}/cmake/OpenVDB")
# Its find module prints a stray "COMPONENT = openvdb" and status blocks about
# Imath's Python bindings (not installed, not needed): keep the log readable.
set(CMAKE_MESSAGE_LOG_LEVEL WARNING)
find_package(OpenVDB REQUIRED)                 # OpenVDB::openvdb
unset(CMAKE_MESSAGE_LOG_LEVEL)
find_package(Eigen3 3.4 REQUIRED NO_MODULE)    # Eigen3::Eigen
find_package(nlohmann_json CONFIG REQUIRED)    # nlohmann_json::nlohmann_json
find_package(CLI11 CONFIG REQUIRED)            # CLI11::CLI11
find_package(Threads REQUIRED)
find_package(ZLIB REQUIRED)                    # ZLIB::ZLIB, for gzip-encoded .nrrd
# niftilib (NIfTI-1/2 headers, qform/sform). Debian 12's NIFTIConfig.cmake
# points at /usr/lib/libznz.so.3.0.0, which the package installs elsewhere:
# find the library and header directly and wrap them in a target.
find_library(VOXHAP_NIFTI2_LIBRARY nifti2 REQUIRED)
find_library(VOXHAP_ZNZ_LIBRARY znz REQUIRED)
find_path(VOXHAP_NIFTI_INCLUDE_DIR nifti2_io.h PATH_SUFFIXES nifti REQUIRED)
add_library(voxhap_nifti2 INTERFACE IMPORTED)
target_include_directories(voxhap_nifti2 SYSTEM INTERFACE ${VOXHAP_NIFTI_INCLUDE_DIR})
target_link_libraries(voxhap_nifti2 INTERFACE ${VOXHAP_NIFTI2_LIBRARY} ${VOXHAP_ZNZ_LIBRARY} ZLIB::ZLIB m)
# GDCM's config prints a status block for every command-line tool it expects
# in /usr/bin (libgdcm-tools, not needed to build): keep the log readable.
set(CMAKE_MESSAGE_LOG_LEVEL NOTICE)
find_package(GDCM 3.0 CONFIG REQUIRED)         # gdcmMSFF (un-namespaced; brings its includes)
unset(CMAKE_MESSAGE_LOG_LEVEL)

# OpenIGTLink 1.11 ships an old-style config without a target, and its USE_FILE adds
# global flags that break other code (toolchain.md): wrap it in an imported target.
if(VOXHAP_WITH_IGTL)
  find_package(OpenIGTLink REQUIRED CONFIG)
  find_library(VOXHAP_IGTL_LIBRARY NAMES OpenIGTLink HINTS ${OpenIGTLink_LIBRARY_DIRS} REQUIRED)
  add_library(voxhap_openigtlink INTERFACE IMPORTED)
  set_target_properties(voxhap_openigtlink PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES "${OpenIGTLink_INCLUDE_DIRS}"
    INTERFACE_LINK_LIBRARIES "${VOXHAP_IGTL_LIBRARY};Threads::Threads")
endif()

if(VOXHAP_BUILD_TESTS)
  find_package(GTest REQUIRED)                 # GTest::gtest_main
  include(GoogleTest)
endif()
if(VOXHAP_BUILD_BENCH)
  find_package(benchmark REQUIRED)             # benchmark::benchmark
endif()
