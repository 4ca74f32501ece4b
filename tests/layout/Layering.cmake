# SPDX-License-Identifier: Apache-2.0
# Every #include between the project's libraries must point down the order of
# cmake/LibraryOrder.cmake, which the README's "Layout" and docs/architecture.md show
# (checked here too)
# (python/, the Python module, binds the physics core and planning; nothing includes it;
# regress/ plots its failing cases with render/; nothing below tools includes it)
# and inside volume/, segmentation/, haptic/ and render/ down their own orders
# (below). A source of one folder may include headers of its own folder and of
# the folders before it, never of one after it; a detail/ folder is its
# parent's alone. Fails listing every offending file:line, and fails when a
# folder or a step of an order has no sources or no includes to check, since
# that is a wrong name, not a pass (LayeringControls.cmake shows both). Run by CTest:
#   cmake -DSOURCE=<root> -P Layering.cmake
cmake_minimum_required(VERSION 3.25)
if(NOT SOURCE)
  message(FATAL_ERROR "Layering.cmake: give -DSOURCE=")
endif()

# The 1-based line of @p line in @p text, into @p out.
function(line_number text line out)
  string(FIND "${text}" "${line}" at)
  string(SUBSTRING "${text}" 0 ${at} before)
  string(REGEX MATCHALL "\n" newlines "${before}")
  list(LENGTH newlines count)
  math(EXPR number "${count} + 1")
  set(${out} ${number} PARENT_SCOPE)
endfunction()

# Rank of a path among the libraries.
include(${SOURCE}/cmake/LibraryOrder.cmake)
set(order ${VOXHAP_LIBRARY_ORDER})

# The documents show the same chain.
list(JOIN order " ← " chain)
foreach(doc README.md docs/architecture.md)
  file(READ ${SOURCE}/${doc} text)
  string(FIND "${text}" "${chain}\n" at)
  if(at LESS 0)
    message(FATAL_ERROR "${doc} does not show the libraries' order of cmake/LibraryOrder.cmake: ${chain}")
  endif()
endforeach()

# The orders inside libraries: regular expressions on a path below the
# library's folder, lowest first; a path's rank is the index of the last one
# it matches ("[^/]+$" is the library's root files), and a source or an
# included header that matches none is an offence.
#
# volume/: the root's Volume, grids, metadata and tissue table (used by all) <-
# detail <- io <- mr <- dicom (dicom/detail is dicom's alone) <- the root's
# format dispatch and description (VolumeFile, VolumeInfo), which may include them all.
set(volume_order "[^/]+$" "detail/" "io/" "mr/" "dicom/" "(VolumeFile|VolumeInfo)\\.")
# segmentation/: lattice/, the dense working arrays and what runs on them
# (distance transform, morphology, components), with the loops of detail/ <-
# the root's labelling, imports and distance fields.
set(segmentation_order "(lattice|detail)/" "[^/]+$")
# haptic/: the root's shared types (device limits, events, layers, the needle)
# <- materials <- shaft <- beam <- papers <- force <- scene <- servo <- devices <- igtl
# (devices/ holds the drivers and the device factory the servo loop runs;
# igtl/ registers its kind there).
set(haptic_order "[^/]+$" "materials/" "shaft/" "beam/" "papers/" "force/" "scene/" "servo/" "devices/" "igtl/")
# render/: raster (images, drawing, PNG) <- plots <- views (a view's kind and
# frame, the volume handed to VTK, with detail/ its VTK arrays, the overlays)
# <- slices <- volume3d <- viewer <- outputs; render/ keeps no file at its root.
set(render_order "raster/" "plots/" "(views|detail)/" "slices/" "volume3d/" "viewer/" "outputs/")
# Every source of these libraries lies in a step of its order.
set(inner volume segmentation haptic render)

# Rank of @p path in the libraries' order, into @p out.
function(library_rank path out)
  string(REGEX MATCH "^([a-z_0-9]+)/" m "${path}")
  list(FIND order "${CMAKE_MATCH_1}" r)
  set(${out} ${r} PARENT_SCOPE)
