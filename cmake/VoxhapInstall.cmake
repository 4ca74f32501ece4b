# SPDX-License-Identifier: Apache-2.0
# The installed CMake package (README "Using voxhap from your own CMake project"). `cmake --install build --prefix P`
# puts
#   P/include/voxhap/<folder>/...   the public headers (a detail/ header only where
#                                   a public one includes it)
#   P/lib/libvoxhap_<folder>.a      the libraries
#   P/lib/cmake/voxhap/             voxhapConfig.cmake, its version file, the targets
#   P/bin/voxhap                    the command-line program, when it is built
# An embedding project writes find_package(voxhap REQUIRED [COMPONENTS ...]) and
# links voxhap::haptic and the rest (examples/device-loop/). voxhap::core, volume,
# phantoms, segmentation, haptic, assessment, planning and batch are always there; render and igtl are
# components, present when the build had VOXHAP_WITH_RENDER and VOXHAP_WITH_IGTL
# and loaded (with VTK or OpenIGTLink) only when asked for.
include(CMakePackageConfigHelpers)
set(VOXHAP_INSTALL_CMAKEDIR lib/cmake/voxhap)

# voxhap_install_headers(<folder> [EXCLUDE <subfolder>...]): the headers of
# <folder> under include/voxhap/<folder>/, without detail/ folders, which are
# private to their parent, except the detail/ headers a public one includes.
function(voxhap_install_headers folder)
  cmake_parse_arguments(ARG "" "" "EXCLUDE" ${ARGN})
  file(GLOB_RECURSE all RELATIVE ${PROJECT_SOURCE_DIR} CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/${folder}/*.h)
  set(public "")
  foreach(h IN LISTS all)
    set(skip FALSE)
    foreach(sub IN LISTS ARG_EXCLUDE)
      if(h MATCHES "^${folder}/${sub}/")
        set(skip TRUE)
      endif()
    endforeach()
    if(NOT skip AND NOT h MATCHES "/detail/")
      list(APPEND public ${h})
    endif()
  endforeach()
  # The detail/ headers the public ones include, and those they include in turn.
  set(todo ${public})
  while(todo)
    list(POP_FRONT todo h)
    file(STRINGS ${PROJECT_SOURCE_DIR}/${h} lines REGEX "^[ \t]*#[ \t]*include[ \t]*\"[^\"]+/detail/[^\"]+\"")
    foreach(line IN LISTS lines)
      string(REGEX MATCH "\"([^\"]+)\"" m "${line}")
      set(d ${CMAKE_MATCH_1})
      if(NOT d IN_LIST public AND EXISTS ${PROJECT_SOURCE_DIR}/${d})
        list(APPEND public ${d})
        list(APPEND todo ${d})
      endif()
    endforeach()
  endwhile()
  foreach(h IN LISTS public)
    get_filename_component(dir ${h} DIRECTORY)
    install(FILES ${PROJECT_SOURCE_DIR}/${h} DESTINATION ${VOXHAP_INSTALL_INCLUDEDIR}/${dir})
  endforeach()
endfunction()

# The physics core: no VTK, X11 or OpenIGTLink.
set(core_targets voxhap_core voxhap_volume voxhap_phantoms voxhap_segmentation voxhap_haptic voxhap_assessment voxhap_planning voxhap_batch)
install(TARGETS ${core_targets} EXPORT voxhapTargets ARCHIVE DESTINATION lib)
install(EXPORT voxhapTargets NAMESPACE voxhap:: DESTINATION ${VOXHAP_INSTALL_CMAKEDIR})
voxhap_install_headers(core)
install(FILES ${PROJECT_BINARY_DIR}/core/include/core/Version.h DESTINATION ${VOXHAP_INSTALL_INCLUDEDIR}/core)
voxhap_install_headers(volume)
voxhap_install_headers(phantoms)
voxhap_install_headers(segmentation)
voxhap_install_headers(haptic EXCLUDE igtl devices/drivers) # drivers are built in the tree, not installed
voxhap_install_headers(assessment)
voxhap_install_headers(planning)
voxhap_install_headers(batch)

# The optional components, each with its own export set, so that an embedding
# project that does not ask for them never looks for VTK or OpenIGTLink.
set(VOXHAP_BUILT_COMPONENTS "")
if(TARGET voxhap_igtl)
  list(APPEND VOXHAP_BUILT_COMPONENTS igtl)
  install(TARGETS voxhap_igtl EXPORT voxhapIgtlTargets ARCHIVE DESTINATION lib)
  install(EXPORT voxhapIgtlTargets NAMESPACE voxhap:: DESTINATION ${VOXHAP_INSTALL_CMAKEDIR})
  voxhap_install_headers(haptic/igtl)
endif()
if(TARGET voxhap_render)
  list(APPEND VOXHAP_BUILT_COMPONENTS render)
  install(TARGETS voxhap_render EXPORT voxhapRenderTargets ARCHIVE DESTINATION lib)
  install(EXPORT voxhapRenderTargets NAMESPACE voxhap:: DESTINATION ${VOXHAP_INSTALL_CMAKEDIR})
  voxhap_install_headers(render)
  get_property(VOXHAP_RENDER_VTK_COMPONENTS GLOBAL PROPERTY VOXHAP_RENDER_VTK_COMPONENTS)
endif()
if(TARGET voxhap)
  install(TARGETS voxhap RUNTIME DESTINATION bin)
endif()

configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/voxhapConfig.cmake.in
  ${PROJECT_BINARY_DIR}/voxhapConfig.cmake INSTALL_DESTINATION ${VOXHAP_INSTALL_CMAKEDIR})
# 0.x: the API may change between minor versions, so only the same minor matches.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/voxhapConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/voxhapConfig.cmake ${PROJECT_BINARY_DIR}/voxhapConfigVersion.cmake
              ${CMAKE_CURRENT_LIST_DIR}/VoxhapWrappedPackages.cmake
        DESTINATION ${VOXHAP_INSTALL_CMAKEDIR})
