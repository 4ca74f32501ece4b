# SPDX-License-Identifier: Apache-2.0
# Every file of the tree that README.md and docs/*.md name must exist, so that
# moving a file cannot leave the documents pointing at nothing. Run by CTest:
#   cmake -DSOURCE=<root> -P DocPaths.cmake
cmake_minimum_required(VERSION 3.25)
if(NOT SOURCE)
  message(FATAL_ERROR "DocPaths.cmake: give -DSOURCE=")
endif()
# The libraries of cmake/LibraryOrder.cmake and the folders beside them.
include(${SOURCE}/cmake/LibraryOrder.cmake)
list(JOIN VOXHAP_LIBRARY_ORDER "|" libraries)
set(missing "")
set(count 0)
foreach(doc README.md docs/physics.md docs/architecture.md docs/scenes.md docs/reference.md docs/guide.md)
  file(READ ${SOURCE}/${doc} text)
  # A path starts the text or follows a character no path holds (my-regress/suite.json is not
  # regress/'s): every other character becomes a space, and a path must follow one.
  string(REGEX REPLACE "[^A-Za-z0-9_./-]+" " " words " ${text}")
  string(REGEX MATCHALL " (${libraries}|examples|tests|fuzz|data|docs)/[A-Za-z0-9_./-]+\\.(h|cpp|json|md|sh|cmake|in)"
         paths "${words}")
  list(TRANSFORM paths STRIP)
  list(REMOVE_DUPLICATES paths)
  foreach(path IN LISTS paths)
    math(EXPR count "${count} + 1")
    # A path inside a longer one (../shared/docs/...) is not the tree's.
    string(FIND "${text}" "shared/${path}" shared)
    if(NOT shared EQUAL -1)
      continue()
    endif()
    if(NOT EXISTS ${SOURCE}/${path})
      list(APPEND missing "${doc}: ${path}")
    endif()
  endforeach()
endforeach()
if(count LESS 20)
  message(FATAL_ERROR "DocPaths.cmake: only ${count} paths found: the scan is broken")
endif()
if(missing)
  list(JOIN missing "\n  " text)
  message(FATAL_ERROR "documents name files that do not exist:\n  ${text}")
endif()
message(STATUS "${count} paths named by the documents exist")