endfunction()

# Rank of @p path inside the library named by `lib` (set by the caller), into
# @p out; -1 when no step of its order matches.
function(inner_rank path out)
  set(r -1)
  set(i 0)
  foreach(pattern IN LISTS ${lib}_order)
    if(path MATCHES "^${lib}/(${pattern})")
      set(r ${i})
    endif()
    math(EXPR i "${i} + 1")
  endforeach()
  set(${out} ${r} PARENT_SCOPE)
endfunction()

# Check the includes of the sources under @p root whose target starts with
# @p prefix, ranked by @p rank; offences are appended to the variable `bad`.
set(bad "")
set(checked 0)
function(check root prefix rank what)
  file(GLOB_RECURSE sources RELATIVE ${SOURCE} ${SOURCE}/${root}/*.h ${SOURCE}/${root}/*.cpp ${SOURCE}/${root}/*.in)
  set(found "")
  set(n ${checked})
  foreach(source IN LISTS sources)
    cmake_language(CALL ${rank} ${source} sourceRank)
    file(READ ${SOURCE}/${source} text)
    if(sourceRank LESS 0)
      list(APPEND found "${source}: lies in no step of ${what}")
    endif()
    file(STRINGS ${SOURCE}/${source} lines REGEX "^[ \t]*#[ \t]*include[ \t]*\"${prefix}")
    foreach(line IN LISTS lines)
      math(EXPR n "${n} + 1")
      string(REGEX MATCH "\"([^\"]+)\"" m "${line}")
      set(target ${CMAKE_MATCH_1})
      cmake_language(CALL ${rank} ${target} targetRank)
      set(why "")
      if(targetRank LESS 0)
        set(why "lies in no step of ${what}")
      elseif(targetRank GREATER sourceRank)
        set(why "lies above it in ${what}")
      endif()
      # A detail/ folder is its parent's alone (checked once, with the libraries).
      if(what STREQUAL "the libraries' order" AND target MATCHES "^(([a-z0-9]+/)*[a-z0-9]+)/detail/")
        set(parent ${CMAKE_MATCH_1}) # read before another MATCHES replaces it
        if(NOT source MATCHES "^${parent}/")
          set(why "is ${parent}/'s own detail")
        endif()
      endif()
      if(why)
        line_number("${text}" "${line}" number)
        list(APPEND found "${source}:${number}: ${target} ${why} (${line})")
      endif()
    endforeach()
  endforeach()
  # A folder without sources or without includes is a wrong name, not a pass.
  if(NOT sources OR n EQUAL checked)
    message(FATAL_ERROR "${root}/: no sources or no includes found to check (${what})")
  endif()
  set(bad ${bad} ${found} PARENT_SCOPE)
  set(checked ${n} PARENT_SCOPE)
endfunction()

foreach(folder IN LISTS order)
  check(${folder} "[a-z_0-9]+/" library_rank "the libraries' order")
endforeach()
foreach(lib IN LISTS inner)
  # Each step of the order names sources: a step that matches none is a wrong name.
  file(GLOB_RECURSE sources RELATIVE ${SOURCE} ${SOURCE}/${lib}/*.h ${SOURCE}/${lib}/*.cpp)
  foreach(pattern IN LISTS ${lib}_order)
    set(matched ${sources})
    list(FILTER matched INCLUDE REGEX "^${lib}/(${pattern})")
    if(NOT matched)
      message(FATAL_ERROR "${lib}/: the step '${pattern}' of its order matches no source")
    endif()
  endforeach()
  check(${lib} "${lib}/" inner_rank "${lib}/'s order")
endforeach()

if(bad)
  list(JOIN bad "\n  " text)
  message(FATAL_ERROR "includes against the layering:\n  ${text}")
endif()
list(JOIN inner ", " innerText)
message(STATUS "${checked} includes checked; every one points down the order ${order} and the own orders of ${innerText}")
