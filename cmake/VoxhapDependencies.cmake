# SPDX-License-Identifier: Apache-2.0
# Every dependency comes from Debian 12 packages (docs: toolchain.md).

# TBB first: otherwise OpenVDB's FindTBB defines TBB::* and VTK's config fails.
find_package(TBB 2021 CONFIG REQUIRED)
# OpenVDB has only a find module, in Debian's OpenVDB folder; the installed
# package's voxhapConfig.cmake looks there too.
set(VOXHAP_OPENVDB_MODULE_DIR "/usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}/cmake/OpenVDB")
list(APPEND CMAKE_MODULE_PATH ${VOXHAP_OPENVDB_MODULE_DIR})
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
include(${CMAKE_CURRENT_LIST_DIR}/VoxhapWrappedPackages.cmake)
voxhap_wrap_nifti2(VOXHAP_HAVE_NIFTI2) # voxhap_nifti2
if(NOT VOXHAP_HAVE_NIFTI2)
  message(FATAL_ERROR "niftilib (libnifti2 and libznz with nifti2_io.h) not found: install libniftiio-dev")
endif()
# GDCM's config prints a status block for every command-line tool it expects
# in /usr/bin (libgdcm-tools, not needed to build): keep the log readable.
set(CMAKE_MESSAGE_LOG_LEVEL NOTICE)
find_package(GDCM 3.0 CONFIG REQUIRED)         # gdcmMSFF (un-namespaced; brings its includes)
unset(CMAKE_MESSAGE_LOG_LEVEL)

if(VOXHAP_WITH_REGISTRATION)
  voxhap_wrap_itk(VOXHAP_HAVE_ITK) # voxhap_itk
  if(NOT VOXHAP_HAVE_ITK)
    message(FATAL_ERROR "ITK 5.2 not found: install libinsighttoolkit5-dev or configure with -DVOXHAP_WITH_REGISTRATION=OFF")
  endif()
endif()

if(VOXHAP_WITH_IGTL)
  voxhap_wrap_openigtlink(VOXHAP_HAVE_IGTL) # voxhap_openigtlink
  if(NOT VOXHAP_HAVE_IGTL)
    message(FATAL_ERROR "OpenIGTLink not found: install libopenigtlink-dev or configure with -DVOXHAP_WITH_IGTL=OFF")
  endif()
endif()

if(VOXHAP_BUILD_TESTS)
  find_package(GTest REQUIRED)                 # GTest::gtest_main
  include(GoogleTest)
endif()
if(VOXHAP_BUILD_BENCH)
  find_package(benchmark REQUIRED)             # benchmark::benchmark
endif()
